"""Tests of ``course_lib.splines`` (Q4) against the exam's own rows and end conditions, the
``splines`` package (uniform Catmull-Rom), ``scipy.interpolate.BSpline`` (uniform cubic
B-spline), ``scipy.spatial.ConvexHull`` and shapely, plus hypothesis laws."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
import splines as splines_pkg
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.interpolate import BSpline
from scipy.spatial import ConvexHull

from course_lib import splines as S

CR, BS = S.catmull_rom_basis(), S.bspline_basis()
RULES = ("d=b", "d=2c-b", "d=c")

# ------------------------------------------------------------------------------------------
# the exam's numbers, Q4(b)


def test_parameter_rows_at_t1_are_the_exams():
    """Q4(b): [1 1 1 1], [3 2 1 0], [6 2 0 0] for p, p', p''."""
    np.testing.assert_array_equal(S.parameter_row(1.0, 0), [1, 1, 1, 1])
    np.testing.assert_array_equal(S.parameter_row(1.0, 1), [3, 2, 1, 0])
    np.testing.assert_array_equal(S.parameter_row(1.0, 2), [6, 2, 0, 0])


def test_catmull_rom_rows_at_t1_are_the_exams():
    """Q4(b): the parameter rows times M_CR are [0 0 1 0], [0 -1/2 0 1/2], [-1 4 -5 2]."""
    expected = [[0, 0, 1, 0], [0, -0.5, 0, 0.5], [-1, 4, -5, 2]]
    got = [S.parameter_row(1.0, k) @ CR for k in range(3)]
    np.testing.assert_allclose(got, expected, atol=1e-15)
    np.testing.assert_allclose(S.end_rows(CR), expected, atol=1e-15)


def test_bspline_end_formulas_are_the_exams():
    """Q4(b): p = (b + 4c + d)/6, p' = (d - b)/2, p'' = b - 2c + d, on random 3-D points."""
    rng = np.random.default_rng(0)
    a, b, c, d = rng.normal(size=(4, 3))
    p, p1, p2 = S.end_derivatives(BS, a, b, c, d)
    np.testing.assert_allclose(p, (b + 4 * c + d) / 6, atol=1e-14)
    np.testing.assert_allclose(p1, (d - b) / 2, atol=1e-14)
    np.testing.assert_allclose(p2, b - 2 * c + d, atol=1e-14)


def test_catmull_rom_end_formulas_are_the_exams():
    """Q4(b): p = c, p' = (d - b)/2, p'' = -a + 4b - 5c + 2d."""
    rng = np.random.default_rng(1)
    a, b, c, d = rng.normal(size=(4, 2))
    p, p1, p2 = S.end_derivatives(CR, a, b, c, d)
    np.testing.assert_allclose(p, c, atol=1e-14)
    np.testing.assert_allclose(p1, (d - b) / 2, atol=1e-14)
    np.testing.assert_allclose(p2, -a + 4 * b - 5 * c + 2 * d, atol=1e-14)


def test_unit_vector_geometry_gives_the_weight_rows():
    """With a, b, c, d the unit vectors of R^4, end_derivatives returns the exam's rows."""
    p, p1, p2 = S.end_derivatives(CR, *np.eye(4))
    np.testing.assert_allclose(np.array([p, p1, p2]),
                               [[0, 0, 1, 0], [0, -0.5, 0, 0.5], [-1, 4, -5, 2]], atol=1e-15)
    np.testing.assert_allclose(S.spline_eval(BS, np.eye(4), 1.0, 0), [0, 1 / 6, 4 / 6, 1 / 6],
                               atol=1e-15)


# ------------------------------------------------------------------------------------------
# Q4(c)(i): the end conditions


@pytest.fixture
def abc():
    return np.random.default_rng(2).normal(size=(3, 2))


