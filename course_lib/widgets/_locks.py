"""One thread at a time on an explorer's figure: :func:`figure_lock` and what holds it.

In JupyterLab 4 with ipykernel 7 the widgets' messages (a slider moved, a button clicked, the
canvas' mouse) are handled in a kernel *subshell* thread, while the main thread runs the
cells and the kernel's event loop (a redraw put off during a drag, Blitter.redraw): two
threads may update, redraw or save one explorer's figure at the same time. Both draw with
the canvas' one Agg renderer, and savefig encodes the PNG straight from that renderer's buffer
(with the GIL released): a redraw at that moment cleared it, and the file came out blank or
drawn only in its top rows (``tests/widgets/test_view.py::
test_a_figure_saved_while_the_explorer_redraws_is_whole`` reproduces it). So an explorer's
update, its redraws and any draw or save of its figure hold one lock.

Nor do one explorer's widgets share a thread: ipykernel (7.4) hands a comm's messages to the
thread that last sent a message on that comm. A slider or the canvas, once updated from the
subshell, are handled there; a button that has only ever been drawn by its cell, on the main
thread (measured in JupyterLab: a "save figure" click ran while the subshell was still
working through a drag's mouse moves). So every message to an explorer's widgets is handled
holding the figure's lock too (:func:`one_message_at_a_time`): the explorer's callbacks,
its guards (``_syncing``, ``_holding``) and its state see one message at a time.

:func:`mark_live_readouts` is here too: it walks the same tree of widgets, once per layout.
Imported from :mod:`course_lib.widgets._view`.
"""

from __future__ import annotations

import collections
import functools
import threading
import weakref

import ipywidgets as W
from matplotlib.backends.backend_agg import FigureCanvasAgg

from .._private_apis import message_handler

__all__ = ["ExplorerCanvas", "FairLock", "figure_lock", "mark_live_readouts", "one_at_a_time",
           "one_message_at_a_time"]


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
    :func:`figure_lock` of ``fig`` (see the module's docstring); returns ``layout``.

    Each widget's comm gets a handler that takes the lock, then does what ipywidgets does
    (``Widget._handle_msg``: set the state the page sent, fire the observers, run the
    callbacks of a click or of a custom message)."""
    lock = figure_lock(fig)
    for widget in _widgets_in(layout):
        comm = getattr(widget, "comm", None)
        if comm is None:
            continue
        comm.on_msg(_holding(lock, message_handler(widget)))
    mark_live_readouts(layout)
    return layout


def _holding(lock, handle):
    """``handle(msg)`` run holding ``lock``."""

    def locked(msg):
        with lock:
            handle(msg)

    return locked


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
    screen reader announces what a control's move changed. A widget with the class
    ``course-quiet`` stays out (a table a screen reader would read out whole on every move:
    its explorer announces a one-line summary beside it). Returns ``layout``."""
    for widget in _widgets_in(layout):
        # a readout marked ``course-quiet`` (a whole table) is read on demand, not announced
        if type(widget) in (W.HTML, W.Label) and "course-quiet" not in widget._dom_classes:
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
