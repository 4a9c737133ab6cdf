"""Tests of course_lib.marching_cubes (Q3(a)-(c)).

Oracles: the exam's own example (iso 10 between 7 and 13 is half way), Bourke's published edge
table, group theory recomputed here from an independently generated rotation group, scikit-image
(``skimage.measure.marching_cubes`` and ``skimage.draw.ellipsoid_stats``), PyMCubes (classic
Bourke tables), trimesh, and analytic volumes and areas of the sphere, ellipsoid and torus.
"""

from __future__ import annotations

import itertools

import mcubes
import numpy as np
import pytest
import skimage.draw
import skimage.measure
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from course_lib import _mc_case_data, _mc_tables
from course_lib import marching_cubes as mc
from course_lib import mesh

# --------------------------------------------------------------------------------------------
# helpers independent of the module under test


def assert_same_mesh(v1, f1, v2, f2):
    """The same triangles up to vertex order, face order and a few ulps.

    Two implementations may compute a vertex with different (equally valid) rounding, e.g.
    ``i*s + t*s`` against ``p0 + t*(p1 - p0)``, so the canonical forms are compared with a
    tolerance, never bit for bit.
    """
    a, b = mesh.canonical_triangles(v1, f1), mesh.canonical_triangles(v2, f2)
    assert a.shape == b.shape
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-7)


def _rotation_group():
    """The 24 rotations of the cube, generated as the closure of two quarter turns."""
    rx = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]])
    rz = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]])
    group = {tuple(np.eye(3, dtype=int).ravel())}
    frontier = [np.eye(3, dtype=int)]
    while frontier:
        m = frontier.pop()
        for g in (rx, rz):
            p = g @ m
            if tuple(p.ravel()) not in group:
                group.add(tuple(p.ravel()))
                frontier.append(p)
    return [np.array(g).reshape(3, 3) for g in group]


CORNER_XYZ = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]


def _perms(matrices):
    centred = {tuple(2 * np.array(c) - 1): i for i, c in enumerate(CORNER_XYZ)}
    return [[centred[tuple(m @ (2 * np.array(c) - 1))] for c in CORNER_XYZ] for m in matrices]


def _permute(index, perm):
    return sum(1 << perm[c] for c in range(8) if index >> c & 1)


def _orbits(complement, reflections):
    mats = _rotation_group()
    if reflections:
        mats = mats + [-m for m in mats]          # -I is a reflection; coset gives all 48
    perms = _perms(mats)
    seen, classes = set(), []
    for i in range(256):
        if i in seen:
            continue
        orbit = {_permute(i, p) for p in perms}
        if complement:
            orbit |= {255 - j for j in orbit}
        seen |= orbit
        classes.append(orbit)
    return classes


def _vertex_distance(a, b):
    """Largest distance from a point of one set to the nearest point of the other."""
    if len(a) == 0 and len(b) == 0:
        return 0.0
    return max(cKDTree(b).query(a)[0].max(), cKDTree(a).query(b)[0].max())


def _gaussians(shape, seed=0, n=4):
    """A smooth field: a sum of broad Gaussian bumps (no noise)."""
    rng = np.random.default_rng(seed)
    grid = np.stack(np.meshgrid(*[np.arange(s, dtype=float) for s in shape], indexing="ij"), -1)
    out = np.zeros(shape)
    for _ in range(n):
        c = rng.uniform(0.2, 0.8, 3) * (np.array(shape) - 1)
        w = rng.uniform(0.15, 0.3) * min(shape)
        out += rng.uniform(0.5, 1.5) * np.exp(-np.sum((grid - c) ** 2, -1) / (2 * w * w))
    return -out      # low values inside, as our "inside" convention


def _iso_off_data(vol, q=0.4):
    """An iso-level near the q-quantile that equals no sample value."""
    iso = float(np.quantile(vol, q))
    while np.any(np.isclose(vol, iso, rtol=0, atol=1e-9)):
        iso += 1e-6
    return iso


# --------------------------------------------------------------------------------------------
# interpolate_edge


def test_interpolate_edge_exam_example():
    # Q3(a): iso-level 10 between data values 7 and 13 lies half way along the edge
    p = mc.interpolate_edge([2.0, 3.0, 4.0], [2.0, 5.0, 4.0], 7.0, 13.0, 10.0)
    np.testing.assert_allclose(p, [2.0, 4.0, 4.0], atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-10, 10), min_size=6, max_size=6),
       st.floats(-50, 50), st.floats(-50, 50), st.floats(0, 1))
def test_interpolate_edge_value_is_iso(pts, v0, v1, s):
    p0, p1 = np.array(pts[:3]), np.array(pts[3:])
    if abs(v1 - v0) < 1e-6:
        return
    iso = float(np.clip(v0 + s * (v1 - v0), min(v0, v1), max(v0, v1)))
    p = mc.interpolate_edge(p0, p1, v0, v1, iso)
    # the linear interpolant evaluated at p equals iso (p on the segment)
    L = np.dot(p1 - p0, p1 - p0)
    t = np.dot(p - p0, p1 - p0) / L if L > 0 else s
    if L > 1e-9:
        assert v0 + t * (v1 - v0) == pytest.approx(iso, abs=1e-6 * (1 + abs(v1 - v0)))
        assert np.allclose(p, p0 + t * (p1 - p0), atol=1e-9)
    np.testing.assert_allclose(mc.interpolate_edge(p0, p1, v0, v1, v0), p0, atol=1e-12)
    np.testing.assert_allclose(mc.interpolate_edge(p0, p1, v0, v1, v1), p1, atol=1e-9)


