"""Several submissions in flight at once (worker processes, :mod:`autograder.service.workers`):
each graded exactly once, started in arrival order, a slow student holding one worker and
waiting behind their own submissions, nothing lost when the service or a worker is killed."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

from gradingtools import function_names
from servicetools import honest, later, submit, with_cell

from autograder.service import inbox, loop, workers
from autograder.service.journal import Journal

HERE = Path(__file__).resolve().parent
#: a notebook's whole-job budget in these tests: far above an honest q1's few seconds
BUDGET = 25.0


def _settle() -> None:
    """Past the inbound's settling time, so the service's own clock notices the submissions
    (the parallel loop reads the real clock)."""
    time.sleep(inbox.SETTLE_SECONDS + 0.2)


def _timeline(svc) -> dict[str, list[tuple]]:
    """``{student: [(started, finished, tries, state), ...]}`` in arrival order."""
    out: dict[str, list[tuple]] = {}
    for student, started, finished, tries, state in svc.journal.db.execute(
            "SELECT student, started, finished, tries, state FROM submissions "
            "ORDER BY ctime_ns, id"):
        out.setdefault(student, []).append((started, finished, tries, state))
    return out


def test_two_in_flight_a_slow_student_waits_behind_their_own(service, q1):
    svc = service()
    svc.workers = 2
    svc.budgets = {q1.name: BUDGET}
    spin = with_cell(honest(q1, "sl123"), function_names(q1)[0], "while True:\n    pass\n")
    submit(svc, "sl123", {q1.name: spin})                 # burns its whole budget
    submit(svc, "sl123", {q1.name: honest(q1, "sl123")})
    submit(svc, "aa123", {q1.name: honest(q1, "aa123")})
    submit(svc, "bb123", {q1.name: honest(q1, "bb123")})
    _settle()
    loop.run(svc, poll=0.1, rounds=1)
    t = _timeline(svc)
    assert svc.journal.states() == {"queued": 0, "grading": 0, "done": 4, "failed": 0}
    assert all(tries == 1 for rows in t.values() for _, _, tries, _ in rows)   # once each
    (slow_start, slow_end, _, _), (again_start, _, _, _) = t["sl123"]
    (aa_start, _, _, _), (bb_start, bb_end, _, _) = t["aa123"][0], t["bb123"][0]
    # started in arrival order; the class graded while the slow notebook held a worker
    assert slow_start <= aa_start <= bb_start
    assert aa_start < slow_end and bb_start < slow_end
    assert bb_end < slow_end
    # the slow student's second submission waited behind their first, not the class
    assert again_start >= slow_end
    for student, graded in (("sl123", 2), ("aa123", 1), ("bb123", 1)):
        assert svc.journal.graded_since(student, q1.name, 0) == graded
    target = function_names(q1)[0]
    slow = [r[4] for r in svc.journal.attempts_rows() if r[0] == "sl123" and r[2] == target]
    assert slow[0] == 0.0 and slow[1] > 0.0          # the spinning attempt, then the honest


def test_the_sandboxes_are_shared_within_jobs(service, q1, monkeypatch):
    """Each submission in flight gets ``jobs // workers`` sandboxes (at least one), alone or
    not, and starts only when that many are free (the fork replaced by a stand-in that
    records what each worker was given)."""
    svc = service()                       # --jobs 2
    started = []

    class Stand:
        def __init__(self, target, args, name, daemon):
            started.append(args[2])
            self.sentinel = None

        def start(self):
            pass

    monkeypatch.setattr(workers._CONTEXT, "Process", Stand)
    for student in ("aa123", "bb123", "cc123"):
        submit(svc, student, {q1.name: honest(q1, student)})
    loop.notice(svc, now=later())
    for n_workers, shares in ((1, [2]), (2, [1, 1]), (3, [1, 1]), (4, [1, 1])):
        svc.workers = n_workers
        svc.journal.db.execute("UPDATE submissions SET state='queued'")
        started.clear()
        pool = workers.Workers(svc)
        assert pool.fill(now=later()) == len(shares) and started == shares, n_workers
        # the others wait for a free slot, queued
        assert svc.journal.states()["queued"] == 3 - len(shares)


#: the service in a child process with two workers; the worker stops inside the grading
CHILD = textwrap.dedent("""
    import os, sys, time
    from pathlib import Path
    sys.path[:0] = [{here!r}, {grading!r}]
    import servicetools
    from autograder.isolation import probe
    from autograder.service import grading, loop

    marker = Path({marker!r})
    def stop(*a, **k):
        marker.write_text(str(os.getpid()))
        time.sleep(3600)
    grading.grade_batch = stop
    svc = servicetools.reopen_service(Path({tmp!r}), probe())
    svc.workers = 2
    loop.run(svc, poll=0.1, rounds=1)
""")


def _gone(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().split(") ")[-1].startswith("Z")
    except FileNotFoundError:
        return True


def test_a_killed_service_takes_its_workers_and_resumes(service, q1, tmp_path):
    svc = service()
    submit(svc, "ka123", {q1.name: honest(q1, "ka123")})
    loop.notice(svc, now=later())
    svc.journal.close()
    marker = tmp_path / "marker"
    code = CHILD.format(here=str(HERE), grading=str(HERE.parent / "grading"),
                        marker=str(marker), tmp=str(tmp_path))
    child = subprocess.Popen([sys.executable, "-c", code])
    try:
        for _ in range(6000):
            if marker.exists() or child.poll() is not None:
                break
            time.sleep(0.05)
        assert marker.exists(), "the child service never reached the grading"
        worker = int(marker.read_text())
        assert worker != child.pid                  # graded in a worker process
        os.kill(child.pid, signal.SIGKILL)
    finally:
        child.wait()
    for _ in range(200):                            # the kernel ends the orphan (PDEATHSIG)
        if _gone(worker):
            break
        time.sleep(0.05)
    assert _gone(worker), "the worker outlived the killed service"
    svc.journal = Journal(svc.journal.path)
    assert svc.journal.states()["grading"] == 1
    svc.workers = 2
    _settle()
    loop.run(svc, poll=0.1, rounds=1)
    assert svc.journal.states() == {"queued": 0, "grading": 0, "done": 1, "failed": 0}
    assert svc.journal.graded_since("ka123", q1.name, 0) == 1
    items = [r for r in svc.journal.attempts_rows() if r[1] == q1.name]
    assert len(items) == len({r[2] for r in items}) > 0     # each item once


def test_a_worker_that_dies_puts_its_submission_back(service, q1, monkeypatch):
    svc = service()
    svc.workers = 2

    def die(_svc, _row):
        os._exit(9)
    monkeypatch.setattr(workers, "process_started", die)
    submit(svc, "dw123", {q1.name: honest(q1, "dw123")})
    submit(svc, "ok123", {q1.name: honest(q1, "ok123")})
    _settle()
    loop.run(svc, poll=0.1, rounds=1)
    rows = dict((s, (st, tries, err)) for s, st, tries, err in svc.journal.db.execute(
        "SELECT student, state, tries, error FROM submissions"))
    for student in ("dw123", "ok123"):
        state, tries, error = rows[student]
        assert state == "queued" and tries == 1 and "exit status 9" in error
    monkeypatch.undo()
    loop.drain(svc, now=later())                    # the retry, after its delay
    assert svc.journal.states()["done"] == 2
    assert svc.journal.graded_since("dw123", q1.name, 0) == 1
