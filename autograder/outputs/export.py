"""Final grades out of nbgrader's gradebook, in the shapes a university uploads.

``python -m autograder export`` reads the gradebook (after marking) and writes, into ``OUT``:

- ``canvas.csv``: Canvas's gradebook import (Gradebook → Import): the columns ``Student``,
  ``ID``, ``SIS User ID``, ``SIS Login ID``, ``Section``, then the total (``tripos2006``), or
  with ``canvas_questions`` one column per question (``tripos2006 q1_imaging`` …) and, where a
  late penalty applies, ``tripos2006 late penalty`` (negative) instead, so that the columns
  always add up to the total and importing every one never counts a mark twice. Canvas reads
  a number in brackets after a column's name as the assignment's id, so no header carries one:
  the maxima are in the ``Points Possible`` row under the header, as in Canvas's own export.
  One row per student follows;
- ``moodle.csv``: Moodle's "Import grades: CSV file": ``ID number``, ``First name``,
  ``Last name``, ``Email address``, one column per question, the late penalty and the total;
- ``grades-long.csv``: the archive, one row per student, notebook and graded cell, with the
  automatic and manual scores, extra credit, whether the cell was marked, and the comment;
- ``items.csv``: the item analysis of the final marks (:func:`write_items`; the columns and
  definitions of :mod:`.items`), written answers included.

A student's name, e-mail and LMS id come from nbgrader's student table (``nbgrader db student
import`` fills it). Marks are rounded to ``decimals`` places, a half always up
(:func:`round_half_up`: 13.25 gives 13.3, as a mark sheet is read, where Python's ``round``
gives 13.2); each question's column is its notebook's score. The late penalty, taken from the
total, is ``late_per_day`` percent of the assignment's marks per started day after the due date
(with any extension nbgrader records), never more than the total. While a written answer waits
for a marker, :func:`unmarked` lists it and the command refuses to write final grades unless
told ``--allow-unmarked``.
"""

from __future__ import annotations

import csv
import datetime as dt
import decimal
import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path

from ..course import ASSIGNMENT, COURSE_ID
from ..model import format_score
from . import items


@dataclass
class StudentGrades:
    """One student's row: identity, per-notebook scores, lateness."""

    student: str
    first_name: str = ""
    last_name: str = ""
    email: str = ""
    lms_user_id: str = ""
    scores: dict[str, float] = field(default_factory=dict)     #: notebook -> score
    cells: list[dict] = field(default_factory=list)             #: the long-format rows
    timestamp: dt.datetime | None = None
    due: dt.datetime | None = None
    extension: dt.timedelta | None = None


def read_gradebook(db_url: str, notebooks: list[str]) -> list[StudentGrades]:
    """Every student of the gradebook, with the scores of ``notebooks`` (0 if not submitted)."""
    from nbgrader.api import Gradebook, MissingEntry

    rows = []
    with warnings.catch_warnings(), Gradebook(db_url, course_id=COURSE_ID) as gb:
        warnings.simplefilter("ignore")
        for st in sorted(gb.students, key=lambda s: s.id):
            row = StudentGrades(st.id, st.first_name or "", st.last_name or "", st.email or "",
                                st.lms_user_id or "", {nb: 0.0 for nb in notebooks})
            try:
                sub = gb.find_submission(ASSIGNMENT, st.id)
            except MissingEntry:
                rows.append(row)
                continue
            row.timestamp, row.due, row.extension = sub.timestamp, sub.duedate, sub.extension
            for nb in sub.notebooks:
                row.scores[nb.name] = float(nb.score or 0.0)
                row.cells += [_long_row(st.id, nb.name, g, nb) for g in nb.grades]
            rows.append(row)
    return rows


def _long_row(student: str, notebook: str, g, nb) -> dict:
    comment = next((c.comment or c.auto_comment or "" for c in nb.comments if c.name == g.name),
                   "")
    opt = lambda x: "" if x is None else format_score(x)  # noqa: E731
    return {"student": student, "notebook": notebook, "grade_id": g.name,
            "score": format_score(g.score or 0.0), "max_score": format_score(g.max_score or 0.0),
            "auto_score": opt(g.auto_score), "manual_score": opt(g.manual_score),
            "extra_credit": opt(g.extra_credit), "marked": "no" if g.needs_manual_grade else "yes",
            "comment": comment}


def unmarked(rows: list[StudentGrades]) -> list[str]:
    """``student/notebook/grade_id`` of every answer still waiting for a marker."""
    return [f"{c['student']}/{c['notebook']}/{c['grade_id']}"
            for r in rows for c in r.cells if c["marked"] == "no"]


def late_penalty(row: StudentGrades, total_max: float, late_per_day: float,
                 due: dt.datetime | None = None) -> float:
    """Marks taken for lateness: ``late_per_day`` % of ``total_max`` per started day late.

    ``due`` (naive UTC) replaces the gradebook's due date, keeping the student's extension.
    """
    if late_per_day < 0:
        raise ValueError(f"late_per_day must be >= 0, got {late_per_day}")
    deadline = row.due if due is None else due + (row.extension or dt.timedelta(0))
    handed_in, deadline = _naive_utc(row.timestamp), _naive_utc(deadline)
    if handed_in is None or deadline is None or handed_in <= deadline:
        return 0.0
    days = math.ceil((handed_in - deadline).total_seconds() / 86400.0)
    return min(sum(row.scores.values()), days * late_per_day / 100.0 * total_max)


def without_due_date(rows: list[StudentGrades], due: dt.datetime | None) -> list[str]:
    """The students who handed in but whom no due date applies to (no ``due`` given and none in
    the gradebook): a late penalty cannot be taken from them."""
    if due is not None:
        return []
    return [r.student for r in rows if r.timestamp is not None and r.due is None]


