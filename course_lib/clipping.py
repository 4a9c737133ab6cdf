"""Homogeneous clipping, triangle decomposition and scanline spans (exam question 6).

The rendering pipeline of the course carries every vertex in *homogeneous 3D screen coordinates*
``[X, Y, Z, w]``: the perspective matrix has already been applied, but the divide by ``w`` has
not. The view volume is then the box

    -w <= X <= w,    -w <= Y <= w,    0 <= Z <= w                                (Q6(a))

which, after the divide ``(x_s, y_s, z_s) = (X, Y, Z) / w``, is the cube-like box
``[-1, 1] x [-1, 1] x [0, 1]`` of non-homogeneous screen space. Clipping against it is done
*before* the divide (Q6(b)(i)): the six inequalities do not depend on the camera, they are cheap
enough for hardware, and polygons that are thrown away never pay for a division.

Contents
--------
Contract functions (``shared/EXERCISES.md``, notebook ``q6_clipping``):
    :func:`inside_view_volume`, :func:`to_screen`, :func:`clip_polygon`, :func:`screen_area`,
    :func:`fan_triangulate`, :func:`scanline_span`.
The exam's triangles:
    :func:`perspective_matrix` (camera coordinates to homogeneous 3D screen coordinates) and
    :data:`EXAM_Q6`, the triangles A and B of Q6(b) in camera coordinates and, through the
    matrix, in homogeneous screen coordinates.
Further tools, for the explorer and the "going further" section:
    :func:`clip_polygons` (many polygons in one call), :func:`clip_against_plane`,
    :func:`clip_steps` (the polygon after each of the six planes); :func:`rasterize_triangle`
    and :func:`triangle_spans` (a scanline rasteriser with the top-left fill rule), written in
    :mod:`course_lib._raster` and imported from here. Area, convexity, ear clipping and the
    spans of a polygon are in :mod:`course_lib._polygons`.

The students' copy
------------------
The students' wheel carries this module without the graded functions and the clipping
machinery (``LEFT_OUT_HELPERS`` in :mod:`autograder.student_bundle`): the explorer gets its
steps, at display precision, from :func:`course_lib.widgets.clipping.clip_display`, and the
notebook's fixed examples from :mod:`course_lib.clip_results` (docs/students-copy.md).

Speed
-----
A renderer clips every polygon of every frame, so :func:`clip_polygon` checks its argument once
and then runs the six passes on Python floats for small polygons (a NumPy call costs about a
microsecond whatever the array size, which dominates on three or four vertices) and on whole
arrays for large ones. :func:`clip_polygons` clips a whole list of polygons with each pass done
by a few NumPy operations over all their vertices at once. All three routes return identical
results.

Points with ``w <= 0``
----------------------
The two X inequalities together say ``w >= |X|``, so every point of the view volume has
``w >= 0`` and the only one with ``w = 0`` is the zero vector, which is not a point at all. A
vertex with ``w < 0`` (behind the centre of projection, as a perspective matrix produces it) is
therefore always *outside*, and the homogeneous clipper cuts it away before anything is divided.
Dividing first would be wrong: ``(X, Y, Z) / w`` with ``w < 0`` lands in front of the viewer,
mirrored, and an edge from such a vertex would wrap around through infinity. Note that
``[X, Y, Z, w]`` and ``-[X, Y, Z, w]`` name the same projective point; the clipper (like the
hardware it models) treats the copy with negative ``w`` as behind the eye, which is the
convention of a perspective matrix that makes ``w`` the (positive) depth in front of the eye.
"""

from __future__ import annotations

import math

import numpy as np

from ._raster import rasterize_triangle, triangle_spans
from ._validate import as_float_array, as_int, as_points, as_scalar, as_vectors

__all__ = [
    "EXAM_Q6",
    "PLANES",
    "PLANE_NAMES",
    "clip_against_plane",
    "clip_polygon",
    "clip_polygons",
    "clip_steps",
    "fan_triangulate",
    "inside_view_volume",
    "perspective_matrix",
    "rasterize_triangle",
    "scanline_span",
    "screen_area",
    "to_screen",
    "triangle_spans",
]

#: The six clipping planes as linear forms ``n . [X, Y, Z, w] >= 0`` (inside), in the order the
#: clipper applies them: left, right, bottom, top, near, far.
PLANES = np.array(
    [
        [1.0, 0.0, 0.0, 1.0],   # X >= -w   (left,   x_s >= -1)
        [-1.0, 0.0, 0.0, 1.0],  # X <=  w   (right,  x_s <=  1)
        [0.0, 1.0, 0.0, 1.0],   # Y >= -w   (bottom, y_s >= -1)
        [0.0, -1.0, 0.0, 1.0],  # Y <=  w   (top,    y_s <=  1)
        [0.0, 0.0, 1.0, 0.0],   # Z >=  0   (near,   z_s >=  0)
        [0.0, 0.0, -1.0, 1.0],  # Z <=  w   (far,    z_s <=  1)
    ]
)
PLANES.setflags(write=False)

