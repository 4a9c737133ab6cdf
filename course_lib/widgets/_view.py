"""The figure of an explorer as a widget, and how it is redrawn after each update (issue 15).

An explorer's figure is shown by a :class:`~course_lib.widgets._canvas.FigureCanvas`, a
``<canvas>`` widget that the browser paints, and redrawn by a :class:`ScenePainter`.

Why the browser paints (issue 15)
---------------------------------
Measured in Chromium through JupyterLab, a key press on a slider took 130-400 ms to reach the
screen with ipympl, although the maths of an update costs 1-30 ms: matplotlib redrew the whole
figure with Agg (ticks, tick labels, legends, the constrained-layout solver), and ipympl then
encoded it as a PNG, sent it, and the page decoded it. Of the approaches weighed:

* **blitting** (:class:`Blitter`): solve the layout once, keep the static part of the figure
  (axes, ticks, tick and axis labels, grids) as a background, and draw only the artists that
  can change. It halved the latency, but rasterising those artists and the PNG round trip of
  the larger figures still cost 100-180 ms at the 90th percentile;
* smaller images while dragging trade sharpness for time and change the picture while moving;
* throttling alone only hides latency; dropping the frames that would pile up behind a drag
  keeps the picture with the mouse, so :meth:`Blitter.redraw` does that;
* **painting on the client**, fed by ``course_lib``'s numbers. A second plotting library
  (bqplot, a hand-written canvas per explorer) would mean six figures drawn twice, unlike the
  notebooks' static matplotlib figures. Instead :class:`ScenePainter` keeps matplotlib as the
  one description of every figure and replaces only its rasteriser: the background is drawn by
  Agg when the geometry changes, and each update records the changing artists with a
  :class:`~course_lib.widgets._scene.SceneRenderer` (paths, markers, glyph outlines and images
  in display pixels) and sends that scene (16-250 kB) to the page, which paints background and
  scene in one task: one frame per update, nothing half drawn.

Widget callbacks may run in another thread than the cells and the kernel's event loop (a kernel
subshell, JupyterLab 4 with ipykernel 7): an explorer's updates, redraws and any draw or save
of its figure hold one lock per figure (:func:`figure_lock`), or a redraw could clear the Agg
buffer a ``savefig`` is encoding.

:class:`Blitter` remains the base of :class:`ScenePainter` (the split into background and
changing artists, the frozen layout, frame dropping) and, through :func:`use_blitting`, redraws
a figure's own Agg canvas headless: ``tests/widgets/test_view.py`` checks on it that the split
is complete (a blitted frame is the same picture as a full draw, for every explorer), which is
what the browser's picture relies on.
"""

from __future__ import annotations

import asyncio
import collections
import functools
import io
import math
import sys
import threading
import time
import weakref

import ipywidgets as W
import numpy as np
from PIL import Image
from matplotlib.axes import Axes
from matplotlib.backend_bases import MouseButton, MouseEvent
from matplotlib.backends.backend_agg import FigureCanvasAgg, RendererAgg
from matplotlib.collections import Collection
from matplotlib.image import AxesImage
from matplotlib.legend import Legend
from matplotlib.patches import Patch
from matplotlib.layout_engine import PlaceHolderLayoutEngine

from ..plots.describe import alt_text
from ._scene import SceneRenderer, pack

__all__ = ["Blitter", "ExplorerCanvas", "FairLock", "FigureExplorer", "FigureView", "KeptPictures",
           "ScenePainter", "figure_lock", "mark_live_readouts", "one_at_a_time", "one_message_at_a_time",
           "readout_html",
           "use_blitting"]


