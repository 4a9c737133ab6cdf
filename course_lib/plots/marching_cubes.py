"""Figures for Q3: the numbered cube, the 15 cases, ambiguous faces, the hole, a triangulated
sphere and the projected prism of equation (4).

Every function takes an optional ``ax`` (a 3-D axes where the figure is 3-D) and returns the
artists it drew, so that the case explorer (:mod:`course_lib.widgets.marching_cubes`) can update
them in place with ``set_verts`` and ``set_data_3d``.

Nothing here runs the graded maths (the students' copy of the library has none of it): a cell
of the case figures has corner values 0 (inside) and 1 (outside), so its triangles are the rows
of :data:`~course_lib.marching_cubes.TRI_TABLE` with each vertex at the fraction ``iso`` of its
edge from the inside corner (:func:`drawn_triangles`, drawn to display precision); the joined
(alternative) triangulation of Q3(c) is drawn for the representative of each ambiguous case
only (:func:`shows_alternative`: the graded question is the other orientations); the sphere
and the hole are meshes the course's references made when the library was built
(:mod:`course_lib.mc_results`).
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

from .. import _mc_case_data
from .. import marching_cubes as mc
from .. import mc_results
from ..plotting import COLOURS
from .describe import num, set_summary

__all__ = [
    "case_values",
    "draw_case",
    "draw_cube",
    "drawn_triangles",
    "new_3d_axes",
    "plot_ambiguous_cases",
    "plot_ambiguous_face",
    "plot_base_cases",
    "plot_cube_numbering",
    "plot_hole",
    "plot_projected_prism",
    "plot_sphere_mesh",
    "shows_alternative",
    "update_case",
]

SURFACE = "#4c9be8"
INSIDE = COLOURS["highlight"]
OUTSIDE = "white"
#: decimals of the drawn case triangles: display precision (1e-4 of the unit cell), far finer
#: than a pixel; the explorer's iso-levels (steps of 0.01) are drawn exactly
DISPLAY_DECIMALS = 4


def new_3d_axes(ax=None, size=4.0):
    """``ax`` if given, else a fresh 3-D axes in a new figure."""
    if ax is not None:
        return ax
    fig = plt.figure(figsize=(size, size))
    return fig.add_subplot(projection="3d")


def _tidy(ax, lim=(-0.1, 1.1), title=None):
    ax.set_xlim(*lim)
    ax.set_ylim(*lim)
    ax.set_zlim(*lim)
    ax.set_box_aspect((1, 1, 1))
    ax.set_axis_off()
    ax.view_init(elev=22, azim=-35)
    if title:
        ax.set_title(title, fontsize=9)


def case_values(index: int, iso: float = 0.5) -> np.ndarray:
    """Corner values for case ``index``: 0 at inside corners, 1 at outside ones.

    With these values the vertex on every crossed edge sits at the fraction ``iso`` of the way
    from the inside corner to the outside one.
    """
    return np.array([0.0 if (int(index) >> c) & 1 else 1.0 for c in range(8)])


def draw_cube(ax, labels: bool = False):
    """The unit cube's 12 edges (and optionally corner and edge numbers); returns the artists."""
    segs = mc.CORNERS[mc.EDGES].astype(float)
    art = {"edges": ax.add_collection3d(Line3DCollection(segs, colors="0.35", linewidths=1.0))}
    if labels:
        art["corner_labels"] = [
            ax.text(*(1.12 * (p - 0.5) + 0.5), str(c), color=INSIDE, fontsize=11,
                    fontweight="bold", ha="center", va="center")
            for c, p in enumerate(mc.CORNERS.astype(float))]
        art["edge_labels"] = [
            ax.text(*(segs[e].mean(axis=0) + 0.06 * (segs[e].mean(axis=0) - 0.5)), str(e),
                    color=COLOURS["curve"], fontsize=9, ha="center", va="center")
            for e in range(12)]
    return art


def shows_alternative(index: int) -> bool:
    """Whether the figures and the explorer draw case ``index``'s alternative triangulation:
    for the representative of each of Lorensen's six ambiguous cases (the figure of Q3(c)),
    not for their other orientations, which are ``alternative_triangulation``'s hidden cases."""
    return int(index) in _mc_case_data.SHOWN_INDICES