def test_catmull_rom_d_equals_b(abc):
    """Q4(c)(i), Fig. 1(a): p = c, p' = 0, p'' = -a + 6b - 5c."""
    a, b, c = abc
    d = S.phantom_point(b, c, "d=b")
    p, p1, p2 = S.end_derivatives(CR, a, b, c, d)
    np.testing.assert_allclose(p, c, atol=1e-14)
    np.testing.assert_allclose(p1, 0.0, atol=1e-14)
    np.testing.assert_allclose(p2, -a + 6 * b - 5 * c, atol=1e-13)


def test_bspline_d_equals_b(abc):
    """Q4(c)(i): p = (2b + 4c)/6 (two thirds of the way from b to c), p' = 0, p'' = 2b - 2c."""
    a, b, c = abc
    p, p1, p2 = S.end_derivatives(BS, a, b, c, S.phantom_point(b, c, "d=b"))
    np.testing.assert_allclose(p, (2 * b + 4 * c) / 6, atol=1e-14)
    np.testing.assert_allclose(p, b + (2 / 3) * (c - b), atol=1e-14)
    np.testing.assert_allclose(p1, 0.0, atol=1e-14)
    np.testing.assert_allclose(p2, 2 * b - 2 * c, atol=1e-13)


def test_catmull_rom_d_equals_2c_minus_b(abc):
    """Q4(c)(i), Fig. 1(b): p = c, p' = c - b, p'' = -a + 2b - c."""
    a, b, c = abc
    d = S.phantom_point(b, c, "d=2c-b")
    np.testing.assert_allclose(d, 2 * c - b, atol=1e-12)
    p, p1, p2 = S.end_derivatives(CR, a, b, c, d)
    np.testing.assert_allclose(p, c, atol=1e-14)
    np.testing.assert_allclose(p1, c - b, atol=1e-14)
    np.testing.assert_allclose(p2, -a + 2 * b - c, atol=1e-13)


def test_bspline_d_equals_2c_minus_b(abc):
    """Q4(c)(i): the B-spline ends exactly at c, with p' = c - b and p'' = 0."""
    a, b, c = abc
    p, p1, p2 = S.end_derivatives(BS, a, b, c, S.phantom_point(b, c, "d=2c-b"))
    np.testing.assert_allclose(p, c, atol=1e-14)
    np.testing.assert_allclose(p1, c - b, atol=1e-14)
    np.testing.assert_allclose(p2, 0.0, atol=1e-13)


def test_end_weights_agree_with_substitution():
    """end_weights is the Q4(b) rows with d replaced by the rule (checked on the exam's rows)."""
    np.testing.assert_allclose(S.end_weights(CR, "d=b"),
                               [[0, 0, 1, 0], [0, 0, 0, 0], [-1, 6, -5, 0]], atol=1e-14)
    np.testing.assert_allclose(S.end_weights(BS, "d=b"),
                               [[0, 2 / 6, 4 / 6, 0], [0, 0, 0, 0], [0, 2, -2, 0]], atol=1e-14)
    np.testing.assert_allclose(S.end_weights(CR, "d=2c-b"),
                               [[0, 0, 1, 0], [0, -1, 1, 0], [-1, 2, -1, 0]], atol=1e-14)
    np.testing.assert_allclose(S.end_weights(BS, "d=2c-b"),
                               [[0, 0, 1, 0], [0, -1, 1, 0], [0, 0, 0, 0]], atol=1e-14)


def test_phantom_point_rules_and_batches():
    b = np.array([[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]])
    c = np.array([[1.0, 1.0, 1.0], [1.0, 0.0, -1.0]])
    np.testing.assert_array_equal(S.phantom_point(b, c, "d=b"), b)
    np.testing.assert_array_equal(S.phantom_point(b, c, "d=c"), c)
    np.testing.assert_array_equal(S.phantom_point(b, c, "d=2c-b"),
                                  [[2.0, 2.0, 2.0], [1.0, -2.0, -5.0]])


# ------------------------------------------------------------------------------------------
# other libraries as oracles


def _random_points(seed, m, k=2):
    return np.random.default_rng(seed).uniform(-5, 5, size=(m, k))


