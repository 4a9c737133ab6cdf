"""Q5: illumination and reflection, the Phong model (notebook ``q5_phong``).

Visible cases carry the exam's Q5(b): ``L`` along ``(1, -1, 1)``, ``N = (0, 1/2, sqrt(3)/2)``,
``V = (0, 1, 0)``, ``n = 10``, a blue surface with ``Ia ka = Ip kd = 0.5`` and ``Ip ks = 1``,
whose Phong intensity is ``(0.0931, 0.0931, 0.699)``. Hidden cases stress what the examiners
saw go wrong: vectors that are not unit length (forgetting to normalise was the commonest
mistake), batches, lights behind the surface and at grazing incidence (no specular term),
reflections pointing away from the viewer (``max(R.V, 0)``), per-point colour arrays, and bad
input that must raise ``ValueError``.
"""

from __future__ import annotations

import numpy as np

from course_lib import shading

from ..model import CellKind
from .base import Case, Exercise, close, number_item

NB = "q5_phong"
_COMPARE = close(rtol=1e-6, atol=1e-9)

_EXAM = shading.EXAM_Q5B
_L = np.array(_EXAM["L"], dtype=float)
_N = np.array(_EXAM["N"], dtype=float)
_V = np.array(_EXAM["V"], dtype=float)
_COEF = (np.array(_EXAM["colour"]), _EXAM["Ia"], _EXAM["ka"], _EXAM["Ip"], _EXAM["kd"],
         _EXAM["ks"], _EXAM["n"])


def _random_vectors(rng, shape=(), scale=(0.2, 5.0)):
    """Random directions with random, non-unit lengths."""
    v = rng.normal(size=(*shape, 3))
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    return v * rng.uniform(*scale, size=(*shape, 1))


def _lit_pair(rng, lit=True):
    """``(L, N)`` with ``L.N > 0.1`` (lit) or ``L.N < -0.1`` (light behind), non-unit."""
    while True:
        L, N = _random_vectors(rng), _random_vectors(rng)
        c = (L @ N) / np.linalg.norm(L) / np.linalg.norm(N)
        if (c > 0.1) if lit else (c < -0.1):
            return L, N


def _coefficients(rng):
    return (rng.uniform(0, 1, 3), float(rng.uniform(0.2, 2)), float(rng.uniform(0, 1)),
            float(rng.uniform(0.2, 2)), float(rng.uniform(0, 1)), float(rng.uniform(0, 1)),
            float(rng.choice([1.0, 2.0, 5.0, 10.0, 37.5, 100.0])))


# --------------------------------------------------------------------------------------------


def _normalize_cases(rng):
    yield Case(args=(_L,), label="exam Q5(b): L = (1, -1, 1) becomes (1, -1, 1)/sqrt(3)",
               visible=True)
    yield Case(args=(np.array([[3.0, 4.0, 0.0], [0.0, 0.0, -2.0]]),),
               label="batch of 2 vectors (3, 4, 0) and (0, 0, -2)", visible=True)
    yield Case(args=(np.array([0.0, 0.0, 0.0]),), label="zero-length vector", visible=True,
               raises=ValueError)
    yield Case(args=(_random_vectors(rng, scale=(1e-3, 1e3)),), label="random vector")
    n = int(rng.integers(2, 20))
    yield Case(args=(_random_vectors(rng, (n,), scale=(1e-3, 1e3)),),
               label=f"batch of {n} vectors of very different lengths")
    yield Case(args=(_random_vectors(rng, (2, 4)),), label="batch of shape (2, 4, 3)")
    yield Case(args=(_random_vectors(rng, scale=(5e-9, 2e-8)),),
               label="a very short (but non-zero) vector")
    bad = _random_vectors(rng, (4,))
    bad[2] = 0.0
    yield Case(args=(bad,), label="batch with one zero-length vector", raises=ValueError)


