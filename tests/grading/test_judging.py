"""Judging and planning on their own (no sandbox): verdicts come from structured fields, the
source of a graded cell says whether it was answered, seeds follow the solution."""

from __future__ import annotations

import numpy as np
import pytest

from autograder.exercises.base import Case, Exercise, close, wrong_shape
from autograder.grade.cases import (CAP_FLOOR, case_seed, name_cap, notebook_digest, result_cap,
                                    solution_digest)
from autograder.grade.planning import answer_hint, reference_import
from autograder.judging import judge_case, judge_choice, summarise, unanswered_or_broken
from autograder.model import (AnswerHint, AnswerShape, CaseOutcome, CaseRecord, CellKind, OutcomeKind,
                              Status, Verdict)

CASE = Case(args=(1.0,), label="one")


def _ex(compare):
    return Exercise(name="f", notebook="qx", reference=lambda x: x, compare=compare)


def _returned(value):
    return CaseOutcome(0, OutcomeKind.RETURNED, value=value)


def test_a_shape_mismatch_is_classified_by_its_kind_not_its_words():
    verdict, _ = judge_case(_ex(close()), CASE, np.zeros(3), _returned(np.zeros(2)))
    assert verdict is Verdict.WRONG_SHAPE
    # a plain string that merely says "wrong shape" is a wrong value: words are not parsed
    verdict, why = judge_case(_ex(lambda e, r: "wrong shape, says the text"), CASE, 1.0,
                              _returned(2.0))
    assert verdict is Verdict.WRONG_VALUE and why == "wrong shape, says the text"
    verdict, _ = judge_case(_ex(lambda e, r: wrong_shape("no")), CASE, 1.0, _returned(2.0))
    assert verdict is Verdict.WRONG_SHAPE


def test_the_released_stub_is_unanswered_by_its_exception_class():
    raised = CaseOutcome(0, OutcomeKind.RAISED, error_type="NotImplementedError",
                         error_mro=("builtins.NotImplementedError", "builtins.RuntimeError",
                                    "builtins.Exception"))
    assert judge_case(_ex(close()), CASE, 1.0, raised)[0] is Verdict.UNANSWERED
    bad = Case(args=(-1.0,), raises=ValueError)
    ok = CaseOutcome(0, OutcomeKind.RAISED, error_type="ValueError",
                     error_mro=("builtins.ValueError", "builtins.Exception"))
    assert judge_case(_ex(close()), bad, None, ok)[0] is Verdict.PASS


@pytest.mark.parametrize("value,verdict", [
    (None, Verdict.UNANSWERED), ("", Verdict.UNANSWERED), (" , ", Verdict.UNANSWERED),
    (3, Verdict.WRONG_SHAPE), (("a",), Verdict.WRONG_SHAPE), ("(b)", Verdict.WRONG_SHAPE),
    ("a", Verdict.WRONG_VALUE), (" B ", Verdict.PASS)])
def test_choices_are_judged_with_the_course_format(value, verdict):
    ex = Exercise(name="q", notebook="qx", kind="choice", answer="b", options=tuple("abcd"))
    assert judge_choice(ex, _returned(value))[0] is verdict


def test_score_is_points_times_the_fraction_passed():
    records = [CaseRecord(i, "", True, v) for i, v in
               enumerate([Verdict.PASS, Verdict.PASS, Verdict.WRONG_VALUE, Verdict.TIMEOUT])]
    score, status, _ = summarise(records, 2.0)
    assert score == pytest.approx(1.0) and status is Status.TIMEOUT


def test_cases_left_unrun_after_timeouts_read_as_not_run():
    """Three cases in a row timed out, so the sandbox ran no more (isolation/inside/supervisor.py): the
    rest read "not run" with the sandbox's reason, not "raised an error"."""
    why = "not run: the 3 cases before it timed out"
    verdict, reason = judge_case(_ex(close()), CASE, 1.0,
                                 CaseOutcome(3, OutcomeKind.NOT_RUN, message=why))
    assert verdict is Verdict.NOT_RUN and reason == why
    records = [CaseRecord(i, "", False, v, reason=r) for i, (v, r) in enumerate(
        [(Verdict.TIMEOUT, "took longer than 2 s")] * 3 + [(Verdict.NOT_RUN, why)] * 2)]
    score, status, message = summarise(records, 2.0)
    assert score == 0 and status is Status.TIMEOUT
    assert "3 timed out, 2 not run" in message and "error" not in message