# -- one thread at a time on a figure --------------------------------------------------------------
# In JupyterLab 4 with ipykernel 7 the widgets' messages (a slider moved, a button clicked, the
# canvas' mouse) are handled in a kernel *subshell* thread, while the main thread runs the
# cells and the kernel's event loop (a redraw put off during a drag, Blitter.redraw): two
# threads may update, redraw or save one explorer's figure at the same time. Both draw with
# the canvas' one Agg renderer, and savefig encodes the PNG straight from that renderer's buffer
# (with the GIL released): a redraw at that moment cleared it, and the file came out blank or
# drawn only in its top rows (seen in the browser tests under load; reproduced by
# tests/widgets/test_view.py::test_a_figure_saved_while_the_explorer_redraws_is_whole).
# So an explorer's update, its redraws and any draw or save of its figure hold one lock.
#
# Nor do one explorer's widgets share a thread: ipykernel (7.4) hands a comm's messages to the
# thread that last sent a message on that comm. A slider or the canvas, once updated from the
# subshell, are handled there; a button that has only ever been drawn by its cell, on the main
# thread (measured in JupyterLab: a "save figure" click ran while the subshell was still
# working through a drag's mouse moves). So every message to an explorer's widgets is handled
# holding the figure's lock too (:func:`one_message_at_a_time`): the explorer's callbacks,
# its guards (``_syncing``, ``_holding``) and its state see one message at a time.

class FairLock:
    """A re-entrant lock that threads get in the order they asked for it.

    ``threading.RLock`` is not fair: a thread drawing or saving the figure in a loop takes it
    back at once after each round, and another thread's update may wait for the whole loop.
    Here a thread that releases the lock and asks again queues behind those already
    waiting."""

    def __init__(self):
        self._cond = threading.Condition(threading.Lock())
        self._owner = None
        self._depth = 0
        self._queue: collections.deque = collections.deque()

    def acquire(self) -> bool:
        me = threading.get_ident()
        with self._cond:
            if self._owner == me:
                self._depth += 1
                return True
            self._queue.append(me)
            try:
                while self._owner is not None or self._queue[0] != me:
                    self._cond.wait()
            except BaseException:
                # interrupted while waiting (Stop pressed on a cell that waits to save): give
                # up this place in the queue, or the threads behind it would wait for good
                self._queue.remove(me)
                self._cond.notify_all()
                raise
            self._queue.popleft()
            self._owner, self._depth = me, 1
            return True

    def release(self) -> None:
        with self._cond:
            if self._owner != threading.get_ident():
                raise RuntimeError("release of a FairLock this thread does not hold")
            self._depth -= 1
            if self._depth == 0:
                self._owner = None
                self._cond.notify_all()

    def __enter__(self):
        return self.acquire()

    def __exit__(self, *exc):
        self.release()


_LOCKS_LOCK = threading.Lock()
_FIGURE_LOCKS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def figure_lock(fig) -> FairLock:
    """The lock that an explorer's updates and every draw or save of ``fig`` hold (re-entrant:
    an update may redraw; fair: a save loop lets the explorer in between saves). Kept per
    figure, not per canvas (savefig to another format swaps the canvas for a while), and
    beside the figure, not in it (a figure still pickles)."""
    with _LOCKS_LOCK:
        lock = _FIGURE_LOCKS.get(fig)
        if lock is None:
            lock = _FIGURE_LOCKS[fig] = FairLock()
    return lock


def one_at_a_time(update):
    """Decorate an explorer's ``update`` method: it runs holding :func:`figure_lock` of
    ``self.fig``, so no other thread draws or saves the figure half-way through it."""

    @functools.wraps(update)
    def locked(self, *args, **kwargs):
        with figure_lock(self.fig):
            return update(self, *args, **kwargs)

    return locked


def one_message_at_a_time(layout, fig):
    """Handle every message from the page to ``layout`` and the widgets inside it holding
    :func:`figure_lock` of ``fig`` (see the note above :class:`FairLock`); returns ``layout``.

    Each widget's comm gets a handler that takes the lock, then does what ipywidgets does
    (``Widget._handle_msg``: set the state the page sent, fire the observers, run the
    callbacks of a click or of a custom message)."""
    lock = figure_lock(fig)
    for widget in _widgets_in(layout):
        comm = getattr(widget, "comm", None)
        if comm is None:
            continue

        def locked(msg, handle=widget._handle_msg):
            with lock:
                handle(msg)

        comm.on_msg(locked)
    mark_live_readouts(layout)
    return layout


