"""The numbers behind Q2's fixed "going further" cells, computed by the course's references.

:mod:`course_lib.collimator_results` hands these to the notebook. In the instructors' copy they
are computed here, on first use, by :func:`course_lib.gamma_camera.ring_hole_positions` and
:func:`course_lib.gamma_camera.open_fraction` (the graded functions' references). The students'
wheel holds neither (docs/students-copy.md): when it is built, this module is replaced by the
text :func:`students_copy` returns, the same :func:`load` over the same arrays written out as
literals, so that the students' cells print the instructors' numbers. Every input is fixed (the
exam's collimator and a thin one): the arrays answer no hidden case of a graded function.
"""

from __future__ import annotations

import base64
import functools

import numpy as np

from .collimator_results import EXAM, THIN


def compute() -> dict:
    """Every array, computed now by the references (the instructors' copy only)."""
    from . import gamma_camera as gc

    holes = gc.ring_hole_positions(EXAM["pitch"], EXAM["n_rings"])
    exam = gc.open_fraction(holes, EXAM["d"], EXAM["L"], EXAM["source_distance"],
                            EXAM["collimator_radius"])
    thin = gc.open_fraction(holes, **THIN)
    return {"exam_holes": np.asarray(holes), "exam_fraction": np.float64(exam),
            "thin_fraction": np.float64(thin)}


@functools.cache
def load() -> dict:
    """``{name: read-only array}``: the cells' numbers (see the module docstring)."""
    out = {k: np.asarray(v) for k, v in compute().items()}
    for a in out.values():
        a.setflags(write=False)
    return out


STUDENTS_COPY = '''"""The numbers behind Q2's fixed "going further" cells, computed by the course's
references when this copy of the library was built (it holds the results, not the functions)."""

import base64
import functools

import numpy as np

#: {name: (dtype, shape, base64 of the array's bytes)}
_ARRAYS = %s


@functools.cache
def load() -> dict:
    """``{name: read-only array}``: the cells' numbers."""
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
              for name, a in sorted((k, np.asarray(v)) for k, v in compute().items())}
    return STUDENTS_COPY % repr(arrays)
