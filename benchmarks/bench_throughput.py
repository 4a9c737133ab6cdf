"""Throughput: mesh volume, polygon clipping and Phong shading on large batches vs naive loops.

- **mesh volume** (Q3(d)): :func:`course_lib.mesh.mesh_volume` on an icosphere of 1.3 million
  triangles against a per-triangle Python loop over equation (4) of the solutions, and against
  trimesh's ``Trimesh.volume`` (a compiled-library peer); all three must agree.
- **clipping** (Q6(b)(iii)): :func:`course_lib.clipping.clip_polygon` called on each of many
  random homogeneous triangles and quadrilaterals against a plain per-vertex Sutherland-Hodgman
  in pure Python (written here); both must keep the same number of vertices per polygon.
  ``clip_polygon`` works on Python floats for small polygons; ``clip_polygons`` clips the
  whole list in one call.
- **Phong shading** (Q5(b)): :func:`course_lib.shading.phong` on 10⁶ normals against a per-pixel
  Python loop timed on a subsample of normals and scaled up to 10⁶ (labelled in the table).
"""

from __future__ import annotations

import math

import numpy as np

from .harness import Row, time_call

SECTION = "throughput"


# ------------------------------------------------------------------------------------------------
# mesh volume


def icosphere(subdivisions: int):
    """Unit icosphere with outward (counter-clockwise from outside) faces: ``20 * 4**s`` faces."""
    import trimesh

    mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    return np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=np.int64)


def naive_mesh_volume(vertices, faces) -> float:
    """Equation (4) summed one triangle at a time with Python floats (projection along z)."""
    V = vertices.tolist()
    total = 0.0
    for i, j, k in faces.tolist():
        ax, ay, az = V[i]
        bx, by, bz = V[j]
        cx, cy, cz = V[k]
        area2 = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)   # ((b - a) x (c - a)) . z
        total += area2 * (az + bz + cz) / 6.0
    return total


def _mesh_rows(smoke: bool) -> list[Row]:
    import trimesh

    from course_lib.mesh import mesh_volume

    subdiv = 3 if smoke else 8
    verts, faces = icosphere(subdiv)
    nf = len(faces)
    ours_v = mesh_volume(verts, faces)
    naive_v = naive_mesh_volume(verts, faces)
    tm = trimesh.Trimesh(verts, faces, process=False)
    tm_v = float(tm.volume)
    agree = (math.isclose(ours_v, naive_v, rel_tol=1e-9, abs_tol=1e-12)
             and math.isclose(ours_v, tm_v, rel_tol=1e-9, abs_tol=1e-12))
    ours = time_call(lambda: mesh_volume(verts, faces), repeat=5)["median"]
    naive = time_call(lambda: naive_mesh_volume(verts, faces), repeat=3, warmup=0)["median"]

    def trimesh_volume():
        # a fresh Trimesh each time: its volume is otherwise cached after the first call
        return trimesh.Trimesh(verts, faces, process=False).volume

    peer = time_call(trimesh_volume, repeat=5)["median"]
    note = (f"icosphere, {nf:,} triangles; volume {ours_v:.6f} "
            f"({'all three agree' if agree else f'DISAGREE: loop {naive_v}, trimesh {tm_v}'})")
    return [
        Row(SECTION, f"mesh_volume, {nf:,} triangles", "time", ours, naive,
            "per-triangle Python loop", notes=note),
        Row(SECTION, f"mesh_volume, {nf:,} triangles", "time", ours, peer,
            "trimesh Trimesh.volume", notes="trimesh: a new Trimesh per call (its volume is "
                                            "cached otherwise)"),
    ]


# ------------------------------------------------------------------------------------------------
# clipping


def random_polygons(count: int, seed: int = 0) -> list[np.ndarray]:
    """Triangles and quadrilaterals in homogeneous screen coordinates, ``w`` in [0.5, 2],
    scattered so that most cross one or more planes of the view volume."""
    rng = np.random.default_rng(seed)
    polys = []
    for k in range(count):
        n = 3 + (k % 2)
        w = rng.uniform(0.5, 2.0, n)
        xyz = rng.uniform([-2.0, -2.0, -0.5], [2.0, 2.0, 1.5], (n, 3)) * w[:, None]
        polys.append(np.column_stack([xyz, w]))
    return polys


_PLANES = [(1.0, 0.0, 0.0, 1.0), (-1.0, 0.0, 0.0, 1.0), (0.0, 1.0, 0.0, 1.0),
           (0.0, -1.0, 0.0, 1.0), (0.0, 0.0, 1.0, 0.0), (0.0, 0.0, -1.0, 1.0)]


