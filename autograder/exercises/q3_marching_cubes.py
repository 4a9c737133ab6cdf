"""Q3: marching cubes and volume estimation (notebook ``q3_marching_cubes``).

Visible cases carry the exam's own numbers: the iso-level 10 between data values 7 and 13 of
Q3(a) (the vertex is half way), the 256 patterns reducing to 15 cases in Q3(b), and a single
inside sample whose isosurface is an octahedron (the simplest closed surface marching cubes
makes, whose volume Q3(d)'s formula gives as 1/6).

A marching-cubes mesh is only defined up to the order of its vertices, the order of its faces
and the starting vertex of each face (and, since the contract does not fix it, the direction in
which all faces are wound), so :func:`same_mesh` compares the set of vertices, the numbers of
faces, closedness, and the enclosed volume and area.

``symmetry_orbit`` (Q3(b)) asks for the class of one case, written out and sorted, on random
cases: no table of class counts answers it. ``alternative_triangulation`` (Q3(c)) has many right
answers (the order of the triangles, the start of each, the choice of fan inside each loop), so
:func:`same_joined_patch` checks the properties the notebook states and then that the triangles
close up with neighbours that join the inside corners on every ambiguous face.
"""

from __future__ import annotations

import functools

import numpy as np

from course_lib import marching_cubes as mc
from course_lib import mesh

from ..model import CellKind
from .base import (Case, Exercise, Mismatch, close, describe, number_item, same_integer, up_to,
                   wrong_shape, wrong_value)

NB = "q3_marching_cubes"


# ------------------------------------------------------------------------------------------------
# comparison rule for marching_cubes


def _sorted_rows(a: np.ndarray, decimals: int = 6) -> np.ndarray:
    r = np.round(a, decimals) + 0.0
    return a[np.lexsort(r.T[::-1])] if len(a) else a


@up_to("vertex order, triangle order, the first vertex of each triangle and the winding of "
       "the whole mesh")
def same_mesh(expected, received, atol: float = 1e-6, rtol: float = 1e-6) -> Mismatch | None:
    """Meshes equal up to vertex order, face order, the start of each face and global winding.

    Checks, in order: ``(verts (V, 3), faces (F, 3) int)``; indices in range; the same number
    of vertices and faces; the same vertex positions as a set; every edge shared by two faces in
    opposite directions exactly when the expected mesh is; the same absolute enclosed volume and
    the same surface area. Arrays of the wrong form (not arrays, not ``(V, 3)`` or ``(F, 3)``,
    not numbers) are wrong values whose text names the form (so the summary words of q3's
    grades stay comparable between terms); a tuple of another length and non-integer faces are
    wrong shapes.
    """
    if not isinstance(received, tuple) or len(received) != 2:
        return wrong_shape(f"wrong type (expected a tuple (verts, faces), got {describe(received)})")
    ev, ef = expected
    rv, rf = received
    if not isinstance(rv, np.ndarray) or not isinstance(rf, np.ndarray):
        return wrong_value("verts and faces must be NumPy arrays")
    if rv.size == 0:
        rv = rv.reshape(0, 3)
    if rv.ndim != 2 or rv.shape[1] != 3:
        return wrong_value(f"verts must have shape (V, 3), got {rv.shape}")
    if rv.dtype.kind not in "iuf":
        return wrong_value(f"verts must be numbers, got dtype {rv.dtype}")
    rv = rv.astype(float)
    if rf.size == 0:
        rf = rf.reshape(0, 3)
    if rf.ndim != 2 or rf.shape[1] != 3:
        return wrong_value(f"faces must have shape (F, 3), got {rf.shape}")
    if rf.dtype.kind not in "iu":
        if rf.dtype.kind == "f" and np.all(rf == np.round(rf)):
            rf = rf.astype(np.int64)
        else:
            return wrong_shape(f"faces must hold integer vertex indices, got dtype {rf.dtype}")
    if rf.size and (rf.min() < 0 or rf.max() >= len(rv)):
        return wrong_value("faces index vertices that do not exist")
    if len(rv) != len(ev):
        return wrong_shape(f"wrong number of vertices (expected {len(ev)}, one per crossed grid "
                           f"edge; got {len(rv)})")
    if len(rf) != len(ef):
        return wrong_shape(f"wrong number of triangles (expected {len(ef)}, got {len(rf)})")
    if not np.all(np.isfinite(rv)):
        return wrong_value("NaN or inf among the vertices")
    if len(ev) and not np.allclose(_sorted_rows(rv), _sorted_rows(ev), atol=atol, rtol=0):
        return wrong_value("the vertex positions differ (check the interpolation along each edge and the "
                           "mapping of index (i, j, k) to (i*sx, j*sy, k*sz))")
    if len(ef) == 0:
        return None
    closed = mesh.is_closed_consistent(ef)
    if mesh.is_closed_consistent(rf) != closed:
        if closed:
            return wrong_value("the mesh is not closed and consistently wound (vertices not shared between "
                               "cells, or triangles ordered inconsistently)")
        return wrong_value("the mesh is closed where it should leave the volume")
    if closed:
        ve, vr = mesh.mesh_volume(ev, ef), mesh.mesh_volume(rv, rf)
        if not np.isclose(abs(vr), abs(ve), rtol=rtol, atol=1e-9):
            return wrong_value(f"wrong enclosed volume (expected {abs(ve):.6g}, got {abs(vr):.6g})")
    ae, ar = mesh.surface_area(ev, ef), mesh.surface_area(rv, rf)
    if not np.isclose(ar, ae, rtol=rtol, atol=1e-9):
        return wrong_value(f"wrong surface area (expected {ae:.6g}, got {ar:.6g}): different triangles")
    return None