#: Human-readable names of :data:`PLANES`, in the same order.
PLANE_NAMES = (
    "left (X >= -w)",
    "right (X <= w)",
    "bottom (Y >= -w)",
    "top (Y <= w)",
    "near (Z >= 0)",
    "far (Z <= w)",
)

#: Relative tolerance under which a vertex counts as lying *on* a clipping plane.
_ON_PLANE_RTOL = 1e-12


# ------------------------------------------------------------------------------------------------
# the perspective matrix and the exam's triangles


def perspective_matrix(near, far, tan_half_fov=1.0) -> np.ndarray:
    """The 4 x 4 matrix from camera coordinates to homogeneous 3D screen coordinates (Q6(a)).

    Parameters
    ----------
    near, far : float
        Distances of the near and far clipping planes in front of the centre of projection,
        ``0 < near < far``.
    tan_half_fov : float, optional
        Tangent of half the field of view (the same horizontally and vertically); the default
        1.0 is a 90 degree view.

    Returns
    -------
    M : ndarray, shape (4, 4)
        ``[X, Y, Z, w] = M @ [x_c, y_c, z_c, 1]`` with ``X = x_c / t``, ``Y = y_c / t``,
        ``Z = far (z_c - near) / (far - near)`` and ``w = z_c`` (``t = tan_half_fov``).

    Raises
    ------
    ValueError
        If ``near`` or ``far`` is not a finite number with ``0 < near < far``, or
        ``tan_half_fov`` is not positive.

    Notes
    -----
    The camera sits at the origin and looks along ``+z_c``. The matrix makes ``w`` the depth
    ``z_c``, so ``w`` grows with distance from the viewer and the divide by ``w`` shrinks
    distant things. After the divide, ``z_s = far (1 - near / z_c) / (far - near)`` is 0 on the
    near plane, 1 on the far plane and increases with depth, and the frustum
    ``|x_c|, |y_c| <= t z_c``, ``near <= z_c <= far`` becomes the view volume
    ``-w <= X, Y <= w``, ``0 <= Z <= w`` of Q6(a). Any positive multiple of ``[X, Y, Z, w]``
    names the same point, so ``w`` is the depth only up to such a factor.

    Examples
    --------
    >>> M = perspective_matrix(3.0, 6.0)
    >>> M @ [0.0, 2.0, 4.0, 1.0]
    array([0., 2., 2., 4.])
    """
    near, far = as_scalar(near, "near"), as_scalar(far, "far")
    t = as_scalar(tan_half_fov, "tan_half_fov")
    if not 0 < near < far:
        raise ValueError(f"near and far must satisfy 0 < near < far, got near={near}, far={far}")
    if not t > 0:
        raise ValueError(f"tan_half_fov must be positive, got {t}")
    depth_scale = far / (far - near)
    return np.array([
        [1.0 / t, 0.0, 0.0, 0.0],
        [0.0, 1.0 / t, 0.0, 0.0],
        [0.0, 0.0, depth_scale, -depth_scale * near],
        [0.0, 0.0, 1.0, 0.0],
    ])


def _exam_triangles() -> dict:
    """:data:`EXAM_Q6`, built from camera coordinates through :func:`perspective_matrix`."""
    near, far = 3.0, 6.0
    camera = {"A": np.array([[0.0, 0.0, 4.0], [0.0, 2.0, 4.0], [0.0, 6.0, 12.0]]),
              "B": np.array([[0.0, 0.0, 3.0], [0.0, 1.5, 3.0], [0.0, 3.0, 6.0]])}
    M = perspective_matrix(near, far)
    out = {"near": near, "far": far, "matrix": M}
    for name, pts in camera.items():
        pts.setflags(write=False)
        homogeneous = np.hstack([pts, np.ones((3, 1))]) @ M.T
        homogeneous.setflags(write=False)
        out[f"{name}_camera"], out[name] = pts, homogeneous
    M.setflags(write=False)
    return out