def _widgets_in(layout):
    """Every widget of ``layout``'s tree, each once (a widget may sit in two boxes)."""
    todo, seen = [layout], set()
    while todo:
        widget = todo.pop()
        if id(widget) in seen:
            continue
        seen.add(id(widget))
        todo.extend(getattr(widget, "children", ()))
        yield widget


def mark_live_readouts(layout):
    """Give the explorer's text readouts (its ``HTML`` and ``Label`` widgets; not the typeset
    formulas, which a screen reader would spell out on every move) the class ``course-live``:
    the figure canvas' page code makes them ``aria-live="polite"`` status regions, so a
    screen reader announces what a control's move changed. Returns ``layout``."""
    for widget in _widgets_in(layout):
        if type(widget) in (W.HTML, W.Label):
            widget.add_class("course-live")
    return layout


class ExplorerCanvas(FigureCanvasAgg):
    """An explorer figure's Agg canvas: draws and saves (``savefig``) hold
    :func:`figure_lock`, so a cell saving the figure and a widget callback redrawing it in
    another thread take turns instead of sharing the renderer half-way."""

    def draw(self):
        with figure_lock(self.figure):
            super().draw()

    def print_figure(self, *args, **kwargs):
        with figure_lock(self.figure):
            return super().print_figure(*args, **kwargs)


