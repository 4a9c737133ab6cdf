"""A PostgreSQL gradebook stopped while the service grades, then started again, is caught up
(docs/grading-service.md, "Guarantees"): on a real server (tests/postgres.py), stopped as a
crash would stop it (``pg_ctl -m immediate``) between the sandbox's grading and the gradebook's
write. The submissions that meet it down stay queued and are retried, each student's in the
order they were handed in; when the server is back the gradebook holds every student's right
scores (the last submission's, by the default policy), no submission is lost, and no attempt is
counted twice nor charged for the tries the gradebook failed."""

from __future__ import annotations

import pytest
from gradingtools import function_names, points_of
from servicetools import (auto_scores, exchange_page, honest, later, make_service, submit,
                          with_cell)

from autograder.service import grading, loop
from autograder.service.policy import attempts_line

pytestmark = [pytest.mark.slow, pytest.mark.timeout(900)]
DOWN = "gradebook unreachable; kept and retried later"


@pytest.fixture
def pg_server():
    from postgres import PostgresUnavailable, start_server

    try:
        server = start_server()
    except PostgresUnavailable as exc:
        pytest.skip(str(exc))
    yield server
    server.stop()


def test_a_postgres_gradebook_restarted_mid_run_is_caught_up(tmp_path, sources, q1, mode,
                                                             pg_server, monkeypatch):
    from postgres import fresh_database

    from autograder.outputs.gradebook import register_cells

    url = fresh_database(pg_server.url(), "service_restart")
    register_cells(url, sources)
    svc = make_service(tmp_path, sources, mode, None)
    svc.db_url = url
    target = function_names(q1)[0]
    # pg123's first try leaves one graded function broken; her second is the model answer
    broken = with_cell(honest(q1, "pg123"), target,
                       f"def {target}(*args, **kwargs):\n    return None\n")
    first = submit(svc, "pg123", {q1.name: broken})

    real = grading.grade_batch

    def grade_then_crash_the_server(*args, **kwargs):
        batch = real(*args, **kwargs)
        pg_server.halt()                  # the sandbox has graded; the gradebook is gone
        return batch
    monkeypatch.setattr(grading, "grade_batch", grade_then_crash_the_server)
    loop.notice(svc, now=later())
    assert loop.drain(svc) == [f"pg123: {DOWN}"]
    monkeypatch.setattr(grading, "grade_batch", real)

    # the server is still down: a new submission waits too, costing no sandbox time
    other = submit(svc, "pq456", {q1.name: honest(q1, "pq456")})
    loop.notice(svc, now=later())
    assert loop.drain(svc) == [f"pq456: {DOWN}"]
    # pg123's attempt was charged before the sandbox ran; pq456's try stopped before anything
    assert svc.journal.graded_since("pg123", q1.name, 0) == 1
    assert svc.journal.graded_since("pq456", q1.name, 0) == 0
    assert svc.journal.states()["queued"] == 2

    pg_server.resume()
    second = submit(svc, "pg123", {q1.name: honest(q1, "pg123")})
    loop.notice(svc, now=later())
    # pg123's second waits behind her first (postponed for its retry), not graded before it
    assert loop.drain(svc) == []
    said = loop.drain(svc, now=later())                # the retries are due
    assert sorted(said) == sorted([f"pg123: graded {q1.name}", f"pq456: graded {q1.name}",
                                   f"pg123: graded {q1.name}"])
    assert svc.journal.states() == {"queued": 0, "grading": 0, "done": 3, "failed": 0}

    # the gradebook: the model answers' full points, so pg123's second submission counted
    # last, after her first (whose broken function scores 0)
    for student in ("pg123", "pq456"):
        scores = auto_scores(svc, student, q1.name)
        for name, test_id, points in q1.graded:
            assert scores[test_id] == pytest.approx(points), (student, name)
    assert points_of(q1, target) > 0
    # attempts: one per graded submission, each item once; the retries charged nothing more
    assert svc.journal.graded_since("pg123", q1.name, 0) == 2
    assert svc.journal.graded_since("pq456", q1.name, 0) == 1
    items = sorted([n for n, _, _ in q1.graded] + [g for g, _ in q1.manual])
    rows = svc.journal.attempts_rows()
    for student, times in (("pg123", 2), ("pq456", 1)):
        mine = sorted(r[2] for r in rows if r[0] == student and r[1] == q1.name)
        assert mine == sorted(items * times), student
    assert attempts_line(4, 5) in exchange_page(svc, first, q1.name)
    assert attempts_line(3, 5) in exchange_page(svc, second, q1.name)
    assert attempts_line(4, 5) in exchange_page(svc, other, q1.name)
    broken_score = [r[4] for r in rows if r[0] == "pg123" and r[2] == target]
    assert sorted(broken_score) == pytest.approx([0.0, points_of(q1, target)])
