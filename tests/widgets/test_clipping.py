"""The clipping explorer: drive its controls from Python (Agg) and check the artists follow the
maths of Q6(b)(iii): the exam's clipped triangle A, inside/outside, and w < 0 vertices."""

from __future__ import annotations

import matplotlib
import matplotlib.pyplot
import numpy as np
import pytest
from shapely.geometry import Polygon, box

from autograder.exercises import get as exercise
from course_lib import clipping
from course_lib.plots.clipping import screen_points
from course_lib.widgets.clipping import ClippingExplorer, clip_display, clipping_explorer

A_H = np.array([[0, 0, 2, 4], [0, 2, 2, 4], [0, 6, 18, 12]], float)   # the exam's A
# exam Q6(b)(iii), (y_s, z_s) of the clipped A
A_CLIPPED_YZ = np.array([[0, 0.5], [0.5, 0.5], [0.5, 1], [0.25, 1]])


def cyclic_match(a, b, atol=1e-9):
    return a.shape == b.shape and any(np.allclose(np.roll(b, -k, axis=0), a, atol=atol)
                                      for k in range(len(b)))


@pytest.fixture
def exam():
    ex = clipping_explorer(A_H, dims=(1, 2))
    yield ex
    matplotlib.pyplot.close(ex.fig)


@pytest.fixture
def default():
    ex = ClippingExplorer()
    yield ex
    matplotlib.pyplot.close(ex.fig)


def test_exam_triangle_far_plane(exam):
    """Stepping through the planes: only the sixth (far) one changes A, to the exam's list."""
    poly = exam.art2d["clipped"]
    for k in range(6):
        exam.step.value = k
        assert cyclic_match(np.array([[0, 0.5], [0.5, 0.5], [0.5, 1.5]]), poly.get_xy()[:-1])
    exam.step.value = 6
    assert cyclic_match(A_CLIPPED_YZ, poly.get_xy()[:-1])
    xs, ys, zs = exam.art3d["vertices"].get_data_3d()
    np.testing.assert_allclose(xs, 0, atol=1e-12)                       # edge-on: x_s = 0 throughout
    assert cyclic_match(A_CLIPPED_YZ, np.c_[ys, zs])
    assert "far" in exam.status.get_text() and "4 vertices" in exam.status.get_text()
    assert exam.art3d["plane"].get_visible()


def test_buttons_step_and_stop_at_the_ends(exam):
    exam.next_button.click()
    exam.next_button.click()
    assert exam.step.value == 2
    for _ in range(10):
        exam.next_button.click()
    assert exam.step.value == 6
    for _ in range(10):
        exam.prev_button.click()
    assert exam.step.value == 0
    assert not exam.art3d["plane"].get_visible()
    assert "yes, yes, no" in exam.status.get_text()         # Q6(b)(i)


def test_moving_a_vertex_inside_removes_the_cut(exam):
    """Pull A's third vertex to z_s = 0.75 (Z = 9, w = 12): A is then entirely inside."""
    exam.step.value = 6
    exam.vertex.value = 2
    assert [s.value for s in exam.coord_sliders] == pytest.approx(A_H[2])   # sliders synced
    exam.coord_sliders[2].value = 9.0
    np.testing.assert_allclose(exam.P[2], [0, 6, 9, 12], atol=1e-12)
    expected = np.array([[0, 0.5], [0.5, 0.5], [0.5, 0.75]])
    assert cyclic_match(expected, exam.art2d["clipped"].get_xy()[:-1])
    assert "3 vertices" in exam.status.get_text()


def test_screen_view_matches_shapely(default):
    """On the screen view the last step is the input's projection cut by the square, as long as
    w > 0 and the Z planes do not cut: check against shapely after moving a vertex (the drawn
    vertices are at display precision, 1e-4: the areas agree to a few 1e-4)."""
    ex = default
    ex.vertex.value = 2
    ex.coord_sliders[2].value = 1.0      # Z = 1, w = 2: z_s = 0.5
    ex.vertex.value = 3
    ex.coord_sliders[3].value = 1.0      # w = 1 for vertex 3
    ex.step.value = 6
    P = ex.P
    assert np.all(P[:, 3] > 0) and np.all((P[:, 2] >= 0) & (P[:, 2] <= P[:, 3]))
    screen = P[:, :2] / P[:, 3:]
    ref = Polygon(screen).intersection(box(-1, -1, 1, 1))
    got = Polygon(ex.art2d["clipped"].get_xy())
    assert got.area == pytest.approx(ref.area, abs=1e-3)
    assert got.symmetric_difference(ref).area < 1e-3
    assert got.area != ref.area          # rounded, not the exact polygon


