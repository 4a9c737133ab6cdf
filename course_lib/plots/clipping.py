"""Figures for exam question 6: the view volume, clipping, triangulation and scanline spans.

Every function takes an optional ``ax`` (a 3-D axes for :func:`plot_view_volume` and
:func:`plot_clipping_3d`) and returns a dict of the artists it drew, so that the clipping explorer
(:mod:`course_lib.widgets.clipping`) can update them in place.

The figures draw what they are given (a clipped polygon, triangles, spans: from
:mod:`course_lib.clip_results` for the notebook's fixed examples) and compute no graded answer:
points are divided by ``w`` only at display precision (:func:`display_round`).
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.patches import Polygon as PolygonPatch
from matplotlib.patches import Rectangle
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from .. import clipping
from .describe import num, set_summary
from ..plotting import COLOURS, equal_axes, new_figure

#: Axis labels of non-homogeneous screen space.
AXIS_LABELS = ("$x_s$", "$y_s$", "$z_s$")
#: The view volume after the divide: [-1, 1] x [-1, 1] x [0, 1].
BOX_MIN = np.array([-1.0, -1.0, 0.0])
BOX_MAX = np.array([1.0, 1.0, 1.0])


def _ax3d(ax):
    if ax is None:
        fig = plt.figure(figsize=(5.0, 4.5), layout="constrained")
        ax = fig.add_subplot(projection="3d")
    return ax


def _box_edges() -> list[np.ndarray]:
    """The 12 edges of the screen-space view volume as (2, 3) arrays."""
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (0, 1)], float)
    edges = []
    for i in range(8):
        for j in range(i + 1, 8):
            if np.sum(corners[i] != corners[j]) == 1:
                edges.append(corners[[i, j]])
    return edges


def display_round(x) -> np.ndarray:
    """``x`` rounded for drawing: to 1e-4 below 10 (1/20000 of the view volume's width, far
    below a pixel), to five significant figures above; NaN and inf kept.

    Far coarser than the grader's tolerances (1e-7 and finer), so that nothing drawn answers
    a graded function's hidden case.
    """
    x = np.asarray(x, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        digits = np.minimum(4.0, 4.0 - np.floor(np.log10(np.abs(x))))
    digits = np.where(np.isfinite(digits), digits, 4.0)
    scale = 10.0 ** digits
    with np.errstate(invalid="ignore", over="ignore"):
        return np.where(np.isfinite(x), np.round(x * scale) / scale, x)


def screen_points(P) -> np.ndarray:
    """Vertices divided by ``w`` for drawing, at display precision (:func:`display_round`);
    vertices with ``w = 0`` become NaN instead of an error."""
    P = np.asarray(P, dtype=float).reshape(-1, 4)
    out = np.full((len(P), 3), np.nan)
    ok = P[:, 3] != 0
    out[ok] = P[ok, :3] / P[ok, 3:]
    return display_round(out)


def _closed(pts: np.ndarray) -> np.ndarray:
    return np.vstack([pts, pts[:1]]) if len(pts) else pts


def plot_view_volume(ax=None, label_axes: bool = True):
    """The view volume ``[-1, 1] x [-1, 1] x [0, 1]`` in screen space as a 3-D wire box (Q6(a)).

    Parameters
    ----------
    ax : mpl_toolkits.mplot3d.Axes3D, optional
    label_axes : bool
        Label the axes ``x_s, y_s, z_s`` and mark the near (``z_s = 0``) and far faces.

    Returns
    -------
    artists : dict
        ``"edges"``: list of 12 ``Line3D``; ``"near"``, ``"far"``: the two shaded faces.
    """
    ax = _ax3d(ax)
    edges = [ax.plot(*e.T, color=COLOURS["control"], lw=1.0)[0] for e in _box_edges()]
    sq = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], float)
    near = Poly3DCollection([np.c_[sq, np.zeros(4)]], facecolor=COLOURS["reference"],
                            alpha=0.12, edgecolor="none")
    far = Poly3DCollection([np.c_[sq, np.ones(4)]], facecolor=COLOURS["hull"],
                           alpha=0.12, edgecolor="none")
    ax.add_collection3d(near)
    ax.add_collection3d(far)
    if label_axes:
        ax.set_xlabel(AXIS_LABELS[0])
        ax.set_ylabel(AXIS_LABELS[1])
        ax.set_zlabel(AXIS_LABELS[2])
        ax.text(0.0, -1.25, 0.0, "near $z_s=0$", fontsize=8, ha="center",
                color=COLOURS["reference"])
        ax.text(0.0, -1.25, 1.0, "far $z_s=1$", fontsize=8, ha="center", color=COLOURS["hull"])
    ax.set_box_aspect((2, 2, 1))
    lo, hi = BOX_MIN, BOX_MAX
    set_summary(ax, f"The view volume after the divide by w, a wire box: x_s from {num(lo[0])} "
                    f"to {num(hi[0])}, y_s from {num(lo[1])} to {num(hi[1])}, z_s from "
                    f"{num(lo[2])} on the near face to {num(hi[2])} on the far face.")
    return {"edges": edges, "near": near, "far": far}


def plot_clipping_3d(P, clipped, ax=None, title: str | None = None):
    """A homogeneous polygon and its clipped version, drawn in 3-D screen space (Q6(b)(iii)).

    Parameters
    ----------
    P : array_like, shape (n, 4)
        The polygon in homogeneous screen coordinates.
    clipped : array_like, shape (m, 4)
        The clipped polygon (homogeneous; e.g. :func:`course_lib.clip_results.exam_A_clipped`).
    ax : Axes3D, optional
    title : str, optional

    Returns
    -------
    artists : dict
        ``"box"`` (see :func:`plot_view_volume`), ``"original"`` (dashed ``Line3D`` through the
        divided input vertices), ``"clipped"`` (a ``Poly3DCollection``), ``"clipped_edges"``
        (``Line3D``) and ``"clipped_vertices"`` (``Line3D`` markers).
    """
    ax = _ax3d(ax)
    P = np.asarray(P, dtype=float)
    box = plot_view_volume(ax)
    orig = _closed(screen_points(P))
    cl = screen_points(clipped)
    (original,) = ax.plot(*orig.T, ls="--", color=COLOURS["control"], marker="o", ms=4,
                          label="input (after the divide)")
    poly = Poly3DCollection([cl] if len(cl) else [], facecolor=COLOURS["curve"], alpha=0.35,
                            edgecolor="none")
    ax.add_collection3d(poly)
    (edges,) = ax.plot(*_closed(cl).T if len(cl) else ([], [], []), color=COLOURS["curve"],
                       lw=2, label="clipped")
    (verts,) = ax.plot(*cl.T if len(cl) else ([], [], []), ls="none", marker="o", ms=5,
                       color=COLOURS["highlight"])
    ax.legend(loc="upper left", fontsize=8)
    if title:
        ax.set_title(title)
    return {"box": box, "original": original, "clipped": poly, "clipped_edges": edges,
            "clipped_vertices": verts}


def plot_clipping_2d(P, clipped, ax=None, dims=(0, 1), title: str | None = None):
    """A polygon and its clipped version seen along one screen axis (Q6(b)).

    Parameters
    ----------
    P : array_like, shape (n, 4)
        Homogeneous polygon.
    clipped : array_like, shape (m, 4)
        The clipped polygon (homogeneous).
    ax : matplotlib.axes.Axes, optional
    dims : pair of ints
        The screen axes to draw: ``(0, 1)`` is the screen itself (``x_s, y_s``); ``(1, 2)`` is a
        side view (``y_s, z_s``), the natural view of the exam's edge-on triangles.
    title : str, optional

    Returns
    -------
    artists : dict
        ``"box"`` (``Rectangle``), ``"original"`` (dashed ``Line2D``), ``"clipped"``
        (``Polygon`` patch) and ``"clipped_vertices"`` (``Line2D`` markers), ``"labels"``
        (vertex numbers, ``Text``).
    """
    if ax is None:
        _, ax = new_figure()
    P = np.asarray(P, dtype=float)
    i, j = dims
    lo, hi = BOX_MIN[[i, j]], BOX_MAX[[i, j]]
    rect = Rectangle(lo, *(hi - lo), fill=True, facecolor="#f2f2f2",
                     edgecolor=COLOURS["control"], lw=1.2, ls="--", label="view volume")
    ax.add_patch(rect)
    orig = _closed(screen_points(P))[:, [i, j]]
    cl = screen_points(clipped)[:, [i, j]]
    (original,) = ax.plot(*orig.T, ls="--", marker="o", ms=4, color=COLOURS["control"],
                          label="input")
    patch = PolygonPatch(cl if len(cl) else np.zeros((1, 2)), closed=True,
                         facecolor=COLOURS["curve"], alpha=0.4, edgecolor=COLOURS["curve"],
                         lw=2, label="clipped", visible=bool(len(cl)))
    ax.add_patch(patch)
    (verts,) = ax.plot(*cl.T, ls="none", marker="o", ms=6, color=COLOURS["highlight"])
    labels = [ax.annotate(str(k), xy, xytext=(4, 4), textcoords="offset points", fontsize=8,
                          color=COLOURS["highlight"]) for k, xy in enumerate(cl)]
    ax.set_xlabel(AXIS_LABELS[i])
    ax.set_ylabel(AXIS_LABELS[j])
    finite = np.vstack([orig[np.all(np.isfinite(orig), axis=1)], lo, hi])
    pad = 0.15 * np.ptp(finite, axis=0).max()
    ax.set_xlim(finite[:, 0].min() - pad, finite[:, 0].max() + pad)
    ax.set_ylim(finite[:, 1].min() - pad, finite[:, 1].max() + pad)
    ax.set_aspect("equal", adjustable="box")
    ax.grid(True, alpha=0.3)
    if title:
        ax.set_title(title)
    ax.legend(loc="best", fontsize=8)
    return {"box": rect, "original": original, "clipped": patch, "clipped_vertices": verts,
            "labels": labels}


def plot_triangulation(poly_xy, triangles, ax=None, title: str | None = None):
    """A polygon split into triangles: a fan for convex ones, ear clipping otherwise (Q6(c)).

    Parameters
    ----------
    poly_xy : array_like, shape (n, 2)
    triangles : array_like of int, shape (n - 2, 3)
        Vertex numbers, one row per triangle (e.g. from :mod:`course_lib.clip_results`).
    ax : matplotlib.axes.Axes, optional
    title : str, optional

    Returns
    -------
    artists : dict
        ``"triangles"`` (``PolyCollection``, one colour per triangle), ``"outline"``
        (``Line2D``) and ``"labels"`` (triangle numbers at the centroids).
    """
    if ax is None:
        _, ax = new_figure()
    p = np.asarray(poly_xy, dtype=float)
    triangles = np.asarray(triangles, dtype=int)
    cmap = plt.get_cmap("tab20")
    coll = PolyCollection(p[triangles], facecolors=[cmap(k % 20) for k in range(len(triangles))],
                          edgecolors="white", linewidths=1.2, alpha=0.85)
    ax.add_collection(coll)
    (outline,) = ax.plot(*_closed(p).T, color="k", lw=1.5)
    labels = [ax.text(*p[t].mean(axis=0), str(k), ha="center", va="center", fontsize=8)
              for k, t in enumerate(triangles)]
    ax.autoscale_view()
    equal_axes(ax, title or f"{len(p)} vertices, {len(triangles)} triangles")
    return {"triangles": coll, "outline": outline, "labels": labels}


def plot_polygon_spans(poly_xy, y, spans, ax=None, title: str | None = None):
    """The spans of a polygon on one scanline: several for a non-convex polygon (Q6(c)).

    Parameters
    ----------
    poly_xy : array_like, shape (n, 2)
    y : float
        Height of the scanline.
    spans : array_like, shape (k, 2)
        The spans ``(x_left, x_right)`` on it (e.g. :func:`course_lib.clip_results.comb`).
    ax : matplotlib.axes.Axes, optional
    title : str, optional

    Returns
    -------
    artists : dict
        ``"outline"`` (``Line2D``), ``"scanline"`` (dotted ``Line2D``) and ``"spans"``
        (``LineCollection``, one segment per span).
    """
    if ax is None:
        _, ax = new_figure()
    p = np.asarray(poly_xy, dtype=float)
    (outline,) = ax.fill(*p.T, facecolor="#e8eef7", edgecolor="k", lw=1.5)
    x0, x1 = p[:, 0].min(), p[:, 0].max()
    pad = 0.1 * (x1 - x0)
    (scan,) = ax.plot([x0 - pad, x1 + pad], [y, y], ls=":", color=COLOURS["control"])
    spans = np.asarray(spans, dtype=float).reshape(-1, 2)
    segs = [[(a, y), (b, y)] for a, b in spans]
    coll = LineCollection(segs, colors=COLOURS["highlight"], linewidths=4)
    ax.add_collection(coll)
    equal_axes(ax, title or f"{len(spans)} span(s) on the scanline y = {y:g}")
    return {"outline": outline, "scanline": scan, "spans": coll}


def plot_raster(tri_xy, width: int, height: int, ax=None, title: str | None = None):
    """A rasterised triangle: covered pixels, one span per row, and the triangle (Q6(c)).

    Pixel coordinates have ``y`` pointing down the screen, as in
    :func:`~course_lib.clipping.rasterize_triangle` (top-left fill rule).

    Returns
    -------
    artists : dict
        ``"image"`` (``AxesImage`` of the mask), ``"spans"`` (``LineCollection``, one segment
        along each row's run of pixels), ``"outline"`` (``Line2D``), ``"centres"`` (pixel
        centres as dots).
    """
    if ax is None:
        _, ax = new_figure(size=4.5)
    tri = np.asarray(tri_xy, dtype=float)
    mask = clipping.rasterize_triangle(tri, width, height)
    img = ax.imshow(mask, cmap="Blues", vmin=0, vmax=1.6, origin="upper",
                    extent=(0, width, height, 0), interpolation="nearest")
    spans = clipping.triangle_spans(tri, width, height)
    segs = [[(c0 + 0.15, r + 0.5), (c1 + 0.85, r + 0.5)] for r, c0, c1 in spans]
    coll = LineCollection(segs, colors=COLOURS["highlight"], linewidths=2)
    ax.add_collection(coll)
    cy, cx = np.mgrid[0:height, 0:width] + 0.5
    (centres,) = ax.plot(cx.ravel(), cy.ravel(), ls="none", marker=".", ms=2,
                         color=COLOURS["control"])
    (outline,) = ax.plot(*_closed(tri).T, color="k", lw=1.5)
    ax.set_xticks(np.arange(0, width + 1, max(1, width // 8)))
    ax.set_yticks(np.arange(0, height + 1, max(1, height // 8)))
    ax.set_xlim(0, width)
    ax.set_ylim(height, 0)
    ax.set_aspect("equal")
    ax.set_title(title or f"{mask.sum()} pixels, {len(spans)} rows, one span each")
    return {"image": img, "spans": coll, "outline": outline, "centres": centres}
