"""Verdicts and scores: the one implementation behind ``incell.check()`` and ``grade``.

The sandbox (or, inside a notebook kernel, :func:`call_in_process`) observes what a student's
code did on each case as a :class:`~autograder.model.CaseOutcome`; this module judges it:

- :func:`judge_case` gives one case's :class:`~autograder.model.Verdict` and a reason, comparing a
  returned value with the reference's answer by the exercise's own rule. A rule returns ``None``
  (a match) or a :class:`~autograder.exercises.base.Mismatch` (its ``kind`` says wrong shape or
  wrong value). Nothing here looks inside message text.
- :func:`judge_choice` judges a multiple-choice answer with
  :func:`course_lib.answers.choice_letters`, the course's one answer format.
- :func:`judge_cell` gives a whole cell's :class:`~autograder.model.CellVerdict` from its
  :class:`CellEvidence`: the precedence of every rule (a reference imported, an item not typed,
  an answer missing or malformed, the cases' summary) in one place, used by ``incell.check()``
  and by ``grade`` alike. Its parts: :func:`summarise` (score, status and message of the cases)
  and :func:`unanswered_or_broken` (the status of a cell whose answer is missing or malformed:
  the student is told what to do, and never that the grader failed).

It imports the model and the registry's helpers, nothing of ``grade`` or ``outputs``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from .exercises.base import Exercise, NotPlainData, as_mismatch, same_choice, to_plain
from .model import (SEVERITY, STATUS_MEANING, VERDICT_STATUS, VERDICT_WORDS, AnswerHint,
                    AnswerShape, CaseOutcome, CaseRecord, CellKind, CellVerdict, OutcomeKind,
                    Status, ValueSummary, Verdict)

#: The MRO entry of the exception the released stubs raise (``raise NotImplementedError()``).
NOT_IMPLEMENTED = "builtins.NotImplementedError"
#: Arrays with more entries than this are kept only as a summary once judged.
KEEP_ENTRIES = 20_000
#: Rows of a summarised array that are kept (enough for the feedback's plots).
KEEP_ROWS = 400


def clip(text: str, n: int) -> str:
    """``text`` on one line, at most ``n`` characters."""
    text = " ".join(str(text).split())
    return text if len(text) <= n else text[: n - 3] + "..."


# --------------------------------------------------------------------------------------------
# one case


def rule_verdict(ex: Exercise, expected, received) -> tuple[Verdict, str]:
    """Compare with the exercise's rule: ``(PASS, "")`` or the mismatch's verdict and text."""
    try:
        why = as_mismatch(ex.compare(expected, received))
    except Exception as exc:  # noqa: BLE001 - a rule that cannot compare is a wrong answer
        return Verdict.WRONG_VALUE, f"wrong value (the answer could not be compared: " \
                                    f"{type(exc).__name__})"
    if why is None:
        return Verdict.PASS, ""
    return Verdict(why.kind), why.text


def judge_case(ex: Exercise, case, expected, outcome: CaseOutcome) -> tuple[Verdict, str]:
    """``(verdict, reason)`` of one case of a graded function (Q-independent: any exercise)."""
    kind = OutcomeKind(outcome.kind)
    if kind is OutcomeKind.RETURNED:
        verdict, reason = _judge_returned(ex, case, expected, outcome.value)
        if verdict is not Verdict.PASS and case.raises is None \
                and form_of(outcome.value)[0] != form_of(expected)[0]:
            reason = f"returned {form_words(outcome.value)}, expected {form_words(expected)}"
        return verdict, reason
    if kind is OutcomeKind.RAISED:
        return _judge_raised(case, outcome)
    if kind is OutcomeKind.TIMEOUT:
        return Verdict.TIMEOUT, outcome.message or "took too long"
    if kind is OutcomeKind.CRASHED:
        extra = f" ({outcome.message})" if outcome.message else ""
        return Verdict.ERROR, "crashed the Python process" + extra
    if kind is OutcomeKind.REJECTED:
        return Verdict.REJECTED, outcome.message or "returned something that is not plain numbers"
    if kind is OutcomeKind.REFERENCE_USED:
        return Verdict.REFERENCE_USED, outcome.message or "used course_lib, the reference library"
    if kind is OutcomeKind.REJECTED_CODE:
        return Verdict.REJECTED_CODE, outcome.message or STATUS_MEANING[Status.REJECTED_CODE]
    return Verdict.NOT_RUN, outcome.message or "not run"


def _judge_returned(ex, case, expected, value) -> tuple[Verdict, str]:
    if case.raises is not None:
        return Verdict.WRONG_VALUE, (f"should raise {case.raises.__name__} for this input, but "
                                     "returned a value")
    try:
        plain = to_plain(value)
    except NotPlainData as exc:
        return Verdict.REJECTED, f"returned {exc}, not plain numbers"
    return rule_verdict(ex, expected, plain)


def _judge_raised(case, outcome: CaseOutcome) -> tuple[Verdict, str]:
    mro = tuple(outcome.error_mro)
    if case.raises is not None:
        want = f"{case.raises.__module__}.{case.raises.__qualname__}"
        if want in mro:
            return Verdict.PASS, ""
    if NOT_IMPLEMENTED in mro:
        return Verdict.UNANSWERED, ("raised NotImplementedError: the function is not written "
                                    "yet (replace the stub's raise with your code)")
    if case.raises is not None:
        return Verdict.ERROR, (f"raised {outcome.error_type} ({clip(outcome.message, 200)}) "
                               f"instead of {case.raises.__name__}")
    return Verdict.ERROR, f"raised {outcome.error_type}: {clip(outcome.message, 300)}"


def judge_choice(ex: Exercise, outcome: CaseOutcome,
                 student: str | None = None) -> tuple[Verdict, str]:
    """``(verdict, reason)`` of a multiple-choice answer (its one "case" is the variable),
    against the key in ``student``'s order of the options (``None``: the canonical order)."""
    if OutcomeKind(outcome.kind) is not OutcomeKind.RETURNED:
        return judge_case(ex, _NO_CASE, None, outcome)
    why = same_choice(ex.key_for(student), outcome.value, ex.options, name=ex.name,
                      single=isinstance(ex.answer, str))
    if why is None:
        return Verdict.PASS, ""
    return Verdict(why.kind), why.text