def drawn_triangles(index: int, iso: float = 0.5, alternative: bool = False) -> np.ndarray:
    """The triangles drawn for case ``index`` at level ``iso``, shape ``(t, 3, 3)``.

    The corners of the drawn cell hold 0 (inside) and 1 (outside), so each vertex sits at the
    fraction ``iso`` of its edge from the inside corner (Q3(a)); the edges are the case's row of
    :data:`~course_lib.marching_cubes.TRI_TABLE` (with ``alternative``, the joined triangulation
    of Q3(c), for the cases of :func:`shows_alternative` only). Coordinates are rounded to
    :data:`DISPLAY_DECIMALS`.
    """
    index = int(index)
    if not 0 <= index <= 255:
        raise ValueError(f"index must be a case number from 0 to 255, got {index}")
    iso = float(iso)
    if not 0.0 < iso < 1.0:
        raise ValueError(f"iso must lie strictly between 0 and 1, got {iso}")
    if alternative and not shows_alternative(index):
        raise ValueError(f"the alternative triangulation is drawn only for the representatives "
                         f"{_mc_case_data.SHOWN_INDICES} of the ambiguous cases, not case {index}")
    if alternative:
        edges = np.array(_mc_case_data.shown_alternatives()[index], dtype=np.int64)
    else:
        edges = mc.TRI_TABLE[index, :mc.N_TRIANGLES[index]]             # (t, 3)
    a, b = mc.EDGES[edges, 0], mc.EDGES[edges, 1]
    t = np.where((index >> a) & 1, iso, 1.0 - iso)          # from a: iso if a is inside
    tris = mc.CORNERS[a] + t[..., None] * (mc.CORNERS[b] - mc.CORNERS[a])
    return np.round(tris, DISPLAY_DECIMALS) + 0.0


def draw_case(index: int, ax=None, alternative: bool = False, iso: float = 0.5,
              title: str | None = None):
    """One cell of case ``index``: cube, inside (red) / outside (white) corners, triangles.

    Returns a dict with ``"surface"`` (a ``Poly3DCollection``), ``"corners"`` (eight ``Line3D``
    markers) and ``"edges"``, ready for :func:`update_case`.
    """
    ax = new_3d_axes(ax)
    art = draw_cube(ax)
    art["surface"] = ax.add_collection3d(Poly3DCollection(
        [], facecolor=SURFACE, edgecolor="k", linewidths=0.6, alpha=0.85))
    art["corners"] = [ax.plot(*p[:, None].astype(float), "o", ms=7, mec="k")[0]
                      for p in mc.CORNERS]
    update_case(art, index, alternative=alternative, iso=iso)
    _tidy(ax, title=title)
    return art


def update_case(art, index: int, alternative: bool = False, iso: float = 0.5):
    """Move the artists of :func:`draw_case` to case ``index`` (no re-plotting).

    Returns the triangles drawn, shape ``(t, 3, 3)`` (:func:`drawn_triangles`).
    """
    tris = drawn_triangles(index, iso, alternative=alternative)
    art["surface"].set_verts(list(tris))
    inside = [c for c in range(8) if (int(index) >> c) & 1]
    for c, line in enumerate(art["corners"]):
        line.set_markerfacecolor(INSIDE if c in inside else OUTSIDE)
    set_summary(art["corners"][0].axes,
                f"Inside corners (filled): {', '.join(map(str, inside)) or 'none'}; "
                f"{len(tris)} triangle{'s' if len(tris) != 1 else ''} at iso-level {num(iso)}.")
    return tris


def plot_cube_numbering(ax=None):
    """The cube with its corner numbers (red) and edge numbers (blue), Lorensen/Bourke order."""
    ax = new_3d_axes(ax, size=4.5)
    art = draw_cube(ax, labels=True)
    for d, name in zip(np.eye(3), "xyz"):
        ax.quiver(-0.25, -0.25, -0.25, *(0.3 * d), color="0.5", arrow_length_ratio=0.25)
        ax.text(*(-0.25 + 0.38 * d), name, color="0.4")
    _tidy(ax, lim=(-0.3, 1.15), title="corner (red) and edge (blue) numbers")
    return art