def test_interpolate_edge_batch_matches_single():
    rng = np.random.default_rng(3)
    p0, p1 = rng.normal(size=(7, 3)), rng.normal(size=(7, 3))
    v0, v1 = rng.uniform(0, 1, 7), rng.uniform(2, 3, 7)
    iso = 1.5
    batch = mc.interpolate_edge(p0, p1, v0, v1, iso)
    assert batch.shape == (7, 3)
    for k in range(7):
        t = (iso - v0[k]) / (v1[k] - v0[k])
        np.testing.assert_allclose(batch[k], (1 - t) * p0[k] + t * p1[k], atol=1e-12)


@pytest.mark.parametrize("args", [
    ([0, 0, 0], [1, 0, 0], 2.0, 2.0, 3.0),           # no crossing on a flat edge
    ([0, 0], [1, 0], 0.0, 1.0, 0.5),                 # 2-D points
    ([0, 0, 0], [1, 0, 0], 0.0, 1.0, 2.0),           # iso off the segment
    (np.zeros((2, 3)), np.ones((3, 3)), 0.0, 1.0, 0.5),   # shapes do not broadcast
])
def test_interpolate_edge_errors(args):
    with pytest.raises(ValueError):
        mc.interpolate_edge(*args)


# --------------------------------------------------------------------------------------------
# cube_index


def test_cube_index_bits():
    for i in range(8):
        vals = np.full(8, 5.0)
        vals[i] = 1.0
        assert mc.cube_index(vals, 3.0) == 2 ** i
    assert mc.cube_index(np.zeros(8), 1.0) == 255
    assert mc.cube_index(np.ones(8), 1.0) == 0          # equal to iso is not below it


@settings(max_examples=80, deadline=None)
@given(st.lists(st.floats(-100, 100).filter(lambda x: abs(x - 0.5) > 1e-9),
                min_size=8, max_size=8))
def test_cube_index_complement(values):
    values = np.array(values)
    i = mc.cube_index(values, 0.5)
    assert mc.cube_index(1.0 - values, 0.5) == 255 - i      # mirror about the iso-level
    assert i == int("".join("1" if v < 0.5 else "0" for v in values[::-1]), 2)


def test_cube_index_batch_and_errors():
    rng = np.random.default_rng(1)
    vals = rng.uniform(size=(4, 5, 8))
    idx = mc.cube_index(vals, 0.5)
    assert idx.shape == (4, 5)
    assert idx[2, 3] == mc.cube_index(vals[2, 3], 0.5)
    with pytest.raises(ValueError):
        mc.cube_index(np.zeros(7), 0.5)
    with pytest.raises(ValueError):
        mc.cube_index(np.zeros(8), [0.5, 0.6])


# --------------------------------------------------------------------------------------------
# symmetry classes and the 15 cases (Q3(b))


@pytest.mark.parametrize("complement, reflections, expected",
                         [(False, False, 23), (True, False, 15), (False, True, 22), (True, True, 14)])
def test_count_symmetry_classes(complement, reflections, expected):
    # orbit enumeration with a rotation group generated independently of the module
    assert len(_orbits(complement, reflections)) == expected
    assert mc.count_symmetry_classes(complement, reflections) == expected


def test_cube_symmetries_are_the_groups():
    for reflections, size in ((False, 24), (True, 48)):
        ours = {tuple(p) for p in mc.cube_symmetries(reflections)}
        mats = _rotation_group()
        if reflections:
            mats = mats + [-m for m in mats]
        assert ours == {tuple(p) for p in _perms(mats)}
        assert len(ours) == size


def test_base_cases_are_lorensens_fifteen():
    classes = _orbits(True, False)
    reps = [c.index for c in mc.BASE_CASES]
    assert [c.number for c in mc.BASE_CASES] == list(range(15))
    hit = [next(k for k, cl in enumerate(classes) if r in cl) for r in reps]
    assert sorted(hit) == list(range(15))                  # one case per class, all classes
    # Q3(b): 14 of the 15 cases need triangles
    assert sum(mc.N_TRIANGLES[r] > 0 for r in reps) == 14
    # triangle counts of Lorensen & Cline's figure of the 15 cases
    assert [int(mc.N_TRIANGLES[r]) for r in reps] == [0, 1, 2, 2, 2, 3, 3, 3, 2, 4, 4, 4, 4, 4, 4]
    # Q3(c): six cases are ambiguous
    assert mc.AMBIGUOUS_CASES == (3, 6, 7, 10, 12, 13)
    # 11 and 14 are mirror images: one class once reflections are allowed
    full = _orbits(True, True)
    c11, c14 = reps[11], reps[14]
    assert any(c11 in cl and c14 in cl for cl in full)
    assert all(mc.case_of(i) == mc.case_of(_permute(i, p)) for i in (5, 77, 200)
               for p in _perms(_rotation_group()))


