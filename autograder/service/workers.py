"""Several submissions in flight at once, each graded in a worker process of its own.

Threads cannot do it: the batch plans its jobs with ``ast.parse``, and CPython 3.11's parser is
not safe to run from several threads at once. So the service's main process keeps the journal
and the schedule, and forks one worker process per submission (at most ``svc.workers`` at a
time); the worker grades it with :func:`~.grading.process_started` on a journal connection of
its own and exits.

- **Exactly once.** The main process marks a row ``grading`` before it forks; the worker alone
  moves it on (``done``, ``queued`` again for a retry, or ``failed``), in the journal's own
  transactions. A worker that dies without doing so (killed, out of memory) is seen when it is
  reaped: its row goes back to the queue and counts a try (:func:`~.grading.retry_or_fail`).
- **Dies with the service.** Each worker asks Linux for SIGKILL when the service dies
  (``PR_SET_PDEATHSIG``): a service killed mid-grade leaves no worker that could finish a row the
  restarted service is grading again; the restart finds the row ``grading`` and resumes it.
- **Sandboxes bounded by ``--jobs``.** Each submission in flight gets an equal share of the
  ``opts.jobs`` sandbox slots (``jobs // workers``, at least one) and starts only when its share
  is free. Not all of them when it is alone: a submission that burns its budget would then hold
  every slot, and the next student's would wait for it.
- **Order and fairness** are the journal's (:meth:`~.journal.Journal.next_ready`): students
  round-robin by when a try of theirs last started, so a retry goes behind everyone not just
  served, and no second submission of a student while one of theirs is in flight, so a student
  whose notebooks burn their budget holds one worker for that one budget (all its tries
  together: :mod:`.tries`) and waits behind their own submissions; the class goes on.
"""

from __future__ import annotations

import ctypes
import multiprocessing
import multiprocessing.connection
import os
import signal
from dataclasses import dataclass, replace

from .grading import Service, process_started
from .tries import retry_or_fail
from .journal import Journal, Row

#: fork, not spawn: the worker inherits the service as built (sources parsed, budgets measured)
_CONTEXT = multiprocessing.get_context("fork")
_PR_SET_PDEATHSIG = 1


@dataclass
class _InFlight:
    process: multiprocessing.process.BaseProcess
    row: Row
    jobs: int
    said: multiprocessing.connection.Connection    #: the worker's one line comes back here


def _die_with(parent: int) -> None:
    """SIGKILL this process when ``parent`` dies (Linux); at once if it already has."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
    except (OSError, AttributeError):   # not Linux: the journal still recovers on restart
        pass
    if os.getppid() != parent:
        os._exit(1)


def _work(svc: Service, row: Row, jobs: int, parent: int, say) -> None:
    """The worker process: grade ``row`` with ``jobs`` sandboxes; what happened goes back to
    the service's process through ``say`` (which prints it where its own output goes)."""
    _die_with(parent)
    # the parent's SQLite connection must not be used across fork: a connection of its own
    own = replace(svc, journal=Journal(svc.journal.path), opts=replace(svc.opts, jobs=jobs))
    try:
        say.send(process_started(own, row))
    finally:
        own.journal.close()
        say.close()


class Workers:
    """The worker processes of one service (its main process's view)."""

    def __init__(self, svc: Service, workers: int | None = None):
        self.svc = svc
        self.workers = max(1, workers or svc.workers)
        self.slots = max(1, svc.opts.jobs)
        self.running: list[_InFlight] = []

    @property
    def busy(self) -> bool:
        return bool(self.running)

    def _free_slots(self) -> int:
        return self.slots - sum(f.jobs for f in self.running)

    def fill(self, now: float | None = None) -> int:
        """Start workers for ready submissions while a worker and a sandbox slot are free;
        how many were started."""
        started = 0
        jobs = max(1, self.slots // self.workers)
        while len(self.running) < self.workers and self._free_slots() >= jobs:
            row = self.svc.journal.next_ready(now)
            if row is None:
                break
            self.svc.journal.start(row)
            # not a daemon: a daemonic process may not start processes of its own, and the
            # batch may (a pool of sandboxes); :meth:`stop` ends the workers instead
            hear, say = _CONTEXT.Pipe(duplex=False)
            proc = _CONTEXT.Process(target=_work, args=(self.svc, row, jobs, os.getpid(), say),
                                    name=f"grade-{row.id}", daemon=False)
            proc.start()
            say.close()
            self.running.append(_InFlight(proc, row, jobs, hear))
            started += 1
        return started

    def wait(self, timeout: float | None) -> None:
        """Until a worker ends (or ``timeout`` seconds)."""
        if self.running:
            multiprocessing.connection.wait([f.process.sentinel for f in self.running], timeout)

    def reap(self) -> list[str]:
        """Collect the workers that ended: what each said it did, or, for one that died before
        its row was settled, what became of the row (queued again or failed)."""
        said, still = [], []
        for f in self.running:
            if f.process.is_alive():
                still.append(f)
                continue
            try:
                if f.said.poll():
                    said.append(f.said.recv())
            except (EOFError, OSError):
                pass
            f.said.close()
            f.process.join()
            code = f.process.exitcode
            f.process.close()
            now = self.svc.journal.row_of(f.row.folder)
            if now is not None and now.state == "grading":
                why = RuntimeError(f"its grading process ended with exit status {code} "
                                   "before recording a result")
                said.append(retry_or_fail(self.svc, f.row, why))
        self.running = still
        return said

    def stop(self) -> None:
        """End the workers (their rows stay ``grading``: the next start resumes them)."""
        for f in self.running:
            f.process.kill()
        for f in self.running:
            f.process.join()
            f.said.close()
        self.running = []
