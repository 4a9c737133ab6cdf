"""Uniform cubic Catmull-Rom splines and B-splines, and how to terminate them (exam Q4).

Every segment of both splines is written in the exam's matrix form

.. math::  \\mathbf p(t) = [t^3\\; t^2\\; t\\; 1]\\, M\\, G, \\qquad 0 \\le t \\le 1,

with the *same* geometry matrix ``G = [a; b; c; d]`` (four consecutive control points, one per
row) and a 4 x 4 basis matrix ``M`` that is the only difference between the two splines (Q4(a)).
A curve of ``N`` segments uses ``N + 3`` points; segment ``i`` takes points ``i .. i+3``. The
curve's last segment runs from (or near) ``b`` to (or near) ``c``, so to carry a curve on to the
last user-given point ``c`` one invents a *phantom* point ``d`` beyond it (Q4(c)): ``d = b``,
``d = 2c - b`` or ``d = c``; at the start the mirror rule invents a point before the first one.
Whether the curve then *reaches* ``c`` depends on the spline and the rule: Catmull-Rom always
does, the B-spline only with ``d = 2c - b`` (with ``d = b`` it stops at ``(b + 2c) / 3``).

Functions of the exercise contract: :func:`catmull_rom_basis`, :func:`bspline_basis`,
:func:`parameter_row`, :func:`end_rows`, :func:`spline_eval`, :func:`end_derivatives`,
:func:`phantom_point`, :func:`sample_curve`. Beyond the contract: :func:`basis_matrix`,
:func:`end_weights`, :func:`extend_with_phantoms`, :func:`segment_geometries`,
:func:`evaluate_curve`, :func:`convex_hull` and :func:`in_convex_hull`. The students' copy of
the library holds only the last two (docs/students-copy.md): its figures draw the curves
through :func:`course_lib.plots.splines.spline_scene`, rounded to display precision, and its
tables of end weights are :mod:`course_lib.spline_weights`.
"""

from __future__ import annotations

import numpy as np

from ._validate import as_float_array, as_int, as_points

__all__ = [
    "KINDS",
    "RULES",
    "basis_matrix",
    "bspline_basis",
    "catmull_rom_basis",
    "convex_hull",
    "end_derivatives",
    "end_rows",
    "end_weights",
    "evaluate_curve",
    "extend_with_phantoms",
    "in_convex_hull",
    "parameter_row",
    "phantom_point",
    "sample_curve",
    "segment_geometries",
    "spline_eval",
]

#: The spline kinds :func:`sample_curve` knows.
KINDS = ("catmull-rom", "b-spline")
#: The end rules of Q4(c): how the phantom point ``d`` is made from ``b`` and ``c``.
RULES = ("d=b", "d=2c-b", "d=c")


# --------------------------------------------------------------------------------------------
# basis matrices and the parameter row


def catmull_rom_basis() -> np.ndarray:
    """The 4 x 4 basis matrix of the uniform Catmull-Rom spline.

    Returns
    -------
    M : ndarray, shape (4, 4)
        ``0.5 * [[-1, 3, -3, 1], [2, -5, 4, -1], [-1, 0, 1, 0], [0, 2, 0, 0]]``, so that
        ``p(t) = [t^3, t^2, t, 1] @ M @ [a; b; c; d]``.

    Notes
    -----
    Q4(a)/(b). The segment interpolates its middle points, ``p(0) = b`` and ``p(1) = c``, with
    tangents ``p'(0) = (c - a) / 2`` and ``p'(1) = (d - b) / 2``: a cubic Hermite segment whose
    tangents are central differences. Its rows at ``t = 1`` are the exam's
    ``[0 0 1 0]``, ``[0 -1/2 0 1/2]`` and ``[-1 4 -5 2]``.

    Examples
    --------
    >>> [1, 1, 1, 1] @ catmull_rom_basis()
    array([0., 0., 1., 0.])
    >>> [6, 2, 0, 0] @ catmull_rom_basis()
    array([-1.,  4., -5.,  2.])
    """
    # written out here, not as a module constant, so that the matrix leaves the students'
    # wheel with the function (docs/students-copy.md)
    return 0.5 * np.array([[-1.0, 3.0, -3.0, 1.0],
                           [2.0, -5.0, 4.0, -1.0],
                           [-1.0, 0.0, 1.0, 0.0],
                           [0.0, 2.0, 0.0, 0.0]])


