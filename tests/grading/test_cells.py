"""``autograder.cells``: a cell's role and its source, against nbgrader's own reading of the
course's notebooks (``nbgrader.utils.is_solution`` / ``is_grade``) and nbformat's."""

from __future__ import annotations

import json

import nbformat
import pytest
from nbgrader import utils

from autograder.cells import CellRole, cell_role, join_source
from autograder.course import source_notebooks

NOTEBOOKS = source_notebooks()


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_roles_agree_with_nbgrader(path):
    nb = nbformat.read(str(path), as_version=4)
    seen = set()
    for cell in nb.cells:
        role = cell_role(cell.metadata.get("nbgrader", {}))
        solution, grade = bool(utils.is_solution(cell)), bool(utils.is_grade(cell))
        assert role.by_student == solution, cell.metadata
        assert (role in (CellRole.TESTS, CellRole.MANUAL)) == grade, cell.metadata
        seen.add(role)
    assert {CellRole.ANSWER, CellRole.TESTS, CellRole.OTHER} <= seen, path.name


def test_anything_but_a_dict_of_flags_is_other():
    for meta in (None, [], "solution", 3):
        assert cell_role(meta) is CellRole.OTHER
    assert cell_role({"solution": True, "grade": True}) is CellRole.MANUAL
    assert cell_role({"solution": 0, "grade": 1}) is CellRole.TESTS


def test_join_source_reads_the_lines_nbformat_writes():
    """nbformat writes a multi-line source as a list of lines; joined, it is the text again."""
    text = "def f(x):\n    return x\n\n# done"
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(text)])
    raw = json.loads(nbformat.writes(nb))["cells"][0]["source"]
    assert isinstance(raw, list) and len(raw) == 4
    assert join_source(raw) == text
    assert join_source(text) == text
    assert join_source(None) == "" and join_source({"x": 1}) == ""
