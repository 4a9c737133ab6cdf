"""Q4 written from the exam's conventions alone (not from course_lib).

p(t) = [t^3, t^2, t, 1] M G with G = [a; b; c; d]: a segment runs from b (t = 0) to c (t = 1).
"""

import numpy as np

_RULES = ("d=b", "d=2c-b", "d=c")


def catmull_rom_basis():
    # p(0) = b, p(1) = c, p'(0) = (c - a)/2, p'(1) = (d - b)/2, solved for the cubic's coefficients
    return 0.5 * np.array([[-1.0, 3.0, -3.0, 1.0],
                           [2.0, -5.0, 4.0, -1.0],
                           [-1.0, 0.0, 1.0, 0.0],
                           [0.0, 2.0, 0.0, 0.0]])


def bspline_basis():
    # the uniform cubic B-spline blending functions, coefficients of t^3 ... 1 per control point
    return np.array([[-1.0, 3.0, -3.0, 1.0],
                     [3.0, -6.0, 3.0, 0.0],
                     [-3.0, 0.0, 3.0, 0.0],
                     [1.0, 4.0, 1.0, 0.0]]) / 6.0


def parameter_row(t, order=0):
    if order not in (0, 1, 2) or isinstance(order, bool):
        raise ValueError("order must be 0, 1 or 2")
    t = np.asarray(t, dtype=float)
    one, zero = np.ones_like(t), np.zeros_like(t)
    rows = {0: [t ** 3, t ** 2, t, one],
            1: [3 * t ** 2, 2 * t, one, zero],
            2: [6 * t, 2 * one, zero, zero]}[order]
    return np.stack(rows, axis=-1)


def spline_eval(M, G, t, order=0):
    M = np.asarray(M, dtype=float)
    G = np.asarray(G, dtype=float)
    if M.shape != (4, 4):
        raise ValueError("M must be 4 x 4")
    if G.ndim != 2 or G.shape[0] != 4:
        raise ValueError("G must have 4 rows")
    return parameter_row(t, order) @ M @ G


def end_rows(M):
    # row k: the k-th derivative of each blending cubic (a column of M) at t = 1
    M = np.asarray(M, dtype=float)
    if M.shape != (4, 4):
        raise ValueError("M must be 4 x 4")
    rows = []
    for k in range(3):
        rows.append([np.polyval(np.polyder(M[:, j], k), 1.0) for j in range(4)])
    return np.array(rows)


def end_derivatives(M, a, b, c, d):
    M = np.asarray(M, dtype=float)
    pts = [np.asarray(p, dtype=float) for p in (a, b, c, d)]
    if M.shape != (4, 4) or len({p.shape for p in pts}) != 1:
        raise ValueError("M must be 4 x 4 and the four points of one shape")
    G = np.stack(pts)                                 # (4, ...) geometry
    out = []
    for order in (0, 1, 2):
        w = parameter_row(1.0, order) @ M             # weights of a, b, c, d at t = 1
        out.append(np.tensordot(w, G, axes=1))
    return tuple(out)


def phantom_point(b, c, rule):
    b = np.asarray(b, dtype=float)
    c = np.asarray(c, dtype=float)
    if rule == "d=b":
        return b.copy()
    if rule == "d=2c-b":
        return 2 * c - b
    if rule == "d=c":
        return c.copy()
    raise ValueError(f"unknown rule {rule!r}")


def sample_curve(points, kind, n_per_segment, end_rule=None):
    P = np.asarray(points, dtype=float)
    bases = {"catmull-rom": catmull_rom_basis, "b-spline": bspline_basis}
    if kind not in bases:
        raise ValueError(f"unknown kind {kind!r}")
    if P.ndim != 2:
        raise ValueError("points must be (m, k)")
    if isinstance(n_per_segment, bool) or int(n_per_segment) != n_per_segment \
            or n_per_segment < 1:
        raise ValueError("n_per_segment must be a positive integer")
    if end_rule is not None:
        if end_rule not in _RULES:
            raise ValueError(f"unknown rule {end_rule!r}")
        if len(P) < 2:
            raise ValueError("need two points to add phantoms")
        first = phantom_point(P[1], P[0], end_rule)
        last = phantom_point(P[-2], P[-1], end_rule)
        P = np.vstack([first, P, last])
    if len(P) < 4:
        raise ValueError("need at least four control points")
    M = bases[kind]()
    n = int(n_per_segment)
    ts = np.arange(n) / n
    pieces = [spline_eval(M, P[i:i + 4], ts) for i in range(len(P) - 3)]
    pieces.append(spline_eval(M, P[-4:], np.array([1.0])))
    return np.vstack(pieces)