def plot_base_cases(fig=None, alternative: bool = False, mark_ambiguous: bool = True):
    """The 15 cases of Q3(b) in a 3 x 5 grid; returns ``(fig, [art, ...])``.

    With ``mark_ambiguous`` a star marks the six cases with an ambiguous face (Q3(c)); the
    notebook draws the figure without it, before asking which cases those are.
    """
    fig = fig or plt.figure(figsize=(12, 7.5))
    arts = []
    for k, case in enumerate(mc.BASE_CASES):
        ax = fig.add_subplot(3, 5, k + 1, projection="3d")
        star = "*" if mark_ambiguous and case.ambiguous else ""
        arts.append(draw_case(case.index, ax, alternative=alternative,
                              title=f"case {case.number}{star} (index {case.index})"))
    note = " (* = ambiguous face)" if mark_ambiguous else ""
    fig.suptitle(f"Lorensen's 15 cases{note}; filled (red) corners are inside")
    return fig, arts


def plot_ambiguous_face(axes=None):
    """An ambiguous face and its two contour choices (Q3(c)); returns the drawn lines.

    Two corners on one diagonal are inside (value 0), two on the other outside (value 1): the
    four crossing points can be joined so that the inside corners are kept apart or joined.
    """
    if axes is None:
        _, axes = plt.subplots(1, 2, figsize=(7, 3.4))
    sq = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]], float)
    inside = [True, False, True, False]
    mids = np.array([[0.5, 0], [1, 0.5], [0.5, 1], [0, 0.5]])
    pairs = {"inside corners kept apart": [(3, 0), (1, 2)],
             "inside corners joined": [(0, 1), (2, 3)]}
    out = []
    for ax, (title, pp) in zip(axes, pairs.items()):
        ax.plot(sq[:, 0], sq[:, 1], color="0.35")
        for (x, y), ins in zip(sq[:4], inside):
            ax.plot(x, y, "o", ms=12, mec="k", mfc=INSIDE if ins else OUTSIDE)
        ax.plot(mids[:, 0], mids[:, 1], "s", color=SURFACE, ms=6)
        for a, b in pp:
            out.append(ax.plot(*mids[[a, b]].T, color=SURFACE, lw=3)[0])
        ax.set_title(title, fontsize=10)
        ax.set_aspect("equal")
        ax.set_xlim(-0.15, 1.15)
        ax.set_ylim(-0.15, 1.15)
        ax.set_axis_off()
    return out


def plot_ambiguous_cases(fig=None):
    """Each of the six ambiguous cases with its two triangulations (2 x 6 grid)."""
    fig = fig or plt.figure(figsize=(14, 5.2))
    amb = [c for c in mc.BASE_CASES if c.ambiguous]
    arts = []
    for k, case in enumerate(amb):
        for row, alt in enumerate((False, True)):
            ax = fig.add_subplot(2, len(amb), row * len(amb) + k + 1, projection="3d")
            label = "apart" if not alt else "joined"
            arts.append(draw_case(case.index, ax, alternative=alt,
                                  title=f"case {case.number}: inside {label}"))
    fig.suptitle("The six ambiguous cases: top, inside corners kept apart on every ambiguous "
                 "face (our table); bottom, joined (the alternative)")
    return fig, arts


def plot_hole(ax=None):
    """The two-cell example of Q3(c): mixing triangulations leaves a hole (drawn in red).

    Only the triangles of the two cells that share the ambiguous face ``x = 2`` are drawn: the
    left cell (alternative triangulation, inside corners joined) in blue, the right cell (our
    table, inside corners kept apart) in orange. Their contours on the shared face disagree, and
    the four edges that only one side uses (red) bound the hole.
    """
    ax = new_3d_axes(ax, size=5)
    verts, faces, holes = mc_results.hole_mesh()
    centroid = verts[faces].mean(axis=1)
    in_pair = np.all((centroid > [1, 1, 1]) & (centroid < [3, 2, 2]), axis=1)
    left = in_pair & (centroid[:, 0] < 2)
    right = in_pair & (centroid[:, 0] > 2)
    art = {
        "left": ax.add_collection3d(Poly3DCollection(verts[faces[left]], facecolor=SURFACE,
                                                     edgecolor="k", linewidths=0.6, alpha=0.8)),
        "right": ax.add_collection3d(Poly3DCollection(verts[faces[right]],
                                                      facecolor=COLOURS["received"],
                                                      edgecolor="k", linewidths=0.6, alpha=0.8)),
    }
    art["hole"] = ax.add_collection3d(Line3DCollection(verts[holes], colors=INSIDE, linewidths=3))
    cell = mc.CORNERS.astype(float) + 1.0
    art["cells"] = [ax.add_collection3d(Line3DCollection((cell + [dx, 0, 0])[mc.EDGES],
                                                         colors="0.5", linewidths=0.8))
                    for dx in (0, 1)]
    art["inside"] = ax.plot(*np.array([[2, 1, 1], [2, 2, 2]]).T, "o", ms=9, mfc=INSIDE,
                            mec="k", ls="")[0]
    ax.set_xlim(1, 3)
    ax.set_ylim(0.5, 2.5)
    ax.set_zlim(0.5, 2.5)
    ax.set_box_aspect((1, 1, 1))
    ax.set_axis_off()
    ax.view_init(elev=35, azim=-60)
    ax.set_title(f"left cell joins, right cell keeps apart: a hole with {len(holes)} edges (red)",
                 fontsize=9)
    art["holes"] = holes
    return art


