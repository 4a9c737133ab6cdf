"""Q2 written from the exam and the contract alone (not from course_lib)."""

import numpy as np


def _positive(*values):
    for v in values:
        a = np.asarray(v, float)
        if not np.all(np.isfinite(a)) or np.any(a <= 0):
            raise ValueError("expected positive numbers")


def pmt_gain(delta, n_dynodes):
    if np.ndim(delta) != 0 or not np.isfinite(delta) or delta <= 0:
        raise ValueError("delta must be one positive number")
    if isinstance(n_dynodes, bool) or np.ndim(n_dynodes) != 0:
        raise ValueError("n_dynodes must be an integer")
    if float(n_dynodes) != int(n_dynodes) or n_dynodes < 0:
        raise ValueError("n_dynodes must be a non-negative integer")
    gain = 1.0
    for _ in range(int(n_dynodes)):
        gain *= float(delta)
    return gain


def collimator_resolution(d, L, z):
    _positive(d, L)
    if np.any(np.asarray(z, float) < 0):
        raise ValueError("z must be >= 0")
    try:
        d, L, z = np.broadcast_arrays(*(np.asarray(x, float) for x in (d, L, z)))
    except ValueError:
        raise ValueError("shapes do not broadcast") from None
    R = d * (1.0 + z / L)          # similar triangles: R / d = (L + z) / L
    return float(R) if R.ndim == 0 else R


def collimator_length_for_resolution(d, R, z):
    _positive(d, R, z)
    try:
        d, R, z = np.broadcast_arrays(*(np.asarray(x, float) for x in (d, R, z)))
    except ValueError:
        raise ValueError("shapes do not broadcast") from None
    if np.any(R <= d):
        raise ValueError("R must exceed d: no finite hole length reaches it")
    L = z * d / (R - d)
    return float(L) if L.ndim == 0 else L


def ring_hole_positions(pitch, n_rings):
    _positive(pitch)
    if isinstance(n_rings, bool) or float(n_rings) != int(n_rings) or n_rings < 0:
        raise ValueError("n_rings must be a non-negative integer")
    points = [(0.0, 0.0)]
    for k in range(1, int(n_rings) + 1):
        for j in range(8 * k):
            angle = 2 * np.pi * j / (8 * k)
            points.append((k * pitch * np.cos(angle), k * pitch * np.sin(angle)))
    return np.array(points)


def open_fraction(holes_xy, d, L, source_distance, collimator_radius):
    holes = np.asarray(holes_xy, float)
    if holes.ndim != 2 or holes.shape[1] != 2:
        raise ValueError("holes_xy must have shape (n, 2)")
    _positive(d, L, source_distance, collimator_radius)
    r = np.hypot(holes[:, 0], holes[:, 1])
    n_open = np.count_nonzero(r * L / source_distance <= d)
    return float(n_open * (d / 2) ** 2 / collimator_radius ** 2)