#: The exam's triangles A and B of Q6(b). The surviving worked solutions give them only after
#: the divide by ``w``: A is (0, 0, 0.5), (0, 0.5, 0.5), (0, 0.5, 1.5) and B the same with
#: ``z_s`` 0.5 smaller. Here they come from camera-space points (``"A_camera"``,
#: ``"B_camera"``) through ``perspective_matrix(near=3, far=6)`` (a 90 degree view), so each
#: vertex's ``w`` is its depth: ``"A"`` is ``[0, 0, 2, 4], [0, 2, 2, 4], [0, 6, 18, 12]`` and
#: ``"B"`` is ``[0, 0, 0, 3], [0, 1.5, 0, 3], [0, 3, 6, 6]``.
EXAM_Q6 = _exam_triangles()


# ------------------------------------------------------------------------------------------------
# contract functions


def inside_view_volume(P) -> np.ndarray:
    """Whether each homogeneous vertex lies inside the view volume (Q6(b)(i)).

    Parameters
    ----------
    P : array_like, shape (..., 4)
        Homogeneous 3D screen coordinates ``[X, Y, Z, w]``; one vertex ``(4,)`` or any batch.

    Returns
    -------
    inside : ndarray of bool, shape (...)
        True where ``-w <= X <= w``, ``-w <= Y <= w`` and ``0 <= Z <= w`` (boundary included).

    Raises
    ------
    ValueError
        If the last axis of ``P`` is not 4, or ``P`` holds NaN or inf.

    Notes
    -----
    Q6(a) gives the view volume in homogeneous coordinates; Q6(b)(i) asks which of the exam's
    vertices lie inside it. The test needs six comparisons and no division, and the same six
    inequalities serve every camera, which is why hardware performs it before the divide by
    ``w``. The inequalities imply ``w >= 0``; the zero vector ``[0, 0, 0, 0]`` satisfies them
    but is not a point, so it is reported as outside (``w > 0`` is required as well).

    Examples
    --------
    The third vertex of the exam's triangle A has ``z_s = 1.5`` (``Z = 18 > w = 12``):

    >>> inside_view_volume(EXAM_Q6["A"])
    array([ True,  True, False])
    """
    P = as_vectors(P, 4, "P")
    X, Y, Z, w = np.moveaxis(P, -1, 0)
    return (w > 0) & (-w <= X) & (X <= w) & (-w <= Y) & (Y <= w) & (0 <= Z) & (Z <= w)


def to_screen(P) -> np.ndarray:
    """Non-homogeneous 3D screen coordinates ``(X, Y, Z) / w`` (Q6(b)(ii)).

    Parameters
    ----------
    P : array_like, shape (..., 4)
        Homogeneous 3D screen coordinates ``[X, Y, Z, w]``.

    Returns
    -------
    screen : ndarray, shape (..., 3)
        ``(x_s, y_s, z_s)``; an empty ``(0, 4)`` input gives an empty ``(0, 3)`` output.

    Raises
    ------
    ValueError
        If the last axis is not 4, or some vertex has ``w = 0`` (a point at infinity has no
        screen position).

    Notes
    -----
    A vertex with ``w < 0`` is divided like any other, but the result is meaningless for
    display: it is the mirror image of a point behind the eye. Clip first
    (:func:`clip_polygon` removes every ``w < 0`` vertex), then divide.

    Examples
    --------
    >>> to_screen([0.0, 6.0, 18.0, 12.0])
    array([0. , 0.5, 1.5])
    """
    P = as_vectors(P, 4, "P")
    w = P[..., 3:]
    if np.any(w == 0):
        raise ValueError("P has a vertex with w = 0 (a point at infinity), which cannot be "
                         "divided by w")
    return P[..., :3] / w