def _as_edge_triangles(received) -> np.ndarray | Mismatch:
    """``received`` as an int64 ``(t, 3)`` array, or the reason it is not one."""
    if not isinstance(received, np.ndarray):
        return wrong_shape(f"wrong type (expected a NumPy array of shape (t, 3), got {describe(received)})")
    if received.size == 0:
        received = received.reshape(0, 3)
    if received.ndim != 2 or received.shape[1] != 3:
        return wrong_shape(f"wrong shape (expected (t, 3) edge numbers, got {received.shape})")
    if received.dtype.kind not in "iu":
        if received.dtype.kind != "f" or not np.all(received == np.round(received)):
            return wrong_value(f"the triangles must hold integer edge numbers, got dtype {received.dtype}")
    return received.astype(np.int64)


#: Each cube edge's set of faces (rows of ``mc.FACES``): a triangle whose three edges share a
#: face lies flat in that face.
_FACES_OF_EDGE = [frozenset(f for f, quad in enumerate(mc.FACES) if a in quad and b in quad)
                  for a, b in mc.EDGES]
@functools.cache
def _case_of_answer() -> dict[bytes, int]:
    """The reference answer of each face-ambiguous case, to find the case back from it (built
    on first use, in the grader's process)."""
    return {mc.alternative_triangulation(i).tobytes(): i
            for i in range(256) if mc.ambiguous_faces(i)}


@up_to("the order of the triangles, the edge each triangle starts from (its winding kept) and "
       "which diagonals cut each loop: any triangulation of the joined contour, wound like "
       "TRI_TABLE, passes")