def bspline_basis() -> np.ndarray:
    """The 4 x 4 basis matrix of the uniform cubic B-spline.

    Returns
    -------
    M : ndarray, shape (4, 4)
        ``(1/6) * [[-1, 3, -3, 1], [3, -6, 3, 0], [-3, 0, 3, 0], [1, 4, 1, 0]]``.

    Notes
    -----
    Q4(a)/(b). The four blending functions are non-negative on ``[0, 1]`` and sum to 1, which
    is why each segment lies in the convex hull of its four control points; the curve is C2.
    At ``t = 1``: ``p = (b + 4c + d) / 6``, ``p' = (d - b) / 2``, ``p'' = b - 2c + d``.

    Examples
    --------
    >>> np.round(6 * ([1, 1, 1, 1] @ bspline_basis()), 12)   # up to round-off
    array([0., 1., 4., 1.])
    """
    return np.array([[-1.0, 3.0, -3.0, 1.0],
                     [3.0, -6.0, 3.0, 0.0],
                     [-3.0, 0.0, 3.0, 0.0],
                     [1.0, 4.0, 1.0, 0.0]]) / 6.0


def basis_matrix(kind: str) -> np.ndarray:
    """The basis matrix of ``kind`` (``"catmull-rom"`` or ``"b-spline"``)."""
    kind = _check_kind(kind)
    return catmull_rom_basis() if kind == "catmull-rom" else bspline_basis()


def parameter_row(t, order: int = 0) -> np.ndarray:
    """The parameter row ``[t^3, t^2, t, 1]`` or its first or second derivative in ``t``.

    Parameters
    ----------
    t : float or array_like
        Parameter value(s); any real number (values outside ``[0, 1]`` extrapolate the cubic).
    order : {0, 1, 2}
        0 for ``[t^3, t^2, t, 1]``, 1 for ``[3t^2, 2t, 1, 0]``, 2 for ``[6t, 2, 0, 0]``.

    Returns
    -------
    T : ndarray, shape ``np.shape(t) + (4,)``
        ``(4,)`` for a scalar ``t``, ``(n, 4)`` for ``n`` values.

    Raises
    ------
    ValueError
        If ``t`` is not numeric/finite or ``order`` is not 0, 1 or 2.

    Notes
    -----
    Q4(b): at ``t = 1`` the three rows are ``[1 1 1 1]``, ``[3 2 1 0]`` and ``[6 2 0 0]``.

    Examples
    --------
    >>> parameter_row(1.0, order=2)
    array([6., 2., 0., 0.])
    >>> parameter_row([0.0, 0.5]).shape
    (2, 4)
    """
    t = as_float_array(t, "t")
    order = _check_order(order)
    one, zero = np.ones_like(t), np.zeros_like(t)
    if order == 0:
        cols = (t**3, t**2, t, one)
    elif order == 1:
        cols = (3.0 * t**2, 2.0 * t, one, zero)
    else:
        cols = (6.0 * t, 2.0 * one, zero, zero)
    return np.stack(cols, axis=-1)


# --------------------------------------------------------------------------------------------
# one segment


def spline_eval(M, G, t, order: int = 0):
    """Position (order 0) or derivative (order 1, 2) of one segment, ``T(t) @ M @ G``.

    Parameters
    ----------
    M : array_like, shape (4, 4)
        Basis matrix (:func:`catmull_rom_basis`, :func:`bspline_basis` or any other).
    G : array_like, shape (4, k) or (4,)
        Geometry matrix: the four control points ``a, b, c, d`` as rows (a ``(4,)`` vector is a
        scalar-valued curve).
    t : float or array_like, shape (n,)
        Parameter value(s).
    order : {0, 1, 2}
        Derivative order with respect to ``t``.

    Returns
    -------
    p : ndarray
        ``(k,)`` for a scalar ``t``, ``(n, k)`` for ``n`` values of ``t`` (a Python float /
        ``(n,)`` when ``G`` is ``(4,)``).

    Raises
    ------
    ValueError
        If ``M`` is not 4 x 4, ``G`` does not have 4 rows, or ``order`` is not 0, 1 or 2.

    Notes
    -----
    Q4(b): ``p(t) = [t^3 t^2 t 1] M G``; the derivatives only change the parameter row.

    Examples
    --------
    >>> G = np.eye(4)          # a, b, c, d as unit vectors: the answer is the weight row
    >>> spline_eval(catmull_rom_basis(), G, 1.0, order=1)
    array([ 0. , -0.5,  0. ,  0.5])
    """
    M = _check_basis(M)
    G = _check_geometry(G)
    row = parameter_row(t, order)
    out = row @ M @ G
    return float(out) if out.ndim == 0 else out


