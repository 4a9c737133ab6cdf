"""Exported marks round halves up (issue 24 §4): the oracle is decimal arithmetic on the
marks' exact decimal text, computed here independently of the exporter."""

from __future__ import annotations

import csv
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


def test_the_csv_files_carry_marks_rounded_half_up(tmp_path):
    maxima = {"q1_imaging": 20.0, "q2_nuclear": 20.0}
    rows = [_student("s1", {"q1_imaging": 13.25, "q2_nuclear": 11.75})]
    export.write_all(rows, maxima, tmp_path, decimals=1)
    with open(tmp_path / "canvas.csv", newline="", encoding="utf-8") as f:
        canvas = list(csv.DictReader(f))
    assert canvas[0]["q1_imaging (20)"] == "13.3"
    assert canvas[0]["q2_nuclear (20)"] == "11.8"
    assert canvas[0]["tripos2006 total (40)"] == "25"
