"""The marching-cubes lookup tables, generated from the cube's numbering (Q3(a), Q3(c)).

Kept apart from the march (:mod:`course_lib.marching_cubes`, which imports every public name of
this module and is where they are imported from), as scikit-image keeps its lookup tables in a
module of their own. The corner and edge numbering is drawn in
:mod:`course_lib.marching_cubes`.

How the tables are made
-----------------------
The 256-entry tables are *generated*, not typed in. For every corner pattern, each of the six
cube faces gets contour segments joining the crossed edges of that face; on an *ambiguous* face
(two inside corners on one diagonal, two outside on the other) the rule is always the same: the
inside corners are kept apart. Because the segments on a face depend only on the four corners
of that face, the two cells sharing a face always agree on it, so every mesh built from the table
is watertight. The segments join up into closed loops on the cube's surface; each loop is
triangulated as a fan. The alternative table :data:`ALT_TRI_TABLE` uses the opposite rule on
ambiguous faces (inside corners joined): it is what Lorensen's original use of complement
symmetry produces, and mixing the two tables is what opens the holes of Q3(c).

The students' copy
------------------
The students' wheel holds the tables a student's ``marching_cubes`` uses (:data:`CORNERS`,
:data:`EDGES`, :data:`FACES`, :data:`TRI_TABLE`, :data:`N_TRIANGLES`, :data:`EDGE_TABLE`) and
:func:`ambiguous_faces`, as literals made when the wheel is built (:func:`students_copy`), and
not the generator: :func:`case_triangles` with ``alternative=True`` and :data:`ALT_TRI_TABLE`
are Q3(c)'s ``alternative_triangulation`` (docs/students-copy.md).

Faces are wound counter-clockwise seen from the outside (values above the iso-level), so their
normals point up the gradient of the data, away from the inside region: a blob of low values
(for example ``|x - c|**2 < r**2``) gets a positive enclosed volume from
:func:`course_lib.mesh.mesh_volume`.
"""

from __future__ import annotations

import inspect

import numpy as np

__all__ = ["ALT_N_TRIANGLES", "ALT_TRI_TABLE", "CORNERS", "EDGES", "EDGE_TABLE", "FACES",
           "N_TRIANGLES", "TRI_TABLE", "ambiguous_faces", "case_triangles"]


#: Corner ``i`` of the unit cube, shape (8, 3).
CORNERS = np.array([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0),
                    (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)], dtype=np.int64)

#: Edge ``e`` joins corners ``EDGES[e]``. The edges are Lorensen's/Bourke's (0: 0-1, 1: 1-2,
#: 2: 2-3, 3: 3-0, 4: 4-5, 5: 5-6, 6: 6-7, 7: 7-4, 8: 0-4, 9: 1-5, 10: 2-6, 11: 3-7), each stored
#: with its corner nearer the origin first, so that the interpolation along an edge runs in the
#: same direction whichever of the (up to four) cells sharing it asks for it.
EDGES = np.array([(0, 1), (1, 2), (3, 2), (0, 3), (4, 5), (5, 6), (7, 6), (4, 7),
                  (0, 4), (1, 5), (2, 6), (3, 7)], dtype=np.int64)

#: The six faces, each as its four corners counter-clockwise seen from outside the cube.
FACES = np.array([(0, 3, 2, 1),   # z = 0
                  (4, 5, 6, 7),   # z = 1
                  (0, 1, 5, 4),   # y = 0
                  (3, 7, 6, 2),   # y = 1
                  (0, 4, 7, 3),   # x = 0
                  (1, 2, 6, 5)],  # x = 1
                 dtype=np.int64)


def _edge_lookup() -> dict:
    return {frozenset(map(int, pair)): e for e, pair in enumerate(EDGES)}


_EDGE_OF = _edge_lookup()


def _check_faces() -> None:
    """Each face is counter-clockwise seen from outside: its normal points away from the centre."""
    for quad in FACES:
        p = CORNERS[quad].astype(float)
        normal = np.cross(p[1] - p[0], p[2] - p[1])
        assert np.dot(normal, p.mean(axis=0) - 0.5) > 0, quad


_check_faces()


# --------------------------------------------------------------------------------------------
# table generation


def _face_segments(inside: np.ndarray, quad, join: bool) -> list[tuple[int, int]]:
    """Directed contour segments ``(edge_from, edge_to)`` on one face.

    Walking the face counter-clockwise (seen from outside), a crossed edge is an *exit* when it
    goes from an inside corner to an outside one, an *entry* otherwise. A segment runs from an
    exit to an entry, so the inside region lies on its left. With two crossings there is one
    segment; with four (an ambiguous face) each exit pairs with the entry just before it
    (``join=False``: inside corners kept apart) or just after it (``join=True``).
    """
    crossings = []
    for k in range(4):
        a, b = int(quad[k]), int(quad[(k + 1) % 4])
        if inside[a] != inside[b]:
            crossings.append((_EDGE_OF[frozenset((a, b))], bool(inside[a])))
    n = len(crossings)
    segments = []
    for k, (edge, is_exit) in enumerate(crossings):
        if is_exit:
            partner = crossings[(k + 1) % n] if (join or n == 2) else crossings[(k - 1) % n]
            segments.append((edge, partner[0]))
    return segments