def end_rows(M) -> np.ndarray:
    """The weights of ``a, b, c, d`` in ``p``, ``p'`` and ``p''`` at the end ``t = 1``.

    Parameters
    ----------
    M : array_like, shape (4, 4)
        Any basis matrix (Catmull-Rom, B-spline, Bezier, Hermite-like or none of these) in the
        convention ``p(t) = [t^3, t^2, t, 1] @ M @ G``.

    Returns
    -------
    W : ndarray, shape (3, 4)
        Row ``k`` is ``parameter_row(1, k) @ M``, i.e. ``[1 1 1 1] M``, ``[3 2 1 0] M`` and
        ``[6 2 0 0] M``; column ``j`` belongs to control point ``j`` (``a, b, c, d``), so
        ``W @ G`` stacks ``p(1), p'(1), p''(1)``.

    Raises
    ------
    ValueError
        If ``M`` is not a finite 4 x 4 array.

    Notes
    -----
    Q4(b): multiplying the parameter rows into ``M`` before touching the points is the step the
    examiners saw candidates slip on. For Catmull-Rom the rows are
    ``[[0, 0, 1, 0], [0, -1/2, 0, 1/2], [-1, 4, -5, 2]]``; for the B-spline
    ``[[0, 1/6, 4/6, 1/6], [0, -1/2, 0, 1/2], [0, 1, -2, 1]]``.

    Examples
    --------
    >>> end_rows(np.eye(4))            # the parameter rows themselves
    array([[1., 1., 1., 1.],
           [3., 2., 1., 0.],
           [6., 2., 0., 0.]])
    >>> end_rows(catmull_rom_basis())[2]
    array([-1.,  4., -5.,  2.])
    """
    M = _check_basis(M)
    return np.stack([parameter_row(1.0, k) @ M for k in range(3)])


def end_derivatives(M, a, b, c, d):
    """``(p, p', p'')`` of the segment ``G = [a; b; c; d]`` at its end ``t = 1``.

    Parameters
    ----------
    M : array_like, shape (4, 4)
        Basis matrix.
    a, b, c, d : array_like, shape (..., k)
        The four control points, all of the same shape (one point each, or batches).

    Returns
    -------
    p, p1, p2 : ndarray, shape (..., k)
        Position, first and second derivative with respect to ``t`` at ``t = 1``.

    Raises
    ------
    ValueError
        If ``M`` is not 4 x 4 or the points are not of one common shape ``(..., k)``.

    Notes
    -----
    Q4(b). Catmull-Rom: ``p = c``, ``p' = (d - b)/2``, ``p'' = -a + 4b - 5c + 2d``.
    B-spline: ``p = (b + 4c + d)/6``, ``p' = (d - b)/2``, ``p'' = b - 2c + d``.

    Examples
    --------
    >>> a, b, c, d = np.eye(4)
    >>> p, p1, p2 = end_derivatives(catmull_rom_basis(), a, b, c, d)
    >>> p2
    array([-1.,  4., -5.,  2.])
    """
    W = end_rows(M)
    G = _stack_points((a, b, c, d), ("a", "b", "c", "d"))
    p, p1, p2 = (np.einsum("j,...jk->...k", W[k], G) for k in range(3))
    return p, p1, p2


# --------------------------------------------------------------------------------------------
# end rules


def phantom_point(b, c, rule: str) -> np.ndarray:
    """The invented point ``d`` beyond the last given point ``c`` (its neighbour being ``b``).

    Parameters
    ----------
    b, c : array_like, shape (..., k)
        The last two given points (same shape). For the *start* of a curve pass the second
        point as ``b`` and the first as ``c``: the mirror rule makes the point before the first.
    rule : {"d=b", "d=2c-b", "d=c"}
        ``"d=b"`` folds back onto ``b``, ``"d=2c-b"`` continues the line ``b -> c`` by the same
        step, ``"d=c"`` repeats ``c``.

    Returns
    -------
    d : ndarray, same shape as ``b``

    Raises
    ------
    ValueError
        For an unknown rule name or points of different shapes.

    Notes
    -----
    Q4(c), Fig. 1(a) is ``d = b`` and Fig. 1(b) is ``d = 2c - b``.

    Examples
    --------
    >>> phantom_point([0.0, 0.0], [1.0, 2.0], "d=2c-b")
    array([2., 4.])
    """
    rule = _check_rule(rule)
    b, c = _same_shape(b, c, ("b", "c"))
    if rule == "d=b":
        return b.copy()
    if rule == "d=2c-b":
        return 2.0 * c - b
    return c.copy()


