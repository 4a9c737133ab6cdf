"""The end weights behind Q4's formulas panel and tables, computed by the course's references.

:mod:`course_lib.spline_weights` hands them to the end-condition explorer and the notebook. In
the instructors' copy they are computed here, on first use, by
:func:`course_lib.splines.end_weights` over the two basis matrices (the graded functions'
references). The students' wheel holds none of those functions (docs/students-copy.md): when it
is built, this module is replaced by the text :func:`students_copy` returns, the same
:func:`load` over the same tables written out as literals. Each table is fixed (two splines,
the general rows and three end rules): small rationals, the panel's own text, which answer no
hidden case of a graded function.
"""

from __future__ import annotations

import functools
from fractions import Fraction

#: the splines and the rules the tables cover ("free": the general rows of Q4(b))
KINDS = ("catmull-rom", "b-spline")
RULES = ("free", "d=b", "d=2c-b", "d=c")
#: every weight is a multiple of 1/6; a larger denominator means the reference changed
MAX_DENOMINATOR = 6


def _as_text(weight: float) -> str:
    frac = Fraction(float(weight)).limit_denominator(MAX_DENOMINATOR)
    if abs(float(frac) - float(weight)) > 1e-12:
        raise ValueError(f"end weight {weight!r} is not a multiple of 1/{MAX_DENOMINATOR}")
    return str(frac)


def compute() -> dict:
    """``{(kind, rule): ((w_a, w_b, w_c, w_d) for p, p', p'')}``, each weight an exact
    fraction as text (``"-1/2"``), computed now by the references (the instructors' copy only)."""
    from . import splines

    out = {}
    for kind in KINDS:
        M = splines.basis_matrix(kind)
        for rule in RULES:
            W = splines.end_weights(M, rule)
            out[(kind, rule)] = tuple(tuple(_as_text(w) for w in row) for row in W)
    return out


@functools.cache
def load() -> dict:
    """The tables of :func:`compute` (see the module docstring)."""
    return compute()


STUDENTS_COPY = '''"""The end weights behind Q4's formulas panel and tables, computed by the course's
references when this copy of the library was built (it holds the tables, not the functions)."""

#: {(kind, rule): ((w_a, w_b, w_c, w_d) for p, p', p''), each weight a fraction as text}
_TABLES = %s


def load() -> dict:
    """The end-weight tables (see the module docstring)."""
    return dict(_TABLES)
'''


def students_copy() -> str:
    """The text of this module in the students' wheel: :func:`load` over literal tables (those
    of :func:`compute`, string for string), and nothing that computes them."""
    return STUDENTS_COPY % repr(dict(sorted(compute().items())))
