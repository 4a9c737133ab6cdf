"""The grading service's policy stated in each release notebook's first cell, from the course's
``grading_service.json`` at release time (the defaults of docs/grading-service.md without one).

Runs on one real source notebook (the smallest) in its own course root, as ``test_course.py``.
"""

from __future__ import annotations

import json

import pytest
from nbtools import read

from autograder.course import prepare_course, source_notebooks
from autograder.release import check_release

NOTEBOOKS = source_notebooks()
pytestmark = [pytest.mark.skipif(not NOTEBOOKS, reason="no notebooks/q*.ipynb yet"),
              pytest.mark.timeout(300)]
MARK = "Graded attempts and feedback while the assignment is open."


def first_markdown(path) -> str:
    return next(c.source for c in read(path).cells if c.cell_type == "markdown")


def test_the_first_cell_states_the_policy_in_force(tmp_path):
    src = min(NOTEBOOKS, key=lambda p: p.stat().st_size)
    source_first = first_markdown(src)
    course = prepare_course(tmp_path / "c", notebooks=[src])
    released = course.release_dir / src.name

    # no policy file: the defaults docs/grading-service.md states (5 a day, Europe/London,
    # the last graded attempt counts, no due date)
    first = first_markdown(released)
    assert first.startswith(source_first.rstrip())          # the question's own text kept
    assert first.count(MARK) == 1
    assert "**5 graded attempts per notebook per day**" in first
    assert "Europe/London" in first and '"4 of 5 graded attempts left today"' in first
    assert "your last graded attempt of each notebook, even one after the due date" in first
    assert "No due date is set yet" in first
    others = [c.source for c in read(released).cells][1:]

    # the instructor changes the policy; the sources are unchanged: released again, stated once
    (course.root / "grading_service.json").write_text(json.dumps(
        {"attempts": 3, "timezone": "America/New_York", "counts": "best",
         "due": "2026-03-13T17:00:00+01:00"}))
    prepare_course(tmp_path / "c", notebooks=[src])
    first = first_markdown(released)
    assert first.startswith(source_first.rstrip()) and first.count(MARK) == 1
    assert "**3 graded attempts per notebook per day**" in first and "5 graded" not in first
    assert "America/New_York" in first and '"2 of 3 graded attempts left today"' in first
    assert "your best graded attempt" in first
    assert "2026-03-13 16:00 UTC" in first          # 17:00 at +01:00, stated in UTC
    assert "No due date" not in first
    assert [c.source for c in read(released).cells][1:] == others
    check_release([released])                       # still fit for students, still runnable

    # one attempt a day reads as one
    (course.root / "grading_service.json").write_text(json.dumps({"attempts": 1}))
    prepare_course(tmp_path / "c", notebooks=[src])
    assert "**1 graded attempt per notebook per day**" in first_markdown(released)


def test_a_bad_policy_file_stops_the_release_naming_it(tmp_path):
    src = min(NOTEBOOKS, key=lambda p: p.stat().st_size)
    (tmp_path / "c").mkdir()
    (tmp_path / "c" / "grading_service.json").write_text(json.dumps({"attempts": 0}))
    with pytest.raises(ValueError, match="grading_service.json.*attempts"):
        prepare_course(tmp_path / "c", notebooks=[src])