def same_joined_patch(expected, received) -> Mismatch | None:
    """Any triangulation of the joined contour of the expected case, wound like the table.

    The case is the one whose reference answer ``expected`` is. ``received`` must be ``(t, 3)``
    edge numbers of edges that case crosses, as many triangles as the reference (``n - 2`` per
    loop of ``n`` crossings), no triangle with a repeated edge or lying flat in a cube face, and
    it must close up, consistently wound, with neighbours that join the inside corners on every
    ambiguous face (:func:`course_lib.marching_cubes.probe_triangulation`).
    """
    index = _case_of_answer()[np.asarray(expected, dtype=np.int64).tobytes()]
    tris = _as_edge_triangles(received)
    if isinstance(tris, Mismatch):
        return tris
    if len(tris) != len(expected):
        return wrong_value(f"wrong number of triangles (expected {len(expected)}: n - 2 for each loop of "
                           f"n crossing points; got {len(tris)})")
    if tris.size and (tris.min() < 0 or tris.max() > 11):
        return wrong_value("edge numbers must be 0 ... 11")
    crossed = [e for e in range(12) if (int(mc.EDGE_TABLE[index]) >> e) & 1]
    if not np.all(np.isin(tris, crossed)):
        return wrong_value(f"a triangle uses an edge the case does not cross (crossed edges: {crossed})")
    for tri in tris.tolist():
        if len(set(tri)) < 3:
            return wrong_value(f"the triangle {tri} repeats an edge")
        if _FACES_OF_EDGE[tri[0]] & _FACES_OF_EDGE[tri[1]] & _FACES_OF_EDGE[tri[2]]:
            return wrong_value(f"the triangle {tri} lies flat in a face of the cube")
    _, faces = mc.probe_triangulation(index, tris)
    if not mesh.is_closed_consistent(faces):
        return wrong_value("the surface does not close up with neighbours that join the inside corners on "
                           "every ambiguous face (check which crossings you join on each ambiguous face, "
                           "and that the triangles are wound anticlockwise seen from outside)")
    return None


def same_bool(expected, received) -> Mismatch | None:
    """A Python bool (NumPy's ``np.bool_`` accepted) equal to the expected one."""
    if not isinstance(received, bool):
        return wrong_shape(f"wrong type (expected True or False, got {describe(received)})")
    return None if received == expected else wrong_value(f"wrong answer (expected {expected})")


# ------------------------------------------------------------------------------------------------
# random inputs


def _smooth_field(rng, shape, n_bumps=3):
    """A sum of broad Gaussian bumps, negated so that the bumps are 'inside' (low values)."""
    grid = np.stack(np.meshgrid(*[np.arange(s, dtype=float) for s in shape], indexing="ij"), -1)
    out = np.zeros(shape)
    for _ in range(n_bumps):
        c = rng.uniform(0.25, 0.75, 3) * (np.array(shape) - 1)
        w = rng.uniform(0.2, 0.35) * min(shape)
        out -= rng.uniform(0.5, 1.5) * np.exp(-np.sum((grid - c) ** 2, -1) / (2 * w * w))
    return out


def _iso_between(rng, vol):
    """An iso-level inside the data range that equals no sample (no degenerate vertices)."""
    lo, hi = np.quantile(vol, [0.15, 0.5])
    iso = rng.uniform(lo, hi)
    while np.any(np.abs(vol - iso) < 1e-7):
        iso += 1e-5
    return float(iso)


