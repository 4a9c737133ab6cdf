"""Q6: homogeneous clipping and triangle decomposition (notebook ``q6_clipping``).

Visible cases carry the exam's own numbers: triangles A and B of Q6(b), made homogeneous by a
real perspective matrix (``course_lib.clipping.EXAM_Q6``: near 3, far 6, 90 degrees, ``w`` the
depth of each vertex), so that the divide by ``w`` matters:

    A = [0, 0, 2, 4], [0, 2, 2, 4], [0, 6, 18, 12]   -> screen (0,0,.5), (0,.5,.5), (0,.5,1.5)
    B = [0, 0, 0, 3], [0, 1.5, 0, 3], [0, 3, 6, 6]   -> screen (0,0,0),  (0,.5,0),  (0,.5,1)

Hidden cases also scale vertices by arbitrary positive factors (the same projective point).

A clipped polygon is only defined up to where its vertex list starts and up to a positive scale
of each homogeneous vertex, so :func:`same_polygon` compares it that way (and forgives repeated
consecutive vertices, which a clipper that treats on-plane vertices as crossings produces).
"""

from __future__ import annotations

import numpy as np

from course_lib import clipping

from ..model import CellKind
from .base import (Case, Exercise, Mismatch, close, describe, number_item, up_to, wrong_shape,
                   wrong_value)

#: The exam's triangles in homogeneous screen coordinates (see the module docstring).
EXAM_A = np.array(clipping.EXAM_Q6["A"])
EXAM_B = np.array(clipping.EXAM_Q6["B"])
NB = "q6_clipping"


# ------------------------------------------------------------------------------------------------
# comparison rule for clip_polygon


def _unit_rows(P: np.ndarray) -> np.ndarray:
    P = P / np.max(np.abs(P), axis=1, keepdims=True)      # no under/overflow in the norm
    return P / np.linalg.norm(P, axis=1, keepdims=True)


def _drop_repeats(U: np.ndarray, atol: float) -> np.ndarray:
    """Remove vertices equal to their predecessor (cyclically) after normalisation."""
    if len(U) < 2:
        return U
    keep = ~np.all(np.abs(U - np.roll(U, 1, axis=0)) <= atol, axis=1)
    if not np.any(keep):
        return U[:1]
    return U[keep]


@up_to("the starting vertex and a positive scale of each homogeneous vertex")
def same_polygon(expected, received, atol: float = 1e-7) -> Mismatch | None:
    """Homogeneous polygons equal up to a cyclic shift and a positive scale per vertex.

    Each vertex is scaled to unit length (a positive scale changes nothing projectively, a
    negative one does: ``w < 0`` is behind the eye), repeated consecutive vertices are merged,
    and the lists must then agree for some starting vertex, in the same order (a reversed list
    has the opposite orientation and is wrong).
    """
    if not isinstance(received, np.ndarray) or received.dtype.kind not in "iuf":
        return wrong_shape(f"wrong type (expected an array of shape (m, 4), got {describe(received)})")
    e = np.asarray(expected, dtype=float)
    r = np.asarray(received, dtype=float)
    if r.ndim != 2 or r.shape[1] != 4:
        return wrong_shape(f"wrong shape (expected (m, 4), got {r.shape})")
    if len(e) == 0 or len(r) == 0:
        if len(e) == len(r):
            return None
        if len(e) == 0:
            return wrong_value(f"expected an empty (0, 4) array (nothing is left), got {len(r)} vertices")
        return wrong_value("expected a polygon, got an empty array")
    if not np.all(np.isfinite(r)):
        return wrong_value("wrong value (NaN or inf in the answer)")
    if np.any(np.all(r == 0, axis=1)):
        return wrong_value("a vertex is [0, 0, 0, 0], which is not a point")
    E = _drop_repeats(_unit_rows(e), atol)
    R = _drop_repeats(_unit_rows(r), atol)
    if len(E) != len(R):
        return wrong_shape(f"wrong number of vertices (expected {len(E)}, got {len(R)})")
    for shift in range(len(R)):
        if np.allclose(np.roll(R, -shift, axis=0), E, atol=atol, rtol=0):
            return None
    for shift in range(len(R)):
        if np.allclose(np.roll(R[::-1], -shift, axis=0), E, atol=atol, rtol=0):
            return wrong_value("the vertices are right but in reverse order (orientation flipped)")
    return wrong_value("wrong vertices (no cyclic shift matches, even allowing a positive scale per vertex)")