def _reflect_cases(rng):
    Lu = _L / np.linalg.norm(_L)
    yield Case(args=(np.array([1.0, 1.0, 0.0]) / np.sqrt(2), np.array([0.0, 1.0, 0.0])),
               label="45 degrees onto the floor comes off at 45 degrees", visible=True)
    yield Case(args=(np.array([1.0, 2.0, 2.0]) / 3.0, np.array([0.0, 0.0, 5.0])),
               label="unit L = (1, 2, 2)/3 about N = (0, 0, 5): N must be normalised",
               visible=True)
    # hidden: the exam's vectors (Q5(b) asks for R.V by hand, so no visible check gives it
    # away), at random lengths so that the answer is not fixed (R keeps the length of L)
    yield Case(args=(Lu * rng.uniform(0.5, 3.0), _N * rng.uniform(0.5, 3.0)),
               label="exam Q5(b): L and N along the exam's directions, at random lengths")
    for _ in range(3):
        L, N = _random_vectors(rng, scale=(1, 1)), _random_vectors(rng, scale=(1, 1))
        yield Case(args=(L, N), label="random unit L and N")
    L, N = _random_vectors(rng, scale=(1, 1)), _random_vectors(rng)
    yield Case(args=(L, N), label="unit L, N not unit length (normalise N)")
    L, N = _random_vectors(rng), _random_vectors(rng, scale=(1, 1))
    yield Case(args=(L, N), label="L not unit length (R keeps the length of L)")
    n = int(rng.integers(2, 12))
    yield Case(args=(_random_vectors(rng, (n,)), _random_vectors(rng, (n,))),
               label=f"batch of {n} (L, N) pairs, not unit length")
    yield Case(args=(_random_vectors(rng, (n,)), _random_vectors(rng)),
               label=f"batch of {n} lights, one normal")
    N = _random_vectors(rng, scale=(1, 1))
    yield Case(args=(-N * 2.0, N), label="L along -N (light behind: R = L)")
    yield Case(args=(Lu, np.zeros(3)), label="zero-length normal", raises=ValueError)
    yield Case(args=(np.array([1.0, 0.0]), np.array([0.0, 1.0])), label="2-D vectors",
               raises=ValueError)


def _halfway_cases(rng):
    yield Case(args=(_L / np.linalg.norm(_L), _V), label="exam Q5: unit L and V", visible=True)
    yield Case(args=(_L, _V), label="exam Q5: L = (1, -1, 1) not yet normalised", visible=True)
    for _ in range(3):
        yield Case(args=(_random_vectors(rng), _random_vectors(rng)),
                   label="random L and V, not unit length")
    n = int(rng.integers(2, 12))
    yield Case(args=(_random_vectors(rng, (n,)), _random_vectors(rng, (n,))),
               label=f"batch of {n} (L, V) pairs")
    yield Case(args=(_random_vectors(rng, (n,)), _random_vectors(rng)),
               label=f"batch of {n} lights, one viewer")
    v = _random_vectors(rng)
    yield Case(args=(v, -3.0 * v), label="V = -L: no half-way vector", raises=ValueError)
    yield Case(args=(np.zeros(3), _V), label="zero-length L", raises=ValueError)


