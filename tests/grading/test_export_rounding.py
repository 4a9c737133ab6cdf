"""Exported marks round halves up (issue 24 §4): the oracle is decimal arithmetic on the
marks' exact decimal text, computed here independently of the exporter."""

from __future__ import annotations

import csv
import datetime as dt
import re
from decimal import ROUND_HALF_UP, Decimal

import pytest

from autograder.outputs import export


@pytest.mark.parametrize("mark, decimals, expected", [
    (13.25, 1, 13.3), (11.75, 1, 11.8), (12.75, 1, 12.8), (0.25, 1, 0.3), (0.125, 2, 0.13),
    (2.5, 0, 3.0), (3.5, 0, 4.0), (-0.25, 1, -0.3), (13.24, 1, 13.2), (0.0, 1, 0.0),
    (4.5 + 8.75, 1, 13.3),          # a sum of quarter marks, exactly 13.25
    (2.675, 2, 2.68),               # stored as 2.67499999...: Python's round gives 2.67
])
def test_round_half_up_on_marks(mark, decimals, expected):
    assert export.round_half_up(mark, decimals) == pytest.approx(expected, abs=1e-12)


def test_every_quarter_mark_rounds_as_decimal_arithmetic_says():
    for k in range(0, 481):            # 0, 0.25, ..., 120: every quarter mark of the paper
        mark = k / 4
        oracle = float(Decimal(str(mark)).quantize(Decimal("0.1"), rounding=ROUND_HALF_UP))
        assert export.round_half_up(mark, 1) == oracle, mark


@pytest.mark.parametrize("bad", [float("nan"), float("inf")])
def test_a_mark_that_is_not_a_number_is_refused(bad):
    with pytest.raises(ValueError, match="finite"):
        export.round_half_up(bad, 1)


def test_negative_decimals_are_refused():
    with pytest.raises(ValueError, match="decimals"):
        export.round_half_up(1.0, -1)


def _student(name: str, scores: dict[str, float]) -> export.StudentGrades:
    return export.StudentGrades(student=name, scores=scores)


def _canvas(path):
    with open(path / "canvas.csv", newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1], [dict(zip(rows[0], r)) for r in rows[2:]]


def test_the_csv_files_carry_marks_rounded_half_up(tmp_path):
    maxima = {"q1_imaging": 20.0, "q2_nuclear": 20.0}
    rows = [_student("s1", {"q1_imaging": 13.25, "q2_nuclear": 11.75})]
    export.write_all(rows, maxima, tmp_path, decimals=1, canvas_questions=True)
    _, _, canvas = _canvas(tmp_path)
    assert canvas[0]["tripos2006 q1_imaging"] == "13.3"
    assert canvas[0]["tripos2006 q2_nuclear"] == "11.8"
    with open(tmp_path / "moodle.csv", newline="", encoding="utf-8") as f:
        moodle = list(csv.DictReader(f))
    assert moodle[0]["tripos2006 total"] == "25"


def test_canvas_headers_carry_no_bracketed_number_and_the_default_is_the_total_alone(tmp_path):
    """Canvas reads ``Name (123)`` as assignment 123: the maxima go in the Points Possible row,
    and importing every column of the default file imports the total once."""
    maxima = {"q1_imaging": 20.0, "q2_nuclear": 20.0}
    rows = [_student("s1", {"q1_imaging": 13.25, "q2_nuclear": 11.75})]
    export.write_all(rows, maxima, tmp_path, decimals=1)
    head, points, canvas = _canvas(tmp_path)
    assert head == ["Student", "ID", "SIS User ID", "SIS Login ID", "Section", "tripos2006"]
    assert not any(re.search(r"\(\d+\)\s*$", h) for h in head)
    assert points[0].strip() == "Points Possible" and points[-1] == "40"
    assert canvas[0]["tripos2006"] == "25" and canvas[0]["SIS User ID"] == "s1"


def test_canvas_questions_and_the_late_penalty_add_up_to_the_total(tmp_path):
    maxima = {"q1_imaging": 20.0, "q2_nuclear": 20.0}
    due = dt.datetime(2026, 12, 4, 16, 0)
    late = export.StudentGrades("s1", scores={"q1_imaging": 13.25, "q2_nuclear": 11.75},
                                timestamp=due + dt.timedelta(hours=30))   # two started days
    on_time = export.StudentGrades("s2", scores={"q1_imaging": 20.0, "q2_nuclear": 0.0},
                                   timestamp=due - dt.timedelta(hours=1))
    export.write_all([late, on_time], maxima, tmp_path, decimals=1, late_per_day=5, due=due,
                     canvas_questions=True)
    head, points, canvas = _canvas(tmp_path)
    assert head[5:] == ["tripos2006 q1_imaging", "tripos2006 q2_nuclear",
                        "tripos2006 late penalty"]
    assert points[5:] == ["20", "20", "0"]
    assert "tripos2006" not in head                       # the total is left out: no double count
    assert canvas[0]["tripos2006 late penalty"] == "-4"     # 2 days x 5 % x 40 marks
    assert sum(float(canvas[0][h]) for h in head[5:]) == pytest.approx(25 - 4, abs=0.11)
    assert canvas[1]["tripos2006 late penalty"] == "0"


def test_a_late_penalty_without_any_due_date_is_said_loudly(capsys):
    from autograder import cli_export

    stamp = dt.datetime(2026, 12, 6, 9, 0)
    rows = [export.StudentGrades("s1", timestamp=stamp),              # no due date anywhere
            export.StudentGrades("s2", timestamp=stamp, due=stamp),   # the gradebook's
            export.StudentGrades("s3")]                               # never handed in
    assert export.without_due_date(rows, None) == ["s1"]
    assert export.without_due_date(rows, stamp) == []
    assert export.late_penalty(rows[0], 40.0, 10.0) == 0.0            # what goes unsaid
    cli_export.warn_without_due(export.without_due_date(rows, None), 10.0)
    err = capsys.readouterr().err
    assert err.startswith("WARNING: --late-per-day 10 but no due date")
    assert "from 1 students (s1)" in err
    assert "nbgrader db assignment add tripos2006 --duedate=" in err and "--due" in err
    cli_export.warn_without_due([], 10.0)
    assert capsys.readouterr().err == ""