def _closed_meshes(rng):
    """Closed, outward meshes: a tetrahedron, an octahedron and a box, randomly placed."""
    tet_v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    tet_f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    oct_v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    oct_f = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4],
                      [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    box_v = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    box_f = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                      [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    out = []
    for v, f in ((tet_v, tet_f), (oct_v, oct_f), (box_v, box_f)):
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        if np.linalg.det(q) < 0:
            q[:, 0] *= -1                                  # a rotation keeps the orientation
        v2 = (v * rng.uniform(0.5, 3.0, 3)) @ q.T + rng.normal(scale=3.0, size=3)
        out.append((v2, f.copy()))
    return out


# ------------------------------------------------------------------------------------------------
# cases


def _interpolate_cases(rng):
    yield Case(args=(np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]), 7.0, 13.0, 10.0),
               label="exam Q3(a): iso 10 between 7 and 13 is half way", visible=True)
    yield Case(args=(np.array([2.0, 3.0, 4.0]), np.array([2.0, 5.0, 4.0]), 13.0, 7.0, 8.5),
               label="values decreasing along the edge", visible=True)
    p0, p1 = rng.normal(size=(6, 3)), rng.normal(size=(6, 3))
    v0, v1 = rng.uniform(-5, 0, 6), rng.uniform(1, 5, 6)
    yield Case(args=(p0, p1, v0, v1, 0.5), label="batch of 6 edges, one iso-level")
    yield Case(args=(p0, p1, v1, v0, rng.uniform(0.0, 1.0, 6)), label="batch, iso per edge")
    yield Case(args=(p0[0], p1[0], float(v0[0]), float(v1[0]), float(v0[0])),
               label="iso equal to v0 gives p0")
    yield Case(args=(p0[1], p1[1], 2.0, 2.0, 2.0), label="flat edge at the iso-level gives p0")
    yield Case(args=(p0[0], p1[0], 2.0, 2.0, 3.0), label="flat edge, no crossing",
               raises=ValueError)
    yield Case(args=(p0[0], p1[0], 0.0, 1.0, 2.0), label="iso off the edge", raises=ValueError)
    yield Case(args=(np.zeros(2), np.ones(2), 0.0, 1.0, 0.5), label="2-D points",
               raises=ValueError)


def _cube_index_cases(rng):
    yield Case(args=(np.array([0.0, 9, 9, 9, 9, 9, 9, 9]), 5.0), label="corner 0 inside",
               visible=True)
    yield Case(args=(np.array([7.0, 13, 13, 7, 13, 7, 7, 13]), 10.0),
               label="corners 0, 3, 5, 6 below 10", visible=True)
    values, iso = rng.uniform(0, 1, 8), float(rng.uniform(0.2, 0.8))
    at_iso = rng.random(8) < 0.5
    at_iso[rng.integers(8)] = True
    values[at_iso] = iso
    yield Case(args=(values, iso), label="some corners equal to iso: those are not below it")
    for _ in range(3):
        yield Case(args=(rng.uniform(0, 1, 8), float(rng.uniform(0.2, 0.8))), label="random cell")
    yield Case(args=(rng.uniform(0, 1, (5, 8)), 0.5), label="batch of 5 cells")
    yield Case(args=(rng.uniform(0, 1, (2, 3, 8)), 0.3), label="batch of 2 x 3 cells")
    yield Case(args=(np.zeros(7), 0.5), label="7 values", raises=ValueError)


#: The groups of ``count_symmetry_classes`` other than the exam's (complement, reflections).
_OTHER_GROUPS = ((False, False), (False, True), (True, True))


def _symmetry_cases(rng):
    yield Case(args=(True, False), label="rotations and complement (exam Q3(b))", visible=True)
    # four inputs in all: each hidden case draws its group, so no call's answer is fixed
    for _ in range(3):
        yield Case(args=_OTHER_GROUPS[rng.integers(len(_OTHER_GROUPS))],
                   label="rotations with or without reflections and complement")


#: The cases with a rotation class of at most 6 members, the empty and the full cube left out.
_SMALL_CLASS_MEMBERS = [i for i in range(1, 255) if len(mc.symmetry_orbit(i)) <= 6]


def _orbit_cases(rng):
    yield Case(args=(1,), label="corner 0 inside, rotations: the eight one-corner cases",
               visible=True)
    yield Case(args=(5, True, False), label="corners 0 and 2 inside, rotations and complement",
               visible=True)
    for flags in ((False, False), (True, False), (False, True), (True, True)):
        for _ in range(2):
            yield Case(args=(int(rng.integers(1, 255)), *flags),
                       label=f"random case, complement={flags[0]}, reflections={flags[1]}")
    yield Case(args=(int(rng.choice([0, 255])), *(bool(b) for b in rng.random(2) < 0.5)),
               label="no corner or every corner")
    yield Case(args=(int(rng.choice(_SMALL_CLASS_MEMBERS)), *(bool(b) for b in rng.random(2) < 0.5)),
               label="a case of a class of at most 6 members (e.g. Lorensen's case 13)")
    yield Case(args=(256,), label="index 256", raises=ValueError)
    yield Case(args=(-1, True), label="index -1", raises=ValueError)
    yield Case(args=(2.5,), label="index 2.5", raises=ValueError)


