"""A matplotlib renderer that records what it draws as a scene for the browser to paint.

The explorers' figures answer a slider within a frame or two when the browser, not
the kernel, turns their changing artists into pixels. :class:`SceneRenderer` is a matplotlib
renderer like Agg's, except that ``draw_path``, ``draw_markers`` and ``draw_image`` record
their geometry, already in display pixels, instead of rasterising it: matplotlib (and so
``course_lib``'s numbers behind every artist) still decides what is drawn and where, and a
``<canvas>`` in the page (:mod:`course_lib.widgets._canvas`) paints the recorded scene over the
figure's static background. Text is recorded as the outlines of its glyphs (matplotlib's
``TextToPath``, the way its PDF and SVG backends can), placed with Agg's own text metrics, so
labels sit where a full Agg draw puts them.

A scene is a list of items, one per primitive::

    {"k": "path", "v": vertices (n, 2) float32, "c": codes (n,) uint8,
     "fill": css colour | None, "stroke": css colour | None, "lw": px, "cap", "join",
     "dash": [offset, on, off, ...] | None, "hatch": {...} | None, "clip": index | None,
     "aa": False when matplotlib draws it without antialiasing (else absent)}
    {"k": "markers", "v", "c" (the marker, relative px), "at": offsets (m, 2) float32, ...}
    {"k": "paths", "v", "c" (every path, one after the other), "n": vertices per path,
     "fills", "strokes": css colours, cycled over the paths, "lw", "cap", "join", "clip"}
    {"k": "image", "m": affine [a, b, c, d, e, f] from image pixels (top row first) to
     display pixels, "rgba": (h, w, 4) uint8, or (h, w) for an opaque grey image,
     "smooth": bool, "clip"}

with clips (a rectangle and/or a path) kept once per frame in a table. Coordinates are
matplotlib's display coordinates: pixels from the figure's bottom-left corner.
:func:`pack` turns a scene into one ``bytes`` message (a JSON header, then every vertex as
float32, every path code as uint8, every image's RGBA bytes); :func:`unpack` reads it back, as
the browser does.
"""

from __future__ import annotations

import json
import struct

import numpy as np
from matplotlib.backend_bases import RendererBase
from matplotlib.path import Path
from matplotlib.transforms import Affine2D

from .._private_apis import cached_text_width, clip_gc, font_of, scalar_alpha, text_to_path

__all__ = ["SceneRenderer", "pack", "unpack"]

_CAPS = {"butt": "butt", "round": "round", "projecting": "square"}
_MAGIC = b"4F9S"


def _css(rgba, alpha=None) -> str | None:
    """A CSS colour for an RGBA tuple (``alpha`` replacing its alpha), ``None`` if invisible."""
    if rgba is None:
        return None
    r, g, b = (min(255, max(0, round(255 * float(v)))) for v in rgba[:3])
    a = float(rgba[3]) if len(rgba) > 3 and alpha is None else (1.0 if alpha is None else alpha)
    if a <= 0:
        return None
    return f"rgba({r},{g},{b},{a:.4g})"


def _css_list(colours, alpha=None) -> list:
    """:func:`_css` of every row of an ``(n, 4)`` RGBA array (a collection's colours), each
    distinct colour formatted once."""
    rgba = np.asarray(colours, dtype=float).reshape(-1, 4)
    if len(rgba) <= 2:
        return [_css(c, alpha) for c in rgba]
    unique, inverse = np.unique(rgba, axis=0, return_inverse=True)
    names = [_css(c, alpha) for c in unique]
    return [names[i] for i in inverse.ravel()]


def _codes(path, n: int) -> np.ndarray:
    """A path's ``n`` codes (uint8), filled in (MOVETO, then LINETO) for a plain polyline."""
    if path.codes is not None:
        return np.asarray(path.codes, dtype=np.uint8)
    c = np.full(n, Path.LINETO, dtype=np.uint8)
    c[:1] = Path.MOVETO
    return c


def _geometry(path) -> tuple[np.ndarray, np.ndarray]:
    """A path's vertices (float32) and codes (uint8), STOP codes left out."""
    v = np.asarray(path.vertices, dtype=np.float32).reshape(-1, 2)
    c = _codes(path, len(v))
    keep = c != Path.STOP
    return v[keep], c[keep]


