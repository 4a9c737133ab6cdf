"""``grade --graded-as STUDENT=ID``: the remedy for an honest wrong ``STUDENT_ID``.

Every student answers the number items and option orders of their own id (Q1–Q6 "your
numbers", :mod:`course_lib.variants`), and the grader judges them on the id of the submission's
folder. A student who typed another id in the notebook's ``STUDENT_ID`` cell worked another
id's numbers and loses those items with "wrong answer"; ``report.html`` lists such answers
under "Own numbers". When the instructor judges it an honest slip, ``--graded-as ab123=xy987
--reason "..."`` judges that student's items on the numbers and letters of ``xy987``; the
decision, its reason and the evidence (the ids each notebook names) are appended to
``OUT/graded-as.log``, and every item so judged says so in its message.

Before the deadline the student is told: the feedback page of a notebook that names an id other
than its folder's says so (:func:`ids_of`, shown by :mod:`autograder.outputs.feedback`).
"""

from __future__ import annotations

import datetime as dt
import getpass
import re
from pathlib import Path

from ..model import ASSIGNMENT, Batch
from .whose import other_students

_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._@+-]{0,127}$")
#: The log of every ``--graded-as`` decision, in the output folder (appended, never rewritten).
LOG_NAME = "graded-as.log"


def parse_graded_as(pairs: list[str], reason: str, submitted: Path) -> dict[str, str]:
    """``{student: id}`` from ``STUDENT=ID`` pairs; ``ValueError`` naming what is wrong."""
    out: dict[str, str] = {}
    for pair in pairs:
        student, sep, other = pair.partition("=")
        student, other = student.strip(), other.strip()
        if not sep or not _ID.match(student) or not _ID.match(other):
            raise ValueError(f"{pair!r} is not STUDENT=ID (two student ids, e.g. ab123=xy987)")
        if student == other:
            raise ValueError(f"{pair!r} names the same id twice")
        if student in out and out[student] != other:
            raise ValueError(f"{student} is given two ids ({out[student]}, {other})")
        if not (Path(submitted) / student / ASSIGNMENT).is_dir():
            raise ValueError(f"no submission of {student} in {submitted}")
        out[student] = other
    if out and not reason.strip():
        raise ValueError("say why with --reason (it is written to the log beside the decision)")
    return out


def ids_of(batch: Batch, graded_as: dict[str, str]) -> dict[tuple[str, str], dict]:
    """Per (student, notebook) the ids its notebook names besides its folder's, and the id it
    was judged on when the instructor decided so: ``{"named": [...], "graded_as": str}``."""
    out = {}
    for (student, notebook), sub in batch.submissions.items():
        named = other_students(sub) if sub.cells else []
        if named or student in graded_as:
            out[(student, notebook)] = {"named": named, "graded_as": graded_as.get(student, "")}
    return out


def _one_line(text: str) -> str:
    """``text`` on one line of the log (its fields are tab-separated, one decision a line)."""
    return " ".join(str(text).split())


def log(out: Path, graded_as: dict[str, str], reason: str, batch: Batch) -> str:
    """Append the decision and its evidence to ``OUT/graded-as.log``; the line to print."""
    path = Path(out) / LOG_NAME
    now = dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")
    named = ids_of(batch, graded_as)
    lines = []
    for student, other in sorted(graded_as.items()):
        evidence = "; ".join(f"{nb} names {', '.join(v['named']) or 'no other id'}"
                             for (s, nb), v in sorted(named.items()) if s == student)
        lines.append(f"{now}\tby {_one_line(getpass.getuser())}\t{student} graded on the "
                     f"numbers and option letters of {other}\treason: {_one_line(reason)}\t"
                     f"evidence: {_one_line(evidence) or 'none found in the notebooks'}\n")
    with open(path, "a", encoding="utf-8") as fh:
        fh.writelines(lines)
    return f"{path}  (the --graded-as decisions: {len(lines)} students, with reason and evidence)"


_LINE = re.compile(r"^(?P<when>[^\t]*)\tby (?P<by>[^\t]*)\t(?P<student>[^\t]*) graded on the "
                   r"numbers and option letters of (?P<graded_as>[^\t]*)\treason: "
                   r"(?P<reason>[^\t]*)\tevidence: (?P<evidence>[^\t]*)$")


def read_log(out: Path) -> list[dict]:
    """The decisions in ``OUT/graded-as.log``, oldest first: ``{when, by, student, graded_as,
    reason, evidence}`` each (a line that is not one of :func:`log`'s is skipped)."""
    path = Path(out) / LOG_NAME
    if not path.is_file():
        return []
    text = path.read_text(encoding="utf-8", errors="replace")
    return [m.groupdict() for m in map(_LINE.match, text.splitlines()) if m]


def decisions(out: Path, graded_as: dict[str, str]) -> list[dict]:
    """For the report: each student's latest decision in ``OUT/graded-as.log``, with
    ``applied``: whether this run graded the student on that id (a re-grade into the same
    folder without ``--graded-as`` does not, and the instructor must see so)."""
    latest = {d["student"]: d for d in read_log(out)}
    return [dict(d, applied=graded_as.get(student) == d["graded_as"])
            for student, d in sorted(latest.items())]