def judge_value(ex: Exercise, outcome: CaseOutcome, student: str) -> tuple[Verdict, str]:
    """``(verdict, reason)`` of a number item against the answer for ``student``'s numbers."""
    if OutcomeKind(outcome.kind) is not OutcomeKind.RETURNED:
        return judge_case(ex, _NO_CASE, None, outcome)
    if outcome.value is None:
        return Verdict.UNANSWERED, (f"not answered: {ex.name} is None; set it to your answer "
                                    "for your own numbers")
    return _judge_returned(ex, _NO_CASE, ex.value_for(student), outcome.value)


def judge_item(ex: Exercise, outcome: CaseOutcome | None,
               student: str | None) -> tuple[Verdict, str]:
    """A choice or a value item, judged for ``student``; ``outcome`` None when its cell types
    no answer (``grade`` judges only the literal typed in the item's own cell)."""
    if outcome is None:
        return Verdict.UNANSWERED, not_typed(ex.name, ex.kind)
    if ex.kind is CellKind.VALUE:
        return judge_value(ex, outcome, student)
    return judge_choice(ex, outcome, student)


def form_of(value) -> tuple:
    """What a value is, without what it holds: ``("number",)`` (a float, an int, a 0-d
    array), ``("bool",)``, ``("array", shape)``, ``("tuple", forms...)`` (lists alike) or the
    type's name. A graded function's returned value is shown on the feedback page only when its
    form is the expected answer's (:func:`same_form`), so a returned text cannot carry
    anything there."""
    if isinstance(value, (bool, np.bool_)):
        return ("bool",)
    if isinstance(value, np.ndarray) and value.ndim:
        return ("array", tuple(int(n) for n in value.shape))
    if isinstance(value, (int, float, np.integer, np.floating, np.ndarray)):
        return ("number",)
    if isinstance(value, (tuple, list)):
        return ("tuple", *(form_of(v) for v in value))
    return (type(value).__name__,)


def same_form(expected, received) -> bool:
    """``received`` has the type and shape of ``expected`` (:func:`form_of`)."""
    try:
        return form_of(expected) == form_of(received)
    except Exception:  # noqa: BLE001 - an odd value is not of the expected form
        return False


def form_words(value) -> str:
    """:func:`form_of` in words: "a str", "an array of shape (3,)", "a tuple of 2"."""
    form = form_of(value)
    if form[0] == "array":
        return f"an array of shape {form[1]}"
    if form[0] == "tuple":
        return f"a tuple of {len(form) - 1}"
    return "None" if value is None else ("an " if form[0][:1] in "aeiou" else "a ") + form[0]


