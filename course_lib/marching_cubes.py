"""Marching cubes: cases, lookup tables, symmetry classes and isosurface extraction (Q3).

Q3 of the 2006 paper asks how marching cubes turns a voxel array into a triangulated isosurface
(part (a)), why the 256 corner patterns of a cube reduce to 15 cases (part (b)), which cases are
ambiguous and what goes wrong when their triangulations are mixed (part (c)). Part (d), the
volume enclosed by the resulting mesh, lives in :mod:`course_lib.mesh`.

Numbering
---------
Corners and edges follow Lorensen & Cline (1987) as popularised by Paul Bourke::

        7 ________ 6            corner  (x, y, z)       edge  corners   edge  corners
         /|      /|               0     (0, 0, 0)         0    0-1        6    6-7
        / |     / |               1     (1, 0, 0)         1    1-2        7    7-4
     4 /__|____/5 |               2     (1, 1, 0)         2    2-3        8    0-4
       |  |____|__|               3     (0, 1, 0)         3    3-0        9    1-5
       | 3/    |  /2              4     (0, 0, 1)         4    4-5       10    2-6
       | /     | /                5     (1, 0, 1)         5    5-6       11    3-7
       |/______|/    z  y         6     (1, 1, 1)
       0        1    | /          7     (0, 1, 1)
                     |/___ x

A corner is *inside* when its value is below the iso-level, and bit ``i`` of the case number is
set when corner ``i`` is inside (:func:`cube_index`).

How the tables are made
-----------------------
The 256-entry tables (:data:`TRI_TABLE`, ``_mc_tables.ALT_TRI_TABLE``, :data:`EDGE_TABLE`) are
generated, not typed in, by :mod:`course_lib._mc_tables` (which says how), and imported from
here; every mesh built from :data:`TRI_TABLE` is watertight, and mixing it with
the alternative table opens the holes of Q3(c). Their faces are wound so that normals point up
the gradient of the data, away from the inside: a blob of low values gets a positive enclosed
volume from :func:`course_lib.mesh.mesh_volume` (Q3(d)).

The students' copy
------------------
Students' wheel holds the tables a march uses (not :data:`~course_lib._mc_tables.ALT_TRI_TABLE`),
:func:`case_of` (a table made at wheel build, :mod:`course_lib._mc_case_data`) and
:func:`closes_up` (the visible test of Q3(c)); not the graded functions, nor the cube's symmetry
group (:func:`cube_symmetries`, which gives Q3(b)'s orbits), nor anything that marches a volume
(:func:`cube_index`, :func:`interpolate_edge`, :func:`marching_cubes`,
:func:`marching_cubes_loop`, :func:`cell_triangles`, :func:`hole_demo`,
:func:`probe_triangulation`); its figures read the references' results on their fixed inputs
from :mod:`course_lib.mc_results` (docs/students-copy.md).
"""

from __future__ import annotations

import collections
import functools
import itertools
from dataclasses import dataclass

import numpy as np

from . import _mc_case_data, _mc_tables
from ._mc_tables import CORNERS, EDGE_TABLE, EDGES, FACES, N_TRIANGLES, TRI_TABLE, ambiguous_faces
from ._validate import as_float_array, as_int, as_positive, as_scalar, as_vectors

__all__ = [
    "AMBIGUOUS_CASES",
    "BASE_CASES",
    "CORNERS",
    "EDGES",
    "EDGE_TABLE",
    "FACES",
    "N_TRIANGLES",
    "TRI_TABLE",
    "BaseCase",
    "alternative_triangulation",
    "ambiguous_faces",
    "case_of",
    "cell_triangles",
    "closes_up",
    "count_symmetry_classes",
    "cube_index",
    "cube_symmetries",
    "ellipsoid_field",
    "ellipsoid_volume",
    "hole_demo",
    "interpolate_edge",
    "marching_cubes",
    "marching_cubes_loop",
    "probe_triangulation",
    "sphere_area",
    "sphere_field",
    "sphere_volume",
    "symmetry_orbit",
    "torus_area",
    "torus_field",
    "torus_volume",
]

# --------------------------------------------------------------------------------------------
# symmetry


def cube_symmetries(reflections: bool = False) -> np.ndarray:
    """The cube's symmetries as corner permutations, shape ``(24, 8)`` or ``(48, 8)``.

    Row ``g`` maps corner ``i`` to corner ``perm[g, i]``. They are the 3 x 3 signed permutation
    matrices (determinant +1 for the 24 rotations; all 48 with reflections) acting on the
    corners centred on the origin.
    """
    centred = 2 * CORNERS - 1
    lookup = {tuple(c): i for i, c in enumerate(centred)}
    perms = []
    for axes in itertools.permutations(range(3)):
        for signs in itertools.product((1, -1), repeat=3):
            m = np.zeros((3, 3), dtype=np.int64)
            m[range(3), axes] = signs
            if not reflections and round(np.linalg.det(m)) != 1:
                continue
            perms.append([lookup[tuple(m @ c)] for c in centred])
    return np.array(perms, dtype=np.int64)