@pytest.mark.parametrize("rule", [None, *RULES])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_catmull_rom_matches_splines_package(rule, seed):
    """sample_curve equals splines.CatmullRom (uniform: no alpha) on the phantom-extended
    polygon; its interior segments u in [1, L - 2] are the uniform Catmull-Rom segments."""
    P = _random_points(seed, 6, k=3 if seed == 2 else 2)
    ext = P if rule is None else S.extend_with_phantoms(P, rule)
    n = 7
    got = S.sample_curve(P, "catmull-rom", n, end_rule=rule)
    n_seg = len(ext) - 3
    ref = splines_pkg.CatmullRom(ext).evaluate(1 + np.arange(n_seg * n + 1) / n)
    assert got.shape == (n_seg * n + 1, P.shape[1])
    np.testing.assert_allclose(got, ref, atol=1e-12)
    u = np.linspace(0, n_seg, 23)
    for order in (1, 2):
        np.testing.assert_allclose(
            S.evaluate_curve(P, "catmull-rom", u[1:-1], order, end_rule=rule),
            splines_pkg.CatmullRom(ext).evaluate(1 + u[1:-1], order), atol=1e-10)


def test_catmull_rom_d_equals_b_is_clamped_with_zero_tangent():
    """With d = b at both ends the end tangents are 0: splines.CatmullRom clamped to (0, 0)."""
    P = _random_points(3, 5)
    zero = [0.0, 0.0]  # plain lists: the package compares the condition with 'natural'
    ref = splines_pkg.CatmullRom(P, endconditions=[zero, zero])
    n = 5
    u = np.arange((len(P) - 1) * n + 1) / n
    np.testing.assert_allclose(S.sample_curve(P, "catmull-rom", n, end_rule="d=b"),
                               ref.evaluate(u), atol=1e-12)


@pytest.mark.parametrize("rule", [None, *RULES])
@pytest.mark.parametrize("k", [2, 3])
def test_bspline_matches_scipy(rule, k):
    """The uniform cubic B-spline is scipy's BSpline with knots 0, 1, ..., L + 3 on
    [3, L]; segment i of ours is knot interval [i + 3, i + 4]."""
    P = _random_points(10 + k, 7, k)
    ext = P if rule is None else S.extend_with_phantoms(P, rule)
    L = len(ext)
    ref = BSpline(np.arange(L + 4, dtype=float), ext, 3)
    n = 6
    u = np.arange((L - 3) * n + 1) / n
    np.testing.assert_allclose(S.sample_curve(P, "b-spline", n, end_rule=rule), ref(u + 3),
                               atol=1e-12)
    for order in (1, 2):
        np.testing.assert_allclose(S.evaluate_curve(P, "b-spline", u, order, end_rule=rule),
                                   ref.derivative(order)(u + 3), atol=1e-10)


def test_convex_hull_matches_scipy_and_shapely():
    rng = np.random.default_rng(5)
    for _ in range(20):
        P = rng.normal(size=(rng.integers(3, 40), 2))
        H = S.convex_hull(P)
        ref = P[ConvexHull(P).vertices]  # scipy: counter-clockwise in 2-D
        assert len(H) == len(ref)
        start = int(np.argmin(np.linalg.norm(ref - H[0], axis=1)))
        np.testing.assert_allclose(np.roll(ref, -start, axis=0), H, atol=1e-12)
        assert shapely.Polygon(H).area == pytest.approx(shapely.MultiPoint(P).convex_hull.area)
        Q = rng.normal(scale=1.5, size=(50, 2))
        inside = shapely.contains_xy(shapely.Polygon(H), Q[:, 0], Q[:, 1])
        np.testing.assert_array_equal(S.in_convex_hull(Q, H), inside)


def test_convex_hull_degenerate_inputs():
    np.testing.assert_array_equal(S.convex_hull([[1.0, 1.0], [1.0, 1.0]]), [[1.0, 1.0]])
    H = S.convex_hull([[0, 0], [1, 1], [2, 2], [3, 3]])
    np.testing.assert_array_equal(H, [[0, 0], [3, 3]])
    assert S.in_convex_hull([1.5, 1.5], H) and not S.in_convex_hull([1.5, 1.6], H)


