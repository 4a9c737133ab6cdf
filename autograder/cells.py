"""nbgrader's cells as the course reads them: a cell's role, from its nbgrader metadata, and its
source as one string.

nbgrader marks a cell with two flags, ``solution`` (the student writes it) and ``grade`` (it
earns points); together they give the cell's role, as nbgrader's "Create Assignment" toolbar
names them (:class:`CellRole`). The source notebooks, the release check and the gradebook all
ask :func:`cell_role`, so the flags are read in one place. This module imports nothing of the
package.
"""

from __future__ import annotations

import enum


class CellRole(str, enum.Enum):
    """What an nbgrader cell is, from its ``solution`` and ``grade`` flags."""

    ANSWER = "answer"     #: ``solution`` only: the student's answer, graded by its test cell
    TESTS = "tests"       #: ``grade`` only: autograder tests, with points
    MANUAL = "manual"     #: ``solution`` and ``grade``: an answer marked by hand, with points
    OTHER = "other"       #: neither (text, setup, figures; possibly ``locked``)

    @property
    def by_student(self) -> bool:
        """Whether the student writes this cell (nbgrader's ``solution`` flag)."""
        return self in (CellRole.ANSWER, CellRole.MANUAL)


def cell_role(meta) -> CellRole:
    """The role of a cell whose nbgrader metadata is ``meta`` (anything not a dict: OTHER)."""
    if not isinstance(meta, dict):
        return CellRole.OTHER
    solution, grade = bool(meta.get("solution")), bool(meta.get("grade"))
    if solution:
        return CellRole.MANUAL if grade else CellRole.ANSWER
    return CellRole.TESTS if grade else CellRole.OTHER


def join_source(source) -> str:
    """A notebook cell's ``source`` (a string or a list of strings) as one string (anything
    else: ``""``)."""
    if isinstance(source, list):
        return "".join(str(s) for s in source)
    return source if isinstance(source, str) else ""
