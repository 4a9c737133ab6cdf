"""The numbers behind Q3's fixed figures and cells, computed by the course's references.

:mod:`course_lib.mc_results` hands these to the figures and the notebook. In the instructors'
copy they are computed here, on first use, by :func:`course_lib.marching_cubes.marching_cubes`
and :mod:`course_lib.mesh` (the graded functions' references). The students' wheel holds none
of those functions (docs/students-copy.md): when it is built, this module is replaced by the
text :func:`students_copy` returns, the same :func:`load` over the same arrays written out as
literals, so that the students' figures are the instructors' ones, number for number. Every
input is fixed (a sphere of radius 4.2 in an 11-unit box, the two-cell hole of Q3(c), the
saddle of the Lewiner comparison): the arrays answer no hidden case of a graded function.
"""

from __future__ import annotations

import base64
import functools

import numpy as np

from .mc_results import DIRECTIONS, SPHERE_CONVERGENCE, SPHERE_FIGURE, saddle_volume


def _sphere_figure(mc, mesh) -> dict:
    n, radius = SPHERE_FIGURE["n"], SPHERE_FIGURE["radius"]
    c = (n - 1) / 2 + 0.1
    verts, faces = mc.marching_cubes(mc.sphere_field((n, n, n), (c, c, c)), radius ** 2)
    return {"sphere_verts": verts, "sphere_faces": faces,
            "sphere_volume": np.float64(mesh.mesh_volume(verts, faces))}


def _convergence(mc, mesh) -> dict:
    """Rows ``(h, triangles, closed, volume along each of DIRECTIONS)``."""
    spec = SPHERE_CONVERGENCE
    rows = []
    for h in spec["h"]:
        n_samples = int(round(spec["box"] / h)) + 1
        vol = mc.sphere_field((n_samples,) * 3, (spec["centre"],) * 3, spacing=(h, h, h))
        verts, faces = mc.marching_cubes(vol, spec["radius"] ** 2, spacing=(h, h, h))
        rows.append([h, len(faces), float(mesh.is_closed_consistent(faces))]
                    + [mesh.mesh_volume(verts, faces, d) for d in DIRECTIONS])
    return {"convergence": np.array(rows)}


def _hole(mc, mesh) -> dict:
    _, verts, faces = mc.hole_demo()
    return {"hole_verts": verts, "hole_faces": faces,
            "hole_boundary": mesh.boundary_edges(faces),
            "hole_closed": np.bool_(mesh.is_closed_consistent(faces)),
            "hole_volumes": np.array([mesh.mesh_volume(verts, faces, d) for d in DIRECTIONS])}


def _saddle(mc) -> dict:
    verts, faces = mc.marching_cubes(saddle_volume(), 0.0)
    return {"saddle_verts": verts, "saddle_faces": faces}


def compute() -> dict:
    """Every array, computed now by the references (the instructors' copy only)."""
    from . import marching_cubes as mc
    from . import mesh

    out = {**_sphere_figure(mc, mesh), **_convergence(mc, mesh), **_hole(mc, mesh),
           **_saddle(mc)}
    return {k: np.asarray(v) for k, v in out.items()}


@functools.cache
def load() -> dict:
    """``{name: read-only array}``: the figures' and cells' numbers (see the module docstring)."""
    out = compute()
    for a in out.values():
        a.setflags(write=False)
    return out


STUDENTS_COPY = '''"""The numbers behind Q3's fixed figures and cells, computed by the course's
references when this copy of the library was built (it holds the results, not the functions)."""

import base64
import functools

import numpy as np

#: {name: (dtype, shape, base64 of the array's bytes)}
_ARRAYS = %s


@functools.cache
def load() -> dict:
    """``{name: read-only array}``: the figures' and cells' numbers."""
    out = {}
    for name, (dtype, shape, text) in _ARRAYS.items():
        a = np.frombuffer(base64.b64decode(text), dtype=dtype).reshape(shape).copy()
        a.setflags(write=False)
        out[name] = a
    return out
'''


def students_copy() -> str:
    """The text of this module in the students' wheel: :func:`load` over literal arrays (bit
    for bit those of :func:`compute`), and nothing that computes them."""
    arrays = {name: (a.dtype.str, list(a.shape), base64.b64encode(a.tobytes()).decode("ascii"))
              for name, a in sorted(compute().items())}
    return STUDENTS_COPY % repr(arrays)