def same_span(expected, received) -> Mismatch | None:
    """``None`` against ``None``; otherwise a tuple ``(x_left, x_right)`` within tolerance."""
    if expected is None:
        if received is None:
            return None
        return wrong_value(f"the line misses the triangle: expected None, got {describe(received)}")
    if received is None:
        return wrong_value("the line crosses the triangle: expected (x_left, x_right), got None")
    if not isinstance(received, tuple) or len(received) != 2:
        return wrong_shape(f"wrong type (expected a tuple (x_left, x_right), got {describe(received)})")
    return close(rtol=1e-7, atol=1e-9)(expected, received)


def same_ints(expected, received) -> Mismatch | None:
    """Integer arrays equal exactly (same shape, same values)."""
    if not isinstance(received, np.ndarray):
        return wrong_shape(f"wrong type (expected an integer array, got {describe(received)})")
    if received.dtype.kind not in "iu":
        if received.dtype.kind == "f" and np.all(received == np.round(received)):
            pass
        else:
            return wrong_shape(f"wrong type (expected integers, got dtype {received.dtype})")
    if received.shape != expected.shape:
        return wrong_shape(f"wrong shape (expected {expected.shape}, got {received.shape})")
    if not np.array_equal(received, expected):
        return wrong_value("wrong indices")
    return None


def same_bools(expected, received) -> Mismatch | None:
    """Boolean arrays (or one bool) equal exactly, same shape."""
    e = np.asarray(expected)
    if isinstance(received, bool):
        received = np.asarray(received)
    if not isinstance(received, np.ndarray) or received.dtype.kind != "b":
        return wrong_shape(f"wrong type (expected booleans, got {describe(received)})")
    if received.shape != e.shape:
        return wrong_shape(f"wrong shape (expected {e.shape}, got {received.shape})")
    bad = np.flatnonzero(received.ravel() != e.ravel())
    if bad.size:
        return wrong_value(f"wrong answer for {bad.size} vertex(es) (first at flat index {bad[0]})")
    return None


# ------------------------------------------------------------------------------------------------
# random inputs


def _random_homogeneous(rng, screen, w_low=0.2, w_high=5.0):
    """Homogeneous coordinates of screen points with random positive w per vertex."""
    screen = np.asarray(screen, dtype=float)
    w = rng.uniform(w_low, w_high, size=screen.shape[:-1] + (1,))
    return np.concatenate([screen * w, w], axis=-1)


def _random_convex_screen(rng, n, centre, radius, z_range=(-0.3, 1.3)):
    """A convex polygon (anticlockwise in x_s, y_s) with n vertices on an ellipse, random z."""
    ang = np.sort(rng.uniform(0, 2 * np.pi, n))
    while np.min(np.diff(np.r_[ang, ang[0] + 2 * np.pi])) < 0.05:
        ang = np.sort(rng.uniform(0, 2 * np.pi, n))
    xy = np.asarray(centre)[:2] + np.stack([radius[0] * np.cos(ang),
                                            radius[1] * np.sin(ang)], axis=1)
    z = rng.uniform(*z_range, size=(n, 1))
    return np.concatenate([xy, z], axis=1)


