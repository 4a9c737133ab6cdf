# ruff: noqa: F821  (CORNERS, EDGES, N_TRIANGLES, TRI_TABLE come from the notebook's setup cell)
"""Q3 written from the exam and the given lookup tables (not from course_lib's functions).

The setup cell of the notebook gives CORNERS, EDGES, N_TRIANGLES and TRI_TABLE (the classic
tables are handed to students); everything else is written here.
"""

import itertools

import numpy as np


def interpolate_edge(p0, p1, v0, v1, iso):
    p0 = np.asarray(p0, dtype=float)
    p1 = np.asarray(p1, dtype=float)
    if p0.shape[-1:] != (3,) or p1.shape[-1:] != (3,):
        raise ValueError("points must be 3-D")
    v0, v1, iso = (np.asarray(x, dtype=float) for x in (v0, v1, iso))
    lo, hi = np.minimum(v0, v1), np.maximum(v0, v1)
    if np.any((iso < lo) | (iso > hi)):
        raise ValueError("the iso-level is not on this edge")
    same = v0 == v1
    t = np.divide(iso - v0, v1 - v0, out=np.zeros(np.broadcast(v0, v1, iso).shape),
                  where=~same)
    return p0 + t[..., None] * (p1 - p0)


def cube_index(values, iso):
    values = np.asarray(values, dtype=float)
    if values.ndim == 0 or values.shape[-1] != 8:
        raise ValueError("eight corner values are needed (last axis of length 8)")
    weights = 2 ** np.arange(8)                       # bit i <-> corner i
    index = np.sum(np.where(values < iso, weights, 0), axis=-1)
    return int(index) if index.ndim == 0 else index.astype(np.int64)


def count_symmetry_classes(complement=False, reflections=False):
    corners = list(itertools.product((0, 1), repeat=3))
    # corner numbering of the course: position of corner c is CORNERS[c]
    position = {tuple(int(x) for x in CORNERS[c]): c for c in range(8)}
    maps = []
    for perm in itertools.permutations(range(3)):
        for flips in itertools.product((False, True), repeat=3):
            matrix = np.zeros((3, 3))
            for row, (col, flip) in enumerate(zip(perm, flips, strict=True)):
                matrix[row, col] = -1.0 if flip else 1.0
            if not reflections and np.linalg.det(matrix) < 0:
                continue
            image = []
            for c in range(8):
                centred = 2 * np.asarray(CORNERS[c], dtype=float) - 1
                moved = (matrix @ centred + 1) / 2
                image.append(position[tuple(int(round(x)) for x in moved)])
            maps.append(image)
    classes = set()
    for pattern in range(256):
        orbit = []
        for image in maps:
            moved = sum(1 << image[c] for c in range(8) if pattern >> c & 1)
            orbit.append(moved)
            if complement:
                orbit.append(255 ^ moved)
        classes.add(min(orbit))
    del corners
    return len(classes)


def marching_cubes(volume, iso, spacing=(1.0, 1.0, 1.0)):
    volume = np.asarray(volume, dtype=float)
    spacing = np.asarray(spacing, dtype=float)
    if volume.ndim != 3 or min(volume.shape) < 2:
        raise ValueError("a 3-D volume of at least 2 samples per axis is needed")
    if spacing.shape != (3,) or np.any(spacing <= 0):
        raise ValueError("spacing must be three positive numbers")
    shared = {}
    vertices, triangles = [], []

    def vertex(a, b):
        key = (min(a, b), max(a, b))       # one vertex per grid edge, shared by its cells
        if key not in shared:
            va, vb = volume[a], volume[b]
            t = 0.0 if va == vb else (iso - va) / (vb - va)
            pa, pb = np.array(a, float) * spacing, np.array(b, float) * spacing
            shared[key] = len(vertices)
            vertices.append(pa + t * (pb - pa))
        return shared[key]

    nx, ny, nz = volume.shape
    for i, j, k in itertools.product(range(nx - 1), range(ny - 1), range(nz - 1)):
        samples = [(i + int(dx), j + int(dy), k + int(dz)) for dx, dy, dz in CORNERS]
        case = cube_index([volume[s] for s in samples], iso)
        for row in TRI_TABLE[case][: N_TRIANGLES[case]]:
            triangles.append([vertex(samples[EDGES[e][0]], samples[EDGES[e][1]]) for e in row])
    return (np.array(vertices, dtype=float).reshape(-1, 3),
            np.array(triangles, dtype=np.int64).reshape(-1, 3))


