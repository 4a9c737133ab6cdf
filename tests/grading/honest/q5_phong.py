"""Q5 written from the exam's equations alone (not from course_lib)."""

import numpy as np


def _vectors(x, name):
    x = np.asarray(x, dtype=float)
    if x.ndim == 0 or x.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3)")
    if not np.all(np.isfinite(x)):
        raise ValueError(f"{name} holds NaN or inf")
    return x


def _dot(a, b):
    return np.sum(a * b, axis=-1)


def normalize(v):
    v = np.asarray(v, dtype=float)
    if v.ndim == 0:
        raise ValueError("a vector is needed, not a number")
    if not np.all(np.isfinite(v)):
        raise ValueError("NaN or inf")
    size = np.sqrt(np.sum(v * v, axis=-1, keepdims=True))
    if np.any(size == 0):
        raise ValueError("zero-length vector")
    return v / size


def reflect(L, N):
    L = _vectors(L, "L")
    N = normalize(_vectors(N, "N"))
    return 2 * _dot(L, N)[..., None] * N - L


def _check_coefficients(Ia, ka, Ip, kd, ks, n):
    if min(Ia, ka, Ip, kd, ks) < 0:
        raise ValueError("negative coefficient")
    if not n > 0:
        raise ValueError("n must be positive")


def _shade(colour, Ia, ka, Ip, kd, ks, n, L, N, V, highlight):
    _check_coefficients(Ia, ka, Ip, kd, ks, n)
    L = normalize(_vectors(L, "L"))
    N = normalize(_vectors(N, "N"))
    V = normalize(_vectors(V, "V"))
    LN = _dot(L, N)
    spec = np.where(LN > 0, np.maximum(highlight(L, N, V), 0.0) ** n, 0.0)
    c = np.asarray(colour, dtype=float)
    if c.ndim == 0:
        c = c * np.ones(3)
    return c * (Ia * ka + Ip * kd * np.maximum(LN, 0.0))[..., None] + (Ip * ks * spec)[..., None]


def phong(colour, Ia, ka, Ip, kd, ks, n, L, N, V):
    return _shade(colour, Ia, ka, Ip, kd, ks, n, L, N, V,
                  lambda L, N, V: _dot(2 * _dot(L, N)[..., None] * N - L, V))


def halfway(L, V):
    s = normalize(_vectors(L, "L")) + normalize(_vectors(V, "V"))
    size = np.sqrt(_dot(s, s))[..., None]
    if np.any(size < 1e-12):
        raise ValueError("V = -L: no half-way vector")
    return s / size


def blinn_phong(colour, Ia, ka, Ip, kd, ks, n, L, N, V):
    return _shade(colour, Ia, ka, Ip, kd, ks, n, L, N, V,
                  lambda L, N, V: _dot(N, halfway(L, V)))
