"""The Q3 case explorer and figures: drive the controls from Python and check the drawn
triangles against the geometry of the cube (vertices at the fraction iso along crossed edges)."""

from __future__ import annotations


import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest

from course_lib import marching_cubes as mc
from course_lib import mesh
from course_lib.plots import marching_cubes as plots
from course_lib.widgets.marching_cubes import CaseExplorer, case_explorer

CORNER_XYZ = np.array([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0),
                       (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)], float)


@pytest.fixture
def ex():
    e = case_explorer(1)
    yield e
    plt.close(e.fig)


def drawn(e):
    """The triangles held by the figure's Poly3DCollection, shape (t, 3, 3)."""
    faces = e.art["surface"]._faces
    return np.asarray(faces, float).reshape(-1, 3, 3)


def expected_points(index, iso):
    """Every crossed edge's vertex: iso of the way from the inside corner to the outside one."""
    pts = []
    for a in range(8):
        for b in range(a + 1, 8):
            if np.sum(np.abs(CORNER_XYZ[a] - CORNER_XYZ[b])) != 1:
                continue                                          # not a cube edge
            ia, ib = (index >> a) & 1, (index >> b) & 1
            if ia != ib:
                p_in, p_out = (CORNER_XYZ[a], CORNER_XYZ[b]) if ia else (CORNER_XYZ[b], CORNER_XYZ[a])
                pts.append(p_in + iso * (p_out - p_in))
    return np.unique(np.round(pts, 9), axis=0).reshape(-1, 3)


def test_case_one_single_triangle_moves_with_iso(ex):
    assert drawn(ex).shape == (1, 3, 3)
    np.testing.assert_allclose(np.sort(drawn(ex)[0], axis=0), np.sort(0.5 * np.eye(3), axis=0), atol=1e-12)
    ex.iso.value = 0.25
    got = drawn(ex)[0]
    np.testing.assert_allclose(sorted(map(tuple, got)), sorted(map(tuple, 0.25 * np.eye(3))), atol=1e-12)
    # the triangle faces away from the inside corner (the origin): normal along +(1, 1, 1)
    n = np.cross(got[1] - got[0], got[2] - got[0])
    assert np.all(n > 0)


@pytest.mark.parametrize("index", [3, 5, 26, 65, 135, 165, 200, 254])
def test_vertices_follow_interpolation(ex, index):
    ex.index.value = index
    for iso in (0.3, 0.7):
        ex.iso.value = iso
        tris = drawn(ex)
        assert len(tris) == mc.N_TRIANGLES[index]
        got = np.unique(np.round(tris.reshape(-1, 3), 9), axis=0)
        np.testing.assert_allclose(got, expected_points(index, iso), atol=1e-9)


def test_three_controls_stay_in_step(ex):
    ex.case.value = 13
    assert ex.index.value == mc.BASE_CASES[13].index
    assert [b.value for b in ex.corners] == [bool((165 >> c) & 1) for c in range(8)]
    ex.corners[1].value = True                        # toggle corner 1 on
    assert ex.index.value == 165 | 2
    assert ex.case.value == mc.case_of(167)
    ex.index.value = 0
    assert not any(b.value for b in ex.corners) and len(drawn(ex)) == 0
    assert ex.case.value == 0


def test_corner_markers_show_inside(ex):
    ex.index.value = 0b10000001                       # corners 0 and 7
    colours = [line.get_markerfacecolor() for line in ex.art["corners"]]
    inside = [c for c, col in enumerate(colours) if col != "white"]
    assert inside == [0, 7]


def test_alternative_triangulation_only_for_ambiguous(ex):
    ex.case.value = 3                                 # two corners on a face diagonal
    apart = drawn(ex).copy()
    assert not ex.alternative.disabled
    ex.alternative.value = True
    joined = drawn(ex)
    # apart: two separate corner triangles; joined: a band through the cell (one piece)
    assert len(apart) == 2 and len(joined) == 4
    assert _components(apart) == 2 and _components(joined) == 1
    ex.index.value = 10                               # case 3 in another orientation: the
    assert ex.alternative.disabled                    # alternative is (c.1)'s to work out
    assert len(drawn(ex)) == 2 and "yours to work out" in ex.info.value
    ex.case.value = 2                                 # not ambiguous: switch disabled
    assert ex.alternative.disabled
    assert len(drawn(ex)) == mc.N_TRIANGLES[mc.BASE_CASES[2].index]


def _components(tris):
    pts, inv = np.unique(np.round(tris.reshape(-1, 3), 9), axis=0, return_inverse=True)
    faces = inv.reshape(-1, 3)
    parent = list(range(len(pts)))

    def find(i):
        while parent[i] != i:
            i = parent[i]
        return i

    for a, b, c in faces:
        parent[find(b)] = find(a)
        parent[find(c)] = find(a)
    return len({find(i) for i in range(len(pts))})


def test_each_control_change_redraws_once(ex, monkeypatch):
    """Every change of the case index triggers exactly one redraw (its speed is measured in
    benchmarks/bench_widgets.py, not here)."""
    calls = []
    monkeypatch.setattr(ex, "_redraw", lambda: calls.append(1))
    for k in range(1, 41):
        ex.index.value = (37 * k + 1) % 256     # never the starting index 1
    assert len(calls) == 40


def test_bad_arguments():
    with pytest.raises(ValueError):
        CaseExplorer(index=300)
    with pytest.raises(ValueError):
        CaseExplorer(iso=1.0)


def test_widget_layout(ex):
    box = ex.widget
    assert box is ex.widget and len(box.children) == 2