def _joined_geometry(paths) -> tuple[np.ndarray, np.ndarray, list]:
    """Every path's vertices (float64) and codes (uint8) one after the other, as
    :func:`_geometry` gives them path by path, and each path's number of vertices."""
    verts = [np.asarray(p.vertices, dtype=np.float64).reshape(-1, 2) for p in paths]
    v = np.concatenate(verts)
    c = np.concatenate([_codes(p, len(x)) for p, x in zip(paths, verts)])
    keep = c != Path.STOP
    if keep.all():
        return v, c, [len(x) for x in verts]
    owner = np.repeat(np.arange(len(verts)), [len(x) for x in verts])
    return v[keep], c[keep], np.bincount(owner[keep], minlength=len(verts)).tolist()


class SceneRenderer(RendererBase):
    """Records the primitives matplotlib artists draw (see the module docstring).

    Parameters
    ----------
    metrics : matplotlib.backends.backend_agg.RendererAgg
        The Agg renderer of the same figure: its size, dpi and text metrics are used, so that
        text is laid out exactly as a full Agg draw lays it out.

    Notes
    -----
    ``items`` is the list the next primitives are appended to; the caller may swap it (one list
    per artist) to keep an unchanged artist's items for the next frame. ``clips`` is the table
    of clip regions the items point into; keep the renderer (and so the table) as long as such
    kept items are reused.
    """

    def __init__(self, metrics):
        super().__init__()
        self._metrics = metrics
        self.width, self.height, self.dpi = metrics.width, metrics.height, metrics.dpi
        self.items: list[dict] = []
        self.clips: list[dict] = []
        self._clip_index: dict = {}
        self._glyphs: dict = {}          # glyph -> (vertices, codes), read from the font once
        self._outlines: dict = {}        # (text, font, features) -> Path, least recent first
        self._smooth = True              # whether the browser smooths the next image it scales

    # -- what artists ask a renderer ------------------------------------------------------------
    def get_canvas_width_height(self):
        return self.width, self.height

    def points_to_pixels(self, points):
        return points * self.dpi / 72.0

    def get_text_width_height_descent(self, s, prop, ismath):
        return self._metrics.get_text_width_height_descent(s, prop, ismath)

    def option_image_nocomposite(self):
        return True  # one item per image: the browser composites them

    def draw_text(self, gc, x, y, s, prop, angle, ismath=False, mtext=None):
        """Text as filled glyph outlines (matplotlib's ``TextToPath``), placed where Agg
        places it. Outlines of plain text come from :meth:`_outline`'s caches.

        ``TextToPath`` lays glyphs out without hinting, Agg with it, so a long label would end
        a few pixels away from where Agg (and the text's own extent, and a box drawn around
        it) ends it: the run of glyphs is stretched along its baseline to Agg's width."""
        if ismath:
            self._draw_text_as_path(gc, x, y, s, prop, angle, ismath, mtext)
            return
        path, width = self._outline(s, prop, mtext)
        if path is None:
            return
        scale = self.points_to_pixels(prop.get_size_in_points()) / text_to_path(self).FONT_SCALE
        stretch = 1.0
        agg_width = self._agg_width(s, prop)
        if width > 0 and agg_width > 0:
            stretch = min(1.25, max(0.8, agg_width / (width * scale)))
        # like _draw_text_as_path: with flipy(), Text.draw handed us y from the top
        transform = (Affine2D().scale(scale * stretch, scale).rotate_deg(angle)
                     .translate(x, self.height - y))
        gc.set_linewidth(0.0)
        self.draw_path(gc, path, transform, rgbFace=gc.get_rgb())

    def _agg_width(self, s, prop) -> float:
        """The width (pixels) Agg gives ``s``: from the cache that ``Text`` layout filled."""
        width = cached_text_width(self, s, prop, self.dpi)
        if width is not None:
            return width
        return float(self.get_text_width_height_descent(s, prop, False)[0])

    def _outline(self, s, prop, mtext):
        """The glyph outlines of ``s`` in ``prop`` (at ``TextToPath.FONT_SCALE``; ``None`` for
        blank text) and their unhinted advance width in the same units. Matplotlib's
        ``get_text_path`` reads every glyph from the font again on each call and joins them
        vertex by vertex; here glyphs are read once per renderer and whole strings are kept
        (the last 1024), which makes a changed label cheap."""
        extra = {}
        if mtext is not None and hasattr(mtext, "get_fontfeatures"):
            extra = {"features": mtext.get_fontfeatures(), "language": mtext.get_language()}
        key = (s, hash(prop), repr(sorted(extra.items())))
        entry = self._outlines.pop(key, None)
        if entry is None:
            text2path = text_to_path(self)
            font = font_of(text2path, prop)
            glyphs, new, _ = text2path.get_glyphs_with_font(
                font, s, glyph_map=self._glyphs, return_new_glyphs_only=True, **extra)
            self._glyphs.update(new)
            verts, codes = [], []
            for glyph, x, y, scale in glyphs:
                v, c = self._glyphs[glyph]
                if len(v):
                    verts.append(np.asarray(v) * scale + (x, y))
                    codes.append(np.asarray(c))
            path = Path(np.concatenate(verts), np.concatenate(codes)) if verts else None
            width = text2path.get_text_width_height_descent(s, prop, False)[0]
            entry = (path, width * text2path.FONT_SCALE / prop.get_size_in_points())
            if len(self._outlines) >= 1024:
                self._outlines.pop(next(iter(self._outlines)))
        self._outlines[key] = entry
        return entry

    # -- the primitives ---------------------------------------------------------------------------
    def _clip(self, gc) -> int | None:
        """The index of ``gc``'s clip region in :attr:`clips` (added when new), or ``None``.
        Regions are keyed by content, so an index stays valid while the table lives."""
        rect = gc.get_clip_rectangle()
        tpath, affine = gc.get_clip_path()
        if rect is None and tpath is None:
            return None
        clip = {"rect": None if rect is None else [round(float(b), 3) for b in rect.bounds]}
        key = (tuple(clip["rect"] or ()),)
        if tpath is not None:
            clip["v"], clip["c"] = _geometry(tpath.cleaned(transform=affine, curves=True))
            key += (clip["v"].tobytes(), clip["c"].tobytes())
        if key not in self._clip_index:
            self._clip_index[key] = len(self.clips)
            self.clips.append(clip)
        return self._clip_index[key]

    def _style(self, gc, rgbFace, filled_only=False) -> dict:
        forced = gc.get_forced_alpha()
        alpha = gc.get_alpha() if forced else None
        lw = 0.0 if filled_only else float(self.points_to_pixels(gc.get_linewidth()))
        style = {"fill": _css(rgbFace, alpha) if rgbFace is not None else None,
                 "stroke": _css(gc.get_rgb()) if lw > 0 else None,
                 "lw": lw, "cap": _CAPS.get(gc.get_capstyle(), "butt"),
                 "join": gc.get_joinstyle() or "miter", "dash": None, "hatch": None,
                 "aa": None if gc.get_antialiased() else False, "clip": self._clip(gc)}
        offset, dashes = gc.get_dashes()
        if dashes is not None and len(dashes) and style["stroke"] is not None:
            style["dash"] = [float(self.points_to_pixels(offset or 0))] + \
                [float(self.points_to_pixels(d)) for d in dashes]
        if gc.get_hatch() is not None:
            size = float(self.points_to_pixels(72))   # Agg: one hatch tile per inch
            unit = gc.get_hatch_path()
            hv, hc = _geometry(unit.cleaned(curves=True))
            lw_hatch = (gc.get_hatch_linewidth() if hasattr(gc, "get_hatch_linewidth")
                        else 1.0)
            style["hatch"] = {"v": hv * size, "c": hc, "size": size,
                              "color": _css(gc.get_hatch_color()),
                              "lw": float(self.points_to_pixels(lw_hatch))}
        return style

    def draw_path(self, gc, path, transform, rgbFace=None):
        lw = float(self.points_to_pixels(gc.get_linewidth()))
        filled = rgbFace is not None or gc.get_hatch() is not None
        margin = lw + 2
        clip = None if filled else (-margin, -margin, self.width + margin, self.height + margin)
        # cleaned (clipped, simplified, snapped to pixel centres) in Agg's y-down pixels, as
        # Agg does it: snapping rounds, so doing it in y-up pixels moves a line by one row
        down = Affine2D().scale(1.0, -1.0).translate(0.0, self.height)
        clean = path.cleaned(transform=transform + down, remove_nans=True, clip=clip,
                             simplify=path.should_simplify and not filled, curves=True,
                             stroke_width=lw, snap=gc.get_snap())
        v, c = _geometry(clean)
        if not len(v):
            return
        v[:, 1] = self.height - v[:, 1]
        style = self._style(gc, rgbFace)
        if style["fill"] is None and style["stroke"] is None and style["hatch"] is None:
            return
        self.items.append({"k": "path", "v": v, "c": c, **style})

    def draw_markers(self, gc, marker_path, marker_trans, path, trans, rgbFace=None):
        at = trans.transform(np.asarray(path.vertices, dtype=float).reshape(-1, 2))
        if path.codes is not None:  # control points of curves carry no marker
            codes = np.asarray(path.codes)
            at = at[(codes == Path.MOVETO) | (codes == Path.LINETO)]
        at = at[np.isfinite(at).all(axis=1)]
        inside = ((at[:, 0] > -50) & (at[:, 0] < self.width + 50)
                  & (at[:, 1] > -50) & (at[:, 1] < self.height + 50))
        at = at[inside]
        if not len(at):
            return
        lw = float(self.points_to_pixels(gc.get_linewidth()))
        v, c = _geometry(marker_path.cleaned(transform=marker_trans, curves=True,
                                             stroke_width=lw, snap=False))
        style = self._style(gc, rgbFace)
        if style["fill"] is None and style["stroke"] is None:
            return
        self.items.append({"k": "markers", "v": v, "c": c,
                           "at": np.asarray(at, dtype=np.float32), **style})

    def draw_image(self, gc, x, y, im, transform=None):
        """An RGBA image with its bottom-left corner at ``(x, y)`` (resampled by matplotlib to
        display pixels), or, with ``transform``, at its own resolution: ``transform`` maps the
        unit square to display pixels relative to ``(x, y)``, as in matplotlib's vector
        backends, and the browser scales it (see :meth:`draw_axes_image`)."""
        rgba = np.asarray(im, dtype=np.uint8)
        if rgba.ndim != 3 or rgba.shape[2] != 4 or 0 in rgba.shape:
            return
        alpha = gc.get_alpha()
        if alpha is not None and alpha < 1:
            rgba = rgba.copy()
            rgba[..., 3] = (rgba[..., 3] * alpha).astype(np.uint8)
        h, w = rgba.shape[:2]
        if transform is None:
            # the rows come bottom first: pixel (u, v) of the flipped image is at x + u, y + h - v
            matrix = Affine2D().scale(1, -1).translate(x, y + h)
            rgba = rgba[::-1]
        else:  # image row v (top first in the browser) is unit-square height v / h
            matrix = Affine2D().scale(1 / w, 1 / h) + transform + Affine2D().translate(x, y)
        if (rgba[..., 3] == 255).all() and (rgba[..., 0] == rgba[..., 1]).all() \
                and (rgba[..., 1] == rgba[..., 2]).all():
            rgba = rgba[..., 0]  # opaque grey (a B-scan): a quarter of the bytes to send
        self.items.append({"k": "image", "m": [float(v) for v in matrix.get_affine().to_values()],
                           "rgba": np.ascontiguousarray(rgba), "smooth": self._smooth,
                           "clip": self._clip(gc)})

    def draw_axes_image(self, image) -> None:
        """Record an ``AxesImage`` at the resolution of its data, for the browser to scale.

        ``AxesImage.draw`` resamples the data to display pixels in the kernel (milliseconds,
        and the frame then carries every display pixel) unless its interpolation is
        ``"none"``. This does what that draw does for ``"none"`` whatever the interpolation:
        the browser scales the image, smoothly (bilinear) unless the interpolation is
        ``"nearest"``/``"none"``, or matplotlib's default ``"auto"`` would pick nearest
        (upsampling by 3 or more)."""
        if not image.get_visible() or image.get_array() is None or image.get_array().size == 0:
            image.stale = False
            return
        if not image.get_transform().is_affine:
            image.draw(self)
            return
        gc = self.new_gc()
        clip_gc(image, gc)
        gc.set_alpha(scalar_alpha(image))
        im, l, b, trans = image.make_image(self, unsampled=True)
        if im is not None:
            trans = Affine2D().scale(im.shape[1], im.shape[0]) + trans
            interpolation = image.get_interpolation()
            if interpolation in ("antialiased", "auto"):
                corners = trans.transform([[0, 0], [1, 1]])
                zoom = np.min(np.abs(corners[1] - corners[0]) / im.shape[1::-1])
                interpolation = "nearest" if zoom >= 3 else "bilinear"
            self._smooth = interpolation not in ("nearest", "none")
            try:
                self.draw_image(gc, l, b, im, trans)
            finally:
                self._smooth = True
        gc.restore()
        image.stale = False

    def draw_path_collection(self, gc, master_transform, paths, all_transforms, offsets,
                             offset_trans, facecolors, edgecolors, linewidths, linestyles,
                             antialiaseds, urls, offset_position, **kwargs):
        """A collection as one ``"paths"`` item (all outlines transformed at once, a colour per
        path) when its paths share one transform, offset, width and solid line style (the
        collimator's hundreds of holes); otherwise one ``draw_path`` per path, as matplotlib's
        base renderer does."""
        offsets = np.asarray(offsets, dtype=float).reshape(-1, 2)
        v = None
        if (len(paths) > 0 and len(all_transforms) == 0 and len(offsets) <= 1
                and len(linewidths) <= 1 and all(d is None for _, d in linestyles)
                and gc.get_hatch() is None):
            transform = master_transform
            if len(offsets):
                xo, yo = offset_trans.transform(offsets[0])
                transform = master_transform + Affine2D().translate(xo, yo)
            v, c, counts = _joined_geometry(paths)
            v = np.asarray(transform.transform(v), dtype=np.float32)
        if v is None or not np.isfinite(v).all():
            super().draw_path_collection(gc, master_transform, paths, all_transforms, offsets,
                                         offset_trans, facecolors, edgecolors, linewidths,
                                         linestyles, antialiaseds, urls, offset_position,
                                         **kwargs)
            return
        lw = float(self.points_to_pixels(linewidths[0] if len(linewidths) else
                                         gc.get_linewidth()))
        forced = gc.get_alpha() if gc.get_forced_alpha() else None
        fills = _css_list(facecolors, forced)
        strokes = _css_list(edgecolors, forced) if lw > 0 else []
        if not any(fills) and not any(strokes):
            return
        self.items.append({"k": "paths", "v": v, "c": c, "n": counts, "fills": fills,
                           "strokes": strokes, "lw": lw,
                           "aa": None if not len(antialiaseds) or any(antialiaseds) else False,
                           "cap": _CAPS.get(gc.get_capstyle(), "butt"),
                           "join": gc.get_joinstyle() or "miter", "clip": self._clip(gc)})

    def draw_gouraud_triangles(self, gc, triangles_array, colors_array, transform):
        raise NotImplementedError("the explorers draw no Gouraud-shaded triangles")