def ambiguous_faces(index: int) -> list[int]:
    """The faces (rows of :data:`FACES`) of case ``index`` whose diagonals disagree (Q3(c))."""
    inside = _bits(index)
    out = []
    for f, quad in enumerate(FACES):
        s = inside[quad]
        if s[0] == s[2] and s[1] == s[3] and s[0] != s[1]:
            out.append(f)
    return out


def _bits(index: int) -> np.ndarray:
    return np.array([(index >> i) & 1 for i in range(8)], dtype=bool)


def _case_loops(index: int, join_faces=()) -> list[list[int]]:
    """Closed loops of crossed edges for case ``index``; ``join_faces`` use the joining rule."""
    inside = _bits(index)
    nxt = {}
    for f, quad in enumerate(FACES):
        for a, b in _face_segments(inside, quad, join=f in join_faces):
            assert a not in nxt
            nxt[a] = b
    loops = []
    while nxt:
        start = min(nxt)
        loop = [start]
        while nxt[loop[-1]] != start:
            loop.append(nxt.pop(loop[-1]))
        nxt.pop(loop[-1])
        loops.append(loop)
    return loops


def case_triangles(index: int, alternative: bool = False) -> np.ndarray:
    """Triangles of case ``index`` as rows of three edge numbers, shape ``(t, 3)``.

    Each loop of contour segments is reversed (so that the normal points to the outside, the
    side of values above the iso-level) and triangulated as a fan from its first edge. With
    ``alternative=True`` every ambiguous face of the cube uses the joining rule instead: this is
    the other triangulation of the ambiguous cases 3, 6, 7, 10, 12 and 13 of Q3(c).
    """
    join = ambiguous_faces(index) if alternative else ()
    tris = []
    for loop in _case_loops(index, join):
        tris.extend(_fan(loop[::-1]))
    return np.array(tris, dtype=np.int64).reshape(-1, 3)


#: For each edge, the two faces (rows of FACES) it lies on.
_FACES_OF_EDGE = [frozenset(f for f, quad in enumerate(FACES) if a in quad and b in quad)
                  for a, b in EDGES]


def _fan(loop: list[int]) -> list[tuple[int, int, int]]:
    """Fan triangulation of a loop from the first apex that puts no triangle flat on a face.

    A triangle whose three edges lie on one cube face would lie in that face and overlap the
    neighbouring cell's surface; fanning from another vertex of the loop avoids it.
    """
    n = len(loop)
    for shift in range(n):
        rot = loop[shift:] + loop[:shift]
        fan = [(rot[0], rot[k], rot[k + 1]) for k in range(1, n - 1)]
        if all(not (_FACES_OF_EDGE[a] & _FACES_OF_EDGE[b] & _FACES_OF_EDGE[c])
               for a, b, c in fan):
            return fan
    raise AssertionError(f"no fan of loop {loop} avoids flat triangles")  # pragma: no cover


def _build_tables(alternative: bool):
    rows = [case_triangles(i, alternative) for i in range(256)]
    width = max(len(r) for r in rows)
    table = np.full((256, width, 3), -1, dtype=np.int64)
    for i, r in enumerate(rows):
        table[i, :len(r)] = r
    return table, np.array([len(r) for r in rows], dtype=np.int64)


#: ``TRI_TABLE[i, t]`` = edges of triangle ``t`` of case ``i`` (rows of -1 after the last one).
TRI_TABLE, N_TRIANGLES = _build_tables(False)
#: The same with ambiguous faces joined (the alternative triangulations); mixing the two tables
#: leaves holes (Q3(c)).
ALT_TRI_TABLE, ALT_N_TRIANGLES = _build_tables(True)
#: ``EDGE_TABLE[i]``: 12-bit mask of the edges crossed in case ``i`` (as in Bourke's table).
EDGE_TABLE = np.array([sum(1 << e for e in range(12)
                           if _bits(i)[EDGES[e, 0]] != _bits(i)[EDGES[e, 1]])
                       for i in range(256)], dtype=np.int64)



#: what the students' copy holds: the tables a march uses, not the generator nor the
#: alternative table (Q3(c)'s graded answer)
STUDENTS_TABLES = ("CORNERS", "EDGES", "FACES", "TRI_TABLE", "N_TRIANGLES", "EDGE_TABLE")

STUDENTS_COPY = '''"""The marching-cubes lookup tables (Q3(a)), made by the course's generator when this
copy of the library was built: corner, edge and face numbering, the triangles of each of the 256
cases (inside corners kept apart on every ambiguous face) and the crossed edges of each case."""

from __future__ import annotations

import numpy as np

__all__ = ["CORNERS", "EDGES", "EDGE_TABLE", "FACES", "N_TRIANGLES", "TRI_TABLE",
           "ambiguous_faces"]

%s

%s
'''


def students_copy() -> str:
    """The text of this module in the students' wheel: the arrays of :data:`STUDENTS_TABLES`
    as literals (equal to this module's) and :func:`ambiguous_faces`, nothing that generates
    a table."""
    arrays = "\n".join(f"{name} = np.array({globals()[name].tolist()!r}, dtype=np.int64)"
                       for name in STUDENTS_TABLES)
    functions = "\n\n".join(inspect.getsource(f) for f in (ambiguous_faces, _bits))
    return STUDENTS_COPY % (arrays, functions)