# ------------------------------------------------------------------------------------------
# shapes of parameter_row and spline_eval


def test_parameter_row_shapes_and_derivatives():
    t = np.array([0.0, 0.25, 2.0])
    assert S.parameter_row(0.5).shape == (4,)
    assert S.parameter_row(t, 1).shape == (3, 4)
    np.testing.assert_allclose(S.parameter_row(t, 0)[:, 0], t**3, atol=1e-12)
    np.testing.assert_allclose(S.parameter_row(t, 1)[:, 0], 3 * t**2, atol=1e-12)
    np.testing.assert_allclose(S.parameter_row(t, 2), np.c_[6 * t, 2 + 0 * t, 0 * t, 0 * t], atol=1e-12)


def test_spline_eval_shapes():
    G = _random_points(4, 4, 3)
    assert S.spline_eval(CR, G, 0.3).shape == (3,)
    assert S.spline_eval(CR, G, [0.1, 0.2], order=2).shape == (2, 3)
    assert isinstance(S.spline_eval(CR, G[:, 0], 0.3), float)
    np.testing.assert_allclose(S.spline_eval(CR, G, [0.0, 1.0]), G[1:3], atol=1e-14)


def test_spline_eval_derivatives_match_finite_differences():
    """order 1 and 2 are the derivatives of order 0 (central differences)."""
    G = _random_points(6, 4, 2)
    t, h = np.linspace(0.1, 0.9, 9), 1e-4
    for M in (CR, BS):
        def f(s, M=M):
            return S.spline_eval(M, G, s)

        np.testing.assert_allclose(S.spline_eval(M, G, t, 1), (f(t + h) - f(t - h)) / (2 * h),
                                   atol=1e-6)
        np.testing.assert_allclose(S.spline_eval(M, G, t, 2),
                                   (f(t + h) - 2 * f(t) + f(t - h)) / h**2, atol=1e-4)


def test_sample_curve_count_and_ends():
    P = _random_points(7, 6)
    out = S.sample_curve(P, "catmull-rom", 5)
    assert out.shape == (3 * 5 + 1, 2)
    np.testing.assert_allclose(out[[0, -1]], P[[1, -2]], atol=1e-13)  # from b to c, not a
    out = S.sample_curve(P, "catmull-rom", 4, end_rule="d=b")
    assert out.shape == (5 * 4 + 1, 2)
    np.testing.assert_allclose(out[[0, -1]], P[[0, -1]], atol=1e-13)  # Catmull-Rom: ends on them
    out = S.sample_curve(P, "b-spline", 3, end_rule="d=2c-b")
    np.testing.assert_allclose(out[[0, -1]], P[[0, -1]], atol=1e-13)
    out = S.sample_curve(P, "b-spline", 3, end_rule="d=b")
    np.testing.assert_allclose(out[-1], (2 * P[-2] + 4 * P[-1]) / 6, atol=1e-13)
    np.testing.assert_allclose(out[0], (2 * P[1] + 4 * P[0]) / 6, atol=1e-13)  # mirror rule


# ------------------------------------------------------------------------------------------
# end_rows on matrices other than the two bases (Q4(b) for any cubic in matrix form)

# Bezier: p(t) = sum_j B_j(t) P_j with the Bernstein cubics; columns = coefficients t^3..1
BEZIER = np.array([[-1.0, 3.0, -3.0, 1.0],
                   [3.0, -6.0, 3.0, 0.0],
                   [-3.0, 3.0, 0.0, 0.0],
                   [1.0, 0.0, 0.0, 0.0]])


def test_end_rows_of_bezier_are_its_textbook_end_conditions():
    # a Bezier curve ends on its last control point, tangent 3(d - c), p'' = 6(b - 2c + d)
    np.testing.assert_allclose(S.end_rows(BEZIER), [[0, 0, 0, 1], [0, 0, -3, 3], [0, 6, -12, 6]],
                               atol=1e-12)


