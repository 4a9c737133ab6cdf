"""Blitted redraws (issue 15): the same picture as a full draw, and one frame per update.

The oracle is matplotlib's own full Agg draw of the same figure: after a few slider moves
redrawn by :class:`course_lib.widgets._view.Blitter`, the canvas must hold the pixels that
``FigureCanvasAgg.draw`` paints from scratch, which shows that the split into a background and
changing artists (the browser canvas' too) misses nothing. The browser canvas' checks (no
browser): one frame per update, a new background only for a new geometry, mouse messages
turned into matplotlib events.
"""

from __future__ import annotations


import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402

from course_lib.widgets import _blit, _view  # noqa: E402
from course_lib.widgets.clipping import ClippingExplorer  # noqa: E402
from course_lib.widgets.gamma_camera import CollimatorExplorer  # noqa: E402
from course_lib.widgets.marching_cubes import CaseExplorer  # noqa: E402
from course_lib.widgets.shading import PhongExplorer  # noqa: E402
from course_lib.widgets.splines import SplineEndExplorer  # noqa: E402
from course_lib.widgets.ultrasound import BScanExplorer  # noqa: E402


@pytest.fixture(autouse=True)
def headless(monkeypatch):
    """No kernel event loop, as in a plain Python process: every redraw happens at once.

    Earlier tests in the same worker (the browser tests' Playwright session) may leave an
    asyncio loop marked running in this thread; the explorers would then defer frames onto it.
    The one test of deferring runs its own loop in a thread of its own."""
    monkeypatch.setattr(_blit, "_running_loop", lambda: None)

#: explorer, then the (control attribute, new value) moves applied one update at a time
MOVES = {
    "phong": (PhongExplorer, [("light_azimuth", 10.0), ("ka", 0.5), ("colour", "#ff3300"),
                              ("view_elevation", 20.0)]),
    "splines": (SplineEndExplorer, [("x", 1.0), ("y", 0.5), ("rule", "d=c"),
                                    ("kind", "b-spline")]),
    "bscan": (BScanExplorer, [("c_fat", 1500.0), ("t_liver", 30.0), ("tgc", True)]),
    "collimator": (CollimatorExplorer, [("z", 500.0), ("d", 2.0), ("L", 80.0), ("pitch", 12.0),
                                        ("n_rings", 3), ("z", 700.0)]),
    "clipping": (ClippingExplorer, [("step", 3), ("step", 5)]),
    "cases": (CaseExplorer, [("iso", 0.3), ("index", 5), ("index", 176), ("iso", 0.6)]),
}


def _control(explorer, name):
    return getattr(explorer, name)


def _pixels(fig) -> np.ndarray:
    return np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(np.int16).copy()


@pytest.fixture(params=sorted(MOVES))
def driven(request):
    cls, moves = MOVES[request.param]
    explorer = cls()
    view = _view.use_blitting(explorer)
    explorer.update()
    yield request.param, explorer, view, moves
    plt.close(explorer.fig)


def test_blitted_frames_match_a_full_draw(driven):
    name, explorer, view, moves = driven
    for attr, value in moves:
        _control(explorer, attr).value = value
        blitted = _pixels(explorer.fig)
        FigureCanvasAgg.draw(explorer.fig.canvas)            # the oracle: everything, from scratch
        full = _pixels(explorer.fig)
        differs = np.abs(blitted - full).max(axis=-1) > 8
        assert differs.mean() < 1e-4, f"{name} after {attr}={value!r}: {differs.sum()} pixels differ"
    assert view.blitter.blits >= 1, f"{name}: no update was blitted"


def test_a_blit_draws_no_tick_label(driven):
    """What a blit paints is the changing artists only: no axis (ticks, tick labels) at all."""
    name, explorer, view, moves = driven
    for artist in view.blitter.dynamic_artists():
        assert not isinstance(artist, matplotlib.axis.Axis), name


def test_axes_limits_change_means_a_full_draw():
    ex = CollimatorExplorer()
    view = _view.use_blitting(ex)
    ex.update()
    ex.z.value = 600.0                                     # side view only: fixed limits
    assert (view.blitter.full_draws, view.blitter.blits) == (1, 1)
    ex.pitch.value = 10.5            # a 52.5 mm face, 4 % margin: still the 60 mm views
    assert view.blitter.full_draws == 1 and ex.ax_exam.get_xlim() == pytest.approx((-60, 60))
    ex.pitch.value = 15.0            # a 75 mm face outgrows them: 80 mm views, a new background
    assert view.blitter.full_draws == 2
    assert ex.ax_exam.get_xlim() == pytest.approx((-80, 80))
    plt.close(ex.fig)