def test_vertex_behind_the_eye():
    """w < 0: the dashed input shows the naive divide (mirrored), the clipped polygon keeps only
    the part with w > 0 inside the box."""
    P = np.array([[-0.5, -0.5, 0.5, 1.0], [0.5, -0.5, 0.5, 1.0], [0.0, 1.5, 0.5, 1.0]])
    ex = ClippingExplorer(P)
    ex.vertex.value = 2
    ex.coord_sliders[3].value = -1.0                      # vertex 2 goes behind the eye
    ex.step.value = 6
    x, y = ex.art2d["original"].get_data()
    assert (x[2], y[2]) == pytest.approx((0.0, -1.5))     # naive divide: mirrored below
    cur = ex.shown["steps"][6]
    assert len(cur) >= 3 and np.all(cur[:, 3] > 0)
    xy = ex.art2d["clipped"].get_xy()
    assert ex.art2d["clipped"].get_visible()
    assert np.all(np.abs(xy) <= 1 + 1e-9)
    # By hand: the edges towards vertex 2 are S + t (V2 - S), w = 1 - 2t, Z = 0.5, so they leave
    # through the far plane (Z = w) at t = 1/4, where y_s = (-0.5 + 2t) / (1 - 2t) = 0 and
    # x_s = -+0.75. The clipped polygon goes *up* the screen to y_s = 0, whereas the naively
    # divided triangle lies entirely at y_s <= -0.5.
    assert xy[:, 1].min() == pytest.approx(-0.5) and xy[:, 1].max() == pytest.approx(0.0)
    assert np.sort(np.abs(xy[np.abs(xy[:, 1]) < 1e-9, 0])) == pytest.approx([0.75, 0.75])
    matplotlib.pyplot.close(ex.fig)


def test_degenerate_vertex_does_not_crash(default):
    ex = default
    ex.vertex.value = 0
    for s in ex.coord_sliders:
        s.value = 0.0
    assert "cannot clip" in ex.status.get_text()
    ex.coord_sliders[3].value = 1.0
    assert "cannot clip" not in ex.status.get_text()


def test_update_is_fast(default):
    ex = default
    times = []
    for k, v in enumerate(np.linspace(-2, 2, 10)):
        ex.coord_sliders[0].value = float(round(v, 2))
        ex.step.value = k % 7
        times.append(ex.last_update_ms)
    assert np.median(times) < 50


def test_bad_polygon():
    with pytest.raises(ValueError):
        ClippingExplorer(np.ones((2, 4)))


def test_a_one_line_summary_is_announced_not_the_vertex_table(exam):
    """Q6(b): the live region says the step in one line (the exam's triangle: 3 vertices as
    input); the vertex table beside it is read on demand, not announced on every move."""
    exam.widget()
    assert "course-live" in exam.summary._dom_classes
    assert "course-live" not in exam.readout._dom_classes
    assert exam.summary.value.startswith(f"input: {len(A_H)} vertices")
    assert "<" not in exam.summary.value and "\n" not in exam.summary.value
    exam.step.value = 1
    assert exam.summary.value.startswith("after plane 1 of 6")


#: the hidden cases of clip_polygon drawn from random floats (the others are the exam's round
#: numbers, a triangle of integers, or empty answers: their vertices survive any rounding)
RANDOM_CLIP_CASES = ("random convex", "polygon entirely inside", "a vertex with w < 0")


@pytest.mark.parametrize("seed", range(4))
def test_what_the_explorer_keeps_answers_no_random_hidden_case(seed):
    """Q6(b): clip_display, the one routine of the explorer that calls the references, keeps
    only display precision. On the grader's hidden cases drawn from random floats, its last
    step fails clip_polygon's own comparison, and the drawn points fail to_screen's."""
    rng = np.random.default_rng(seed)
    clip_ex, screen_ex = exercise("clip_polygon"), exercise("to_screen")
    checked = 0
    for case in clip_ex.draw_cases(rng):
        if case.raises or not case.label.startswith(RANDOM_CLIP_CASES):
            continue
        (P,) = case.args
        expected = clipping.clip_polygon(P)
        shown = clip_display(P)
        if len(expected):
            last = shown["steps"][6]
            assert len(last) == len(expected)                      # the same polygon...
            np.testing.assert_allclose(last, expected, atol=5e-4)  # ...at three decimals
            assert clip_ex.compare(expected, last) is not None     # not the grader's answer
            checked += 1
        for k, step in enumerate(clipping.clip_steps(P)):
            if len(step) and np.all(step[:, 3] != 0):
                assert screen_ex.compare(clipping.to_screen(step), shown["screen"][k]) is not None
    assert checked >= 4
    for case in screen_ex.draw_cases(rng):
        if not case.raises and case.label.startswith("batch of 25"):
            (P,) = case.args
            drawn = screen_points(P)
            np.testing.assert_allclose(drawn, clipping.to_screen(P), atol=1e-4)
            assert screen_ex.compare(clipping.to_screen(P), drawn) is not None


def test_clip_display_reads_the_exam_triangle_and_a_bad_polygon():
    """Exam Q6(b)(i) and (iii): A's vertices in/out as text, its steps' vertex counts and table;
    a zero vertex gives the reason instead of steps."""
    shown = clip_display(A_H)
    assert shown["inside"] == "yes, yes, no" and shown["error"] is None
    assert [len(s) for s in shown["steps"]] == [3, 3, 3, 3, 3, 3, 4]
    assert "0.250" in shown["tables"][6] and shown["tables"][6].count("<tr>") == 5
    assert cyclic_match(A_CLIPPED_YZ, shown["screen"][6][:, 1:])
    bad = clip_display(np.array([[0, 0, 0, 0], [1, 0, 0.5, 1], [0, 1, 0.5, 1]], float))
    assert "zero vertex" in bad["error"] and bad["inside"] is None
    assert [len(s) for s in bad["steps"]] == [3, 0, 0, 0, 0, 0, 0]
    assert all(isinstance(t, str) for t in bad["tables"])
