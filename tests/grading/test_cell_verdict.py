"""One verdict per cell, one vocabulary: ``judging.judge_cell``'s rules in their order, kinds as
one enum, rules that speak only ``Mismatch``, graded tests as named records.

The expected statuses and scores are the documented ones (the ``Status`` legend, the rule list
of ``judge_cell``'s docstring, the exercise registry's keys), never read back from the grader.
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from autograder.exercises import REGISTRY
from autograder.exercises.base import Exercise, Mismatch, close, wrong_value
from autograder.incell import check
from autograder.isolation.jobs import CHOICE, FUNCTION, KINDS, NameJob, wire_kind
from autograder.judging import CellEvidence, judge_cell
from autograder.model import (AnswerHint, AnswerShape, CaseOutcome, CaseRecord, CellKind,
                              GradedTest, OutcomeKind, SourceNotebook, Status, Verdict)

EXERCISES = Path(__file__).resolve().parents[2] / "autograder" / "exercises"


def _function():
    return Exercise(name="f", notebook="qx", reference=lambda x: x, compare=close())


def _choice():
    return Exercise(name="q", notebook="qx", kind=CellKind.CHOICE, answer="b",
                    options=tuple("abcd"))


def _records(*verdicts):
    return [CaseRecord(i, f"case {i}", True, v, reason="" if v is Verdict.PASS else "why")
            for i, v in enumerate(verdicts)]


# --------------------------------------------------------------------------------------------
# judge_cell: the first rule that applies decides


def test_a_function_that_imports_the_reference_scores_0_whatever_its_cases():
    ev = CellEvidence(_function(), 4.0, _records(Verdict.PASS, Verdict.PASS),
                      AnswerHint(reference="course_lib.shading.phong"))
    v = judge_cell(ev)
    assert (v.score, v.status) == (0.0, Status.REFERENCE_USED)
    assert "course_lib.shading.phong" in v.message


def test_cases_are_scored_by_the_fraction_passed_when_no_rule_overrides():
    v = judge_cell(CellEvidence(_function(), 4.0, _records(Verdict.PASS, Verdict.PASS,
                                                           Verdict.PASS, Verdict.WRONG_VALUE)))
    assert v.score == pytest.approx(3.0) and v.status is Status.FAILED
    v = judge_cell(CellEvidence(_function(), 4.0, _records(Verdict.PASS)))
    assert (v.score, v.status) == (4.0, Status.OK)


@pytest.mark.parametrize("shape,status", [(AnswerShape.UNTOUCHED, Status.UNANSWERED),
                                          (AnswerShape.EMPTY, Status.UNANSWERED),
                                          (AnswerShape.NONE, Status.UNANSWERED),
                                          (AnswerShape.WRONG_ARITY, Status.FAILED)])
def test_a_cell_that_earned_nothing_gets_the_advice_of_its_shape(shape, status):
    ev = CellEvidence(_function(), 2.0, _records(Verdict.ERROR, Verdict.ERROR),
                      AnswerHint(shape, "takes 2 arguments"))
    v = judge_cell(ev)
    assert (v.score, v.status) == (0.0, status) and "f" in v.message


def test_the_advice_never_hides_points_earned():
    """A cell of an odd shape that still passes some cases keeps its score and summary."""
    ev = CellEvidence(_function(), 2.0, _records(Verdict.PASS, Verdict.ERROR),
                      AnswerHint(AnswerShape.WRONG_ARITY, "takes 2 arguments"))
    v = judge_cell(ev)
    assert v.score == pytest.approx(1.0) and v.status is Status.ERROR
    assert "1 of 2 cases passed" in v.message


def test_cases_refused_by_the_sandbox_keep_their_status_over_the_advice():
    ev = CellEvidence(_function(), 2.0, _records(Verdict.REJECTED_CODE),
                      AnswerHint(AnswerShape.UNTOUCHED))
    assert judge_cell(ev).status is Status.REJECTED_CODE


def test_a_name_left_undefined_says_why_from_the_load_notes():
    ev = CellEvidence(_function(), 2.0, _records(Verdict.ERROR), defined=False,
                      load_notes=["cell 3: SyntaxError: invalid syntax"])
    v = judge_cell(ev)
    assert v.status is Status.ERROR and "SyntaxError" in v.message and "not defined" in v.message


def test_an_item_computed_instead_of_typed_scores_0_even_when_right():
    right = CaseRecord(0, "your answer", True, Verdict.PASS)
    v = judge_cell(CellEvidence(_choice(), 1.0, [right], typed=False))
    assert (v.score, v.status) == (0.0, Status.FAILED) and "not typed" in v.message
    # ... unless the name is not even defined: that advice comes first
    v = judge_cell(CellEvidence(_choice(), 1.0, [right], typed=False, defined=False))
    assert v.status is Status.ERROR and "not defined" in v.message
    # a typed right answer scores its points
    v = judge_cell(CellEvidence(_choice(), 1.0, [right]))
    assert (v.score, v.status, v.message) == (1.0, Status.OK, "correct")


def test_a_wrong_item_that_fits_another_student_is_noted_only_once_revealed():
    ex = _choice()
    other = next(s for s in (f"zz{i:03d}" for i in range(200)) if ex.key_for(s) != ex.key_for("me1"))
    answer = CaseOutcome(0, OutcomeKind.RETURNED, value=ex.key_for(other))
    wrong = CaseRecord(0, "your answer", True, Verdict.WRONG_VALUE, "wrong answer")
    hidden = judge_cell(CellEvidence(ex, 1.0, [wrong], answer=answer, others=(other,),
                                     student="me1"))
    assert hidden.fits_other == other and other not in hidden.message and not hidden.notes
    shown = judge_cell(CellEvidence(ex, 1.0, [wrong], answer=answer, others=(other,),
                                    student="me1", reveal=True, notes=["found by name"]))
    assert shown.message.startswith("wrong answer. Note: found by name; ")
    assert f"option letters of student {other}" in shown.message and len(shown.notes) == 2


# --------------------------------------------------------------------------------------------
# incell.check judges the cell as grade does


def test_check_fails_a_function_that_misses_a_case_and_passes_the_reference():
    ex = REGISTRY["normalize"]
    check("normalize", ex.reference)
    with pytest.raises(AssertionError, match=r"normalize: \d+ case\(s\) failed"):
        check("normalize", lambda v: np.asarray(v, dtype=float))


def test_check_judges_a_choice_for_the_given_student():
    ex = next(e for e in REGISTRY.values() if e.kind is CellKind.CHOICE and isinstance(e.answer, str))
    check(ex.name, ex.key_for("ab123"), student="ab123")
    wrong = next(x for x in "abcd"[:len(ex.options)] if x != ex.key_for("ab123"))
    with pytest.raises(AssertionError, match=f"^{ex.name}: "):
        check(ex.name, wrong, student="ab123")


# --------------------------------------------------------------------------------------------
# one spelling of kinds; one mismatch protocol; named graded tests


def test_every_exercise_kind_is_the_enum_and_strings_are_converted_or_refused():
    assert all(type(ex.kind) is CellKind for ex in REGISTRY.values())
    assert Exercise(name="x", notebook="qx", kind="value").kind is CellKind.VALUE
    with pytest.raises(ValueError, match="Exercise.kind"):
        Exercise(name="x", notebook="qx", kind="essay")


def test_the_wire_kinds_are_the_enums_values():
    assert (FUNCTION, CHOICE) == (CellKind.FUNCTION.value, CellKind.CHOICE.value)
    assert KINDS == (FUNCTION, CHOICE) and all(type(k) is str for k in KINDS)
    assert wire_kind(CellKind.FUNCTION) == "function"
    assert wire_kind(CellKind.CHOICE) == wire_kind(CellKind.VALUE) == "choice"
    with pytest.raises(ValueError):
        wire_kind(CellKind.MANUAL)
    assert NameJob("f", wire_kind(CellKind.VALUE), []).kind == "choice"


def _returns_text(node) -> bool:
    if isinstance(node, ast.JoinedStr) or (isinstance(node, ast.Constant)
                                           and isinstance(node.value, str)):
        return True
    if isinstance(node, ast.IfExp):
        return _returns_text(node.body) or _returns_text(node.orelse)
    return False


def _rules(tree):
    """The comparison rules of a module: functions annotated to return a ``Mismatch``, and
    the inner ``rule`` closures of rule factories."""
    for fn in ast.walk(tree):
        if isinstance(fn, ast.FunctionDef) and (
                (fn.returns is not None and "Mismatch" in ast.unparse(fn.returns))
                or fn.name == "rule"):
            yield fn


@pytest.mark.parametrize("path", sorted(EXERCISES.glob("*.py")), ids=lambda p: p.name)
def test_registry_rules_return_a_mismatch_never_a_bare_string(path):
    tree = ast.parse(path.read_text("utf-8"))
    bare = [f"{path.name}:{node.lineno} in {fn.name}" for fn in _rules(tree)
            for node in ast.walk(fn) if isinstance(node, ast.Return) and node.value is not None
            and _returns_text(node.value)]
    assert not bare, bare


def test_every_registry_rule_reports_a_wrong_answer_as_a_mismatch():
    """Each function exercise's rule, on its first case's expected answer and a mangled copy."""
    rng = np.random.default_rng(0)
    for ex in REGISTRY.values():
        if ex.kind is not CellKind.FUNCTION:
            continue
        case = next(c for c in ex.draw_cases(rng) if c.raises is None)
        expected = ex.expected(case)
        assert ex.compare(expected, expected) is None, ex.name
        for wrong in ("not an answer", ()):
            why = ex.compare(expected, wrong)
            assert isinstance(why, Mismatch), (ex.name, why)


def test_a_mesh_of_the_wrong_form_is_a_mismatch_graded_as_a_wrong_value():
    from autograder.exercises.q3_marching_cubes import same_mesh

    verts, faces = np.zeros((3, 3)), np.array([[0, 1, 2]])
    why = same_mesh((verts, faces), (np.zeros((3, 2)), faces))
    assert why == wrong_value("verts must have shape (V, 3), got (3, 2)")


def test_graded_tests_are_named_and_tuples_are_converted():
    src = SourceNotebook("qx", None, {}, "", [], [], [("f", "test_f", 2.0)], [("a1", 3.0)])
    (test,) = src.graded
    assert test == GradedTest("f", "test_f", 2.0) and test.points == 2.0
    name, test_id, points = test
    assert (name, test_id, points) == ("f", "test_f", 2.0)
    with pytest.raises(AttributeError):
        test.points = 3.0   # frozen

