"""Tests of course_lib.mesh (Q3(d)): projected-prism volume, closedness, area.

Oracles: trimesh (volume, area, watertightness, winding), analytic volumes of boxes, spheres
and tetrahedra, a Monte Carlo count for a single prism, and the laws the derivation implies
(independence of the direction of projection, antisymmetry under a change of winding).
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.spatial import ConvexHull

from course_lib import mesh

finite = st.floats(-10, 10, allow_nan=False)
vec3 = st.tuples(finite, finite, finite).map(np.array)


def _closed_meshes():
    box = trimesh.creation.box(extents=(2.0, 3.0, 5.0))
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=1.7)
    torus = trimesh.creation.torus(major_radius=3.0, minor_radius=1.0)
    rng = np.random.default_rng(4)
    pts = rng.normal(size=(40, 3))
    hull = trimesh.Trimesh(pts, ConvexHull(pts).simplices, process=False)
    trimesh.repair.fix_normals(hull)
    return [box, sphere, torus, hull]


# --------------------------------------------------------------------------------------------
# triangle_projected_volume, equation (4)


def test_prism_of_a_flat_triangle():
    # unit right triangle at height 2 above the plane z = 0: area 1/2, height 2
    assert (mesh.triangle_projected_volume([0, 0, 2], [1, 0, 2], [0, 1, 2], [0, 0, 1])
            == pytest.approx(1.0, abs=1e-12))
    # clockwise seen from +z: negative
    assert (mesh.triangle_projected_volume([0, 0, 2], [0, 1, 2], [1, 0, 2], [0, 0, 1])
            == pytest.approx(-1.0, abs=1e-12))
    # the length of n does not matter
    assert (mesh.triangle_projected_volume([0, 0, 2], [1, 0, 2], [0, 1, 2], [0, 0, 7])
            == pytest.approx(1.0, abs=1e-12))


def test_prism_volume_monte_carlo():
    """A tilted triangle above z = 0: count random points between it and its shadow."""
    a, b, c = np.array([0.1, 0.2, 1.0]), np.array([0.9, 0.1, 2.0]), np.array([0.4, 0.95, 0.5])
    rng = np.random.default_rng(0)
    n = 400_000
    p = rng.uniform([0, 0, 0], [1, 1, 2], size=(n, 3))
    # barycentric coordinates of (x, y) in the projected triangle
    T = np.array([[b[0] - a[0], c[0] - a[0]], [b[1] - a[1], c[1] - a[1]]])
    uv = np.linalg.solve(T, (p[:, :2] - a[:2]).T).T
    inside = (uv[:, 0] >= 0) & (uv[:, 1] >= 0) & (uv.sum(1) <= 1)
    height = a[2] + uv[:, 0] * (b[2] - a[2]) + uv[:, 1] * (c[2] - a[2])
    mc = 2.0 * np.mean(inside & (p[:, 2] <= height))
    got = mesh.triangle_projected_volume(a, b, c, [0, 0, 1])
    assert abs(got) == pytest.approx(mc, rel=0.01)


@settings(max_examples=80, deadline=None)
@given(vec3, vec3, vec3, vec3)
def test_projected_volume_antisymmetric_and_cyclic(a, b, c, n):
    assume(np.linalg.norm(n) > 1e-3)
    v = mesh.triangle_projected_volume(a, b, c, n)
    scale = 1e-9 * (1 + np.max(np.abs([a, b, c])) ** 3)
    assert mesh.triangle_projected_volume(b, a, c, n) == pytest.approx(-v, abs=scale)
    assert mesh.triangle_projected_volume(a, c, b, n) == pytest.approx(-v, abs=scale)
    assert mesh.triangle_projected_volume(b, c, a, n) == pytest.approx(v, abs=scale)
    assert mesh.triangle_projected_volume(a, b, c, -n) == pytest.approx(v, abs=scale)


def test_projected_volume_batches_and_broadcasts():
    rng = np.random.default_rng(2)
    a, b, c = rng.normal(size=(3, 6, 3))
    n = np.array([0.3, -0.2, 0.9])
    batch = mesh.triangle_projected_volume(a, b, c, n)
    assert batch.shape == (6,)
    nh = n / np.linalg.norm(n)
    for k in range(6):
        # equation (2) times equation (3), written out by hand
        area = 0.5 * np.dot(np.cross(b[k] - a[k], c[k] - a[k]), nh)
        height = np.dot(a[k] + b[k] + c[k], nh) / 3
        assert batch[k] == pytest.approx(area * height)


@pytest.mark.parametrize("args", [
    ([0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]),
    ([0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 0]),
    (np.zeros((2, 3)), np.zeros((3, 3)), np.zeros((3, 3)), [0, 0, 1]),
])
def test_projected_volume_errors(args):
    with pytest.raises(ValueError):
        mesh.triangle_projected_volume(*args)


# --------------------------------------------------------------------------------------------
# mesh_volume, is_closed_consistent, area, boundary


@pytest.mark.parametrize("k", range(4))
def test_mesh_volume_matches_trimesh(k):
    tm = _closed_meshes()[k]
    v, f = np.asarray(tm.vertices, float), np.asarray(tm.faces, np.int64)
    assert tm.is_watertight and tm.is_winding_consistent
    assert mesh.mesh_volume(v, f) == pytest.approx(tm.volume, rel=1e-10)
    assert mesh.surface_area(v, f) == pytest.approx(tm.area, rel=1e-10)
    assert mesh.is_closed_consistent(f)
    assert mesh.mesh_volume(v, f[:, ::-1]) == pytest.approx(-tm.volume, rel=1e-10)


def test_box_volume_is_exact():
    tm = trimesh.creation.box(extents=(2.0, 3.0, 5.0))
    assert mesh.mesh_volume(tm.vertices, tm.faces) == pytest.approx(30.0, rel=1e-12)
    assert mesh.surface_area(tm.vertices, tm.faces) == pytest.approx(2 * (6 + 10 + 15))


@settings(max_examples=40, deadline=None)
@given(vec3, vec3, st.integers(0, 3))
def test_volume_independent_of_direction_and_origin(n, shift, k):
    assume(np.linalg.norm(n) > 1e-3)
    tm = _MESHES[k]
    v, f = np.asarray(tm.vertices, float), np.asarray(tm.faces, np.int64)
    expected = tm.volume
    assert mesh.mesh_volume(v, f, n) == pytest.approx(expected, rel=1e-9)
    assert mesh.mesh_volume(v + shift, f, n) == pytest.approx(expected, rel=1e-8, abs=1e-8)


_MESHES = _closed_meshes()


def test_open_mesh_depends_on_direction():
    """Without closedness the sum is not a volume: it changes with n (Q3(d) conditions)."""
    tm = trimesh.creation.icosphere(subdivisions=1)
    f = np.asarray(tm.faces)[1:]
    v = np.asarray(tm.vertices) + [3.0, 1.0, 2.0]
    assert not mesh.is_closed_consistent(f)
    vols = [mesh.mesh_volume(v, f, n) for n in ([1, 0, 0], [0, 1, 0], [0, 0, 1])]
    assert np.ptp(vols) > 1e-3


def test_is_closed_consistent_against_trimesh():
    rng = np.random.default_rng(7)
    tm = trimesh.creation.icosphere(subdivisions=1)
    faces = np.asarray(tm.faces, np.int64)
    for trial in range(40):
        f = faces.copy()
        kind = trial % 4
        if kind == 1:                                    # flip one face
            i = rng.integers(len(f))
            f[i] = f[i, ::-1]
        elif kind == 2:                                  # drop a face: a hole
            f = np.delete(f, rng.integers(len(f)), axis=0)
        elif kind == 3:                                  # duplicate a face: non-manifold
            f = np.vstack([f, f[rng.integers(len(f))]])
        t = trimesh.Trimesh(tm.vertices, f, process=False)
        expected = bool(t.is_watertight and t.is_winding_consistent)
        assert mesh.is_closed_consistent(f) == expected == (kind == 0)


def test_boundary_edges_against_trimesh():
    tm = trimesh.creation.icosphere(subdivisions=1)
    f = np.asarray(tm.faces, np.int64)[3:]
    ours = {frozenset(e) for e in mesh.boundary_edges(f).tolist()}
    e = np.sort(trimesh.Trimesh(tm.vertices, f, process=False).edges, axis=1)
    once = trimesh.grouping.group_rows(e, require_count=1)
    theirs = {frozenset(x) for x in e[once].tolist()}
    assert ours == theirs and len(ours) > 0
    assert len(mesh.boundary_edges(tm.faces)) == 0


def test_tetrahedron_and_empty():
    v = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    f = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    assert mesh.mesh_volume(v, f) == pytest.approx(1 / 6)
    assert mesh.mesh_volume(v, np.zeros((0, 3), int)) == 0.0
    assert mesh.is_closed_consistent(np.zeros((0, 3), int))


def test_canonical_triangles_ignores_order():
    tm = trimesh.creation.icosphere(subdivisions=1)
    v, f = np.asarray(tm.vertices), np.asarray(tm.faces)
    rng = np.random.default_rng(3)
    perm = rng.permutation(len(v))
    inv = np.argsort(perm)
    f2 = inv[f][rng.permutation(len(f))]
    f2 = np.roll(f2, 1, axis=1)
    a = mesh.canonical_triangles(v, f)
    assert np.array_equal(a, mesh.canonical_triangles(v[perm], f2))
    assert not np.array_equal(a, mesh.canonical_triangles(v, f[:, ::-1]))


@pytest.mark.parametrize("args", [
    (np.zeros((4, 3)), [[0, 1, 4]]),                  # index out of range
    (np.zeros((4, 3)), [[0, 1, -1]]),                 # negative index
    (np.zeros((4, 2)), [[0, 1, 2]]),                  # 2-D vertices
    (np.zeros((4, 3)), [[0, 1, 2, 3]]),               # quads
    (np.zeros((4, 3)), [[0, 1, 2.5]]),                # non-integer index
    (np.zeros((4, 3)), [[0, 1, 2]], [0, 0, 0]),       # zero direction
])
def test_mesh_volume_errors(args):
    with pytest.raises(ValueError):
        mesh.mesh_volume(*args)


def test_is_closed_consistent_errors():
    with pytest.raises(ValueError):
        mesh.is_closed_consistent([[0, 1]])
    with pytest.raises(ValueError):
        mesh.is_closed_consistent([[0, 1, -2]])
