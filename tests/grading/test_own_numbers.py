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
from gradingtools import (expect_full_marks, model_version, read_grades, run_grade,
                          typed_version, write_nb)

pytestmark = [pytest.mark.xdist_group("own_numbers"), pytest.mark.slow]

STUDENTS = ("alice", "bob")


def _items(src):
    return [name for name, _, _ in src.graded
            if name in REGISTRY and REGISTRY[name].kind in ("choice", "value")]


def literal_version(src, student: str) -> dict:
    """The model notebook with every choice and number item typed for ``student``, and
    ``student`` typed as the id (what a careful student hands in)."""
    nb = typed_version(model_version(src), student)
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
        # dave copies a notebook whose items are computed from `mine` (not typed)
        write_nb(sub / "dave" / "tripos2006" / f"{src.name}.ipynb", model_version(src),
                 type_answers=False)
    out = root / "out"
    run_grade(sub, out)
    first = (out / "grades.csv").read_text()
    run_grade(sub, out)
    graded = {"rows": read_grades(out), "first": first, "again": (out / "grades.csv").read_text(),
              "report": (out / "report.html").read_text(encoding="utf-8"), "out": out}
    revealed = root / "revealed"
    run_grade(sub, revealed, "--reveal-hidden")
    graded["revealed"] = read_grades(revealed)
    return graded


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
                # before the deadline the student is not told whose numbers they fit (a note
                # naming ids of the student's choice would be an oracle for the keys) ...
                assert "alice" not in message, message
                # ... after it, they are
                revealed = _score(graded["revealed"], "bob2", src, tid)[2]
                assert "fits the" in revealed and "student alice" in revealed, revealed
                lost.append(name)
            else:
                assert score == pytest.approx(points) and status == "ok", (name, status, message)
                kept.append(name)
    assert len(lost) >= 10 and len(kept) >= 20


def test_computed_item_answers_score_nothing(graded, sources):
    """A notebook whose choice and number cells compute from ``mine`` would hand every friend
    who copies it their own right answers: items count only when typed (issue 11)."""
    for src in sources:
        for name, tid, points in src.graded:
            score, status, message = _score(graded["rows"], "dave", src, tid)
            if name in _items(src):
                assert score == 0 and status == "failed" and "not typed" in message, (name, message)
            else:
                assert score == pytest.approx(points) and status == "ok", (name, message)


def test_the_report_lists_answers_that_fit_another_student(graded):
    section = graded["report"].split("<section class='own-numbers'>", 1)[1].split("</section>")[0]
    assert "<td>bob2</td>" in section and "<td>alice</td>" in section
    assert "<td>carol</td>" not in section       # typed literals for one's own numbers: fine


def test_made_up_ids_cost_nothing_and_tell_nothing(tmp_path, sources):
    """Red-team F1/F2: thousands of ids in saved outputs and typed lines; the note is bounded
    and, before the deadline, absent from the student's feedback."""
    import time

    from autograder.grade.whose import MAX_OTHERS, other_students
    from autograder.model import Submission

    cells = [{"cell_type": "code", "source": "\n".join(f'STUDENT_ID = "x{k}"' for k in range(2000)),
              "raw": {"outputs": [{"output_type": "stream", "name": "stdout",
                                   "text": "".join(f"Your numbers (student y{k})\n"
                                                   for k in range(50_000))}] * 50}}] * 200
    sub = Submission("bob", "q1_imaging", tmp_path / "q1.ipynb", cells=cells)
    t0 = time.perf_counter()
    found = other_students(sub)
    assert found == ["x0", "x1", "x2"][:MAX_OTHERS]
    assert time.perf_counter() - t0 < 5.0, "the scan is bounded"


def test_regrading_is_reproducible(graded):
    assert graded["first"] == graded["again"]