class _NoCase:
    raises = None


_NO_CASE = _NoCase()


def call_in_process(func, case, index: int = 0) -> CaseOutcome:
    """Call ``func`` on ``case`` in this process and record what happened (for ``incell``)."""
    t0 = time.perf_counter()
    try:
        value = func(*case.args, **case.kwargs)
    except Exception as exc:  # noqa: BLE001 - the student's code may raise anything
        mro = tuple(f"{c.__module__}.{c.__qualname__}" for c in type(exc).__mro__)
        return CaseOutcome(index, OutcomeKind.RAISED, error_type=type(exc).__name__,
                           error_mro=mro, message=str(exc), seconds=time.perf_counter() - t0)
    return CaseOutcome(index, OutcomeKind.RETURNED, value=value,
                       seconds=time.perf_counter() - t0)


# --------------------------------------------------------------------------------------------
# a cell


def summarise(records: list[CaseRecord], points: float,
              kind: CellKind = CellKind.FUNCTION) -> tuple[float, Status, str]:
    """``(score, status, message)`` of a test cell: ``points × passed / cases``, where a
    function's visible and bad-input cases count in proportion to the hidden ordinary cases it
    passes (:func:`withheld_passes`); the status names the most serious failure
    (:data:`~autograder.model.SEVERITY`)."""
    n = len(records)
    if n == 0:
        return 0.0, Status.GRADER_ERROR, "no cases could be run (instructor: check the registry)"
    passed = sum(r.verdict is Verdict.PASS for r in records)
    counts: dict[Verdict, int] = {}
    for r in records:
        if r.verdict is not Verdict.PASS:
            counts[r.verdict] = counts.get(r.verdict, 0) + 1
    if Verdict.REFERENCE_USED in counts:
        ref = next(r for r in records if r.verdict is Verdict.REFERENCE_USED)
        return 0.0, Status.REFERENCE_USED, (f"{clip(ref.reason, 160)}: a graded function must "
                                            "be your own work, so this test scores 0")
    withheld = withheld_passes(records) if kind is CellKind.FUNCTION else 0.0
    score = round(points * (passed - withheld) / n, 6)
    if kind in (CellKind.CHOICE, CellKind.VALUE):
        return score, _status_of(counts) if counts else Status.OK, \
            ("correct" if not counts else clip(records[0].reason, 300))
    if passed == n:
        return score, Status.OK, f"all {n} cases passed"
    parts = [f"{c} {VERDICT_WORDS[v]}" for v, c in sorted(counts.items(), key=lambda x: -x[1])]
    msg = f"{passed} of {n} cases passed ({', '.join(parts)})"
    if withheld > 1e-9:
        msg += ("; the visible and bad-input cases it passed count only in proportion to the "
                "hidden ordinary cases it answers right")
    first = next((r for r in records if r.verdict is not Verdict.PASS and r.visible), None)
    if first is not None:
        msg += f"; e.g. {first.label or 'a visible case'}: {clip(first.reason, 200)}"
    else:
        first = next(r for r in records if r.verdict is not Verdict.PASS)
        msg += f"; e.g. a hidden case: {VERDICT_WORDS[first.verdict]}"
    return score, _status_of(counts), msg


def withheld_passes(records: list[CaseRecord]) -> float:
    """How many of the passed cases of a graded function do not count (the course's one credit
    rule, stated in each notebook's first cell).

    The cases a function can pass without the knowledge count only in proportion to the share
    of its *hidden ordinary* cases it answers right: its visible cases (their inputs and
    answers are in the notebook and on the page) and its bad-input cases (where raising
    ``ValueError`` is the right answer, ``record.raises``). Every hidden ordinary case's answer
    depends on the draw and the hidden cases run in a shuffled order (``grade.cases``), so a
    function that raises on every input, answers the visible cases from a table, or counts its
    calls and answers by position (issue 33, finding 1: 12.6 of 64 points) earns nothing for
    them; a function right on every hidden ordinary case keeps them all.

    Without hidden cases (a student's own ``check``, or a name whose only case is visible) the
    visible ordinary cases stand in for the hidden ones and only the bad-input cases are
    withheld; a function whose cases all must raise keeps them (the rule needs an ordinary
    case).
    """
    ordinary = [r for r in records if not r.raises]
    if not ordinary:
        return 0.0
    hidden = [r for r in ordinary if not r.visible]
    share = sum(r.verdict is Verdict.PASS for r in hidden or ordinary) / len(hidden or ordinary)
    counted_in_proportion = [r for r in records if r.raises or (hidden and r.visible)]
    return sum(r.verdict is Verdict.PASS for r in counted_in_proportion) * (1.0 - share)


