"""Grading one journalled submission: collect, charge, grade, hand out, record.

:func:`process` is the service's whole work on one submission, in this order:

1. **collect** the assignment's notebooks and nothing else (:func:`.inbox.collect`); a notebook
   over the grader's size limit is never read, let alone parsed;
2. **decide and charge**: each notebook is unchanged (free: its last page again), over the
   day's attempts (recorded, not graded), too large (a page saying so, free) or to be graded,
   and all of it is written to the journal (:meth:`.journal.Journal.charge`) *before* the
   sandbox runs and before any page leaves. A crash, a kill or a notebook that breaks the
   grader later leaves the attempt counted (a notebook whose grading raised after another's page
   was out used to get both pages for no attempt, issue 33); a retry of the same submission
   finds its charge and grades again without charging;
3. **grade** the charged notebooks in one batch, within what is left of the submission's one
   time budget (:mod:`.budget`), which all its tries share (:mod:`.tries`);
4. **hand out** their pages, then write the counting notebooks and the gradebook, then mark the
   row ``done`` with the items' scores (:meth:`.journal.Journal.finish`).

It is safe to repeat after a kill at any point. A failed try is retried with back-off, a limited
number of times, then the submission is ``failed`` with a page saying so (:mod:`.tries`).
"""

from __future__ import annotations

import datetime as dt
import errno
import hashlib
import json
import shutil
import sys
from dataclasses import dataclass, field, replace
from pathlib import Path

from ..grade.batch import Options, grade_batch
from ..model import CellKind, CellResult, SourceNotebook, Status
from . import budget, handout, inbox, pages, recording
from .journal import Journal, NotebookOutcome, Row
from .policy import Policy, attempts_line
from .tries import (MAX_TRIES, RETRY_SECONDS, Meter, give_up, last_page, retry_or_fail,
                    wait_for_gradebook)

#: what a notebook can be in a submission (:func:`_decide`)
GRADE, UNCHANGED, OVER, TOO_LARGE = "grade", "unchanged", "over the day's attempts", "too large"


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
    attempt; an unreadable file hashes its bytes. Only ever called on a collected copy, which
    is within the size limit (:func:`.inbox.collect`)."""
    data = path.read_bytes()
    try:
        cells = [(c.get("cell_type"), c.get("source")) for c in json.loads(data)["cells"]]
        data = json.dumps(cells, sort_keys=True).encode()
    except (ValueError, KeyError, TypeError, AttributeError, RecursionError):
        pass
    return hashlib.sha256(data).hexdigest()


class _OutOfTime(Exception):
    """The submission's time budget is used up (its tries together took it)."""


def process(svc: Service, row: Row) -> str:
    """Grade ``row``; what happened, one line. Never raises for one submission's sake: a
    full disk postpones it, a refused submission fails it, a grader error retries it."""
    svc.journal.start(row)
    return process_started(svc, row)


def process_started(svc: Service, row: Row) -> str:
    """:func:`process` of a row already marked ``grading`` (by the service's main process,
    before it hands the row to a worker process: :mod:`.workers`). The try's time is added to
    the row's, whatever ended it."""
    meter = Meter(svc.journal, row)
    try:
        return _try(svc, row, meter)
    finally:
        try:
            meter.settle()
        except Exception as exc:  # noqa: BLE001 - the row is settled; its time only is lost
            print(f"error: the time of submission {row.folder} was not recorded: {exc}",
                  file=sys.stderr)