def test_collimator_side_view_fits_its_mm_into_fixed_axes():
    ex = CollimatorExplorer()
    for d, L, z in ((1.0, 40.0, 1000.0), (3.0, 120.0, 80.0)):
        ex.set(d=d, L=L, z=z)
        assert ex.ax_side.get_xlim() == (-1.0, 1.0) and ex.ax_side.get_ylim() == (0.0, 1.0)
        (x0, x1), (y0, y1) = ex.side_limits
        to_axes = ex.art["side"]["source"].get_transform() - ex.ax_side.transData
        np.testing.assert_allclose(to_axes.transform([(x0, y0), (x1, y1)]), [(-1, 0), (1, 1)],
                                   atol=1e-12)
        # the source sits at height z in mm, inside the shown range
        _, (zs,) = ex.art["side"]["source"].get_data()
        assert zs == pytest.approx(z) and y0 < zs < y1
    plt.close(ex.fig)


def test_a_changed_text_is_drawn_again_not_taken_from_its_sprite():
    ex = CaseExplorer(index=1)
    view = _view.use_blitting(ex)
    ex.update()
    ex.iso.value = 0.3                                     # sprites of the unchanged artists
    ex.index.value = 254                                   # corners change colour
    assert view.blitter.blits == 2
    blitted = _pixels(ex.fig)
    FigureCanvasAgg.draw(ex.fig.canvas)
    assert np.abs(blitted - _pixels(ex.fig)).max() <= 8
    plt.close(ex.fig)


# --- the browser canvas ------------------------------------------------------------------------

def test_one_frame_per_update_and_the_background_only_when_the_geometry_changes():
    ex = PhongExplorer(size=64)
    assert ex.widget is not None                           # the layout, shown as it is
    canvas = ex._view.widget(ex.fig)
    painter = ex._view.blitter
    assert painter.full_draws == 1 and canvas.background[:4] == b"\x89PNG"
    background, frame = canvas.background, canvas.frame
    ex.light_azimuth.value = 30.0
    ex.ks.value = 0.3
    assert canvas.frame == frame + 2                       # one frame per update, no more
    assert painter.full_draws == 1 and canvas.background is background
    width, height = ex.fig.get_size_inches()
    ex.fig.set_size_inches(width + 1, height)              # new geometry: a new background
    ex._redraw()
    assert painter.full_draws == 2 and canvas.background != background
    assert canvas.width == round(ex.fig.bbox.width) > round(width * ex.fig.dpi)
    plt.close(ex.fig)


def test_mouse_messages_become_matplotlib_events():
    ex = SplineEndExplorer()
    assert ex.widget is not None
    canvas, fig = ex._view.widget(ex.fig), ex.fig
    seen = []
    fig.canvas.mpl_connect("button_press_event", lambda e: seen.append((e.x, e.y, e.inaxes)))
    x, y = fig.axes[0].transData.transform((0.0, 0.0))
    canvas._handle_custom_msg({"type": "mouse", "name": "button_press_event", "x": x, "y": y,
                               "button": 1}, [])
    canvas._handle_custom_msg({"type": "mouse", "name": "no_such_event", "x": x, "y": y}, [])
    for bad in ("?", "nan", "inf", "9" * 400, None):       # ignored, never raised
        canvas._handle_custom_msg({"type": "mouse", "name": "button_press_event", "x": bad,
                                   "y": y}, [])
    canvas._handle_custom_msg({"type": "mouse", "name": "button_press_event", "x": x,
                               "y": y, "button": 10 ** 400}, [])
    for bad in ("x", 10 ** 400, float("nan"), 100.0, None):
        canvas._handle_custom_msg({"type": "ratio", "ratio": bad}, [])
    canvas._handle_custom_msg("not a dict", [])
    assert seen == [(int(x), int(y), fig.axes[0])]       # matplotlib keeps whole pixels
    dpi = fig.dpi
    canvas.ratio = 2.0                                     # the page writes the trait itself
    canvas._handle_custom_msg({"type": "ratio", "ratio": 2.0}, [])
    assert fig.dpi == pytest.approx(2 * dpi, abs=1e-9) and canvas.ratio == 2.0
    plt.close(fig)


def _running_loop_of_this_thread():
    import asyncio

    try:
        return asyncio.get_running_loop()
    except RuntimeError:
        return None


def _record(fn, failed: list) -> None:
    try:
        fn()
    except BaseException as exc:  # noqa: BLE001 - reported by the test's thread
        failed.append(repr(exc))