def end_weights(M, rule: str) -> np.ndarray:
    """Weights of ``a, b, c`` in ``p, p', p''`` at ``t = 1`` once ``d`` follows ``rule``.

    Parameters
    ----------
    M : array_like, shape (4, 4)
    rule : {"d=b", "d=2c-b", "d=c", "free"}
        With ``"free"`` the weights of ``d`` are kept (the result is :func:`end_rows`).

    Returns
    -------
    W : ndarray, shape (3, 4)
        Rows for ``p, p', p''``; columns for ``a, b, c, d`` (the ``d`` column is zero unless
        ``rule == "free"``).

    Notes
    -----
    Q4(c)(i): substitute the rule into the Q4(b) rows, e.g. Catmull-Rom with ``d = b`` gives
    ``p'' = -a + 6b - 5c``.

    Examples
    --------
    >>> end_weights(bspline_basis(), "d=2c-b")
    array([[ 0.,  0.,  1.,  0.],
           [ 0., -1.,  1.,  0.],
           [ 0.,  0.,  0.,  0.]])
    """
    W = end_rows(M)
    if rule != "free":
        _apply_rule(W, _check_rule(rule))
    W[np.abs(W) < 1e-12] = 0.0  # round-off of the rational weights, and -0.0
    return W


def _apply_rule(W, rule):
    wd = W[:, 3].copy()
    W[:, 3] = 0.0
    if rule == "d=b":
        W[:, 1] += wd
    elif rule == "d=2c-b":
        W[:, 1] -= wd
        W[:, 2] += 2.0 * wd
    else:
        W[:, 2] += wd


def extend_with_phantoms(points, rule: str) -> np.ndarray:
    """``points`` with one phantom point added before the first and after the last.

    The end phantom is ``phantom_point(points[-2], points[-1], rule)``; the start phantom is
    the mirror, ``phantom_point(points[1], points[0], rule)``. Shape ``(m, k) -> (m + 2, k)``.

    Notes
    -----
    Q4(c): with phantoms at both ends a curve of ``m`` given points has ``m - 1`` segments, one
    per pair of neighbouring given points. The Catmull-Rom curve then runs from ``points[0]``
    to ``points[-1]``; the B-spline does so only with ``d = 2c - b`` (with ``d = b`` it stops
    two thirds of the way from ``points[-2]`` to ``points[-1]``).
    """
    P = _check_curve_points(points, _check_rule(rule))
    start = phantom_point(P[1], P[0], rule)
    end = phantom_point(P[-2], P[-1], rule)
    return np.vstack([start, P, end])


# --------------------------------------------------------------------------------------------
# multi-segment curves


def segment_geometries(points, end_rule: str | None = None) -> np.ndarray:
    """The geometry matrices of every segment: ``(N, 4, k)`` for ``N = len(points) - 3``.

    With ``end_rule`` the points are first extended by :func:`extend_with_phantoms`, so there
    are ``len(points) - 1`` segments.

    Notes
    -----
    Q4(a): consecutive segments share three control points, so ``N + 3`` points make ``N``
    segments.
    """
    P = _check_curve_points(points, end_rule)
    if end_rule is not None:
        P = extend_with_phantoms(P, end_rule)
    idx = np.arange(P.shape[0] - 3)[:, None] + np.arange(4)
    return P[idx]


