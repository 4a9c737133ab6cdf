"""The page's echo of a slider value the kernel set is not a student's move
(course_lib/widgets/_slider_echoes.py).

The page is played by ``Widget.set_state``, the call ipywidgets makes for every value that
arrives from the browser; the echo of a value is that value put on the slider's step grid
(``round`` below), as ipywidgets' slider view sends it. The browser test
``tests/browser/test_canvas_fidelity.py::test_dragging_a_spline_point_moves_it_in_the_kernel``
drives the same thing through the real page.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import time

import ipywidgets as W
import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.backend_bases import MouseEvent

from course_lib.widgets import _slider_echoes
from course_lib.widgets._slider_echoes import ECHO, MOVE, STALE, SliderEchoes, from_page
from course_lib.widgets.clipping import ClippingExplorer
from course_lib.widgets.splines import spline_end_explorer


def page_sends(slider, value):
    """``value`` arriving from the browser, as ipywidgets delivers it."""
    slider.set_state({"value": value})


def on_grid(slider, value):
    """Where the page's slider view puts ``value``: the nearest step from ``min``."""
    return slider.min + round((value - slider.min) / slider.step) * slider.step


class Clock:
    def __init__(self):
        self.now = time.monotonic()

    def __call__(self):
        return self.now


def test_from_page_tells_the_browser_from_the_kernel():
    slider = W.FloatSlider(min=0, max=10, step=0.1)
    seen = []
    slider.observe(lambda change: seen.append(from_page(change["owner"])), names="value")
    slider.value = 3.0
    page_sends(slider, 4.0)
    slider.value = 5.0
    assert seen == [False, True, False]


def judged(echoes, slider, value, current):
    """The verdicts on ``value`` sent by the page (none when it does not change the slider)."""
    verdicts = []

    def observer(change):
        verdicts.append(echoes.judge(change, current))

    slider.observe(observer, names="value")
    try:
        page_sends(slider, value)
    finally:
        slider.unobserve(observer, names="value")
    return verdicts


@pytest.fixture
def slider():
    return W.FloatSlider(min=-2.7, max=8.7, step=0.01)


def test_the_rule(slider):
    clock = Clock()
    echoes = SliderEchoes(clock)
    for v in (1.2345, 2.3456, 3.4567):          # a drag: the kernel sets three values
        echoes.set(slider, v)
    # the echo of an older value, arriving late: stale (and forgets that value and older ones)
    assert judged(echoes, slider, on_grid(slider, 2.3456), current=3.4567) == [STALE]
    # a second copy of an already-answered echo is no longer recognised: a move
    assert judged(SliderEchoes(clock), slider, 2.35, current=3.4567) == [MOVE]
    # the echo of the current value: nothing to do
    echoes.set(slider, 3.4567)
    echoes.set(slider, 4.4444)
    assert judged(echoes, slider, on_grid(slider, 4.4444), current=4.4444) == [ECHO]
    # a value the kernel never set, once the page shows the latest: the student's move,
    # after which nothing is remembered
    echoes.set(slider, 5.5555)
    echoes.set(slider, 6.6666)
    clock.now += _slider_echoes.DISPLAY_LAG_S + 0.1
    assert judged(echoes, slider, 0.5, current=6.6666) == [MOVE]
    assert judged(echoes, slider, on_grid(slider, 5.5555), current=6.6666) == [MOVE]


def test_a_key_pressed_before_the_page_showed_the_latest_value_is_set_back(slider):
    """The playtest's case: the point switched from p1 (x = 1) to p2 (x = 3) and a key pressed
    on x at once stepped from the 1.00 the page still showed. Every such step is set back; once
    the page shows 3.00, a step from it is a move."""
    clock = Clock()
    echoes = SliderEchoes(clock)
    for v in (1.0, 6.0, 3.0):                       # p1, then p4, then p2 selected quickly
        echoes.set(slider, v)
    assert [judged(echoes, slider, v, current=3.0)[0] for v in (1.01, 1.02, 1.03)] == \
        [STALE] * 3
    assert judged(echoes, slider, 3.01, current=3.0) == [MOVE]
    # the same first step after the page has had time to show 3.00 is a move
    echoes.set(slider, 1.0)
    echoes.set(slider, 3.0)
    clock.now += _slider_echoes.DISPLAY_LAG_S + 0.1
    assert judged(echoes, slider, 1.01, current=3.0) == [MOVE]


def test_an_echo_is_only_expected_for_a_while(slider, monkeypatch):
    clock = Clock()
    echoes = SliderEchoes(clock)
    echoes.set(slider, 1.2345)
    echoes.set(slider, 3.0)
    clock.now += _slider_echoes.ECHO_WINDOW_S + 0.1
    assert judged(echoes, slider, on_grid(slider, 1.2345), current=3.0) == [MOVE]


