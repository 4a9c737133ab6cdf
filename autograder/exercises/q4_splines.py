"""Q4: terminating Catmull-Rom splines and B-splines (notebook ``q4_splines``).

``end_rows`` is hidden-tested on matrices other than the two bases (Bezier, Hermite, random).
Visible cases carry the exam's own rows (Q4(b): a, b, c, d as the unit vectors of R^4 turn
``p, p', p''`` into the weight rows ``[0 0 1 0]``, ``[0 -1/2 0 1/2]``, ``[-1 4 -5 2]``) and the
end conditions of Q4(c); hidden cases draw random geometry in 2-D and 3-D, scalar and array
``t``, orders 0..2, every end rule, and bad input that must raise ``ValueError``.
"""

from __future__ import annotations

import numpy as np

from course_lib import splines

from ..model import CellKind
from .base import Case, Exercise, close, number_item

NB = "q4_splines"
RULES = ("d=b", "d=2c-b", "d=c")
KINDS = ("catmull-rom", "b-spline")
_CR = splines.catmull_rom_basis()
_BS = splines.bspline_basis()
_COMPARE = close(rtol=1e-7, atol=1e-9)


def _basis_cases(name):
    def cases(rng):
        return [Case(args=(), label=f"the {name} basis matrix (4 x 4)", visible=True)]
    return cases


def _parameter_row_cases(rng):
    for k in range(3):
        yield Case(args=(1.0,), kwargs={"order": k}, visible=True,
                   label=f"exam Q4(b): t = 1, order {k} ([1 1 1 1], [3 2 1 0], [6 2 0 0])")
    yield Case(args=(0.0,), label="t = 0, default order", visible=True)
    yield Case(args=(np.array([0.0, 0.5, 1.0]),), kwargs={"order": 1}, visible=True,
               label="array of 3 values of t, order 1")
    for k in range(3):
        yield Case(args=(float(rng.uniform(0, 1)),), kwargs={"order": k},
                   label=f"random scalar t, order {k}")
        n = int(rng.integers(2, 12))
        yield Case(args=(rng.uniform(-0.5, 1.5, n),), kwargs={"order": k},
                   label=f"array of {n} values of t (some outside [0, 1]), order {k}")
    yield Case(args=(rng.uniform(0, 1, 1),), kwargs={"order": 2}, label="array of one value")
    yield Case(args=(0.5,), kwargs={"order": 3}, label="order 3", raises=ValueError)
    yield Case(args=(0.5,), kwargs={"order": -1}, label="order -1", raises=ValueError)


_BEZIER = np.array([[-1.0, 3.0, -3.0, 1.0],
                    [3.0, -6.0, 3.0, 0.0],
                    [-3.0, 3.0, 0.0, 0.0],
                    [1.0, 0.0, 0.0, 0.0]])
# cubic Hermite, geometry [p0; p1; m0; m1]: "Hermite-like" (its columns are not control points)
_HERMITE = np.array([[2.0, -2.0, 1.0, 1.0],
                     [-3.0, 3.0, -2.0, -1.0],
                     [0.0, 0.0, 1.0, 0.0],
                     [1.0, 0.0, 0.0, 0.0]])


def _end_rows_cases(rng):
    yield Case(args=(np.eye(4),), visible=True,
               label="M = identity: the weights are the parameter rows themselves")
    yield Case(args=(_BEZIER,), visible=True,
               label="Bezier basis: ends on d, tangent 3(d - c), p'' = 6(b - 2c + d)")
    # end_rows is linear in M: a random factor keeps each named basis's answer from being fixed
    for M, name in ((_CR, "exam Q4(b): the Catmull-Rom basis"),
                    (_BS, "exam Q4(b): the B-spline basis"),
                    (_HERMITE, "the cubic Hermite basis (geometry p0, p1, m0, m1)")):
        yield Case(args=(float(rng.uniform(0.5, 3.0)) * M,), label=f"{name}, times a random factor")
    for i in range(3):
        yield Case(args=(rng.normal(scale=3.0, size=(4, 4)),), label=f"random 4 x 4 matrix {i + 1}")
    yield Case(args=(rng.integers(-6, 7, size=(4, 4)).astype(float),),
               label="random matrix of small integers")
    yield Case(args=(np.ones((3, 4)),), label="M of shape (3, 4)", raises=ValueError)
    yield Case(args=(np.ones((4, 3)),), label="M of shape (4, 3)", raises=ValueError)
    yield Case(args=(np.stack([_CR, _BS]),), label="two matrices, shape (2, 4, 4)",
               raises=ValueError)