def _status_of(counts: dict[Verdict, int]) -> Status:
    statuses = {VERDICT_STATUS[v] for v in counts}
    return next(s for s in SEVERITY if s in statuses)


def unanswered_or_broken(name: str, kind: CellKind, hint: AnswerHint, defined: bool,
                         load_why: str = "") -> tuple[Status, str] | None:
    """The status and advice for a cell whose answer is absent or malformed, else None.

    ``hint`` is what the cell's source shows (:class:`~autograder.model.AnswerShape`);
    ``defined`` whether the name existed after the solution cells ran. Only consulted when the
    cell earned nothing, so a cell that works despite an odd shape keeps its score.
    """
    what = "function" if kind is CellKind.FUNCTION else "answer variable"
    shape = hint.shape
    if shape is AnswerShape.UNTOUCHED:
        return Status.UNANSWERED, (f"not answered: the cell of {name} is still the released "
                                   "stub (raise NotImplementedError()); write your answer in "
                                   "its place, run the cell and resubmit")
    if shape is AnswerShape.EMPTY:
        return Status.UNANSWERED, (f"not answered: the solution cell of {name} has no code; "
                                   f"define the {what} {name} there and resubmit")
    if shape is AnswerShape.NONE:
        return Status.UNANSWERED, (f"not answered: your cell sets {name} to None; "
                                   + _how_to_answer(name, kind) + " and resubmit")
    if shape is AnswerShape.NOT_A_FUNCTION and kind is CellKind.FUNCTION:
        return Status.FAILED, (f"{name} must be a function (def {name}(...)), but your cell "
                               f"sets it to {hint.detail}; keep the released signature")
    if shape is AnswerShape.WRONG_ARITY and kind is CellKind.FUNCTION:
        return Status.FAILED, (f"{name} cannot be called as the exercise calls it: {hint.detail}; "
                               "keep the released signature (names and number of arguments)")
    if not defined:
        why = f" ({load_why})" if load_why else ""
        return Status.ERROR, (f"the {what} {name} is not defined after running your solution "
                              f"cells{why}; run your notebook top to bottom (Restart & Run All) "
                              "to find the error")
    return None


def not_typed(name: str, kind: CellKind) -> str:
    """The message for a choice or number item whose cell computes its answer instead of
    typing it (items are graded on what the student types)."""
    example = "\"b\"" if kind is CellKind.CHOICE else "[1.25, 0.5, 3.0]"
    return (f"not typed: the cell of {name} must set {name} to your answer typed out as a "
            f"literal, e.g. {name} = {example}. Items are graded on what you type, not on "
            "what code computes: work it out in another cell if you like, then type the result "
            "here and resubmit")


def _how_to_answer(name: str, kind: CellKind) -> str:
    if kind is CellKind.FUNCTION:
        return f"define it with def {name}(...)"
    if kind is CellKind.VALUE:
        return "set it to your answer for your own numbers"
    return "set it to option letters such as \"b\""


def reference_imported(name: str, reference: str) -> tuple[Status, str]:
    """The status of a graded function whose cell imports the course's reference."""
    return Status.REFERENCE_USED, (f"the cell of {name} imports {reference}, from course_lib, "
                                   "the course's reference library: a graded function may use "
                                   "only NumPy and your own answers, so this test scores 0")


# --------------------------------------------------------------------------------------------
# a cell's verdict: the rules in their order


@dataclass
class CellEvidence:
    """Everything one graded cell's verdict depends on, once its code has run (or been called
    in the kernel by ``incell.check``)."""

    exercise: Exercise
    points: float
    records: list[CaseRecord]               #: the judged cases (one for an item)
    hint: AnswerHint = field(default_factory=AnswerHint)   #: what the cell's source shows
    defined: bool = True                    #: the name existed after the solution cells ran
    load_notes: list[str] = field(default_factory=list)    #: why cells failed, as shown
    typed: bool = True                      #: an item's cell types its answer as a literal
    answer: CaseOutcome | None = None       #: an item's answer as judged
    notes: list[str] = field(default_factory=list)  #: what the student is told besides
    others: tuple[str, ...] = ()            #: other students' ids the notebook names
    student: str = ""                       #: whose notebook (the folder's id)
    reveal: bool = False                    #: hidden tests revealed (after the deadline)

    @property
    def load_why(self) -> str:
        """The last few load notes, for the advice of a name that is not defined."""
        return "; ".join(clip(n, 200) for n in self.load_notes[-3:])


