"""Per-student variants through the real grader, in its sandbox (issue 11).

Two students, alice and bob. Each scores full marks on their own; an honest by-hand student who
types literal answers for their own numbers scores full marks too; bob handing in alice's
literal answers loses exactly the items whose right answer differs between the two (decided
here with NumPy on the two students' reference values, not by the grader), and his feedback
says whose numbers they fit; a re-grade gives the same CSV.
"""

from __future__ import annotations

import numpy as np
import pytest

from autograder.exercises import REGISTRY
from gradingtools import (cell_index, expect_full_marks, model_version, read_grades, run_grade,
                          write_nb)

pytestmark = [pytest.mark.xdist_group("grading"), pytest.mark.slow]

STUDENTS = ("alice", "bob")


def _items(src):
    return [name for name, _, _ in src.graded
            if name in REGISTRY and REGISTRY[name].kind in ("choice", "value")]


def _literal(value) -> str:
    """How a student types an answer worked out by hand."""
    if isinstance(value, np.ndarray):
        return repr(value.tolist())
    return repr(value)


def literal_version(src, student: str) -> dict:
    """The model notebook with every choice and number item typed as literals for ``student``,
    and ``student`` typed as the id (what a careful student hands in)."""
    nb = model_version(src)
    for name in _items(src):
        ex = REGISTRY[name]
        answer = ex.key_for(student) if ex.kind == "choice" else ex.value_for(student)
        nb["cells"][cell_index(nb, name)]["source"] = f"{name} = {_literal(answer)}\n"
    for cell in nb["cells"]:
        if cell["cell_type"] == "code" and 'STUDENT_ID = ""' in "".join(cell["source"]):
            cell["source"] = "".join(cell["source"]).replace('STUDENT_ID = ""',
                                                             f'STUDENT_ID = "{student}"')
    return nb


def _differs(name: str, one: str = "alice", other: str = "bob") -> bool:
    """Whether ``one``'s right answer is wrong for ``other`` (NumPy on the two reference
    answers)."""
    ex = REGISTRY[name]
    if ex.kind == "choice":
        return ex.key_for(one) != ex.key_for(other)
    a, b = (np.asarray(ex.value_for(s), dtype=float) for s in (one, other))
    return a.shape != b.shape or not np.allclose(a, b, rtol=5e-3, atol=1e-3)


@pytest.fixture(scope="module")
def graded(tmp_path_factory, sources):
    root = tmp_path_factory.mktemp("variants")
    sub = root / "submitted"
    for src in sources:
        for student in STUDENTS:            # everyone's own model notebook
            write_nb(sub / student / "tripos2006" / f"{src.name}.ipynb", model_version(src))
        write_nb(sub / "carol" / "tripos2006" / f"{src.name}.ipynb", literal_version(src, "carol"))
        write_nb(sub / "bob2" / "tripos2006" / f"{src.name}.ipynb", literal_version(src, "alice"))
    out = root / "out"
    run_grade(sub, out)
    first = (out / "grades.csv").read_text()
    run_grade(sub, out)
    return {"rows": read_grades(out), "first": first, "again": (out / "grades.csv").read_text(),
            "out": out}


def _score(rows, student, src, tid):
    row = rows[(student, src.name, tid)]
    return (None if row["score"] == "" else float(row["score"])), row["status"], row["message"]


@pytest.mark.parametrize("student", ["alice", "bob", "carol"])
def test_each_student_scores_full_marks_on_their_own_numbers(graded, sources, student):
    wrong = {}
    for src in sources:
        for tid, (points, status) in expect_full_marks(src).items():
            got = _score(graded["rows"], student, src, tid)
            if got[1] != status or (points is not None and abs(got[0] - points) > 1e-9):
                wrong[(src.name, tid)] = got
    assert not wrong


def test_the_two_students_see_different_numbers(sources):
    names = [n for src in sources for n in _items(src) if REGISTRY[n].kind == "value"]
    assert len(names) >= 6
    assert sum(_differs(n) for n in names) >= len(names) - 1


def test_handing_in_someone_elses_answers_loses_exactly_the_variant_items(graded, sources):
    lost, kept = [], []
    for src in sources:
        for name, tid, points in src.graded:
            score, status, message = _score(graded["rows"], "bob2", src, tid)
            should_lose = name in _items(src) and _differs(name, "alice", "bob2")
            if should_lose:
                assert score == 0 and status == "failed", (name, score, status, message)
                assert "fits the" in message and "student alice" in message, message
                lost.append(name)
            else:
                assert score == pytest.approx(points) and status == "ok", (name, status, message)
                kept.append(name)
    assert len(lost) >= 10 and len(kept) >= 20


def test_regrading_is_reproducible(graded):
    assert graded["first"] == graded["again"]
