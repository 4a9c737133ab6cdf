"""Grading one journalled submission: collect, decide the attempts, grade, record, hand out.

:func:`process` is the service's whole work on one submission; it is safe to repeat after a
kill at any point (the collected copy is taken again, pages and the gradebook's automatic scores
are overwritten with the same values, and the attempts are recorded with the row's ``done`` in
one transaction: :mod:`.journal`).
"""

from __future__ import annotations

import datetime as dt
import errno
import hashlib
import json
import shutil
import sys
import traceback
from dataclasses import dataclass, field, replace
from pathlib import Path

from ..course import file_lock
from ..grade.batch import Options, grade_batch
from ..model import Batch, CellKind, CellResult, SourceNotebook, Status
from ..outputs import gradebook
from . import handout, inbox, pages
from .journal import Journal, NotebookOutcome, Row
from .policy import Policy, attempts_line

#: seconds before a postponed submission (a full disk, the gradebook down, a grader error) is
#: tried again
DISK_RETRY = 60.0
#: tries before a submission whose grading keeps failing is left ``failed`` (the instructor
#: re-queues it after fixing the cause: ``UPDATE submissions SET state='queued'``)
MAX_TRIES = 5


@dataclass
class Service:
    """What the service grades with (built by :mod:`.cli`)."""

    course: Path
    inbound: Path
    exchange: Path | None
    journal: Journal
    policy: Policy
    sources: list[SourceNotebook]
    opts: Options
    budgets: dict[str, float] = field(default_factory=dict)
    db_url: str | None = None           #: None: no gradebook
    uid_of: object = inbox.unix_uid
    #: submissions graded at once, each in a worker process of its own (:mod:`.workers`);
    #: 1: one at a time, in the service's own process
    workers: int = 1

    @property
    def work(self) -> Path:
        return Path(self.course) / "service" / "work"


def digest(path: Path) -> str:
    """A notebook's cells (type and source), hashed: outputs and counts do not make a new
    attempt; an unreadable file hashes its bytes."""
    data = path.read_bytes()
    try:
        cells = [(c.get("cell_type"), c.get("source")) for c in json.loads(data)["cells"]]
        data = json.dumps(cells, sort_keys=True).encode()
    except (ValueError, KeyError, TypeError, AttributeError):
        pass
    return hashlib.sha256(data).hexdigest()


def process(svc: Service, row: Row) -> str:
    """Grade ``row``; what happened, one line. Never raises for one submission's sake: a
    full disk postpones it, a refused submission fails it, a grader error retries it."""
    svc.journal.start(row)
    return process_started(svc, row)


def process_started(svc: Service, row: Row) -> str:
    """:func:`process` of a row already marked ``grading`` (by the service's main process,
    before it hands the row to a worker process: :mod:`.workers`)."""
    folder = svc.work / str(row.id)
    try:
        ping_gradebook(svc.db_url)                  # down: no sandbox time spent in vain
        shutil.rmtree(folder, ignore_errors=True)   # a killed run's half copy
        collected = inbox.collect(svc.inbound, row.folder, row.student, row.ctime_ns, folder,
                                  svc.uid_of)
        outcomes = _grade(svc, row, collected)
        svc.journal.finish(row, outcomes)
        shutil.rmtree(folder, ignore_errors=True)
        graded = [o.notebook for o in outcomes if o.graded]
        return f"{row.student}: graded {', '.join(graded) or 'nothing new'}"
    except inbox.Changed as why:
        svc.journal.retime(row, why.ctime_ns)
        svc.journal.postpone(row, str(why), inbox.SETTLE_SECONDS)
        return f"{row.student}: still being written; later"
    except OSError as exc:
        if exc.errno != errno.ENOSPC:
            return retry_or_fail(svc, row, exc)
        svc.journal.postpone(row, f"disk full: {exc}", DISK_RETRY, count_try=False)
        print(f"error: the disk is full ({exc}); submission {row.folder} is kept in the "
              f"queue and tried again in {DISK_RETRY:g} s", file=sys.stderr)
        return f"{row.student}: disk full; kept and retried later"
    except inbox.exchange_rules().SubmissionRefused as why:
        svc.journal.fail(row, f"refused: {why}")
        return f"{row.student}: refused ({why})"
    except Exception as exc:  # noqa: BLE001 - one submission never stops the service
        if _gradebook_unreachable(exc):
            return _wait_for_gradebook(svc, row, exc)
        return retry_or_fail(svc, row, exc)