def _apply(perm: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """Case numbers after moving corner ``i`` to ``perm[i]``."""
    bits = (indices[:, None] >> np.arange(8)) & 1
    return (bits << perm[None, :]).sum(axis=1)


@functools.cache
def _orbit_labels(complement: bool, reflections: bool) -> np.ndarray:
    """For each of the 256 cases, the smallest case number in its symmetry class."""
    all_cases = np.arange(256)
    images = [_apply(p, all_cases) for p in cube_symmetries(reflections)]
    if complement:
        images += [255 - im for im in images]
    labels = np.min(images, axis=0)
    labels.setflags(write=False)
    return labels


def count_symmetry_classes(complement: bool = False, reflections: bool = False) -> int:
    """Number of classes the 256 corner patterns fall into under the cube's symmetries, Q3(b).

    Parameters
    ----------
    complement : bool
        Also identify a pattern with its complement (inside and outside swapped).
    reflections : bool
        Use the 48 symmetries of the cube (rotations and reflections) instead of the 24
        rotations.

    Returns
    -------
    int
        23 (rotations), 15 (rotations + complement: Lorensen's 15 cases), 22 (rotations +
        reflections) or 14 (all of them).

    Notes
    -----
    Computed by Burnside's lemma: the number of orbits is the average, over the group, of the
    number of patterns each element leaves fixed; a rotation fixes ``2**c`` patterns where ``c``
    is the number of its corner cycles, and ``complement o g`` fixes a pattern only when every
    cycle of ``g`` has even length, and then ``2**c`` of them. (The tests check the result
    against an explicit orbit enumeration.) Under rotations and complement the cases 11 and 14
    are distinct mirror images; allowing reflections merges them, which gives 14.

    Examples
    --------
    >>> count_symmetry_classes(complement=True)
    15
    """
    group = cube_symmetries(bool(reflections))
    fixed = 0
    for perm in group:
        cycles = _cycle_lengths(perm)
        fixed += 2 ** len(cycles)
        if complement:
            fixed += 2 ** len(cycles) if all(c % 2 == 0 for c in cycles) else 0
    size = len(group) * (2 if complement else 1)
    return int(fixed // size)


def _cycle_lengths(perm) -> list[int]:
    seen, lengths = set(), []
    for start in range(len(perm)):
        if start in seen:
            continue
        n, i = 0, start
        while i not in seen:
            seen.add(i)
            i = int(perm[i])
            n += 1
        lengths.append(n)
    return lengths


def _case_index(index, name: str = "index") -> int:
    """``index`` as a case number 0 ... 255; ``ValueError`` otherwise."""
    value = as_int(index, name)
    if not 0 <= value <= 255:
        raise ValueError(f"{name} must be a case number from 0 to 255, got {value}")
    return value


def symmetry_orbit(index, complement: bool = False, reflections: bool = False) -> np.ndarray:
    """Every case number the cube's symmetries map case ``index`` to, sorted, Q3(b).

    Parameters
    ----------
    index : int
        A case number, 0 ... 255 (bit ``i`` set when corner ``i`` is inside).
    complement : bool
        Also include the complements (inside and outside swapped) of the images.
    reflections : bool
        Use the 48 symmetries of the cube (rotations and reflections) instead of the 24
        rotations.

    Returns
    -------
    ndarray of int64, shape (m,)
        The class (orbit) of ``index``, ascending: ``orbit[0]`` is the class's smallest case
        number and ``len(orbit)`` its size. The sizes of all classes add up to 256.

    Raises
    ------
    ValueError
        If ``index`` is not an integer from 0 to 255.

    Notes
    -----
    Q3(b) reduces the 256 patterns to 15 classes; an orbit is one of those classes written
    out. By the orbit-stabiliser theorem its size divides the order of the group (24 or 48,
    doubled with complement).

    Examples
    --------
    >>> symmetry_orbit(1).tolist()           # one corner inside: any of the eight corners
    [1, 2, 4, 8, 16, 32, 64, 128]
    >>> len(symmetry_orbit(1, complement=True))
    16
    """
    index = _case_index(index)
    images = np.concatenate([_apply(perm, np.array([index]))
                             for perm in cube_symmetries(bool(reflections))])
    if complement:
        images = np.concatenate([images, 255 - images])
    return np.unique(images).astype(np.int64)


@dataclass(frozen=True)
class BaseCase:
    """One of Lorensen's 15 cases: its number, a representative case index and its inside corners."""

    number: int
    index: int
    inside: tuple
    description: str
    ambiguous: bool


def _case(number, inside, description):
    index = sum(1 << c for c in inside)
    return BaseCase(number, index, tuple(inside), description, bool(ambiguous_faces(index)))


#: Lorensen's 15 cases, each with a representative case number (``index``) whose inside corners
#: are listed. Cases 11 and 14 are the two mirror-image "helices" (three cube edges in a
#: non-planar chain); which one carries which number is a convention.
BASE_CASES = (
    _case(0, (), "no corner inside: no triangles"),
    _case(1, (0,), "one corner cut off by a triangle"),
    _case(2, (0, 1), "two corners on an edge: a quadrilateral"),
    _case(3, (0, 2), "two corners on a face diagonal (ambiguous face)"),
    _case(4, (0, 6), "two corners on a body diagonal: two triangles"),
    _case(5, (0, 1, 2), "three corners of a face: a pentagon"),
    _case(6, (0, 1, 6), "an edge and the far corner (ambiguous face)"),
    _case(7, (1, 3, 4), "three corners pairwise on face diagonals (three ambiguous faces)"),
    _case(8, (0, 1, 2, 3), "a whole face: one plane, two triangles"),
    _case(9, (0, 1, 3, 4), "a corner and its three neighbours: a hexagon"),
    _case(10, (0, 1, 6, 7), "two opposite parallel edges (two ambiguous faces)"),
    _case(11, (0, 1, 3, 7), "a chain of three edges (one mirror image)"),
    _case(12, (0, 1, 2, 7), "three corners of a face and one far corner (two ambiguous faces)"),
    _case(13, (0, 2, 5, 7), "four corners, no two adjacent (six ambiguous faces)"),
    _case(14, (0, 1, 2, 6), "a chain of three edges (the other mirror image)"),
)

#: Lorensen's numbers of the cases with an ambiguous face.
AMBIGUOUS_CASES = tuple(c.number for c in BASE_CASES if c.ambiguous)


def case_of(index: int) -> int:
    """Lorensen's case number (0 ... 14) of case index ``index`` (rotations + complement).

    Read from a 256-entry table that the symmetry classes make (:mod:`course_lib._mc_case_data`;
    in the students' copy, literals made when the wheel was built)."""
    return _mc_case_data.case_labels()[_case_index(index)]


# --------------------------------------------------------------------------------------------
# the graded functions


def interpolate_edge(p0, p1, v0, v1, iso):
    """The point on segment ``p0``-``p1`` where the linearly interpolated value equals ``iso``.

    Q3(a): the lookup table says only *which* edge a vertex lies on; *where* on the edge comes
    from the data values at the two ends.

    Parameters
    ----------
    p0, p1 : array_like, shape (..., 3)
        End points of the edge.
    v0, v1 : array_like, shape (...)
        Data values at ``p0`` and ``p1``.
    iso : float or array_like, shape (...)
        The iso-level, between ``v0`` and ``v1`` (inclusive).

    Returns
    -------
    ndarray, shape (..., 3)
        ``p0 + t (p1 - p0)`` with ``t = (iso - v0) / (v1 - v0)``; ``p0`` where ``v0 == v1 == iso``.

    Raises
    ------
    ValueError
        If the points are not ``(..., 3)``, if the shapes do not broadcast, if ``v0 == v1 != iso``
        (no crossing), or if ``iso`` is not between ``v0`` and ``v1`` (the crossing would be off
        the segment).

    Examples
    --------
    The exam's example: iso-level 10 between values 7 and 13 lies half way.

    >>> interpolate_edge([0, 0, 0], [1, 0, 0], 7.0, 13.0, 10.0)
    array([0.5, 0. , 0. ])
    """
    p0 = as_vectors(p0, 3, "p0")
    p1 = as_vectors(p1, 3, "p1")
    v0 = as_float_array(v0, "v0")
    v1 = as_float_array(v1, "v1")
    iso = as_float_array(iso, "iso")
    try:
        shape = np.broadcast_shapes(p0.shape[:-1], p1.shape[:-1], v0.shape, v1.shape, iso.shape)
    except ValueError as exc:
        raise ValueError(f"p0, p1, v0, v1 and iso do not broadcast together: {exc}") from None
    dv = v1 - v0
    flat = dv == 0
    if np.any(flat & (iso != v0)):
        raise ValueError("v0 == v1 but iso differs from them: the edge does not cross the iso-level")
    lo, hi = np.minimum(v0, v1), np.maximum(v0, v1)
    if np.any((iso < lo) | (iso > hi)):
        raise ValueError("iso must lie between v0 and v1: otherwise the crossing is off the edge")
    t = np.where(flat, 0.0, (iso - v0) / np.where(flat, 1.0, dv))
    out = p0 + t[..., None] * (p1 - p0)
    return np.broadcast_to(out, shape + (3,)).copy()


def cube_index(values, iso):
    """The 8-bit case number of a cell: bit ``i`` is set when ``values[i] < iso`` (Q3(b)).

    Parameters
    ----------
    values : array_like, shape (..., 8)
        Data values at the eight corners, in the corner order of this module.
    iso : float
        The iso-level.

    Returns
    -------
    int or ndarray of int, shape (...)
        A Python ``int`` for one cell, an integer array for a batch.

    Raises
    ------
    ValueError
        If the last axis does not have length 8 or ``iso`` is not a number.

    Examples
    --------
    >>> cube_index([0, 9, 9, 9, 9, 9, 9, 9], 5.0)   # only corner 0 below the level
    1
    >>> cube_index([0, 0, 9, 9, 9, 9, 9, 9], 5.0)   # corners 0 and 1
    3
    """
    values = as_vectors(values, 8, "values")
    iso = as_scalar(iso, "iso")
    index = ((values < iso).astype(np.int64) << np.arange(8)).sum(axis=-1)
    return int(index) if index.ndim == 0 else index


def _check_volume(volume, iso, spacing, finite=True):
    """Checked ``(volume, iso, spacing)``; ``finite=False`` leaves the NaN/inf test of the
    samples to the caller (:func:`_active_cells` does it slab by slab, while they are in cache)."""
    if finite:
        volume = as_float_array(volume, "volume")
    else:
        try:
            volume = np.asarray(volume, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"volume must be numeric, got {type(volume).__name__}") from exc
    if volume.ndim != 3:
        raise ValueError(f"volume must be a 3-D array, got {volume.ndim} dimension(s)")
    if min(volume.shape) < 2:
        raise ValueError(f"volume needs at least 2 samples along each axis, got {volume.shape}")
    iso = as_scalar(iso, "iso")
    spacing = as_positive(spacing, "spacing")
    if spacing.shape != (3,):
        raise ValueError(f"spacing must have 3 entries (sx, sy, sz), got shape {spacing.shape}")
    return volume, iso, spacing


def _edge_axis_offset():
    """For each cube edge: its axis and the offset (di, dj, dk) of its first corner."""
    axis = np.array([int(np.flatnonzero(CORNERS[b] - CORNERS[a])[0]) for a, b in EDGES])
    return axis, CORNERS[EDGES[:, 0]]


_EDGE_AXIS, _EDGE_START = _edge_axis_offset()


def marching_cubes(volume, iso, spacing=(1.0, 1.0, 1.0)):
    """Triangulated isosurface ``volume == iso`` by marching cubes, Q3(a)-(c).

    Vectorised: the cells are classified with whole-array operations (no Python loop over
    cells), only the cells the surface crosses are kept, the table rows of all of them are
    gathered in one go, and each crossed grid edge gets one global number, so that neighbouring
    cells share their vertices and the mesh is watertight wherever the surface stays inside the
    volume. Its time and peak memory are on a par with scikit-image's compiled
    ``skimage.measure.marching_cubes`` (``benchmarks/bench_marching_cubes.py`` measures both).

    Parameters
    ----------
    volume : array_like, shape (nx, ny, nz)
        Samples on a regular grid; each axis at least 2 long.
    iso : float
        The iso-level. A sample is *inside* when it is below ``iso``.
    spacing : sequence of 3 positive floats
        Sample spacing ``(sx, sy, sz)``: index ``(i, j, k)`` sits at ``(i*sx, j*sy, k*sz)``.

    Returns
    -------
    verts : ndarray, shape (V, 3), float64
        One vertex per crossed grid edge, ordered by the edges' global numbers (edges along x
        first, then y, then z, each in C order of their first sample).
    faces : ndarray, shape (F, 3), int64
        Triangles as vertex indices, counter-clockwise seen from outside (values above ``iso``):
        normals point up the gradient. Ambiguous faces always keep inside corners apart.

    Raises
    ------
    ValueError
        If ``volume`` is not 3-D (or has an axis shorter than 2) or holds NaN or inf, ``iso``
        is not a number or ``spacing`` is not three positive numbers.

    Notes
    -----
    The vertex on a crossed edge is the linear interpolation of Q3(a) (:func:`interpolate_edge`):
    at ``t = (iso - v0) / (v1 - v0)`` from the sample nearer the origin. See
    :func:`marching_cubes_loop` for the same algorithm written one cell at a time.

    Examples
    --------
    >>> vol = np.ones((3, 3, 3)); vol[1, 1, 1] = 0.0
    >>> verts, faces = marching_cubes(vol, 0.5)
    >>> verts.shape, faces.shape          # an octahedron around the centre sample
    ((6, 3), (8, 3))
    """
    volume, iso, spacing = _check_volume(volume, iso, spacing, finite=False)
    return _march(volume, iso, spacing)


# --- the vectorised version: tables re-indexed for the fast case-number pass -----------------

#: The fast case-number pass of :func:`marching_cubes` sets bit ``x + 2y + 4z`` for the corner at
#: ``(x, y, z)``, which is corner order 0, 1, 3, 2, 4, 5, 7, 6 of this module: the two orders
#: differ by swapping bits 2 <-> 3 and 6 <-> 7. ``_XYZ_TO_CASE[i]`` is the case number (this
#: module's order) of the index ``i`` made in that order.
_XYZ_CORNER = [int(np.flatnonzero((CORNERS == (b & 1, b >> 1 & 1, b >> 2 & 1)).all(axis=1))[0])
               for b in range(8)]
_XYZ_TO_CASE = np.array([sum(1 << _XYZ_CORNER[b] for b in range(8) if i >> b & 1)
                         for i in range(256)], dtype=np.int64)

#: The four cube edges along each axis: x (0, 2, 4, 6), y (1, 3, 5, 7), z (8, 9, 10, 11).
_AXIS_EDGES = tuple(tuple(int(e) for e in np.flatnonzero(_EDGE_AXIS == ax)) for ax in range(3))


@dataclass(frozen=True)
class _FastTables:
    """A triangle table re-indexed for :func:`_march` by case numbers in the corner order
    ``x + 2y + 4z`` of :data:`_XYZ_TO_CASE` (built once, at import)."""

    ntri: np.ndarray        # (256,) triangles per case
    first: np.ndarray       # (256,) row of the case's first triangle in ``edges``
    edges: np.ndarray       # (sum ntri, 3) cube edges of every triangle, cases one after another
    crossed: np.ndarray     # (12, 256) whether cube edge e is crossed in case i


def _fast_tables(table, ntri) -> _FastTables:
    case = _XYZ_TO_CASE
    counts = ntri[case]
    first = np.concatenate(([0], np.cumsum(counts)[:-1]))
    edges = np.concatenate([table[c, :ntri[c]] for c in case]).astype(np.intp).reshape(-1, 3)
    crossed = ((EDGE_TABLE[case][None, :] >> np.arange(12)[:, None]) & 1).astype(bool)
    return _FastTables(counts, first, edges, crossed)


_FAST = _fast_tables(TRI_TABLE, N_TRIANGLES)

#: Cells per slab in :func:`_active_cells`: small enough for the slab's few ``uint8`` arrays to
#: stay in the processor's cache, large enough for NumPy's per-call overhead not to matter.
_SLAB_CELLS = 1 << 18
#: Grids with fewer edges than this number them in ``int32`` (half the memory of ``int64``).
_INT32_EDGES = 2 ** 31
#: Bit shifts by 1, 2 and 4 as multiplications: NumPy vectorises ``uint8`` products, not shifts.
_TWO, _FOUR, _SIXTEEN = np.uint8(2), np.uint8(4), np.uint8(16)


def _active_cells(volume, iso):
    """Flat numbers (C order) and case numbers of the cells the surface crosses, in order.

    The case number of every cell comes from three passes over ``uint8`` arrays: neighbouring
    samples are combined along x (bits 0-1), the pairs along y (bits 0-3), then along z (bits
    0-7), bit ``x + 2y + 4z`` for the corner at ``(x, y, z)`` (the order of :data:`_FAST`).
    The volume is swept in slabs of whole ``yz`` layers of cells: a Python loop over a few
    dozen slabs, not over cells, which keeps every temporary small and in cache (the buffers
    are allocated once and reused). The samples are checked for NaN and inf on the way
    (``ValueError``, as :func:`marching_cubes` promises).
    """
    nx, ny, nz = volume.shape
    layer = (ny - 1) * (nz - 1)
    step = min(max(1, _SLAB_CELLS // layer), nx - 1)
    size = (step + 1) * ny * nz
    size += -size % 8                                      # whole 8-byte words (see below)
    # three buffers, allocated once, each reused as soon as its contents have been read
    buf_a, buf_b, buf_c = (np.empty(size, dtype=np.uint8) for _ in range(3))
    cells, cases = [], []
    for x0 in range(0, nx - 1, step):
        s = min(step, nx - 1 - x0)                         # layers of cells in this slab
        block = volume[x0:x0 + s + 1]
        finite = np.isfinite(block, out=buf_b[:block.size].view(bool).reshape(block.shape))
        if not finite.all():
            raise ValueError("volume must be finite (no NaN or inf)")
        ins = np.less(block, iso, out=buf_a[:block.size].view(bool).reshape(block.shape))
        ins = ins.view(np.uint8)
        pairs = np.multiply(ins[1:], _TWO, out=buf_b[:s * ny * nz].reshape(s, ny, nz))
        pairs |= ins[:-1]                                  # (s, ny, nz): bits x = 0, 1
        quads = np.multiply(pairs[:, 1:], _FOUR,
                            out=buf_c[:s * (ny - 1) * nz].reshape(s, ny - 1, nz))
        quads |= pairs[:, :-1]                             # (s, ny-1, nz): bits 0-3
        n = s * layer
        index = np.multiply(quads[:, :, 1:], _SIXTEEN, out=buf_a[:n].reshape(s, ny - 1, nz - 1))
        index |= quads[:, :, :-1]                          # (s, ny-1, nz-1): bits 0-7
        flat = buf_a[:n]
        flat -= 1                                          # 0 -> 255: active <=> below 254
        active = buf_c.view(bool)
        np.less(flat, 254, out=active[:n])
        active[n:n + (-n % 8)] = False                     # pad to whole words
        # the surface crosses few cells: find the nonzero 8-byte words first, then the cells
        words = np.flatnonzero(active.view(np.uint64)[:(n + 7) // 8])
        hits = np.flatnonzero(active.reshape(-1, 8)[words])
        found = words[hits >> 3] * 8 + (hits & 7)
        cases.append(flat[found])
        found += x0 * layer
        cells.append(found)
    cells = np.concatenate(cells) if len(cells) > 1 else cells[0]
    cases = np.concatenate(cases) if len(cases) > 1 else cases[0]
    cases += 1
    return cells, cases.astype(np.intp)


def _march(volume, iso, spacing, tables=_FAST):
    """The vectorised marching cubes of :func:`marching_cubes` (inputs already checked).

    1. The active cells, those the surface crosses, and their case numbers
       (:func:`_active_cells`); everything after works on them only.
    2. Each edge of an active cell has a global number (x-edges, then y, then z, each in C order
       of its first sample) = the cell's base number on that axis + a fixed offset per edge.
       Per axis, the crossed edges of the active cells are sorted (four already sorted runs),
       the duplicates shared by neighbouring cells merged, and the rank of each one is the
       vertex number: vertices come out in the order of their global numbers.
    3. The triangles of every cell are looked up, and their edges turned into vertex numbers.
    """
    nx, ny, nz = volume.shape
    cells, cases = _active_cells(volume, iso)
    m = len(cells)

    shapes = ((nx - 1, ny, nz), (nx, ny - 1, nz), (nx, ny, nz - 1))
    sizes = [a * b * c for a, b, c in shapes]
    small = sum(sizes) < _INT32_EDGES
    itype = np.int32 if small else np.int64
    # the cell's (i, j, k) and its base number on each axis's grid of edges
    i, rest = np.divmod(cells.astype(itype) if small else cells, (ny - 1) * (nz - 1))
    j, k = np.divmod(rest, nz - 1)
    del rest, cells
    ij = i * ny + j
    bases = (ij * nz + k,                                  # x-edges: (nx-1, ny, nz)
             (i * (ny - 1) + j) * nz + k + sizes[0],       # y-edges: (nx, ny-1, nz)
             ij * (nz - 1) + k + (sizes[0] + sizes[1]))    # z-edges: (nx, ny, nz-1)
    del i, j, k, ij

    vid = np.empty((m, 12), dtype=itype)                   # vertex number of each cell edge
    verts_parts, nverts = [], 0
    for ax in range(3):
        _, s1, s2 = shapes[ax]
        runs, sels = [], []
        for e in _AXIS_EDGES[ax]:
            di, dj, dk = _EDGE_START[e]
            sel = np.flatnonzero(tables.crossed[e][cases])
            runs.append(bases[ax][sel] + itype((di * s1 + dj) * s2 + dk))
            sels.append(sel)
        keys = np.concatenate(runs)
        order = np.argsort(keys, kind="stable")            # merges four sorted runs
        keys = keys[order]
        new = np.empty(len(keys), dtype=bool)
        new[:1] = True
        np.not_equal(keys[1:], keys[:-1], out=new[1:])
        rank = np.cumsum(new, dtype=itype)
        rank += itype(nverts - 1)
        numbers = np.empty_like(rank)
        numbers[order] = rank
        del order, rank
        start = 0
        for e, sel in zip(_AXIS_EDGES[ax], sels):
            vid[sel, e] = numbers[start:start + len(sel)]
            start += len(sel)
        edges = keys[new]
        edges -= itype(sum(sizes[:ax]))
        del keys, new, numbers, runs, sels
        verts_parts.append(_axis_vertices(volume, iso, spacing, edges, ax, shapes[ax]))
        nverts += len(edges)
    del bases

    counts = tables.ntri[cases]
    ends = np.cumsum(counts)
    ntris = int(ends[-1]) if m else 0
    # row of every triangle in tables.edges: its case's first row + its number within the cell
    rows = np.repeat(tables.first[cases] - (ends - counts), counts)
    rows += np.arange(ntris)
    cell_edges = tables.edges[rows]                        # (T, 3) cube edges
    del rows
    cell_edges += np.repeat(np.arange(0, 12 * m, 12), counts)[:, None]
    faces = np.take(vid.reshape(-1), cell_edges).astype(np.int64)
    return np.concatenate(verts_parts), faces


def _axis_vertices(volume, iso, spacing, edges, ax, shape):
    """The interpolated crossing (Q3(a)) on each of the grid edges ``edges`` along axis ``ax``.

    ``edges`` are numbers in C order on the grid of edges along ``ax`` (``shape``); the edge
    runs from its first sample ``(i, j, k)`` to the next sample along ``ax``.
    """
    _, s1, s2 = shape
    i, rest = np.divmod(edges, s1 * s2)
    j, k = np.divmod(rest, s2)
    first = (i, j, k)
    v0 = volume[first]
    v1 = volume[tuple(n + 1 if c == ax else n for c, n in enumerate(first))]
    t = (iso - v0) / (v1 - v0)
    verts = np.empty((len(edges), 3))
    for c in range(3):
        np.multiply(first[c], spacing[c], out=verts[:, c])
    verts[:, ax] += t * spacing[ax]                        # i*s + t*s along the edge
    return verts


def marching_cubes_loop(volume, iso, spacing=(1.0, 1.0, 1.0)):
    """Marching cubes one cell at a time: the readable version of :func:`marching_cubes`.

    Same parameters, results and errors as :func:`marching_cubes` (the tests check that both
    give the same mesh). It is slow (a Python loop over every cell) and is here to be read:

    1. for each cell, read its 8 corner values and form the case number (:func:`cube_index`);
    2. look up the triangles of that case in :data:`TRI_TABLE` (edges, not positions);
    3. for each edge of a triangle, reuse the vertex of that grid edge if a neighbouring cell
       already made it, otherwise interpolate a new one along the edge (:func:`interpolate_edge`).
    """
    volume, iso, spacing = _check_volume(volume, iso, spacing)
    return _march_loop(volume, iso, spacing)


def _table_triangles(cell, case) -> np.ndarray:
    """The triangles (edge numbers) :data:`TRI_TABLE` gives case ``case``, whatever the cell."""
    return TRI_TABLE[case, :N_TRIANGLES[case]]


def _march_loop(volume, iso, spacing, triangles_of_cell=_table_triangles):
    """The cell-by-cell march; ``triangles_of_cell((i, j, k), case)`` gives each cell's
    triangles as rows of edge numbers (the table's by default)."""
    nx, ny, nz = volume.shape
    vertex_of_edge = {}   # grid edge (start sample, axis) -> vertex number
    verts, faces = [], []
    for i in range(nx - 1):
        for j in range(ny - 1):
            for k in range(nz - 1):
                values = [volume[i + dx, j + dy, k + dz] for dx, dy, dz in CORNERS]
                case = cube_index(values, iso)
                for tri in triangles_of_cell((i, j, k), case):
                    face = []
                    for e in tri:
                        a, b = EDGES[e]
                        start = (i + CORNERS[a][0], j + CORNERS[a][1], k + CORNERS[a][2])
                        key = (start, int(_EDGE_AXIS[e]))
                        if key not in vertex_of_edge:
                            end = (i + CORNERS[b][0], j + CORNERS[b][1], k + CORNERS[b][2])
                            p = interpolate_edge(np.multiply(start, spacing),
                                                 np.multiply(end, spacing),
                                                 volume[start], volume[end], iso)
                            vertex_of_edge[key] = len(verts)
                            verts.append(p)
                        face.append(vertex_of_edge[key])
                    faces.append(face)
    return (np.array(verts, dtype=np.float64).reshape(-1, 3),
            np.array(faces, dtype=np.int64).reshape(-1, 3))


def cell_triangles(values, iso, alternative: bool = False) -> np.ndarray:
    """The triangles of one unit cell as coordinates, shape ``(t, 3, 3)``.

    ``values`` are the eight corner values (corner order of this module); the case comes from
    :func:`cube_index`, the triangles from :data:`TRI_TABLE` (or the alternative table), and
    each vertex is interpolated along its edge (:func:`interpolate_edge`). The tests check the
    case figures' own triangles (:func:`course_lib.plots.marching_cubes.drawn_triangles`) against
    it; like the march, it is not in the students' copy.
    """
    values = as_vectors(values, 8, "values")
    if values.shape != (8,):
        raise ValueError(f"values must have shape (8,), got shape {values.shape}")
    case = cube_index(values, iso)
    table, ntri = ((_mc_tables.ALT_TRI_TABLE, _mc_tables.ALT_N_TRIANGLES) if alternative
                   else (TRI_TABLE, N_TRIANGLES))
    edges = table[case, :ntri[case]]                                    # (t, 3)
    a, b = EDGES[edges, 0], EDGES[edges, 1]
    v0, v1 = values[a], values[b]
    t = (float(iso) - v0) / (v1 - v0)
    return CORNERS[a] + t[..., None] * (CORNERS[b] - CORNERS[a])


# --------------------------------------------------------------------------------------------
# the hole of Q3(c)


def hole_demo(alternative: bool = True):
    """Two cells sharing an ambiguous face, triangulated inconsistently: the hole of Q3(c).

    The volume is 5 x 4 x 4 samples of value 1 (outside) with two samples of value 0 (inside)
    at ``(2, 1, 1)`` and ``(2, 2, 2)``: on the face ``x = 2`` shared by cells ``(1, 1, 1)`` and
    ``(2, 1, 1)`` they sit on one diagonal, the outside samples on the other. The consistent
    table cuts each inside sample off by its own closed surface. Here cell ``(1, 1, 1)`` uses
    the *alternative* triangulation (inside corners joined across the face) while its neighbour
    keeps them apart: the two cells disagree on the shared face and a hole opens there.

    Parameters
    ----------
    alternative : bool
        ``False`` gives the consistent mesh of the same volume (closed, no hole).

    Returns
    -------
    volume : ndarray, shape (5, 4, 4)
    verts : ndarray, shape (V, 3)
    faces : ndarray, shape (F, 3)
        Iso-level 0.5, unit spacing; see :func:`course_lib.mesh.boundary_edges` for the hole.
    """
    volume = np.ones((5, 4, 4))
    volume[2, 1, 1] = 0.0
    volume[2, 2, 2] = 0.0
    joined = {(1, 1, 1)} if alternative else set()

    def triangles_of_cell(cell, case):
        table, ntri = ((_mc_tables.ALT_TRI_TABLE, _mc_tables.ALT_N_TRIANGLES) if cell in joined
                       else (TRI_TABLE, N_TRIANGLES))
        return table[case, :ntri[case]]

    verts, faces = _march_loop(volume, 0.5, np.ones(3), triangles_of_cell)
    return volume, verts, faces


def alternative_triangulation(index) -> np.ndarray:
    """The other consistent triangulation of a face-ambiguous case: every ambiguous face joined.

    Parameters
    ----------
    index : int
        A case number 0 ... 255 with at least one ambiguous face (:func:`ambiguous_faces`):
        one of Lorensen's cases 3, 6, 7, 10, 12 or 13, in any orientation.

    Returns
    -------
    ndarray of int64, shape (t, 3)
        Triangles as rows of three cube-edge numbers, wound counter-clockwise seen from the
        outside, in which every ambiguous face *joins* its two inside corners (the table
        :data:`TRI_TABLE` keeps them apart). Each closed loop of ``n`` crossed edges is cut into
        ``n - 2`` triangles, none lying flat in a face of the cube. The row of
        ``_mc_tables.ALT_TRI_TABLE``.

    Raises
    ------
    ValueError
        If ``index`` is not a case number or has no ambiguous face (then there is no other
        triangulation to choose).

    Notes
    -----
    Q3(c): six of the 15 cases can be triangulated in two ways. Joining the inside corners of
    case ``i`` is keeping apart the inside corners of its complement ``255 - i``, so this is
    also ``TRI_TABLE[255 - i]`` with every triangle reversed (up to the choice of fan): the
    reason why Lorensen's use of complement symmetry mixed the two choices and left holes.

    Examples
    --------
    >>> alternative_triangulation(5).shape     # corners 0 and 2: a band of 4 triangles
    (4, 3)
    """
    index = _case_index(index)
    if not ambiguous_faces(index):
        raise ValueError(f"case {index} has no ambiguous face: it has only one triangulation")
    table, count = _mc_tables.ALT_TRI_TABLE, _mc_tables.ALT_N_TRIANGLES
    return table[index, :count[index]].copy()


def probe_triangulation(index, triangles):
    """Mesh the cell of case ``index`` with ``triangles`` among neighbours that join, Q3(c).

    A 4 x 4 x 4 volume of outside samples (value 1) whose central cell, ``(1, 1, 1)`` to
    ``(2, 2, 2)``, has the inside corners (value 0) of case ``index``; iso-level 0.5. The central
    cell is triangulated with ``triangles`` (rows of edge numbers) and every other cell with
    ``_mc_tables.ALT_TRI_TABLE``: each ambiguous face of the central cell is shared with a neighbour
    that joins its inside corners, and no other cell has an ambiguous face. So the mesh is closed
    and consistently wound exactly when ``triangles`` joins the inside corners on every
    ambiguous face and is wound like its neighbours.

    Parameters
    ----------
    index : int
        The central cell's case number, 0 ... 255.
    triangles : array_like of int, shape (t, 3)
        Cube-edge numbers 0 ... 11.

    Returns
    -------
    verts : ndarray, shape (V, 3)
    faces : ndarray, shape (F, 3)

    Raises
    ------
    ValueError
        If ``index`` is not a case number or ``triangles`` is not ``(t, 3)`` edge numbers of
        edges the case crosses.
    """
    index = _case_index(index)
    triangles = _probe_triangles(index, triangles)
    volume = np.ones((4, 4, 4))
    for c in range(8):
        if (index >> c) & 1:
            volume[tuple(1 + CORNERS[c])] = 0.0

    def triangles_of_cell(cell, case):
        if cell == (1, 1, 1):
            return triangles
        return _mc_tables.ALT_TRI_TABLE[case, :_mc_tables.ALT_N_TRIANGLES[case]]

    return _march_loop(volume, 0.5, np.ones(3), triangles_of_cell)


def _probe_triangles(index: int, triangles) -> np.ndarray:
    """``triangles`` checked as ``(t, 3)`` numbers of edges case ``index`` crosses."""
    triangles = np.asarray(triangles)
    if triangles.size == 0:
        triangles = triangles.reshape(0, 3)
    if triangles.ndim != 2 or triangles.shape[1] != 3 or triangles.dtype.kind not in "iu":
        raise ValueError(f"triangles must be integer edge numbers of shape (t, 3), got "
                         f"{triangles.dtype} of shape {triangles.shape}")
    if triangles.size and (triangles.min() < 0 or triangles.max() > 11
                           or not np.all((EDGE_TABLE[index] >> triangles) & 1)):
        raise ValueError(f"triangles must use only the edges case {index} crosses")
    return triangles


def closes_up(index, triangles) -> bool:
    """Does case ``index``, triangulated with ``triangles``, close up among joining neighbours?

    Q3(c): the cell of :func:`probe_triangulation` (its corners those of case ``index``, in a
    block of outside samples whose other cells all join the inside corners on their ambiguous
    faces) is triangulated with ``triangles``. True when the surface is then closed and
    consistently wound: every edge between two crossing points is used by exactly two
    triangles, in opposite directions, and no triangle repeats a crossing point. Only which
    grid edges the triangles join matters here, not where on them the vertices sit.

    Parameters
    ----------
    index : int
        The central cell's case number, 0 ... 255.
    triangles : array_like of int, shape (t, 3)
        Cube-edge numbers 0 ... 11 of edges the case crosses.

    Raises
    ------
    ValueError
        As :func:`probe_triangulation`.

    Notes
    -----
    A neighbour with an ambiguous face joins its inside corners as the table keeps apart those
    of its complement: its triangles are the complement's row of :data:`TRI_TABLE`, each
    reversed (any triangulation of the same contour loops gives the same verdict).

    Examples
    --------
    >>> closes_up(5, TRI_TABLE[250, :N_TRIANGLES[250], ::-1])    # the joined band
    True
    >>> closes_up(5, TRI_TABLE[5, :N_TRIANGLES[5]])              # kept apart: a hole each side
    False
    """
    index = _case_index(index)
    triangles = _probe_triangles(index, triangles)
    inside = {tuple(1 + CORNERS[c]) for c in range(8) if (index >> c) & 1}
    directed = collections.Counter()
    for cell in itertools.product(range(3), repeat=3):
        corners = [tuple(np.add(cell, p)) for p in CORNERS]
        case = sum(1 << c for c, p in enumerate(corners) if p in inside)
        if cell == (1, 1, 1):
            rows = triangles
        elif ambiguous_faces(case):
            rows = TRI_TABLE[255 - case, :N_TRIANGLES[255 - case], ::-1]
        else:
            rows = TRI_TABLE[case, :N_TRIANGLES[case]]
        for tri in rows.tolist():
            # a crossing point is its grid edge: the edge's first sample and its axis
            keys = [(corners[EDGES[e, 0]], int(_EDGE_AXIS[e])) for e in tri]
            if len(set(keys)) < 3:
                return False
            directed.update(zip(keys, keys[1:] + keys[:1]))
    return all(n == 1 and directed.get((v, u)) == 1 for (u, v), n in directed.items())


# --------------------------------------------------------------------------------------------
# analytic test volumes


def _grid(shape, spacing):
    axes = [np.arange(n) * s for n, s in zip(shape, spacing)]
    return np.meshgrid(*axes, indexing="ij")


def sphere_field(shape, centre, spacing=(1.0, 1.0, 1.0)):
    """``|x - centre|**2`` sampled at ``(i*sx, j*sy, k*sz)``: iso ``r**2`` is a sphere of radius r."""
    x, y, z = _grid(shape, spacing)
    cx, cy, cz = centre
    return (x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2


def ellipsoid_field(shape, centre, semi_axes, spacing=(1.0, 1.0, 1.0)):
    """``sum(((x - c) / a)**2)``: iso 1 is the ellipsoid with semi-axes ``a``."""
    x, y, z = _grid(shape, spacing)
    (cx, cy, cz), (a, b, c) = centre, semi_axes
    return ((x - cx) / a) ** 2 + ((y - cy) / b) ** 2 + ((z - cz) / c) ** 2


def torus_field(shape, centre, R, spacing=(1.0, 1.0, 1.0)):
    """``(sqrt((x-cx)**2 + (y-cy)**2) - R)**2 + (z-cz)**2``: iso ``r**2`` is a torus (axis z)."""
    x, y, z = _grid(shape, spacing)
    cx, cy, cz = centre
    return (np.hypot(x - cx, y - cy) - R) ** 2 + (z - cz) ** 2


def sphere_volume(r: float) -> float:
    """``4/3 pi r**3``."""
    return 4.0 / 3.0 * np.pi * r ** 3


def sphere_area(r: float) -> float:
    """``4 pi r**2``."""
    return 4.0 * np.pi * r ** 2


def ellipsoid_volume(a: float, b: float, c: float) -> float:
    """``4/3 pi a b c``."""
    return 4.0 / 3.0 * np.pi * a * b * c


def torus_volume(R: float, r: float) -> float:
    """``2 pi**2 R r**2`` (Pappus)."""
    return 2.0 * np.pi ** 2 * R * r ** 2


def torus_area(R: float, r: float) -> float:
    """``4 pi**2 R r`` (Pappus)."""
    return 4.0 * np.pi ** 2 * R * r
