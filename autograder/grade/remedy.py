"""``grade --graded-as STUDENT=ID``: the remedy for an honest wrong ``STUDENT_ID``.

Every student answers the number items and option orders of their own id (Q1–Q6 "your
numbers", :mod:`course_lib.variants`), and the grader judges them on the id of the submission's
folder. A student who typed another id in the notebook's ``STUDENT_ID`` cell worked another
id's numbers and loses those items with "wrong answer"; ``report.html`` lists such answers
under "Own numbers". When the instructor judges it an honest slip, ``--graded-as ab123=xy987
--reason "..."`` (or ``--graded-as "ab123=xy987:reason"``, one reason per decision) judges that
student's items on the numbers and letters of ``xy987``; every item so judged says so in its
message.

The decisions live in one place, ``OUT/graded-as.log`` (appended, never rewritten): each line
holds the time, who decided, the two ids, the reason and the evidence (the ids each notebook
names). Every later ``grade`` into the same ``OUT`` re-applies the standing decisions read back
from it (:func:`standing`) and says so; ``--graded-as ab123=ab123 --reason "..."`` withdraws
one, logged the same way.

Before the deadline the student is told: the feedback page of a notebook that names an id other
than its folder's says so (:func:`ids_of`, shown by :mod:`autograder.outputs.feedback`).
"""

from __future__ import annotations

import datetime as dt
import getpass
import re
from dataclasses import dataclass
from pathlib import Path

from ..course import ASSIGNMENT
from ..model import Batch
from .whose import other_students

_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._@+-]{0,127}$")
#: The log of every ``--graded-as`` decision, in the output folder (appended, never rewritten).
LOG_NAME = "graded-as.log"
_DECIDED = re.compile(r"^(\S+) graded on the numbers and option letters of (\S+)$")
_WITHDRAWN = re.compile(r"^(\S+) withdrawn: graded on its own id again$")


@dataclass(frozen=True)
class Decision:
    """One instructor's decision: judge ``student`` on ``other``'s numbers (``other ==
    student``: a withdrawal); ``when`` and ``by`` are empty until it is logged."""

    student: str
    other: str
    reason: str
    when: str = ""
    by: str = ""

    @property
    def withdrawn(self) -> bool:
        return self.other == self.student

    def describe(self) -> str:
        """The line ``grade`` prints for it."""
        when = f"decided {self.when} by {self.by}" if self.when else "decided now"
        if self.withdrawn:
            return f"graded {self.student} on its own id again (withdrawn, {when}: {self.reason})"
        return f"graded {self.student} as {self.other}, {when}: {self.reason}"


def parse_graded_as(pairs: list[str], reason: str, submitted: Path) -> dict[str, Decision]:
    """``{student: Decision}`` from ``STUDENT=ID`` or ``STUDENT=ID:reason`` (``ID`` equal to
    ``STUDENT`` withdraws a decision); ``--reason`` is the reason of those without their own.
    ``ValueError`` naming what is wrong."""
    out: dict[str, Decision] = {}
    for pair in pairs:
        student, sep, rest = pair.partition("=")
        other, _, own_reason = rest.partition(":")
        student, other = student.strip(), other.strip()
        if not sep or not _ID.match(student) or not _ID.match(other):
            raise ValueError(f"{pair!r} is not STUDENT=ID (two student ids, e.g. ab123=xy987)")
        if student in out and out[student].other != other:
            raise ValueError(f"{student} is given two ids ({out[student].other}, {other})")
        if not (Path(submitted) / student / ASSIGNMENT).is_dir():
            raise ValueError(f"no submission of {student} in {submitted}")
        why = " ".join((own_reason or reason).split())
        if not why:
            raise ValueError(f"say why for {student} with --reason or STUDENT=ID:reason (it is "
                             "written to the log beside the decision)")
        out[student] = Decision(student, other, why)
    return out


def standing(out: Path) -> dict[str, Decision]:
    """The decisions in force in ``OUT/graded-as.log``: each student's latest line, unless it
    withdrew the decision. Lines that are not decisions are skipped."""
    path = Path(out) / LOG_NAME
    latest: dict[str, Decision] = {}
    if not path.is_file():
        return latest
    for line in path.read_text(encoding="utf-8").splitlines():
        fields = line.split("\t")
        if len(fields) < 4 or not fields[3].startswith("reason: "):
            continue
        decided, withdrawn = _DECIDED.match(fields[2]), _WITHDRAWN.match(fields[2])
        if not (decided or withdrawn):
            continue
        student = (decided or withdrawn).group(1)
        other = decided.group(2) if decided else student
        latest[student] = Decision(student, other, fields[3][len("reason: "):], fields[0],
                                   fields[1].removeprefix("by "))
    return {s: d for s, d in latest.items() if not d.withdrawn}


def merge(logged: dict[str, Decision], new: dict[str, Decision]
          ) -> tuple[dict[str, Decision], list[Decision]]:
    """The decisions to apply (``logged`` updated by ``new``) and the new ones that change
    something, to log."""
    changes = [d for s, d in sorted(new.items())
               if (s in logged and logged[s].other != d.other)
               or (s not in logged and not d.withdrawn)]
    applied = dict(logged)
    for d in changes:
        if d.withdrawn:
            applied.pop(d.student, None)
        else:
            applied[d.student] = d
    return applied, changes


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


def log(out: Path, changes: list[Decision], batch: Batch) -> str:
    """Append the decisions and their evidence to ``OUT/graded-as.log``; the line to print."""
    path = Path(out) / LOG_NAME
    now = dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")
    named = ids_of(batch, {d.student: d.other for d in changes})
    lines = []
    for d in changes:
        evidence = "; ".join(f"{nb} names {', '.join(v['named']) or 'no other id'}"
                             for (s, nb), v in sorted(named.items()) if s == d.student)
        what = (f"{d.student} withdrawn: graded on its own id again" if d.withdrawn else
                f"{d.student} graded on the numbers and option letters of {d.other}")
        lines.append(f"{now}\tby {_one_line(getpass.getuser())}\t{what}\treason: "
                     f"{_one_line(d.reason)}\tevidence: "
                     f"{_one_line(evidence) or 'none found in the notebooks'}\n")
    with open(path, "a", encoding="utf-8") as fh:
        fh.writelines(lines)
    return f"{path}  (the --graded-as decisions: {len(lines)} new, with reason and evidence)"


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