def evaluate_curve(points, kind: str, u, order: int = 0, end_rule: str | None = None):
    """Position or derivative of a multi-segment curve at global parameter(s) ``u``.

    Parameters
    ----------
    points : array_like, shape (m, k)
        Control points (``m >= 4``, or ``m >= 2`` with an ``end_rule``).
    kind : {"catmull-rom", "b-spline"}
    u : float or array_like
        Global parameter in ``[0, N]``: segment ``i = floor(u)`` (the last segment for
        ``u = N``) at local ``t = u - i``.
    order : {0, 1, 2}
    end_rule : {None, "d=b", "d=2c-b", "d=c"}

    Returns
    -------
    ndarray, shape ``np.shape(u) + (k,)``

    Raises
    ------
    ValueError
        For bad points, kind, rule, order, or ``u`` outside ``[0, N]``.
    """
    M = basis_matrix(kind)
    order = _check_order(order)
    Gs = segment_geometries(points, end_rule)
    n_seg = Gs.shape[0]
    u = as_float_array(u, "u")
    if np.any((u < 0) | (u > n_seg)):
        raise ValueError(f"u must lie in [0, {n_seg}] for a curve of {n_seg} segments")
    i = np.minimum(np.floor(u).astype(int), n_seg - 1)
    t = u - i
    rows = parameter_row(t, order) @ M  # (..., 4)
    return np.einsum("...j,...jk->...k", rows, Gs[i])


def sample_curve(points, kind: str, n_per_segment: int, end_rule: str | None = None):
    """A polyline through every segment of a multi-segment Catmull-Rom or B-spline curve.

    Parameters
    ----------
    points : array_like, shape (m, k)
        Control points. Without ``end_rule`` the curve has ``N = m - 3`` segments (``m >= 4``);
        with one it has ``N = m - 1`` (``m >= 2``).
    kind : {"catmull-rom", "b-spline"}
    n_per_segment : int
        Samples per segment (``>= 1``): segment ``i`` is sampled at
        ``t = 0, 1/n, ..., (n-1)/n``, and the curve's very end ``t = 1`` of the last segment
        is appended.
    end_rule : {None, "d=b", "d=2c-b", "d=c"}
        When given, a phantom point is added at each end (:func:`extend_with_phantoms`), which
        gives one segment per pair of neighbouring points. The curve then reaches the first and
        last points for Catmull-Rom (every rule) and for the B-spline with ``"d=2c-b"`` only.

    Returns
    -------
    xy : ndarray, shape (N * n_per_segment + 1, k)

    Raises
    ------
    ValueError
        Unknown kind or rule, ``points`` not ``(m, k)``, too few points, ``n_per_segment < 1``.

    Notes
    -----
    Q4(a) and Q4(c): segment ``i`` uses ``G = points[i:i+4]`` and ``p(t) = T(t) M G``.

    Examples
    --------
    >>> P = [[0.0, 0.0], [1.0, 0.0], [2.0, 1.0], [3.0, 1.0]]
    >>> sample_curve(P, "catmull-rom", 2)      # one segment, from b to c
    array([[1. , 0. ],
           [1.5, 0.5],
           [2. , 1. ]])
    """
    M = basis_matrix(kind)
    n = as_int(n_per_segment, "n_per_segment", minimum=1)
    Gs = segment_geometries(points, end_rule)
    n_seg = Gs.shape[0]
    t = np.arange(n) / n
    rows = parameter_row(t) @ M  # (n, 4)
    body = np.einsum("sj,ijk->isk", rows, Gs).reshape(n_seg * n, -1)
    last = parameter_row(1.0) @ M @ Gs[-1]
    return np.vstack([body, last])


# --------------------------------------------------------------------------------------------
# convex hull (2-D)


def convex_hull(points) -> np.ndarray:
    """The convex hull of 2-D points by Andrew's monotone chain, counter-clockwise.

    Parameters
    ----------
    points : array_like, shape (m, 2)

    Returns
    -------
    hull : ndarray, shape (h, 2)
        Hull vertices counter-clockwise without repeating the first; collinear points on an
        edge are dropped. ``h`` is 1 or 2 for coincident or collinear input.

    Notes
    -----
    Q4(a): every B-spline segment lies in the convex hull of its four control points (and so
    the whole curve lies in the hull of all its control points).

    Examples
    --------
    >>> convex_hull([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5]])
    array([[0., 0.],
           [1., 0.],
           [1., 1.],
           [0., 1.]])
    """
    P = as_points(points, 2, "points", min_count=1)
    P = np.unique(P, axis=0)  # sorted by x, then y
    if len(P) <= 2:
        return P

    def half(seq):
        chain: list[np.ndarray] = []
        for p in seq:
            while len(chain) >= 2 and _cross(chain[-2], chain[-1], p) <= 0:
                chain.pop()
            chain.append(p)
        return chain

    lower, upper = half(P), half(P[::-1])
    hull = np.array(lower[:-1] + upper[:-1])
    return hull


