"""Tests of course_lib.clipping (exam Q6) against the exam's numbers, shapely, mapbox-earcut,
brute-force pixel tests, Monte Carlo sampling and the laws clipping must obey."""

from __future__ import annotations

import mapbox_earcut
import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from scipy.spatial import Delaunay
from shapely.geometry import LineString, Polygon, box

from autograder.exercises.q6_clipping import same_polygon
from course_lib import _polygons as Pg
from course_lib import clipping as C

# The exam's screen coordinates (solutions to Q6(b)(ii)) and the clipped A of Q6(b)(iii).
A_SCREEN = np.array([[0, 0, 0.5], [0, 0.5, 0.5], [0, 0.5, 1.5]])
B_SCREEN = np.array([[0, 0, 0], [0, 0.5, 0], [0, 0.5, 1]])
A_CLIPPED_SCREEN = np.array([[0, 0, 0.5], [0, 0.5, 0.5], [0, 0.5, 1], [0, 0.25, 1]])
# Homogeneous versions used by the notebook: camera points (0, 0, 4), (0, 2, 4), (0, 6, 12) and
# (0, 0, 3), (0, 1.5, 3), (0, 3, 6) through the perspective with near 3, far 6, 90 degrees:
# X = x_c, Y = y_c, Z = 2 z_c - 6, w = z_c (worked out by hand).
A_H = np.array([[0, 0, 2, 4], [0, 2, 2, 4], [0, 6, 18, 12]], float)
B_H = np.array([[0, 0, 0, 3], [0, 1.5, 0, 3], [0, 3, 6, 6]], float)

SQUARE = box(-1, -1, 1, 1)
SETTINGS = settings(max_examples=60, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])


def homogeneous(screen, w):
    screen = np.asarray(screen, float)
    w = np.broadcast_to(np.asarray(w, float), screen.shape[:-1])[..., None]
    return np.concatenate([screen * w, w], axis=-1)


def in_box(P, tol=1e-9, atol=0.0):
    """The view-volume inequalities written out independently, with a tolerance relative to
    each vertex and an absolute one (``atol``): a vertex clipped next to the eye (w near 0) is
    tiny, and its rounding error is the input's, not its own size's."""
    X, Y, Z, w = P.T
    s = tol * np.max(np.abs(P), axis=1) + atol
    return ((-w - s <= X) & (X <= w + s) & (-w - s <= Y) & (Y <= w + s)
            & (-s <= Z) & (Z <= w + s))


def cyclic_match(a, b, atol=1e-9):
    """True when the rows of b are a cyclic shift of the rows of a."""
    if a.shape != b.shape:
        return False
    return any(np.allclose(np.roll(b, -k, axis=0), a, atol=atol) for k in range(len(b)))


def convex_polygon(rng, n, centre, radius):
    ang = np.sort(rng.uniform(0, 2 * np.pi, n))
    return np.asarray(centre) + radius * np.stack([np.cos(ang), np.sin(ang)], axis=1)


def star_polygon(rng, n):
    """A random simple star-shaped polygon (anticlockwise), generic positions."""
    ang = np.sort(rng.uniform(0, 2 * np.pi, n))
    while np.min(np.diff(np.r_[ang, ang[0] + 2 * np.pi])) < 1e-3:
        ang = np.sort(rng.uniform(0, 2 * np.pi, n))
    r = rng.uniform(0.2, 1.0, n)
    return np.stack([r * np.cos(ang), r * np.sin(ang)], axis=1)


# ------------------------------------------------------------------------------------------------
# the exam's numbers


def test_exam_triangles_come_from_the_perspective_matrix():
    np.testing.assert_allclose(C.EXAM_Q6["A"], A_H, atol=1e-12)
    np.testing.assert_allclose(C.EXAM_Q6["B"], B_H, atol=1e-12)
    # w is the depth z_c of each camera-space vertex, so it grows with distance
    np.testing.assert_allclose(C.EXAM_Q6["A"][:, 3], C.EXAM_Q6["A_camera"][:, 2], atol=1e-12)
    np.testing.assert_allclose(C.EXAM_Q6["B"][:, 3], C.EXAM_Q6["B_camera"][:, 2], atol=1e-12)


def test_exam_w_grows_with_depth():
    """The notebook says w grows with depth: vertices at the same z_s share w, deeper ones have
    larger w (checked on the divided coordinates of all six vertices)."""
    P = np.vstack([C.EXAM_Q6["A"], C.EXAM_Q6["B"]])
    z_s, w = P[:, 2] / P[:, 3], P[:, 3]
    order = np.argsort(z_s, kind="stable")
    assert np.all(np.diff(w[order]) >= 0)
    for i in range(len(P)):
        for j in range(len(P)):
            if np.isclose(z_s[i], z_s[j]):
                assert np.isclose(w[i], w[j])
            elif z_s[i] < z_s[j]:
                assert w[i] < w[j]