class Blitter:
    """Redraws a figure by restoring a cached background and drawing its changing artists.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure on an Agg canvas.

    Notes
    -----
    :meth:`redraw` is the only entry point. The first call (and any call after the figure's
    geometry changed, see :meth:`signature`) draws everything; the others blit.
    ``full_draws`` and ``blits`` count what was done, for the tests and the benchmarks.
    """

    def __init__(self, fig):
        self.fig = fig
        self.background = None
        self.sprites = None
        self._signature = None
        self._own_draw = False
        self.full_draws = 0
        self.blits = 0
        self._deferred = None              # the scheduled redraw, while frames are dropped
        self._finished = -math.inf         # when the last frame was sent (perf_counter)
        self._cost = 0.0                   # and how long it took to draw
        # explorers decide when to draw: no automatic draw_idle on every set_data (pyplot's
        # stale callback would draw the whole figure again)
        fig.stale_callback = None
        for ax in fig.axes:
            if ax.name != "3d":
                ax.set_axisbelow(True)
        fig.canvas.mpl_connect("draw_event", self._on_draw_event)

    def _on_draw_event(self, _event):
        if not self._own_draw:  # a draw from elsewhere (resize, dpi ratio, savefig): start again
            self.background = None
            self._forget_pictures()

    def _forget_pictures(self) -> None:
        """After a draw from elsewhere: pictures kept of unchanged artists can no longer be
        trusted, since that draw cleared every artist's ``stale`` flag, changed or not (a
        ``savefig`` between an update and its put-off frame; playtest 7)."""
        self.sprites = None

    def signature(self) -> tuple:
        """What the background depends on: the figure's size and dpi, and each axes' position,
        view limits and scales."""
        fig = self.fig
        axes = tuple((tuple(ax.get_position().bounds), tuple(ax.viewLim.bounds),
                      ax.get_xscale(), ax.get_yscale(), _view_3d(ax)) for ax in fig.axes)
        return (tuple(fig.bbox.bounds), float(fig.dpi), axes)

    def dynamic_artists(self) -> list:
        """The artists drawn on every update, in the order a full draw paints them."""
        fig = self.fig
        out = []
        for ax in fig.axes:
            static = {ax.xaxis, ax.yaxis, getattr(ax, "zaxis", None), ax.patch}
            children = [a for a in ax.get_children() if a not in static]
            if ax.name == "3d":
                _project_3d(ax, children)
            out.extend(sorted(children, key=lambda a: a.get_zorder()))
        figure_texts = [getattr(fig, name, None) for name in ("_suptitle", "_supxlabel",
                                                               "_supylabel")]
        for text in [*figure_texts, *fig.texts]:  # the suptitle is in fig.texts too
            if text is not None and text not in out:
                out.append(text)
        return out

    def redraw(self) -> None:
        """Show the figure as it is now: blit when the background still fits, else draw all.

        While updates arrive faster than frames can be drawn (a drag, a held key), frames are
        dropped rather than queued: when the last frame ended less than its own drawing time
        ago, the redraw is put off until then on the kernel's event loop, and every update
        that arrives meanwhile is shown by that one frame. Without a running event loop
        (headless, the tests) every redraw happens at once.
        """
        with figure_lock(self.fig):
            if self._deferred is None:
                wait = self._cost - (time.perf_counter() - self._finished)
                loop = _running_loop() if wait > 0 else None
                if loop is None:
                    self._redraw_now()
                else:
                    self._deferred = loop.call_later(wait, self._redraw_deferred)
            # else: the frame already scheduled will show this state too. Either way the
            # figure is taken care of: a stale figure would make pyplot's post_execute hook
            # call draw_idle, a full redraw.
            self.fig.stale = False

    def _redraw_deferred(self):
        with figure_lock(self.fig):
            self._deferred = None
            self._redraw_now()

    def _redraw_now(self):
        start = time.perf_counter()
        if self.background is None or self.signature() != self._signature:
            self._draw_all()
        else:
            self._blit()
        self._finished = time.perf_counter()
        self._cost = self._finished - start

    def _draw_background(self) -> list:
        """Draw the figure with Agg without its changing artists (the layout frozen first);
        returns those artists, visible again. Counts a full draw."""
        fig, canvas = self.fig, self.fig.canvas
        self._freeze_layout()
        dynamic = [a for a in self.dynamic_artists() if a.get_visible()]
        stale = [a.stale for a in dynamic]
        for a in dynamic:
            a.set_visible(False)
        self._own_draw = True
        try:
            FigureCanvasAgg.draw(canvas)  # no frame sent yet: only the background
        finally:
            self._own_draw = False
            for a, was_stale in zip(dynamic, stale):
                a.set_visible(True)
                a.stale = was_stale   # hidden and shown again, it has not changed
        renderer = canvas.get_renderer()
        for ax in fig.axes:  # a hidden title is placed as if it were not there: place it again
            if hasattr(ax, "_update_title_position"):
                ax._update_title_position(renderer)
        self._signature = self.signature()
        self.full_draws += 1
        return dynamic

    def _draw_all(self):
        dynamic = self._draw_background()
        canvas = self.fig.canvas
        self.background = canvas.copy_from_bbox(self.fig.bbox)
        self.sprites = SpriteCache(canvas.get_renderer())
        self._paint(dynamic)

    def _freeze_layout(self):
        """Solve the figure's layout (constrained) once, with every artist visible, and keep
        it: re-solving it cost up to half of every full draw."""
        fig = self.fig
        engine = fig.get_layout_engine()
        if engine is not None and not isinstance(engine, PlaceHolderLayoutEngine):
            engine.execute(fig)
            fig.set_layout_engine("none")

    def _blit(self):
        self.fig.canvas.restore_region(self.background)
        self.blits += 1
        self._paint(self.dynamic_artists(), self.sprites)

    def _paint(self, artists, sprites=None):
        """Draw ``artists`` over the canvas (from their sprites when unchanged) and send it."""
        fig = self.fig
        renderer = fig.canvas.get_renderer()
        for a in artists:
            if not a.get_visible():
                continue
            if sprites is not None and KeptPictures.unchanged(a):
                sprites.paint(a, renderer)
            else:
                if sprites is not None:  # changed: its old pixels are no longer its own
                    sprites.forget(a)
                fig.draw_artist(a)
        fig.canvas.blit(fig.bbox)