def test_case_of_is_the_class_of_the_independent_orbits():
    """Every case index gets the Lorensen number of the base case in its class (classes from
    the independently generated rotation group, with complement), and bad indices are refused."""
    for cl in _orbits(True, False):
        numbers = {c.number for c in mc.BASE_CASES if c.index in cl}
        assert len(numbers) == 1
        assert {mc.case_of(i) for i in cl} == numbers
    for bad in (256, -1, 2.5):
        with pytest.raises(ValueError):
            mc.case_of(bad)


def _students_module(module):
    """The students' copy of a generated module (its ``students_copy()`` text), executed."""
    namespace = {}
    exec(compile(module.students_copy(), f"<students' {module.__name__}>", "exec"), namespace)
    return namespace


def test_students_tables_are_the_generators_and_hold_no_alternative():
    """The students' ``_mc_tables`` (literals made at wheel build) gives the generated tables
    bit for bit, the same ambiguous faces, and neither the alternative table nor a generator."""
    theirs = _students_module(_mc_tables)
    for name in _mc_tables.STUDENTS_TABLES:
        ours = getattr(_mc_tables, name)
        assert theirs[name].dtype == ours.dtype, name
        np.testing.assert_array_equal(theirs[name], ours, err_msg=name)
    assert all(theirs["ambiguous_faces"](i) == _mc_tables.ambiguous_faces(i) for i in range(256))
    public = {k for k in theirs if not k.startswith("_")} - {"annotations", "np"}
    assert public == set(_mc_tables.STUDENTS_TABLES) | {"ambiguous_faces"}
    assert not {"ALT_TRI_TABLE", "ALT_N_TRIANGLES", "case_triangles", "_case_loops"} & set(theirs)


def test_students_case_data_are_the_references():
    """The students' ``_mc_case_data``: Lorensen's number of each index as the orbits give it,
    and the joined rows of the six representatives only, those of the alternative table."""
    theirs = _students_module(_mc_case_data)
    labels = theirs["case_labels"]()
    assert len(labels) == 256 and labels == tuple(mc.case_of(i) for i in range(256))
    reps = [c.index for c in mc.BASE_CASES if c.ambiguous]
    assert theirs["SHOWN_INDICES"] == tuple(reps) == _mc_case_data.SHOWN_INDICES
    shown = theirs["shown_alternatives"]()
    assert sorted(shown) == sorted(reps)
    for index, rows in shown.items():
        np.testing.assert_array_equal(np.array(rows), mc.alternative_triangulation(index))
        assert mc.closes_up(index, np.array(rows))


def test_hidden_alternative_cases_are_never_a_shown_representative():
    """``alternative_triangulation``'s cases cover the six ambiguous classes in other
    orientations than the ones the figures draw (those rows are shipped): five hidden, drawn
    among each class's members, and case 13, whose one other member would be a fixed hidden
    answer, visible."""
    from autograder.exercises import REGISTRY

    ex = REGISTRY["alternative_triangulation"]
    for seed in range(40):
        cases = [c for c in ex.draw_cases(np.random.default_rng(seed)) if c.raises is None]
        hidden = [c.args[0] for c in cases if not c.visible]
        visible = [c.args[0] for c in cases if c.visible]
        assert not set(hidden) & set(_mc_case_data.SHOWN_INDICES)
        assert sorted(mc.case_of(i) for i in hidden) == [3, 6, 7, 10, 12]
        assert [i for i in visible if mc.case_of(i) == 13 and i not in _mc_case_data.SHOWN_INDICES]


# Bourke's published edgeTable, first sixteen entries
BOURKE_EDGE_TABLE_0_15 = [0x0, 0x109, 0x203, 0x30a, 0x406, 0x50f, 0x605, 0x70c,
                          0x80c, 0x905, 0xa0f, 0xb06, 0xc0a, 0xd03, 0xe09, 0xf00]
BOURKE_EDGES = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4),
                (0, 4), (1, 5), (2, 6), (3, 7)]


def test_edge_table_matches_bourke():
    assert list(mc.EDGE_TABLE[:16]) == BOURKE_EDGE_TABLE_0_15
    for i in range(256):
        expected = sum(1 << e for e, (a, b) in enumerate(BOURKE_EDGES)
                       if (i >> a & 1) != (i >> b & 1))
        assert mc.EDGE_TABLE[i] == expected
        assert mc.EDGE_TABLE[255 - i] == mc.EDGE_TABLE[i]
    assert {frozenset(e) for e in mc.EDGES.tolist()} == {frozenset(e) for e in BOURKE_EDGES}
    for e, (a, b) in enumerate(mc.EDGES):      # same edge numbers as Bourke
        assert {a, b} == set(BOURKE_EDGES[e])


def _boundary_segments(tris):
    """Undirected edges used by exactly one triangle of a case, as frozensets of cube edges."""
    count = {}
    for t in tris:
        for k in range(3):
            key = frozenset((int(t[k]), int(t[(k + 1) % 3])))
            count[key] = count.get(key, 0) + 1
    return {k for k, n in count.items() if n == 1}