def test_perspective_matrix_maps_the_frustum_onto_the_view_volume():
    """Near plane -> z_s = 0, far plane -> z_s = 1, window edges -> x_s, y_s = +-1, w = depth,
    and z_s = far (1 - near / z_c) / (far - near) (the analytic form), for random cameras."""
    rng = np.random.default_rng(6)
    for _ in range(20):
        near = rng.uniform(0.1, 5.0)
        far = near + rng.uniform(0.1, 50.0)
        t = rng.uniform(0.2, 3.0)
        M = C.perspective_matrix(near, far, t)
        z = rng.uniform(0.5 * near, 2.0 * far, 200)
        x, y = rng.uniform(-1.5, 1.5, (2, 200)) * t * z
        P = np.stack([x, y, z, np.ones_like(z)], axis=1) @ M.T
        np.testing.assert_allclose(P[:, 3], z, atol=1e-12)
        s = P[:, :3] / P[:, 3:]
        np.testing.assert_allclose(s[:, 2], far * (1 - near / z) / (far - near), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(s[:, :2], np.stack([x, y], axis=1) / (t * z[:, None]), atol=1e-12)
        inside = (np.abs(x) <= t * z) & (np.abs(y) <= t * z) & (near <= z) & (z <= far)
        margin = np.minimum.reduce([t * z - np.abs(x), t * z - np.abs(y), z - near, far - z])
        clear = np.abs(margin) > 1e-9 * far
        assert np.array_equal(C.inside_view_volume(P)[clear], inside[clear])
        ends = np.array([[0.0, 0.0, near, 1.0], [0.0, 0.0, far, 1.0]]) @ M.T
        np.testing.assert_allclose(ends[:, 2] / ends[:, 3], [0.0, 1.0], atol=1e-12)


@pytest.mark.parametrize("args", [(0.0, 1.0), (2.0, 1.0), (1.0, 1.0), (-1.0, 2.0),
                                  (1.0, 2.0, 0.0), (1.0, np.inf), ([1.0, 2.0], 3.0)])
def test_perspective_matrix_rejects_bad_planes(args):
    with pytest.raises(ValueError):
        C.perspective_matrix(*args)


def test_exam_screen_coordinates():
    np.testing.assert_allclose(C.to_screen(A_H), A_SCREEN, atol=1e-12)
    np.testing.assert_allclose(C.to_screen(B_H), B_SCREEN, atol=1e-12)
    # the divide matters: w is not 1 for every vertex
    assert not np.allclose(A_H[:, 3], 1) and not np.allclose(B_H[:, 3], 1)


def test_exam_inside_outside():
    """Q6(b)(i): all of B inside; A's first two inside, its third outside (Z > w)."""
    assert C.inside_view_volume(A_H).tolist() == [True, True, False]
    assert C.inside_view_volume(B_H).tolist() == [True, True, True]
    assert A_H[2, 2] > A_H[2, 3]


def test_exam_clipped_A():
    """Q6(b)(iii): the far plane cuts two edges of A, giving four vertices."""
    got = C.to_screen(C.clip_polygon(A_H))
    assert cyclic_match(A_CLIPPED_SCREEN, got)
    # the exam's order exactly: surviving vertices first, then the two crossings
    np.testing.assert_allclose(got, A_CLIPPED_SCREEN, atol=1e-12)


def test_exam_B_unchanged_and_edge_on():
    np.testing.assert_array_equal(C.clip_polygon(B_H), B_H)
    # Q6(b)(ii): both triangles are seen edge-on: no screen area
    assert C.screen_area(A_SCREEN) == pytest.approx(0.0, abs=1e-12)
    assert C.screen_area(B_SCREEN) == pytest.approx(0.0, abs=1e-12)


@SETTINGS
@given(st.lists(st.floats(0.05, 20.0), min_size=3, max_size=3))
def test_exam_clip_independent_of_w(ws):
    """Any positive w per vertex is the same triangle A: same screen result after clipping."""
    got = C.to_screen(C.clip_polygon(homogeneous(A_SCREEN, ws)))
    np.testing.assert_allclose(got, A_CLIPPED_SCREEN, atol=1e-9)


def test_exam_clipped_fan():
    """The clipped A has four vertices: two triangles."""
    assert C.fan_triangulate(len(C.clip_polygon(A_H))).shape == (2, 3)


# ------------------------------------------------------------------------------------------------
# inside_view_volume and to_screen


def test_inside_boundary_and_negative_w():
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (0, 1)], float)
    assert C.inside_view_volume(homogeneous(corners, 3.0)).all()
    # a point behind the eye whose divide lands inside the box is still outside
    p = np.array([0.0, 0.0, -0.5, -1.0])
    assert np.allclose(C.to_screen(p), [0, 0, 0.5])
    assert not C.inside_view_volume(p)
    assert not C.inside_view_volume(np.zeros(4))


def test_inside_matches_screen_box_for_positive_w():
    rng = np.random.default_rng(0)
    screen = rng.uniform(-1.5, 1.5, (2000, 3))
    w = rng.uniform(0.1, 10, 2000)
    expected = np.all(np.abs(screen[:, :2]) <= 1, axis=1) & (screen[:, 2] >= 0) & (screen[:, 2] <= 1)
    got = C.inside_view_volume(homogeneous(screen, w))
    # rounding of screen * w can move points within 1 ulp of a face: ignore those
    near = np.min(np.abs(np.r_['1,2,0', np.abs(screen[:, :2]) - 1, screen[:, 2], screen[:, 2] - 1]),
                  axis=1) < 1e-12
    assert np.array_equal(got[~near], expected[~near])