def _gradebook_unreachable(exc: BaseException) -> bool:
    """Whether ``exc`` says the gradebook's database could not be reached or dropped the
    connection (a PostgreSQL server stopped or restarting, a locked SQLite file), rather than
    anything about the submission."""
    try:
        from sqlalchemy.exc import DBAPIError, OperationalError
    except ImportError:
        return False
    return isinstance(exc, OperationalError) or (
        isinstance(exc, DBAPIError) and bool(exc.connection_invalidated))


def ping_gradebook(db_url: str | None) -> None:
    """Open and close one connection to a gradebook server (SQLite files and no gradebook
    are skipped): raises SQLAlchemy's ``OperationalError`` when it cannot be reached, before
    nbgrader's ``Gradebook`` would take the failure for an empty database and try to create
    the course again."""
    if db_url is None or db_url.startswith("sqlite"):
        return
    from sqlalchemy import create_engine, text

    engine = create_engine(db_url)
    try:
        with engine.connect() as con:
            con.execute(text("SELECT 1"))
    finally:
        engine.dispose()


def _wait_for_gradebook(svc: Service, row: Row, exc: BaseException) -> str:
    """Keep the submission queued for as long as the gradebook is down: nothing was counted
    (the attempts are written only with ``done``), and this try is not held against it."""
    first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
    svc.journal.postpone(row, f"gradebook unreachable: {first}", DISK_RETRY, count_try=False)
    print(f"error: the gradebook cannot be reached ({first}); submission {row.folder} is kept "
          f"in the queue and tried again in {DISK_RETRY:g} s", file=sys.stderr)
    return f"{row.student}: gradebook unreachable; kept and retried later"


def retry_or_fail(svc: Service, row: Row, exc: BaseException) -> str:
    """``row`` back in the queue after an error (a minute later), or ``failed`` after
    :data:`MAX_TRIES` tries; what happened, one line."""
    traceback.print_exception(type(exc), exc, exc.__traceback__)
    if row.tries + 1 >= MAX_TRIES:
        svc.journal.fail(row, f"{type(exc).__name__}: {exc}")
        return f"{row.student}: failed {MAX_TRIES} times; left for the instructor"
    svc.journal.postpone(row, f"{type(exc).__name__}: {exc}", DISK_RETRY)
    return f"{row.student}: grader error; retried later"


def _grade(svc: Service, row: Row, collected: Path) -> list[NotebookOutcome]:
    """Decide, grade and hand out each notebook of the collected submission."""
    when = dt.datetime.fromtimestamp(row.ctime_ns / 1e9, dt.timezone.utc)
    since = svc.policy.day_start(when).timestamp()
    outcomes, to_grade, lines = [], [], {}
    for src in svc.sources:
        path = collected / f"{src.name}.ipynb"
        if not path.is_file():
            continue
        d = digest(path)
        used = svc.journal.graded_since(row.student, src.name, since)
        line = attempts_line(max(0, svc.policy.attempts - used), svc.policy.attempts)
        if d == svc.journal.last_digest(row.student, src.name):
            outcomes.append(NotebookOutcome(src.name, d, graded=False))
            _hand_again(svc, collected, row.student, src.name, line)
        elif used >= svc.policy.attempts:
            outcomes.append(NotebookOutcome(src.name, d, graded=False))
            html = pages.not_graded_page(row.student, src.name, attempts_line(
                0, svc.policy.attempts), svc.policy.next_day(when))
            handout.hand_out(svc.course, svc.exchange, collected, row.student, src.name, html)
        else:
            to_grade.append((src, d))
            lines[src.name] = attempts_line(svc.policy.attempts - used - 1, svc.policy.attempts)
    results, subs = _run(svc, row.student, collected.parent.parent, [s for s, _ in to_grade])
    counting = []
    for src, d in to_grade:
        rows = [r for r in results if r.notebook == src.name]
        auto = [r for r in rows if r.kind is not CellKind.MANUAL]
        if auto and all(r.status is Status.GRADER_ERROR for r in auto):
            # the grader's failure, never the student's: no attempt is charged; retried
            raise RuntimeError(f"the grader failed on every test of {src.name}")
        score = sum(r.score or 0.0 for r in auto)
        functions = tuple(r.name for r in auto if r.kind is CellKind.FUNCTION)
        ranked = sum(r.score or 0.0 for r in auto if r.kind is CellKind.FUNCTION)
        outcomes.append(NotebookOutcome(src.name, d, True, score, sum(r.max_score for r in auto),
                                        tuple((r.name, r.score, r.max_score, r.status.value)
                                              for r in rows)))
        render = pages.open_page if svc.policy.is_open(dt.datetime.now(dt.timezone.utc)) \
            else pages.closed_page
        html = render(row.student, src.name, rows, lines[src.name])
        handout.write_atomic(_last_page(svc, row.student, src.name), html, 0o600)
        handout.hand_out(svc.course, svc.exchange, collected, row.student, src.name, html)
        if _counts(svc, row, when, src.name, ranked, functions):
            counting.append(src.name)
    _record(svc, row.student, collected, counting, results, subs)
    return outcomes


