"""Faults lose nothing: a kill mid-grade, a crashing sandbox, a full disk, a refused folder,
and ``grade`` stopped part-way."""

from __future__ import annotations

import csv
import errno
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from gradingtools import function_names
from servicetools import exchange_page, honest, later, submit, with_cell

from autograder.service import handout, loop
from autograder.service.journal import Journal
from autograder.service.policy import attempts_line

HERE = Path(__file__).resolve().parent

#: the service in a child process, made to stop (forever) at ``point`` after leaving a marker
CHILD = textwrap.dedent("""
    import sys, time
    from pathlib import Path
    sys.path[:0] = [{here!r}, {grading!r}]
    import servicetools
    from autograder.isolation import probe
    from autograder.service import grading, loop
    from autograder.service.journal import Journal

    marker = Path({marker!r})
    def stop(*a, **k):
        marker.write_text("here")
        time.sleep(3600)
    if {point!r} == "grade":
        grading.grade_batch = stop
    else:
        Journal.finish = stop
    svc = servicetools.reopen_service(Path({tmp!r}), probe())
    loop.run(svc, poll=0.1, rounds=1)
""")


@pytest.mark.parametrize("point", ["grade", "finish"])
def test_killed_mid_grade_then_restarted(service, q1, tmp_path, point):
    svc = service()
    folder = submit(svc, "ka123", {q1.name: honest(q1, "ka123")})
    loop.notice(svc, now=later())
    svc.journal.close()
    marker = tmp_path / "marker"
    code = CHILD.format(here=str(HERE), grading=str(HERE.parent / "grading"),
                        marker=str(marker), point=point, tmp=str(tmp_path))
    child = subprocess.Popen([sys.executable, "-c", code])
    try:
        for _ in range(6000):                # until the child is inside the grading
            if marker.exists() or child.poll() is not None:
                break
            time.sleep(0.05)
        assert marker.exists(), "the child service never reached the grading"
        os.kill(child.pid, signal.SIGKILL)
    finally:
        child.wait()
    svc.journal = Journal(svc.journal.path)                  # restart
    assert svc.journal.states()["grading"] == 1
    loop.run(svc, poll=0, rounds=1)
    assert svc.journal.states() == {"queued": 0, "grading": 0, "done": 1, "failed": 0}
    assert svc.journal.graded_since("ka123", q1.name, 0) == 1
    items = [r for r in svc.journal.attempts_rows() if r[1] == q1.name]
    # one row per graded item and written answer of the notebook: none lost, none twice
    assert sorted(r[2] for r in items) == sorted([n for n, _, _ in q1.graded]
                                                 + [g for g, _ in q1.manual])
    assert attempts_line(4, 5) in exchange_page(svc, folder, q1.name)


def test_a_crashing_sandbox_affects_only_its_student(service, q1):
    svc = service()
    target = function_names(q1)[0]
    crash = with_cell(honest(q1, "cr123"), target,
                      "import os, signal\nos.kill(os.getpid(), signal.SIGKILL)\n")
    submit(svc, "cr123", {q1.name: crash})
    submit(svc, "ok123", {q1.name: honest(q1, "ok123")})
    loop.notice(svc, now=later())
    loop.drain(svc)
    assert svc.journal.states()["done"] == 2
    rows = {(r[0], r[2]): r[4] for r in svc.journal.attempts_rows()}
    functions = [(n, p) for n, _, p in q1.graded if n in function_names(q1)]
    for name, points in functions:            # the honest student: full marks, as written
        assert rows[("ok123", name)] == pytest.approx(points)
    assert rows[("cr123", target)] == 0.0


def test_a_full_disk_keeps_the_submission_and_retries(service, q1, monkeypatch, capsys):
    svc = service()
    folder = submit(svc, "fd123", {q1.name: honest(q1, "fd123")})
    real = handout.write_atomic
    calls = []

    def full(path, text, mode=0o644):
        calls.append(path)
        if len(calls) == 1:
            raise OSError(errno.ENOSPC, "No space left on device", str(path))
        return real(path, text, mode)
    monkeypatch.setattr(handout, "write_atomic", full)
    loop.notice(svc, now=later())
    said = loop.drain(svc)
    assert said == ["fd123: disk full; kept and retried later"]
    assert "the disk is full" in capsys.readouterr().err
    assert svc.journal.states()["queued"] == 1 and svc.journal.attempts_rows() == []
    # charged before any page was written, and once: the retry does not charge again
    assert svc.journal.graded_since("fd123", q1.name, 0) == 1
    loop.drain(svc, now=later())                          # the retry, after the delay
    assert svc.journal.states()["done"] == 1
    assert svc.journal.graded_since("fd123", q1.name, 0) == 1
    assert attempts_line(4, 5) in exchange_page(svc, folder, q1.name)


def test_a_refused_submission_is_failed_with_why(service, q1):
    svc = service()
    folder = submit(svc, "ln123", {q1.name: honest(q1, "ln123")})
    os.symlink("/etc/passwd", svc.inbound / folder / "extra.ipynb")
    submit(svc, "ok123", {q1.name: honest(q1, "ok123")})
    loop.notice(svc, now=later())
    loop.drain(svc)
    states = dict(svc.journal.db.execute("SELECT student, state FROM submissions"))
    assert states == {"ln123": "failed", "ok123": "done"}
    why = svc.journal.db.execute("SELECT error FROM submissions WHERE student='ln123'"
                                 ).fetchone()[0]
    assert "symbolic link" in why


