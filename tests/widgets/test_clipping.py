"""The clipping explorer: drive its controls from Python (Agg) and check the artists follow the
maths of Q6(b)(iii): the exam's clipped triangle A, inside/outside, and w < 0 vertices."""

from __future__ import annotations

import matplotlib
import matplotlib.pyplot
import numpy as np
import pytest
from shapely.geometry import Polygon, box

from course_lib.widgets.clipping import ClippingExplorer, clipping_explorer

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
    w > 0 and the Z planes do not cut: check against shapely after moving a vertex."""
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
    assert got.area == pytest.approx(ref.area, rel=1e-9)
    assert got.symmetric_difference(ref).area < 1e-9


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
    cur = ex.steps[6]
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
