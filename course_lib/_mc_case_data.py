"""What the Q3 case explorer and figures label and draw: Lorensen's case of each case index and
the alternative triangulations the notebook shows, computed by the course's references.

:func:`course_lib.marching_cubes.case_of` (the explorer's "Lorensen case" label, Q3(b)) reads
:func:`case_labels`; the figures of the six ambiguous cases and the explorer's "alternative
triangulation" view (Q3(c)) read :func:`shown_alternatives`. In the instructors' copy both are
computed here, on first use, by the references (the symmetry classes of
:func:`course_lib.marching_cubes.symmetry_orbit`'s group, :data:`course_lib._mc_tables.ALT_TRI_TABLE`).
The students' wheel holds none of those (docs/students-copy.md): when it is built, this module
is replaced by the text :func:`students_copy` returns, the same two functions over literals.

The alternative triangulation is shown for :data:`SHOWN_INDICES` only, the representative of
each of Lorensen's six ambiguous cases (the figure's cells); the hidden cases of
``alternative_triangulation`` are the other orientations of those classes
(``autograder/exercises/q3_marching_cubes.py``), so no shipped row answers one.
"""

from __future__ import annotations

import functools

#: the case indices whose alternative triangulation the figures and the explorer draw: the
#: representatives (``BASE_CASES[k].index``) of Lorensen's ambiguous cases 3, 6, 7, 10, 12, 13
SHOWN_INDICES = (5, 67, 26, 195, 135, 165)


def compute() -> dict:
    """``{"case_of": (256 Lorensen numbers), "alternatives": {index: ((e, e, e), ...)}}``,
    computed now by the references (the instructors' copy only)."""
    from . import _mc_tables
    from . import marching_cubes as mc

    labels = mc._orbit_labels(True, False)
    number = {int(labels[c.index]): c.number for c in mc.BASE_CASES}
    alternatives = {i: tuple(tuple(int(e) for e in row)
                             for row in _mc_tables.ALT_TRI_TABLE[i, :_mc_tables.ALT_N_TRIANGLES[i]])
                    for i in SHOWN_INDICES}
    return {"case_of": tuple(number[int(label)] for label in labels),
            "alternatives": alternatives}


@functools.cache
def _data() -> dict:
    return compute()


def case_labels() -> tuple:
    """Lorensen's case number (0 ... 14) of each case index 0 ... 255 (rotations and complement)."""
    return _data()["case_of"]


def shown_alternatives() -> dict:
    """``{index: ((edge, edge, edge), ...)}``: the joined triangulation of each of
    :data:`SHOWN_INDICES`, as rows of three edge numbers."""
    return dict(_data()["alternatives"])


STUDENTS_COPY = '''"""What the Q3 case explorer and figures label and draw: Lorensen's case of each case
index, and the joined (alternative) triangulation of the representative of each ambiguous case,
computed by the course's references when this copy of the library was built."""

SHOWN_INDICES = %r

_CASE_OF = %r

_ALTERNATIVES = %r


def case_labels() -> tuple:
    """Lorensen's case number (0 ... 14) of each case index 0 ... 255."""
    return _CASE_OF


def shown_alternatives() -> dict:
    """``{index: ((edge, edge, edge), ...)}`` for the indices of ``SHOWN_INDICES``."""
    return dict(_ALTERNATIVES)
'''


def students_copy() -> str:
    """The text of this module in the students' wheel: the two readers over literals (equal to
    :func:`compute`'s), and nothing that computes them."""
    data = compute()
    return STUDENTS_COPY % (SHOWN_INDICES, data["case_of"], data["alternatives"])