@pytest.mark.parametrize("code,shape", [
    ("def f(x):\n    '''doc'''\n    # YOUR CODE HERE\n    raise NotImplementedError()\n",
     AnswerShape.UNTOUCHED),
    ("# YOUR CODE HERE\nraise NotImplementedError()\n", AnswerShape.UNTOUCHED),
    ("", AnswerShape.EMPTY), ("# later\n", AnswerShape.EMPTY),
    ("f = None\n", AnswerShape.NONE), ("f = 3\n", AnswerShape.NOT_A_FUNCTION),
    ("f = [1, 2]\n", AnswerShape.NOT_A_FUNCTION),
    ("def f(a, b):\n    return a\n", AnswerShape.WRONG_ARITY),
    ("def f(x, *, scale=1):\n    return x\n", AnswerShape.WRITTEN),
    ("f = lambda x: x\n", AnswerShape.WRITTEN)])
def test_answer_hints_read_the_source(code, shape):
    assert answer_hint(code, "f", CellKind.FUNCTION, [((1.0,), {})]).shape is shape


def test_no_answer_is_the_students_status_with_advice():
    for shape in (AnswerShape.UNTOUCHED, AnswerShape.EMPTY, AnswerShape.NONE):
        status, message = unanswered_or_broken("f", CellKind.FUNCTION, AnswerHint(shape), True)
        assert status is Status.UNANSWERED and "resubmit" in message
    status, message = unanswered_or_broken("f", CellKind.FUNCTION,
                                           AnswerHint(AnswerShape.NOT_A_FUNCTION, "a list"), True)
    assert status is Status.FAILED and "a list" in message
    assert unanswered_or_broken("f", CellKind.FUNCTION, AnswerHint(), True) is None


def test_reference_imports_are_found_but_data_tables_are_allowed():
    import ast

    assert reference_import(ast.parse("from course_lib.shading import _shade")) \
        == "course_lib.shading._shade"
    assert reference_import(ast.parse("def g():\n    import course_lib.splines as s\n"))
    assert not reference_import(ast.parse("from course_lib.marching_cubes import TRI_TABLE"))
    assert not reference_import(ast.parse("import numpy as np"))


def test_hidden_seed_follows_every_character_of_the_solution():
    """The sandbox's code can read its cells' text: a comment or a space could carry a lookup
    table, so they too draw new hidden cases."""
    a = solution_digest("def f(x):\n    return x  # one\n")
    assert a == solution_digest("def f(x):\n    return x  # one\n")
    assert a != solution_digest("def f(x):\n    return x  # two\n")
    assert a != solution_digest("def f(x):\n    return x   # one\n")
    deep = "_pad = " + "+".join(["1"] * 3000) + "\n"
    assert solution_digest(deep + "_T = 'A B'\n") != solution_digest(deep + "_T = 'A  B'\n")
    assert a != solution_digest("def f(x):\n    return -x\n")
    assert case_seed(b"s", "kim", "f", a) != case_seed(b"s", "kim", "f", solution_digest("x=1"))
    assert case_seed(b"s", "kim", "f", a) == case_seed(b"s", "kim", "f", a)


def test_hidden_seed_follows_every_solution_cell_of_the_notebook():
    f, helper = "def f(x):\n    return _impl(x)\n", "def _impl(x):\n    return x\n"
    base = notebook_digest([helper, f])
    assert base != notebook_digest([helper + "# a comment\n", f])       # comments count too
    changed = notebook_digest([helper.replace("return x", "return -x"), f])  # ANOTHER cell
    assert case_seed(b"s", "kim", "f", base) != case_seed(b"s", "kim", "f", changed)
    assert base != notebook_digest([helper, f, "table = 1\n"])           # an added cell


def test_one_result_cap_per_name_reveals_no_case():
    # the cap is a power of two, at least the floor, and the same whatever the smaller cases
    caps = [result_cap(None), result_cap(np.zeros(10_000))]
    cap = name_cap(caps)
    assert cap == name_cap([caps[1]]) == name_cap([caps[1], result_cap(np.zeros(3))])
    assert cap >= max(caps) and cap & (cap - 1) == 0
    assert name_cap([result_cap(None)]) == name_cap([result_cap(1.0)]) == CAP_FLOOR


def test_result_cap_follows_the_expected_answer():
    small, big = result_cap(1.0), result_cap(np.zeros(10_000))
    assert big - small >= 4 * 80_000 and small >= 16 * 1024


def test_a_wrong_number_item_never_says_how_far_off():
    """The size of the error would give a one-number answer away."""
    from autograder.exercises import REGISTRY
    from autograder.judging import judge_value
    from autograder.model import CaseOutcome, OutcomeKind, Verdict

    ex = REGISTRY["q2c_your_length"]
    right = ex.value_for("ab123")
    for received in (right * 1.2, [right * 1.2], (right + 7.0,)):
        verdict, why = judge_value(ex, CaseOutcome(0, OutcomeKind.RETURNED, value=received),
                                   "ab123")
        assert verdict in (Verdict.WRONG_VALUE, Verdict.WRONG_SHAPE)
        assert str(round(right, 1)) not in why and "error" not in why, why
    ok, _ = judge_value(ex, CaseOutcome(0, OutcomeKind.RETURNED, value=right * 1.004), "ab123")
    assert ok is Verdict.PASS                  # within the stated 0.5 %
    off, _ = judge_value(ex, CaseOutcome(0, OutcomeKind.RETURNED, value=right * 1.01), "ab123")
    assert off is Verdict.WRONG_VALUE