def test_updates_faster_than_frames_are_shown_by_one_later_frame():
    """A drag: updates arrive back to back on the kernel's event loop. The frames that would
    queue behind them are dropped and the one frame drawn afterwards shows the last state."""
    import asyncio

    ex = SplineEndExplorer()
    view = _view.use_blitting(ex)
    ex.update()                                            # no event loop: drawn at once
    blitter = view.blitter
    blitter._cost = 0.2                                    # as if a frame took 200 ms

    async def drag():
        for k in range(20):
            ex.x.value = 0.5 + 0.05 * k
            await asyncio.sleep(0)
        assert blitter.full_draws + blitter.blits == 1     # nothing drawn yet: one is due
        await asyncio.sleep(0.5)

    def kernel():                                          # a loop of its own, as a kernel's
        asyncio.run(drag())

    import threading

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(_blit, "_running_loop", _running_loop_of_this_thread)
        failed = []
        thread = threading.Thread(target=lambda: _record(kernel, failed))
        thread.start()
        thread.join(30)
    assert not failed, failed
    assert blitter.full_draws + blitter.blits == 2
    shown = _pixels(ex.fig)
    FigureCanvasAgg.draw(ex.fig.canvas)
    assert np.abs(shown - _pixels(ex.fig)).max() <= 8      # the last state, nothing older
    plt.close(ex.fig)


def test_a_figure_saved_while_the_explorer_redraws_is_whole():
    """JupyterLab 4 + ipykernel 7 run widget callbacks in a subshell thread while the main
    thread may redraw (a deferred frame) or save the explorer's figure. Both use the canvas'
    one Agg renderer, and
    savefig encodes the PNG from its buffer with the GIL released: unguarded, a redraw in the
    other thread cleared it half-way (25 of 40 saves came out blank or torn). Oracle: a save taken
    while nothing else runs. Below the axes everything is static (tick and axis labels), so
    every save must match it there, and the exam model's open holes must be drawn."""
    import io
    import threading

    from PIL import Image

    from course_lib.plots.gamma_camera import OPEN
    from matplotlib.colors import to_rgb

    ex = CollimatorExplorer()
    assert ex.widget is not None
    painter = ex._view.blitter

    def save():
        buffer = io.BytesIO()
        ex.fig.savefig(buffer, format="png", dpi=ex.fig.dpi)
        return np.asarray(Image.open(buffer).convert("RGB"), dtype=np.int16)

    reference = save()
    below_axes = int(round(reference.shape[0] - ex.ax_exam.bbox.y0)) + 2
    green = np.round(255 * np.array(to_rgb(OPEN))).astype(np.int16)
    stop, failed = threading.Event(), []

    def drive():
        for k in range(10_000):
            if stop.is_set():
                return
            painter.background = None                      # each frame draws the background
            ex.z.value = 500.0 + 10.0 * (k % 50)           # z >= 500 mm: ring 1 stays open

    thread = threading.Thread(target=lambda: _record(drive, failed))
    thread.start()
    try:
        saves = [save() for _ in range(12)]
    finally:
        stop.set()
        thread.join(30)
    assert not failed, failed
    for k, picture in enumerate(saves):
        strip = np.abs(picture[below_axes:] - reference[below_axes:]).max(axis=-1)
        assert (strip <= 2).mean() > 0.999, f"save {k}: the static labels differ (torn/blank)"
        assert (np.abs(picture - green).max(axis=-1) <= 2).sum() > 50, f"save {k}: no open hole"
    plt.close(ex.fig)


def test_a_blitted_figure_asks_pyplot_for_no_redraw():
    """IPython runs pyplot's post_execute hook after every widget message; it redraws every
    stale figure with draw_idle, which under ipympl means a full redraw asked by the browser.
    A blitted explorer's figure is up to date, so it must not look stale."""
    from matplotlib._pylab_helpers import Gcf

    ex = PhongExplorer(size=64)
    _view.use_blitting(ex)
    calls = []
    ex.fig.canvas.draw_idle = lambda *a, **k: calls.append(1)
    for value in (10.0, 20.0, 30.0):
        ex.light_azimuth.value = value
        assert not ex.fig.stale
        Gcf.draw_all()
    assert calls == []
    plt.close(ex.fig)