def _spline_eval_cases(rng):
    eye = np.eye(4)
    for k in range(3):
        yield Case(args=(_CR, eye, 1.0), kwargs={"order": k}, visible=True,
                   label=f"exam Q4(b): Catmull-Rom, G = identity, t = 1, order {k}")
        yield Case(args=(_BS, eye, 1.0), kwargs={"order": k}, visible=True,
                   label=f"exam Q4(b): B-spline, G = identity, t = 1, order {k}")
    for dim in (2, 3):
        for k in range(3):
            M = _CR if rng.random() < 0.5 else _BS
            G = rng.normal(scale=5.0, size=(4, dim))
            yield Case(args=(M, G, float(rng.uniform(0, 1))), kwargs={"order": k},
                       label=f"random {dim}-D geometry, scalar t, order {k}")
            n = int(rng.integers(2, 10))
            yield Case(args=(M, G, rng.uniform(0, 1, n)), kwargs={"order": k},
                       label=f"random {dim}-D geometry, {n} values of t, order {k}")
    yield Case(args=(rng.normal(size=(4, 4)), rng.normal(size=(4, 2)), 0.3),
               label="another basis matrix (any 4 x 4 M)")
    yield Case(args=(_CR, rng.normal(size=(3, 2)), 0.5), label="G with 3 rows",
               raises=ValueError)
    yield Case(args=(np.eye(3), rng.normal(size=(4, 2)), 0.5), label="M of shape (3, 3)",
               raises=ValueError)
    yield Case(args=(_BS, rng.normal(size=(4, 2)), 0.5), kwargs={"order": 3}, label="order 3",
               raises=ValueError)


def _end_derivatives_cases(rng):
    e = tuple(np.eye(4))
    yield Case(args=(_CR, *e), visible=True,
               label="exam Q4(b): Catmull-Rom rows [0 0 1 0], [0 -1/2 0 1/2], [-1 4 -5 2]")
    yield Case(args=(_BS, *e), visible=True,
               label="exam Q4(b): B-spline rows (b + 4c + d)/6, (d - b)/2, b - 2c + d")
    b, c = np.array([1.0, 2.0]), np.array([3.0, 3.0])
    yield Case(args=(_CR, np.array([0.0, 0.0]), b, c, b), visible=True,
               label="exam Q4(c)(i): Catmull-Rom with d = b")
    yield Case(args=(_BS, np.array([0.0, 0.0]), b, c, 2 * c - b), visible=True,
               label="exam Q4(c)(i): B-spline with d = 2c - b")
    for dim in (2, 3):
        for M, name in ((_CR, "Catmull-Rom"), (_BS, "B-spline")):
            a, b, c, d = rng.normal(scale=5.0, size=(4, dim))
            yield Case(args=(M, a, b, c, d), label=f"{name}, random {dim}-D points")
    n = int(rng.integers(2, 8))
    yield Case(args=(_BS, *rng.normal(size=(4, n, 3))), label=f"B-spline, batch of {n} (n, 3)")
    yield Case(args=(_CR, np.zeros(2), np.ones(2), np.ones(3), np.ones(2)),
               label="points of different shapes", raises=ValueError)


def _phantom_point_cases(rng):
    b, c = np.array([1.0, 2.0]), np.array([3.0, 3.0])
    for rule in RULES:
        yield Case(args=(b, c, rule), visible=True, label=f"rule {rule!r}, 2-D")
    for rule in RULES:
        dim = int(rng.integers(2, 4))
        yield Case(args=(*rng.normal(scale=5.0, size=(2, dim)), rule),
                   label=f"rule {rule!r}, random {dim}-D points")
        n = int(rng.integers(2, 6))
        yield Case(args=(*rng.normal(size=(2, n, 3)), rule),
                   label=f"rule {rule!r}, batch of {n} (n, 3)")
    yield Case(args=(b, c, "d=a"), label="unknown rule 'd=a'", raises=ValueError)
    yield Case(args=(b, c, "natural"), label="unknown rule 'natural'", raises=ValueError)


