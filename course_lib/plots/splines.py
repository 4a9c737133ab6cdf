"""Figures for Q4: control polygons, segments, end derivatives and the B-spline's convex hull.

:func:`spline_scene` computes everything a figure of one curve shows (pure NumPy, no drawing),
rounded to display precision, 1e-4 of the points' span (:func:`display_decimals`): the
students' copy computes it with the course's graded functions compiled into it alone, so what
it returns is a drawing's data, never a graded answer (docs/students-copy.md);
:func:`draw_curve` draws it once and returns the artists, and :func:`update_curve` moves those
artists to a new scene in place, which is what the explorer of
:mod:`course_lib.widgets.splines` calls on every change. The other functions build the
notebook's figures: :func:`compare_splines` (Q4(a)), :func:`plot_blending_functions` (Q4(a)/(b))
and :func:`plot_end_rules` (the sketches of Q4(c)(i)).
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import FancyArrowPatch, Patch, Polygon

from .. import splines
from ..plotting import COLOURS, equal_axes, new_figure

__all__ = [
    "EXAMPLE_POINTS",
    "compare_splines",
    "display_decimals",
    "draw_curve",
    "legend_handles",
    "plot_blending_functions",
    "plot_end_rules",
    "spline_scene",
    "update_curve",
]

#: Five control points used by the notebook's figures (an open, gently winding path).
EXAMPLE_POINTS = np.array([[0.0, 0.0], [1.0, 2.0], [3.0, 2.5], [4.0, 0.5], [6.0, 1.0]])

_KIND_TITLE = {"catmull-rom": "Catmull-Rom", "b-spline": "B-spline"}
_SEGMENT_CMAP = plt.get_cmap("viridis")
_P1_COLOUR = COLOURS["highlight"]
_P2_COLOUR = "#e377c2"
_END_COLOUR = "black"
#: the weights of a, b, c, d: a colour and a marker each (told apart without the colour)
_WEIGHT_COLOURS = (COLOURS["curve"], COLOURS["received"], COLOURS["reference"], COLOURS["hull"])
_WEIGHT_MARKERS = ("o", "s", "^", "D")


def spline_scene(points, kind, end_rule=None, phantoms=None, n_per_segment=32):
    """Everything a figure of one multi-segment curve shows.

    Parameters
    ----------
    points : array_like, shape (m, 2)
        The user's control points.
    kind : {"catmull-rom", "b-spline"}
    end_rule : {None, "d=b", "d=2c-b", "d=c", "free"}
        How the curve is terminated. ``None``: no phantom points (``m - 3`` segments);
        a rule of Q4(c): phantom points made by :func:`course_lib.splines.phantom_point` at both
        ends; ``"free"``: the two phantom points are given in ``phantoms``.
    phantoms : array_like, shape (2, 2), optional
        ``[start_phantom, end_phantom]`` for ``end_rule="free"``.
    n_per_segment : int
        Samples per segment.

    Returns
    -------
    dict
        Every coordinate and vector rounded to :func:`display_decimals` of the extended
        polygon. ``control`` (m, 2), the points as given; ``extended`` (the polygon the
        segments use); ``phantoms`` (0 or 2 points); ``segments`` (N, n_per_segment + 1, 2);
        ``abcd`` (4, 2), the geometry of the last segment; ``end`` = ``(p, p1, p2)`` at its
        ``t = 1``; ``hull`` (h, 2), the convex hull of the extended polygon (``None`` for
        Catmull-Rom).
    """
    P = np.asarray(points, dtype=float)
    if end_rule == "free":
        if phantoms is None:
            raise ValueError("phantoms must be given (2 points) when end_rule is 'free'")
        ph = np.asarray(phantoms, dtype=float).reshape(2, 2)
        ext = np.vstack([ph[0], P, ph[1]])
    elif end_rule is None:
        ext = P
    else:
        ext = splines.extend_with_phantoms(P, end_rule)
    M = splines.basis_matrix(kind)
    Gs = splines.segment_geometries(ext)
    t = np.linspace(0.0, 1.0, n_per_segment + 1)
    segments = np.einsum("sj,ijk->isk", splines.parameter_row(t) @ M, Gs)
    a, b, c, d = Gs[-1]
    end = splines.end_derivatives(M, a, b, c, d)
    # what is drawn and read out, at display precision (docs/students-copy.md)
    decimals = display_decimals(ext)
    ext = np.round(ext, decimals)
    ph = ext[[0, -1]] if end_rule is not None else np.empty((0, 2))
    hull = splines.convex_hull(ext) if kind == "b-spline" else None
    return {"kind": kind, "end_rule": end_rule, "control": P, "extended": ext, "phantoms": ph,
            "segments": np.round(segments, decimals), "abcd": ext[-4:],
            "end": tuple(np.round(v, decimals) for v in end), "hull": hull}


def display_decimals(points) -> int:
    """Decimals that round a figure's coordinates to about 1e-4 of the span of ``points``
    (its largest extent along an axis): far finer than a pixel, far coarser than the 1e-6 a
    grader compares at."""
    span = float(np.max(np.ptp(np.asarray(points, dtype=float), axis=0), initial=0.0))
    if not np.isfinite(span) or span <= 0.0:
        span = 1.0
    return int(4 - np.floor(np.log10(span)))


def draw_curve(scene, ax=None, *, show_hull=True, show_end=True, show_labels=True,
               deriv_scale=(1.0, 0.5), legend=True):
    """Draw a :func:`spline_scene` on ``ax``; returns the artists as a dict.

    The control polygon is dashed grey, phantom points are hollow with a dotted link, each
    segment has its own colour, the curve's end ``p(1)`` is a black dot with arrows for ``p'``
    (red) and ``p''`` (pink) drawn to scale times ``deriv_scale = (s1, s2)`` (vectors per unit
    ``t``; the legend states the factors), the last segment's four points are labelled
    ``a, b, c, d`` (Q4's names), and for the B-spline the convex hull of all control points is
    shaded. ``legend=True`` puts the legend below the axes.
    """
    if ax is None:
        _, ax = new_figure()
    equal_axes(ax, f"{_KIND_TITLE[scene['kind']]}  ({_rule_title(scene['end_rule'])})")
    ax.set_adjustable("box")  # fixed limits (the explorer drags points within them)
    art = {"ax": ax, "deriv_scale": deriv_scale}
    art["hull"] = ax.add_patch(Polygon(np.zeros((3, 2)), closed=True, facecolor=COLOURS["hull"],
                                       alpha=0.15, edgecolor=COLOURS["hull"], lw=1,
                                       label="convex hull", visible=False, zorder=0))
    art["show_hull"] = show_hull
    (art["polygon"],) = ax.plot([], [], "--", color=COLOURS["control"], lw=1,
                                label="control polygon", zorder=1)
    (art["phantom_links"],) = ax.plot([], [], ":", color=COLOURS["control"], lw=1, zorder=1)
    (art["control"],) = ax.plot([], [], "o", color=COLOURS["control"], ms=7, zorder=4,
                                label="control points")
    (art["phantom"],) = ax.plot([], [], "o", mfc="white", mec=COLOURS["control"], ms=7,
                                zorder=4, label="phantom points")
    n_seg = scene["segments"].shape[0]
    shades = np.linspace(0.0, 0.85, n_seg) if n_seg > 1 else [0.3]
    art["segments"] = [ax.plot([], [], "-", lw=2.5, color=_SEGMENT_CMAP(x), zorder=2)[0]
                       for x in shades]
    (art["end"],) = ax.plot([], [], "o", color=_END_COLOUR, ms=8, zorder=5,
                            label="p(1), end of the last segment")
    art["end"].set_visible(show_end)
    art["p1"] = ax.add_patch(FancyArrowPatch((0, 0), (0, 0), arrowstyle="-|>", mutation_scale=14,
                                             color=_P1_COLOUR, lw=2, zorder=6, visible=show_end))
    art["p2"] = ax.add_patch(FancyArrowPatch((0, 0), (0, 0), arrowstyle="-|>", mutation_scale=14,
                                             color=_P2_COLOUR, lw=2, zorder=6, visible=show_end))
    art["labels"] = [ax.annotate(name, (0, 0), xytext=(6, 6), textcoords="offset points",
                                 fontsize=12, fontweight="bold", visible=show_labels)
                     for name in "abcd"]
    update_curve(art, scene)
    art["legend"] = None
    if legend:
        art["legend"] = ax.legend(handles=legend_handles(art), fontsize=7, ncol=3,
                                  loc="upper center", bbox_to_anchor=(0.5, -0.08))
    _fit_limits(ax, scene)
    return art


def legend_handles(art):
    """Legend entries for the artists of :func:`draw_curve` (segments are told by colour)."""
    handles = [art["polygon"], art["control"], art["phantom"]]
    if art["show_hull"]:  # a proxy: the hull patch itself is hidden for Catmull-Rom
        handles.append(Patch(facecolor=COLOURS["hull"], alpha=0.15, edgecolor=COLOURS["hull"],
                             label="convex hull (B-spline)"))
    if art["end"].get_visible():
        s1, s2 = art["deriv_scale"]
        handles += [art["end"],
                    Line2D([], [], color=_P1_COLOUR, lw=2, label=_scaled("p'(1)", s1)),
                    Line2D([], [], color=_P2_COLOUR, lw=2, label=_scaled("p''(1)", s2))]
    return handles


def _scaled(name, s):
    return name if s == 1 else f"{s:g} × {name}"


def update_curve(art, scene):
    """Move the artists returned by :func:`draw_curve` to a new scene, in place."""
    P, ph = scene["control"], scene["phantoms"]
    art["polygon"].set_data(P[:, 0], P[:, 1])
    art["control"].set_data(P[:, 0], P[:, 1])
    art["phantom"].set_data(ph[:, 0], ph[:, 1])
    if len(ph):
        links = np.array([ph[0], P[0], [np.nan, np.nan], P[-1], ph[1]])
    else:
        links = np.empty((0, 2))
    art["phantom_links"].set_data(links[:, 0], links[:, 1])
    for line, seg in zip(art["segments"], scene["segments"]):
        line.set_data(seg[:, 0], seg[:, 1])
    hull = scene["hull"]
    if hull is not None and art["show_hull"]:
        art["hull"].set_xy(_hull_polygon(hull))
        art["hull"].set_visible(True)
    else:
        art["hull"].set_visible(False)
    p, p1, p2 = scene["end"]
    s1, s2 = art["deriv_scale"]
    art["end"].set_data([p[0]], [p[1]])
    art["p1"].set_positions(tuple(p), tuple(p + s1 * p1))
    art["p2"].set_positions(tuple(p), tuple(p + s2 * p2))
    for text, q in zip(art["labels"], scene["abcd"]):
        text.xy = tuple(q)
    _offset_coincident_labels(art["labels"], scene["abcd"])
    return art


def compare_splines(points=EXAMPLE_POINTS, end_rule="d=2c-b", n_per_segment=32):
    """Catmull-Rom and B-spline on the same control points, side by side (Q4(a)).

    Returns ``(fig, (art_cr, art_bs))`` with the artists of :func:`draw_curve`.
    """
    fig, axes = new_figure(ncols=2, size=4.5)
    arts = []
    for ax, kind in zip(axes.ravel(), splines.KINDS):
        scene = spline_scene(points, kind, end_rule, n_per_segment=n_per_segment)
        arts.append(draw_curve(scene, ax, legend=False))
    _share_limits(axes.ravel())
    fig.legend(handles=legend_handles(arts[1]), loc="outside lower center", ncol=4, fontsize=8)
    return fig, tuple(arts)


def plot_blending_functions(ax=None, n=101):
    """The four blending functions ``[t^3 t^2 t 1] M`` of both splines over ``0 <= t <= 1``.

    Solid: B-spline (non-negative, sum 1: the convex-hull property); dashed: Catmull-Rom
    (negative lobes for ``a`` and ``d``, and ``b``'s weight is 1 at ``t = 0``: interpolation).
    Returns the list of lines (their data at 4 decimals).
    """
    if ax is None:
        _, ax = new_figure(size=4.5)
    t = np.linspace(0.0, 1.0, n)
    lines = []
    for kind, style in (("b-spline", "-"), ("catmull-rom", "--")):
        # weights between -0.1 and 1: rounded to display precision
        W = np.round(splines.parameter_row(t) @ splines.basis_matrix(kind), 4)
        for j, name in enumerate("abcd"):
            lines += ax.plot(t, W[:, j], style, color=_WEIGHT_COLOURS[j], lw=2,
                             marker=_WEIGHT_MARKERS[j], markevery=max(1, (n - 1) // 5), ms=4,
                             label=f"{_KIND_TITLE[kind]}: {name}")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel("t")
    ax.set_ylabel("weight")
    ax.set_title("Blending functions [t³ t² t 1] M")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    return lines


def plot_end_rules(points=EXAMPLE_POINTS, rules=("d=b", "d=2c-b"), n_per_segment=32):
    """The sketches of Q4(c)(i): both splines (rows) terminated by each rule (columns).

    Returns ``(fig, arts)`` with ``arts[i][j]`` the artists of kind ``i``, rule ``j``.
    """
    fig, axes = new_figure(ncols=len(rules), nrows=2, size=3.8)
    axes = np.asarray(axes).reshape(2, len(rules))
    arts = []
    for i, kind in enumerate(splines.KINDS):
        row = []
        for j, rule in enumerate(rules):
            scene = spline_scene(points, kind, rule, n_per_segment=n_per_segment)
            row.append(draw_curve(scene, axes[i, j], legend=False))
        arts.append(row)
    _share_limits(axes.ravel())
    fig.legend(handles=legend_handles(arts[1][0]), loc="outside lower center", ncol=4,
               fontsize=8)
    return fig, arts


# --------------------------------------------------------------------------------------------


def _rule_title(rule):
    if rule is None:
        return "no phantom points"
    if rule == "free":
        return "free phantom points"
    return rule.replace("=", " = ")


def _hull_polygon(hull):
    """A drawable polygon even for a degenerate (1- or 2-point) hull."""
    return hull if len(hull) >= 3 else np.resize(hull, (3, 2))


def _offset_coincident_labels(labels, abcd):
    """Stack the labels of coincident points (e.g. d = b) so both names stay readable."""
    for i, text in enumerate(labels):
        same = [j for j in range(i) if np.allclose(abcd[j], abcd[i])]
        text.set_position((6, 6 + 13 * len(same)))


def _fit_limits(ax, scene, margin=0.15):
    pts = [scene["extended"], scene["segments"].reshape(-1, 2)]
    lo = np.min([q.min(axis=0) for q in pts], axis=0)
    hi = np.max([q.max(axis=0) for q in pts], axis=0)
    pad = margin * max(float(np.max(hi - lo)), 1e-9)
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)


def _share_limits(axes):
    x = [ax.get_xlim() for ax in axes]
    y = [ax.get_ylim() for ax in axes]
    for ax in axes:
        ax.set_xlim(min(a for a, _ in x), max(b for _, b in x))
        ax.set_ylim(min(a for a, _ in y), max(b for _, b in y))