@pytest.mark.parametrize("name", sorted(MOVES))
def test_kept_scene_items_are_what_a_fresh_recording_gives(name):
    """Unchanged artists' items are reused from the frame before (by ``stale`` and, for
    colour-mapped collections, by their data array): after every move the scene sent must be
    the scene a painter with nothing kept records from the same figure."""
    from course_lib.widgets._scene import unpack

    cls, moves = MOVES[name]
    ex = cls()
    ex.update()
    painter = ex._view.blitter
    for attr, value in moves:
        _control(ex, attr).value = value
        sent = unpack(painter.widget.scene)["items"]
        painter._own_draw = True      # the fresh painter's draw must not reset this one's store
        try:
            fresh = _fresh_scene(ex.fig)
        finally:
            painter._own_draw = False
        painter.background = None                   # the fresh painter drew the figure
        _assert_same_scene(sent, fresh, (name, attr))
    plt.close(ex.fig)


def _fresh_scene(fig) -> list:
    """The scene items a painter with nothing kept records from ``fig`` as it is now."""
    from course_lib.widgets._canvas import FigureCanvas
    from course_lib.widgets._scene import unpack

    fresh_painter = _view.ScenePainter(fig, FigureCanvas())
    fresh_painter.redraw()
    return unpack(fresh_painter.widget.scene)["items"]


def _assert_same_scene(sent, fresh, where) -> None:
    assert [i["k"] for i in sent] == [i["k"] for i in fresh], where
    for a, b in zip(sent, fresh):
        for key in ("fill", "stroke", "fills", "strokes", "lw", "dash"):
            assert a.get(key) == b.get(key), (*where, key)
        for key in ("v", "at"):
            if key in a:
                np.testing.assert_allclose(a[key], b[key], rtol=0, atol=1e-3)
        if "rgba" in a:
            np.testing.assert_array_equal(a["rgba"], b["rgba"])


@pytest.mark.parametrize("name", sorted(MOVES))
def test_a_figure_saved_before_a_put_off_frame_leaves_that_frame_right(name):
    """Playtest 7: a move whose frame is put off (frames outrun), then ``savefig`` from a cell
    before that frame is drawn. The save's full draw clears every artist's ``stale`` flag, so
    the frame must not trust what it kept of "unchanged" artists: the scene it sends is the
    one a painter with nothing kept records (before the fix, the old pictures of the moved
    artists were sent and the canvas kept showing the state before the move)."""
    import asyncio
    import io
    import threading
    import time

    from course_lib.widgets._scene import unpack

    cls, moves = MOVES[name]
    ex = cls()
    ex.update()                                            # no event loop: drawn at once
    painter = ex._view.blitter
    attr, value = moves[0]

    async def move_then_save():
        painter._cost, painter._finished = 0.3, time.perf_counter()   # a frame just sent
        _control(ex, attr).value = value
        assert painter._deferred is not None               # its frame is put off
        ex.fig.savefig(io.BytesIO(), format="png")         # a cell saves the figure
        await asyncio.sleep(0.6)                           # the put-off frame is drawn

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(_blit, "_running_loop", _running_loop_of_this_thread)
        failed = []
        thread = threading.Thread(target=lambda: _record(lambda: asyncio.run(move_then_save()),
                                                         failed))
        thread.start()
        thread.join(30)
    assert not failed, failed
    assert painter._deferred is None
    sent = unpack(painter.widget.scene)["items"]
    _assert_same_scene(sent, _fresh_scene(ex.fig), (name, attr))
    plt.close(ex.fig)


def test_a_new_view_of_one_axes_records_its_artists_again_and_keeps_the_others():
    """A slider that changes one axes' limits (the collimator's pitch) needs a new background;
    what the other axes hold has not moved and is kept, what that axes holds has moved although
    no ``set_*`` touched it. Oracle: a painter with nothing kept, recording the same figure."""
    from course_lib.widgets._canvas import FigureCanvas
    from course_lib.widgets._scene import unpack

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(6, 3))
    ax1.plot([0, 1, 2], [0, 1, 0], color="tab:blue")
    ax2.plot([0, 1, 2], [1, 0, 1], color="tab:red")
    painter = _view.ScenePainter(fig, FigureCanvas())
    painter.redraw()
    kept_line = painter._kept.get(ax2.lines[0])
    ax1.set_xlim(-1, 4)                                    # only ax1's view changes
    painter.redraw()
    assert painter.full_draws == 2
    assert painter._kept.get(ax2.lines[0]) is kept_line    # kept, not recorded again
    sent = unpack(painter.widget.scene)["items"]
    fresh = _view.ScenePainter(fig, FigureCanvas())
    fresh.redraw()
    expected = unpack(fresh.widget.scene)["items"]
    assert len(sent) == len(expected)
    for a, b in zip(sent, expected):
        np.testing.assert_allclose(a["v"], b["v"], rtol=0, atol=1e-3)
    plt.close(fig)