def test_a_value_set_in_the_kernel_is_always_a_move(slider):
    echoes = SliderEchoes()
    echoes.set(slider, 1.2345)
    echoes.set(slider, 3.0)
    verdicts = []

    def observer(change):
        verdicts.append(echoes.judge(change, 3.0))

    slider.observe(observer, names="value")
    slider.value = on_grid(slider, 1.2345)          # e.g. a student's code, or a test
    slider.unobserve(observer, names="value")
    assert verdicts == [MOVE]
    # and it forgot nothing: the page's echo of 1.2345 is still recognised
    assert judged(echoes, slider, on_grid(slider, 1.2345) + 0.001, current=3.0) == [STALE]


def test_setting_an_unchanged_value_expects_no_echo(slider):
    echoes = SliderEchoes()
    echoes.set(slider, 2.0)
    echoes.set(slider, 2.0)                          # nothing is sent: nothing to echo
    echoes.set(slider, 3.0)
    # one 2.0 was remembered: its echo is recognised once, the next value by it is a move
    assert judged(echoes, slider, 2.0, current=3.0) == [STALE]
    assert judged(echoes, slider, 2.004, current=3.0) == [MOVE]


# -- the explorers ----------------------------------------------------------------------------

def mouse(e, name, xy):
    x, y = e.ax.transData.transform(xy)
    e.fig.canvas.callbacks.process(name, MouseEvent(name, e.fig.canvas, x, y, button=1))


@pytest.fixture
def spline():
    e = spline_end_explorer()
    e.fig.canvas.draw()                              # final data -> pixel transforms
    yield e
    plt.close(e.fig)


def test_a_late_echo_does_not_pull_a_dragged_point_back(spline):
    """The CI failure at b9b8b12: echoes of the drag's earlier positions arrived after the
    release and moved the point back to one of them."""
    k = len(spline.points) - 1
    path = spline.points[k] + np.array([[-0.3, -0.2], [-0.7, -0.55], [-1.4234, -1.1041]])
    mouse(spline, "button_press_event", spline.points[k])
    for xy in path[:-1]:
        mouse(spline, "motion_notify_event", xy)
    mouse(spline, "button_release_event", path[-1])
    others = np.delete(spline.points, k, axis=0).copy()
    np.testing.assert_allclose(spline.points[k], path[-1], atol=1e-12)
    for xy in path:                                  # every echo, late
        page_sends(spline.x, on_grid(spline.x, xy[0]))
        page_sends(spline.y, on_grid(spline.y, xy[1]))
    np.testing.assert_allclose(spline.points[k], path[-1], atol=1e-12)      # exact, not rounded
    np.testing.assert_allclose((spline.x.value, spline.y.value), path[-1], atol=0.005)
    np.testing.assert_array_equal(np.delete(spline.points, k, axis=0), others)


def test_a_students_slider_move_sets_one_coordinate(spline):
    k = spline.point.value
    y = spline.points[k, 1]
    page_sends(spline.x, 2.5)
    np.testing.assert_allclose(spline.points[k], [2.5, y], atol=1e-12)
    page_sends(spline.y, -1.25)
    np.testing.assert_allclose(spline.points[k], [2.5, -1.25], atol=1e-12)


def test_a_late_echo_of_the_previous_vertex_leaves_the_clipping_vertex_alone():
    ex = ClippingExplorer()
    clock = ex._echoes._clock = Clock()
    try:
        first = ex.P[ex.vertex.value].copy()
        ex.vertex.value = 2
        here = ex.P[2].copy()
        moved = [c for c in range(4) if abs(first[c] - here[c]) > ex.coord_sliders[c].step]
        assert moved, "the test needs vertices that differ"
        for c in moved:                              # the first vertex's values, echoed late
            page_sends(ex.coord_sliders[c], float(first[c]))
        np.testing.assert_array_equal(ex.P[2], here)
        np.testing.assert_allclose([s.value for s in ex.coord_sliders], here, atol=1e-12)
        clock.now += _slider_echoes.DISPLAY_LAG_S + 0.1
        page_sends(ex.coord_sliders[moved[0]], float(first[moved[0]]))    # now a move
        assert ex.P[2, moved[0]] == pytest.approx(first[moved[0]])
    finally:
        plt.close(ex.fig)


def test_a_quick_switch_then_a_key_leaves_every_point_where_it_was(spline):
    """Playtest 6: p0, p3, p1, p4, p2 picked 60 ms apart, then ArrowRight pressed on x three
    times while the page still showed p1's x: p4 had taken p1's x plus a step."""
    before = spline.points.copy()
    for k in (0, 3, 1, 4, 2):
        spline.point.set_state({"index": k})         # a Dropdown syncs its index
    assert spline.point.value == 2
    shown = before[1, 0]                              # what the page still showed
    for press in (1, 2, 3):
        page_sends(spline.x, on_grid(spline.x, shown) + press * spline.x.step)
    np.testing.assert_array_equal(spline.points, before)
    assert spline.x.value == pytest.approx(before[2, 0])   # the slider back on p2's x
