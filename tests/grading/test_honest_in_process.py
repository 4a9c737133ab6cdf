"""The honest bank (``tests/grading/honest/``) against every registered case, in this process.

``test_bank.py`` grades the honest student through the sandbox in ``make test`` (minutes, a
whole batch); this is the same judgement without the sandbox (``judging.judge_case`` and
``judge_cell``, as ``incell.check`` and ``grade`` use), on several seeds of hidden cases, so
that ``make test-fast`` sees at once what a change to an exercise breaks for an honest
student: a case the reference and an answer written from the exam no longer agree on, a graded
function with no honest answer yet, an answer left for a name the registry dropped.
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from autograder import marks
from autograder.cells import join_source
from autograder.course import NOTEBOOKS_DIR
from autograder.exercises import NOTEBOOKS, for_notebook
from autograder.judging import CellEvidence, call_in_process, judge_case, judge_cell
from autograder.model import CaseRecord, Status

HONEST_DIR = Path(__file__).parent / "honest"
#: hidden cases are drawn per student from the course secret: a few seeds stand for a class
SEEDS = (0, 1, 2)


def _honest(notebook: str) -> dict:
    """The honest answers run as the grader runs a submission: after the notebook's setup cell
    (q3's answers use the tables it gives students)."""
    cells = marks.read_cells(NOTEBOOKS_DIR / f"{notebook}.ipynb")
    setup = next(join_source(c["source"]) for c in cells
                 if c.get("metadata", {}).get("nbgrader", {}).get("grade_id") == f"setup_{notebook}")
    path = HONEST_DIR / f"{notebook}.py"
    namespace: dict = {"__name__": f"honest_{notebook}"}
    exec(compile(setup, f"setup_{notebook}", "exec"), namespace)
    exec(compile(path.read_text(encoding="utf-8"), str(path), "exec"), namespace)
    return namespace


def _functions(notebook: str) -> list[str]:
    return [ex.name for ex in for_notebook(notebook) if ex.kind == "function"]


CASES = [(nb, name) for nb in NOTEBOOKS for name in _functions(nb)]


@pytest.mark.parametrize("notebook", NOTEBOOKS)
def test_every_graded_function_has_an_honest_answer_and_no_other(notebook):
    path = HONEST_DIR / f"{notebook}.py"
    assert path.exists(), f"no honest answers for {notebook}: write {path}"
    defined = {node.name for node in ast.parse(path.read_text(encoding="utf-8")).body
               if isinstance(node, ast.FunctionDef) and not node.name.startswith("_")}
    graded = set(_functions(notebook))
    assert graded - defined == set(), f"graded functions with no honest answer in {path.name}"
    assert defined - graded == set(), f"honest answers for names {notebook} does not grade"


@pytest.mark.parametrize("notebook, name", CASES, ids=[n for _, n in CASES])
def test_the_honest_answer_earns_full_marks_on_every_case(notebook, name):
    from autograder.exercises import get

    ex, func = get(name), _honest(notebook)[name]
    for seed in SEEDS:
        records = []
        for i, case in enumerate(ex.draw_cases(np.random.default_rng(seed))):
            expected = ex.expected(case) if case.raises is None else None
            verdict, why = judge_case(ex, case, expected, call_in_process(func, case, i))
            records.append(CaseRecord(i, case.label, bool(case.visible), verdict, why))
        cell = judge_cell(CellEvidence(ex, 1.0, records))
        failed = [f"{r.label}: {r.reason}" for r in records if r.reason][:3]
        assert cell.status is Status.OK and cell.score == pytest.approx(1.0, abs=1e-12), \
            f"seed {seed}: {cell.message} {failed}"