def _ambiguous_indices(rng):
    """A random member of each of the six face-ambiguous classes (rotations and complement),
    never the representative whose alternative the notebook's figure and explorer draw
    (``course_lib._mc_case_data.SHOWN_INDICES``: shipped, so it would answer the case). A class
    with one other member (case 13: 165 and 90) would give a fixed answer: it is left out."""
    for orbit in _unshown_ambiguous_orbits():
        if len(orbit) > 1:      # case 13's one other member is a visible case
            yield int(rng.choice(orbit))


@functools.cache
def _unshown_ambiguous_orbits() -> tuple[tuple[int, ...], ...]:
    """The members of each face-ambiguous class but the one the notebook shows (computed once:
    each orbit takes the cube's 48 symmetries)."""
    from course_lib._mc_case_data import SHOWN_INDICES

    return tuple(tuple(i for i in mc.symmetry_orbit(case.index, complement=True).tolist()
                       if i not in SHOWN_INDICES)
                 for case in mc.BASE_CASES if case.ambiguous)


def _alternative_cases(rng):
    yield Case(args=(5,), label="corners 0 and 2 inside (Lorensen's case 3)", visible=True)
    yield Case(args=(250,), label="its complement: corners 1, 3, 4, 5, 6, 7 inside",
               visible=True)
    yield Case(args=(90,), label="corners 1, 3, 4, 6 inside (Lorensen's case 13, the orientation "
                                 "the figure does not show)", visible=True)
    for index in _ambiguous_indices(rng):
        yield Case(args=(index,), label=f"a case of class {mc.case_of(index)}, random orientation")
    yield Case(args=(int(rng.choice([1, 3, 15, 65])),),
               label="no ambiguous face", raises=ValueError)
    yield Case(args=(300,), label="index 300", raises=ValueError)


def _marching_cases(rng):
    vol = np.ones((3, 3, 3))
    vol[1, 1, 1] = 0.0
    yield Case(args=(vol, 0.5), label="one inside sample: an octahedron", visible=True)
    sphere = mc.sphere_field((7, 7, 7), (3.1, 2.9, 3.05))
    yield Case(args=(sphere, 5.3), label="small sphere, radius sqrt(5.3)", visible=True)
    yield Case(args=(sphere, 5.3, (0.5, 1.0, 2.0)), label="the same sphere, spacing (0.5, 1, 2)",
               visible=True)
    for k in range(3):
        shape = tuple(int(n) for n in rng.integers(5, 9, 3))
        field = _smooth_field(rng, shape)
        yield Case(args=(field, _iso_between(rng, field)), label=f"smooth random field {k + 1}")
    field = _smooth_field(rng, (6, 7, 5))
    yield Case(args=(field, _iso_between(rng, field), tuple(rng.uniform(0.3, 2.0, 3))),
               label="smooth field, anisotropic spacing")
    # R + r <= 5.1 and the centre within 0.2 of (5.6, 5.4, 2.6): the torus stays in the grid
    torus = mc.torus_field((12, 12, 6), (5.6, 5.4, 2.6) + rng.uniform(-0.2, 0.2, 3),
                           float(rng.uniform(3.3, 3.6)))
    iso = float(rng.uniform(1.4, 1.5)) ** 2
    while np.any(np.abs(torus - iso) < 1e-7):
        iso += 1e-5
    yield Case(args=(torus, iso), label="a torus (genus one)")
    field = _smooth_field(rng, (6, 5, 6))
    empty = rng.random() < 1 / 3
    yield Case(args=(field, float(field.min()) - 1.0 if empty else _iso_between(rng, field)),
               label="smooth field, iso-level drawn (a third of the time below the data: an "
                     "empty mesh)")
    yield Case(args=(np.zeros((4, 4)), 0.5), label="2-D volume", raises=ValueError)
    yield Case(args=(field, 0.5, (1.0, 0.0, 1.0)), label="zero spacing", raises=ValueError)