def _model_cases(rng):
    yield Case(args=(*_COEF, _L, _N, _V), visible=True,
               label="the exam's Q5(b) vectors and coefficients")
    yield Case(args=(*_COEF, _L / np.linalg.norm(_L), _N, _V), visible=True,
               label="exam Q5(b) with L already unit length")
    yield Case(args=(*_COEF, _N, _N, _N), visible=True,
               label="light and viewer along the normal: ambient + diffuse + full highlight")
    yield Case(args=(*_COEF, _L, _N, np.zeros(3)), visible=True,
               label="zero-length V", raises=ValueError)
    for _ in range(4):
        L, N = _lit_pair(rng)
        yield Case(args=(*_coefficients(rng), L, N, _random_vectors(rng)),
                   label="random lit point, L, N, V not unit length")
    L, N = _lit_pair(rng)
    V = -shading.reflect(shading.normalize(L), N) * 2.5
    yield Case(args=(*_coefficients(rng), L, N, V),
               label="viewer opposite the mirror direction (R.V < 0 gives no highlight)")
    for _ in range(2):
        L, N = _lit_pair(rng, lit=False)
        yield Case(args=(*_coefficients(rng), L, N, _random_vectors(rng)),
                   label="light behind the surface (L.N < 0): ambient only")
    yield Case(args=(*_coefficients(rng), np.array([2.0, 0.0, 0.0]), np.array([0.0, 0.0, 3.0]),
                     np.array([-1.0, 0.0, 0.3])),
               label="grazing light (L.N = 0): no specular even near the mirror direction")
    n = int(rng.integers(3, 15))
    yield Case(args=(*_coefficients(rng), _random_vectors(rng, (n,)),
                     _random_vectors(rng, (n,)), _random_vectors(rng, (n,))),
               label=f"batch of {n} points (some lit, some not), one colour")
    coef = list(_coefficients(rng))
    coef[0] = rng.uniform(0, 1, (n, 3))
    yield Case(args=(*coef, _random_vectors(rng), _random_vectors(rng, (n,)),
                     _random_vectors(rng)),
               label=f"colour array (n, 3) with {n} normals, one light and viewer")
    coef = list(_coefficients(rng))
    coef[0] = rng.uniform(0, 1, (n, 3))
    L, N = _lit_pair(rng)
    yield Case(args=(*coef, L, N, _random_vectors(rng)),
               label=f"{n} colours for one lit point")
    coef = list(_coefficients(rng))
    coef[0] = 0.5
    L, N = _lit_pair(rng)
    yield Case(args=(*coef, L, N, _random_vectors(rng)), label="a scalar colour (grey)")
    yield Case(args=(*_COEF, np.zeros(3), _N, _V), label="zero-length L", raises=ValueError)
    yield Case(args=(*_COEF, _L, np.zeros(3), _V), label="zero-length N", raises=ValueError)
    yield Case(args=(*_COEF, _L[:2], _N[:2], _V[:2]), label="2-D vectors", raises=ValueError)


def _function(name, reference, cases, description):
    return Exercise(name=name, notebook=NB, reference=reference,
                    cases=cases, compare=_COMPARE,
                    description=description)


_choices = ("a", "b", "c", "d")

EXERCISES = [
    _function("normalize", shading.normalize, _normalize_cases,
              "Q5(b) unit vectors along the last axis"),
    _function("reflect", shading.reflect, _reflect_cases,
              "Q5(a) the mirror vector R = 2(L.N)N - L"),
    _function("phong", shading.phong, _model_cases, "Q5(b) the Phong model, RGB"),
    _function("halfway", shading.halfway, _halfway_cases, "Q5(c) the half-way vector H"),
    _function("blinn_phong", shading.blinn_phong, _model_cases,
              "Q5(c) the Blinn-Phong model, (N.H)^n"),
    # Q5(a), Item Q5.1: what the specular exponent does
    Exercise(name="q5_item1", notebook=NB, kind=CellKind.CHOICE, answer="b",
             options=_choices, description="Q5(a) Item Q5.1: the role of n"),
    # Q5(c), Item Q5.2: when N.H saves work
    Exercise(name="q5_item2", notebook=NB, kind=CellKind.CHOICE, answer="c",
             options=_choices, description="Q5(c) Item Q5.2: when the half-way vector is cheaper"),
    # Q5(d), Item Q5.3: the cause of colour aliasing
    Exercise(name="q5_item3", notebook=NB, kind=CellKind.CHOICE, answer="c",
             options=_choices, description="Q5(d) Item Q5.3: why three samples alias"),
    # Q5(d), Item Q5.4: what reduces it (all that apply)
    Exercise(name="q5_item4", notebook=NB, kind=CellKind.CHOICE,
             answer=frozenset({"a", "c"}), options=_choices,
             description="Q5(d) Item Q5.4: remedies for colour aliasing (all that apply)"),
]


# Q5(b) on the student's own numbers: the reflected intensity of each colour.
EXERCISES.append(number_item(
    "q5b_your_intensity", NB,
    lambda v: shading.phong(np.array(v.colour), v.Ia, v.ka, v.Ip, v.kd, v.ks, v.n,
                            np.array(v.L), np.array(v.N), np.array(v.V)),
    "Q5(b) on your numbers: (I_r, I_g, I_b)"))