@pytest.mark.parametrize("alternative", [False, True])
def test_tables_follow_a_face_rule(alternative):
    """Every triangle edge on a cube face joins two crossed edges of that face; on an ambiguous
    face the consistent table keeps the inside corners apart, the alternative joins them."""
    edge_corners = [set(e) for e in BOURKE_EDGES]
    table = _mc_tables.ALT_TRI_TABLE if alternative else mc.TRI_TABLE
    ntri = _mc_tables.ALT_N_TRIANGLES if alternative else mc.N_TRIANGLES
    for i in range(256):
        tris = table[i, :ntri[i]]
        crossed = {e for e in range(12) if mc.EDGE_TABLE[i] >> e & 1}
        assert set(tris.ravel().tolist()) == crossed
        segs = _boundary_segments(tris)
        # each crossed edge ends exactly two boundary segments (one per face it lies on)
        for e in crossed:
            assert sum(e in s for s in segs) == 2
        for s in segs:
            a, b = tuple(s)
            shared = edge_corners[a] | edge_corners[b]
            assert len(shared) in (3, 4)                    # the two edges lie on one face
            if len(shared) == 3:                            # adjacent edges: cut off a corner
                corner = (edge_corners[a] & edge_corners[b]).pop()
                face_corners = None
                for quad in ([0, 1, 2, 3], [4, 5, 6, 7], [0, 1, 5, 4], [3, 2, 6, 7],
                             [0, 3, 7, 4], [1, 2, 6, 5]):
                    if shared <= set(quad):
                        face_corners = quad
                states = [i >> c & 1 for c in face_corners]
                ambiguous = states[0] == states[2] != states[1] == states[3]
                if ambiguous:
                    inside = i >> corner & 1
                    assert inside == (0 if alternative else 1)


def test_tables_are_rotation_equivariant():
    """The table is what the 15 cases give under the 24 rotations: rotating case i's contour
    segments gives the segments of the rotated case (the fan diagonals may differ)."""
    perms = _perms(_rotation_group())
    edge_index = {frozenset(e): k for k, e in enumerate(BOURKE_EDGES)}
    for i in range(256):
        segs = _boundary_segments(mc.TRI_TABLE[i, :mc.N_TRIANGLES[i]])
        for p in perms:
            j = _permute(i, p)
            moved = {frozenset(edge_index[frozenset(p[c] for c in BOURKE_EDGES[e])] for e in s)
                     for s in segs}
            assert moved == _boundary_segments(mc.TRI_TABLE[j, :mc.N_TRIANGLES[j]])
            assert mc.N_TRIANGLES[j] == mc.N_TRIANGLES[i]


def _pattern_block(patterns, cells_shape):
    """Stack binary corner patterns of a block of cells along x, each padded by outside samples."""
    nx, ny, nz = (s + 1 for s in cells_shape)
    blocks = []
    for bits in patterns:
        b = np.ones((nx + 2, ny + 2, nz + 2))
        b[1:-1, 1:-1, 1:-1] = np.where(np.array(bits).reshape(nx, ny, nz), 0.0, 1.0)
        blocks.append(b[:-1])
    return np.concatenate(blocks + [np.ones((1, ny + 2, nz + 2))], axis=0)


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_every_pair_of_cells_is_watertight(axis):
    """All 2**12 patterns of two cells sharing a face: the mesh is closed and consistent."""
    shape = [1, 1, 1]
    shape[axis] = 2
    patterns = [[(p >> k) & 1 for k in range(12)] for p in range(4096)]
    vol = _pattern_block(patterns, shape)
    verts, faces = mc.marching_cubes(vol, 0.5)
    assert mesh.is_closed_consistent(faces)
    tm = trimesh.Trimesh(verts, faces, process=False)
    assert tm.is_watertight and tm.is_winding_consistent
    assert tm.volume > 0


def test_random_blocks_of_cells_are_watertight():
    rng = np.random.default_rng(11)
    patterns = rng.integers(0, 2, size=(800, 27))
    vol = _pattern_block(patterns, (2, 2, 2))
    verts, faces = mc.marching_cubes(vol, 0.5)
    assert mesh.is_closed_consistent(faces)
    tm = trimesh.Trimesh(verts, faces, process=False)
    assert tm.is_watertight and tm.is_winding_consistent


def test_hole_from_mixed_triangulations():
    vol, verts, faces = mc.hole_demo()
    holes = mesh.boundary_edges(faces)
    assert len(holes) == 4                                  # a quadrilateral hole
    assert np.allclose(verts[holes.ravel(), 0], 2.0)        # ... in the shared face x = 2
    assert not trimesh.Trimesh(verts, faces, process=False).is_watertight
    vol2, verts2, faces2 = mc.hole_demo(alternative=False)
    assert np.array_equal(vol, vol2)
    assert len(mesh.boundary_edges(faces2)) == 0 and mesh.is_closed_consistent(faces2)
    # the consistent mesh is the one skimage's vertices give, and what the fast version makes
    v3, f3 = mc.marching_cubes(vol, 0.5)
    assert_same_mesh(v3, f3, verts2, faces2)


