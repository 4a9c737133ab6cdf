"""Input validation shared by every ``course_lib`` module.

Each helper turns its argument into a float64 NumPy array (or a Python float) and raises a
``ValueError`` that names the argument and says what was wrong, so that a student calling a
reference function with a bad argument learns why at once.
"""

from __future__ import annotations

import numpy as np


def as_float_array(x, name: str) -> np.ndarray:
    """``x`` as a float64 array; ``ValueError`` if it is not numeric or holds NaN/inf."""
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numeric, got {type(x).__name__}") from exc
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite (no NaN or inf)")
    return arr


def as_vectors(x, dim: int, name: str) -> np.ndarray:
    """``x`` as float64 of shape ``(..., dim)``; ``ValueError`` for any other last axis."""
    arr = as_float_array(x, name)
    if arr.ndim == 0 or arr.shape[-1] != dim:
        raise ValueError(f"{name} must have shape (..., {dim}), got shape {arr.shape}")
    return arr


def as_points(x, dim: int, name: str, min_count: int = 1) -> np.ndarray:
    """``x`` as float64 of shape ``(n, dim)`` with ``n >= min_count``."""
    arr = as_float_array(x, name)
    if arr.ndim != 2 or arr.shape[1] != dim:
        raise ValueError(f"{name} must have shape (n, {dim}), got shape {arr.shape}")
    if arr.shape[0] < min_count:
        raise ValueError(f"{name} needs at least {min_count} points, got {arr.shape[0]}")
    return arr


def as_positive(x, name: str, allow_zero: bool = False) -> np.ndarray:
    """``x`` as float64 with every element > 0 (or >= 0 when ``allow_zero``)."""
    arr = as_float_array(x, name)
    bad = arr < 0 if allow_zero else arr <= 0
    if np.any(bad):
        kind = "non-negative" if allow_zero else "positive"
        raise ValueError(f"{name} must be {kind}, got {arr if arr.ndim == 0 else arr[bad][0]}")
    return arr


def as_scalar(x, name: str) -> float:
    """``x`` as a Python float; ``ValueError`` if it is not a single finite number."""
    arr = as_float_array(x, name)
    if arr.ndim != 0:
        raise ValueError(f"{name} must be a single number, got shape {arr.shape}")
    return float(arr)


def as_int(x, name: str, minimum: int | None = None) -> int:
    """``x`` as a Python int (integral floats accepted); ``ValueError`` below ``minimum``."""
    if isinstance(x, (bool, np.bool_)):
        raise ValueError(f"{name} must be an integer, got a bool")
    try:
        value = int(x)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an integer, got {x!r}") from exc
    if value != x:
        raise ValueError(f"{name} must be an integer, got {x!r}")
    if minimum is not None and value < minimum:
        raise ValueError(f"{name} must be at least {minimum}, got {value}")
    return value
