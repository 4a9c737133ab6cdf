"""The grading service's policy, in one place: attempts, which submission counts, what a page shows.

Loaded from ``<course>/grading_service.json`` (every key optional; the defaults are below)::

    {"attempts": 5, "timezone": "Europe/London", "counts": "last",
     "due": "2026-03-13T16:00:00+00:00", "margin": 10, "floor_seconds": 20}

- ``attempts``: graded attempts per notebook, per student, per calendar day (in ``timezone``).
  A notebook counts as an attempt only when its cells changed since its last graded attempt, so
  resubmitting the whole assignment to change one notebook costs one attempt of that notebook.
- ``counts``: which graded attempt the gradebook keeps: ``"last"`` (the latest, late or not: the
  late penalty is ``export``'s, from the submission's time), ``"last_before_due"`` (the latest
  on time; later ones get feedback only) or ``"best"`` (per notebook, the highest automatic
  score, ties to the later).
- ``due``: the due date (ISO 8601 with a UTC offset). Before it the pages are *open-window*
  pages (:mod:`.pages`); from it on they show everything ``grade`` shows without
  ``--reveal-hidden``.
- ``margin`` and ``floor_seconds``: each notebook's time budget is ``max(floor, margin x the
  reference solution's own grading time)`` (:mod:`.budget`).

The anti-oracle rule (Q-items are choice letters and numbers, e.g. Q1(a)'s four brightness
items): before the due date a page never says whether a choice or number item is right, and never
shows a total (a total would give the sum over items, hence an item by difference). Graded
functions show their visible cases in full and their hidden cases as "passed / total".
"""

from __future__ import annotations

import datetime as dt
import json
from dataclasses import dataclass, fields
from pathlib import Path
from zoneinfo import ZoneInfo, ZoneInfoNotFoundError

#: the policy file, in the course folder
POLICY_FILE = "grading_service.json"
COUNTS = ("last", "last_before_due", "best")


@dataclass(frozen=True)
class Policy:
    """How the service grades while the assignment is open (see the module docstring)."""

    attempts: int = 5
    timezone: str = "Europe/London"
    counts: str = "last"
    due: dt.datetime | None = None
    margin: float = 10.0
    floor_seconds: float = 20.0

    def __post_init__(self):
        if type(self.attempts) is not int or self.attempts < 1:
            raise ValueError(f"attempts must be a positive whole number, got {self.attempts!r}")
        if self.counts not in COUNTS:
            raise ValueError(f"counts must be one of {', '.join(COUNTS)}, got {self.counts!r}")
        try:
            ZoneInfo(self.timezone)
        except (ZoneInfoNotFoundError, ValueError, TypeError) as exc:
            raise ValueError(f"timezone {self.timezone!r} is not a known time zone") from exc
        if self.due is not None and self.due.tzinfo is None:
            raise ValueError("due must carry a UTC offset (e.g. 2026-03-13T16:00:00+00:00)")
        for name in ("margin", "floor_seconds"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
                raise ValueError(f"{name} must be a positive number, got {value!r}")

    def is_open(self, when: dt.datetime) -> bool:
        """Whether ``when`` (aware) is before the due date (always, without one)."""
        return self.due is None or when < self.due

    def day_start(self, when: dt.datetime) -> dt.datetime:
        """The start of ``when``'s calendar day in the policy's time zone (the attempts'
        window), as an aware datetime."""
        local = when.astimezone(ZoneInfo(self.timezone))
        return local.replace(hour=0, minute=0, second=0, microsecond=0)

    def next_day(self, when: dt.datetime) -> dt.datetime:
        """When the next window opens after ``when``."""
        # aware arithmetic is on the wall clock: midnight to midnight, summer time or not
        return self.day_start(when) + dt.timedelta(days=1)


def attempts_line(left: int, total: int) -> str:
    """The line every page carries."""
    return f"{left} of {total} graded attempts left today"


def load_policy(course: Path) -> Policy:
    """The policy of the course folder ``course`` (defaults for what its file leaves out).
    Raises ``ValueError`` naming the file on an unknown key or a bad value."""
    path = Path(course) / POLICY_FILE
    if not path.is_file():
        return Policy()
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise ValueError(f"{path}: not readable JSON ({exc})") from exc
    return policy_from(data, str(path))


def policy_from(data, where: str = "the policy") -> Policy:
    """A :class:`Policy` from a JSON object; ``ValueError`` (naming ``where``) when bad."""
    if not isinstance(data, dict):
        raise ValueError(f"{where}: expected a JSON object")
    known = {f.name for f in fields(Policy)}
    unknown = sorted(set(data) - known)
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {', '.join(unknown)}; known: "
                         f"{', '.join(sorted(known))}")
    data = dict(data)
    if data.get("due") is not None:
        try:
            data["due"] = dt.datetime.fromisoformat(str(data["due"]))
        except ValueError as exc:
            raise ValueError(f"{where}: due {data['due']!r} is not an ISO 8601 time") from exc
    try:
        return Policy(**data)
    except (ValueError, TypeError) as exc:
        raise ValueError(f"{where}: {exc}") from exc


#: the first words of the paragraph :func:`policy_paragraph` writes (the release finds and
#: replaces an earlier one by them)
PARAGRAPH_MARK = "**Graded attempts and feedback while the assignment is open.**"

_COUNTS_TEXT = {
    "last": "your last graded attempt of each notebook, even one after the due date (the late "
            "rules then apply to its time)",
    "last_before_due": "your last graded attempt of each notebook before the due date; later "
                       "attempts get feedback only",
    "best": "for each notebook, your best graded attempt, ranked by its graded functions' score "
            "(a tie goes to the later attempt), with the choice and number answers it holds",
}


def policy_paragraph(policy: Policy) -> str:
    """The policy in words for students, as the release states it in each notebook's first
    cell: attempts per day, what a page shows before the due date, which attempt counts."""
    reveal = ("No due date is set yet, so their verdicts come only in the feedback your "
              "instructor returns after the term." if policy.due is None else
              "Their verdicts are shown from the due date on, "
              f"{policy.due.astimezone(dt.timezone.utc):%Y-%m-%d %H:%M} UTC.")
    plural = "attempt" if policy.attempts == 1 else "attempts"
    return (
        f"{PARAGRAPH_MARK} Press **Submit** in the Assignments panel, then **Fetch Feedback**: "
        "the course's grading service grades each notebook you changed and hands back a "
        f"feedback page. You have **{policy.attempts} graded {plural} per notebook per day** "
        f"(midnight to midnight, {policy.timezone} time); a notebook submitted unchanged costs "
        "no attempt, and every page says how many are left today (such as \""
        f"{attempts_line(max(0, policy.attempts - 1), policy.attempts)}\"). A changed notebook "
        "costs its attempt as soon as the service takes it, even if its grading then fails "
        "(its page says so, and it scores 0). Before the due "
        "date a page shows each graded function's score, its visible test cases in full and "
        "how many of its hidden cases passed; multiple-choice and number answers are recorded "
        f"but not marked right or wrong, and no total is shown. {reveal} "
        f"What counts for your mark: {_COUNTS_TEXT[policy.counts]}."
    )