def naive_clip(poly: list[list[float]]) -> list[list[float]]:
    """Sutherland-Hodgman against the six planes, one vertex at a time, in pure Python."""
    for px, py, pz, pw in _PLANES:
        out = []
        n = len(poly)
        for i in range(n):
            s, e = poly[i], poly[(i + 1) % n]
            ds = px * s[0] + py * s[1] + pz * s[2] + pw * s[3]
            de = px * e[0] + py * e[1] + pz * e[2] + pw * e[3]
            if ds >= 0:
                out.append(s)
            if ds * de < 0:
                t = ds / (ds - de)
                out.append([s[0] + t * (e[0] - s[0]), s[1] + t * (e[1] - s[1]),
                            s[2] + t * (e[2] - s[2]), s[3] + t * (e[3] - s[3])])
        poly = out
        if len(poly) < 3:
            return []
    return poly


def _clip_rows(smoke: bool) -> list[Row]:
    from course_lib.clipping import clip_polygon, clip_polygons

    polys = random_polygons(200 if smoke else 5000)
    as_lists = [p.tolist() for p in polys]
    counts_ours = [len(clip_polygon(p)) for p in polys]
    counts_batch = [len(c) for c in clip_polygons(polys)]
    counts_naive = [len(naive_clip(p)) for p in as_lists]
    mismatched = sum(a != b for a, b in zip(counts_ours, counts_naive, strict=True))
    mismatched_batch = sum(a != b for a, b in zip(counts_batch, counts_naive, strict=True))
    kept = sum(c > 0 for c in counts_ours)
    ours = time_call(lambda: [clip_polygon(p) for p in polys], repeat=3)["median"]
    batch = time_call(lambda: clip_polygons(polys), repeat=3)["median"]
    naive = time_call(lambda: [naive_clip(p) for p in as_lists], repeat=3)["median"]
    n = len(polys)

    def agree(bad):
        return "same vertex counts" if not bad else f"{bad} vertex counts differ"

    note = (f"{n:,} random triangles/quads, {kept:,} with something left; {agree(mismatched)}; "
            f"per polygon {1e3 * ours / n:.1f} µs vs {1e3 * naive / n:.1f} µs "
            "(one call per polygon: argument checks and array conversion on 3-4 vertices)")
    note_batch = (f"the same {n:,} polygons in one call; {agree(mismatched_batch)}; "
                  f"per polygon {1e3 * batch / n:.1f} µs vs {1e3 * naive / n:.1f} µs")
    return [Row(SECTION, f"clip_polygon, {n:,} polygons", "time", ours, naive,
                "pure-Python Sutherland-Hodgman", notes=note),
            Row(SECTION, f"clip_polygons (batch), {n:,} polygons", "time", batch, naive,
                "pure-Python Sutherland-Hodgman", notes=note_batch)]


# ------------------------------------------------------------------------------------------------
# Phong shading


def naive_phong(colour, Ia, ka, Ip, kd, ks, n, L, normals, V):
    """The Phong model of Q5(a) evaluated one normal at a time with Python floats."""
    def unit(v):
        s = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
        return (v[0] / s, v[1] / s, v[2] / s)

    L, V = unit(L), unit(V)
    out = []
    for N in normals:
        N = unit(N)
        ln = L[0] * N[0] + L[1] * N[1] + L[2] * N[2]
        if ln > 0:
            R = (2 * ln * N[0] - L[0], 2 * ln * N[1] - L[1], 2 * ln * N[2] - L[2])
            rv = max(R[0] * V[0] + R[1] * V[1] + R[2] * V[2], 0.0)
            spec = Ip * ks * rv ** n
            body = Ia * ka + Ip * kd * ln
        else:
            spec, body = 0.0, Ia * ka
        out.append((colour[0] * body + spec, colour[1] * body + spec, colour[2] * body + spec))
    return out


def _phong_rows(smoke: bool) -> list[Row]:
    from course_lib.shading import phong

    total = 10_000 if smoke else 1_000_000
    sub = 2_000 if smoke else 20_000
    rng = np.random.default_rng(1)
    N = rng.normal(size=(total, 3))
    args = ((0.2, 0.4, 1.0), 1.0, 0.5, 1.0, 0.5, 1.0, 10.0)
    L, V = (1.0, -1.0, 1.0), (0.0, 1.0, 0.0)
    ours_img = phong(*args, L, N[:sub], V)
    naive_img = np.array(naive_phong(*args, L, N[:sub].tolist(), V))
    agree = np.allclose(ours_img, naive_img, rtol=1e-9, atol=1e-12)
    ours = time_call(lambda: phong(*args, L, N, V), repeat=5)["median"]
    normals = N[:sub].tolist()
    naive_sub = time_call(lambda: naive_phong(*args, L, normals, V), repeat=3)["median"]
    scale = total / sub
    note = (f"loop timed on {sub:,} normals ({naive_sub:.0f} ms) and scaled ×{scale:g} to "
            f"{total:,}; {'results agree' if agree else 'RESULTS DIFFER'} on the subsample")
    return [Row(SECTION, f"phong, {total:,} normals", "time", ours, naive_sub * scale,
                "per-pixel Python loop (scaled)", notes=note)]


def run(smoke: bool = False) -> list[Row]:
    rows = []
    for part in (_mesh_rows, _clip_rows, _phong_rows):
        rows.extend(part(smoke))
    return rows