class ScenePainter(Blitter):
    """Redraws a figure in the browser: Agg draws the static background (when the geometry
    changes), the changing artists go to the page as a vector scene (issue 15).

    Same split and the same frame dropping as :class:`Blitter`, but nothing is rasterised in
    the kernel after the first frame: each update records the dynamic artists with a
    :class:`~course_lib.widgets._scene.SceneRenderer` (an unchanged artist's items are kept
    from the frame before) and sends them to a :class:`~course_lib.widgets._canvas.FigureCanvas`,
    whose page paints them over the background in one JavaScript task.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    canvas_widget : FigureCanvas
        The widget the frames go to; its mouse messages come back as matplotlib events.
    """

    def __init__(self, fig, canvas_widget):
        _plain_agg_canvas(fig)
        super().__init__(fig)
        self.widget = canvas_widget
        self._base_dpi = float(fig.dpi)
        self._ratio = 1.0                  # the page's pixels per CSS pixel, as last reported
        self._renderer = None
        self._kept = KeptPictures()          # each unchanged artist's recorded items
        self._describing = None              # the scheduled rewrite of the text alternative
        canvas_widget.on_msg(self._on_msg)
        # a 3-D view turns by dragging it, and by the arrow keys on the focused canvas
        canvas_widget.turnable = any(ax.name == "3d" for ax in fig.axes)

    def _forget_pictures(self) -> None:
        self._kept.clear()

    def _draw_all(self):
        before = self._signature
        dynamic = self._draw_background()
        renderer = self.fig.canvas.get_renderer()
        with io.BytesIO() as png:  # the background, as the page will show it
            Image.fromarray(np.asarray(renderer.buffer_rgba())).save(
                png, format="png", compress_level=1)
            self.background = png.getvalue()
        moved = _axes_with_a_new_view(before, self._signature, self.fig)
        if moved is None or self._renderer is None or self._renderer._metrics is not renderer:
            self._renderer = SceneRenderer(renderer)
            self._kept.clear()
        else:  # same size and layout: what other axes hold is where it was (a pitch slider)
            self._kept.keep_only(lambda artist: getattr(artist, "axes", None) not in moved)
        self._paint(dynamic, new_background=True)

    def _blit(self):
        self.blits += 1
        self._paint(self.dynamic_artists())

    def _paint(self, artists, new_background=False):
        scene = self._renderer
        items = []
        for a in artists:
            if not a.get_visible():
                continue
            kept = self._kept.get(a)
            if kept is KeptPictures.NONE:
                scene.items = kept = []
                if isinstance(a, AxesImage):
                    scene.draw_axes_image(a)  # at its own resolution: the browser scales it
                else:
                    a.draw(scene)
                self._kept.put(a, kept)
            items.extend(kept)
        width, height = (int(round(v)) for v in self.fig.bbox.size)
        self.widget.show(scene=pack(items, scene.clips, scene.height), size=(width, height),
                         background=self.background if new_background else None)
        self._describe()

    #: the canvas' text alternative is rewritten at most this long after a frame (s)
    DESCRIBE_AFTER_S = 0.25

    def _describe(self):
        """Rewrite the canvas' text alternative (``alt``, its ``aria-label``) from the figure:
        at once without an event loop (headless), else once, :attr:`DESCRIBE_AFTER_S` after
        the frame, off the key-to-pixels path; the frames of a drag in between are not
        described, the last one is."""
        loop = _running_loop()
        if loop is None:
            self.widget.alt = alt_text(self.fig)
        elif self._describing is None:
            self._describing = loop.call_later(self.DESCRIBE_AFTER_S, self._describe_now)

    def _describe_now(self):
        with figure_lock(self.fig):
            self._describing = None
            self.widget.alt = alt_text(self.fig)

    # -- messages from the page -------------------------------------------------------------
    def _on_msg(self, _widget, content, _buffers):
        if not isinstance(content, dict):
            return
        if content.get("type") == "ratio":
            self._set_ratio(content.get("ratio"))
        elif content.get("type") == "mouse":
            self._mouse(content)
        elif content.get("type") == "key":
            self._turn(content)

    #: degrees of a 3-D view's turn per arrow key (with Shift: three times as many)
    TURN_DEG = 5.0

    def _turn(self, content):
        """An arrow key on the canvas: turn every 3-D axes of the figure (left/right: azimuth,
        up/down: elevation, kept within +-90 degrees), what dragging the view does by mouse.
        Other keys, and figures without a 3-D axes, are ignored."""
        steps = {"ArrowLeft": (0, -1), "ArrowRight": (0, 1), "ArrowUp": (1, 0),
                 "ArrowDown": (-1, 0)}
        if content.get("key") not in steps:
            return
        de, da = (self.TURN_DEG * (3 if content.get("shift") else 1) * s
                  for s in steps[content["key"]])
        with figure_lock(self.fig):
            axes = [ax for ax in self.fig.axes if ax.name == "3d"]
            for ax in axes:
                ax.view_init(elev=float(np.clip(ax.elev + de, -90.0, 90.0)),
                             azim=(ax.azim + da + 180.0) % 360.0 - 180.0, roll=ax.roll)
            if axes:
                self.redraw()

    def _set_ratio(self, ratio):
        """The page's ``devicePixelRatio`` (0.5 to 4; anything else is ignored): the figure is
        drawn with that many pixels per CSS pixel."""
        try:
            ratio = float(ratio)
        except (TypeError, ValueError, OverflowError):
            return
        if not (0.5 <= ratio <= 4) or ratio == self._ratio:
            return
        with figure_lock(self.fig), self.widget.hold_sync():
            self._ratio = ratio
            self.fig.set_dpi(self._base_dpi * ratio)
            self.widget.ratio = ratio
            self.redraw()

    def _mouse(self, content):
        """A mouse message from the page as a matplotlib event: a press, a move while pressed
        or a release, at finite display coordinates within the canvas (others are ignored)."""
        name = content.get("name")
        if name not in ("button_press_event", "motion_notify_event", "button_release_event"):
            return
        try:
            x, y = float(content["x"]), float(content["y"])
            button = MouseButton(int(content.get("button", 1)))
        except (KeyError, TypeError, ValueError, OverflowError):
            return
        width, height = self.fig.bbox.size
        if not (math.isfinite(x) and math.isfinite(y)):
            return
        x, y = min(max(x, 0.0), width), min(max(y, 0.0), height)
        with figure_lock(self.fig):
            event = MouseEvent(name, self.fig.canvas, x, y, button=button)
            self.fig.canvas.callbacks.process(name, event)
            if self.fig.stale:  # e.g. a 3-D axes turned by the drag: show it
                self.redraw()


