"""Text alternatives of the course's figures, written from the data they show.

A blind student reads a figure through its text alternative (the image's ``alt``, the
explorer canvas' ``aria-label``). Matplotlib has no alt-text API, so :func:`alt_text` writes
one from the artists themselves: per panel its title, each axis' label (with its units) and
range, and what is drawn (each curve's range and extreme, an image's size and value range, the
bars' heights, the markers, the labels written on the plot, the legend). A plot function that
knows what the student should read off (the B-scan's displayed depths, the sphere's
highlight) puts that first with :func:`set_summary`; the panels follow.

The text is built from the figure as it is when asked, so an explorer that moves its artists
gets a new text each frame.
"""

from __future__ import annotations

import numpy as np
from matplotlib.collections import LineCollection, PathCollection, QuadMesh
from matplotlib.container import BarContainer
from matplotlib.patches import Rectangle

from .._private_apis import colorbar_of, segments_3d, suptitle_text

__all__ = ["alt_text", "describe_axes", "num", "set_summary", "summary"]

#: most curves, texts or bars named per panel (a longer list is summed up by its count)
MAX_ITEMS = 8
_SUMMARY = "_course_alt_summary"


def num(value) -> str:
    """A number as a student reads it off a figure: three significant figures."""
    value = float(value)
    if not np.isfinite(value):
        return str(value)
    if abs(value) < 1e-12:      # rounding noise of a computed zero ("2.78e-17"), read as 0
        value = 0.0
    if value == 0 or not 1e-3 <= abs(value) < 1e6:
        return f"{value:.3g}".replace("e+0", "e").replace("e-0", "e-")
    digits = 2 - int(np.floor(np.log10(abs(value))))    # decimals that keep 3 figures
    text = f"{round(value, digits):.{max(digits, 0)}f}"
    return text.rstrip("0").rstrip(".") if "." in text else text


def set_summary(where, text) -> None:
    """What a figure or one of its axes (``where``) shows, in a sentence or two with its
    numbers: put first in the figure's :func:`alt_text` or first in that panel's description.
    Plot functions call it; explorers call it again when they move. ``text`` may be a
    function of no arguments returning the text, called only when the text is asked for (an
    explorer's update then costs nothing more)."""
    setattr(where, _SUMMARY, text if callable(text) else " ".join(str(text).split()))


def summary(where) -> str:
    """The text :func:`set_summary` gave a figure or axes (``""`` if none)."""
    text = getattr(where, _SUMMARY, "") or ""
    return " ".join(str(text()).split()) if callable(text) else text


def alt_text(fig) -> str:
    """The text alternative of ``fig``: its summary (if a plot function set one), then each
    panel described from its artists."""
    axes = [ax for ax in fig.axes if ax.get_visible() and not _is_colourbar(ax)]
    parts = [summary(fig)]
    title = suptitle_text(fig)
    if title:
        parts.append(f"Figure: {_clean(title)}.")
    for i, ax in enumerate(axes):
        head = f"Panel {i + 1} of {len(axes)}: " if len(axes) > 1 else ""
        parts.append(head + describe_axes(ax))
    for ax in fig.axes:
        if _is_colourbar(ax):
            parts.append(_colourbar(ax))
    return " ".join(p for p in parts if p).strip() or "An empty figure."


def _clean(text: str) -> str:
    """Plain words of a label: mathtext dollars and braces dropped, lines joined."""
    text = str(text).replace("$", "").replace("\\", "").replace("{", "").replace("}", "")
    return " ".join(text.split())


def _is_colourbar(ax) -> bool:
    return colorbar_of(ax) is not None


def _colourbar(ax) -> str:
    cb = colorbar_of(ax)
    label = _clean(cb.ax.get_ylabel() or cb.ax.get_xlabel()) or "value"
    lo, hi = cb.norm.vmin, cb.norm.vmax
    if lo is None or hi is None:
        return f"Colour scale of {label}."
    return f"Colour scale of {label} from {num(lo)} to {num(hi)}."


def _axis(ax, name: str) -> str:
    label = _clean(getattr(ax, f"get_{name}label")()) or name
    lo, hi = getattr(ax, f"get_{name}lim")()
    return f"{name} axis {label}, {num(lo)} to {num(hi)}"