#: places a score is first cleaned to, so that float noise from summing (13.249999999999998)
#: does not decide which way a half goes
_NOISE_PLACES = decimal.Decimal("1e-9")


def round_half_up(x: float, decimals: int) -> float:
    """``x`` rounded to ``decimals`` places, a half always away from zero (12.75 -> 12.8,
    13.25 -> 13.3, -0.25 -> -0.3), in decimal arithmetic; ``ValueError`` for a negative
    ``decimals`` or a value that is not finite."""
    if decimals < 0:
        raise ValueError(f"decimals must be >= 0, got {decimals}")
    if not math.isfinite(x):
        raise ValueError(f"a mark must be a finite number, got {x!r}")
    clean = decimal.Decimal(float(x)).quantize(_NOISE_PLACES, rounding=decimal.ROUND_HALF_EVEN)
    step = decimal.Decimal(1).scaleb(-decimals)
    return float(clean.quantize(step, rounding=decimal.ROUND_HALF_UP))


def _naive_utc(when: dt.datetime | None) -> dt.datetime | None:
    """``when`` as a naive UTC datetime (nbgrader stores naive UTC)."""
    if when is None or when.tzinfo is None:
        return when
    return when.astimezone(dt.timezone.utc).replace(tzinfo=None)


def write_all(rows: list[StudentGrades], maxima: dict[str, float], out: Path, *,
              decimals: int = 1, late_per_day: float = 0.0,
              due: dt.datetime | None = None, canvas_questions: bool = False) -> list[Path]:
    """Write ``canvas.csv``, ``moodle.csv`` and ``grades-long.csv``; returns their paths."""
    if decimals < 0:
        raise ValueError(f"decimals must be >= 0, got {decimals}")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    total_max = sum(maxima.values())
    fmt = lambda x: format_score(round_half_up(x, decimals))  # noqa: E731
    late = late_per_day > 0
    canvas_head, points = _canvas_columns(maxima, canvas_questions, late)
    canvas, moodle = [points], []
    for r in rows:
        penalty = late_penalty(r, total_max, late_per_day, due)
        per_q = [fmt(r.scores[nb]) for nb in maxima]
        total = fmt(max(0.0, sum(r.scores.values()) - penalty))
        name = f"{r.last_name}, {r.first_name}".strip(", ") or r.student
        marks = [total] if not canvas_questions else per_q + ([fmt(0.0 - penalty)] if late else [])
        canvas.append([name, r.lms_user_id, r.student, r.email, "", *marks])
        moodle.append([r.student, r.first_name, r.last_name, r.email, *per_q, fmt(penalty),
                       total])
    heads = [f"{nb} ({format_score(m)})" for nb, m in maxima.items()]
    paths = [out / "canvas.csv", out / "moodle.csv", out / "grades-long.csv"]
    _write(paths[0], canvas_head, canvas)
    _write(paths[1], ["ID number", "First name", "Last name", "Email address", *heads,
                      "Late penalty", f"{ASSIGNMENT} total"], moodle)
    long_cols = ["student", "notebook", "grade_id", "score", "max_score", "auto_score",
                 "manual_score", "extra_credit", "marked", "comment"]
    _write(paths[2], long_cols, [[c[k] for k in long_cols] for r in rows for c in r.cells])
    return paths


#: The first cell of the row under the header that gives each column's maximum, as Canvas's
#: own gradebook export writes it (and its import reads it).
POINTS_POSSIBLE = "    Points Possible"


def _canvas_columns(maxima: dict[str, float], questions: bool, late: bool
                    ) -> tuple[list[str], list[str]]:
    """The header of ``canvas.csv`` and its ``Points Possible`` row (see the module docstring):
    the total alone, or the questions and, when ``late``, the late penalty (worth 0)."""
    ids = ["Student", "ID", "SIS User ID", "SIS Login ID", "Section"]
    if not questions:
        return ([*ids, ASSIGNMENT],
                [POINTS_POSSIBLE, "", "", "", "", format_score(sum(maxima.values()))])
    names = [f"{ASSIGNMENT} {nb}" for nb in maxima] + ([f"{ASSIGNMENT} late penalty"]
                                                       if late else [])
    points = [format_score(m) for m in maxima.values()] + (["0"] if late else [])
    return [*ids, *names], [POINTS_POSSIBLE, "", "", "", "", *points]


def _write(path: Path, header: list[str], rows: list[list[str]]) -> None:
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)


def item_responses(rows: list[StudentGrades],
                   kinds: dict[tuple[str, str], str]) -> list[items.Response]:
    """Every graded cell of the gradebook as an item response, on the final score (a marker's
    score where there is one, else the automatic one; extra credit left out). ``kinds`` maps
    ``(notebook, grade_id)`` to the cell's kind (``function``, ``choice``, ``value``,
    ``manual``). A written answer not yet marked is no answer to its item (it counts 0 in the
    rest score, as in the exported total)."""
    out = []
    for r in rows:
        for c in r.cells:
            kind = kinds.get((c["notebook"], c["grade_id"]), "")
            score = None if c["marked"] == "no" else float(c["score"])
            out.append(items.Response(r.student, c["notebook"], c["grade_id"], kind, score,
                                      float(c["max_score"])))
    return out


def write_items(rows: list[StudentGrades], kinds: dict[tuple[str, str], str],
                out: Path) -> Path:
    """``out/items.csv``: :func:`.items.item_statistics` of the final marks, the columns of
    ``grade``'s ``items.csv``."""
    Path(out).mkdir(parents=True, exist_ok=True)
    stats = items.item_statistics(item_responses(rows, kinds))
    return items.write_items_csv(stats, Path(out) / "items.csv")