def judge_cell(ev: CellEvidence) -> CellVerdict:
    """The verdict of one graded cell: the first of these rules that applies decides.

    1. A graded function whose cell imports the course's reference scores 0
       (``reference-used``), whatever its cases did.
    2. An item (choice or number) whose cell computes its answer instead of typing it scores 0
       (``failed``, "not typed"), unless rule 4's advice applies to it.
    3. Cases that used the reference or that the sandbox refused keep their summary.
    4. A cell that earned nothing and whose answer is absent or malformed gets the status and
       advice for that (:func:`unanswered_or_broken`: unanswered, wrong signature, not defined).
    5. Otherwise the cases' summary (:func:`summarise`): ``points × passed / cases`` (a
       function's bad-input cases counted only once an ordinary case passes), the status of
       the most serious failure.

    The message then carries the notes (and, revealed, whose numbers a wrong item fits).
    """
    ex, kind = ev.exercise, ev.exercise.kind
    score, status, message = summarise(ev.records, ev.points, kind)

    def broken():
        return unanswered_or_broken(ex.name, kind, ev.hint, ev.defined, ev.load_why)

    if kind is CellKind.FUNCTION and ev.hint.reference:                            # 1
        score, (status, message) = 0.0, reference_imported(ex.name, ev.hint.reference)
    elif kind.is_item and not ev.typed and ev.hint.shape is AnswerShape.WRITTEN:   # 2
        score, (status, message) = 0.0, (broken() or (Status.FAILED, not_typed(ex.name, kind)))
    elif status in (Status.REFERENCE_USED, Status.REJECTED_CODE):                  # 3
        pass
    elif score == 0 and (advice := broken()) is not None:                          # 4
        status, message = advice
    return _with_notes(ev, CellVerdict(score, status, message))                   # 5


def _with_notes(ev: CellEvidence, verdict: CellVerdict) -> CellVerdict:
    """``verdict`` with the notes appended to its message, and whose answer a wrong item fits."""
    ex, notes = ev.exercise, list(ev.notes)
    fits = ""
    if ex.kind.is_item and verdict.status is not Status.OK and ev.answer is not None:
        fits = fits_other(ex, ev.answer, ev.others)
    if fits and ev.reveal:
        notes.append(fits_note(ex, fits, ev.student))
    message = verdict.message + (". Note: " + "; ".join(notes) if notes else "")
    return CellVerdict(verdict.score, verdict.status, message, tuple(notes), fits)


def fits_other(ex: Exercise, answer: CaseOutcome, others) -> str:
    """The first of ``others`` (ids the notebook names) whose numbers or letters this wrong
    answer fits, else ``""``."""
    for other in others:
        try:
            verdict, _ = judge_item(ex, answer, other)
        except Exception:  # noqa: BLE001 - a note only; never fail the grading over it
            continue
        if verdict is Verdict.PASS:
            return other
    return ""


def fits_note(ex: Exercise, other: str, student: str) -> str:
    """What the student is told, once hidden tests are revealed, when their wrong item fits
    another student's numbers or option letters."""
    what = "option letters" if ex.kind is CellKind.CHOICE else "numbers"
    return (f"this answer fits the {what} of student {other}, not yours ({student}): every "
            f"student answers on their own {what}, and the grade uses yours")


# --------------------------------------------------------------------------------------------
# keeping values small once judged


def keep(value):
    """``value`` as the feedback keeps it: small values whole, big arrays as a
    :class:`~autograder.model.ValueSummary` (shape, dtype, the first rows)."""
    if isinstance(value, np.ndarray) and value.size > KEEP_ENTRIES:
        head = np.array(value[:KEEP_ROWS] if value.ndim else value, copy=True)
        if head.size > KEEP_ENTRIES:
            head = head.reshape(-1)[:KEEP_ENTRIES]
        return ValueSummary(tuple(value.shape), str(value.dtype), head)
    if isinstance(value, tuple):
        return tuple(keep(v) for v in value)
    if isinstance(value, str) and len(value) > 2000:
        return value[:2000] + "…"
    return value


def clip_block(text: str, n: int) -> str:
    """``text`` (several lines) cut to ``n`` characters, saying how much was left out."""
    if len(text) <= n:
        return text
    return text[:n] + f"\n... [{len(text) - n} more characters not shown]"
