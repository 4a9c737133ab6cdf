"""``make test-fast`` runs what a change to an exercise can break (CONTRIBUTING.md, "Tests").

The Makefile's ``FAST_TESTS`` is read as make reads it; the modules named here are the checks an
exercise's change touches: its notebook's marks and the docs' counts (``test_facts``), the
honest bank in process, the contract, the registry's rules, the students'-copy name rules
(the wheel leaves every graded function out), the docs' links and ``new-exercise`` itself.
"""

from __future__ import annotations

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
MUST = ("tests/notebooks/test_facts.py", "tests/grading/test_honest_in_process.py",
        "tests/notebooks/test_contract.py", "tests/grading/test_cell_verdict.py",
        "tests/notebooks/test_student_wheel_guard.py", "tests/notebooks/test_items_ask_first.py",
        "tests/test_docs_links.py", "tests/notebooks/test_new_exercise.py",
        "tests/notebooks/test_execute_sources.py", "tests/test_lint.py")


def fast_tests() -> list[str]:
    text = (REPO / "Makefile").read_text(encoding="utf-8").replace("\\\n", " ")
    line = re.search(r"^FAST_TESTS\s*:=(.*)$", text, re.M)
    assert line, "no FAST_TESTS in the Makefile"
    return line[1].split()


def test_fast_tests_run_the_checks_an_exercise_change_touches():
    listed = fast_tests()
    assert [m for m in MUST if m not in listed] == []
    assert [p for p in listed if not (REPO / p).exists()] == []


def test_fast_tests_hold_no_slow_test():
    """A slow test in the inner loop costs every commit; ``make test`` runs it. The one
    exception is the reason for the loop: each source notebook run with its hidden tests."""
    files = [p for entry in fast_tests() for p in
             ((REPO / entry).rglob("test_*.py") if (REPO / entry).is_dir() else [REPO / entry])]
    slow = [str(p.relative_to(REPO)) for p in files
            if "pytest.mark.slow" in p.read_text(encoding="utf-8")
            and p.name != "test_execute_sources.py"]
    assert slow == []