def _prism_cases(rng):
    yield Case(args=(np.array([0.0, 0, 2]), np.array([1.0, 0, 2]), np.array([0.0, 1, 2]),
                     np.array([0.0, 0, 1])),
               label="unit right triangle at height 2: area 1/2 x height 2", visible=True)
    yield Case(args=(np.array([0.0, 0, 2]), np.array([0.0, 1, 2]), np.array([1.0, 0, 2]),
                     np.array([0.0, 0, 5])),
               label="the same, wound the other way, n not unit", visible=True)
    a, b, c = rng.normal(size=(3, 8, 3))
    yield Case(args=(a[0], b[0], c[0], rng.normal(size=3)), label="random triangle, random n")
    yield Case(args=(a, b, c, rng.normal(size=3) * 4), label="batch of 8, one n (not unit)")
    yield Case(args=(a, b, c, rng.normal(size=(8, 3))), label="batch of 8, n per triangle")
    yield Case(args=(a[0], b[0], c[0], np.zeros(3)), label="zero n", raises=ValueError)
    yield Case(args=(a[0, :2], b[0], c[0], np.array([0.0, 0, 1])), label="2-D vertex",
               raises=ValueError)


def _volume_cases(rng):
    meshes = _closed_meshes(rng)
    tet_v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    tet_f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    yield Case(args=(tet_v, tet_f), label="unit tetrahedron: volume 1/6", visible=True)
    yield Case(args=(tet_v, tet_f[:, ::-1]), label="the same, wound inwards: -1/6", visible=True)
    for (v, f), name in zip(meshes, ("tetrahedron", "octahedron", "box")):
        yield Case(args=(v, f), label=f"random {name}, default n")
        yield Case(args=(v, f, rng.normal(size=3)), label=f"random {name}, random n")
    v, f = meshes[1]
    yield Case(args=(v, f[1:], np.array([1.0, 2.0, 0.5])), label="open mesh (one face missing)")
    yield Case(args=(tet_v, np.array([[0, 1, 4]])), label="face index out of range",
               raises=ValueError)
    yield Case(args=(tet_v[:, :2], tet_f), label="2-D vertices", raises=ValueError)


def _closed_cases(rng):
    tet_f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    yield Case(args=(tet_f,), label="tetrahedron", visible=True)
    flipped = tet_f.copy()
    flipped[0] = flipped[0, ::-1]
    yield Case(args=(flipped,), label="one face flipped", visible=True)
    yield Case(args=(tet_f[1:],), label="one face missing", visible=True)
    # each hidden case is its defect or a closed mesh like it, drawn: True or False at random
    perm = rng.permutation(8)
    box_f = perm[_closed_meshes(rng)[2][1]]
    flipped = box_f.copy()
    k = rng.integers(len(box_f))
    flipped[k] = flipped[k, ::-1]
    yield Case(args=(box_f if rng.random() < 0.5 else flipped,),
               label="box, vertices renumbered, perhaps with one face flipped")
    yield Case(args=(np.vstack([box_f, box_f[rng.integers(len(box_f)), None]])
                     if rng.random() < 0.5 else box_f[rng.permutation(len(box_f))],),
               label="box, faces shuffled, perhaps with a face repeated")
    yield Case(args=(np.vstack([box_f, box_f[:, ::-1] if rng.random() < 0.5 else box_f + 8]),),
               label="box and its inside-out copy (each edge used four times) or a second box")
    two = np.vstack([tet_f, tet_f + 4])[rng.permutation(8)]
    yield Case(args=(two if rng.random() < 0.5 else two[1:],),
               label="two tetrahedra, faces shuffled, perhaps with one face missing")
    yield Case(args=(np.array([[0, 1]]),), label="faces of 2 vertices", raises=ValueError)