def _box_corners(rng, n):
    """``n`` corners of the view volume (``-w <= X, Y <= w``, ``0 <= Z <= w``) with random
    ``w > 0``, each moved just outside it along one axis with probability 1/2."""
    w = rng.uniform(0.5, 5.0, n)
    corners = np.column_stack([rng.choice([-1.0, 1.0], n) * w, rng.choice([-1.0, 1.0], n) * w,
                               rng.choice([0.0, 1.0], n) * w, w])
    for i in np.flatnonzero(rng.random(n) < 0.5):
        axis = int(rng.integers(3))
        corners[i, axis] = corners[i, axis] * 1.001 if corners[i, axis] else -1e-3 * w[i]
    return corners


# ------------------------------------------------------------------------------------------------
# cases


def _inside_cases(rng):
    yield Case(args=(EXAM_A,), label="exam Q6(b)(i): triangle A", visible=True)
    yield Case(args=(EXAM_B,), label="exam Q6(b)(i): triangle B (two vertices on planes)",
               visible=True)
    yield Case(args=(EXAM_A[2],), label="one vertex, shape (4,)", visible=True)
    yield Case(args=(_box_corners(rng, 6),),
               label="6 corners of the box (inclusive), some moved just outside")
    inside = _random_homogeneous(rng, rng.uniform([-1, -1, 0], [1, 1, 1], size=(6, 3)))
    behind = rng.random(6) < 0.5
    inside[behind] *= -1.0
    yield Case(args=(inside,), label="6 vertices inside the box, some negated (w < 0: behind "
                                     "the eye, though the divide by w lands inside)")
    pts = _random_homogeneous(rng, rng.uniform(-1.6, 1.6, size=(40, 3)) + [0, 0, 0.5])
    yield Case(args=(pts,), label="batch of 40 random vertices")
    pts = rng.uniform(-2, 2, size=(2, 5, 4))
    yield Case(args=(pts,), label="batch of shape (2, 5, 4), some w < 0")
    yield Case(args=(np.ones((3, 3)),), label="wrong shape (3, 3)", raises=ValueError)


def _to_screen_cases(rng):
    yield Case(args=(EXAM_A,), label="exam Q6(b)(ii): triangle A", visible=True)
    yield Case(args=(EXAM_B,), label="exam Q6(b)(ii): triangle B", visible=True)
    yield Case(args=(_random_homogeneous(rng, rng.uniform(-1, 1, 3)),),
               label="one vertex, shape (4,)")
    yield Case(args=(_random_homogeneous(rng, rng.uniform(-1, 1, (25, 3))),),
               label="batch of 25 vertices")
    yield Case(args=(_random_homogeneous(rng, rng.uniform(-1, 1, (2, 3, 3))),),
               label="batch of shape (2, 3, 4)")
    n = int(rng.integers(0, 4))
    yield Case(args=(_random_homogeneous(rng, rng.uniform(-1, 1, (n, 3))),),
               label="0 to 3 vertices (none: an empty polygon of shape (0, 4))")
    yield Case(args=(np.array([1.0, 2.0, 3.0, 0.0]),), label="w = 0", raises=ValueError)
    yield Case(args=(np.ones((4, 3)),), label="wrong shape (4, 3)", raises=ValueError)