# -- one scene as one message ---------------------------------------------------------------------

_ARRAYS = ("v", "c", "at", "rgba", "hatch")


def _static_json(item: dict) -> str:
    """An item's header fields that are not arrays, as JSON without its closing brace; kept in
    the item (``"_json"``), since an unchanged artist's items are packed again every frame."""
    text = item.get("_json")
    if text is None:
        fields = {k: v for k, v in item.items()
                  if k not in _ARRAYS and not k.startswith("_") and v is not None}
        if item.get("hatch") is not None:
            fields["hatch"] = {k: v for k, v in item["hatch"].items() if k not in ("v", "c")}
        if "rgba" in item:
            fields["h"], fields["w"] = item["rgba"].shape[:2]
            fields["gray"] = item["rgba"].ndim == 2
        text = item["_json"] = json.dumps(fields, separators=(",", ":"))[:-1]
    return text


def pack(items: list[dict], clips: list[dict], height: float) -> bytes:
    """One message: ``b"4F9S"``, the header's length (uint32, little-endian), the JSON header,
    padding to 4 bytes, every vertex (float32 x, y), every code (uint8, padded to 4 bytes), and
    every image's bytes (RGBA, or one grey byte per pixel when ``"gray"``). Arrays in the header
    become ``[start, count]`` into those blocks (a hatch's as ``"hv"``), an image's bytes an
    offset ``"o"``."""
    verts, codes, images = [], [], []
    n_verts = n_image_bytes = 0

    def geometry(v, c):
        nonlocal n_verts
        verts.append(v)
        codes.append(c)
        n_verts += len(v)
        return f"[{n_verts - len(v)},{len(v)}]"

    parts = []
    for item in items:
        text = [_static_json(item)]
        if "v" in item:
            text.append(f',"v":{geometry(item["v"], item["c"])}')
        if "at" in item:
            at = item["at"]
            text.append(f',"at":{geometry(at, np.zeros(len(at), dtype=np.uint8))}')
        if item.get("hatch") is not None:
            text.append(f',"hv":{geometry(item["hatch"]["v"], item["hatch"]["c"])}')
        if "rgba" in item:
            text.append(f',"o":{n_image_bytes}')
            images.append(item["rgba"])
            n_image_bytes += item["rgba"].nbytes
        parts.append("".join(text) + "}")
    header_clips = []
    for clip in clips:
        out = {"rect": clip["rect"]}
        if "v" in clip:
            start = n_verts
            geometry(clip["v"], clip["c"])
            out["v"] = [start, len(clip["v"])]
        header_clips.append(out)
    header = (f'{{"height":{float(height)!r},"nv":{n_verts},"items":[{",".join(parts)}],'
              f'"clips":{json.dumps(header_clips, separators=(",", ":"))}}}').encode()
    header += b" " * (-(len(_MAGIC) + 4 + len(header)) % 4)
    v = np.concatenate(verts).astype("<f4", copy=False) if verts else np.zeros((0, 2), "<f4")
    c = np.concatenate(codes) if codes else np.zeros(0, np.uint8)
    c_bytes = c.tobytes() + b"\0" * (-len(c) % 4)
    return b"".join([_MAGIC, struct.pack("<I", len(header)), header, v.tobytes(), c_bytes,
                     *(im.tobytes() for im in images)])


