"""The figure of an explorer as a widget, and how it is redrawn after each update.

With ipympl (``%matplotlib widget``) the figure's canvas *is* a widget. With the inline backend
(or Agg, headless) it is not: the figure is drawn into an :class:`ipywidgets.Output` instead,
which is cleared and refilled on each redraw.

Why explorers blit (issue 15)
-----------------------------
Measured in Chromium through JupyterLab, a key press on a slider took 130-300 ms to reach the
screen although the maths of an update costs 0.3-17 ms: nearly all of it was matplotlib
redrawing the *whole* figure with Agg (ticks, tick labels, legends, titles, the constrained
layout solver), plus ipympl's round trip (``draw_idle`` asks the browser, which asks the kernel
back for a frame). Of the approaches weighed:

* a client-side widget library (anywidget with a canvas, bqplot) would answer fastest, but it
  means a second drawing stack for six explorers, a new dependency in the students' wheel, and
  figures that no longer match the notebooks' static matplotlib figures;
* smaller images while dragging trade sharpness for time and still pay for every tick label;
* throttling alone only hides latency (the kernel handles one slider message at a time
  anyway), but dropping the frames that would pile up behind a drag keeps the picture with
  the mouse, so the blitter does that too (:meth:`Blitter.redraw`);
* **blitting** keeps matplotlib and ipympl and removes the waste, so it is what
  :class:`Blitter` does. The layout is solved once and then frozen; the static part of the
  figure (axes backgrounds, ticks, tick and axis labels, grids) is drawn once into a
  background; an update restores that background, draws only the artists that can change
  (lines, images, collections, patches, texts and legends inside the axes, titles, the
  suptitle, the spines that a full draw paints over them; unchanged ones are pasted from
  sprites, see :class:`SpriteCache`) and sends the frame at once (``canvas.blit``): one frame
  per update, no round trip, nothing drawn twice, so nothing flickers. When an axes' limits
  or position, or the figure's size or dpi, have changed since the background was drawn,
  that update draws the whole figure and takes a new background.

A blitted frame is the same picture as a full draw (``tests/widgets/test_view.py`` compares
their pixels for every explorer), except that grid lines are drawn under an axes' content
(``axisbelow``) in both.
"""

from __future__ import annotations

import asyncio
import io
import math
import time
import types

import ipywidgets as W
import numpy as np
from PIL import Image
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg, RendererAgg
from matplotlib.collections import Collection
from matplotlib.legend import Legend
from matplotlib.patches import Patch
from matplotlib.layout_engine import PlaceHolderLayoutEngine

__all__ = ["Blitter", "FigureExplorer", "FigureView", "use_blitting"]


def _is_ipympl(canvas) -> bool:
    return isinstance(canvas, W.DOMWidget)