def _clip_cases(rng):
    yield Case(args=(EXAM_A,), label="exam Q6(b)(iii): triangle A against the far plane",
               visible=True)
    yield Case(args=(EXAM_B,), label="exam Q6(b)(i): triangle B, all inside", visible=True)
    for n in (3, 3, 4, 5, 6, 8):
        screen = _random_convex_screen(rng, n, rng.uniform(-0.8, 0.8, 2),
                                       rng.uniform(0.4, 1.4, 2))
        yield Case(args=(_random_homogeneous(rng, screen),),
                   label=f"random convex {n}-gon cut by several planes")
    screen = _random_convex_screen(rng, 5, (0.0, 0.0), (0.5, 0.5), z_range=(0.2, 0.8))
    yield Case(args=(_random_homogeneous(rng, screen),), label="polygon entirely inside")
    # an empty result a third of the time, so that no call's answer is fixed
    beyond = rng.random() < 1 / 3
    screen = _random_convex_screen(rng, 4, (3.0 if beyond else rng.uniform(0.8, 1.2), 0.0),
                                   (0.5, 0.5), z_range=(0.2, 0.8))
    yield Case(args=(_random_homogeneous(rng, screen),),
               label="polygon entirely right of the volume (empty (0, 4)) or across x = 1")
    beyond = rng.random() < 1 / 3
    screen = _random_convex_screen(rng, 4, (0.0, 0.0), (0.5, 0.5),
                                   z_range=(1.5, 2.0) if beyond else (0.7, 1.3))
    yield Case(args=(_random_homogeneous(rng, screen),),
               label="polygon entirely beyond the far plane (empty (0, 4)) or across it")
    tri = np.array([[0.2, 0.1, 0.5, 1.0], [-0.3, 0.2, 0.4, 1.0], [0.1, -0.2, 0.3, -0.5]])
    tri[:, :3] += rng.uniform(-0.05, 0.05, (3, 3))
    yield Case(args=(tri,), label="a vertex with w < 0 (behind the eye)")
    big = np.array([[-3.0, -3.0], [3.0, -3.0], [0.0, 4.0]]) + rng.uniform(-0.2, 0.2, (3, 2))
    big = np.column_stack([big, np.full(3, rng.uniform(0.1, 0.9))])
    yield Case(args=(_random_homogeneous(rng, big),), label="triangle larger than the screen")
    yield Case(args=(np.ones((3, 3)),), label="wrong shape (3, 3)", raises=ValueError)
    yield Case(args=(np.ones((2, 4)),), label="only two vertices", raises=ValueError)


def _area_cases(rng):
    yield Case(args=(clipping.to_screen(EXAM_A),), label="exam Q6(b)(ii): A is edge-on",
               visible=True)
    yield Case(args=(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),),
               label="unit right triangle, anticlockwise", visible=True)
    screen = _random_convex_screen(rng, 3, rng.uniform(-1, 1, 2), rng.uniform(0.2, 2, 2))
    yield Case(args=(screen[::-1],), label="clockwise triangle: negative area")
    for n in (4, 7, 12):
        screen = _random_convex_screen(rng, n, rng.uniform(-1, 1, 2), rng.uniform(0.2, 2, 2))
        yield Case(args=(screen,), label=f"random convex {n}-gon")
        yield Case(args=(screen[::-1],), label=f"random convex {n}-gon, clockwise")
    n = int(rng.choice([0, 3, 4, 5]))
    screen = _random_convex_screen(rng, n, rng.uniform(-1, 1, 2), rng.uniform(0.2, 2, 2)) \
        if n else np.zeros((0, 3))
    yield Case(args=(screen,), label="0, 3, 4 or 5 vertices (none: area 0)")
    yield Case(args=(np.ones((4,)),), label="wrong shape (4,)", raises=ValueError)


def _fan_cases(rng):
    yield Case(args=(4,), label="exam Q6(b)(iii): clipped A has 4 vertices", visible=True)
    yield Case(args=(3,), label="a triangle is one triangle", visible=True)
    for m in sorted(rng.choice(np.arange(5, 40), size=4, replace=False)):
        yield Case(args=(int(m),), label=f"{m}-gon")
    yield Case(args=(2,), label="m = 2 is not a polygon", raises=ValueError)
    yield Case(args=(4.5,), label="m = 4.5 is not an integer", raises=ValueError)