def _sample_curve_cases(rng):
    P4 = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 1.0], [3.0, 1.0]])
    yield Case(args=(P4, "catmull-rom", 2), visible=True,
               label="one Catmull-Rom segment: runs from the 2nd point to the 3rd")
    P5 = np.array([[0.0, 0.0], [1.0, 2.0], [3.0, 2.5], [4.0, 0.5], [6.0, 1.0]])
    yield Case(args=(P5, "b-spline", 4), kwargs={"end_rule": "d=2c-b"}, visible=True,
               label="B-spline with d = 2c - b at both ends: from the first point to the last")
    yield Case(args=(P5, "b-spline", 4), kwargs={"end_rule": "d=b"}, visible=True,
               label="B-spline with d = b at both ends")
    for kind in KINDS:
        for rule in (None, *RULES):
            dim = int(rng.integers(2, 4))
            m = int(rng.integers(2 if rule else 4, 8))
            n = int(rng.integers(1, 9))
            yield Case(args=(rng.normal(scale=5.0, size=(m, dim)), kind, n),
                       kwargs={"end_rule": rule},
                       label=f"{kind}, {m} random {dim}-D points, {n} per segment, "
                             f"end_rule={rule!r}")
    yield Case(args=(rng.normal(scale=3.0, size=(5, 2)), "catmull-rom", 3),
               label="end_rule left at its default")
    yield Case(args=(P5, "bezier", 4), label="unknown kind 'bezier'", raises=ValueError)
    yield Case(args=(P5[:3], "b-spline", 4), label="3 points and no end rule",
               raises=ValueError)
    yield Case(args=(P5[:1], "catmull-rom", 4), kwargs={"end_rule": "d=b"},
               label="one point with an end rule", raises=ValueError)
    yield Case(args=(P5, "b-spline", 4), kwargs={"end_rule": "d=a"}, label="unknown rule",
               raises=ValueError)
    yield Case(args=(P5, "b-spline", 0), label="n_per_segment = 0", raises=ValueError)
    yield Case(args=(P5[:, 0], "b-spline", 4), label="points of shape (m,)", raises=ValueError)


def _function(name, reference, cases, description):
    return Exercise(name=name, notebook=NB, reference=reference,
                    cases=cases, compare=_COMPARE,
                    description=description)


EXERCISES = [
    _function("catmull_rom_basis", splines.catmull_rom_basis, _basis_cases("Catmull-Rom"),
              "Q4(b) the Catmull-Rom basis matrix"),
    _function("bspline_basis", splines.bspline_basis, _basis_cases("B-spline"),
              "Q4(b) the uniform cubic B-spline basis matrix"),
    _function("parameter_row", splines.parameter_row, _parameter_row_cases,
              "Q4(b) [t^3, t^2, t, 1] and its derivatives"),
    _function("end_rows", splines.end_rows, _end_rows_cases,
              "Q4(b) the 3 x 4 weights of a, b, c, d in p(1), p'(1), p''(1) for any basis M"),
    _function("end_derivatives", splines.end_derivatives, _end_derivatives_cases,
              "Q4(b) p, p', p'' at t = 1"),
    _function("spline_eval", splines.spline_eval, _spline_eval_cases,
              "Q4(c)(i) one segment's position or derivative"),
    _function("phantom_point", splines.phantom_point, _phantom_point_cases,
              "Q4(c)(i) the invented end point d"),
    _function("sample_curve", splines.sample_curve, _sample_curve_cases,
              "Q4(c)(i) a multi-segment curve with or without phantom end points"),
    Exercise(name="q4_item1", notebook=NB, kind=CellKind.CHOICE, answer="b",
             options=("a", "b", "c", "d"),
             description="Q4(a) control points needed for N segments: N + 3"),
    Exercise(name="q4_item2", notebook=NB, kind=CellKind.CHOICE,
             answer=frozenset({"b", "d", "e"}), options=("a", "b", "c", "d", "e"),
             description="Q4(a) interpolation, continuity, shared geometry (not: B-spline "
                         "through its ends, Catmull-Rom in the hull)"),
    Exercise(name="q4_item4", notebook=NB, kind=CellKind.CHOICE, answer="b",
             options=("a", "b", "c", "d"),
             description="Q4(c)(i) with d = b the B-spline stops at (b + 2c)/3, at rest"),
    Exercise(name="q4_item5", notebook=NB, kind=CellKind.CHOICE,
             answer=frozenset({"a", "b", "d"}), options=("a", "b", "c", "d", "e"),
             description="Q4(c)(i) which spline and rule end on the last given point"),
    Exercise(name="q4_item7", notebook=NB, kind=CellKind.CHOICE, answer="c",
             options=("a", "b", "c", "d"),
             description="Q4(c)(ii) d = b suits Catmull-Rom: the end tangent is not imposed"),
    Exercise(name="q4_item8", notebook=NB, kind=CellKind.CHOICE, answer="b",
             options=("a", "b", "c", "d"),
             description="Q4(c)(ii) B-spline: d = b rests at (b+2c)/3, d = 2c - b ends on c moving"),
]


def _your_end(v) -> np.ndarray:
    """p(1), p'(1), p''(1) of the last segment [a; b; c; d], d the phantom of the rule."""
    M = splines.catmull_rom_basis() if v.kind == "catmull-rom" else splines.bspline_basis()
    a, b, c = (np.array(p, dtype=float) for p in (v.a, v.b, v.c))
    d = splines.phantom_point(b, c, v.rule)
    return np.array(splines.end_derivatives(M, a, b, c, d))


# Q4(c)(i) on the student's own numbers: the end of their curve under their rule.
EXERCISES.append(number_item(
    "q4ci_your_end", NB, _your_end,
    "Q4(c)(i) on your numbers: p(1), p'(1), p''(1) of your last segment, shape (3, 2)"))
