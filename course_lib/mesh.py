"""Triangle meshes: enclosed volume by projected prisms, area, closedness (Q3(d)).

Q3(d) asks for the volume inside a closed triangulated surface. Project every triangle along a
fixed direction ``n`` onto the plane through the origin perpendicular to ``n``: triangle and
shadow bound a prism whose signed volume is (projected area) x (height of the centroid),
equation (4) of the solutions,

    V = 1/6 [((b - a) x (c - a)) . n] [(a + b + c) . n].

Summed over a closed, consistently wound surface, the prisms under the near side cancel those
under the far side and what is left is the enclosed volume; the choice of ``n`` does not matter.

Instructors only: the students' wheel does not carry this module (its figures read the volumes
the references computed, :mod:`course_lib.mc_results`).
"""

from __future__ import annotations

import numpy as np

from ._validate import as_points, as_vectors
from .shading import _normalised as unit

__all__ = [
    "boundary_edges",
    "canonical_triangles",
    "face_normals",
    "is_closed_consistent",
    "mesh_volume",
    "surface_area",
    "triangle_projected_volume",
]


def triangle_projected_volume(a, b, c, n):
    """Signed volume of the prism between triangle ``abc`` and its projection along ``n``, Q3(d).

    Parameters
    ----------
    a, b, c : array_like, shape (..., 3)
        The triangle's vertices, in order: the sign follows the winding.
    n : array_like, shape (..., 3)
        The direction of projection; it is normalised here (any length but zero).

    Returns
    -------
    float or ndarray, shape (...)
        ``1/6 [((b - a) x (c - a)) . n] [(a + b + c) . n]``, equation (4) of the solutions:
        the projected area, equation (2), times the centroid's distance from the plane through
        the origin perpendicular to ``n``, equation (3). A Python float for a single triangle.

    Raises
    ------
    ValueError
        If an input is not ``(..., 3)``, the shapes do not broadcast, or ``n`` has zero length.

    Examples
    --------
    The right triangle of unit legs in the plane z = 2, counter-clockwise seen from above,
    casts a prism of area 1/2 and height 2:

    >>> triangle_projected_volume([0, 0, 2], [1, 0, 2], [0, 1, 2], [0, 0, 1])
    1.0
    """
    a = as_vectors(a, 3, "a")
    b = as_vectors(b, 3, "b")
    c = as_vectors(c, 3, "c")
    n = unit(as_vectors(n, 3, "n"), "n")
    try:
        np.broadcast_shapes(a.shape, b.shape, c.shape, n.shape)
    except ValueError as exc:
        raise ValueError(f"a, b, c and n do not broadcast together: {exc}") from None
    area2 = np.sum(np.cross(b - a, c - a) * n, axis=-1)        # twice the projected area, eq. (2)
    height3 = np.sum((a + b + c) * n, axis=-1)                  # three times the height, eq. (3)
    out = area2 * height3 / 6.0
    return float(out) if out.ndim == 0 else out


def _check_mesh(vertices, faces):
    vertices = as_points(vertices, 3, "vertices", min_count=0)
    faces = _check_faces(faces)
    if faces.size and (faces.min() < 0 or faces.max() >= len(vertices)):
        raise ValueError(f"faces index vertices out of range: indices must be in "
                         f"[0, {len(vertices) - 1}], got [{faces.min()}, {faces.max()}]")
    return vertices, faces


def _check_faces(faces):
    arr = np.asarray(faces)
    if arr.size == 0:
        arr = arr.reshape(-1, 3)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"faces must have shape (F, 3), got shape {arr.shape}")
    if arr.dtype.kind == "f":
        if not np.all(np.isfinite(arr)) or np.any(arr != np.round(arr)):
            raise ValueError("faces must hold integer vertex indices")
    elif arr.dtype.kind not in "iu":
        raise ValueError(f"faces must hold integer vertex indices, got dtype {arr.dtype}")
    if arr.size and arr.min() < 0:
        raise ValueError(f"faces index vertices out of range: negative index {arr.min()}")
    return arr.astype(np.int64)


