"""The one HTML helper of the outputs: escaping, the page shell, values as text, plots.

Values are summarised, never dumped: an array shows its shape, dtype and a few entries, and a
plot draws at most :data:`PLOT_POINTS` points per line, so a page stays small whatever a
submission returned.
"""

from __future__ import annotations

import html

import numpy as np

from ..model import ValueSummary

#: Points drawn per line of a plot.
PLOT_POINTS = 400
#: Characters of a value's text.
VALUE_CHARS = 2000
#: Numeric arrays of more entries than this, or of 3 or more dimensions (a volume), are shown
#: by shape, dtype, first entries and range: a 7 x 7 x 7 volume would fill the page.
ARRAY_ENTRIES = 120
#: First entries shown of such an array.
ARRAY_HEAD = 6

BASE_STYLE = """
body{font-family:system-ui,-apple-system,Segoe UI,sans-serif;max-width:1000px;margin:2em auto;
padding:0 1em;color:#222;line-height:1.45}h1{font-size:1.5em;margin-bottom:.2em}
h2{font-size:1.15em;margin:1.6em 0 .3em}table{border-collapse:collapse;width:100%;
margin:.4em 0;font-size:.9em}td,th{border:1px solid #ddd;padding:.3em .5em;vertical-align:top;
text-align:left}th{background:#f5f5f5}pre{margin:0;white-space:pre-wrap;word-break:break-word;
font-size:.9em}.note{color:#555;font-size:.9em}
"""


def e(text) -> str:
    """``text`` escaped for HTML (quotes included)."""
    return html.escape(str(text), quote=True)


def e_clipped(text, limit: int) -> str:
    """``text`` escaped for HTML, then cut to at most ``limit`` characters (never inside an
    entity, an ellipsis added when cut): escaping can multiply a text's length six-fold, so a
    page is budgeted by what it holds, not by what the student wrote."""
    escaped = e(str(text)[:limit])
    if len(escaped) <= limit:
        return escaped
    cut = escaped[:limit]
    amp = cut.rfind("&")
    if amp > cut.rfind(";"):
        cut = cut[:amp]
    return cut + "…"


def write_page(path, text: str) -> None:
    """Write ``text`` as UTF-8; a character UTF-8 cannot hold (a lone surrogate) becomes ``?``."""
    with open(path, "w", encoding="utf-8", errors="replace") as f:
        f.write(text)


def page(title: str, body: list[str], style: str = "") -> str:
    """A complete, self-contained HTML page."""
    head = (f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>{e(title)}"
            f"</title><style>{BASE_STYLE}{style}</style></head><body>")
    return "\n".join([head, *body, "</body></html>"])


def _array_summary(v: np.ndarray) -> str:
    """A large numeric array by its shape, dtype, first entries and range."""
    head = np.array2string(v.reshape(-1)[:ARRAY_HEAD], precision=6, separator=", ")
    finite = v[np.isfinite(v)] if v.dtype.kind == "f" else v.astype(float)
    if not finite.size:
        return f"array of shape {v.shape}, dtype {v.dtype}; first entries {head} …"
    low, high = (f"{float(x):.6g}" for x in (finite.min(), finite.max()))
    return f"array of shape {v.shape}, dtype {v.dtype}; first entries {head} …; from {low} to {high}"


def value_text(v) -> str:
    """A plain value as short text: arrays by a few entries (and their shape), floats to 8
    significant digits, summaries of big arrays by shape, dtype and first entries."""
    if isinstance(v, ValueSummary):
        head = np.array2string(np.asarray(v.head).reshape(-1)[:8], precision=6, separator=", ")
        return f"array of shape {v.shape}, dtype {v.dtype}; first entries {head} …"
    if (isinstance(v, np.ndarray) and v.dtype.kind in "biuf"
            and (v.size > ARRAY_ENTRIES or (v.ndim >= 3 and v.size > ARRAY_HEAD))):
        return _array_summary(v)
    if isinstance(v, np.ndarray):
        text = np.array2string(v, precision=6, threshold=60, edgeitems=4, max_line_width=70)
        return text if v.ndim <= 1 and v.size <= 60 else f"{text}\n(shape {v.shape})"
    if isinstance(v, float):
        return f"{v:.8g}"
    if isinstance(v, (tuple, list)):
        inner = ", ".join(value_text(x) for x in v[:20]) + (", …" if len(v) > 20 else "")
        return f"({inner}{',' if len(v) == 1 else ''})" if isinstance(v, tuple) else f"[{inner}]"
    text = repr(v)
    return text if len(text) <= VALUE_CHARS else text[:VALUE_CHARS] + "…"


def plot_data(v):
    """The array a plot may use: a summary's first rows, an array itself, else None."""
    if isinstance(v, ValueSummary):
        return np.asarray(v.head)
    return v


def svg_lines(expected_lines: list, received_lines: list, closed: bool, label: str,
              what: str) -> str:
    """An inline SVG of expected (blue) and received (red, dashed) lines, each capped in points."""
    lines = [np.asarray(p, float)[:: max(1, len(p) // PLOT_POINTS)]
             for p in expected_lines + received_lines if len(p)]
    if not lines:
        return ""
    xy = np.vstack(lines)
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    if not len(xy):
        return ""
    lo, span = xy.min(axis=0), max(float(np.max(xy.max(axis=0) - xy.min(axis=0))), 1e-9)
    size, pad = 320.0, 14.0

    def path(pts, style):
        pts = np.asarray(pts, float)[:: max(1, len(pts) // PLOT_POINTS)]
        pts = pts[np.all(np.isfinite(pts), axis=1)]
        if len(pts) < 2:
            return ""
        q = (pts - lo) / span * (size - 2 * pad) + pad
        d = " ".join(f"{a:.1f},{size - b:.1f}" for a, b in q[:, :2])
        return f"<{'polygon' if closed else 'polyline'} points='{d}' fill='none' {style}/>"

    blue = "stroke='#1565c0' stroke-width='2.2'"
    red = "stroke='#c62828' stroke-width='1.6' stroke-dasharray='5,3'"
    body = "".join(path(p, blue) for p in expected_lines) + \
        "".join(path(p, red) for p in received_lines)
    return (f"<div><svg width='{size:.0f}' height='{size:.0f}' viewBox='0 0 {size:.0f} "
            f"{size:.0f}' role='img' aria-label='expected and received {what}'>{body}</svg>"
            f"<div class='legend note'><span style='color:#1565c0'>━ expected</span> "
            f"<span style='color:#c62828'>╍ your answer</span> {e(label)}: {what}</div></div>")