def describe_axes(ax) -> str:
    """One panel: title, axes with their ranges, then what is drawn on it."""
    names = ("x", "y", "z") if ax.name == "3d" else ("x", "y")
    title = " ".join(_clean(t) for t in (ax.get_title("left"), ax.get_title(),
                                         ax.get_title("right")) if t)
    parts = [f"{title}." if title else "", summary(ax)]
    if ax.name == "3d":
        parts.append(f"A 3-D view seen from azimuth {num(ax.azim)} degrees, elevation "
                     f"{num(ax.elev)} degrees.")
    if ax.axison or ax.name == "3d":   # a 3-D box's range is its content, shown or not
        parts.append("; ".join(_axis(ax, n) for n in names) + ".")
    parts += _lines(ax) + _images(ax) + _collections(ax) + _bars(ax) + _texts(ax) + _legend(ax)
    return " ".join(p for p in parts if p)


def _finite_xy(line):
    x, y = (np.asarray(v, dtype=float).ravel() for v in line.get_data(orig=False)[:2])
    if x.shape != y.shape:
        return np.empty(0), np.empty(0)
    ok = np.isfinite(x) & np.isfinite(y)
    return x[ok], y[ok]


def _in_view(line, x, y):
    """The part of a curve inside its panel's x range, its values clipped to the y range:
    what the figure shows (a trace drawn down to -120 on an axis from -100 reads -100)."""
    ax = line.axes
    if ax is None or ax.name != "rectilinear" or x.size == 0:
        return x, y
    (x0, x1), (y0, y1) = sorted(ax.get_xlim()), sorted(ax.get_ylim())
    inside = (x >= x0) & (x <= x1)
    return (x[inside], np.clip(y[inside], y0, y1)) if inside.any() else (x[:0], y[:0])


def _line(line) -> str:
    label = line.get_label()
    name = f"'{_clean(label)}'" if label and not label.startswith("_") else "a line"
    if hasattr(line, "get_data_3d"):
        xyz = np.asarray(line.get_data_3d(), dtype=float)
        pts = xyz[:, np.all(np.isfinite(xyz), axis=0)].T
        if len(pts) <= 4:
            return f"{name} through " + ", ".join(
                "(" + ", ".join(num(v) for v in p) + ")" for p in pts)
        return f"{name} of {len(pts)} points"
    x, y = _in_view(line, *_finite_xy(line))
    if x.size == 0:
        return ""
    if np.ptp(x) == 0 and np.ptp(y) == 0:
        return f"{name} at the point ({num(x[0])}, {num(y[0])})"
    if x.size > 4 and x[0] == x[-1] and y[0] == y[-1]:
        return (f"{name}, a closed outline over x {num(x.min())} to {num(x.max())}, "
                f"y {num(y.min())} to {num(y.max())}")
    if x.size <= 4:
        return f"{name} through " + ", ".join(f"({num(a)}, {num(b)})" for a, b in zip(x, y))
    k, j = int(np.argmax(y)), int(np.argmin(y))
    return (f"{name} from ({num(x[0])}, {num(y[0])}) to ({num(x[-1])}, {num(y[-1])}), "
            f"highest {num(y[k])} at x = {num(x[k])}, lowest {num(y[j])} at x = {num(x[j])}")


def _lines(ax) -> list[str]:
    """Named curves one by one; unnamed ones (edges, guides) too when few."""
    lines = [ln for ln in ax.get_lines() if ln.get_visible()]
    named = [ln for ln in lines if not ln.get_label().startswith("_")]
    unnamed = [ln for ln in lines if ln.get_label().startswith("_")]
    shown = named[:MAX_ITEMS] + (unnamed if len(unnamed) <= 3 else [])
    # many unnamed lines are a drawing's edges and guides: not worth a count read aloud
    said = [s for s in map(_line, shown) if s]
    return [("Lines: " if len(said) > 1 else "") + "; ".join(said) + "."] if said else []


def _images(ax) -> list[str]:
    out = []
    for im in ax.images:
        if not im.get_visible():
            continue
        arr = np.ma.filled(np.ma.asarray(im.get_array(), dtype=float), np.nan)
        what = f"An image of {arr.shape[1]} by {arr.shape[0]} pixels"
        if arr.ndim == 2 and np.isfinite(arr).any():
            what += (f", values from {num(np.nanmin(arr))} to {num(np.nanmax(arr))} "
                     f"shown on the {im.get_cmap().name} colour map")
        elif arr.ndim == 3 and arr.shape[2] >= 3 and np.isfinite(arr).any():
            what += _brightness(arr)
        out.append(what + ".")
    return out


