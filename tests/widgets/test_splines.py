"""The Q4 end-condition explorer and figures: drive the controls from Python (and the mouse
through synthetic matplotlib events) and check the drawn data against the exam's formulas."""

from __future__ import annotations


import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest
import shapely
from matplotlib.backend_bases import MouseEvent

from course_lib.plots import splines as plots
from course_lib.widgets.splines import (
    SplineEndExplorer,
    combination_tex,
    end_summary,
    spline_end_explorer,
)

P = np.array([[0.0, 0.0], [1.0, 2.0], [3.0, 2.5], [4.0, 0.5], [6.0, 1.0]])
A, B, C = P[-3], P[-2], P[-1]
#: what a figure draws is rounded to 1e-4 of the points' span (4 decimals for these points)
DRAWN = 0.5e-4 + 1e-12


@pytest.fixture
def ex():
    e = spline_end_explorer(P.copy())
    yield e
    plt.close(e.fig)


def end_marker(e):
    x, y = e.art["end"].get_data()
    return np.array([x[0], y[0]])


def arrow(e, name):
    """The vector an arrow patch draws (head minus tail), from its stored positions."""
    tail, head = e.art[name]._posA_posB
    return np.subtract(head, tail)


def test_bspline_d_2c_minus_b_ends_exactly_at_c(ex):
    ex.kind.value = "b-spline"
    ex.rule.value = "d=2c-b"
    np.testing.assert_allclose(end_marker(ex), C, atol=DRAWN)
    s1, _ = ex.art["deriv_scale"]
    np.testing.assert_allclose(arrow(ex, "p1"), s1 * (C - B), atol=DRAWN)  # p' = c - b
    np.testing.assert_allclose(arrow(ex, "p2"), 0.0, atol=DRAWN)  # p'' = 0
    # the last drawn segment ends at the marker, and starts at (a + 4b + c)/6
    seg = np.column_stack(ex.art["segments"][-1].get_data())
    np.testing.assert_allclose(seg[-1], C, atol=DRAWN)
    np.testing.assert_allclose(seg[0], (A + 4 * B + C) / 6, atol=DRAWN)


def test_switching_to_d_equals_b_moves_the_end(ex):
    ex.kind.value = "b-spline"
    ex.rule.value = "d=2c-b"
    before = end_marker(ex)
    ex.rule.value = "d=b"
    np.testing.assert_allclose(end_marker(ex), (2 * B + 4 * C) / 6, atol=DRAWN)
    assert np.linalg.norm(end_marker(ex) - before) > 0.1
    _, s2 = ex.art["deriv_scale"]
    np.testing.assert_allclose(arrow(ex, "p1"), 0.0, atol=DRAWN)  # zero velocity
    np.testing.assert_allclose(arrow(ex, "p2"), s2 * (2 * B - 2 * C), atol=DRAWN)


def test_catmull_rom_end_vectors(ex):
    ex.kind.value = "catmull-rom"
    ex.rule.value = "d=b"
    s1, s2 = ex.art["deriv_scale"]
    np.testing.assert_allclose(end_marker(ex), C, atol=DRAWN)
    np.testing.assert_allclose(arrow(ex, "p1"), 0.0, atol=DRAWN)
    np.testing.assert_allclose(arrow(ex, "p2"), s2 * (-A + 6 * B - 5 * C), atol=DRAWN)
    ex.rule.value = "d=2c-b"
    np.testing.assert_allclose(arrow(ex, "p1"), s1 * (C - B), atol=DRAWN)
    np.testing.assert_allclose(arrow(ex, "p2"), s2 * (-A + 2 * B - C), atol=DRAWN)


def test_formula_text_changes_with_the_case(ex):
    ex.kind.value = "catmull-rom"
    ex.rule.value = "d=b"
    text = ex.formulas.value
    assert r"\mathbf p'' = -\mathbf a + 6\mathbf b - 5\mathbf c" in text
    assert r"\mathbf p' = \mathbf 0" in text
    ex.rule.value = "d=2c-b"
    assert ex.formulas.value != text
    assert r"\mathbf p' = \mathbf c - \mathbf b" in ex.formulas.value
    assert r"-\mathbf a + 2\mathbf b - \mathbf c" in ex.formulas.value
    ex.kind.value = "b-spline"
    assert r"\mathbf p'' = \mathbf 0" in ex.formulas.value
    ex.rule.value = "d=b"  # (2b + 4c)/6, written in lowest terms
    assert r"\mathbf p = \tfrac{1}{3}(\mathbf b + 2\mathbf c)" in ex.formulas.value
    assert r"\mathbf p'' = 2\mathbf b - 2\mathbf c" in ex.formulas.value


def test_combination_tex_on_the_exam_rows():
    assert combination_tex([0, 0, 1, 0]) == r"\mathbf c"
    assert combination_tex([0, -0.5, 0, 0.5]) == r"\tfrac{1}{2}(\mathbf d - \mathbf b)"
    assert combination_tex([-1, 4, -5, 2]) == \
        r"-\mathbf a + 4\mathbf b - 5\mathbf c + 2\mathbf d"
    assert combination_tex([0, 1 / 6, 4 / 6, 1 / 6]) == \
        r"\tfrac{1}{6}(\mathbf b + 4\mathbf c + \mathbf d)"
    assert combination_tex([0, 0, 0, 0]) == r"\mathbf 0"