def test_a_case_number_item_is_exact():
    """0.5 % of 200 is a whole case number; a case number must match exactly."""
    from autograder.exercises import REGISTRY
    from autograder.judging import judge_value
    from autograder.model import CaseOutcome, OutcomeKind, Verdict

    ex = REGISTRY["q3a_your_case"]
    for sid in ("ab123", "cd456", "st0007"):
        right = ex.value_for(sid)
        judge = lambda v, s=sid: judge_value(ex, CaseOutcome(0, OutcomeKind.RETURNED, value=v), s)[0]  # noqa: E731
        assert judge(right) is Verdict.PASS and judge(float(right)) is Verdict.PASS
        assert judge(right + 1) is Verdict.WRONG_VALUE and judge(right - 1) is Verdict.WRONG_VALUE
        assert judge(right + 0.5) is Verdict.WRONG_VALUE
        assert judge(str(right)) is Verdict.WRONG_SHAPE and judge([right]) is Verdict.WRONG_SHAPE


def test_hidden_seed_follows_where_the_solution_cells_stand(tmp_path):
    """A cell's label (its graded name and its place in the notebook) reaches the sandbox, so it
    seeds the hidden cases too: the same code with empty cells moved about, which could carry
    answers into the sandbox in the labels, draws new cases."""
    import json

    from autograder.grade.cases import job_digest
    from autograder.grade.planning import plan_cells
    from autograder.grade.reading import read_submission
    from gradingtools import course_sources, model_version, planned_cells

    src = next(s for s in course_sources() if s.name == "q3_marching_cubes")
    model = model_version(src)
    moved = json.loads(json.dumps(model))
    first = next(i for i, c in enumerate(moved["cells"])
                 if (c.get("metadata", {}).get("nbgrader") or {}).get("solution"))
    moved["cells"][first:first] = [{"cell_type": "raw", "metadata": {}, "source": ""}] * 3

    def planned(nb, folder):
        folder.mkdir()
        (folder / f"{src.name}.ipynb").write_text(json.dumps(nb), encoding="utf-8")
        return plan_cells(src, read_submission(folder, "kim", src.name)).cells

    cells, cells_moved = planned(model, tmp_path / "a"), planned(moved, tmp_path / "b")
    assert [code for _, code in cells] == [code for _, code in cells_moved]   # same code
    assert job_digest(cells) != job_digest(cells_moved)
    assert job_digest(cells) == job_digest(planned_cells(model))   # the bank seeds as the grader


def test_a_notebook_of_countless_empty_cells_is_unreadable_at_once(tmp_path):
    """700,000 empty cells are 22 MB on disk and no code, yet planning them held the whole batch
    for minutes and a gigabyte: such a notebook is refused as it is read."""
    import json

    from autograder.grade.reading import MAX_CELLS, read_submission
    from autograder.model import Status

    cells = [{"cell_type": "code", "metadata": {}, "source": "", "outputs": [],
              "execution_count": None}] * (MAX_CELLS + 1)
    nb = {"nbformat": 4, "nbformat_minor": 5, "metadata": {}, "cells": cells}
    (tmp_path / "q5_phong.ipynb").write_text(json.dumps(nb), encoding="utf-8")
    sub = read_submission(tmp_path, "kim", "q5_phong")
    assert sub.status is Status.UNREADABLE
    assert f"{MAX_CELLS + 1:,} cells" in sub.message and "delete the added cells" in sub.message
    nb["cells"] = cells[:MAX_CELLS]
    (tmp_path / "q5_phong.ipynb").write_text(json.dumps(nb), encoding="utf-8")
    assert read_submission(tmp_path, "kim", "q5_phong").status is not Status.UNREADABLE


# --------------------------------------------------------------------------------------------
# bad-input cases count in proportion to the hidden ordinary cases passed


def _rec(i, verdict, raises=""):
    return CaseRecord(i, "", True, verdict, "why", raises=raises)


def test_raising_on_every_input_scores_nothing():
    # 3 ordinary cases all wrong (they raised), 2 bad-input cases right: 0 of 5 points, not 2
    records = [_rec(0, Verdict.ERROR), _rec(1, Verdict.ERROR), _rec(2, Verdict.ERROR),
               _rec(3, Verdict.PASS, "ValueError"), _rec(4, Verdict.PASS, "ValueError")]
    score, status, message = summarise(records, 5.0)
    assert score == 0.0 and status is Status.ERROR
    assert "in proportion" in message