def clip_polygon(P) -> np.ndarray:
    """Sutherland-Hodgman clipping of a polygon against the view volume (Q6(b)(iii)).

    Parameters
    ----------
    P : array_like, shape (n, 4), n >= 3
        The polygon's vertices in homogeneous 3D screen coordinates, in order.

    Returns
    -------
    clipped : ndarray, shape (m, 4)
        The part of the polygon inside the view volume, still homogeneous, in the same
        orientation (vertex order) as ``P``; a vertex of ``P`` that survives is returned
        unchanged. An empty ``(0, 4)`` array when nothing with positive extent is left (fewer
        than three vertices).

    Raises
    ------
    ValueError
        If ``P`` is not ``(n, 4)`` with ``n >= 3``, holds NaN/inf, or has a zero vertex.

    Notes
    -----
    The polygon is clipped against each plane ``d(P) = n . P >= 0`` of :data:`PLANES` in turn.
    For each edge ``S -> E`` of the current polygon, ``S`` is kept when ``d(S) >= 0``, and when
    the edge crosses the plane strictly (``d(S) d(E) < 0``) the crossing point

        I = S + t (E - S),    t = d(S) / (d(S) - d(E))

    is inserted after it (computed as ``(|d(E)| S + |d(S)| E) / (|d(S)| + |d(E)|)``, the same
    point with better rounding). Because ``d`` is linear in homogeneous coordinates, ``I`` lies exactly
    on the plane; the crossing point is the same projective point one would find in screen
    space, only its parameter ``t`` differs. A vertex lying on a plane (within a relative
    tolerance of 1e-12) counts as inside and creates no extra vertex, so clipping an
    already-clipped polygon changes nothing. Points with ``w < 0`` fail ``X >= -w`` or
    ``X <= w`` and are removed without ever being divided (see the module notes). Clipping a
    convex polygon gives one convex polygon; a triangle may come back with up to nine vertices,
    which is why triangle decomposition comes after clipping (Q6(c)).

    ``P`` is checked once, on entry. A polygon of up to a couple of hundred vertices (the usual
    case: triangles and quadrilaterals) is then clipped with Python floats, a plane being
    skipped after one comparison per vertex when no vertex lies outside it; a larger one with
    whole-array NumPy passes. Both paths perform the same floating-point operations and give
    the same result, bit for bit. To clip many polygons, :func:`clip_polygons` is several times
    faster than calling this function on each.

    Examples
    --------
    The exam's triangle A (``z_s`` of its third vertex is 1.5) loses a corner to the far plane:

    >>> to_screen(clip_polygon(EXAM_Q6["A"]))
    array([[0.  , 0.  , 0.5 ],
           [0.  , 0.5 , 0.5 ],
           [0.  , 0.5 , 1.  ],
           [0.  , 0.25, 1.  ]])
    """
    P = _as_float64(P, "P")
    if P.ndim != 2 or P.shape[1] != 4 or not 3 <= len(P) <= _SMALL_POLYGON:
        return _clip_array(_polygon4(P))        # raises for a bad P
    # The checks of _polygon4 on Python floats (a few NumPy calls would cost more than the
    # whole clip). The sum of finite numbers is finite unless it overflows: only then, or for
    # a zero vertex, is _polygon4 asked (and raises, or not).
    flat = P.ravel().tolist()
    rows = P.tolist()
    if not math.isfinite(sum(flat)) or _ZERO_ROW in rows:
        _polygon4(P)
    out = _clip_rows(rows, max(max(flat), -min(flat)))
    if out is rows:
        return P.copy()
    return np.array(out, dtype=np.float64) if out else np.zeros((0, 4))


def screen_area(P_screen) -> float:
    """Signed area of a polygon's projection on the ``(x_s, y_s)`` plane (Q6(b)(ii)).

    Parameters
    ----------
    P_screen : array_like, shape (n, 3) or (n, 2)
        Vertices in (non-homogeneous) screen coordinates; only ``x_s`` and ``y_s`` are used.
        ``n`` may be 0, 1 or 2 (area 0), so an empty clipped polygon is accepted.

    Returns
    -------
    area : float
        The shoelace sum ``1/2 sum_i (x_i y_{i+1} - x_{i+1} y_i)``: positive when the vertices
        run anticlockwise with ``x_s`` to the right and ``y_s`` up, negative when clockwise.

    Raises
    ------
    ValueError
        If ``P_screen`` is not a 2-D array with 2 or 3 columns, or holds NaN/inf.

    Notes
    -----
    Q6(b)(ii): the exam's triangles A and B both have ``x_s = 0`` at every vertex, so they are
    seen edge-on and cover no screen area at all, however large they are in the world.

    Examples
    --------
    >>> screen_area([[0, 0, 0.5], [0, 0.5, 0.5], [0, 0.5, 1.5]])
    0.0
    >>> screen_area([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    0.5
    """
    P = as_float_array(P_screen, "P_screen")
    if P.ndim != 2 or P.shape[1] not in (2, 3):
        raise ValueError(f"P_screen must have shape (n, 3) or (n, 2), got shape {P.shape}")
    if len(P) < 3:
        return 0.0
    return shoelace_area(P[:, 0], P[:, 1])


