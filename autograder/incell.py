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
Both judge each case with :func:`autograder.judging.judge_case` and the cell with
:func:`autograder.judging.judge_cell`, so a case passes here exactly when it passes there (the
kernel sees no cell source, so the rules about a cell's source do not apply here).
"""

from __future__ import annotations

import sys

import numpy as np

from course_lib.variants import student_id

from .exercises import get
from .judging import CellEvidence, call_in_process, judge_case, judge_cell, judge_item
from .model import CaseOutcome, CaseRecord, OutcomeKind, Status, Verdict

#: The seed of the in-kernel hidden cases (the batch grader draws its own from the course secret).
INCELL_SEED = 4_2006


def _judged(name: str, func, seed: int) -> list[tuple[object, CaseRecord]]:
    """Every case of exercise ``name`` called on ``func`` in this kernel, with its judged record."""
    ex = get(name)
    out = []
    for i, case in enumerate(ex.draw_cases(np.random.default_rng(seed))):
        expected = ex.expected(case) if case.raises is None else None
        verdict, reason = judge_case(ex, case, expected, call_in_process(func, case, i))
        out.append((case, CaseRecord(i, case.label, bool(case.visible), verdict, reason,
                                     raises=case.raises.__name__ if case.raises else "")))
    return out


def run_cases(name: str, func, seed: int = INCELL_SEED) -> list[tuple[object, str | None]]:
    """``[(case, reason_or_None), ...]`` for every case of exercise ``name`` against ``func``."""
    return [(case, None if r.verdict is Verdict.PASS else r.reason)
            for case, r in _judged(name, func, seed)]


def check(name: str, func_or_value, student: str | None = None) -> None:
    """Assert that a graded function (or a choice or number item) passes all its cases.

    The cell's verdict is :func:`autograder.judging.judge_cell`'s, as in ``grade``. Choices and
    number items are judged for ``student`` (default: the working student,
    :func:`course_lib.variants.student_id`, with the notebook's ``STUDENT_ID`` as typed id)."""
    ex = get(name)
    if ex.kind.is_item:
        if student is None:
            student = student_id(getattr(sys.modules.get("__main__"), "STUDENT_ID", "") or "")
        outcome = CaseOutcome(0, OutcomeKind.RETURNED, value=func_or_value)
        verdict, why = judge_item(ex, outcome, student)
        record = CaseRecord(0, "your answer", True, verdict, why)
        cell = judge_cell(CellEvidence(ex, 1.0, [record], answer=outcome, student=student))
        assert cell.status is Status.OK, f"{name}: {why}"
        return
    records = [r for _, r in _judged(name, func_or_value, INCELL_SEED)]
    cell = judge_cell(CellEvidence(ex, 1.0, records))
    if cell.status is not Status.OK:
        failures = [r for r in records if r.verdict is not Verdict.PASS]
        lines = [f"{name}: {len(failures)} case(s) failed"]
        lines += [f"  - {r.label or 'case'}: {r.reason}" for r in failures[:5]]
        raise AssertionError("\n".join(lines))