def _try(svc: Service, row: Row, meter: Meter) -> str:
    folder = svc.work / str(row.id)
    try:
        recording.ping_gradebook(svc.db_url)        # down: no sandbox time spent in vain
        shutil.rmtree(folder, ignore_errors=True)   # a killed run's half copy
        got = inbox.collect(svc.inbound, row.folder, row.student, row.ctime_ns, folder,
                            [s.name for s in svc.sources], max_notebook_bytes(svc), svc.uid_of)
        outcomes = _grade(svc, row, got, meter)
        svc.journal.finish(row, outcomes)
        shutil.rmtree(folder, ignore_errors=True)
        graded = [o.notebook for o in outcomes if o.graded]
        return f"{row.student}: graded {', '.join(graded) or 'nothing new'}"
    except inbox.Changed as why:
        svc.journal.retime(row, why.ctime_ns)
        return retry_or_fail(svc, row, why, inbox.SETTLE_SECONDS, "still being written; later",
                             "it kept changing while it was being collected")
    except _OutOfTime as why:
        give_up(svc, row, f"out of time: {why}", f"its grading used up its time ({why})")
        return f"{row.student}: out of time; failed"
    except OSError as exc:
        if exc.errno != errno.ENOSPC:
            return retry_or_fail(svc, row, exc)
        svc.journal.postpone(row, f"disk full: {exc}", RETRY_SECONDS, count_try=False)
        print(f"error: the disk is full ({exc}); submission {row.folder} is kept in the "
              f"queue and tried again in {RETRY_SECONDS:g} s", file=sys.stderr)
        return f"{row.student}: disk full; kept and retried later"
    except inbox.exchange_rules().SubmissionRefused as why:
        shown = str(why).replace(f"{svc.inbound / row.folder}/", "")
        give_up(svc, row, f"refused: {why}", f"it was refused: {shown}")
        return f"{row.student}: refused ({why})"
    except Exception as exc:  # noqa: BLE001 - one submission never stops the service
        if recording.gradebook_unreachable(exc):
            return wait_for_gradebook(svc, row, exc)
        return retry_or_fail(svc, row, exc)


def max_notebook_bytes(svc: Service) -> int:
    """The largest notebook file the service reads: the grader's own limit
    (``Options.max_notebook_mb``), which would reject a larger one anyway, but only after
    reading and parsing it."""
    return int(svc.opts.max_notebook_mb * 2**20)


@dataclass
class _Plan:
    """What becomes of one notebook of a submission (:func:`_decide`)."""

    src: SourceNotebook
    digest: str
    kind: str           #: GRADE, UNCHANGED, OVER or TOO_LARGE
    used: int           #: the day's graded attempts of the notebook before this submission
    size: int = 0       #: bytes, for one TOO_LARGE


def _grade(svc: Service, row: Row, got: inbox.Collected, meter: Meter) -> list[NotebookOutcome]:
    """Decide and charge, grade, then hand out each notebook of the collected submission."""
    when = dt.datetime.fromtimestamp(row.ctime_ns / 1e9, dt.timezone.utc)
    since = svc.policy.day_start(when).timestamp()
    charged = svc.journal.charged(row)
    plans = [p for p in (_decide(svc, row, got, src, since, charged) for src in svc.sources) if p]
    svc.journal.charge(row, [(p.src.name, p.digest, p.kind == GRADE) for p in plans])
    to_grade = [p for p in plans if p.kind == GRADE]
    results, subs = _run(svc, row, got.folder.parent.parent, [p.src for p in to_grade], meter)
    # every page is made before any leaves: a notebook that breaks the grader is found first
    outcomes, out, counting = [], [], []
    for plan in to_grade:
        outcome, html, counts = _judged(svc, row, plan, when,
                                        [r for r in results if r.notebook == plan.src.name])
        outcomes.append(outcome)
        out.append((plan.src.name, html, True))
        if counts:
            counting.append(plan.src.name)
    for plan in (p for p in plans if p.kind != GRADE):
        outcomes.append(NotebookOutcome(plan.src.name, plan.digest, graded=False))
        html = _ungraded_page(svc, row, plan, when)
        if html is not None:
            out.append((plan.src.name, html, False))
    for notebook, html, graded in out:
        if graded:
            handout.write_atomic(last_page(svc, row.student, notebook), html, 0o600)
        handout.hand_out(svc.course, svc.exchange, got.folder, row.student, notebook, html)
    recording.record(svc, row.student, got.folder, counting, results, subs)
    return outcomes


