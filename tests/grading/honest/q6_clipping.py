"""Q6 written from the exam's definitions alone (not from course_lib).

View volume in homogeneous screen coordinates: -w <= X <= w, -w <= Y <= w, 0 <= Z <= w, i.e.
six half-spaces n . P >= 0, linear in P, so clipping never divides by w.
"""

import numpy as np

_PLANES = np.array([[1.0, 0, 0, 1], [-1.0, 0, 0, 1], [0, 1.0, 0, 1], [0, -1.0, 0, 1],
                    [0, 0, 1.0, 0], [0, 0, -1.0, 1]])


def _homogeneous(P):
    P = np.asarray(P, dtype=float)
    if P.ndim == 0 or P.shape[-1] != 4:
        raise ValueError("P must have shape (..., 4)")
    if not np.all(np.isfinite(P)):
        raise ValueError("NaN or inf")
    return P


def inside_view_volume(P):
    P = _homogeneous(P)
    X, Y, Z, w = np.moveaxis(P, -1, 0)
    return (-w <= X) & (X <= w) & (-w <= Y) & (Y <= w) & (0 <= Z) & (Z <= w)


def to_screen(P):
    P = _homogeneous(P)
    w = P[..., 3:]
    if np.any(w == 0):
        raise ValueError("w = 0: a point at infinity")
    return P[..., :3] / w


def clip_polygon(P):
    P = _homogeneous(P)
    if P.ndim != 2 or len(P) < 3 or np.any(np.all(P == 0, axis=1)):
        raise ValueError("P must be (n, 4), n >= 3, without zero vertices")
    poly = list(P)
    for plane in _PLANES:
        if not poly:
            break
        out = []
        for k in range(len(poly)):
            S, E = poly[k - 1], poly[k]
            dS, dE = plane @ S, plane @ E
            tol = 1e-12 * max(np.abs(S).max(), np.abs(E).max())
            s_in, e_in = dS >= -tol, dE >= -tol
            if e_in:
                if not s_in and dE > tol:
                    out.append((abs(dE) * S + abs(dS) * E) / (abs(dS) + abs(dE)))
                out.append(E)
            elif s_in and dS > tol:
                out.append((abs(dE) * S + abs(dS) * E) / (abs(dS) + abs(dE)))
        poly = out
    if len(poly) < 3:
        return np.zeros((0, 4))
    return np.array(poly)


def screen_area(P_screen):
    P = np.asarray(P_screen, dtype=float)
    if P.ndim != 2 or P.shape[1] not in (2, 3) or not np.all(np.isfinite(P)):
        raise ValueError("P_screen must be (n, 2) or (n, 3) and finite")
    x, y = P[:, 0], P[:, 1]
    return float(0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def fan_triangulate(m):
    if isinstance(m, bool) or int(m) != m or m < 3:
        raise ValueError("m must be an integer >= 3")
    return np.array([[0, i, i + 1] for i in range(1, int(m) - 1)], dtype=int)


def scanline_span(tri_xy, y):
    T = np.asarray(tri_xy, dtype=float)
    if T.shape != (3, 2) or not np.all(np.isfinite(T)):
        raise ValueError("tri_xy must be (3, 2)")
    if np.ndim(y) != 0 or not np.isfinite(y):
        raise ValueError("y must be one finite number")
    xs = []
    for k in range(3):
        (x0, y0), (x1, y1) = T[k], T[(k + 1) % 3]
        if min(y0, y1) <= y <= max(y0, y1):
            if y0 == y1:
                xs += [x0, x1]
            else:
                xs.append(x0 + (y - y0) * (x1 - x0) / (y1 - y0))
    if not xs:
        return None
    return (float(min(xs)), float(max(xs)))