def _brightness(rgb) -> str:
    """Where a colour image is brightest and darkest (relative luminance, 0 to 1), and its
    mean: what a student reads off a shaded sphere or a swatch."""
    scale = 255.0 if np.nanmax(rgb[..., :3]) > 1.0 else 1.0
    lum = rgb[..., :3] @ np.array([0.2126, 0.7152, 0.0722]) / scale
    if rgb.shape[2] == 4:                     # transparent pixels are background, not image
        lum = np.where(rgb[..., 3] > 0, lum, np.nan)
    if not np.isfinite(lum).any():
        return ""
    hi = np.unravel_index(np.nanargmax(lum), lum.shape)
    lo = np.unravel_index(np.nanargmin(lum), lum.shape)
    return (f", brightest {num(lum[hi])} at column {hi[1]}, row {hi[0]}, darkest "
            f"{num(lum[lo])} at column {lo[1]}, row {lo[0]}, mean brightness "
            f"{num(np.nanmean(lum))}")


def _collection(c) -> str:
    label = c.get_label()
    name = f" '{_clean(label)}'" if label and not label.startswith("_") else ""
    if isinstance(c, PathCollection):
        offsets = np.asarray(c.get_offsets(), dtype=float).reshape(-1, 2)
        if len(offsets) <= 4:
            pts = ", ".join(f"({num(a)}, {num(b)})" for a, b in offsets)
            return f"markers{name} at {pts}" if pts else ""
        return (f"{len(offsets)} markers{name}, x {num(offsets[:, 0].min())} to "
                f"{num(offsets[:, 0].max())}, y {num(offsets[:, 1].min())} to "
                f"{num(offsets[:, 1].max())}")
    if isinstance(c, QuadMesh):
        arr = np.asarray(c.get_array(), dtype=float)
        return f"a colour-mapped grid{name} of values {num(np.nanmin(arr))} to {num(np.nanmax(arr))}"
    faces = segments_3d(c)     # a 3-D collection has no 2-D paths until drawn
    n = len(faces) if faces is not None else len(c.get_paths())
    kind = "line segments" if isinstance(c, LineCollection) else "filled shapes"
    return f"{n} {kind}{name}" if n else ""


def _collections(ax) -> list[str]:
    said = [s for s in (_collection(c) for c in ax.collections if c.get_visible()) if s]
    if len(said) > MAX_ITEMS:
        said = said[:MAX_ITEMS] + [f"and {len(said) - MAX_ITEMS} more groups"]
    return ["Also drawn: " + "; ".join(said) + "."] if said else []


def _bars(ax) -> list[str]:
    out = []
    for bars in ax.containers:
        if not isinstance(bars, BarContainer):
            continue
        heights = [p.get_height() for p in bars.patches]
        label = bars.get_label()
        name = f" '{_clean(label)}'" if label and not label.startswith("_") else ""
        if len(heights) <= MAX_ITEMS * 2:
            out.append(f"Bars{name} of heights " + ", ".join(num(h) for h in heights) + ".")
        else:
            k = int(np.argmax(heights))
            left = bars.patches[k].get_x() + bars.patches[k].get_width() / 2
            out.append(f"{len(heights)} bars{name}, the tallest {num(heights[k])} "
                       f"at x = {num(left)}.")
    in_bars = {id(p) for b in ax.containers for p in getattr(b, "patches", [])}
    shapes = [p for p in ax.patches if id(p) not in in_bars and p.get_visible()]
    rects = [p for p in shapes if isinstance(p, Rectangle)]
    if shapes:
        out.append(f"{len(shapes)} shape{'s' if len(shapes) > 1 else ''}"
                   + (f", {len(rects)} of them rectangles." if rects else "."))
    return out


def _texts(ax) -> list[str]:
    texts = [_clean(t.get_text()) for t in ax.texts if t.get_visible() and t.get_text().strip()]
    if not texts:
        return []
    shown = texts[:MAX_ITEMS] + ([f"and {len(texts) - MAX_ITEMS} more"]
                                 if len(texts) > MAX_ITEMS else [])
    return ["Labels on the plot: " + "; ".join(shown) + "."]


def _legend(ax) -> list[str]:
    legend = ax.get_legend()
    if legend is None or not legend.get_visible():
        return []
    entries = [_clean(t.get_text()) for t in legend.get_texts() if t.get_text()]
    return ["Legend: " + "; ".join(entries) + "."] if entries else []
