"""The figure of an explorer as a widget, and how it is redrawn after each update.

An explorer's figure is shown by a :class:`~course_lib.widgets._canvas.FigureCanvas`, a
``<canvas>`` widget that the browser paints, and redrawn by a :class:`ScenePainter`: the
static part of the figure (axes, ticks, labels, grids) is drawn by Agg when the geometry
changes, and each update sends the changing artists to the page as a vector scene recorded by
a :class:`~course_lib.widgets._scene.SceneRenderer`, painted over that background in one task.
matplotlib stays the one description of every figure, as in the notebooks' static figures;
only its rasteriser is replaced, because redrawing a whole figure with Agg and sending it as
a PNG took longer than a key press may (``docs/explorers-design.md`` weighs the approaches).

The pieces live in three modules, all imported from here:

* :mod:`._locks`: one thread at a time on a figure (:func:`figure_lock`, :func:`one_at_a_time`,
  :func:`one_message_at_a_time`, :class:`ExplorerCanvas`): widget callbacks may run in another
  thread than the cells, and a redraw must not clear the buffer a ``savefig`` is encoding;
* :mod:`._blit`: :class:`Blitter`, the split into a frozen background and changing artists and
  the frame dropping, which :class:`ScenePainter` extends; through :func:`use_blitting` it
  redraws a figure's own Agg canvas headless, which is how ``tests/widgets/test_view.py``
  checks that the split is complete (a blitted frame is the picture of a full draw);
* this module: :class:`ScenePainter`, :class:`FigureView` and :class:`FigureExplorer`, what
  every explorer builds on.
"""

from __future__ import annotations

import io
import math
import sys

import ipywidgets as W
import numpy as np
from PIL import Image
from matplotlib.backend_bases import MouseButton, MouseEvent
from matplotlib.image import AxesImage

from ..plots.describe import alt_text
from . import _blit
from ._blit import Blitter, KeptPictures
from ._locks import (ExplorerCanvas, FairLock, figure_lock, mark_live_readouts, one_at_a_time,
                     one_message_at_a_time)
from ._scene import SceneRenderer, pack

__all__ = ["Blitter", "ExplorerCanvas", "FairLock", "FigureExplorer", "FigureView", "KeptPictures",
           "ScenePainter", "figure_lock", "mark_live_readouts", "one_at_a_time", "one_message_at_a_time",
           "readout_html",
           "use_blitting"]


class ScenePainter(Blitter):
    """Redraws a figure in the browser: Agg draws the static background (when the geometry
    changes), the changing artists go to the page as a vector scene.

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
        loop = _blit._running_loop()
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


class FigureView:
    """Shows one figure in an explorer's layout and redraws it after each update.

    By default the figure is a :class:`~course_lib.widgets._canvas.FigureCanvas` widget that
    the browser paints, redrawn by a :class:`ScenePainter`: a static background
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