def _judged(svc: Service, row: Row, plan: _Plan, when: dt.datetime,
            rows: list[CellResult]) -> tuple[NotebookOutcome, str, bool]:
    """The outcome, page and whether it counts (the policy's ``counts``) of a graded notebook.

    A notebook on which the grader failed every test raises, for a retry (its attempt charged
    already), except on the last try: then the attempt stands, scored 0, with a page saying so,
    and the gradebook keeps what it had."""
    auto = [r for r in rows if r.kind is not CellKind.MANUAL]
    line = attempts_line(svc.policy.attempts - plan.used - 1, svc.policy.attempts)
    items = tuple((r.name, r.score, r.max_score, r.status.value) for r in rows)
    most = sum(r.max_score for r in auto)
    if auto and all(r.status is Status.GRADER_ERROR for r in auto):
        if row.tries + 1 < MAX_TRIES:
            raise RuntimeError(f"the grader failed on every test of {plan.src.name}")
        return (NotebookOutcome(plan.src.name, plan.digest, True, 0.0, most, items),
                pages.failed_page(row.student, plan.src.name, line,
                                  f"the grader failed on it {MAX_TRIES} times", True), False)
    functions = tuple(r.name for r in auto if r.kind is CellKind.FUNCTION)
    ranked = sum(r.score or 0.0 for r in auto if r.kind is CellKind.FUNCTION)
    render = pages.open_page if svc.policy.is_open(dt.datetime.now(dt.timezone.utc)) \
        else pages.closed_page
    return (NotebookOutcome(plan.src.name, plan.digest, True, sum(r.score or 0.0 for r in auto),
                            most, items),
            render(row.student, plan.src.name, rows, line),
            _counts(svc, row, when, plan.src.name, ranked, functions))


def _decide(svc: Service, row: Row, got: inbox.Collected, src: SourceNotebook, since: float,
            charged: set[str]) -> _Plan | None:
    """What becomes of ``src``'s notebook in the submission (None when it holds none). A
    notebook an earlier try of this submission charged is graded again and charged no more,
    even if the student has since made it too large or taken it away (the grader then finds
    it missing: 0)."""
    used = svc.journal.graded_since(row.student, src.name, since, other_than=row.id)
    path = got.folder / f"{src.name}.ipynb"
    if src.name in got.too_large:
        size = got.too_large[src.name]
        kind = GRADE if src.name in charged else TOO_LARGE
        return _Plan(src, f"not read: {size} bytes", kind, used, size)
    if not path.is_file():
        return _Plan(src, "not submitted", GRADE, used) if src.name in charged else None
    d = digest(path)
    if src.name in charged:
        return _Plan(src, d, GRADE, used)
    if d == svc.journal.last_digest(row.student, src.name, other_than=row.id):
        return _Plan(src, d, UNCHANGED, used)
    if used >= svc.policy.attempts:
        return _Plan(src, d, OVER, used)
    return _Plan(src, d, GRADE, used)


def _ungraded_page(svc: Service, row: Row, plan: _Plan, when: dt.datetime) -> str | None:
    """The page of a notebook not graded (None: an unchanged one never graded has none)."""
    total = svc.policy.attempts
    if plan.kind == OVER:
        return pages.not_graded_page(row.student, plan.src.name, attempts_line(0, total),
                                     svc.policy.next_day(when))
    line = attempts_line(max(0, total - plan.used), total)
    if plan.kind == TOO_LARGE:
        return pages.too_large_page(row.student, plan.src.name, line, plan.size,
                                    max_notebook_bytes(svc))
    last = last_page(svc, row.student, plan.src.name)   # unchanged: its last graded page again
    return pages.with_line(last.read_text(encoding="utf-8"), line) if last.is_file() else None


def _run(svc: Service, row: Row, submitted: Path, sources: list[SourceNotebook],
         meter: Meter):
    """The results and submissions of ``row``'s ``sources``, by the public ``grade_batch``
    (its ``opts.jobs`` sandboxes at a time) within what is left of the submission's budget
    (:func:`.budget.batch_timeout`), charged to it before the batch starts.

    One call for the whole submission, not one per notebook in parallel threads: the batch
    plans its jobs (``ast.parse``) in one thread, and CPython 3.11's parser is not safe to run
    from several threads at once (``SystemError: AST constructor recursion depth mismatch``,
    seen here under load)."""
    if not sources:
        return [], {}
    default = svc.opts.limits.job_timeout
    whole = budget.submission_budget(svc.budgets, [s.name for s in sources], default)
    left = whole - svc.journal.spent(row)
    if left < budget.MIN_TRY_SECONDS:
        raise _OutOfTime(f"{whole:.0f} s over {row.tries + 1} tries")
    longest = max(svc.budgets.get(s.name, default) for s in sources)
    timeout, waves = budget.batch_timeout(left, len(sources), max(1, svc.opts.jobs), longest)
    meter.reserve(timeout * waves)
    limits = replace(svc.opts.limits, job_timeout=timeout)
    batch = grade_batch(submitted, sources, replace(svc.opts, limits=limits, progress=False),
                        students=[row.student])
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