class Blitter:
    """Redraws a figure by restoring a cached background and drawing its changing artists.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure on an Agg-based canvas (ipympl's, or plain Agg).

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
        # stale callback would make ipympl ask the browser for a second, full frame)
        fig.stale_callback = None
        for ax in fig.axes:
            if ax.name != "3d":
                ax.set_axisbelow(True)
        fig.canvas.mpl_connect("draw_event", self._on_draw_event)
        if _is_ipympl(fig.canvas) and hasattr(fig.canvas, "_last_buff"):
            fig.canvas.get_diff_image = types.MethodType(_fast_diff_image, fig.canvas)

    def _on_draw_event(self, _event):
        if not self._own_draw:  # a draw from elsewhere (resize, dpi ratio): start again
            self.background = None

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
        if self._deferred is None:
            wait = self._cost - (time.perf_counter() - self._finished)
            loop = _running_loop() if wait > 0 else None
            if loop is None:
                self._redraw_now()
            else:
                self._deferred = loop.call_later(wait, self._redraw_deferred)
        # else: the frame already scheduled will show this state too. Either way the figure
        # is taken care of: a stale figure would make pyplot's post_execute hook (run after
        # every widget message) call draw_idle, and ipympl would then ask for a full redraw.
        self.fig.stale = False

    def _redraw_deferred(self):
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

    def _draw_all(self):
        fig, canvas = self.fig, self.fig.canvas
        self._freeze_layout()
        dynamic = [a for a in self.dynamic_artists() if a.get_visible()]
        for a in dynamic:
            a.set_visible(False)
        self._own_draw = True
        try:
            FigureCanvasAgg.draw(canvas)  # no frame sent yet: only the background
        finally:
            self._own_draw = False
            for a in dynamic:
                a.set_visible(True)
        renderer = canvas.get_renderer()
        for ax in fig.axes:  # a hidden title is placed as if it were not there: place it again
            if hasattr(ax, "_update_title_position"):
                ax._update_title_position(renderer)
        self.background = canvas.copy_from_bbox(fig.bbox)
        self.sprites = SpriteCache(canvas.get_renderer())
        self._signature = self.signature()
        self.full_draws += 1
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
            if sprites is not None and not a.stale and _cacheable(a):
                sprites.paint(a, renderer)
            else:
                if sprites is not None:  # changed: its old pixels are no longer its own
                    sprites.forget(a)
                fig.draw_artist(a)
        if not getattr(fig.canvas, "syncing_data_url", False):
            fig.canvas.blit(fig.bbox)  # ipympl: sends this one frame to the browser now
        # else: no browser view yet. ipympl would keep the frame as the widget's initial
        # image, in a form its front-end cannot load; the view asks for a full draw anyway.


def _running_loop():
    """The running asyncio event loop (the kernel's, in a notebook), or ``None``."""
    try:
        return asyncio.get_running_loop()
    except RuntimeError:
        return None


def _fast_diff_image(canvas):
    """Matplotlib's ``FigureCanvasWebAggCore.get_diff_image`` (the frame ipympl sends: the
    pixels changed since the last frame, the others transparent), PNG-compressed at level 1
    instead of zlib's default 6: a third less time per frame, a few kB more to send."""
    if not canvas._png_is_old:
        return None
    pixels = np.asarray(canvas.get_renderer().buffer_rgba())
    buff = pixels.view(np.uint32).squeeze(2)
    if (canvas._force_full or buff.shape != canvas._last_buff.shape
            or (pixels[:, :, 3] != 255).any()):
        canvas.set_image_mode("full")
        output = buff
    else:
        canvas.set_image_mode("diff")
        output = np.where(buff != canvas._last_buff, buff, 0)
    canvas._last_buff = buff.copy()
    canvas._force_full = False
    canvas._png_is_old = False
    data = output.view(dtype=np.uint8).reshape((*output.shape, 4))
    with io.BytesIO() as png:
        Image.fromarray(data).save(png, format="png", compress_level=1)
        return png.getvalue()


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


def _cacheable(artist) -> bool:
    """Whether an unchanged artist may be painted from a sprite: not an axes, nor a legend
    that places itself ("best") where the data leave room."""
    if isinstance(artist, Axes):
        return False
    return not (isinstance(artist, Legend) and artist._loc in (0, "best"))


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
        self._sprites: dict[int, tuple] = {}

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
        self._sprites.pop(id(artist), None)

    def paint(self, artist, renderer) -> None:
        """Composite ``artist``'s sprite (made now if missing) onto ``renderer``."""
        key = id(artist)
        entry = self._sprites.get(key)
        if entry is None or entry[0] is not artist:
            entry = self._sprites[key] = (artist, self._render(artist))
        sprite = entry[1]
        if sprite is not None:
            x, y, image = sprite
            gc = renderer.new_gc()
            renderer.draw_image(gc, x, y, image)
            gc.restore()


class FigureView:
    """Shows one figure in an explorer's layout and redraws it after each update.

    Parameters
    ----------
    blit : bool or None
        Redraw with a :class:`Blitter`. ``None`` (the default): with ipympl, where the frame
        goes to a browser. Plain Agg (headless, the tests) keeps matplotlib's own full draw
        unless ``blit=True``.
    """

    def __init__(self, blit: bool | None = None):
        self.output: W.Output | None = None
        self._widget = None
        self.blit = blit
        self.blitter: Blitter | None = None

    def widget(self, fig):
        """The widget to place in the layout: the ipympl canvas, or an Output to draw into."""
        if self._widget is None:
            if _is_ipympl(fig.canvas):
                self._widget = fig.canvas
            else:  # inline backend: redraw the figure into an Output widget
                self.output = self._widget = W.Output()
        return self._widget

    def _use_blitter(self, fig) -> bool:
        if self.blit is None:
            return _is_ipympl(fig.canvas)
        return bool(self.blit) and isinstance(fig.canvas, FigureCanvasAgg)

    def redraw(self, fig) -> None:
        """Redraw ``fig``: blitted (ipympl), in place (Agg) or into the Output widget (inline)."""
        if self._use_blitter(fig):
            if self.blitter is None or self.blitter.fig is not fig:
                self.blitter = Blitter(fig)
            self.blitter.redraw()
        elif self.output is not None:
            from IPython.display import display

            with self.output:
                self.output.clear_output(wait=True)
                display(fig)
        else:
            fig.canvas.draw_idle()


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
            self._layout = self._build_layout(self._view.widget(self.fig))
            self._redraw()
        return self._layout

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)


def use_blitting(explorer) -> FigureView:
    """Make ``explorer`` redraw by blitting whatever its canvas, plain Agg included (the tests
    and ``benchmarks/bench_widgets.py`` measure the browser's redraw path headless this way).

    Returns the new :class:`FigureView`; its ``blitter`` counts full draws and blits.
    """
    view = FigureView(blit=True)
    if isinstance(explorer, FigureExplorer):
        explorer._figure_view = view
    elif hasattr(explorer, "_view"):  # the B-scan and clipping explorers hold their own view
        explorer._view = view
        explorer.output = None  # redraw the figure itself, not a static copy in an Output
    else:
        raise ValueError(f"explorer: {type(explorer).__name__} has no figure view to replace")
    return view
