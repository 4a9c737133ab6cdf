"""What the outputs keep of a judged graded name: hidden cases' details only when revealed, big
values summarised, the student's printed output capped (and withheld while hidden cases are).

The batch (:mod:`.batch`) judges each name as soon as its job returns and keeps only this, so the
grader's memory does not grow with what students return.
"""

from __future__ import annotations

import builtins

from .. import judging
from ..model import VERDICT_WORDS, CaseOutcome, CaseRecord, NameRun, OutcomeKind, Verdict

#: Characters of printed output kept per graded cell for its feedback.
PRINTED_CAP = 20_000


#: What stands for the student's own text while hidden tests are not revealed.
HIDDEN_OUTPUT = ("not shown before the deadline, because this notebook has hidden tests; run "
                 "your notebook yourself to see it")


def load_notes(run: NameRun, show: bool) -> list[str]:
    """The notes of running the cells (their text is the student's: error messages, names)."""
    if show or not run.load_notes:
        return list(run.load_notes)
    return [f"{len(run.load_notes)} message(s) from running your cells: {HIDDEN_OUTPUT}"]


def hidden_printed(run: NameRun, records: list[CaseRecord]) -> str:
    """What stands for the printed output of a job that held hidden inputs, before the deadline."""
    printed = run.printed.strip() or any(r.printed.strip() for r in records)
    return f"(what your code printed is {HIDDEN_OUTPUT})" if printed else ""


#: Exception names a page may show before the deadline: Python's own and NumPy's. Any other
#: name is the student's to choose (``type("x_4_25", (Exception,), {})``), so it could spell
#: what the code saw.
SHOWN_EXCEPTIONS = frozenset(
    [n for n, v in vars(builtins).items() if isinstance(v, type) and issubclass(v, BaseException)]
    + ["LinAlgError", "AxisError"])


def withheld_reason(verdict: Verdict, outcome: CaseOutcome, raises: type | None) -> str | None:
    """A case's reason with nothing of the sandbox's text, for a job that held hidden inputs
    before the deadline (``None``: keep the grader's own reason).

    A text a worker's record carries (an exception's message and name, a timeout's or a
    rejection's message) comes from the student's process, which may write anything there,
    e.g. the inputs another name's worker saw: so it says only what the grader itself knows,
    the verdict and a well-known exception's type. A returned value's reason is the grader's
    (its values are shown only in the expected answer's form), and so are the messages of the
    grader's decoder and the supervisor (``said_by_student`` False)."""
    if outcome.kind is OutcomeKind.RETURNED or verdict is Verdict.PASS:
        return None
    if outcome.kind is OutcomeKind.RAISED and verdict is Verdict.ERROR:
        name = outcome.error_type if outcome.error_type in SHOWN_EXCEPTIONS else \
            "an exception of its own class"
        instead = f" instead of {raises.__name__}" if raises is not None else ""
        return f"raised {name}{instead} (its message: {HIDDEN_OUTPUT})"
    if verdict is Verdict.UNANSWERED or not outcome.said_by_student:
        return None                         # the grader's or the supervisor's own words
    return VERDICT_WORDS[verdict]


def kept(r: CaseRecord, reveal: bool) -> CaseRecord:
    """What the outputs keep of a record: hidden details only when revealed, big values summarised."""
    if not r.visible and not (reveal and r.verdict is not Verdict.PASS):
        return CaseRecord(r.index, "", False, r.verdict)
    keep = judging.keep
    return CaseRecord(r.index, r.label, r.visible, r.verdict, r.reason,
                      args=keep(tuple(r.args)), kwargs={k: keep(v) for k, v in r.kwargs.items()},
                      expected=keep(r.expected), received=keep(r.received), raises=r.raises,
                      printed=judging.clip_block(r.printed, 2000), shown=r.shown)


def printed(run: NameRun, records: list[CaseRecord], reveal: bool) -> str:
    """The solution cells' output, then what the visible (and, revealed, hidden) cases printed."""
    parts = [run.printed] if run.printed.strip() else []
    for r in records:
        if r.printed.strip() and (r.visible or reveal):
            parts.append(f"--- while running {r.label or f'case {r.index + 1}'} ---\n{r.printed}")
    return judging.clip_block("\n".join(parts), PRINTED_CAP)