def _plain_agg_canvas(fig) -> None:
    """Make ``fig`` the browser canvas' own: out of pyplot, on an :class:`ExplorerCanvas`.

    pyplot would otherwise keep the figure as its current one (a student's next ``plt.plot``
    would draw into the explorer, and the inline backend would show it again as a picture).
    Another canvas (ipympl's, under ``%matplotlib widget``) is a widget of its own, whose page
    asks the kernel for full redraws: it is closed. Callbacks live on the figure and stay."""
    pyplot = sys.modules.get("matplotlib.pyplot")
    if pyplot is not None:
        pyplot.close(fig)
    old = fig.canvas
    if type(old) is not ExplorerCanvas:
        ExplorerCanvas(fig)
        if isinstance(old, W.Widget):
            old.close()


def _axes_with_a_new_view(before, after, fig) -> set | None:
    """Between two :meth:`Blitter.signature` of ``fig``: the axes whose view (limits, scales,
    3-D angles) changed, when nothing else did; ``None`` when the figure's size, dpi, number
    of axes or any axes' position changed (then every artist may have moved)."""
    if before is None or before[:2] != after[:2] or len(before[2]) != len(after[2]):
        return None
    moved = set()
    for ax, old, new in zip(fig.axes, before[2], after[2]):
        if old[0] != new[0]:
            return None
        if old != new:
            moved.add(ax)
    return moved


def _running_loop():
    """The running asyncio event loop (the kernel's, in a notebook), or ``None``."""
    try:
        return asyncio.get_running_loop()
    except RuntimeError:
        return None


def _view_3d(ax) -> tuple:
    """The viewing angles and limits of a 3-D axes (``()`` for a 2-D one)."""
    if ax.name != "3d":
        return ()
    return (ax.elev, ax.azim, ax.roll, tuple(ax.get_w_lims()))