def test_visible_and_bad_input_cases_count_in_proportion_to_the_hidden_ordinary_cases_passed():
    # 3 ordinary cases (1 visible passed; hidden: 1 of 2 passed), 2 bad-input cases passed:
    # the visible and bad-input cases count half, so 1 + (1 + 2) x 1/2 = 2.5 of 5 cases
    records = [_rec(0, Verdict.PASS), _rec(1, Verdict.PASS), _rec(2, Verdict.WRONG_VALUE),
               _rec(3, Verdict.PASS, "ValueError"), _rec(4, Verdict.PASS, "ValueError")]
    for r in records[1:]:
        r.visible = False
    score, status, message = summarise(records, 5.0)
    assert score == pytest.approx(2.5, abs=1e-9)
    assert "visible and bad-input cases" in message and "in proportion" in message


def test_visible_cases_from_a_table_earn_nothing():
    """A red team answered the visible cases (shown on the page) from a table and raised on
    everything else (issue 33: by position): with no hidden ordinary case right, neither the
    visible nor the bad-input cases count."""
    records = [_rec(0, Verdict.PASS), _rec(1, Verdict.ERROR), _rec(2, Verdict.ERROR),
               _rec(3, Verdict.PASS, "ValueError"), _rec(4, Verdict.PASS, "ValueError")]
    for r in records[1:]:
        r.visible = False
    assert summarise(records, 5.0)[0] == 0.0


def test_without_hidden_cases_the_visible_ones_count_and_set_the_share():
    # a student's own check: 2 of 3 visible ordinary cases right, 1 bad-input case right:
    # 2 + 1 x 2/3 of 4 cases
    records = [_rec(0, Verdict.PASS), _rec(1, Verdict.PASS), _rec(2, Verdict.WRONG_VALUE),
               _rec(3, Verdict.PASS, "ValueError")]
    assert summarise(records, 4.0)[0] == pytest.approx(2 + 2 / 3, abs=1e-6)


def test_all_hidden_ordinary_cases_passed_keep_every_bad_input_case():
    records = [_rec(0, Verdict.WRONG_VALUE), _rec(1, Verdict.PASS),
               _rec(2, Verdict.PASS, "ValueError")]
    for r in records[1:]:
        r.visible = False
    assert summarise(records, 3.0)[0] == pytest.approx(2.0, abs=1e-9)


def test_a_function_whose_cases_all_must_raise_keeps_them():
    records = [_rec(0, Verdict.PASS, "ValueError"), _rec(1, Verdict.ERROR, "ValueError")]
    assert summarise(records, 2.0)[0] == pytest.approx(1.0, abs=1e-9)


def test_incell_check_and_the_batch_apply_the_same_rule():
    """``incell.check`` (the student's own check) fails a function that always raises
    ValueError, and the records it judges carry which cases must raise."""
    from autograder.incell import _judged, check

    def always_raise(*args, **kwargs):
        raise ValueError("bad input")

    records = [r for _, r in _judged("normalize", always_raise, 7)]
    assert any(r.raises == "ValueError" and r.verdict is Verdict.PASS for r in records)
    assert summarise(records, 1.0)[0] == 0.0
    with pytest.raises(AssertionError):
        check("normalize", always_raise)


# --------------------------------------------------------------------------------------------
# a returned value's form


@pytest.mark.parametrize("expected,received,same", [
    (np.zeros(3), np.ones(3), True), (np.zeros(3), np.ones((1, 3)), False),
    (np.zeros(3), "text", False), (np.zeros(3), [1.0, 2.0, 3.0], False),
    (1.5, np.float64(2.0), True), (1.5, np.array(2.0), True), (1.5, 2, True),
    (True, False, True), (True, 1.0, False), (None, None, True), (None, "x", False),
    ((np.zeros((2, 3)), np.zeros((1, 3), int)), (np.ones((2, 3)), np.ones((1, 3))), True),
    ((np.zeros((2, 3)), np.zeros((1, 3))), [np.ones((2, 3)), np.ones((1, 3))], True),
    ((np.zeros((2, 3)), np.zeros((1, 3))), (np.ones((2, 3)),), False)])
def test_same_form_is_type_and_shape(expected, received, same):
    from autograder.judging import same_form

    assert same_form(expected, received) is same


def test_a_returned_text_is_described_by_its_form_never_its_content():
    secret = "the hidden inputs: 0.123, 0.456" * 10
    verdict, why = judge_case(_ex(close()), CASE, np.zeros(3), _returned(secret))
    assert verdict is Verdict.WRONG_SHAPE
    assert why == "returned a str, expected an array of shape (3,)"
    verdict, why = judge_case(_ex(close()), CASE, True, _returned("the hidden inputs"))
    assert "hidden" not in why and why == "returned a str, expected a bool"
