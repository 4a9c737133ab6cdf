"""The hand-back: one page per student and notebook, released through nbgrader's exchange.

``python -m autograder feedback`` merges, for every graded submission,

- the marks of nbgrader's gradebook (automatic scores, the markers' scores, extra credit, the
  late penalty) and the markers' comments on the written answers, and
- the grader's own page ``OUT/feedback/<student>/<notebook>.html`` (visible cases in full,
  hidden cases as counts, or in full when ``grade`` ran with ``--reveal-hidden``),

into ``<course>/feedback/<student>/tripos2006/<notebook>.html``, beside the ``timestamp.txt``
and ``submission_secret.txt`` of the autograded folder (nbgrader's ``release_feedback`` reads
both; see ``../shared/NBGRADER-NOTES.md``). Then it runs ``nbgrader release_feedback`` so that
``nbgrader fetch_feedback`` (and the Assignments panel) deliver the pages.

Pages are rewritten only when their content changed (a SHA-256 per page in
``<course>/feedback/.handback.json``): a changed mark or comment regenerates that page without
``--force``. No rubric, model answer or hidden test reaches a page: it is built from the
gradebook's numbers and comments and the grader's page, never from a source notebook.
"""

from __future__ import annotations

import hashlib
import json
import re
import shutil
import warnings
from dataclasses import dataclass, field
from pathlib import Path

from ..course import ASSIGNMENT, COURSE_ID, run_nbgrader
from ..model import format_score
from .feedback import with_marks
from .gradebook import CARRIED_FILES
from .html import e, page
from .safe_markdown import comment_html

MANIFEST = ".handback.json"
_BODY = re.compile(r"<body>(.*)</body>", re.S)
_STYLE_TAG = re.compile(r"<style>(.*?)</style>", re.S)
#: the grader page's note on the id the notebook names (:func:`.feedback.whose_text`)
_WHOSE = re.compile(r"<p class='whose'>[^<]*</p>")


@dataclass
class Mark:
    """One graded cell of a submitted notebook, as the gradebook holds it."""

    grade_id: str
    score: float
    max_score: float
    written: bool                   #: a written (manually graded) answer
    marked: bool                    #: no longer waiting for a marker
    comment: str = ""


@dataclass
class NotebookMarks:
    """A student's notebook in the gradebook: its marks, penalty and total."""

    student: str
    notebook: str
    marks: list[Mark] = field(default_factory=list)
    late_penalty: float = 0.0

    @property
    def total(self) -> float:
        return max(0.0, sum(m.score for m in self.marks) - self.late_penalty)

    @property
    def max_total(self) -> float:
        return sum(m.max_score for m in self.marks)


def cell_order(sources) -> dict[tuple[str, str], int]:
    """``{(notebook, grade_id): position}`` of every cell of the source notebooks: the order a
    page lists a notebook's marks in (the gradebook keeps none)."""
    return {(src.name, c.meta.get("grade_id")): i for src in sources
            for i, c in enumerate(src.cells) if c.meta.get("grade_id")}


def read_marks(db_url: str, order: dict[tuple[str, str], int] | None = None
               ) -> list[NotebookMarks]:
    """Every submitted notebook of the assignment with its marks and comments, each
    notebook's marks in the order of ``order`` (:func:`cell_order`; by grade_id without)."""
    order = order or {}
    from nbgrader.api import Gradebook

    out = []
    with warnings.catch_warnings(), Gradebook(db_url, course_id=COURSE_ID) as gb:
        warnings.simplefilter("ignore")
        for sub in gb.assignment_submissions(ASSIGNMENT):
            for nb in sub.notebooks:
                comments = {c.name: (c.comment or c.auto_comment or "") for c in nb.comments}
                marks = [Mark(g.name, float(g.score or 0.0), float(g.max_score or 0.0),
                              g.cell.cell_type == "markdown" or g.auto_score is None,
                              not g.needs_manual_grade, comments.get(g.name, ""))
                         for g in sorted(nb.grades, key=lambda g: (
                             order.get((nb.name, g.name), len(order)), g.name))]
                out.append(NotebookMarks(sub.student_id, nb.name, marks,
                                         float(nb.late_submission_penalty or 0.0)))
    return out