def test_end_rows_of_identity_are_the_parameter_rows():
    np.testing.assert_allclose(S.end_rows(np.eye(4)), [[1, 1, 1, 1], [3, 2, 1, 0], [6, 2, 0, 0]], atol=1e-12)


@settings(max_examples=30, deadline=None)
@given(M=arrays(np.float64, (4, 4), elements=st.floats(-10, 10)))
def test_end_rows_match_numpy_polynomials(M):
    """Column j of M holds the coefficients (t^3 .. 1) of point j's blending cubic; numpy's
    polyval/polyder give its value and derivatives at t = 1 independently."""
    want = [[np.polyval(np.polyder(M[:, j], k), 1.0) for j in range(4)] for k in range(3)]
    np.testing.assert_allclose(S.end_rows(M), want, rtol=1e-12, atol=1e-9)


def test_end_rows_rejects_a_non_square_basis():
    with pytest.raises(ValueError, match="M"):
        S.end_rows(np.ones((3, 4)))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_bspline_with_d_equals_b_does_not_reach_the_last_point(seed):
    """Q4(c)(i): phantoms d = b leave the B-spline short of both given end points (scipy's
    uniform BSpline as the oracle): it stops at (b + 2c)/3, which is neither c nor b."""
    P = _random_points(20 + seed, 5)
    ext = S.extend_with_phantoms(P, "d=b")
    ref = BSpline(np.arange(len(ext) + 4, dtype=float), ext, 3)
    end, start = ref(float(len(ext))), ref(3.0)
    b, c = P[-2], P[-1]
    np.testing.assert_allclose(end, (b + 2 * c) / 3, atol=1e-12)
    assert np.linalg.norm(end - c) > 0.1 * np.linalg.norm(c - b)
    assert np.linalg.norm(end - b) > 0.1 * np.linalg.norm(c - b)
    assert np.linalg.norm(start - P[0]) > 0.1 * np.linalg.norm(P[1] - P[0])
    out = S.sample_curve(P, "b-spline", 4, end_rule="d=b")
    np.testing.assert_allclose(out[[0, -1]], [start, end], atol=1e-12)


# ------------------------------------------------------------------------------------------
# validation


@pytest.mark.parametrize("call", [
    lambda: S.parameter_row(0.5, order=3),
    lambda: S.parameter_row(0.5, order=-1),
    lambda: S.parameter_row(0.5, order=1.5),
    lambda: S.parameter_row(np.nan),
    lambda: S.spline_eval(CR, np.zeros((3, 2)), 0.5),
    lambda: S.spline_eval(CR, np.zeros((4, 2, 2)), 0.5),
    lambda: S.spline_eval(np.eye(3), np.zeros((4, 2)), 0.5),
    lambda: S.spline_eval(CR, np.zeros((4, 2)), 0.5, order=4),
    lambda: S.end_derivatives(CR, [0, 0], [1, 1], [2, 2], [3, 3, 3]),
    lambda: S.end_derivatives(np.ones((4, 3)), [0, 0], [1, 1], [2, 2], [3, 3]),
    lambda: S.phantom_point([0, 0], [1, 1], "d=a"),
    lambda: S.phantom_point([0, 0], [1, 1], "natural"),
    lambda: S.phantom_point([0, 0], [1, 1, 1], "d=b"),
    lambda: S.sample_curve(np.zeros((3, 2)), "catmull-rom", 4),
    lambda: S.sample_curve(np.zeros((1, 2)), "b-spline", 4, end_rule="d=b"),
    lambda: S.sample_curve(np.zeros((5, 2)), "bezier", 4),
    lambda: S.sample_curve(np.zeros((5, 2)), "b-spline", 0),
    lambda: S.sample_curve(np.zeros((5, 2)), "b-spline", 4, end_rule="d=a"),
    lambda: S.sample_curve(np.zeros(5), "b-spline", 4),
    lambda: S.evaluate_curve(np.zeros((5, 2)), "b-spline", 2.5),
])
def test_bad_input_raises_value_error(call):
    with pytest.raises(ValueError):
        call()