def plot_sphere_mesh(ax=None):
    """The sphere of :data:`course_lib.mc_results.SPHERE_FIGURE` (radius 4.2 sampled on a
    12**3 grid) as the course's marching cubes triangulates it, with its volume by equation (4)."""
    ax = new_3d_axes(ax, size=5)
    n, radius = mc_results.SPHERE_FIGURE["n"], mc_results.SPHERE_FIGURE["radius"]
    verts, faces, v = mc_results.sphere_mesh()
    poly = ax.add_collection3d(Poly3DCollection(verts[faces], facecolor=SURFACE,
                                                edgecolor="k", linewidths=0.3, alpha=0.9))
    ax.set_xlim(0, n - 1)
    ax.set_ylim(0, n - 1)
    ax.set_zlim(0, n - 1)
    ax.set_box_aspect((1, 1, 1))
    ax.set_title(f"{len(faces)} triangles; volume {v:.1f} vs 4/3 pi r^3 = "
                 f"{mc.sphere_volume(radius):.1f}", fontsize=9)
    return {"surface": poly, "verts": verts, "faces": faces}


def plot_projected_prism(ax=None, a=(0.2, 0.1, 1.2), b=(1.0, 0.3, 1.7), c=(0.5, 0.9, 0.9)):
    """Equation (4): a triangle, its shadow on z = 0 and the prism between them.

    The prism's volume is the projected area ``A`` (equation (2)) times the height ``l`` of the
    centroid above the plane (equation (3)); the title gives both and their product.
    """
    ax = new_3d_axes(ax, size=5)
    tri = np.array([a, b, c], float)
    shadow = tri * [1, 1, 0]
    art = {
        "triangle": ax.add_collection3d(Poly3DCollection([tri], facecolor=SURFACE,
                                                         edgecolor="k", alpha=0.9)),
        "shadow": ax.add_collection3d(Poly3DCollection([shadow], facecolor="0.8",
                                                       edgecolor="0.4", alpha=0.7)),
        "sides": ax.add_collection3d(Line3DCollection(np.stack([tri, shadow], 1),
                                                      colors="0.4", linestyles="--")),
    }
    g = tri.mean(axis=0)
    art["height"] = ax.plot(*np.array([g * [1, 1, 0], g]).T, color=INSIDE, lw=2)[0]
    ax.text(*(g + [0.05, 0, -g[2] / 2]), "l", color=INSIDE, fontsize=12)
    ax.quiver(1.2, 1.2, 0, 0, 0, 0.5, color="k", arrow_length_ratio=0.2)
    ax.text(1.22, 1.2, 0.55, "n", fontsize=12)
    A = 0.5 * np.cross(tri[1] - tri[0], tri[2] - tri[0])[2]
    V = A * g[2]                                         # the title's own product, to 3 decimals
    ax.set_xlim(0, 1.3)
    ax.set_ylim(0, 1.3)
    ax.set_zlim(0, 1.8)
    ax.set_box_aspect((1.3, 1.3, 1.8))
    ax.view_init(elev=16, azim=-58)
    ax.set_title(f"A = {A:.3f}, l = {g[2]:.3f}, V = A l = {V:.3f}", fontsize=10)
    return art