def in_convex_hull(query, hull, tol: float = 1e-9) -> np.ndarray:
    """Whether each 2-D point of ``query`` lies in the convex polygon ``hull`` (CCW).

    ``hull`` as returned by :func:`convex_hull`; a point within ``tol`` (relative to the hull's
    size) of an edge counts as inside. Returns a bool array of ``query``'s leading shape.
    """
    Q = as_float_array(query, "query")
    if Q.ndim == 0 or Q.shape[-1] != 2:
        raise ValueError(f"query must have shape (..., 2), got shape {Q.shape}")
    H = as_points(hull, 2, "hull", min_count=1)
    scale = max(1.0, float(np.ptp(H, axis=0).max()) if len(H) > 1 else 1.0)
    eps = tol * scale
    if len(H) == 1:
        return np.linalg.norm(Q - H[0], axis=-1) <= eps
    if len(H) == 2:
        e = H[1] - H[0]
        s = np.clip(((Q - H[0]) @ e) / (e @ e), 0.0, 1.0)
        return np.linalg.norm(Q - H[0] - s[..., None] * e, axis=-1) <= eps
    E = np.roll(H, -1, axis=0) - H                     # edges (h, 2)
    R = Q[..., None, :] - H                            # (..., h, 2)
    cross = E[:, 0] * R[..., 1] - E[:, 1] * R[..., 0]  # left of every CCW edge
    return np.all(cross >= -eps * np.linalg.norm(E, axis=1), axis=-1)


# --------------------------------------------------------------------------------------------
# validation helpers


def _cross(o, a, b) -> float:
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def _check_order(order) -> int:
    value = as_int(order, "order")
    if value not in (0, 1, 2):
        raise ValueError(f"order must be 0, 1 or 2, got {value}")
    return value


def _check_kind(kind) -> str:
    if not isinstance(kind, str) or kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    return kind


def _check_rule(rule) -> str:
    if not isinstance(rule, str) or rule not in RULES:
        raise ValueError(f"rule must be one of {RULES}, got {rule!r}")
    return rule


def _check_basis(M) -> np.ndarray:
    M = as_float_array(M, "M")
    if M.shape != (4, 4):
        raise ValueError(f"M must be a 4 x 4 basis matrix, got shape {M.shape}")
    return M


def _check_geometry(G) -> np.ndarray:
    G = as_float_array(G, "G")
    if G.ndim not in (1, 2) or G.shape[0] != 4 or (G.ndim == 2 and G.shape[1] == 0):
        raise ValueError(f"G must have shape (4, k) (four control points as rows), "
                         f"got shape {G.shape}")
    return G


def _check_curve_points(points, end_rule) -> np.ndarray:
    if end_rule is not None:
        _check_rule(end_rule)
    need = 4 if end_rule is None else 2
    arr = as_float_array(points, "points")
    if arr.ndim != 2 or arr.shape[1] < 1:
        raise ValueError(f"points must have shape (m, k), got shape {arr.shape}")
    if arr.shape[0] < need:
        why = "with an end rule" if end_rule is not None else "without an end rule"
        raise ValueError(f"points needs at least {need} points {why}, got {arr.shape[0]}")
    return arr


def _same_shape(b, c, names):
    b = as_float_array(b, names[0])
    c = as_float_array(c, names[1])
    if b.shape != c.shape:
        raise ValueError(f"{names[0]} and {names[1]} must have the same shape, "
                         f"got {b.shape} and {c.shape}")
    if b.ndim == 0:
        raise ValueError(f"{names[0]} and {names[1]} must be points of shape (..., k)")
    return b, c


def _stack_points(pts, names) -> np.ndarray:
    arrs = [as_float_array(p, n) for p, n in zip(pts, names)]
    shape = arrs[0].shape
    for arr, n in zip(arrs, names):
        if arr.shape != shape:
            raise ValueError(f"a, b, c and d must have the same shape; {names[0]} has "
                             f"{shape} but {n} has {arr.shape}")
    if len(shape) == 0:
        raise ValueError("a, b, c and d must be points of shape (..., k), got scalars")
    return np.stack(arrs, axis=-2)