# --------------------------------------------------------------------------------------------
# figures


def test_base_cases_figure():
    fig, arts = plots.plot_base_cases()
    counts = [len(np.asarray(a["surface"]._faces)) for a in arts]
    assert counts == [0, 1, 2, 2, 2, 3, 3, 3, 2, 4, 4, 4, 4, 4, 4]   # Lorensen's figure
    starred = [a["surface"].axes.get_title().split()[1].endswith("*") for a in arts]
    assert [k for k, s in enumerate(starred) if s] == [3, 6, 7, 10, 12, 13]   # the exam's six
    plt.close(fig)
    # the notebook draws it before asking which cases are ambiguous: no star, no hint
    fig, arts = plots.plot_base_cases(mark_ambiguous=False)
    assert not any("*" in a["surface"].axes.get_title() for a in arts)
    assert "ambiguous" not in fig._suptitle.get_text()
    plt.close(fig)


def test_hole_figure_outlines_the_hole():
    art = plots.plot_hole()
    segs = np.asarray(art["hole"]._segments3d, float)        # the red outline, (4, 2, 3)
    assert segs.shape == (4, 2, 3)
    np.testing.assert_allclose(segs[:, :, 0], 2.0, atol=1e-12)          # in the shared face x = 2
    # the outline is a closed loop: every end point is used by exactly two segments
    _, counts = np.unique(np.round(segs.reshape(-1, 3), 9), axis=0, return_counts=True)
    assert np.all(counts == 2)
    plt.close("all")


def test_prism_figure_title_is_equation_4():
    art = plots.plot_projected_prism(a=(0, 0, 2), b=(1, 0, 2), c=(0, 1, 2))
    title = art["triangle"].axes.get_title()
    assert "A = 0.500" in title and "l = 2.000" in title and "V = A l = 1.000" in title
    plt.close("all")


def test_other_figures_draw():
    ax = plots.plot_cube_numbering()
    assert len(ax["corner_labels"]) == 8 and len(ax["edge_labels"]) == 12
    lines = plots.plot_ambiguous_face()
    assert len(lines) == 4
    art = plots.plot_sphere_mesh()
    assert mesh.is_closed_consistent(art["faces"])
    _fig, arts = plots.plot_ambiguous_cases()
    assert len(arts) == 12
    plt.close("all")


# --------------------------------------------------------------------------------------------
# what the figures draw without the graded maths (the students' copy has none of it)


@pytest.mark.parametrize("alternative", [False, True])
def test_drawn_triangles_are_the_references_at_display_precision(alternative):
    """Every case at iso-levels across the explorer's slider: the drawn triangles are those of
    the instructors' :func:`~course_lib.marching_cubes.cell_triangles` (the table's rows,
    vertices interpolated by the reference) within the display precision, 1e-4."""
    for index in range(256):
        if alternative and not plots.shows_alternative(index):
            if mc.ambiguous_faces(index):       # another orientation: (c.1)'s hidden cases
                with pytest.raises(ValueError, match="representatives"):
                    plots.drawn_triangles(index, 0.5, alternative=True)
            continue
        for iso in (0.02, 0.13, 0.37, 0.5, 0.81, 0.98):
            got = plots.drawn_triangles(index, iso, alternative=alternative)
            want = mc.cell_triangles(plots.case_values(index), iso, alternative=alternative)
            assert got.shape == want.shape, (index, iso)
            np.testing.assert_allclose(got, want, rtol=0, atol=0.5e-4, err_msg=str((index, iso)))


def test_drawn_triangles_refuse_bad_arguments():
    for index, iso in ((256, 0.5), (-1, 0.5), (3, 0.0), (3, 1.0)):
        with pytest.raises(ValueError):
            plots.drawn_triangles(index, iso)


def _pixels(fig):
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba()).copy()


@pytest.mark.parametrize("index, iso, alternative", [(1, 0.5, False), (165, 0.3, False),
                                                     (165, 0.74, True), (26, 0.61, False)])
def test_explorer_renders_the_references_figure(index, iso, alternative):
    """The explorer's figure, pixel for pixel, is the one drawn from the reference's triangles."""
    e = CaseExplorer(index=index, iso=iso)
    e.alternative.value = alternative
    ours = _pixels(e.fig)
    want = mc.cell_triangles(plots.case_values(index), iso, alternative=alternative)
    e.art["surface"].set_verts(list(want))
    assert np.array_equal(_pixels(e.fig), ours)
    plt.close(e.fig)


def test_sphere_and_hole_figures_show_the_references_meshes():
    """The sphere and the hole are the meshes the instructors' marching cubes makes of the same
    volumes (their numbers shipped in the students' copy, :mod:`course_lib.mc_results`)."""
    art = plots.plot_sphere_mesh()
    n, r = 12, 4.2
    c = (n - 1) / 2 + 0.1
    verts, faces = mc.marching_cubes(mc.sphere_field((n, n, n), (c, c, c)), r ** 2)
    np.testing.assert_array_equal(mesh.canonical_triangles(art["verts"], art["faces"]),
                                  mesh.canonical_triangles(verts, faces))
    title = art["surface"].axes.get_title()
    assert f"{len(faces)} triangles; volume {mesh.mesh_volume(verts, faces):.1f}" in title
    plt.close("all")
    art = plots.plot_hole()
    _, verts, faces = mc.hole_demo()
    drawn_hole = np.asarray(art["hole"]._segments3d, float)
    np.testing.assert_array_equal(drawn_hole, verts[mesh.boundary_edges(faces)])
    plt.close("all")
