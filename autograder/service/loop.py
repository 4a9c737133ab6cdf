"""The service loop: notice new submissions, grade the next one, repeat.

Each round lists the exchange's inbound (:func:`~.inbox.scan`), journals what is new (a
refused folder is journalled ``failed`` with its reason), and grades queued submissions in the
journal's fair order (:meth:`~.journal.Journal.next_ready`: round-robin over students): one at a
time in this process, or several at once in worker processes (:mod:`.workers`). Polling costs
one ``listdir`` of the inbound and an ``lstat`` walk of each folder not yet journalled, every
``poll`` seconds (default 2).
"""

from __future__ import annotations

import sys
import time

from . import inbox
from .grading import Service, process


def notice(svc: Service, now: float | None = None) -> int:
    """Journal the inbound's new submissions; how many were new."""
    new = 0
    for found in inbox.scan(svc.inbound, svc.uid_of, now):
        if svc.journal.notice(found.folder, found.student, found.ctime_ns):
            new += 1
            if found.refused:
                svc.journal.fail(svc.journal.row_of(found.folder), f"refused: {found.refused}")
                print(f"refused {found.folder!r}: {found.refused!r}", file=sys.stderr)
    return new


def drain(svc: Service, limit: int | None = None, now: float | None = None) -> list[str]:
    """Grade queued submissions until none is ready (or ``limit`` were taken); what happened.
    ``now``: the clock that decides which postponed submissions are ready."""
    said = []
    while limit is None or len(said) < limit:
        row = svc.journal.next_ready(now)
        if row is None:
            break
        said.append(process(svc, row))
        print(said[-1], file=sys.stderr)
    return said


def run(svc: Service, poll: float = 2.0, rounds: int | None = None) -> None:
    """Serve until interrupted (or for ``rounds`` rounds): recover, then notice and drain.

    With ``svc.workers`` above 1, submissions are graded in worker processes, several at a
    time (:func:`run_parallel`)."""
    recovered = svc.journal.recover()
    if recovered:
        print(f"resuming {recovered} submission(s) a stopped service was grading",
              file=sys.stderr)
    if svc.workers > 1:
        run_parallel(svc, poll, rounds)
        return
    done = 0
    while rounds is None or done < rounds:
        notice(svc)
        if not drain(svc):
            time.sleep(poll)
        done += 1


def run_parallel(svc: Service, poll: float = 2.0, rounds: int | None = None) -> None:
    """Serve with up to ``svc.workers`` submissions in flight (:class:`~.workers.Workers`),
    noticing new submissions between starts. A round ends when nothing is ready and nothing
    is in flight (``rounds=1``: grade what is there, then stop)."""
    from .workers import Workers

    pool = Workers(svc)
    idle = 0
    try:
        while rounds is None or idle < rounds:
            notice(svc)
            pool.fill()
            if pool.busy:
                pool.wait(poll)
            else:
                idle += 1
                if rounds is None or idle < rounds:
                    time.sleep(poll)
            for line in pool.reap():
                print(line, file=sys.stderr)
    finally:
        pool.stop()