def shoelace_area(x, y) -> float:
    """The shoelace sum ``1/2 sum_i (x_i y_{i+1} - x_{i+1} y_i)`` of the closed polygon with
    vertex coordinates ``x``, ``y`` (1-D float arrays of one length, at least 3; unchecked):
    positive when anticlockwise.

    The coordinates are shifted to their centroid first: the same sum, with far less
    cancellation.

    Examples
    --------
    >>> shoelace_area(np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0]))
    0.5
    """
    x = x - x.mean()
    y = y - y.mean()
    return float(0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def fan_triangulate(m) -> np.ndarray:
    """Fan triangulation of a convex m-gon: triangles ``(0, i, i + 1)`` (Q6(c)).

    Parameters
    ----------
    m : int
        Number of vertices, at least 3.

    Returns
    -------
    triangles : ndarray of int, shape (m - 2, 3)
        Vertex indices; every triangle keeps the polygon's orientation.

    Raises
    ------
    ValueError
        If ``m`` is not an integer >= 3.

    Notes
    -----
    Q6(c): a clipped convex polygon is split into triangles right after clipping. Fanning from
    vertex 0 is correct for any convex polygon because the segment from vertex 0 to every other
    vertex lies inside it. A non-convex polygon needs ear clipping
    (:func:`course_lib._polygons.ear_clip`).

    Examples
    --------
    The clipped triangle A has four vertices, hence two triangles:

    >>> fan_triangulate(4)
    array([[0, 1, 2],
           [0, 2, 3]])
    """
    m = as_int(m, "m", minimum=3)
    i = np.arange(1, m - 1)
    return np.stack([np.zeros_like(i), i, i + 1], axis=1)


def scanline_span(tri_xy, y):
    """Where the horizontal line at height ``y`` crosses a triangle (Q6(c)).

    Parameters
    ----------
    tri_xy : array_like, shape (3, 2)
        The triangle's screen vertices ``(x, y)``.
    y : float
        Height of the scanline.

    Returns
    -------
    span : tuple of two floats, or None
        ``(x_left, x_right)``, ``x_left <= x_right``, the closed interval the line shares with
        the (closed) triangle; ``None`` when the line misses it. A line through a single vertex
        gives ``(x, x)``; a line along a horizontal edge gives that edge.

    Raises
    ------
    ValueError
        If ``tri_xy`` is not ``(3, 2)`` or ``y`` is not a single finite number.

    Notes
    -----
    Q6(c): a triangle is convex, so a scanline meets it in one interval, a *single span*; the
    rasteriser fills it from ``x_left`` to ``x_right`` with no sorting. Each edge ``a -> b``
    that the line meets (``min(a_y, b_y) <= y <= max(a_y, b_y)``) contributes
    ``x = a_x + (y - a_y)(b_x - a_x) / (b_y - a_y)`` (both ends if the edge is horizontal);
    the span runs from the smallest to the largest. A non-convex polygon can have several
    spans on one line (:func:`course_lib._polygons.polygon_spans`).

    Examples
    --------
    >>> scanline_span([[0, 0], [4, 0], [0, 2]], 1.0)
    (0.0, 2.0)
    >>> scanline_span([[0, 0], [4, 0], [0, 2]], 3.0) is None
    True
    """
    tri = as_points(tri_xy, 2, "tri_xy")
    if tri.shape[0] != 3:
        raise ValueError(f"tri_xy must have shape (3, 2), got shape {tri.shape}")
    y = as_scalar(y, "y")
    a, b = tri, np.roll(tri, -1, axis=0)
    lo, hi = np.minimum(a[:, 1], b[:, 1]), np.maximum(a[:, 1], b[:, 1])
    hit = (lo <= y) & (y <= hi)
    if not np.any(hit):
        return None
    a, b = a[hit], b[hit]
    dy = b[:, 1] - a[:, 1]
    flat = dy == 0
    xs = [a[flat, 0], b[flat, 0]]
    s = ~flat
    xs.append(a[s, 0] + (y - a[s, 1]) * (b[s, 0] - a[s, 0]) / dy[s])
    xs = np.concatenate(xs)
    return float(xs.min()), float(xs.max())


# ------------------------------------------------------------------------------------------------
# clipping, one plane at a time


def clip_against_plane(P, plane) -> np.ndarray:
    """One Sutherland-Hodgman pass: the part of polygon ``P`` where ``plane . P >= 0``.

    Parameters
    ----------
    P : array_like, shape (n, 4)
        Homogeneous polygon (``n`` may be 0; fewer than 3 vertices are passed through the same
        rule, which is what a step-by-step display needs).
    plane : array_like, shape (4,) or int
        The linear form ``n`` of the half-space ``n . P >= 0``, or an index into :data:`PLANES`.

    Returns
    -------
    clipped : ndarray, shape (m, 4)
        Surviving vertices and inserted crossings, in the order of ``P``.

    Notes
    -----
    See :func:`clip_polygon` for the rule. The pass is vectorised over the vertices: each
    vertex ``S_i`` contributes up to two outputs, itself (if inside) and the crossing on edge
    ``S_i S_{i+1}`` (if the edge crosses), which are put in that order. When no vertex is
    outside the half-space the pass returns a copy of ``P`` at once.
    """
    P = as_float_array(P, "P")
    if P.ndim != 2 or P.shape[1] != 4:
        raise ValueError(f"P must have shape (n, 4), got shape {P.shape}")
    if isinstance(plane, (int, np.integer)):
        plane = PLANES[as_int(plane, "plane", minimum=0)]
    plane = as_vectors(plane, 4, "plane")
    return _clip_plane_array(P, plane)


def clip_steps(P) -> list[np.ndarray]:
    """The polygon before clipping and after each of the six planes, in order (Q6(b)(iii)).

    Parameters
    ----------
    P : array_like, shape (n, 4), n >= 3
        Homogeneous polygon.

    Returns
    -------
    steps : list of 7 ndarrays of shape (m_k, 4)
        ``steps[0]`` is ``P``; ``steps[k]`` is the polygon after planes ``1 .. k`` of
        :data:`PLANES` (left, right, bottom, top, near, far). Unlike :func:`clip_polygon`, a
        polygon reduced to one or two vertices on the way is kept as it is, so every step can be
        drawn; ``steps[6]`` has fewer than 3 vertices exactly when :func:`clip_polygon` returns
        an empty array.
    """
    P = _polygon4(P)
    steps = [P]
    for plane in PLANES:
        steps.append(_clip_plane_array(steps[-1], plane))
    return steps


def clip_polygons(polygons) -> list[np.ndarray]:
    """:func:`clip_polygon` applied to each polygon of a list, in one call (Q6(b)(iii)).

    Parameters
    ----------
    polygons : sequence of array_like, each of shape (n_i, 4), n_i >= 3
        Homogeneous polygons, as for :func:`clip_polygon`; they may have different vertex
        counts. A single ``(k, n, 4)`` array (``k`` polygons of ``n`` vertices) works too.

    Returns
    -------
    clipped : list of ndarrays of shape (m_i, 4)
        ``clipped[i]`` equals ``clip_polygon(polygons[i])`` value for value (same vertices, same
        order, an empty ``(0, 4)`` array for a polygon with nothing left).

    Raises
    ------
    ValueError
        If some polygon is not ``(n, 4)`` with ``n >= 3``, holds NaN/inf, or has a zero vertex;
        the message names it by its index, e.g. ``polygons[3]``.

    Notes
    -----
    A renderer clips every polygon of a frame, most of them triangles. Calling
    :func:`clip_polygon` once per triangle pays its fixed cost (argument checks, conversions,
    creating the result) every time. Here all the vertices are stacked into one array and
    checked at once, and each of the six passes is a few NumPy operations over every polygon
    together: the next vertex of each vertex within its polygon, the crossings of all the edges
    that cross, and one scatter that puts every kept vertex and crossing in its place; a polygon
    left with fewer than three vertices is dropped from the array. The operations on each
    polygon are those of :func:`clip_polygon`, so the results are identical. The returned
    arrays are slices of one output array: disjoint, and never sharing memory with the input.

    Examples
    --------
    The exam's triangle A loses a corner to the far plane; B lies inside and comes back whole:

    >>> [len(p) for p in clip_polygons([EXAM_Q6["A"], EXAM_Q6["B"]])]
    [4, 3]
    """
    arrays = []
    for i, P in enumerate(polygons):
        if type(P) is np.ndarray and P.dtype == np.float64:
            A = P
        else:
            A = _as_float64(P, f"polygons[{i}]")
        if A.ndim != 2 or A.shape[1] != 4 or A.shape[0] < 3:
            for k, B in enumerate(arrays):        # name the first bad polygon, whatever is
                _polygon4(B, f"polygons[{k}]")    # wrong with it
            _polygon4(A, f"polygons[{i}]")        # raises
        arrays.append(A)
    if not arrays:
        return []
    counts = np.array([len(A) for A in arrays])
    V = np.concatenate(arrays)
    size = np.abs(V).max(axis=1)
    if not (np.isfinite(size).all() and size.all()):
        for i, A in enumerate(arrays):
            _polygon4(A, f"polygons[{i}]")        # raises for the first offending polygon
    V, counts = _clip_batch(V, size, counts)
    ends = np.cumsum(counts).tolist()
    return [V[e - c:e] for e, c in zip(ends, counts.tolist())]


# ------------------------------------------------------------------------------------------------
# private machinery: checked once at the entry, then unchecked passes

#: Up to this many vertices :func:`clip_polygon` clips with Python floats (a list of rows), above
#: it with whole-array NumPy passes. A NumPy pass costs a dozen calls of about a microsecond
#: each whatever the size, some 80 us for the six planes; the Python passes cost about a
#: microsecond per vertex and skip the planes that cut nothing. Measured crossover: about 300
#: vertices. Both paths perform the same floating-point operations in the same order.
_SMALL_POLYGON = 256


_ZERO_ROW = [0.0, 0.0, 0.0, 0.0]


def _as_float64(P, name) -> np.ndarray:
    try:
        return np.asarray(P, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numeric, got {type(P).__name__}") from exc


def _polygon4(P, name="P") -> np.ndarray:
    """``P`` as a float64 ``(n, 4)`` array, ``n >= 3``, finite, with no zero vertex."""
    P = _as_float64(P, name)
    if not np.isfinite(P).all():
        raise ValueError(f"{name} must be finite (no NaN or inf)")
    if P.ndim != 2 or P.shape[1] != 4:
        raise ValueError(f"{name} must have shape (n, 4), got shape {P.shape}")
    if P.shape[0] < 3:
        raise ValueError(f"{name} needs at least 3 vertices to be a polygon, got {P.shape[0]}")
    if not np.abs(P).max(axis=1).all():
        raise ValueError(f"{name} has a zero vertex [0, 0, 0, 0], which is not a homogeneous "
                         "point")
    return P


def _clip_array(P) -> np.ndarray:
    """The six passes on a checked ``(n, 4)`` array, whole-array NumPy (large polygons)."""
    for plane in PLANES:
        P = _clip_plane_array(P, plane)
        if len(P) < 3:
            return np.zeros((0, 4))
    return P


def _clip_plane_array(P, plane) -> np.ndarray:
    """One unchecked Sutherland-Hodgman pass, vectorised over the vertices of ``P``."""
    if len(P) == 0:
        return P.copy()
    d = P @ plane
    size = np.abs(P).max(axis=1)
    tol = _ON_PLANE_RTOL * size * np.abs(plane).max()
    d[np.abs(d) <= tol] = 0.0
    keep = d >= 0
    if keep.all():
        return P.copy()            # nothing outside: no vertex dropped, no edge crosses
    dE = np.roll(d, -1)
    cross = d * dE < 0
    i = np.flatnonzero(cross)
    j = (i + 1) % len(P)
    # I = (|d_E| S + |d_S| E) / (|d_S| + |d_E|): positive weights, so every coordinate is
    # accurate relative to the vertices' size and d(I) = 0 up to rounding.
    aS, aE = np.abs(d[i])[:, None], np.abs(d[j])[:, None]
    crossing = (aE * P[i] + aS * P[j]) / (aS + aE)
    # An edge from S to a negative multiple of S passes through the 4-D origin, which is no
    # point: such a crossing is dropped (the edge is degenerate projectively).
    ok = np.abs(crossing).max(axis=1) > _ON_PLANE_RTOL * np.maximum(size[i], size[j])
    # Interleave: vertex k sorts at 2k, the crossing on its outgoing edge at 2k + 1.
    order = np.concatenate([2 * np.flatnonzero(keep), 2 * i[ok] + 1])
    out = np.concatenate([P[keep], crossing[ok]])
    return out[np.argsort(order, kind="stable")]


def _clip_batch(V, size, counts):
    """The six passes on many checked polygons at once, whole-batch NumPy.

    ``V`` holds the vertices of every polygon, one polygon after another, ``size`` their
    ``max |coordinate|`` and ``counts`` the number of vertices of each polygon. Returns the
    clipped vertices in the same layout and the new counts (0 for a polygon with nothing left).
    Every polygon goes through exactly the operations of :func:`_clip_plane_array`, so the
    results are those of :func:`clip_polygon`, bit for bit.
    """
    rtol = _ON_PLANE_RTOL
    for plane in PLANES:
        if len(V) == 0:
            break
        d = V @ plane
        d[np.abs(d) <= rtol * size] = 0.0          # max |plane| = 1 for all six planes
        keep = d >= 0
        if keep.all():
            continue
        # the next vertex of each vertex's polygon (the first one after the last)
        starts = np.cumsum(counts) - counts
        nxt = np.arange(1, len(V) + 1)
        live = counts > 0
        nxt[(starts + counts - 1)[live]] = starts[live]
        cross = d * d[nxt] < 0
        i = np.flatnonzero(cross)
        j = nxt[i]
        aS, aE = np.abs(d[i])[:, None], np.abs(d[j])[:, None]
        crossing = (aE * V[i] + aS * V[j]) / (aS + aE)
        csize = np.abs(crossing).max(axis=1)
        ok = csize > rtol * np.maximum(size[i], size[j])
        i, crossing, csize = i[ok], crossing[ok], csize[ok]
        # vertex k is followed by the crossing on its outgoing edge: place both
        has_cross = np.zeros(len(V), dtype=bool)
        has_cross[i] = True
        per_vertex = keep.astype(np.intp) + has_cross
        first = np.cumsum(per_vertex) - per_vertex
        out = np.empty((first[-1] + per_vertex[-1], 4))
        out_size = np.empty(len(out))
        out[first[keep]] = V[keep]
        out_size[first[keep]] = size[keep]
        at = first[i] + keep[i]
        out[at] = crossing
        out_size[at] = csize
        poly = np.repeat(np.arange(len(counts)), counts)
        counts = np.bincount(poly, weights=per_vertex, minlength=len(counts)).astype(np.intp)
        # a polygon left with fewer than 3 vertices is gone
        short = (counts > 0) & (counts < 3)
        if short.any():
            alive = np.repeat(~short, counts)
            out, out_size = out[alive], out_size[alive]
            counts[short] = 0
        V, size = out, out_size
    return V, counts


def _clip_rows(V, size):
    """The six passes on a checked small polygon held as Python floats.

    ``V`` is a list of rows ``[X, Y, Z, w]`` and ``size`` the largest ``|coordinate|`` in it.
    Returns ``V`` itself when no plane cuts anything, ``[]`` when fewer than 3 vertices are
    left, otherwise a new list of rows (input rows reused as they are, crossings as new tuples).

    Each pass computes exactly what :func:`_clip_plane_array` computes, operation for operation,
    so both paths return the same bits. It is specialised to the six planes of :data:`PLANES`,
    whose coefficients are 0 and +-1: ``n . P`` is one addition, subtraction or copy, and
    ``max |n| = 1``. A plane with no vertex outside it is skipped after one comparison per
    vertex (the pass would change nothing). The per-vertex tolerance ``1e-12 max|P_i|`` and the
    per-crossing size test are only evaluated exactly when a value comes within ``1e-12``
    times a bound on every vertex's size (crossings are convex combinations of vertices, so
    twice ``size`` bounds theirs too, rounding included); otherwise their outcome is known.
    """
    # Wholly inside (the usual case in a scene): every pass would be skipped. The comparisons
    # are exact: x + w rounds to a negative number exactly when x < -w, and so on.
    if all(-w <= x <= w and -w <= y <= w and 0.0 <= z <= w for x, y, z, w in V):
        return V
    rtol = _ON_PLANE_RTOL
    thr = rtol * (2.0 * size)
    for k in range(6):
        if k == 0:
            ds = [v[0] + v[3] for v in V]
        elif k == 1:
            ds = [v[3] - v[0] for v in V]
        elif k == 2:
            ds = [v[1] + v[3] for v in V]
        elif k == 3:
            ds = [v[3] - v[1] for v in V]
        elif k == 4:
            ds = [v[2] for v in V]
        else:
            ds = [v[3] - v[2] for v in V]
        if min(ds) >= 0.0:
            continue                      # all inside: the pass changes nothing
        if min(map(abs, ds)) <= thr:      # a vertex may lie on the plane: the exact test
            ds = [0.0 if abs(d) <= rtol * max(abs(v[0]), abs(v[1]), abs(v[2]), abs(v[3]))
                  else d for d, v in zip(ds, V)]
            if min(ds) >= 0.0:
                continue
        out = []
        push = out.append
        # Edges S -> E, starting with the closing edge V[-1] -> V[0], whose crossing belongs
        # at the end of the output (after V[-1]); every other one right after its S.
        S = V[-1]
        dS = ds[-1]
        closing = None
        first = True
        for E, dE in zip(V, ds):
            if dS * dE < 0.0:
                aS = abs(dS)
                aE = abs(dE)
                s = aS + aE
                S0, S1, S2, S3 = S
                E0, E1, E2, E3 = E
                I = ((aE * S0 + aS * E0) / s, (aE * S1 + aS * E1) / s,
                     (aE * S2 + aS * E2) / s, (aE * S3 + aS * E3) / s)
                # drop a crossing at the 4-D origin (S and E opposite multiples of a point)
                if (abs(I[3]) > thr or abs(I[0]) > thr or abs(I[1]) > thr or abs(I[2]) > thr
                        or max(map(abs, I)) > rtol * max(map(abs, (S0, S1, S2, S3,
                                                                   E0, E1, E2, E3)))):
                    if first:
                        closing = I
                    else:
                        push(I)
            first = False
            if dE >= 0.0:
                push(E)
            S = E
            dS = dE
        if closing is not None:
            push(closing)
        if len(out) < 3:
            return []
        V = out
    return V