def test_grade_keeps_what_it_graded_when_stopped(tmp_path, q1, mode):
    from gradingtools import SECRET, write_nb

    from autograder.grade.batch import Options
    from autograder.isolation import Limits
    from autograder.service.incremental import grade_in_chunks, write_csv_atomic

    for s in ("aa1", "bb2", "cc3"):
        write_nb(tmp_path / "submitted" / s / "tripos2006" / f"{q1.name}.ipynb", honest(q1, s))
    out = tmp_path / "grades.csv"
    chunks = []

    def keep(batch):
        write_csv_atomic(batch, out)
        chunks.append(len(batch.students))
        if len(chunks) == 2:
            raise KeyboardInterrupt           # the time limit strikes after two students
    opts = Options(out=tmp_path, jobs=1, limits=Limits(case_timeout=1.5), secret=SECRET,
                   mode=mode, progress=False)
    with pytest.raises(KeyboardInterrupt):
        grade_in_chunks(tmp_path / "submitted", [q1], opts, on_chunk=keep, chunk=1)
    rows = list(csv.DictReader(out.open()))
    assert {r["student"] for r in rows} == {"aa1", "bb2"}
    points = {n: p for n, _, p in q1.graded}
    for r in rows:
        if r["grade_id"] in {t for _, t, _ in q1.graded}:
            name = next(n for n, t, _ in q1.graded if t == r["grade_id"])
            assert float(r["score"]) == pytest.approx(points[name]), r


def test_a_grader_failure_is_charged_once_and_retried_before_any_page(service, q1,
                                                                       monkeypatch):
    """The attempt is charged before the sandbox runs (an exception anywhere later must not
    leave it free: issue 33), no page leaves while the grader fails, and the retry that grades
    it charges nothing more."""
    import dataclasses

    from autograder.model import Status
    from autograder.service import grading

    svc = service()
    folder = submit(svc, "ge123", {q1.name: honest(q1, "ge123")})
    real = grading.grade_batch

    def failing(*args, **kwargs):
        batch = real(*args, **kwargs)
        batch.results[:] = [dataclasses.replace(r, status=Status.GRADER_ERROR, score=0.0)
                            for r in batch.results]
        return batch
    monkeypatch.setattr(grading, "grade_batch", failing)
    loop.notice(svc, now=later())
    assert loop.drain(svc) == ["ge123: grader error; retried later"]
    assert svc.journal.graded_since("ge123", q1.name, 0) == 1
    with pytest.raises(FileNotFoundError):
        exchange_page(svc, folder, q1.name)
    monkeypatch.setattr(grading, "grade_batch", real)
    loop.drain(svc, now=later())
    assert svc.journal.graded_since("ge123", q1.name, 0) == 1
    assert attempts_line(4, 5) in exchange_page(svc, folder, q1.name)


def test_a_submission_changing_after_it_was_noticed_is_retimed(service, q1):
    svc = service()
    folder = submit(svc, "ch123", {q1.name: honest(q1, "ch123")})
    loop.notice(svc, now=later())
    noticed = svc.journal.row_of(folder).ctime_ns
    path = svc.inbound / folder / f"{q1.name}.ipynb"
    for _ in range(500):          # still being written, until the kernel's clock ticks past
        with open(path, "a") as fh:        # the noticed time (ctime has a tick's resolution)
            fh.write(" ")
        if os.lstat(path).st_ctime_ns != noticed:
            break
        time.sleep(0.01)
    assert loop.drain(svc) == ["ch123: still being written; later"]
    newer = svc.journal.row_of(folder).ctime_ns
    assert newer == os.lstat(path).st_ctime_ns > noticed
    loop.drain(svc, now=later())
    assert svc.journal.states()["done"] == 1


def test_a_gradebook_down_mid_run_is_caught_up(service, q1, monkeypatch):
    from nbgrader.api import Gradebook

    from autograder.course import ASSIGNMENT
    from autograder.outputs import gradebook

    svc = service()
    submit(svc, "db123", {q1.name: honest(q1, "db123")})
    real = gradebook.sync

    def down(*args, **kwargs):
        raise ConnectionError("could not connect to server: Connection refused")
    monkeypatch.setattr(gradebook, "sync", down)
    loop.notice(svc, now=later())
    assert loop.drain(svc) == ["db123: grader error; retried later"]
    assert svc.journal.graded_since("db123", q1.name, 0) == 1     # charged, once
    monkeypatch.setattr(gradebook, "sync", real)                  # the server is back
    loop.drain(svc, now=later())
    assert svc.journal.graded_since("db123", q1.name, 0) == 1
    with Gradebook(svc.db_url, course_id="4f9") as gb:
        nb = gb.find_submission_notebook(q1.name, ASSIGNMENT, "db123")
        auto = {g.name: g.auto_score for g in nb.grades}
    for name, test_id, points in q1.graded:
        assert auto[test_id] == pytest.approx(points), name