def _hand_again(svc: Service, collected: Path, student: str, notebook: str, line: str) -> None:
    """An unchanged notebook: its last graded page again (this submission has its own secret,
    so its own copy), with today's attempts line."""
    last = _last_page(svc, student, notebook)
    if last.is_file():
        html = pages.with_line(last.read_text(encoding="utf-8"), line)
        handout.hand_out(svc.course, svc.exchange, collected, student, notebook, html)


def _last_page(svc: Service, student: str, notebook: str) -> Path:
    """Where the page of ``student``'s last graded attempt of ``notebook`` is kept."""
    return Path(svc.course) / "service" / "pages" / student / f"{notebook}.html"


def _run(svc: Service, student: str, submitted: Path, sources: list[SourceNotebook]):
    """The results and submissions of ``student``'s ``sources``, by the public ``grade_batch``
    (its ``opts.jobs`` sandboxes at a time) under the largest of their budgets.

    One call for the whole submission, not one per notebook in parallel threads: the batch
    plans its jobs (``ast.parse``) in one thread, and CPython 3.11's parser is not safe to run
    from several threads at once (``SystemError: AST constructor recursion depth mismatch``,
    seen here under load)."""
    if not sources:
        return [], {}
    limits = svc.opts.limits
    own = [svc.budgets[s.name] for s in sources if s.name in svc.budgets]
    if own:
        limits = replace(limits, job_timeout=max(own))
    batch = grade_batch(submitted, sources, replace(svc.opts, limits=limits, progress=False),
                        students=[student])
    return batch.results, batch.submissions


def _counts(svc: Service, row: Row, when: dt.datetime, notebook: str, ranked: float,
            functions: tuple[str, ...]) -> bool:
    """Whether this graded notebook replaces the gradebook's (the policy's ``counts``).

    ``best`` ranks attempts by their graded functions alone (``ranked``), ties going to the
    later: the choice and number items, whose right or wrong the pages do not show before the
    due date, come with the attempt so chosen. Ranking by the whole score would let a student
    who answers an item differently in each attempt keep the right answer without knowing it."""
    if svc.policy.counts == "last_before_due":
        return svc.policy.is_open(when)
    if svc.policy.counts == "best":
        best = svc.journal.best_score(row.student, notebook, row.id, functions)
        return best is None or ranked >= best
    return True


def _record(svc: Service, student: str, collected: Path, counting: list[str],
            results: list[CellResult], subs: dict) -> None:
    """The counting notebooks into ``submitted/`` and their automatic scores into the gradebook
    (markers' scores and comments untouched: :func:`autograder.outputs.gradebook.sync`)."""
    if not counting:
        return
    ping_gradebook(svc.db_url)      # submitted/ and the gradebook change together or not at all
    handout.keep_counting(svc.course, collected, student, counting)
    if svc.db_url is None:
        return
    rows = [r for r in results if r.notebook in counting]
    kept = {k: v for k, v in subs.items() if k[1] in counting}
    with _gradebook_turn(svc):
        gradebook.sync(Batch(rows, kept, [student]), svc.sources,
                       submitted=Path(svc.course) / "submitted", out=Path(svc.course),
                       db_url=svc.db_url)


def _gradebook_turn(svc: Service):
    """One worker process at a time writes the gradebook: two writers of a SQLite gradebook
    would meet its lock (nbgrader's engine waits only seconds) and retry the whole submission."""
    return file_lock(Path(svc.course) / "service" / "gradebook.lock")