# --------------------------------------------------------------------------------------------
# marching_cubes against other libraries and analytic shapes


def test_vectorised_equals_loop():
    vol = _gaussians((9, 8, 7), seed=2)
    iso = _iso_off_data(vol)
    for spacing in ((1, 1, 1), (0.5, 2.0, 1.5)):
        v1, f1 = mc.marching_cubes(vol, iso, spacing)
        v2, f2 = mc.marching_cubes_loop(vol, iso, spacing)
        assert len(f1) > 20 and len(v1) == len(v2)
        assert_same_mesh(v1, f1, v2, f2)


def _two_sided_noise(shape, seed, iso=0.25):
    """Random samples at least 0.2 above or below ``iso``: a crossing on an edge then sits at
    ``t`` in [0.1, 0.9], many cells are ambiguous and the surface reaches the volume's faces."""
    rng = np.random.default_rng(seed)
    return iso + rng.choice([-1.0, 1.0], shape) * rng.uniform(0.2, 1.0, shape)


def _in_global_edge_order(verts, faces, spacing):
    """Vertices renumbered by the grid edge they lie on: x-edges, then y, then z, each in C
    order of the edge's first sample (the order :func:`mc.marching_cubes` documents). The edge
    is read off the coordinates: two are whole multiples of the spacing, the third is not."""
    q = verts / np.asarray(spacing, dtype=float)
    whole = np.isclose(q, np.round(q), rtol=0, atol=1e-9)
    assert np.all(whole.sum(axis=1) == 2)           # every vertex strictly inside one edge
    axis = np.argmin(whole, axis=1)
    start = np.floor(q + 1e-9).astype(np.int64)
    order = np.lexsort((start[:, 2], start[:, 1], start[:, 0], axis))
    renumber = np.empty(len(verts), dtype=np.int64)
    renumber[order] = np.arange(len(verts))
    return verts[order], renumber[faces]


@pytest.mark.parametrize("shape, seed, spacing", [
    ((7, 6, 5), 0, (1.0, 1.0, 1.0)),
    ((6, 7, 4), 1, (0.5, 2.0, 1.5)),
    ((2, 9, 3), 2, (1.0, 0.25, 3.0)),
    ((8, 2, 2), 3, (2.0, 1.0, 1.0)),
])
def test_vectorised_equals_loop_exactly(shape, seed, spacing, monkeypatch):
    """Same vertices in the documented order, same faces in the same order and winding, on
    noise (ambiguous cells everywhere, surface through the volume's faces); with slabs of one
    layer of cells and int64 edge numbers too, the paths large volumes take."""
    vol = _two_sided_noise(shape, seed)
    v_loop, f_loop = _in_global_edge_order(*mc.marching_cubes_loop(vol, 0.25, spacing), spacing)
    assert len(f_loop) > 10
    results = [mc.marching_cubes(vol, 0.25, spacing)]
    monkeypatch.setattr(mc, "_SLAB_CELLS", 1)
    results.append(mc.marching_cubes(vol, 0.25, spacing))
    monkeypatch.setattr(mc, "_INT32_EDGES", 0)
    results.append(mc.marching_cubes(vol, 0.25, spacing))
    for verts, faces in results:
        assert verts.dtype == np.float64 and faces.dtype == np.int64
        np.testing.assert_allclose(verts, v_loop, rtol=0, atol=1e-12)
        assert np.array_equal(faces, f_loop)


def test_vectorised_accepts_any_layout_and_dtype():
    """Fortran order, a strided view, integers and float32 give the mesh of a C-ordered float64
    copy of the same samples."""
    vol = _two_sided_noise((9, 8, 7), seed=4)
    views = [np.asfortranarray(vol), vol[::-1, :, ::2], np.round(4 * vol).astype(np.int16),
             vol.astype(np.float32)]
    for view in views:
        expected = mc.marching_cubes(np.array(view, dtype=np.float64, order="C"), 0.25)
        got = mc.marching_cubes(view, 0.25)
        # bit-exact by construction: marching_cubes converts any input to a C-ordered float64
        # copy first, so both calls run the same elementwise arithmetic on the same numbers
        assert np.array_equal(got[0], expected[0]) and np.array_equal(got[1], expected[1])
        assert len(got[1]) > 0


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_sample_anywhere_is_rejected(bad, monkeypatch):
    monkeypatch.setattr(mc, "_SLAB_CELLS", 16)            # several slabs; the bad one is last
    vol = np.zeros((12, 5, 6))
    vol[-1, 4, 5] = bad
    with pytest.raises(ValueError, match="finite"):
        mc.marching_cubes(vol, 0.5)
    with pytest.raises(ValueError, match="finite"):
        mc.marching_cubes_loop(vol, 0.5)