def test_an_explorer_figure_still_pickles():
    """The per-figure lock lives beside the figure, not in it: a figure pickles as before
    (oracle: the unpickled figure has the same axes titles)."""
    import pickle

    ex = CollimatorExplorer()
    assert ex.widget is not None
    with _view.figure_lock(ex.fig):
        copy = pickle.loads(pickle.dumps(ex.fig))
    assert [a.get_title() for a in copy.axes] == [a.get_title() for a in ex.fig.axes]
    plt.close(ex.fig)
    plt.close(copy)


def test_the_figure_lock_is_fair_and_re_entrant():
    """A thread that releases the lock and asks again queues behind a waiting one (a loop of
    saves or redraws must let another thread's update in between), and the owner may take it
    again (an update redraws). Oracle: the order in which the two threads got the lock."""
    import threading
    import time

    lock = _view.FairLock()
    order, waiting = [], threading.Event()

    def other():
        waiting.set()
        with lock:
            order.append("other")

    with lock:
        with lock:                                         # re-entrant
            thread = threading.Thread(target=other)
            thread.start()
            waiting.wait(5)
            time.sleep(0.2)                                # it is queued now
        order.append("first")
    with lock:                                             # asks again at once: second in line
        order.append("again")
    thread.join(5)
    assert order == ["first", "other", "again"]
    with pytest.raises(RuntimeError):
        lock.release()                                     # not held by this thread


@pytest.mark.parametrize("name", sorted(MOVES))
def test_every_message_to_an_explorer_waits_for_its_figure(name):
    """ipykernel hands each widget's messages to the thread that last sent on its comm, so
    one explorer's button and its sliders may be handled on two threads at once: every widget
    in the layout (nested boxes too, and the canvas) handles its messages holding the figure's
    lock. Oracle: a message delivered from another thread while this one holds the lock has
    not been handled after 0.5 s, and is handled once the lock is released."""
    import threading

    import ipywidgets as W

    cls, _ = MOVES[name]
    ex = cls()
    layout = ex.widget() if callable(ex.widget) else ex.widget
    widgets, todo = [], [layout]
    while todo:
        w = todo.pop()
        widgets.append(w)
        todo.extend(getattr(w, "children", ()))
    sliders = [w for w in widgets if isinstance(w, (W.FloatSlider, W.IntSlider))]
    assert len(widgets) > 5 and sliders
    handled = []
    for w in widgets:
        w.on_msg(lambda widget, content, buffers: handled.append(widget))
    with _view.figure_lock(ex.fig):
        threads = [threading.Thread(target=w.comm.handle_msg, args=(
            {"content": {"data": {"method": "custom", "content": {"type": "test"}}},
             "buffers": []},)) for w in widgets]
        for t in threads:
            t.start()
        threads[0].join(0.5)
        assert handled == [], f"{name}: a message was handled while the figure was locked"
    for t in threads:
        t.join(10)
    assert {id(w) for w in handled} == {id(w) for w in widgets}
    # the state a page sends goes through the same lock
    slider = sliders[0]
    with _view.figure_lock(ex.fig):
        value = slider.min if slider.value != slider.min else slider.max
        t = threading.Thread(target=slider.comm.handle_msg, args=(
            {"content": {"data": {"method": "update", "state": {"value": value}}},
             "buffers": []},))
        t.start()
        t.join(0.5)
        assert slider.value != value
    t.join(10)
    assert slider.value == value
    plt.close(ex.fig)


def test_a_wait_for_the_figure_lock_that_is_interrupted_gives_up_its_place():
    """Stop pressed on a cell that waits for the lock (a save while the explorer redraws):
    the interrupted thread leaves the queue, so the lock still goes to the next thread (red
    team 6: before, every later page message to the explorer waited for good). Oracle: another
    thread gets the lock after the holder releases it."""
    import signal
    import threading

    lock = _view.FairLock()
    holding, release = threading.Event(), threading.Event()

    def holder():
        with lock:
            holding.set()
            release.wait(10)

    first = threading.Thread(target=holder, daemon=True)   # daemons: a failure cannot hang
    first.start()
    holding.wait(5)

    def interrupt(*_):
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGALRM, interrupt)
    try:
        signal.setitimer(signal.ITIMER_REAL, 0.2)
        with pytest.raises(KeyboardInterrupt):
            with lock:                                   # waits, then is interrupted
                pass
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    got = threading.Event()
    second = threading.Thread(target=lambda: (lock.acquire(), got.set(), lock.release()),
                              daemon=True)
    second.start()
    release.set()
    first.join(5)
    assert got.wait(5), "the lock never went to the next thread after the interrupted wait"
    second.join(5)
