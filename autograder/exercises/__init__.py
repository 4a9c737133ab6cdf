"""The exercise registry: every graded function and choice of the course, by name.

One module per notebook (``q1_imaging.py`` … ``q6_clipping.py``), each defining
``EXERCISES = [Exercise(...), ...]``: per graded name its reference, its cases and its rule.
The folder mirrors ``notebooks/`` so an exercise's rule sits next to its question's name.
"""

from __future__ import annotations

import importlib

from .base import (Case, Exercise, Mismatch, NotPlainData, close, describe, same_choice, to_plain,
                   wrong_shape, wrong_value)

NOTEBOOKS = (
    "q1_imaging",
    "q2_nuclear",
    "q3_marching_cubes",
    "q4_splines",
    "q5_phong",
    "q6_clipping",
)


def _load() -> dict[str, Exercise]:
    registry: dict[str, Exercise] = {}
    for nb in NOTEBOOKS:
        try:
            module = importlib.import_module(f"{__name__}.{nb}")
        except ModuleNotFoundError as exc:  # a question not written yet
            if exc.name == f"{__name__}.{nb}":
                continue
            raise
        for ex in module.EXERCISES:
            if ex.name in registry:
                raise ValueError(f"exercise {ex.name!r} is registered twice")
            if ex.notebook != nb:
                raise ValueError(f"exercise {ex.name!r} is in {nb}.py but names {ex.notebook}")
            registry[ex.name] = ex
    return registry


REGISTRY: dict[str, Exercise] = _load()


def get(name: str) -> Exercise:
    """The exercise called ``name``; ``KeyError`` with the known names otherwise."""
    try:
        return REGISTRY[name]
    except KeyError:
        raise KeyError(f"no exercise {name!r}; known: {sorted(REGISTRY)}") from None


def for_notebook(notebook: str) -> list[Exercise]:
    """The exercises of one notebook, in registry order."""
    return [ex for ex in REGISTRY.values() if ex.notebook == notebook]


__all__ = [
    "Case", "Exercise", "Mismatch", "NotPlainData", "close", "describe", "same_choice", "to_plain",
    "wrong_shape", "wrong_value",
    "NOTEBOOKS", "REGISTRY", "get", "for_notebook",
]
