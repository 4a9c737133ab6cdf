"""The numbers behind Q6's fixed figures and cells, computed by the course's references.

:mod:`course_lib.clip_results` hands these to the figures and the notebook. In the instructors'
copy they are computed here, on first use, by the references of :mod:`course_lib.clipping`
(``to_screen``, ``screen_area``, ``clip_polygon``, ``clip_steps``, ``fan_triangulate``) and by
:mod:`course_lib._polygons` (areas, ear clipping, spans). The students' wheel holds none of
those (docs/students-copy.md): when it is built, this module is replaced by the text
:func:`students_copy` returns, the same :func:`load` over the same arrays written out as
literals, so that the students' figures are the instructors' ones, number for number. Every
input is fixed (the exam's triangles, the comb, the star, the explorer's default polygon, a
square): the arrays answer no hidden case of a graded function.
"""

from __future__ import annotations

import base64
import functools

import numpy as np

from .clip_results import COMB, COMB_Y, SQUARE, star_polygon


def _exam(C, pg) -> dict:
    A, B = C.EXAM_Q6["A"], C.EXAM_Q6["B"]
    camera = [C.EXAM_Q6["A_camera"], C.EXAM_Q6["B_camera"]]
    return {"exam_screen_A": C.to_screen(A), "exam_screen_B": C.to_screen(B),
            "exam_screen_areas": np.array([C.screen_area(C.to_screen(P)) for P in (A, B)]),
            "exam_camera_areas": np.array([pg.polygon_area(P[:, 1:]) for P in camera]),
            "A_clipped": C.clip_polygon(A),
            "A_step_counts": np.array([len(s) for s in C.clip_steps(A)])}


def _polygons(C, pg) -> dict:
    star = star_polygon()
    star_tris = pg.ear_clip(star)
    return {"comb_spans": np.array(pg.polygon_spans(COMB, COMB_Y)).reshape(-1, 2),
            "comb_triangles": pg.ear_clip(COMB),
            "star_triangles": star_tris,
            "star_triangle_areas": np.array([pg.polygon_area(star[t]) for t in star_tris]),
            "star_area": np.float64(pg.polygon_area(star)),
            "square_fan": C.fan_triangulate(len(SQUARE))}


def _default(C) -> dict:
    from .widgets.clipping import DEFAULT_POLYGON

    xy = C.to_screen(C.clip_polygon(DEFAULT_POLYGON))[:, :2]
    return {"default_clipped_xy": xy, "default_fan": C.fan_triangulate(len(xy))}


def compute() -> dict:
    """Every array, computed now by the references (the instructors' copy only)."""
    from . import _polygons as pg
    from . import clipping as C

    out = {**_exam(C, pg), **_polygons(C, pg), **_default(C)}
    return {k: np.asarray(v) for k, v in out.items()}


@functools.cache
def load() -> dict:
    """``{name: read-only array}``: the figures' and cells' numbers (see the module docstring)."""
    out = compute()
    for a in out.values():
        a.setflags(write=False)
    return out


STUDENTS_COPY = '''"""The numbers behind Q6's fixed figures and cells, computed by the course's
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
