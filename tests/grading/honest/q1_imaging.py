"""Q1(c) written from the exam and the contract alone (not from course_lib).

A scanner converts echo delay to depth with its assumed speed: a layer of thickness T and
true speed c takes 2T/c there and back, drawn as c_assumed * (2T/c) / 2 = T c_assumed / c.
"""

import numpy as np


def displayed_thickness(thickness, c_true, c_assumed=1540.0):
    try:
        T, c, ca = np.broadcast_arrays(np.asarray(thickness, float), np.asarray(c_true, float),
                                       np.asarray(c_assumed, float))
    except ValueError as exc:
        raise ValueError(f"shapes do not broadcast: {exc}") from None
    if not (np.all(np.isfinite(T)) and np.all(np.isfinite(c)) and np.all(np.isfinite(ca))):
        raise ValueError("values must be finite")
    if np.any(T < 0):
        raise ValueError("thickness must be >= 0")
    if np.any(c <= 0) or np.any(ca <= 0):
        raise ValueError("speeds must be positive")
    shown = T * ca / c
    return float(shown) if shown.ndim == 0 else shown


def displayed_depths(thicknesses, speeds, c_assumed=1540.0):
    T = np.asarray(thicknesses, float)
    c = np.asarray(speeds, float)
    if T.ndim != 1 or c.ndim != 1 or len(T) != len(c):
        raise ValueError("thicknesses and speeds must be 1-D and of equal length")
    if np.any(T < 0) or np.any(c <= 0) or not np.isfinite(c_assumed) or c_assumed <= 0:
        raise ValueError("negative thickness or non-positive speed")
    depth = 0.0
    out = []
    for t, v in zip(T, c, strict=True):
        depth += t * c_assumed / v
        out.append(depth)
    return np.array(out)


def round_trip_attenuation_db(alpha_db_per_cm_mhz, freq_mhz, thickness_cm):
    a = np.asarray(alpha_db_per_cm_mhz, float)
    t = np.asarray(thickness_cm, float)
    f = np.asarray(freq_mhz, float)
    if a.ndim > 1 or t.ndim > 1 or f.ndim != 0:
        raise ValueError("layers must be scalars or 1-D, the frequency a single number")
    if a.ndim == 1 and t.ndim == 1 and len(a) != len(t):
        raise ValueError("one attenuation per layer")
    if np.any(a < 0) or np.any(t < 0) or f <= 0:
        raise ValueError("negative attenuation or thickness, or non-positive frequency")
    one_way = np.sum(a * t) * float(f)
    return float(2.0 * one_way)
