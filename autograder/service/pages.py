"""The service's feedback pages: useful while the assignment is open, never a key oracle.

Before the due date (:meth:`~.policy.Policy.is_open`) a page shows, for each graded function,
its status, score, message and visible cases in full, and its hidden cases as "passed / total"
(as ``grade`` does without ``--reveal-hidden``). For a choice or number item (e.g. Q1(a)'s
brightness letters, Q2's count rates) it says only that the answer was recorded and is revealed
after the due date, whatever the answer: a student who probes an item option by option receives
the same page every time. No total is shown (the total minus the functions' scores would be the
items' sum). Written answers are marked by hand after the due date. Every page carries the
attempts line (:func:`~.policy.attempts_line`).

From the due date on, the page is ``grade``'s own (:func:`autograder.outputs.feedback.render`),
with the attempts line on top.
"""

from __future__ import annotations

import datetime as dt
import re

from ..model import CellKind, CellResult
from ..outputs import feedback
from ..outputs.html import e, page

RECORDED = "recorded; revealed after the due date"
_LINE = re.compile(r"<p class='attempts'><b>[^<]*</b></p>")


def open_page(student: str, notebook: str, rows: list[CellResult], line: str) -> str:
    """The page of one graded notebook before the due date (see the module docstring)."""
    body = [f"<h1>{e(notebook)}</h1>", f"<p class='attempts'><b>{e(line)}</b></p>",
            "<p class='note'>Graded functions: visible cases in full, hidden cases as counts. "
            "Choice and number items: recorded, revealed after the due date. No total is shown "
            "before the due date.</p>"]
    whole = next((r for r in rows if r.whole_notebook), None)
    if whole is not None:       # missing or unreadable: about the file, not the answers
        body.append(f"<p class='msg'>{e(whole.message)}</p>")
    body += [_row_html(r) for r in rows]
    return page(f"{notebook}: feedback for {student}", body, feedback._STYLE)


def _row_html(r: CellResult) -> str:
    if r.kind is CellKind.MANUAL:
        return (f"<h2>{e(r.grade_id)} <small>(written answer, {r.max_score:g} marks)</small>"
                "</h2><p class='msg'>marked by hand after the due date</p>")
    if r.kind is not CellKind.FUNCTION:
        return (f"<h2>{e(r.name)} <small>({r.max_score:g} marks)</small></h2>"
                f"<p class='msg'>{RECORDED}</p>")
    score = "–" if r.score is None else f"{round(r.score, 2):g}"
    parts = [f"<h2>{e(r.name)} <span class='badge {e(r.status.value)}'>{e(r.status.value)}"
             f"</span> <small>{score} / {r.max_score:g}</small></h2>",
             f"<p class='msg'>{e(r.message)}</p>"]
    parts += feedback._visible_html([c for c in r.cases if c.visible],
                                    feedback._up_to(r.name))
    parts += feedback._hidden_html([c for c in r.cases if not c.visible], reveal=False)
    return "\n".join(parts)


def closed_page(student: str, notebook: str, rows: list[CellResult], line: str) -> str:
    """The page from the due date on: ``grade``'s, the attempts line first."""
    html = feedback.render(student, notebook, rows, reveal_hidden=False)
    return html.replace(f"<h1>{e(notebook)}</h1>",
                        f"<h1>{e(notebook)}</h1><p class='attempts'><b>{e(line)}</b></p>", 1)


def not_graded_page(student: str, notebook: str, line: str, reopens: dt.datetime) -> str:
    """The page of a notebook submitted with no graded attempt left in the window."""
    return _message_page(
        student, notebook, line,
        f"This version was recorded but not graded: no graded attempt is left today. The next "
        f"one opens at {e(reopens.strftime('%Y-%m-%d %H:%M %Z'))}. Your earlier graded attempts "
        "keep their feedback and their place in the course's policy (which attempt counts).")


def too_large_page(student: str, notebook: str, line: str, size: int, limit: int) -> str:
    """The page of a notebook over the size limit: not read, not graded, no attempt charged."""
    return _message_page(
        student, notebook, line,
        f"This version was not graded and cost no attempt: the file is {size / 2**20:.1f} MB, "
        f"over the limit of {limit / 2**20:g} MB a notebook may be (huge outputs?). Clear all "
        "outputs (Edit &gt; Clear Outputs of All Cells), save and submit again.")


def failed_page(student: str, notebook: str, line: str, why: str, charged: bool) -> str:
    """The page of a notebook whose submission could not be graded (``why``, in words for the
    student); ``charged``: it counted as a graded attempt, scored 0."""
    cost = ("It counted as a graded attempt of this notebook, scored 0 (what counts for your "
            "mark is unchanged)." if charged else "It cost no graded attempt.")
    return _message_page(student, notebook, line,
                         f"This submission could not be graded: {e(why)}. {cost} Submit again "
                         "to be graded; your instructor has the details.")


def _message_page(student: str, notebook: str, line: str, message_html: str) -> str:
    """A page of no grades: the notebook, its attempts line and one message (already HTML)."""
    body = [f"<h1>{e(notebook)}</h1>", f"<p class='attempts'><b>{e(line)}</b></p>",
            f"<p class='msg'>{message_html}</p>"]
    return page(f"{notebook}: feedback for {student}", body, feedback._STYLE)


def with_line(html: str, line: str) -> str:
    """A page with its attempts line replaced by ``line``."""
    return _LINE.sub(lambda _m: f"<p class='attempts'><b>{e(line)}</b></p>", html, count=1)
