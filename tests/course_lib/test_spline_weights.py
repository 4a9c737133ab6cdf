"""The end-weight tables Q4's explorer and notebook show (``course_lib.spline_weights``): the
references' weights exactly, checked against scipy's cubic Hermite (the Catmull-Rom segment
is the Hermite cubic with central-difference tangents) and scipy's B-spline, and a students'
copy that holds the same tables as literals and computes nothing."""

from __future__ import annotations

import ast
from fractions import Fraction

import numpy as np
import pytest
from scipy.interpolate import BSpline, CubicHermiteSpline

from course_lib import _spline_weights_data as data
from course_lib import spline_weights
from course_lib import splines as S

CASES = [(kind, rule) for kind in spline_weights.KINDS for rule in spline_weights.RULES]
#: d from b and c for each rule (a, b, c, d as the four columns), written out independently
PHANTOM = {"d=b": (0, 1, 0), "d=2c-b": (0, -1, 2), "d=c": (0, 0, 1)}


def _oracle_end(kind, a, b, c, d):
    """p(1), p'(1), p''(1) of the last segment from scipy, for scalar points."""
    if kind == "catmull-rom":
        seg = CubicHermiteSpline([0.0, 1.0], [b, c], [(c - a) / 2, (d - b) / 2])
        return [float(seg(1.0, nu)) for nu in range(3)]
    seg = BSpline(np.arange(8.0), [a, b, c, d], 3)    # the segment is knot interval [3, 4]
    return [float(seg(4.0, nu)) for nu in range(3)]


def _oracle_weights(kind, rule):
    """(3, 4): the weight of each point, the response of the end to a unit impulse there."""
    W = np.zeros((3, 4))
    for j in range(4 if rule == "free" else 3):
        a, b, c = np.eye(4)[j][:3]
        d = np.eye(4)[j][3] if rule == "free" else np.dot(PHANTOM[rule], (a, b, c))
        W[:, j] = _oracle_end(kind, a, b, c, d)
    return W


@pytest.mark.parametrize("kind, rule", CASES)
def test_tables_match_scipy(kind, rule):
    got = np.array([[float(Fraction(w)) for w in row]
                    for row in spline_weights.end_weights_text(kind, rule)])
    np.testing.assert_allclose(got, _oracle_weights(kind, rule), rtol=0, atol=1e-12)


@pytest.mark.parametrize("kind, rule", CASES)
def test_tables_are_the_references_weights(kind, rule):
    want = S.end_weights(S.basis_matrix(kind), rule)
    got = np.array([[float(Fraction(w)) for w in row] for row in data.compute()[(kind, rule)]])
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-15)


def test_exam_rows_and_rules_exactly():
    """Q4(b)'s rows, and a rule substituted into them in exact arithmetic, give the tables."""
    text = spline_weights.end_weights_text
    assert text("catmull-rom", "free") == (("0", "0", "1", "0"), ("0", "-1/2", "0", "1/2"),
                                           ("-1", "4", "-5", "2"))
    assert text("b-spline", "free")[0] == ("0", "1/6", "2/3", "1/6")
    for kind, rule in CASES:
        if rule == "free":
            continue
        free = [[Fraction(w) for w in row] for row in text(kind, "free")]
        want = [[w[0] + w[3] * PHANTOM[rule][0], w[1] + w[3] * PHANTOM[rule][1],
                 w[2] + w[3] * PHANTOM[rule][2], 0] for w in free]
        assert [[Fraction(w) for w in row] for row in text(kind, rule)] == want, (kind, rule)
    # a point's weights sum to 1, a derivative's to 0
    assert all(spline_weights.row_sums(*case) == ("1", "0", "0") for case in CASES)


def test_bad_kind_or_rule_raises():
    with pytest.raises(ValueError, match="kind"):
        spline_weights.end_weights_text("bezier", "free")
    with pytest.raises(ValueError, match="rule"):
        spline_weights.end_weights_text("b-spline", "natural")


def test_students_copy_is_the_same_tables_and_computes_nothing():
    text = data.students_copy()
    tree = ast.parse(text)
    assert not [n for n in ast.walk(tree) if isinstance(n, (ast.Import, ast.ImportFrom))]
    names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
    names |= {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)}
    assert not names & {"splines", "end_weights", "end_rows", "basis_matrix"}
    ns: dict = {}
    exec(compile(text, "students_copy", "exec"), ns)
    assert ns["load"]() == data.compute()
    assert all(isinstance(w, str) for table in ns["load"]().values()
               for row in table for w in row)