def test_shapes():
    P = np.random.default_rng(1).uniform(0.1, 1, (2, 5, 4))
    assert C.inside_view_volume(P).shape == (2, 5)
    assert C.to_screen(P).shape == (2, 5, 3)
    assert C.inside_view_volume(P[0, 0]).shape == ()
    assert C.to_screen(np.zeros((0, 4))).shape == (0, 3)


# ------------------------------------------------------------------------------------------------
# clip_polygon against shapely (w > 0, Z-planes not cutting)


@pytest.mark.parametrize("seed", range(25))
def test_clip_matches_shapely_convex(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 10))
    xy = convex_polygon(rng, n, rng.uniform(-1, 1, 2), rng.uniform(0.3, 1.6))
    z = rng.uniform(0.1, 0.9, (n, 1))
    P = homogeneous(np.hstack([xy, z]), rng.uniform(0.2, 5, n))
    got = C.to_screen(C.clip_polygon(P)) if len(C.clip_polygon(P)) else np.zeros((0, 3))
    ref = Polygon(xy).intersection(SQUARE)
    assert C.screen_area(got) == pytest.approx(ref.area, rel=1e-9, abs=1e-12)
    if ref.area == 0:
        assert len(got) == 0
        return
    ref_xy = np.asarray(shapely.normalize(ref).exterior.coords)[:-1]
    assert len(ref_xy) == len(got)
    # same vertex sets
    d = np.linalg.norm(ref_xy[:, None, :] - got[None, :, :2], axis=2)
    assert np.all(d.min(axis=1) < 1e-9) and np.all(d.min(axis=0) < 1e-9)
    # z is interpolated linearly in screen space along each clipped edge: stays in (0.1, 0.9)
    assert np.all((got[:, 2] >= 0.1 - 1e-9) & (got[:, 2] <= 0.9 + 1e-9))