@pytest.mark.parametrize("spacing", [(1.0, 1.0, 1.0), (0.5, 1.0, 2.0)])
@pytest.mark.parametrize("seed", [0, 1])
def test_vertices_match_skimage_on_smooth_fields(spacing, seed):
    vol = _gaussians((18, 16, 14), seed=seed)
    iso = _iso_off_data(vol, 0.3)
    verts, faces = mc.marching_cubes(vol, iso, spacing)
    for method in ("lewiner", "lorensen"):
        sv, _sf, _, _ = skimage.measure.marching_cubes(vol, iso, spacing=spacing, method=method)
        assert len(sv) == len(verts)
        assert _vertex_distance(verts, sv.astype(float)) < 1e-4      # skimage is float32
    tm = trimesh.Trimesh(verts, faces, process=False)
    if tm.is_watertight:
        assert abs(tm.volume) == pytest.approx(abs(mesh.mesh_volume(verts, faces)), rel=1e-12)


def test_vertices_match_pymcubes():
    # PyMCubes (Bourke's tables) takes volume[x, y, z] and returns vertices in index order; its
    # faces are wound the other way, so its signed volume is minus ours.
    vol = mc.ellipsoid_field((30, 26, 22), (14.2, 12.7, 10.4), (11.3, 9.1, 7.2))
    verts, faces = mc.marching_cubes(vol, 1.0)
    mv, mf = mcubes.marching_cubes(vol, 1.0)
    assert len(mv) == len(verts) and len(mf) == len(faces)
    assert _vertex_distance(verts, mv) < 1e-9
    ours = mesh.mesh_volume(verts, faces)
    theirs = trimesh.Trimesh(mv, mf.astype(np.int64), process=False).volume
    assert ours > 0 and theirs < 0
    assert abs(theirs) == pytest.approx(ours, rel=1e-3)


@pytest.mark.parametrize("semi", [(5.0, 5.0, 5.0), (6.0, 4.5, 3.5)])
def test_sphere_and_ellipsoid_converge_to_skimage_stats(semi):
    """Area and volume approach skimage.draw.ellipsoid_stats as the grid is refined."""
    exact_vol, exact_area = skimage.draw.ellipsoid_stats(*semi)
    errors = []
    for scale in (1.0, 2.0):
        a = np.array(semi) * scale
        shape = tuple(int(2 * x + 5) for x in a)
        centre = (np.array(shape) - 1) / (2 * scale) + 0.13
        vol = mc.ellipsoid_field(shape, centre, semi, spacing=(1 / scale,) * 3)
        verts, faces = mc.marching_cubes(vol, 1.0, spacing=(1 / scale,) * 3)
        assert mesh.is_closed_consistent(faces)
        tm = trimesh.Trimesh(verts, faces, process=False)
        assert tm.is_watertight and tm.is_winding_consistent
        v, s = mesh.mesh_volume(verts, faces), mesh.surface_area(verts, faces)
        assert tm.volume == pytest.approx(v, rel=1e-12)
        errors.append((abs(v - exact_vol) / exact_vol, abs(s - exact_area) / exact_area))
        assert exact_vol == pytest.approx(mc.ellipsoid_volume(*semi), rel=1e-12)
    # second-order convergence: relative error below (h / smallest semi-axis)**2 at h = 1, 1/2
    for (err_v, err_s), h in zip(errors, (1.0, 0.5)):
        tol = (h / min(semi)) ** 2
        assert err_v < tol and err_s < tol
    assert errors[1][0] < errors[0][0] / 3 and errors[1][1] < errors[0][1] / 3


def test_torus_volume_and_area():
    R, r = 9.0, 3.5
    errors = []
    for scale in (1.0, 2.0):
        shape = (int(2 * (R + r) * scale) + 5,) * 2 + (int(2 * r * scale) + 5,)
        centre = (np.array(shape) - 1) / (2 * scale) + 0.07
        vol = mc.torus_field(shape, centre, R, spacing=(1 / scale,) * 3)
        verts, faces = mc.marching_cubes(vol, r * r, spacing=(1 / scale,) * 3)
        tm = trimesh.Trimesh(verts, faces, process=False)
        assert tm.is_watertight and tm.is_winding_consistent
        assert tm.euler_number == 0                      # genus one
        v, s = mesh.mesh_volume(verts, faces), mesh.surface_area(verts, faces)
        errors.append((abs(v / mc.torus_volume(R, r) - 1), abs(s / mc.torus_area(R, r) - 1)))
    assert errors[1][0] < errors[0][0] < 0.05
    assert errors[1][1] < errors[0][1] < 0.05


def test_spacing_scales_the_mesh():
    vol = _gaussians((10, 11, 12), seed=5)
    iso = _iso_off_data(vol)
    v1, f1 = mc.marching_cubes(vol, iso)
    s = np.array([0.7, 1.3, 2.1])
    v2, f2 = mc.marching_cubes(vol, iso, spacing=s)
    assert np.array_equal(f1, f2)
    np.testing.assert_allclose(v2, v1 * s, atol=1e-12)
    if mesh.is_closed_consistent(f1):
        assert mesh.mesh_volume(v2, f2) == pytest.approx(np.prod(s) * mesh.mesh_volume(v1, f1))


def test_octahedron_and_empty():
    vol = np.ones((3, 3, 3))
    vol[1, 1, 1] = 0.0
    verts, faces = mc.marching_cubes(vol, 0.5)
    # the six edge mid-points around the centre: a regular octahedron of "radius" 1/2
    assert len(verts) == 6 and len(faces) == 8
    assert mesh.mesh_volume(verts, faces) == pytest.approx(4 / 3 * 0.5 ** 3)
    v, f = mc.marching_cubes(vol, -1.0)
    assert v.shape == (0, 3) and f.shape == (0, 3)