def _project_3d(ax, children) -> None:
    """What :meth:`Axes3D.draw` does before drawing its children: project the collections and
    patches to 2-D and, with ``computed_zorder``, order them by depth above the axis."""
    ax.M = ax.get_proj()
    ax.invM = np.linalg.inv(ax.M)
    items = [a for a in children if isinstance(a, (Collection, Patch)) and a.get_visible()]
    if not ax.computed_zorder:
        for a in items:
            a.do_3d_projection()
        return
    offset = max(axis.get_zorder() for axis in (ax.xaxis, ax.yaxis, ax.zaxis)) + 1
    zorder = {Collection: offset, Patch: offset}
    for a in sorted(items, key=lambda a: a.do_3d_projection(), reverse=True):
        kind = Collection if isinstance(a, Collection) else Patch
        a.zorder = zorder[kind]
        zorder[kind] += 1


class KeptPictures:
    """What was drawn of each artist (a sprite, recorded scene items), kept for as long as the
    artist does not change, by :class:`SpriteCache` and :class:`ScenePainter`.

    A picture is out of date once its artist is stale (matplotlib sets ``stale`` on every
    ``set_*``) or, for a colour-mapped collection, holds another data array: ``set_array``
    does not mark it stale, so the entry keeps the array it was drawn with (a new array can
    then never reuse its ``id``). Axes and legends that place themselves (``loc="best"``) are
    never kept: where they land depends on everything else.
    """

    NONE = object()                  # what :meth:`get` answers when nothing valid is kept

    def __init__(self):
        self._entries: dict[int, tuple] = {}

    @staticmethod
    def data_of(artist):
        """The data array of a colour-mapped artist (a collection's ``set_array``), else
        ``None``."""
        get_array = getattr(artist, "get_array", None)
        return get_array() if callable(get_array) and not isinstance(artist, AxesImage) else None

    @staticmethod
    def unchanged(artist) -> bool:
        """Whether ``artist`` may be shown from a kept picture at all: not stale, not an axes,
        nor a legend that places itself."""
        if artist.stale or isinstance(artist, Axes):
            return False
        return not (isinstance(artist, Legend) and artist._loc in (0, "best"))

    def get(self, artist):
        """``artist``'s kept picture if still valid, else :attr:`NONE`."""
        entry = self._entries.get(id(artist))
        if (entry is None or entry[0] is not artist or entry[2] is not self.data_of(artist)
                or not self.unchanged(artist)):
            return self.NONE
        return entry[1]

    def put(self, artist, picture):
        """Keep ``picture`` as what ``artist`` looks like now; returns it."""
        self._entries[id(artist)] = (artist, picture, self.data_of(artist))
        return picture

    def forget(self, artist) -> None:
        self._entries.pop(id(artist), None)

    def keep_only(self, wanted) -> None:
        """Forget every picture whose artist ``wanted(artist)`` rejects."""
        self._entries = {k: e for k, e in self._entries.items() if wanted(e[0])}

    def clear(self) -> None:
        self._entries.clear()


class SpriteCache:
    """Pixels of unchanged artists, painted back instead of drawing them again.

    Drawing text (titles, legends, labels) is most of what a blitted update costs in Agg. An
    artist that has not changed since it was last drawn (matplotlib clears its ``stale`` flag
    when it is drawn and sets it on every ``set_*``) is drawn once onto a transparent canvas of
    the figure's size; the smallest rectangle holding its pixels is kept and composited over
    the frame afterwards, which is the same "over" blend its own drawing does. The cache lives
    as long as the background it was made for. An explorer that changes an artist some other
    way (a transform it mutates, an array edited in place) must call a ``set_*`` method too, or
    set ``artist.stale = True``: the collimator's side view, which mutates its scaling, moves
    every one of its artists with ``set_*`` on each update.
    """

    def __init__(self, renderer):
        self.width, self.height, self.dpi = renderer.width, renderer.height, renderer.dpi
        self._scratch = None
        self._sprites = KeptPictures()

    def _render(self, artist):
        if self._scratch is None:
            self._scratch = RendererAgg(self.width, self.height, self.dpi)
        scratch = self._scratch
        scratch.clear()
        artist.draw(scratch)
        pixels = np.asarray(scratch.buffer_rgba())
        alpha = pixels[..., 3]
        rows, cols = np.flatnonzero(alpha.any(axis=1)), np.flatnonzero(alpha.any(axis=0))
        if rows.size == 0:
            return None
        r0, r1, c0, c1 = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
        return c0, self.height - r1, pixels[r0:r1, c0:c1][::-1].copy()  # rows bottom-up

    def forget(self, artist) -> None:
        """Drop ``artist``'s sprite (it has changed)."""
        self._sprites.forget(artist)

    def paint(self, artist, renderer) -> None:
        """Composite ``artist``'s sprite (made now if missing or out of date) onto
        ``renderer``."""
        sprite = self._sprites.get(artist)
        if sprite is KeptPictures.NONE:
            sprite = self._sprites.put(artist, self._render(artist))
        if sprite is not None:
            x, y, image = sprite
            gc = renderer.new_gc()
            renderer.draw_image(gc, x, y, image)
            gc.restore()