@pytest.mark.parametrize("seed", range(15))
def test_clip_area_matches_shapely_nonconvex(seed):
    """Sutherland-Hodgman on a non-convex polygon may join pieces by zero-width bridges along a
    clip edge, but the signed area is still that of the true intersection."""
    rng = np.random.default_rng(100 + seed)
    n = int(rng.integers(5, 14))
    xy = 1.6 * star_polygon(rng, n) + rng.uniform(-0.8, 0.8, 2)
    P = homogeneous(np.hstack([xy, np.full((n, 1), 0.5)]), rng.uniform(0.2, 5, n))
    clipped = C.clip_polygon(P)
    area = C.screen_area(C.to_screen(clipped)) if len(clipped) else 0.0
    assert area == pytest.approx(Polygon(xy).intersection(SQUARE).area, rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("seed", range(10))
def test_clip_monte_carlo_homogeneous(seed):
    """Triangles with w of both signs and cut by all six planes: sample the 4-D triangle,
    keep the samples inside the (independently coded) view volume, and check they are exactly
    the samples inside the clipped polygon's projection."""
    rng = np.random.default_rng(200 + seed)
    P = rng.uniform(-1.5, 1.5, (3, 4))
    P[:, 3] = rng.uniform(-0.5, 2, 3)
    P[:, 2] = rng.uniform(-0.5, 1.5, 3) * np.abs(P[:, 3])
    clipped = C.clip_polygon(P)
    bary = rng.dirichlet(np.ones(3), 4000)
    S = bary @ P
    inside = in_box(S, tol=0.0) & (S[:, 3] > 0)
    if len(clipped) == 0:
        assert inside.mean() < 1e-3
        return
    assert np.all(clipped[:, 3] > 0)
    poly = Polygon(C.to_screen(clipped)[:, :2])
    if poly.area < 1e-6:                   # seen edge-on: nothing to sample against
        return
    xy = S[inside, :2] / S[inside, 3:]
    far = np.abs(poly.exterior.distance(shapely.points(xy))) > 1e-7
    assert np.all(shapely.contains_xy(poly, *xy[far].T))
    out = ~inside & (np.abs(S[:, 3]) > 1e-6)
    xy_out = S[out, :2] / S[out, 3:]
    far = poly.exterior.distance(shapely.points(xy_out)) > 1e-7
    # a point outside the volume may still project into the polygon only if it is the mirror
    # image (w < 0) of a point in front, or outside in z; those with w > 0 and z_s in [0, 1]
    # must project outside
    Sw = S[out][far]
    zs = Sw[:, 2] / Sw[:, 3]
    front = (Sw[:, 3] > 0) & (zs > 1e-9) & (zs < 1 - 1e-9)
    assert not np.any(shapely.contains_xy(poly, *xy_out[far][front].T))


def test_negative_w_vertex_is_cut_before_divide():
    """An edge from a point in front of the eye to one behind it, through the left plane."""
    P = np.array([[0.0, 0.0, 0.5, 1.0], [0.5, 0.0, 0.5, 1.0], [0.5, 0.5, 0.5, -1.0]])
    out = C.clip_polygon(P)
    assert np.all(out[:, 3] > 0)
    assert np.all(in_box(out))
    # the divided third vertex (-0.5, -0.5, -0.5) would be below and left: dividing before
    # clipping gives a triangle in the wrong place with the opposite orientation
    wrong = C.screen_area(C.to_screen(P))
    right = C.screen_area(C.to_screen(out))
    assert np.sign(wrong) != np.sign(right) or wrong != pytest.approx(right)


# ------------------------------------------------------------------------------------------------
# laws (hypothesis)


@st.composite
def homogeneous_polygons(draw, lo=-2.0, hi=2.0, wpos=True, nmax=8):
    n = draw(st.integers(3, nmax))
    coords = draw(st.lists(st.tuples(st.floats(lo, hi), st.floats(lo, hi), st.floats(lo, hi)),
                           min_size=n, max_size=n))
    wl = 0.1 if wpos else -2.0
    ws = draw(st.lists(st.floats(wl, 4.0), min_size=n, max_size=n))
    P = np.array([[x * w, y * w, z * w, w] for (x, y, z), w in zip(coords, ws)])
    assume(np.all(np.any(P != 0, axis=1)))
    return P


@SETTINGS
@given(homogeneous_polygons(wpos=False))
def test_law_clipped_vertices_in_volume(P):
    out = C.clip_polygon(P)
    assert out.ndim == 2 and out.shape[1] == 4
    assert len(out) == 0 or len(out) >= 3
    # a crossing's rounding error scales with the edge's end points, not with the new vertex
    assert np.all(in_box(out, tol=1e-9, atol=1e-12 * np.max(np.abs(P))))


@SETTINGS
@given(homogeneous_polygons(wpos=False))
def test_law_idempotent(P):
    once = C.clip_polygon(P)
    assume(len(once) >= 3)
    twice = C.clip_polygon(once)
    assert same_polygon(once, twice) is None
    np.testing.assert_allclose(twice, once, atol=1e-9)


@SETTINGS
@given(homogeneous_polygons(lo=-1.0, hi=1.0))
def test_law_inside_unchanged(P):
    P[:, 2] = np.abs(P[:, 2])   # z_s in [0, 1]
    assert C.inside_view_volume(P).all()
    np.testing.assert_array_equal(C.clip_polygon(P), P)


@SETTINGS
@given(homogeneous_polygons(lo=-1.0, hi=1.0), st.integers(0, 5), st.floats(1.001, 3.0))
def test_law_outside_empty(P, plane, shift):
    """Move every vertex beyond one plane: nothing is left."""
    screen = C.to_screen(P)
    axis = plane // 2 if plane < 4 else 2
    if plane in (0, 2):
        screen[:, axis] -= 2 * shift
    elif plane in (1, 3):
        screen[:, axis] += 2 * shift
    elif plane == 4:
        screen[:, 2] = 1.0 - shift - np.abs(screen[:, 2])        # z_s < 0
    else:
        screen[:, 2] = shift + np.abs(screen[:, 2])              # z_s > 1
    Q = homogeneous(screen, P[:, 3])
    assert not C.inside_view_volume(Q).any()
    out = C.clip_polygon(Q)
    assert out.shape == (0, 4)


@SETTINGS
@given(homogeneous_polygons(nmax=3))
def test_law_orientation_and_area_bound(P):
    """A clipped triangle (w > 0) is a piece of it: same orientation, no more screen area."""
    before = C.screen_area(C.to_screen(P))
    assume(abs(before) > 1e-6)
    out = C.clip_polygon(P)
    if len(out):
        after = C.screen_area(C.to_screen(out))
        assert after * np.sign(before) >= -1e-12
        assert abs(after) <= abs(before) + 1e-9


def test_clip_steps():
    steps = C.clip_steps(A_H)
    assert len(steps) == 7
    np.testing.assert_array_equal(steps[0], A_H)
    for k in range(1, 6):          # only the far plane (the 6th) cuts A
        np.testing.assert_array_equal(steps[k], A_H)
    assert same_polygon(C.clip_polygon(A_H), steps[6]) is None


# ------------------------------------------------------------------------------------------------
# screen_area, fan_triangulate


@pytest.mark.parametrize("seed", range(10))
def test_screen_area_matches_shapely(seed):
    rng = np.random.default_rng(300 + seed)
    xy = star_polygon(rng, int(rng.integers(3, 20))) * 5 + rng.uniform(-100, 100, 2)
    P = np.hstack([xy, rng.uniform(0, 1, (len(xy), 1))])
    assert C.screen_area(P) == pytest.approx(Polygon(xy).area, rel=1e-9)
    assert C.screen_area(P[::-1]) == pytest.approx(-Polygon(xy).area, rel=1e-9)


@pytest.mark.parametrize("m", [3, 4, 5, 9, 30])
def test_fan_covers_convex_polygon(m):
    rng = np.random.default_rng(m)
    xy = convex_polygon(rng, m, (0.3, -0.2), 2.0)
    tris = C.fan_triangulate(m)
    assert tris.shape == (m - 2, 3) and tris.dtype.kind == "i"
    areas = [Pg.polygon_area(xy[t]) for t in tris]
    assert all(a > 0 for a in areas)
    assert sum(areas) == pytest.approx(Polygon(xy).area, rel=1e-12)
    union = shapely.union_all([Polygon(xy[t]) for t in tris])
    assert union.symmetric_difference(Polygon(xy)).area < 1e-9
    assert set(tris.ravel()) == set(range(m))


# ------------------------------------------------------------------------------------------------
# ear clipping against mapbox-earcut and shapely


@pytest.mark.parametrize("seed", range(30))
def test_ear_clip_matches_earcut(seed):
    rng = np.random.default_rng(400 + seed)
    n = int(rng.integers(3, 40))
    xy = star_polygon(rng, n)
    if seed % 2:
        xy = xy[::-1]                               # clockwise too
    mine = Pg.ear_clip(xy)
    ref = mapbox_earcut.triangulate_float64(xy, np.array([n], dtype=np.uint32)).reshape(-1, 3)
    assert mine.shape == ref.shape == (n - 2, 3)
    area = Polygon(xy).area
    my_areas = np.array([Pg.polygon_area(xy[t]) for t in mine])
    ref_areas = np.abs([Polygon(xy[t]).area for t in ref])
    assert np.abs(my_areas).sum() == pytest.approx(area, rel=1e-9)
    assert ref_areas.sum() == pytest.approx(area, rel=1e-9)
    # same orientation as the polygon, no overlap, nothing outside
    sign = np.sign(Pg.polygon_area(xy))
    assert np.all(sign * my_areas > 0)
    union = shapely.union_all([Polygon(xy[t]) for t in mine])
    assert union.symmetric_difference(Polygon(xy)).area < 1e-9 * max(area, 1)


def test_ear_clip_notched_polygons():
    """A comb and an L, with collinear vertices: n - 2 triangles, the right area."""
    comb = np.array([[0, 0], [5, 0], [5, 3], [4, 3], [4, 1], [3, 1], [3, 3], [2, 3], [2, 1],
                     [1, 1], [1, 3], [0, 3]], float)
    L = np.array([[0, 0], [1, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2], [0, 1]], float)
    for poly in (comb, L):
        tris = Pg.ear_clip(poly)
        assert tris.shape == (len(poly) - 2, 3)
        areas = np.array([Pg.polygon_area(poly[t]) for t in tris])
        assert np.all(areas >= -1e-12)
        assert areas.sum() == pytest.approx(Polygon(poly).area)
        union = shapely.union_all([Polygon(poly[t]) for t in tris if Pg.polygon_area(poly[t]) > 0])
        assert union.symmetric_difference(Polygon(poly)).area < 1e-9


def test_is_convex():
    rng = np.random.default_rng(5)
    assert Pg.is_convex(convex_polygon(rng, 7, (0, 0), 1))
    assert not Pg.is_convex([[0, 0], [2, 0], [1, 0.5], [2, 2], [0, 2]])
    pentagram = np.array([[np.cos(a), np.sin(a)] for a in np.arange(5) * 4 * np.pi / 5])
    assert not Pg.is_convex(pentagram)


# ------------------------------------------------------------------------------------------------
# spans and rasterisation


@pytest.mark.parametrize("seed", range(20))
def test_scanline_span_matches_shapely(seed):
    rng = np.random.default_rng(500 + seed)
    tri = rng.uniform(-5, 5, (3, 2))
    for y in rng.uniform(-6, 6, 10):
        got = C.scanline_span(tri, y)
        cut = Polygon(tri).intersection(LineString([(-20, y), (20, y)]))
        if cut.is_empty:
            assert got is None
        else:
            xmin, _, xmax, _ = cut.bounds
            assert got == pytest.approx((xmin, xmax), abs=1e-9)


def test_scanline_span_edges_and_vertices():
    tri = np.array([[0, 0], [4, 0], [0, 2]], float)
    assert C.scanline_span(tri, 0.0) == pytest.approx((0.0, 4.0), abs=1e-12)   # the bottom edge
    assert C.scanline_span(tri, 2.0) == pytest.approx((0.0, 0.0), abs=1e-12)   # the apex
    assert C.scanline_span(tri, 2.0 + 1e-9) is None
    x = C.scanline_span(tri, 0.5)
    assert isinstance(x, tuple) and all(type(v) is float for v in x)


@pytest.mark.parametrize("seed", range(12))
def test_polygon_spans_match_shapely(seed):
    rng = np.random.default_rng(600 + seed)
    xy = star_polygon(rng, int(rng.integers(6, 25)))
    poly = Polygon(xy)
    for y in rng.uniform(-1, 1, 8):
        spans = Pg.polygon_spans(xy, y)
        cut = poly.intersection(LineString([(-3, y), (3, y)]))
        pieces = [] if cut.is_empty else getattr(cut, "geoms", [cut])
        pieces = sorted((g.bounds[0], g.bounds[2]) for g in pieces if g.length > 0)
        assert len(spans) == len(pieces)
        np.testing.assert_allclose(np.array(spans).reshape(-1, 2),
                                   np.array(pieces).reshape(-1, 2), atol=1e-9)


def test_nonconvex_has_several_spans():
    """Q6(c): a non-convex polygon can need more than one span on a scanline, a triangle never."""
    comb = np.array([[0, 0], [5, 0], [5, 3], [4, 3], [4, 1], [3, 1], [3, 3], [2, 3], [2, 1],
                     [1, 1], [1, 3], [0, 3]], float)
    assert Pg.polygon_spans(comb, 2.0) == [(0.0, 1.0), (2.0, 3.0), (4.0, 5.0)]
    for tri in Pg.ear_clip(comb):
        assert len(Pg.polygon_spans(comb[tri], 2.0)) <= 1


def _barycentric_inside(tri, pts):
    """Independent point-in-triangle test by solving for barycentric coordinates."""
    T = np.array([[tri[0, 0] - tri[2, 0], tri[1, 0] - tri[2, 0]],
                  [tri[0, 1] - tri[2, 1], tri[1, 1] - tri[2, 1]]])
    lam = np.linalg.solve(T, (pts - tri[2]).T)
    l3 = 1 - lam.sum(axis=0)
    return np.all(np.vstack([lam, l3]) > 0, axis=0), np.min(np.abs(np.vstack([lam, l3])), axis=0)


@pytest.mark.parametrize("seed", range(20))
def test_rasterize_matches_brute_force(seed):
    rng = np.random.default_rng(700 + seed)
    W, H = 40, 30
    tri = rng.uniform([-5, -5], [W + 5, H + 5], (3, 2))
    mask = C.rasterize_triangle(tri, W, H)
    cy, cx = np.mgrid[0:H, 0:W] + 0.5
    pts = np.stack([cx.ravel(), cy.ravel()], axis=1)
    inside, margin = _barycentric_inside(tri, pts)
    clear = margin > 1e-9                  # centres not on an edge: no fill rule needed
    assert np.array_equal(mask.ravel()[clear], inside[clear])


@pytest.mark.parametrize("seed", range(12))
def test_rasterize_one_span_per_row_matches_scanline_span(seed):
    rng = np.random.default_rng(800 + seed)
    W, H = 50, 50
    tri = rng.uniform(0, 50, (3, 2))
    spans = C.triangle_spans(tri, W, H)
    mask = C.rasterize_triangle(tri, W, H)
    assert len(spans) == mask.any(axis=1).sum()
    for row, c0, c1 in spans:
        xl, xr = C.scanline_span(tri, row + 0.5)
        cols = np.arange(W) + 0.5
        expected = np.flatnonzero((cols >= xl) & (cols < xr))
        assert np.array_equal(np.arange(c0, c1 + 1), expected)


@pytest.mark.parametrize("seed", range(8))
def test_top_left_rule_tiles_exactly_once(seed):
    """Vertices on half-integers put many pixel centres exactly on shared edges; with the
    top-left rule every centre strictly inside the mesh is drawn exactly once."""
    rng = np.random.default_rng(900 + seed)
    W = H = 16
    pts = np.unique(rng.integers(0, 16, (30, 2)), axis=0) + 0.5
    pts = np.vstack([pts, [[0.5, 0.5], [15.5, 0.5], [0.5, 15.5], [15.5, 15.5]]])
    tri = Delaunay(pts)
    count = np.zeros((H, W), int)
    for s in tri.simplices:
        count += C.rasterize_triangle(pts[s], W, H)
    assert count.max() == 1
    # interior of the square [0.5, 15.5]^2: centres 1.5 .. 14.5 are all covered
    assert np.all(count[1:15, 1:15] == 1)
    # left/top border (x = 0.5 or y = 0.5) is drawn, right/bottom (15.5) is not
    assert np.all(count[0, :15] == 1) and np.all(count[:15, 0] == 1)
    assert np.all(count[15, :] == 0) and np.all(count[:, 15] == 0)


def test_rasterize_degenerate_and_orientation():
    tri = np.array([[1.0, 1.0], [9.0, 2.0], [3.0, 8.0]])
    np.testing.assert_array_equal(C.rasterize_triangle(tri, 12, 12),
                                  C.rasterize_triangle(tri[::-1], 12, 12))
    assert not C.rasterize_triangle([[0, 0], [5, 5], [10, 10]], 12, 12).any()


# ------------------------------------------------------------------------------------------------
# bad input


@pytest.mark.parametrize("call", [
    lambda: C.inside_view_volume(np.ones((3, 3))),
    lambda: C.inside_view_volume([[0, 0, np.nan, 1]]),
    lambda: C.to_screen([1, 2, 3, 0]),
    lambda: C.to_screen(np.ones(3)),
    lambda: C.clip_polygon(np.ones((2, 4))),
    lambda: C.clip_polygon(np.ones((3, 3))),
    lambda: C.clip_polygon([[0, 0, 0, 0], [1, 0, 0, 1], [0, 1, 0, 1]]),
    lambda: C.screen_area(np.ones(4)),
    lambda: C.screen_area(np.ones((4, 4))),
    lambda: C.fan_triangulate(2),
    lambda: C.fan_triangulate(3.5),
    lambda: C.fan_triangulate(True),
    lambda: C.scanline_span(np.ones((4, 2)), 0.0),
    lambda: C.scanline_span(np.ones((3, 2)), [0.0, 1.0]),
    lambda: Pg.ear_clip([[0, 0], [1, 1], [2, 2]]),
    lambda: C.rasterize_triangle(np.ones((3, 2)), 0, 5),
])
def test_value_errors(call):
    with pytest.raises(ValueError):
        call()


def test_error_messages_name_the_argument():
    with pytest.raises(ValueError, match="P"):
        C.clip_polygon(np.ones((3, 3)))
    with pytest.raises(ValueError, match="w = 0"):
        C.to_screen([1, 2, 3, 0])
    with pytest.raises(ValueError, match="m"):
        C.fan_triangulate(1)


# ------------------------------------------------------------------------------------------------
# the registry's comparison rule for clip_polygon


def test_same_polygon_rule():
    rng = np.random.default_rng(11)
    P = rng.uniform(0.1, 1, (5, 4))
    scaled = np.roll(P, 2, axis=0) * rng.uniform(0.1, 9, (5, 1))
    assert same_polygon(P, scaled) is None
    assert same_polygon(P, np.insert(P, 1, P[0] * 3, axis=0)) is None      # repeated vertex
    assert "reverse" in same_polygon(P, P[::-1])
    assert same_polygon(P, -P) is not None                                 # negative scale
    assert same_polygon(P, P[:4]) is not None
    assert same_polygon(np.zeros((0, 4)), np.zeros((0, 4))) is None
    assert same_polygon(np.zeros((0, 4)), P) is not None
    assert same_polygon(P, P.tolist()) is not None


# ------------------------------------------------------------------------------------------------
# the fast paths: Python floats for small polygons, NumPy for large ones, the batch API


def naive_sutherland_hodgman(P):
    """Textbook Sutherland-Hodgman, one vertex at a time, with the crossing written as
    S + t (E - S): an oracle independent of the module's code (no tolerance, no shortcuts)."""
    poly = [list(map(float, v)) for v in P]
    for n in C.PLANES.tolist():
        out = []
        for i, s in enumerate(poly):
            e = poly[(i + 1) % len(poly)]
            ds = sum(a * b for a, b in zip(n, s))
            de = sum(a * b for a, b in zip(n, e))
            if ds >= 0:
                out.append(s)
            if ds * de < 0:
                t = ds / (ds - de)
                out.append([a + t * (b - a) for a, b in zip(s, e)])
        poly = out
        if len(poly) < 3:
            return np.zeros((0, 4))
    return np.array(poly)


def random_homogeneous_polygon(rng, n, negative_w=False):
    """A convex screen polygon around a random centre, cut by several planes, random w."""
    ang = np.sort(rng.uniform(0, 2 * np.pi, n))
    xy = rng.uniform(-1, 1, 2) + rng.uniform(0.3, 1.5) * np.stack([np.cos(ang), np.sin(ang)], 1)
    z = rng.uniform(-0.4, 1.4, n)
    w = rng.uniform(0.2, 3.0, n)
    P = np.column_stack([xy * w[:, None], z * w, w])
    if negative_w:
        P[rng.integers(n)] *= -rng.uniform(0.5, 2)      # one vertex behind the eye
    return P


@pytest.mark.parametrize("n", [3, 4, 5, 8, 40, 300])
def test_clip_matches_naive_oracle(n):
    """Small (Python) and large (NumPy) polygons, w of both signs: the same vertices as the
    textbook algorithm, in the same order."""
    rng = np.random.default_rng(1000 + n)
    for k in range(60 if n < 100 else 6):
        P = random_homogeneous_polygon(rng, n, negative_w=k % 3 == 0)
        got, ref = C.clip_polygon(P), naive_sutherland_hodgman(P)
        assert got.shape == ref.shape
        np.testing.assert_allclose(got, ref, rtol=1e-9, atol=1e-12 * np.abs(P).max())


def test_clip_on_plane_vertices():
    """Integer polygons put many vertices exactly on planes (d = 0). The oracle, having no
    tolerance, may repeat a vertex when its rounding puts a crossing 1e-17 beyond a later
    plane; up to such repeats (the registry's rule) the two agree."""
    rng = np.random.default_rng(7)
    checked = 0
    for _ in range(400):
        n = int(rng.integers(3, 7))
        P = rng.integers(-3, 4, (n, 4)).astype(float)
        if np.any(np.all(P == 0, axis=1)):
            continue
        ref = naive_sutherland_hodgman(P)
        # a crossing at the 4-D origin is dropped by clip_polygon but not by the oracle
        if len(ref) and np.any(np.all(np.abs(ref) < 1e-12, axis=1)):
            continue
        got = C.clip_polygon(P)
        assert (len(got) == 0) == (len(ref) == 0)
        if len(got):
            assert same_polygon(ref, got) is None
        checked += 1
    assert checked > 300


@SETTINGS
@given(homogeneous_polygons(wpos=False))
def test_python_path_equals_numpy_passes(P):
    """clip_polygon's float path returns the very bits of six public NumPy passes
    (clip_against_plane), including on-plane and w < 0 vertices."""
    Q = P
    for k in range(6):
        Q = C.clip_against_plane(Q, k)
        if len(Q) < 3:
            Q = np.zeros((0, 4))
            break
    got = C.clip_polygon(P)
    assert got.shape == Q.shape and got.dtype == np.float64
    # bit-exact by construction: both run the same elementwise interpolation on the same inputs
    np.testing.assert_array_equal(got, Q)


def test_clip_polygon_large_path_equals_python_path():
    """A polygon above the size threshold goes through the NumPy passes; the float passes on
    the same polygon give the same bits."""
    rng = np.random.default_rng(3)
    n = C._SMALL_POLYGON + 50
    P = random_homogeneous_polygon(rng, n)
    big = C.clip_polygon(P)
    small_parts = C._clip_rows(P.tolist(), float(np.abs(P).max()))
    # bit-exact by construction: every plane has exactly two non-zero coefficients (+-1), so
    # the signed distance X + w (etc.) is one correctly rounded addition in any summation order,
    # BLAS or Python, and both paths then apply the same elementwise interpolation
    np.testing.assert_array_equal(big, np.array(small_parts).reshape(-1, 4))


def test_clip_returns_copies_and_keeps_inputs():
    P = np.array(B_H)
    out = C.clip_polygon(P)
    np.testing.assert_array_equal(out, B_H)
    assert not np.shares_memory(out, P)
    out[0, 0] = 99.0
    np.testing.assert_array_equal(P, B_H)
    # ints and lists accepted, result float64
    assert C.clip_polygon(B_H.astype(int).tolist()).dtype == np.float64


@pytest.mark.filterwarnings("ignore:overflow encountered")
def test_clip_huge_finite_coordinates_accepted():
    """Coordinates near the float limit: their sum overflows, yet they are finite and valid."""
    P = np.array([[0.0, 0.0, 1e308, 1.7e308], [1e308, 0.0, 1e308, 1.7e308],
                  [0.0, 1e308, 1e308, 1.7e308]])
    assert C.inside_view_volume(P).all()
    np.testing.assert_array_equal(C.clip_polygon(P), P)
    np.testing.assert_array_equal(C.clip_polygons([P])[0], P)


@pytest.mark.parametrize("bad", [
    [[0.0, 0.0, np.nan, 1.0], [1, 0, 0, 1], [0, 1, 0, 1]],
    [[0.0, 0.0, np.inf, 1.0], [1, 0, 0, 1], [0, 1, 0, 1]],
    [[-0.0, 0.0, 0.0, -0.0], [1, 0, 0, 1], [0, 1, 0, 1]],
])
def test_clip_rejects_nonfinite_and_zero_vertices(bad):
    with pytest.raises(ValueError, match="P"):
        C.clip_polygon(bad)
    with pytest.raises(ValueError, match=r"polygons\[1\]"):
        C.clip_polygons([A_H, bad])


@SETTINGS
@given(st.lists(homogeneous_polygons(wpos=False), min_size=1, max_size=12))
def test_clip_polygons_equals_clip_polygon(polys):
    got = C.clip_polygons(polys)
    assert isinstance(got, list) and len(got) == len(polys)
    for P, g in zip(polys, got):
        ref = C.clip_polygon(P)
        assert g.shape == ref.shape and g.dtype == np.float64
        # bit-exact by construction (see test_clip_polygon_large_path_equals_python_path)
        np.testing.assert_array_equal(g, ref)
        assert not np.shares_memory(g, P)


def test_clip_polygons_mixed_sizes_and_forms():
    rng = np.random.default_rng(12)
    polys = [random_homogeneous_polygon(rng, n, negative_w=n % 2 == 0)
             for n in (3, 4, C._SMALL_POLYGON + 10, 5, 3, 9)]
    polys.append(A_H.tolist())                  # a nested list
    polys.append((2 * B_H).astype(int))         # an integer array (B, each vertex scaled by 2)
    got = C.clip_polygons(polys)
    for P, g in zip(polys, got):
        np.testing.assert_array_equal(g, C.clip_polygon(P))
        assert g.shape == naive_sutherland_hodgman(P).shape
    np.testing.assert_allclose(C.to_screen(got[-2]), A_CLIPPED_SCREEN, atol=1e-12)
    np.testing.assert_array_equal(got[-1], 2 * B_H)
    # writing into one result touches no other
    before = [g.copy() for g in got]
    got[0][...] = -1.0
    for g, b in zip(got[1:], before[1:]):
        np.testing.assert_array_equal(g, b)
    # a (k, n, 4) array of triangles, an empty list, a generator
    tris = np.stack([A_H, B_H, A_H])
    assert [len(g) for g in C.clip_polygons(tris)] == [4, 3, 4]
    assert C.clip_polygons([]) == []
    assert [len(g) for g in C.clip_polygons(p for p in (A_H, B_H))] == [4, 3]


def test_clip_polygons_empty_results():
    """Polygons wholly outside, or cut down to an edge, come back as (0, 4) arrays."""
    outside = homogeneous(A_SCREEN + [3.0, 0, 0], 2.0)              # beyond the right plane
    edge_on = np.array([[1.0, 0, 0.5, 1], [2, 0.5, 0.5, 1], [2, -0.5, 0.5, 1]])  # touches x = w
    behind = -np.abs(homogeneous(A_SCREEN, 1.0))                    # every w < 0
    got = C.clip_polygons([outside, A_H, edge_on, behind])
    assert [g.shape for g in got] == [(0, 4), (4, 4), (0, 4), (0, 4)]
    for P in (outside, edge_on, behind):
        assert C.clip_polygon(P).shape == (0, 4)


@pytest.mark.parametrize("call, match", [
    (lambda: C.clip_polygons([A_H, np.ones((2, 4))]), r"polygons\[1\].*at least 3"),
    (lambda: C.clip_polygons([A_H, np.ones((3, 3))]), r"polygons\[1\].*shape"),
    (lambda: C.clip_polygons([A_H, "abc"]), r"polygons\[1\]"),
    (lambda: C.clip_polygons([[[0, 0, np.nan, 1]] * 3, np.ones((2, 4))]), r"polygons\[0\].*finite"),
    (lambda: C.clip_polygons(np.ones((4, 4))), r"polygons\[0\]"),
])
def test_clip_polygons_value_errors(call, match):
    with pytest.raises(ValueError, match=match):
        call()
