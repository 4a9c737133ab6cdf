"""Q3's fixed examples, worked by the course's references: meshes, volumes, a convergence table.

The figures of :mod:`course_lib.plots.marching_cubes` and the "putting the pieces together"
and "going further" cells of the Q3 notebook show what the course's ``marching_cubes`` and
``mesh_volume`` give on a few fixed inputs: a sphere of radius 4.2 sampled on a 12**3 grid, the
same sphere on finer and finer grids (Q3(d)'s convergence), the two cells of Q3(c) whose mixed
triangulations leave a hole, and a face whose saddle Lewiner's decider resolves differently.

The students' copy of the library holds these results, computed when it was built, and not the
functions that compute them (writing those is the question). Every function here returns the
same arrays in both copies; none takes an input of yours.
"""

from __future__ import annotations

import numpy as np

__all__ = ["DIRECTIONS", "SPHERE_CONVERGENCE", "SPHERE_FIGURE", "hole_mesh", "hole_volumes",
           "saddle_mesh", "saddle_volume", "sphere_convergence", "sphere_mesh"]

#: the sphere of the figure: ``n**3`` samples at unit spacing, centre ``(n - 1) / 2 + 0.1``
SPHERE_FIGURE = {"n": 12, "radius": 4.2}
#: the convergence table's sphere: radius, centre (each coordinate) and box side, and spacings
SPHERE_CONVERGENCE = {"radius": 4.2, "centre": 5.6, "box": 11.0, "h": (1.0, 0.5, 0.25, 0.125)}
#: the directions of projection ``n`` of equation (4) the volumes are computed along
DIRECTIONS = ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (1.0, 1.0, 1.0))


def _data() -> dict:
    from ._mc_results_data import load

    return load()


def saddle_volume() -> np.ndarray:
    """The Lewiner comparison's 4 x 4 x 3 volume: two samples far below the level 0 on one
    diagonal of a face, the other two just above it (the face's saddle is below the level)."""
    vol = np.full((4, 4, 3), 1.0)
    vol[1, 1, 1] = vol[2, 2, 1] = -1.0
    vol[1, 2, 1] = vol[2, 1, 1] = 0.1
    return vol


def sphere_mesh():
    """``(verts, faces, volume)``: the sphere of :data:`SPHERE_FIGURE` (iso-level ``r**2`` of
    ``|x - c|**2``) triangulated by marching cubes, and the volume equation (4) gives it, Q3(d)."""
    d = _data()
    return d["sphere_verts"], d["sphere_faces"], float(d["sphere_volume"])


def sphere_convergence() -> list[dict]:
    """The sphere of :data:`SPHERE_CONVERGENCE` on grids of spacing ``h`` = 1, 1/2, 1/4, 1/8:
    one dict per ``h`` with ``h``, ``triangles``, ``closed`` (every edge shared by two faces,
    opposite ways) and ``volumes`` (equation (4) along each of :data:`DIRECTIONS`)."""
    return [{"h": float(row[0]), "triangles": int(row[1]), "closed": bool(row[2]),
             "volumes": tuple(float(v) for v in row[3:])} for row in _data()["convergence"]]


def hole_mesh():
    """``(verts, faces, hole)``: the volume of Q3(c)'s hole example (5 x 4 x 4 samples of 1,
    two samples of 0 on a diagonal of the face ``x = 2``, iso-level 0.5), meshed with the left
    cell joining the inside corners and the right keeping them apart; ``hole`` the directed
    edges (pairs of vertex numbers) that only one side uses: the outline of the hole."""
    d = _data()
    return d["hole_verts"], d["hole_faces"], d["hole_boundary"]


def hole_volumes():
    """``(closed, volumes)`` of :func:`hole_mesh`: it is not closed, and equation (4) gives it
    a different "volume" along each of :data:`DIRECTIONS`."""
    d = _data()
    return bool(d["hole_closed"]), tuple(float(v) for v in d["hole_volumes"])


def saddle_mesh():
    """``(verts, faces)``: :func:`saddle_volume` at iso-level 0 by our table (which keeps the
    two inside samples apart: two separate closed pieces)."""
    d = _data()
    return d["saddle_verts"], d["saddle_faces"]