class FigureView:
    """Shows one figure in an explorer's layout and redraws it after each update.

    By default the figure is a :class:`~course_lib.widgets._canvas.FigureCanvas` widget that
    the browser paints, redrawn by a :class:`ScenePainter` (issue 15): a static background
    drawn by Agg now and then, and the changing artists as vector scenes.

    Parameters
    ----------
    blit : bool
        ``True``: redraw the figure's own Agg canvas with a :class:`Blitter` instead, and show
        nothing (headless: the tests and benchmarks of the Agg redraw use it through
        :func:`use_blitting`).
    """

    def __init__(self, blit: bool = False):
        self.blit = bool(blit)
        self.blitter: Blitter | None = None      # the Blitter or ScenePainter that redraws
        self._widget = None

    def widget(self, fig):
        """The widget to place in the layout: the figure's browser canvas."""
        if self._widget is None:
            from ._canvas import FigureCanvas

            self._widget = FigureCanvas()
        return self._widget

    def redraw(self, fig) -> None:
        """Show ``fig`` as it is now (in the browser canvas, or on its Agg canvas with
        ``blit=True``)."""
        if self.blitter is None or self.blitter.fig is not fig:
            self.blitter = Blitter(fig) if self.blit else ScenePainter(fig, self.widget(fig))
        self.blitter.redraw()


class FigureExplorer:
    """What every figure-based explorer shares: the figure view, the cached layout, redrawing
    and display. A subclass sets ``self.fig`` and writes ``_build_layout(view)``, which places
    ``view`` (the figure's widget) among its controls and returns the whole layout."""

    fig = None

    @property
    def _view(self) -> FigureView:
        if "_figure_view" not in self.__dict__:
            self._figure_view = FigureView()
        return self._figure_view

    def _build_layout(self, view):  # pragma: no cover - every explorer overrides it
        raise NotImplementedError

    def _redraw(self):
        self._view.redraw(self.fig)

    @property
    def widget(self):
        """The explorer's layout, built once; shows the figure as it is now."""
        if self.__dict__.get("_layout") is None:
            self._layout = one_message_at_a_time(self._build_layout(self._view.widget(self.fig)),
                                                 self.fig)
            self._redraw()
        return self._layout

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)


def readout_html(*lines: str) -> str:
    """An explorer's text readout (an ``ipywidgets.HTML`` value): ``lines`` in a monospace
    block, one per line."""
    return ("<div style='font-family: monospace; font-size: 12px; line-height: 1.5'>"
            + "<br>".join(lines) + "</div>")


def set_view(explorer, view):
    """Give ``explorer`` another figure view (anything with ``redraw(fig)``); returns it.

    The tests and benchmarks swap views this way: :func:`use_blitting`, or a view that draws
    nothing, to time an update's compute alone."""
    if isinstance(explorer, FigureExplorer):
        explorer._figure_view = view
    elif hasattr(explorer, "_view"):  # the B-scan and clipping explorers hold their own view
        explorer._view = view
    else:
        raise ValueError(f"explorer: {type(explorer).__name__} has no figure view to replace")
    return view


def use_blitting(explorer) -> FigureView:
    """Make ``explorer`` redraw its own Agg canvas by blitting (the tests and
    ``benchmarks/bench_widgets.py`` measure that redraw headless this way).

    Returns the new :class:`FigureView`; its ``blitter`` counts full draws and blits.
    """
    return set_view(explorer, FigureView(blit=True))