@pytest.mark.parametrize("args", [
    (np.zeros((4, 4)), 0.5),
    (np.zeros((4, 4, 4, 2)), 0.5),
    (np.zeros((1, 4, 4)), 0.5),
    (np.zeros((4, 4, 4)), 0.5, (1.0, 0.0, 1.0)),
    (np.zeros((4, 4, 4)), 0.5, (1.0, -1.0, 1.0)),
    (np.zeros((4, 4, 4)), 0.5, (1.0, 1.0)),
    (np.zeros((4, 4, 4)), np.nan),
])
def test_marching_cubes_errors(args):
    with pytest.raises(ValueError):
        mc.marching_cubes(*args)
    with pytest.raises(ValueError):
        mc.marching_cubes_loop(*args)


def test_base_case_volumes_are_closed_when_padded():
    """Each of the 15 cases alone, surrounded by outside samples, gives a closed surface."""
    for case in mc.BASE_CASES:
        bits = [(case.index >> c) & 1 for c in range(8)]
        vol = np.ones((4, 4, 4))
        for c, (x, y, z) in enumerate(itertools.islice(CORNER_XYZ, 8)):
            vol[1 + x, 1 + y, 1 + z] = 0.0 if bits[c] else 1.0
        _verts, faces = mc.marching_cubes(vol, 0.5)
        assert mesh.is_closed_consistent(faces)
        assert (len(faces) > 0) == (case.number > 0)


# --------------------------------------------------------------------------------------------
# one case's class (Q3(b)) and the other triangulation of an ambiguous case (Q3(c))


@pytest.mark.parametrize("complement, reflections",
                         list(itertools.product((False, True), repeat=2)))
def test_symmetry_orbit_is_the_class_of_an_independent_enumeration(complement, reflections):
    classes = _orbits(complement, reflections)
    for orbit in classes:
        for index in orbit:
            got = mc.symmetry_orbit(index, complement, reflections)
            assert got.dtype.kind == "i" and got.tolist() == sorted(orbit)
    # orbit-stabiliser: every class size divides the order of the group
    order = (48 if reflections else 24) * (2 if complement else 1)
    assert all(order % len(orbit) == 0 for orbit in classes)


def test_symmetry_orbit_exam_numbers_and_errors():
    # one inside corner can be any of the eight; with complement, also one outside corner
    assert mc.symmetry_orbit(1).tolist() == [1 << c for c in range(8)]
    assert mc.symmetry_orbit(1, complement=True).tolist() == sorted(
        [1 << c for c in range(8)] + [255 - (1 << c) for c in range(8)])
    # the 15 classes of Q3(b) cover the 256 cases exactly once
    reps = [c.index for c in mc.BASE_CASES]
    assert sum(len(mc.symmetry_orbit(r, complement=True)) for r in reps) == 256
    for bad in (256, -1, 2.5, True, "3"):
        with pytest.raises(ValueError):
            mc.symmetry_orbit(bad)


def _probe_trimesh(index, triangles):
    verts, faces = mc.probe_triangulation(index, triangles)
    return trimesh.Trimesh(verts, faces, process=False)


AMBIGUOUS = [i for i in range(256) if mc.ambiguous_faces(i)]


def test_ambiguous_indices_are_the_six_classes():
    classes = {mc.case_of(i) for i in AMBIGUOUS}
    assert classes == {3, 6, 7, 10, 12, 13}
    assert len(AMBIGUOUS) == sum(len(mc.symmetry_orbit(c.index, complement=True))
                                 for c in mc.BASE_CASES if c.ambiguous)


@pytest.mark.parametrize("index", AMBIGUOUS)
def test_alternative_triangulation_closes_only_with_joining_neighbours(index):
    alt = mc.alternative_triangulation(index)
    tm = _probe_trimesh(index, alt)
    assert tm.is_watertight and tm.is_winding_consistent and tm.volume > 0
    # an independent route to the same surface: the complement's table row, reversed
    comp = mc.TRI_TABLE[255 - index, :mc.N_TRIANGLES[255 - index]][:, ::-1]
    assert len(comp) == len(alt)
    tm = _probe_trimesh(index, comp)
    assert tm.is_watertight and tm.is_winding_consistent
    # the table's own choice (inside corners apart) and the reversed surface both leave holes
    assert not _probe_trimesh(index, mc.TRI_TABLE[index, :mc.N_TRIANGLES[index]]).is_watertight
    assert not _probe_trimesh(index, alt[:, ::-1]).is_winding_consistent
    # with the table's choice in every cell (marching_cubes) the same volume closes as well
    verts, faces = mc.marching_cubes(_probe_volume(index), 0.5)
    assert trimesh.Trimesh(verts, faces, process=False).is_watertight


def _probe_volume(index):
    vol = np.ones((4, 4, 4))
    for c, (x, y, z) in enumerate(CORNER_XYZ):
        if index >> c & 1:
            vol[1 + x, 1 + y, 1 + z] = 0.0
    return vol