# ------------------------------------------------------------------------------------------------
# the registry


def _choice(name, answer, description, options=("a", "b", "c", "d")):
    return Exercise(name=name, notebook=NB, kind=CellKind.CHOICE, answer=answer, options=options,
                    description=description)


EXERCISES = [
    Exercise(name="interpolate_edge", notebook=NB, reference=mc.interpolate_edge,
             cases=_interpolate_cases, compare=close(rtol=1e-9, atol=1e-9),
             description="Q3(a) vertex position by linear interpolation along an edge"),
    Exercise(name="cube_index", notebook=NB, reference=mc.cube_index,
             cases=_cube_index_cases, compare=close(rtol=0, atol=0),
             description="Q3(b) the 8-bit case number"),
    Exercise(name="count_symmetry_classes", notebook=NB, reference=mc.count_symmetry_classes,
             cases=_symmetry_cases, compare=close(rtol=0, atol=0),
             description="Q3(b) 256 patterns into classes"),
    Exercise(name="symmetry_orbit", notebook=NB, reference=mc.symmetry_orbit,
             cases=_orbit_cases, compare=close(rtol=0, atol=0),
             description="Q3(b) the class of one case under the cube's symmetries"),
    Exercise(name="alternative_triangulation", notebook=NB,
             reference=mc.alternative_triangulation,
             cases=_alternative_cases, compare=same_joined_patch,
             description="Q3(c) the other triangulation of an ambiguous case"),
    Exercise(name="marching_cubes", notebook=NB, reference=mc.marching_cubes,
             cases=_marching_cases, compare=same_mesh,
             description="Q3(a)-(c) the whole algorithm"),
    Exercise(name="triangle_projected_volume", notebook=NB,
             reference=mesh.triangle_projected_volume,
             cases=_prism_cases, compare=close(rtol=1e-9, atol=1e-12),
             description="Q3(d) equation (4)"),
    Exercise(name="mesh_volume", notebook=NB, reference=mesh.mesh_volume,
             cases=_volume_cases, compare=close(rtol=1e-9, atol=1e-12),
             description="Q3(d) sum of equation (4) over the faces"),
    Exercise(name="is_closed_consistent", notebook=NB, reference=mesh.is_closed_consistent,
             cases=_closed_cases, compare=same_bool,
             description="Q3(d) the closed and consistently ordered condition"),
    _choice("q3_item1", "b", "Q3(a) where on the edge the vertex goes"),
    _choice("q3_item2", "c", "Q3(b) how many cases, how many with triangles"),
    _choice("q3_item3", "d", "Q3(c) which cases are ambiguous"),
    _choice("q3_item4", "a", "Q3(c) what the ambiguity is and what goes wrong"),
    _choice("q3_item5", "c", "Q3(d) conditions for the volume to be meaningful"),
]


# Q3(a) on the student's own numbers: the vertex on their crossed edge, and their cell's case.
EXERCISES += [
    number_item("q3a_your_vertex", NB,
                lambda v: mc.interpolate_edge(np.array(v.p0), np.array(v.p1), v.v0, v.v1, v.iso),
                "Q3(a) on your numbers: where the vertex lies on your crossed edge"),
    number_item("q3a_your_case", NB,
                lambda v: int(mc.cube_index(np.array(v.corner_values), v.iso)),
                "Q3(a) on your numbers: the case number (0-255) of your cell",
                compare=same_integer),
]
