"""A small scanline rasteriser with the top-left fill rule (Q6(c), going further).

The pixels a triangle covers (:func:`rasterize_triangle`) and its one run of pixels per
scanline (:func:`triangle_spans`): the single span per line that Q6(c) decomposes polygons
into triangles for. The public names are imported from :mod:`course_lib.clipping`, which
re-exports them.
"""

from __future__ import annotations

import numpy as np

from ._validate import as_int, as_points

__all__ = ["rasterize_triangle", "triangle_spans"]


def _cross(o, a, b):
    """z-component of ``(a - o) x (b - o)``, broadcasting over leading axes."""
    return (a[..., 0] - o[..., 0]) * (b[..., 1] - o[..., 1]) - \
        (a[..., 1] - o[..., 1]) * (b[..., 0] - o[..., 0])


def rasterize_triangle(tri_xy, width, height) -> np.ndarray:
    """Pixels covered by a triangle, with the top-left fill rule (Q6(c), further).

    Parameters
    ----------
    tri_xy : array_like, shape (3, 2)
        Vertices in pixel coordinates: ``x`` to the right, ``y`` *down* (row index), pixel
        ``(row, col)`` having its centre at ``(col + 0.5, row + 0.5)``.
    width, height : int
        Size of the raster, at least 1.

    Returns
    -------
    mask : ndarray of bool, shape (height, width)
        True for the pixels whose centre the triangle covers.

    Notes
    -----
    A pixel centre ``p`` is inside when the three edge functions
    ``E_ab(p) = (b - a) x (p - a)`` (vertices ordered to give a positive area) are all
    positive. A centre exactly on an edge is given to the triangle only when the edge is a
    *top* edge (horizontal, with the triangle below it) or a *left* edge (going up the screen
    in this ordering), as in Direct3D and OpenGL. With that rule two triangles that share an
    edge never both draw, nor both miss, a pixel centre on it: every pixel of a mesh is drawn
    exactly once. Degenerate (zero-area) triangles cover nothing. Each row of the result is a
    single run of pixels (:func:`triangle_spans`), because a triangle is convex.
    """
    tri = as_points(tri_xy, 2, "tri_xy")
    if tri.shape[0] != 3:
        raise ValueError(f"tri_xy must have shape (3, 2), got shape {tri.shape}")
    width = as_int(width, "width", minimum=1)
    height = as_int(height, "height", minimum=1)
    mask = np.zeros((height, width), dtype=bool)
    area2 = _cross(tri[0], tri[1], tri[2])
    if area2 == 0:
        return mask
    if area2 < 0:
        tri = tri[[0, 2, 1]]
    # Only the bounding box needs testing.
    c0 = max(int(np.floor(tri[:, 0].min() - 0.5)), 0)
    c1 = min(int(np.ceil(tri[:, 0].max() - 0.5)), width - 1)
    r0 = max(int(np.floor(tri[:, 1].min() - 0.5)), 0)
    r1 = min(int(np.ceil(tri[:, 1].max() - 0.5)), height - 1)
    if c0 > c1 or r0 > r1:
        return mask
    px = np.arange(c0, c1 + 1) + 0.5
    py = np.arange(r0, r1 + 1)[:, None] + 0.5
    inside = np.ones((r1 - r0 + 1, c1 - c0 + 1), dtype=bool)
    for i in range(3):
        a, b = tri[i], tri[(i + 1) % 3]
        dx, dy = b[0] - a[0], b[1] - a[1]
        e = dx * (py - a[1]) - dy * (px - a[0])
        top_left = (dy == 0 and dx > 0) or dy < 0
        inside &= (e >= 0) if top_left else (e > 0)
    mask[r0:r1 + 1, c0:c1 + 1] = inside
    return mask


def triangle_spans(tri_xy, width, height) -> np.ndarray:
    """The pixel runs of a rasterised triangle, one per scanline (Q6(c), further).

    Parameters
    ----------
    tri_xy : array_like, shape (3, 2)
        Vertices in pixel coordinates (``y`` down), as for :func:`rasterize_triangle`.
    width, height : int

    Returns
    -------
    spans : ndarray of int, shape (k, 3)
        Rows ``(row, first_col, last_col)`` (inclusive), one per scanline the triangle covers,
        in increasing ``row``.

    Notes
    -----
    Built from :func:`rasterize_triangle`. That each covered row is a single run of pixels is
    the property Q6(c) relies on (a triangle is convex); it is asserted as the spans are read.
    """
    mask = rasterize_triangle(tri_xy, width, height)
    rows = np.flatnonzero(mask.any(axis=1))
    spans = np.empty((len(rows), 3), dtype=np.intp)
    for k, r in enumerate(rows):
        cols = np.flatnonzero(mask[r])
        spans[k] = r, cols[0], cols[-1]
        assert cols[-1] - cols[0] + 1 == len(cols), "a triangle row must be one run"
    return spans