@pytest.mark.parametrize("bad", [1, 3, 15, 65, 256, -1, 2.5])
def test_alternative_triangulation_errors(bad):
    with pytest.raises(ValueError):
        mc.alternative_triangulation(bad)


def test_joined_patch_rule_accepts_every_valid_answer_and_names_the_fault():
    from autograder.exercises.q3_marching_cubes import same_joined_patch

    rng = np.random.default_rng(3)
    for index in AMBIGUOUS:
        expected = mc.alternative_triangulation(index)
        # vertex order within each triangle (cyclic shift) and triangle order do not matter
        shuffled = np.roll(expected, int(rng.integers(3)), axis=1)[rng.permutation(len(expected))]
        assert same_joined_patch(expected, shuffled) is None
        comp = mc.TRI_TABLE[255 - index, :mc.N_TRIANGLES[255 - index]][:, ::-1]
        assert same_joined_patch(expected, comp.astype(float)) is None
        own = mc.TRI_TABLE[index, :mc.N_TRIANGLES[index]]
        assert same_joined_patch(expected, own) is not None
        assert same_joined_patch(expected, expected[:, ::-1]) is not None
        assert same_joined_patch(expected, expected[1:]) is not None
        assert same_joined_patch(expected, expected.tolist()) is not None
        uncrossed = [e for e in range(12) if not (int(mc.EDGE_TABLE[index]) >> e) & 1]
        if uncrossed:                                   # case 13 crosses all twelve edges
            wrong_edge = expected.copy()
            wrong_edge[0, 0] = uncrossed[0]
            assert "does not cross" in same_joined_patch(expected, wrong_edge)
        repeated = expected.copy()
        repeated[0, 1] = repeated[0, 0]
        assert "repeats" in same_joined_patch(expected, repeated)


def test_sphere_volume_error_quarters_when_the_spacing_halves():
    """The notebook's claim on the sphere of Q3(d): halving the spacing quarters the error."""
    r, c, box = 4.2, 5.6, 11.0
    exact = 4 / 3 * np.pi * r ** 3                       # analytic, not our sphere_volume
    errors = []
    for h in (1.0, 0.5, 0.25, 0.125):
        n = int(round(box / h)) + 1
        vol = mc.sphere_field((n,) * 3, (c, c, c), spacing=(h,) * 3)
        verts, faces = mc.marching_cubes(vol, r * r, spacing=(h,) * 3)
        errors.append(exact - mesh.mesh_volume(verts, faces))
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all(np.array(errors) > 0)                  # the inscribed mesh underestimates
    assert np.all((ratios > 3.6) & (ratios < 4.4)), ratios


def test_joined_patch_rule_rejects_a_triangle_flat_in_a_face():
    from autograder.exercises.q3_marching_cubes import same_joined_patch

    expected = mc.alternative_triangulation(5)          # corners 0 and 2: bottom face z = 0
    flat = expected.copy()
    flat[0] = (0, 1, 2)                                  # three crossings of the bottom face
    assert "flat" in same_joined_patch(expected, flat)


def _candidate_triangulations(index, rng):
    """The table's row, the joined row, the joined row reversed, and random triangles of the
    crossed edges (mostly not closing up)."""
    alt = _mc_tables.ALT_TRI_TABLE[index, :_mc_tables.ALT_N_TRIANGLES[index]]
    out = [alt, mc.TRI_TABLE[index, :mc.N_TRIANGLES[index]], alt[:, ::-1], alt[:-1]]
    crossed = [e for e in range(12) if (int(mc.EDGE_TABLE[index]) >> e) & 1]
    if crossed:
        out += [rng.choice(crossed, size=(max(len(alt), 1), 3)) for _ in range(3)]
    return [np.asarray(t, dtype=np.int64).reshape(-1, 3) for t in out]


def test_closes_up_is_the_probe_meshs_closedness():
    """``closes_up`` (in the students' copy: no march, no vertex positions) agrees with the
    probe mesh that the references march, judged by ``is_closed_consistent``, on every case;
    the joined row closes up (trimesh agrees), the table's row does not where a face is ambiguous."""
    rng = np.random.default_rng(2006)
    verdicts = []
    for index in range(256):
        for tris in _candidate_triangulations(index, rng):
            want = mesh.is_closed_consistent(mc.probe_triangulation(index, tris)[1])
            assert mc.closes_up(index, tris) == want, (index, tris.tolist())
            verdicts.append(want)
    assert 0 < sum(verdicts) < len(verdicts)
    for index in AMBIGUOUS[:12]:
        alt = mc.alternative_triangulation(index)
        assert mc.closes_up(index, alt) and _probe_trimesh(index, alt).is_watertight
        assert not mc.closes_up(index, mc.TRI_TABLE[index, :mc.N_TRIANGLES[index]])


def test_closes_up_refuses_bad_arguments():
    for index, tris in ((256, [[0, 1, 2]]), (5, [[0, 1]]), (5, [[0, 1, 4]]), (5, [[0.0, 1, 2]])):
        with pytest.raises(ValueError):
            mc.closes_up(index, tris)