def test_hull_shown_only_for_the_bspline_and_contains_the_curve(ex):
    ex.kind.value = "catmull-rom"
    assert not ex.art["hull"].get_visible()
    ex.kind.value = "b-spline"
    ex.rule.value = "d=2c-b"
    assert ex.art["hull"].get_visible()
    hull = shapely.Polygon(ex.art["hull"].get_xy())
    ext = np.vstack([2 * P[0] - P[1], P, 2 * C - B])  # phantoms of d = 2c - b at both ends
    assert hull.area == pytest.approx(shapely.MultiPoint(ext).convex_hull.area)
    for line in ex.art["segments"]:
        xy = np.column_stack(line.get_data())
        assert np.all(shapely.distance(hull, shapely.points(xy)) < 1.5 * DRAWN)
    ex.show_hull.value = False
    assert not ex.art["hull"].get_visible()


def test_sliders_move_the_selected_point(ex):
    ex.kind.value = "catmull-rom"
    ex.rule.value = "d=2c-b"
    ex.point.value = len(P) - 1  # c
    ex.x.value, ex.y.value = 5.0, 2.0
    np.testing.assert_allclose(ex.points[-1], [5.0, 2.0], atol=1e-12)
    np.testing.assert_allclose(end_marker(ex), [5.0, 2.0], atol=DRAWN)  # CR interpolates c
    np.testing.assert_allclose(ex.art["phantom"].get_data()[0][-1], 2 * 5.0 - B[0], atol=DRAWN)


def test_free_phantom_point(ex):
    ex.kind.value = "b-spline"
    ex.rule.value = "d=c"
    ex.rule.value = "free"  # the free phantoms start where d = c put them
    np.testing.assert_allclose(ex.phantoms[1], C, atol=DRAWN)
    np.testing.assert_allclose(end_marker(ex), (B + 5 * C) / 6, atol=DRAWN)
    ex.point.value = "end"
    ex.x.value, ex.y.value = 7.0, 3.0
    d = np.array([7.0, 3.0])
    np.testing.assert_allclose(end_marker(ex), (B + 4 * C + d) / 6, atol=DRAWN)
    assert r"\tfrac{1}{6}(\mathbf b + 4\mathbf c + \mathbf d)" in ex.formulas.value


def _mouse(e, name, xy, button=1):
    x, y = e.ax.transData.transform(xy)
    event = MouseEvent(name, e.fig.canvas, x, y, button=button)
    e.fig.canvas.callbacks.process(name, event)


def test_dragging_moves_a_control_point(ex):
    ex.kind.value = "catmull-rom"
    ex.rule.value = "d=b"
    ex.fig.canvas.draw()  # fix the layout so data -> pixel transforms are final
    _mouse(ex, "button_press_event", P[2])
    assert ex.point.value == 2
    _mouse(ex, "motion_notify_event", (2.5, 3.0))
    _mouse(ex, "button_release_event", (2.0, 3.5))
    np.testing.assert_allclose(ex.points[2], [2.0, 3.5], atol=1e-9)
    np.testing.assert_allclose((ex.x.value, ex.y.value), (2.0, 3.5), atol=1e-9)
    # Catmull-Rom interpolates: the join between segments 1 and 2 is the moved point
    seg = np.column_stack(ex.art["segments"][1].get_data())
    np.testing.assert_allclose(seg[-1], [2.0, 3.5], atol=1e-9)
    # after release, motion does nothing
    _mouse(ex, "motion_notify_event", (1.0, 1.0))
    np.testing.assert_allclose(ex.points[2], [2.0, 3.5], atol=1e-9)


def test_press_away_from_points_drags_nothing(ex):
    ex.fig.canvas.draw()
    before = ex.points.copy()
    _mouse(ex, "button_press_event", (2.0, -1.5))
    _mouse(ex, "motion_notify_event", (2.5, -1.0))
    np.testing.assert_array_equal(ex.points, before)


def test_update_is_in_place(ex):
    """Updates change artists in place (no new artists); their speed is in benchmarks/."""
    ex.kind.value = "b-spline"
    lines = list(ex.ax.lines)
    patches = list(ex.ax.patches)
    ex.fig.canvas.draw_idle = lambda *a, **k: None
    for i in range(50):
        ex.x.value = 5.0 + 0.01 * i
    assert list(ex.ax.lines) == lines and list(ex.ax.patches) == patches  # no new artists


def test_widget_layout_and_bad_points():
    e = SplineEndExplorer(P.copy(), kind="b-spline", rule="d=c")
    assert e.widget.children[1].children[0] is e.kind
    plt.close(e.fig)
    with pytest.raises(ValueError):
        SplineEndExplorer(np.zeros((1, 2)))
    with pytest.raises(ValueError):
        SplineEndExplorer(np.zeros((4, 3)))