def triangle_projected_volume(a, b, c, n=(0.0, 0.0, 1.0)):
    a, b, c, n = (np.asarray(x, dtype=float) for x in (a, b, c, n))
    if any(x.shape[-1:] != (3,) for x in (a, b, c, n)):
        raise ValueError("vertices and n must be 3-D")
    size = np.sqrt(np.sum(n * n, axis=-1, keepdims=True))
    if np.any(size == 0):
        raise ValueError("n must not be zero")
    u = n / size
    area2 = np.sum(np.cross(b - a, c - a) * u, axis=-1)     # twice the projected area
    height3 = np.sum((a + b + c) * u, axis=-1)              # three times the centroid height
    out = area2 * height3 / 6.0
    return float(out) if np.ndim(out) == 0 else out


def mesh_volume(vertices, faces, n=(0.0, 0.0, 1.0)):
    V = np.asarray(vertices, dtype=float)
    F = np.asarray(faces)
    if V.ndim != 2 or V.shape[1] != 3:
        raise ValueError("vertices must be (V, 3)")
    if F.size == 0:
        return 0.0
    if F.ndim != 2 or F.shape[1] != 3 or F.dtype.kind not in "iu":
        raise ValueError("faces must be (F, 3) integers")
    if F.min() < 0 or F.max() >= len(V):
        raise ValueError("face index out of range")
    return float(np.sum(triangle_projected_volume(V[F[:, 0]], V[F[:, 1]], V[F[:, 2]], n)))


def is_closed_consistent(faces):
    F = np.asarray(faces)
    if F.size == 0:
        return True
    if F.ndim != 2 or F.shape[1] != 3 or F.dtype.kind not in "iu" or F.min() < 0:
        raise ValueError("faces must be (F, 3) non-negative integers")
    directed = {}
    for u, v, w in F.tolist():
        if len({u, v, w}) < 3:
            return False
        for edge in ((u, v), (v, w), (w, u)):
            directed[edge] = directed.get(edge, 0) + 1
    return all(count == 1 and directed.get((v, u), 0) == 1 for (u, v), count in directed.items())


def symmetry_orbit(index, complement=False, reflections=False):
    if isinstance(index, bool) or not float(index).is_integer() or not 0 <= index <= 255:
        raise ValueError("index must be a whole number from 0 to 255")
    index = int(index)
    # the rotation group as the closure of two quarter turns, acting on corner positions
    quarter_x = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]])
    quarter_z = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]])
    group, todo = {tuple(np.eye(3, dtype=int).ravel())}, [np.eye(3, dtype=int)]
    while todo:
        m = todo.pop()
        for g in (quarter_x, quarter_z):
            key = tuple((g @ m).ravel())
            if key not in group:
                group.add(key)
                todo.append(g @ m)
    mats = [np.array(k).reshape(3, 3) for k in group]
    if reflections:
        mats += [-m for m in mats]                      # the point reflection times each rotation
    position = {tuple(2 * np.asarray(CORNERS[c]) - 1): c for c in range(8)}
    members = set()
    for m in mats:
        image = 0
        for c in range(8):
            if index >> c & 1:
                image |= 1 << position[tuple(m @ (2 * np.asarray(CORNERS[c]) - 1))]
        members.add(image)
        if complement:
            members.add(image ^ 255)
    return np.array(sorted(members), dtype=np.int64)


def alternative_triangulation(index):
    if isinstance(index, bool) or not float(index).is_integer() or not 0 <= index <= 255:
        raise ValueError("index must be a whole number from 0 to 255")
    index = int(index)
    # the six faces found from the corner positions: four corners sharing one coordinate value
    ambiguous = False
    for axis in range(3):
        for value in (0, 1):
            quad = [c for c in range(8) if CORNERS[c][axis] == value]
            # order the four corners around the face: by angle about the face centre
            others = [a for a in range(3) if a != axis]
            quad.sort(key=lambda c: np.arctan2(CORNERS[c][others[1]] - 0.5,
                                               CORNERS[c][others[0]] - 0.5))
            flags = [index >> c & 1 for c in quad]
            if flags[0] == flags[2] != flags[1] == flags[3]:
                ambiguous = True
    if not ambiguous:
        raise ValueError("this case has a single triangulation")
    flipped = index ^ 255                # joining inside corners = separating the complement's
    rows = TRI_TABLE[flipped][: N_TRIANGLES[flipped]]
    return np.array([[e for e in reversed(row)] for row in rows], dtype=np.int64).reshape(-1, 3)
