"""A submission put in ``submitted/`` by hand, without ``timestamp.txt``: ``grade`` grades it,
warns naming the student, and the gradebook keeps no hand-in time, so ``export``'s late rules
never count it late (docs/instructors.md, step 3); a collected one beside it keeps its time and
is counted late."""

from __future__ import annotations

import datetime as dt

import pytest
from gradingtools import model_version, run_grade, write_nb

from autograder.course import ASSIGNMENT

pytestmark = pytest.mark.timeout(900)


def test_a_hand_placed_submission_is_graded_with_a_warning_and_never_late(tmp_path, sources):
    from autograder.outputs.export import late_penalty, read_gradebook

    q1 = next(s for s in sources if s.name == "q1_imaging")

    submitted = tmp_path / "course" / "submitted"
    for student in ("hp123", "tl456"):
        write_nb(submitted / student / ASSIGNMENT / f"{q1.name}.ipynb", model_version(q1))
    # collected by nbgrader: a day and a minute after the due date below
    (submitted / "tl456" / ASSIGNMENT / "timestamp.txt").write_text(
        "2026-03-14 16:01:00.000000 UTC")
    proc = run_grade(submitted, tmp_path / "grading")     # no course root: the gradebook in OUT

    warnings = [line for line in proc.stderr.splitlines() if "timestamp.txt" in line]
    assert len(warnings) == 1, proc.stderr[-3000:]
    assert "hp123's submission" in warnings[0] and "never counts it late" in warnings[0]
    assert "tl456" not in proc.stderr.replace(str(tmp_path), "")

    rows = {r.student: r for r in read_gradebook(
        f"sqlite:///{tmp_path / 'grading' / 'gradebook.db'}", [q1.name])}
    assert rows["hp123"].timestamp is None
    assert rows["tl456"].timestamp.replace(tzinfo=None) == dt.datetime(2026, 3, 14, 16, 1)
    # both graded alike (same model answers), and both earned marks to lose
    assert rows["hp123"].scores[q1.name] > 0
    due = dt.datetime(2026, 3, 13, 16, 0)
    # 10 % of 20 marks per started day late: tl456 is two started days late (24 h 1 min)
    assert late_penalty(rows["tl456"], 20.0, 10.0, due) == pytest.approx(
        min(rows["tl456"].scores[q1.name], 4.0))
    assert late_penalty(rows["hp123"], 20.0, 10.0, due) == 0.0