def test_end_rules_figure_matches_the_exam():
    """The Q4(c)(i) sketch grid: row 0 Catmull-Rom, row 1 B-spline; column 0 d = b,
    column 1 d = 2c - b. The drawn ends follow the exam's results."""
    fig, arts = plots.plot_end_rules(P)
    end = {(i, j): np.array([v[0] for v in arts[i][j]["end"].get_data()])
           for i in range(2) for j in range(2)}
    np.testing.assert_allclose(end[0, 0], C, atol=DRAWN)
    np.testing.assert_allclose(end[0, 1], C, atol=DRAWN)
    np.testing.assert_allclose(end[1, 0], (2 * B + 4 * C) / 6, atol=DRAWN)
    np.testing.assert_allclose(end[1, 1], C, atol=DRAWN)
    # every curve starts at the first point's side, not at 'a': the first drawn point of the
    # Catmull-Rom curve is P[0] itself
    first = np.column_stack(arts[0][0]["segments"][0].get_data())[0]
    np.testing.assert_allclose(first, P[0], atol=DRAWN)
    plt.close(fig)


def test_blending_functions_figure():
    fig, ax = plt.subplots()
    lines = plots.plot_blending_functions(ax)
    bs = np.array([ln.get_ydata() for ln in lines[:4]])
    cr = np.array([ln.get_ydata() for ln in lines[4:]])
    np.testing.assert_allclose(bs.sum(axis=0), 1.0, atol=4 * DRAWN)
    assert bs.min() >= 0 and cr.min() < 0  # B-spline weights >= 0; Catmull-Rom has lobes
    np.testing.assert_allclose(bs[:, -1], [0, 1 / 6, 4 / 6, 1 / 6], atol=DRAWN)
    np.testing.assert_allclose(cr[:, -1], [0, 0, 1, 0], atol=DRAWN)
    plt.close(fig)


def test_the_announced_summary_states_the_end_values():
    """Q4(c): a B-spline ended by d = 2c - b has p(1) = (b + 4c + d)/6 = c and
    p''(1) = b - 2c + d = 0; the one line a screen reader hears says so, in two decimals."""
    e = spline_end_explorer(P.copy(), kind="b-spline", rule="d=2c-b")
    try:
        line = e.summary.value
        assert line == end_summary("b-spline", "d=2c-b", e.scene["end"])
        assert f"p = ({C[0]:.2f}, {C[1]:.2f})" in line
        assert "p'' = (0.00, 0.00)" in line or "p'' = (-0.00, 0.00)" in line
        assert e.widget is not None   # building the layout marks its readouts live
        assert "course-live" in e.summary._dom_classes
    finally:
        plt.close(e.fig)


@pytest.mark.parametrize("kind", ["catmull-rom", "b-spline"])
@pytest.mark.parametrize("rule", [None, "d=b", "d=2c-b", "d=c", "free"])
def test_scene_is_the_references_at_display_precision(kind, rule):
    """What a figure draws is the references' curve, phantoms and end rounded to 1e-4 of the
    points' span (on points spread over 1e3 and offset by 1e3), and no finer: the grader
    (1e-7 relative) would refuse it as an answer."""
    from course_lib import splines as S

    rng = np.random.default_rng(7)
    pts = 1e3 + rng.normal(scale=300.0, size=(6, 2))
    ph = rng.normal(scale=300.0, size=(2, 2))
    scene = plots.spline_scene(pts, kind, rule, phantoms=ph, n_per_segment=8)
    ext = np.vstack([ph[0], pts, ph[1]]) if rule == "free" else \
        pts if rule is None else S.extend_with_phantoms(pts, rule)
    span = np.ptp(ext, axis=0).max()
    quantum = 10.0 ** (np.floor(np.log10(span)) - 4)
    assert 1e-5 * span < quantum <= 1e-4 * span
    t = np.linspace(0.0, 1.0, 9)
    want = {"extended": ext, "abcd": ext[-4:],
            "segments": np.array([S.spline_eval(S.basis_matrix(kind), G, t)
                                  for G in S.segment_geometries(ext)]),
            "end": np.array(S.end_derivatives(S.basis_matrix(kind), *ext[-4:]))}
    for name, ref in want.items():
        got = np.asarray(scene[name])
        np.testing.assert_allclose(got, ref, rtol=0, atol=0.5 * quantum * (1 + 1e-9), err_msg=name)
        np.testing.assert_allclose(np.round(got / quantum), got / quantum, rtol=0, atol=1e-6)
        assert not np.allclose(got, ref, rtol=1e-7, atol=1e-9), name
    if rule not in (None, "free"):
        d = S.phantom_point(pts[-2], pts[-1], rule)
        np.testing.assert_allclose(scene["phantoms"][1], d, rtol=0, atol=0.5 * quantum)


def test_the_explorer_keeps_only_drawn_values(ex):
    """Every array the explorer keeps that a graded function could give (phantom points, the
    scene) is at display precision: 4 decimals for these points."""
    for rule in ("d=2c-b", "free", "d=c"):
        ex.rule.value = rule
        kept = [ex.phantoms, ex.scene["extended"], ex.scene["segments"], *ex.scene["end"]]
        for arr in kept:
            np.testing.assert_array_equal(np.round(arr, 4), arr)
