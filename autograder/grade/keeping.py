"""What the outputs keep of a judged graded name: hidden cases' details only when revealed, big
values summarised, the student's printed output capped (and withheld while hidden cases are).

The batch (:mod:`.batch`) judges each name as soon as its job returns and keeps only this, so the
grader's memory does not grow with what students return.
"""

from __future__ import annotations

from .. import judging
from ..model import CaseRecord, NameRun, Verdict

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