def _span_cases(rng):
    tri = np.array([[0.0, 0.0], [4.0, 0.0], [0.0, 2.0]])
    yield Case(args=(tri, 1.0), label="right triangle, halfway up", visible=True)
    yield Case(args=(tri, 3.0), label="above the triangle: None", visible=True)
    flat = rng.uniform(-5, 5, (3, 2))
    flat[1, 1] = flat[0, 1]
    yield Case(args=(flat, float(flat[0, 1])), label="along a horizontal edge")
    t = rng.uniform(-5, 5, (3, 2))
    yield Case(args=(t, float(t[:, 1].max())), label="through the top vertex only")
    for k in range(6):
        t = rng.uniform(-5, 5, (3, 2))
        y = rng.uniform(t[:, 1].min(), t[:, 1].max())
        yield Case(args=(t, float(y)), label=f"random triangle {k}, inside its height")
    t = rng.uniform(-5, 5, (3, 2))
    misses = rng.random() < 1 / 3      # None a third of the time, so that no answer is fixed
    y = t[:, 1].min() - 1.0 if misses else rng.uniform(t[:, 1].min(), t[:, 1].max())
    yield Case(args=(t, float(y)), label="below a random triangle (None), or across it")
    yield Case(args=(t, float(t[1, 1])), label="through a vertex")
    yield Case(args=(np.ones((4, 2)), 0.0), label="four vertices", raises=ValueError)
    yield Case(args=(np.ones((3, 3)), 0.0), label="wrong shape (3, 3)", raises=ValueError)


# ------------------------------------------------------------------------------------------------
# the registry


def _choice(name, answer, description, options=("a", "b", "c", "d")):
    return Exercise(name=name, notebook=NB, kind=CellKind.CHOICE, answer=answer, options=options,
                    description=description)


EXERCISES = [
    Exercise(name="inside_view_volume", notebook=NB, reference=clipping.inside_view_volume,
             cases=_inside_cases, compare=same_bools,
             description="Q6(b)(i): -w <= X <= w, -w <= Y <= w, 0 <= Z <= w per vertex"),
    Exercise(name="to_screen", notebook=NB, reference=clipping.to_screen,
             cases=_to_screen_cases, compare=close(rtol=1e-9, atol=1e-12),
             description="Q6(b)(ii): divide by w"),
    Exercise(name="clip_polygon", notebook=NB, reference=clipping.clip_polygon,
             cases=_clip_cases, compare=same_polygon,
             description="Q6(b)(iii): Sutherland-Hodgman against the six planes, homogeneous"),
    Exercise(name="screen_area", notebook=NB, reference=clipping.screen_area,
             cases=_area_cases, compare=close(rtol=1e-7, atol=1e-10),
             description="Q6(b)(ii): signed shoelace area on the (x_s, y_s) plane"),
    Exercise(name="fan_triangulate", notebook=NB, reference=clipping.fan_triangulate,
             cases=_fan_cases, compare=same_ints,
             description="Q6(c): (0, i, i+1) for i = 1 .. m-2"),
    Exercise(name="scanline_span", notebook=NB, reference=clipping.scanline_span,
             cases=_span_cases, compare=same_span,
             description="Q6(c): the one span of a triangle on a scanline"),
    _choice("q6_item1", "b",
            "Q6(a), Item Q6.1: far plane against aliasing, near plane for cut-aways"),
    _choice("q6_item2", "c",
            "Q6(b)(i), Item Q6.2: camera-independent inequalities; rejects skip the divide"),
    _choice("q6_item3", "b",
            "Q6(b)(ii), Item Q6.3: A is larger than B in the world; both are edge-on"),
    _choice("q6_item4", "d",
            "Q6(c), Item Q6.4: decompose into triangles right after clipping"),
]


# Q6(b) on the student's own numbers: which vertices are inside, and where they land on screen.
EXERCISES += [
    number_item("q6bi_your_inside", NB,
                lambda v: clipping.inside_view_volume(np.array(v.vertices, dtype=float)),
                "Q6(b)(i) on your numbers: which of your three vertices are inside"),
    number_item("q6bii_your_screen", NB,
                lambda v: clipping.to_screen(np.array(v.vertices, dtype=float)),
                "Q6(b)(ii) on your numbers: your vertices in screen coordinates, shape (3, 3)"),
]
