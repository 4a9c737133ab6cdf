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
"""

from __future__ import annotations

import numpy as np

from course_lib.answers import ChoiceFormatError, choice_letters

from .exercises import NotPlainData, get, to_plain

#: The seed of the in-kernel hidden cases (the batch grader draws its own from the course secret).
INCELL_SEED = 4_2006


def run_cases(name: str, func, seed: int = INCELL_SEED) -> list[tuple[object, str | None]]:
    """``[(case, reason_or_None), ...]`` for every case of exercise ``name`` against ``func``."""
    ex = get(name)
    results = []
    for case in ex.draw_cases(np.random.default_rng(seed)):
        results.append((case, judge(ex, case, func)))
    return results


def judge(ex, case, func) -> str | None:
    """Call ``func`` on one case and compare with the reference: ``None`` when it passes."""
    try:
        got = func(*case.args, **case.kwargs)
    except Exception as exc:  # noqa: BLE001 - the student's code may raise anything
        if case.raises is not None and isinstance(exc, case.raises):
            return None
        return f"raised {type(exc).__name__}: {exc}"
    if case.raises is not None:
        return f"should raise {case.raises.__name__} but returned a value"
    try:
        got = to_plain(got)
    except NotPlainData as exc:
        return f"returned {exc}, not plain numbers"
    return ex.compare(ex.expected(case), got)


def check(name: str, func_or_value) -> None:
    """Assert that a graded function (or a multiple-choice answer) passes all its cases."""
    ex = get(name)
    if ex.kind == "choice":
        options = "".join(ex.options) if ex.options else "abcd"
        try:
            given = choice_letters(func_or_value, options, name=name)
        except ChoiceFormatError as exc:
            raise AssertionError(f"{name}: {exc}") from None
        assert given == choice_letters("".join(ex.answer), options), f"{name}: wrong answer"
        return
    failures = [(c, why) for c, why in run_cases(name, func_or_value) if why is not None]
    if failures:
        lines = [f"{name}: {len(failures)} case(s) failed"]
        lines += [f"  - {c.label or 'case'}: {why}" for c, why in failures[:5]]
        raise AssertionError("\n".join(lines))