def mesh_volume(vertices, faces, n=(0.0, 0.0, 1.0)) -> float:
    """Signed volume enclosed by a closed triangle mesh: the sum of eq. (4) over faces, Q3(d).

    Parameters
    ----------
    vertices : array_like, shape (V, 3)
    faces : array_like of int, shape (F, 3)
        Vertex indices of each triangle.
    n : array_like, shape (3,)
        Direction of projection (normalised here). For a closed, consistently wound mesh the
        result does not depend on it.

    Returns
    -------
    float
        Positive when the faces are wound counter-clockwise seen from outside (outward
        normals), negative for the opposite winding; 0.0 for no faces.

    Raises
    ------
    ValueError
        Wrong shapes, non-integer faces, indices out of range, or ``n`` of zero length.

    Notes
    -----
    The answer is the enclosed volume only when the surface is closed (no gaps), does not
    intersect itself, is a manifold, and all its triangles are ordered the same way (see
    :func:`is_closed_consistent`): the conditions listed in the solutions to Q3(d).

    Examples
    --------
    A tetrahedron with outward faces:

    >>> v = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    >>> f = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    >>> round(mesh_volume(v, f), 12)
    0.166666666667
    """
    vertices, faces = _check_mesh(vertices, faces)
    n = as_vectors(n, 3, "n")
    if n.shape != (3,):
        raise ValueError(f"n must be one direction of shape (3,), got shape {n.shape}")
    if len(faces) == 0:
        unit(n, "n")
        return 0.0
    tri = vertices[faces]
    return float(np.sum(triangle_projected_volume(tri[:, 0], tri[:, 1], tri[:, 2], n)))


def _directed_edges(faces):
    return np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])


def is_closed_consistent(faces) -> bool:
    """True when every edge is shared by exactly two faces that traverse it in opposite directions.

    That is the "closed and consistently ordered" condition of Q3(d): each directed edge
    ``(u, v)`` occurs once and its reverse ``(v, u)`` occurs once. A face that repeats a vertex
    makes the mesh fail. An empty face list counts as closed.

    Parameters
    ----------
    faces : array_like of int, shape (F, 3)

    Returns
    -------
    bool

    Raises
    ------
    ValueError
        If ``faces`` is not ``(F, 3)`` non-negative integers.

    Examples
    --------
    >>> is_closed_consistent([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    True
    >>> is_closed_consistent([[0, 1, 2], [0, 1, 3], [0, 3, 2], [1, 2, 3]])   # one face flipped
    False
    """
    faces = _check_faces(faces)
    if len(faces) == 0:
        return True
    if np.any((faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2])
              | (faces[:, 2] == faces[:, 0])):
        return False
    d = _directed_edges(faces)
    if len(np.unique(d, axis=0)) != len(d):
        return False                      # a directed edge used twice: inconsistent or non-manifold
    fwd = np.unique(d, axis=0)
    rev = np.unique(d[:, ::-1], axis=0)
    return bool(np.array_equal(fwd, rev))


def boundary_edges(faces) -> np.ndarray:
    """Directed edges ``(u, v)`` used more often than their reverse ``(v, u)``, shape ``(m, 2)``.

    On a consistently wound mesh these are the edges of its holes (Q3(c)): empty for a closed
    mesh. Each is returned in the direction its face traverses it, sorted.
    """
    faces = _check_faces(faces)
    d = _directed_edges(faces)
    if len(d) == 0:
        return d.reshape(0, 2)
    # count each directed edge; an edge is a boundary edge (in its majority direction) when it
    # is used more often one way than the other
    uniq, counts = np.unique(d, axis=0, return_counts=True)
    count = {tuple(e): k for e, k in zip(uniq.tolist(), counts.tolist())}
    out = sorted(e for e, k in count.items() if k > count.get((e[1], e[0]), 0))
    return np.array(out, dtype=np.int64).reshape(-1, 2)


def face_normals(vertices, faces) -> np.ndarray:
    """Un-normalised face normals ``(b - a) x (c - a)`` (twice the area), shape ``(F, 3)``; eq. (1)."""
    vertices, faces = _check_mesh(vertices, faces)
    tri = vertices[faces]
    return np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])


def surface_area(vertices, faces) -> float:
    """Total area ``sum |(b - a) x (c - a)| / 2`` of the triangles, equation (1)."""
    return float(np.linalg.norm(face_normals(vertices, faces), axis=-1).sum() / 2.0)


def canonical_triangles(vertices, faces, decimals: int = 8) -> np.ndarray:
    """The mesh as a sorted ``(F, 9)`` array of rounded triangle coordinates.

    Each triangle is rotated cyclically (which keeps its orientation) so that its smallest
    vertex comes first, then the rows are sorted. Two meshes that differ only in vertex order,
    face order and the starting vertex of each face give the same array.
    """
    vertices, faces = _check_mesh(vertices, faces)
    pts = np.round(vertices[faces], decimals) + 0.0            # (F, 3, 3), -0.0 -> 0.0
    if len(faces) == 0:
        return pts.reshape(0, 9)
    _, rank = np.unique(pts.reshape(-1, 3), axis=0, return_inverse=True)
    order = np.argmin(rank.reshape(-1, 3), axis=1)              # lexicographically first vertex
    idx = (order[:, None] + np.arange(3)) % 3
    rotated = np.take_along_axis(pts, idx[:, :, None], axis=1).reshape(-1, 9)
    return rotated[np.lexsort(rotated.T[::-1])]