def test_error_messages_name_the_problem():
    with pytest.raises(ValueError, match="rule"):
        S.phantom_point([0, 0], [1, 1], "d=a")
    with pytest.raises(ValueError, match="order"):
        S.parameter_row(0.0, 5)
    with pytest.raises(ValueError, match="G"):
        S.spline_eval(CR, np.zeros((3, 2)), 0.0)
    with pytest.raises(ValueError, match="at least 4"):
        S.sample_curve(np.zeros((3, 2)), "b-spline", 2)


# ------------------------------------------------------------------------------------------
# hypothesis laws

# coordinates on a 0.01 grid: duplicates and collinear points come up often, subnormals never
coords = st.integers(-10_000, 10_000).map(lambda i: i / 100)


def polylines(min_m=4, max_m=9):
    return st.integers(min_m, max_m).flatmap(
        lambda m: arrays(np.float64, (m, 2), elements=coords))


@settings(max_examples=60, deadline=None)
@given(t=st.floats(-3, 3, allow_nan=False))
def test_partition_of_unity(t):
    """Both bases' blending functions sum to 1 for every t (translation invariance)."""
    for M in (CR, BS):
        assert np.sum(S.parameter_row(t) @ M) == pytest.approx(1.0, abs=1e-12)
        assert np.sum(S.parameter_row(t, 1) @ M) == pytest.approx(0.0, abs=1e-12)
        assert np.sum(S.parameter_row(t, 2) @ M) == pytest.approx(0.0, abs=1e-12)


@settings(max_examples=60, deadline=None)
@given(t=st.floats(0, 1))
def test_bspline_weights_non_negative(t):
    assert np.all(S.parameter_row(t) @ BS >= -1e-15)


@settings(max_examples=60, deadline=None)
@given(P=polylines(), n=st.integers(1, 6))
def test_catmull_rom_interpolates_middle_points(P, n):
    out = S.sample_curve(P, "catmull-rom", n)
    np.testing.assert_allclose(out[::n], P[1:-1], atol=1e-9)


@settings(max_examples=60, deadline=None)
@given(P=polylines(), rule=st.sampled_from([None, *RULES]))
def test_bspline_in_convex_hull(P, rule):
    """Every B-spline sample lies in the convex hull of the (extended) control points:
    checked with shapely (distance 0 up to round-off) and with the hull inequalities."""
    ext = P if rule is None else S.extend_with_phantoms(P, rule)
    curve = S.sample_curve(P, "b-spline", 9, end_rule=rule)
    hull = shapely.MultiPoint(ext).convex_hull
    tol = 1e-9 * (1 + np.abs(ext).max())
    assert np.all(shapely.distance(hull, shapely.points(curve)) <= tol)
    H = S.convex_hull(ext)
    assert np.all(S.in_convex_hull(curve, H))
    # and each segment lies in the hull of its own four points (the local property)
    for i, G in enumerate(S.segment_geometries(ext)):
        seg = S.spline_eval(BS, G, np.linspace(0, 1, 11))
        local = shapely.MultiPoint(G).convex_hull
        assert np.all(shapely.distance(local, shapely.points(seg)) <= tol), i


@settings(max_examples=60, deadline=None)
@given(P=polylines(5, 8))
def test_continuity_at_joins(P):
    """Catmull-Rom is C1 and the B-spline C2 at every join (segment i at t=1 vs i+1 at t=0)."""
    Gs = S.segment_geometries(P)
    scale = 1 + np.abs(P).max()
    for M, orders in ((CR, (0, 1)), (BS, (0, 1, 2))):
        for i in range(len(Gs) - 1):
            for k in orders:
                left = S.spline_eval(M, Gs[i], 1.0, k)
                right = S.spline_eval(M, Gs[i + 1], 0.0, k)
                np.testing.assert_allclose(left, right, atol=1e-10 * scale)


