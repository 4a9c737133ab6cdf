"""Hidden tests run inside a notebook kernel: ``check("phong", phong)``.

The instructor's source notebooks end every graded test cell with::

    ### BEGIN HIDDEN TESTS
    from autograder.incell import check
    check("phong", phong)
    ### END HIDDEN TESTS

``check`` runs the exercise's registry cases against the student's function *in the same kernel*,
which is what plain ``nbgrader autograde`` does; it keeps the source notebooks honest (CI runs
them, so the notebook solution must agree with the reference on every case). The grades that
count come from ``python -m autograder grade``, which runs the same cases outside the kernel.
Both judge with :mod:`autograder.judging`, so a case passes here exactly when it passes there.
"""

from __future__ import annotations

import numpy as np

import sys

from course_lib.variants import student_id

from .exercises import get
from .judging import call_in_process, judge_case, judge_item
from .model import CaseOutcome, OutcomeKind, Verdict

#: The seed of the in-kernel hidden cases (the batch grader draws its own from the course secret).
INCELL_SEED = 4_2006


def run_cases(name: str, func, seed: int = INCELL_SEED) -> list[tuple[object, str | None]]:
    """``[(case, reason_or_None), ...]`` for every case of exercise ``name`` against ``func``."""
    ex = get(name)
    results = []
    for i, case in enumerate(ex.draw_cases(np.random.default_rng(seed))):
        expected = ex.expected(case) if case.raises is None else None
        verdict, reason = judge_case(ex, case, expected, call_in_process(func, case, i))
        results.append((case, None if verdict is Verdict.PASS else reason))
    return results


def check(name: str, func_or_value, student: str | None = None) -> None:
    """Assert that a graded function (or a choice or number item) passes all its cases.

    Choices and number items are judged for ``student`` (default: the working student,
    :func:`course_lib.variants.student_id`, with the notebook's ``STUDENT_ID`` as typed id)."""
    ex = get(name)
    if ex.kind in ("choice", "value"):
        if student is None:
            student = student_id(getattr(sys.modules.get("__main__"), "STUDENT_ID", "") or "")
        outcome = CaseOutcome(0, OutcomeKind.RETURNED, value=func_or_value)
        verdict, why = judge_item(ex, outcome, student)
        assert verdict is Verdict.PASS, f"{name}: {why}"
        return
    failures = [(c, why) for c, why in run_cases(name, func_or_value) if why is not None]
    if failures:
        lines = [f"{name}: {len(failures)} case(s) failed"]
        lines += [f"  - {c.label or 'case'}: {why}" for c, why in failures[:5]]
        raise AssertionError("\n".join(lines))