def render(marks: NotebookMarks, grader_page: str | None) -> str:
    """The hand-back page: the marks and comments, then the grader's page of results."""
    done = all(m.marked for m in marks.marks)
    # the note that the notebook names another id comes first: a student reads the top
    whose = _WHOSE.search(grader_page or "")
    head = [f"<h1>{e(marks.notebook)}: feedback for {e(marks.student)}</h1>",
            *([whose.group(0)] if whose else []),
            f"<p class='total'>Total <b>{format_score(round(marks.total, 2))} / "
            f"{format_score(marks.max_total)}</b>"
            + ("" if done else " (some written answers are not marked yet)") + "</p>"]
    if marks.late_penalty:
        head.append(f"<p>Late penalty: −{format_score(marks.late_penalty)}.</p>")
    rows = ["<table><tr><th>cell</th><th>mark</th><th>marker's comment</th></tr>"]
    for m in marks.marks:
        # a practice item is worth nothing: "0 / 0" would read as a fail beside it
        mark = ("practice, no marks" if m.max_score == 0 and not m.written
                else f"{format_score(round(m.score, 2))} / {format_score(m.max_score)}" if m.marked
                else "not marked yet")
        rows.append(f"<tr><td>{e(m.grade_id)}{' (written answer)' if m.written else ''}</td>"
                    f"<td>{e(mark)}</td><td class='comment'>{comment_html(m.comment)}</td></tr>")
    rows.append("</table>")
    # a comment is prose, rendered as Markdown: the page's font at full size (not a <pre>
    # inside the table's smaller font, which rendered it at 0.8 of the text around it), the
    # marker's line breaks kept (comment_html leaves no newline between its blocks)
    style = ("td.comment{white-space:pre-wrap;word-break:break-word;font-size:1.1em}"
             "td.comment p{margin:0 0 .4em}td.comment p:last-child{margin:0}")
    body = ["<p class='note'>The automatic tests' results are not available.</p>"]
    if grader_page:
        written = {m.grade_id: (m.score, m.max_score, m.marked) for m in marks.marks
                   if m.written}
        found = _BODY.search(with_marks(_WHOSE.sub("", grader_page, count=1), written))
        style += "".join(_STYLE_TAG.findall(grader_page))
        body = ["<h2>Automatic tests, case by case</h2>", found.group(1) if found else ""]
    return page(f"{marks.notebook}: feedback for {marks.student}", head + rows + body, style)


def write_pages(all_marks: list[NotebookMarks], grading: Path, root: Path) -> tuple[int, int]:
    """Write the pages that changed; returns (written, unchanged)."""
    feedback = root / "feedback"
    manifest_path = feedback / MANIFEST
    try:
        manifest = json.loads(manifest_path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        manifest = {}
    written = unchanged = 0
    for marks in all_marks:
        grader = Path(grading) / "feedback" / marks.student / f"{marks.notebook}.html"
        text = render(marks, grader.read_text(encoding="utf-8") if grader.is_file() else None)
        folder = feedback / marks.student / ASSIGNMENT
        target = folder / f"{marks.notebook}.html"
        digest = hashlib.sha256(text.encode("utf-8")).hexdigest()
        key = f"{marks.student}/{marks.notebook}"
        _carry_files(root / "autograded" / marks.student / ASSIGNMENT, folder)
        if manifest.get(key) == digest and target.is_file():
            unchanged += 1
            continue
        folder.mkdir(parents=True, exist_ok=True)
        target.write_text(text, encoding="utf-8")
        manifest[key] = digest
        written += 1
    feedback.mkdir(parents=True, exist_ok=True)
    manifest_path.write_text(json.dumps(manifest, indent=1, sort_keys=True) + "\n",
                             encoding="utf-8")
    return written, unchanged


def _carry_files(autograded: Path, folder: Path) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    for name in CARRIED_FILES:
        kept = autograded / name
        if kept.is_file() and not kept.is_symlink():
            shutil.copyfile(kept, folder / name)


def missing_secrets(root: Path) -> list[str]:
    """Students whose feedback folder lacks a file ``release_feedback`` needs."""
    return sorted(p.parent.name for p in (root / "feedback").glob(f"*/{ASSIGNMENT}")
                  if any(not (p / n).is_file() for n in CARRIED_FILES))


def release(root: Path, db_url: str, exclude: list[str] = ()) -> None:
    """``nbgrader release_feedback``: copy the pages to the course's exchange."""
    extra = [f"--CourseDirectory.student_id_exclude={','.join(exclude)}"] if exclude else []
    run_nbgrader(["release_feedback", ASSIGNMENT, *extra], root, db_url)