def test_catmull_rom_is_not_c2():
    """The second derivative of Catmull-Rom jumps at a join (a counter-example)."""
    P = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 1.0], [4.0, 0.0], [4.5, 2.0]])
    Gs = S.segment_geometries(P)
    jump = S.spline_eval(CR, Gs[1], 0.0, 2) - S.spline_eval(CR, Gs[0], 1.0, 2)
    # by the exam's rows: p''(1) of [a b c d] is -a+4b-5c+2d, p''(0) of [b c d e] is 2b-5c+4d-e
    a, b, c, d, e = P
    np.testing.assert_allclose(jump, (2 * b - 5 * c + 4 * d - e) - (-a + 4 * b - 5 * c + 2 * d), atol=1e-12)
    assert np.linalg.norm(jump) > 1.0


@settings(max_examples=40, deadline=None)
@given(P=polylines(2, 7), rule=st.sampled_from(RULES))
def test_end_rules_make_the_curve_span_every_point(P, rule):
    """With phantoms at both ends Catmull-Rom runs from the first point to the last."""
    out = S.sample_curve(P, "catmull-rom", 3, end_rule=rule)
    assert out.shape == ((len(P) - 1) * 3 + 1, 2)
    np.testing.assert_allclose(out[::3], P, atol=1e-9 * (1 + np.abs(P).max()))


# ------------------------------------------------------------------------------------------
# the registry's cases catch the slips the examiners saw (Q4(b): matrix multiplications)


def _fails(name, func):
    from autograder.incell import run_cases

    return any(why is not None for _, why in run_cases(name, func))


def test_registry_accepts_the_references():
    from autograder.exercises import for_notebook

    for ex in for_notebook("q4_splines"):
        if ex.kind == "function":
            assert not _fails(ex.name, getattr(S, ex.name)), ex.name


def test_registry_catches_common_mistakes():
    # multiplying in the wrong order (G M T instead of T M G, written with a transposed M)
    assert _fails("spline_eval", lambda M, G, t, order=0: S.parameter_row(t, order)
                  @ np.asarray(M).T @ np.asarray(G))
    # forgetting the 1/2 of the Catmull-Rom basis
    assert _fails("catmull_rom_basis", lambda: 2 * S.catmull_rom_basis())
    # using the position row for every order
    assert _fails("end_derivatives", lambda M, a, b, c, d: tuple(
        S.parameter_row(1.0) @ np.asarray(M) @ np.stack([a, b, c, d], axis=-2)
        for _ in range(3)))
    # repeating every join (n + 1 samples per segment)
    def doubled(points, kind, n, end_rule=None):
        ext = np.asarray(points, float) if end_rule is None else \
            S.extend_with_phantoms(points, end_rule)
        return np.vstack([S.spline_eval(S.basis_matrix(kind), G, np.linspace(0, 1, n + 1))
                          for G in S.segment_geometries(ext)])
    assert _fails("sample_curve", doubled)
    # the mirror rule at the start applied the wrong way round
    def unmirrored(points, kind, n, end_rule=None):
        if end_rule is None:
            return S.sample_curve(points, kind, n)
        P = np.asarray(points, float)
        ext = np.vstack([S.phantom_point(P[0], P[1], end_rule), P,
                         S.phantom_point(P[-2], P[-1], end_rule)])
        return S.sample_curve(ext, kind, n)
    assert _fails("sample_curve", unmirrored)
    # end_rows: rows multiplied into the transposed matrix; a table of the two bases' answers
    assert _fails("end_rows", lambda M: np.stack([S.parameter_row(1.0, k) @ np.asarray(M).T
                                                  for k in range(3)]))
    def two_bases_only(M):
        return S.end_rows(CR if np.allclose(M, CR) else BS)
    assert _fails("end_rows", two_bases_only)
    # end_rows without its ValueError for a matrix that is not 4 x 4
    assert _fails("end_rows", lambda M: np.stack([S.parameter_row(1.0, k) @ np.asarray(M)
                                                  for k in range(3)]))
    # accepting any rule name silently
    assert _fails("phantom_point", lambda b, c, rule: 2 * np.asarray(c, float) - b
                  if rule == "d=2c-b" else np.asarray(b if rule == "d=b" else c, float))