def unpack(message: bytes) -> dict:
    """Read a :func:`pack` message back: the header with every ``[start, count]`` replaced by
    the arrays it points to (the reading the browser does, for the tests). A damaged or
    truncated message raises ``ValueError``."""
    message = bytes(message)
    try:
        if message[:4] != _MAGIC:
            raise ValueError("it does not start with b'4F9S'")
        (n,) = struct.unpack_from("<I", message, 4)
        header = json.loads(message[8:8 + n])
        nv = int(header["nv"])
        offset = 8 + n
        verts = np.frombuffer(message, "<f4", 2 * nv, offset).reshape(nv, 2)
        codes = np.frombuffer(message, np.uint8, nv, offset + 8 * nv)
        _resolve(header, verts, codes, message, offset + 8 * nv + nv + (-nv % 4))
    except (ValueError, struct.error, KeyError, TypeError, IndexError) as exc:
        raise ValueError(f"message: not a whole scene ({exc})") from None
    return header


def _resolve(header: dict, verts, codes, message: bytes, images: int) -> None:
    """Replace the header's references by the arrays of the message (images at ``images``)."""

    def arrays(ref):
        start, count = ref
        if start < 0 or count < 0 or start + count > len(verts):
            raise ValueError(f"a reference [{start}, {count}] beyond {len(verts)} vertices")
        return verts[start:start + count], codes[start:start + count]

    for item in header["items"]:
        if "v" in item:
            item["v"], item["c"] = arrays(item["v"])
        if "at" in item:
            item["at"] = arrays(item["at"])[0]
        if "hv" in item:
            item["hatch"]["v"], item["hatch"]["c"] = arrays(item.pop("hv"))
        if "o" in item:
            shape = (item["h"], item["w"]) if item["gray"] else (item["h"], item["w"], 4)
            item["rgba"] = np.frombuffer(message, np.uint8, int(np.prod(shape)),
                                         images + item["o"]).reshape(shape)
    for clip in header["clips"]:
        if "v" in clip:
            clip["v"], clip["c"] = arrays(clip["v"])
