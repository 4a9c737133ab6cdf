"""A submission's tries: each one timed against its budget, retried with back-off, then given up.

Every try of a submission counts, whatever ended it: a grader error, a worker that died, a
folder that changed while it was copied (a student can touch their own inbound folder at will:
53 copies in 60 s re-queued at the front of the queue, issue 33). So:

- **time**: each try's time is added to the submission's ``spent`` (:class:`Meter`), and its
  batch may use only what is left of the submission's one budget (:mod:`.budget`);
- **back-off**: a failed try is retried after :func:`retry_delay`, which doubles with each try;
- **a limit**: after :data:`MAX_TRIES` tries, or with the budget used up, the submission is
  ``failed`` (:func:`give_up`): the attempts it was charged stay charged and score 0, and each of
  its notebooks gets a page saying so, so a student never waits on a submission that will not
  come back. The instructor re-queues it after fixing a cause of the course's own:
  ``UPDATE submissions SET state='queued', tries=0, spent=0 WHERE id=N``.

The journal's queue ranks a student by their last start (:meth:`.journal.Journal.next_ready`),
so a retry waits behind every student not just served.
"""

from __future__ import annotations

import datetime as dt
import shutil
import sys
import time
import traceback
from pathlib import Path
from typing import TYPE_CHECKING

from . import handout, inbox, pages
from .journal import Journal, Row
from .policy import attempts_line

if TYPE_CHECKING:
    from .grading import Service

#: seconds before a failed try is tried again (:func:`retry_delay` doubles it for each further
#: counted try; a full disk or a gradebook down, the course's faults, wait this long each time)
RETRY_SECONDS = 60.0
#: tries before a submission is left ``failed``
MAX_TRIES = 5
#: the clock a try's time is measured on (monotonic: the worker held, not CPU)
clock = time.monotonic


def retry_delay(first: float, tries: int) -> float:
    """Seconds before the next try after ``tries`` tries (the first waits ``first``)."""
    if tries < 1:
        raise ValueError(f"a retry follows at least one try, got {tries}")
    return first * 2.0 ** (tries - 1)


class Meter:
    """The time one try of ``row`` uses, added to the row's ``spent`` as it goes.

    What the batch may use is charged before it starts (:meth:`reserve`: a worker that dies
    while grading leaves it charged; :meth:`.journal.Journal.recover` gives it back after the
    service itself was killed), and the try's measured time replaces it when the try ends
    (:meth:`settle`)."""

    def __init__(self, journal: Journal, row: Row):
        self.journal, self.row = journal, row
        self.start = clock()
        self.charged = 0.0

    def reserve(self, seconds: float) -> None:
        self.journal.reserve(self.row, seconds)
        self.charged += seconds

    def settle(self) -> None:
        used = clock() - self.start
        self.journal.spend(self.row, used - self.charged)
        self.charged = used


def retry_or_fail(svc: Service, row: Row, exc: BaseException, first: float = RETRY_SECONDS,
                  later: str = "grader error; retried later",
                  why: str = "the grader failed on it") -> str:
    """``row`` back in the queue after an error, :func:`retry_delay` later, or given up after
    :data:`MAX_TRIES` tries (``why``: the reason in words for the student's page); what
    happened, one line (``later`` when retried)."""
    if not isinstance(exc, inbox.Changed):
        traceback.print_exception(type(exc), exc, exc.__traceback__)
    tries = row.tries + 1           # ``row`` was read before this try began
    error = f"{type(exc).__name__}: {exc}"
    if tries >= MAX_TRIES:
        give_up(svc, row, error, f"{why} {tries} times")
        return f"{row.student}: failed {MAX_TRIES} times; left for the instructor"
    svc.journal.postpone(row, error, retry_delay(first, tries))
    return f"{row.student}: {later}"


def wait_for_gradebook(svc: Service, row: Row, exc: BaseException) -> str:
    """Keep the submission queued for as long as the gradebook is down, this try not held
    against it (the course's fault): an attempt it was charged stays charged once, and the
    retry charges nothing more."""
    first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
    svc.journal.postpone(row, f"gradebook unreachable: {first}", RETRY_SECONDS,
                         count_try=False)
    print(f"error: the gradebook cannot be reached ({first}); submission {row.folder} is kept "
          f"in the queue and tried again in {RETRY_SECONDS:g} s", file=sys.stderr)
    return f"{row.student}: gradebook unreachable; kept and retried later"


def give_up(svc: Service, row: Row, error: str, why: str) -> None:
    """Leave ``row`` ``failed`` (``error`` for the instructor), then hand each of its notebooks a
    page saying so (``why``, for the student). Never raises for the pages' sake: the row is
    settled first."""
    svc.journal.fail(row, error)
    try:
        _failure_pages(svc, row, why)
    except Exception:  # noqa: BLE001 - the row is settled; a page that fails is only logged
        traceback.print_exc()
        print(f"error: no page for the failed submission {row.folder}", file=sys.stderr)


def _failure_pages(svc: Service, row: Row, why: str) -> None:
    """A page for each notebook ``row`` was charged for or holds: why it failed, and whether
    it cost an attempt. A charged one's page is also kept as its last graded page."""
    charged = svc.journal.charged(row)
    held = {s.name for s in svc.sources
            if (svc.inbound / row.folder / f"{s.name}.ipynb").exists()
            or (svc.inbound / row.folder / f"{s.name}.ipynb").is_symlink()}
    if not charged | held:
        return
    when = dt.datetime.fromtimestamp(row.ctime_ns / 1e9, dt.timezone.utc)
    since = svc.policy.day_start(when).timestamp()
    folder = svc.work / f"{row.id}-failed"
    shutil.rmtree(folder, ignore_errors=True)
    try:
        collected = inbox.collect_secret(svc.inbound, row.folder, row.student, folder,
                                         svc.uid_of)
        for src in svc.sources:
            if src.name not in charged | held:
                continue
            used = svc.journal.graded_since(row.student, src.name, since)
            line = attempts_line(max(0, svc.policy.attempts - used), svc.policy.attempts)
            html = pages.failed_page(row.student, src.name, line, why, src.name in charged)
            if src.name in charged:
                handout.write_atomic(last_page(svc, row.student, src.name), html, 0o600)
            handout.hand_out(svc.course, svc.exchange, collected, row.student, src.name, html)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def last_page(svc: Service, student: str, notebook: str) -> Path:
    """Where the page of ``student``'s last graded attempt of ``notebook`` is kept."""
    return Path(svc.course) / "service" / "pages" / student / f"{notebook}.html"
