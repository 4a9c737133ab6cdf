"""2-D polygons in screen space: area, convexity, ear clipping, spans (Q6(b)(ii), Q6(c)).

What happens to a polygon once it is clipped and divided by ``w``: its signed area (the
shoelace sum that :func:`course_lib.clipping.screen_area` grades), whether it is convex, its
triangulation when it is not (:func:`ear_clip`), and its spans on a scanline when it is not a
triangle (:func:`polygon_spans`).

Instructors only: the shoelace sum is :func:`course_lib.clipping.screen_area`'s answer and a
triangle's span is :func:`course_lib.clipping.scanline_span`'s, so the students' wheel does not
carry this module (``INSTRUCTORS_ONLY`` in :mod:`autograder.student_bundle`); the notebook's
fixed examples of it (the comb, the star) come from :mod:`course_lib.clip_results`.
"""

from __future__ import annotations

import numpy as np

from ._raster import _cross
from .clipping import shoelace_area
from ._validate import as_points, as_scalar

__all__ = ["ear_clip", "is_convex", "polygon_area", "polygon_spans", "shoelace_area"]


def _polygon2(poly_xy, name="poly_xy", min_count=3) -> np.ndarray:
    return as_points(poly_xy, 2, name, min_count=min_count)


def polygon_area(poly_xy) -> float:
    """Signed (shoelace) area of a 2-D polygon: positive when anticlockwise.

    Parameters
    ----------
    poly_xy : array_like, shape (n, 2), n >= 3

    Returns
    -------
    float
    """
    p = _polygon2(poly_xy)
    return shoelace_area(p[:, 0], p[:, 1])


def is_convex(poly_xy) -> bool:
    """True when a 2-D polygon is convex (all turns the same way, collinear turns allowed).

    Parameters
    ----------
    poly_xy : array_like, shape (n, 2), n >= 3

    Returns
    -------
    bool

    Notes
    -----
    Checks the sign of every turn and that the boundary winds around exactly once (the turning
    angles add up to +-2 pi), which rules out self-intersecting "stars" whose turns all agree.
    """
    p = _polygon2(poly_xy)
    prev, nxt = np.roll(p, 1, axis=0), np.roll(p, -1, axis=0)
    turn = _cross(prev, p, nxt)
    scale = np.max(np.abs(p - p.mean(axis=0))) ** 2
    turn = np.where(np.abs(turn) <= 1e-12 * scale, 0.0, turn)
    if np.any(turn > 0) and np.any(turn < 0):
        return False
    e = nxt - p
    ang = np.arctan2(e[:, 1], e[:, 0])
    dtheta = np.angle(np.exp(1j * (np.roll(ang, -1) - ang)))
    return bool(abs(abs(dtheta.sum()) - 2 * np.pi) < 1e-6)


def ear_clip(poly_xy) -> np.ndarray:
    """Triangulate a simple (possibly non-convex) 2-D polygon by ear clipping (Q6(c), further).

    Parameters
    ----------
    poly_xy : array_like, shape (n, 2), n >= 3
        Vertices of a simple polygon (no self-intersections, no holes), either orientation.

    Returns
    -------
    triangles : ndarray of int, shape (n - 2, 3)
        Indices into ``poly_xy``; each triangle has the polygon's orientation and together they
        cover it exactly once, so their areas sum to the polygon's area.

    Raises
    ------
    ValueError
        If ``poly_xy`` is not ``(n, 2)`` with ``n >= 3``, or has zero area.

    Notes
    -----
    Every simple polygon with more than three vertices has at least two *ears* (Meisters' two
    ears theorem): convex vertices whose triangle with their two neighbours contains no other
    vertex. Cutting an ear off leaves a simple polygon with one vertex fewer, so ``n - 2``
    cuts triangulate it, in ``O(n^2)`` tests at most per cut here (each vectorised over the
    remaining vertices). A vertex whose neighbours are collinear with it is cut as a
    zero-area triangle when no proper ear is left, which keeps the count at ``n - 2``.
    """
    p = _polygon2(poly_xy)
    n = len(p)
    area = polygon_area(p)
    scale = np.max(np.abs(p - p.mean(axis=0))) ** 2
    if abs(area) <= 1e-14 * max(scale, np.finfo(float).tiny):
        raise ValueError("poly_xy has zero area, so it cannot be triangulated")
    sign = 1.0 if area > 0 else -1.0
    tol = 1e-12 * scale
    idx = list(range(n))
    tris = []
    while len(idx) > 3:
        m = len(idx)
        q = p[idx]
        prev, nxt = np.roll(q, 1, axis=0), np.roll(q, -1, axis=0)
        turn = sign * _cross(prev, q, nxt)
        cut = None
        for k in np.flatnonzero(turn > tol):
            a, b, c = q[k - 1], q[k], q[(k + 1) % m]
            others = np.delete(np.arange(m), [(k - 1) % m, k, (k + 1) % m])
            r = q[others]
            # Any other vertex inside or on the candidate triangle blocks the ear (vertices that
            # coincide with a, b or c are ignored: they touch the ear only at a corner).
            dup = (np.all(r == a, axis=1) | np.all(r == b, axis=1) | np.all(r == c, axis=1))
            r = r[~dup]
            ab = sign * _cross(a, b, r)
            bc = sign * _cross(b, c, r)
            ca = sign * _cross(c, a, r)
            if not np.any((ab >= -tol) & (bc >= -tol) & (ca >= -tol)):
                cut = k
                break
        if cut is None:
            # Only (numerically) collinear or reflex vertices remain: drop the flattest one.
            cut = int(np.argmin(np.abs(turn)))
        tris.append((idx[cut - 1], idx[cut], idx[(cut + 1) % m]))
        del idx[cut]
    tris.append(tuple(idx))
    return np.array(tris, dtype=np.intp)


def polygon_spans(poly_xy, y) -> list[tuple[float, float]]:
    """All spans of a 2-D polygon on the scanline at height ``y`` (even-odd rule; Q6(c)).

    Parameters
    ----------
    poly_xy : array_like, shape (n, 2), n >= 3
    y : float

    Returns
    -------
    spans : list of (x_left, x_right)
        Disjoint intervals sorted by ``x``; empty when the line misses the polygon.

    Notes
    -----
    The crossings of the line with the edges are sorted and paired: inside runs from the 1st
    crossing to the 2nd, the 3rd to the 4th, ... Each edge is treated as half-open in ``y``
    (its lower end counts, its upper end does not) so a vertex is never counted twice and
    horizontal edges add nothing. A convex polygon gives at most one span; a non-convex one
    can give several, which a rasteriser has to sort: the reason Q6(c) splits polygons into
    triangles.
    """
    p = _polygon2(poly_xy)
    y = as_scalar(y, "y")
    a, b = p, np.roll(p, -1, axis=0)
    lo, hi = np.minimum(a[:, 1], b[:, 1]), np.maximum(a[:, 1], b[:, 1])
    hit = (lo <= y) & (y < hi)
    a, b = a[hit], b[hit]
    xs = np.sort(a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1]))
    return [(float(xs[i]), float(xs[i + 1])) for i in range(0, len(xs) - 1, 2)
            if xs[i + 1] > xs[i]]
