"""Every private matplotlib and ipywidgets API that ``course_lib`` uses, and nowhere else.

The explorers redraw only what changed (:mod:`course_lib.widgets._blit`), paint figures in the
browser from a recording renderer (:mod:`course_lib.widgets._scene`), take the figure's lock
around each widget message (:mod:`course_lib.widgets._locks`), tell a slider moved on the page
from one set in the kernel (:mod:`course_lib.widgets._slider_echoes`) and describe figures in
words (:mod:`course_lib.plots.describe`). A few of those steps need what the two libraries keep
private; each such use is one small function here, so that a new release that renames or
changes one breaks this module alone, and ``tests/course_lib/test_private_apis.py`` says which
one (it checks that each name still exists, with the signature and the behaviour used here).

``pyproject.toml`` bounds matplotlib to the series listed in :data:`CHECKED` (and ipywidgets to
its major version); raise the bound only after that test passes on the new release.
"""

from __future__ import annotations

try:  # Text's cache of text metrics, keyed by renderer
    from matplotlib.text import _get_text_metrics_with_cache as _text_metrics
except ImportError:  # pragma: no cover - a matplotlib without it: measured afresh instead
    _text_metrics = None

__all__ = ["CHECKED", "cached_text_width", "clip_gc", "colorbar_of", "figure_texts", "font_of",
           "legend_places_itself", "message_handler", "place_title", "scalar_alpha",
           "segments_3d", "set_from_page", "suptitle_text", "text_to_path"]

#: the releases these functions were checked against (``major.minor``)
CHECKED = {"matplotlib": "3.11", "ipywidgets": "8.1"}

#: the figure-level texts a figure keeps as private attributes (title, x and y labels)
_FIGURE_TEXTS = ("_suptitle", "_supxlabel", "_supylabel")


# -- matplotlib: axes, legends, figures ---------------------------------------------------------

def place_title(ax, renderer) -> None:
    """Place ``ax``'s titles again (``Axes._update_title_position``): a title drawn while
    hidden is placed as if it were not there. Nothing for an axes without the method."""
    if hasattr(ax, "_update_title_position"):
        ax._update_title_position(renderer)


def legend_places_itself(legend) -> bool:
    """Whether ``legend`` was given ``loc="best"`` (``Legend._loc`` 0 or ``"best"``): where it
    lands depends on everything else in the axes."""
    return legend._loc in (0, "best")


def figure_texts(fig) -> list:
    """The figure's suptitle, supxlabel and supylabel, each ``None`` when not set."""
    return [getattr(fig, name, None) for name in _FIGURE_TEXTS]


def suptitle_text(fig) -> str:
    """The text of ``fig``'s suptitle, ``""`` when it has none."""
    return fig._suptitle.get_text() if getattr(fig, "_suptitle", None) else ""


def colorbar_of(ax):
    """The colorbar that ``ax`` is the axes of (``Axes._colorbar``), else ``None``."""
    return getattr(ax, "_colorbar", None)


def segments_3d(collection):
    """A 3-D collection's faces before projection (``_segments3d``), else ``None``: it has no
    2-D paths until drawn."""
    return getattr(collection, "_segments3d", None)


# -- matplotlib: renderers, text and images -----------------------------------------------------

def text_to_path(renderer):
    """The :class:`~matplotlib.textpath.TextToPath` a renderer keeps (``_text2path``)."""
    return renderer._text2path


def font_of(text2path, prop):
    """The FT2Font that ``text2path`` lays ``prop`` out with (``TextToPath._get_font``)."""
    return text2path._get_font(prop)


def cached_text_width(renderer, s, prop, dpi) -> float | None:
    """The width of ``s`` in ``prop`` from the cache that ``Text`` layout filled for
    ``renderer`` (``text._get_text_metrics_with_cache``), or ``None`` when this matplotlib has
    no such cache or another signature than 3.7-3.11's."""
    if _text_metrics is None:
        return None
    try:
        return float(_text_metrics(renderer, s, prop, False, dpi)[0])
    except TypeError:
        return None


def clip_gc(artist, gc) -> None:
    """Set ``gc``'s clip box and path from ``artist`` (``Artist._set_gc_clip``)."""
    artist._set_gc_clip(gc)


def scalar_alpha(image) -> float:
    """An image's alpha as one number (``_ImageBase._get_scalar_alpha``: 1 for a per-pixel
    alpha array, which the image data carries)."""
    return image._get_scalar_alpha()


# -- ipywidgets ---------------------------------------------------------------------------------

def message_handler(widget):
    """What ipywidgets does with a message from the page to ``widget`` (``Widget._handle_msg``:
    set the state the page sent, fire the observers, run a click's or a custom message's
    callbacks); an explorer wraps it to hold the figure's lock."""
    return widget._handle_msg


def set_from_page(widget, name: str) -> bool:
    """Whether the change of ``widget.<name>`` being observed came from the page.

    ipywidgets sets a value received from the page inside ``_lock_property`` and fires the
    observers before releasing it (documented in ``Widget.set_state``: "Properties must be
    locked when the hold_trait_notification context manager is released and notifications
    are fired"); a value set in the kernel is not locked."""
    return name in getattr(widget, "_property_lock", {})
