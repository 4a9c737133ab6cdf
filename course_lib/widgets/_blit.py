"""Redrawing a figure by blitting: a cached background, only the changing artists drawn.

Drawing a whole figure with Agg on every update redraws ticks, tick labels, legends and the
constrained-layout solution that have not changed. :class:`Blitter` solves the layout once,
keeps the static part of the figure (axes, ticks, tick and axis labels, grids) as a
background, and draws only the artists that can change, from kept pictures
(:class:`SpriteCache`, :class:`KeptPictures`) when they have not. While updates arrive faster
than frames can be drawn (a drag, a held key), frames are dropped rather than queued, so the
picture keeps up with the mouse.

:class:`~course_lib.widgets._view.ScenePainter` extends it to paint in the browser; on its
own, through :func:`~course_lib.widgets._view.use_blitting`, it redraws a figure's own Agg
canvas headless (the tests and benchmarks). Imported from :mod:`course_lib.widgets._view`.
"""

from __future__ import annotations

import asyncio
import math
import time

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg, RendererAgg
from matplotlib.collections import Collection
from matplotlib.image import AxesImage
from matplotlib.layout_engine import PlaceHolderLayoutEngine
from matplotlib.legend import Legend
from matplotlib.patches import Patch

from .._private_apis import figure_texts, legend_places_itself, place_title
from ._locks import figure_lock

__all__ = ["Blitter", "KeptPictures", "SpriteCache"]


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
        ``savefig`` between an update and its put-off frame)."""
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
        for text in [*figure_texts(fig), *fig.texts]:  # the suptitle is in fig.texts too
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
            place_title(ax, renderer)
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
        return not (isinstance(artist, Legend) and legend_places_itself(artist))

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
