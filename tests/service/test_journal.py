"""The journal: nothing lost, nothing counted twice, students served in turn."""

from __future__ import annotations

import sqlite3

import pytest

from autograder.service.journal import Journal, NotebookOutcome


def _outcome(nb="q1_imaging", items=(("q1_item1", 1.0, 1.0, "ok"),)):
    return NotebookOutcome(nb, "d1", True, 1.0, 1.0, items)


def test_noticing_twice_queues_once(tmp_path):
    j = Journal(tmp_path / "j.db")
    assert j.notice("ana+tripos2006+t+1", "ana", 10)
    assert not j.notice("ana+tripos2006+t+1", "ana", 10)
    assert j.states()["queued"] == 1


def test_wal_mode(tmp_path):
    Journal(tmp_path / "j.db")
    assert sqlite3.connect(tmp_path / "j.db").execute("PRAGMA journal_mode").fetchone()[0] == "wal"


def _serve(j, n):
    order = []
    for _ in range(n):
        row = j.next_ready()
        j.start(row)
        j.finish(row, [])
        order.append(row.folder)
    return order


def test_round_robin_a_student_waits_behind_their_own(tmp_path):
    j = Journal(tmp_path / "j.db")
    for i in range(3):                       # ana submits three times before bo submits once
        j.notice(f"ana+{i}", "ana", 100 + i)
    j.notice("bo+0", "bo", 200)
    j.notice("cy+0", "cy", 300)
    assert _serve(j, 5) == ["ana+0", "bo+0", "cy+0", "ana+1", "ana+2"]
    assert j.next_ready() is None


def test_a_killed_grading_is_resumed_and_counted_once(tmp_path):
    j = Journal(tmp_path / "j.db")
    j.notice("ana+0", "ana", 5 * 10**9)
    row = j.next_ready()
    j.start(row)
    j.close()                                # killed while grading
    j = Journal(tmp_path / "j.db")           # restarted
    assert j.next_ready() is None            # still "grading" until recovered
    assert j.recover() == 1
    row = j.next_ready()
    j.start(row)
    j.finish(row, [_outcome()])
    j.finish(row, [_outcome()])              # finishing again (a repeated run) adds nothing
    assert j.graded_since("ana", "q1_imaging", 0) == 1
    assert len(j.attempts_rows()) == 1
    assert j.states()["done"] == 1 and row.tries == 1


def test_finish_is_all_or_nothing(tmp_path):
    j = Journal(tmp_path / "j.db")
    j.notice("ana+0", "ana", 1)
    row = j.next_ready()
    j.start(row)
    bad = NotebookOutcome("q1_imaging", "d", True, 1.0, 1.0, (("x", 1.0),))  # malformed item
    with pytest.raises(ValueError):
        j.finish(row, [_outcome("q2_nuclear"), bad])
    assert j.attempts_rows() == [] and j.states()["grading"] == 1


def test_postponed_until_its_time(tmp_path):
    j = Journal(tmp_path / "j.db")
    j.notice("ana+0", "ana", 1)
    row = j.next_ready()
    j.start(row)
    j.postpone(row, "disk full", 60)
    assert j.next_ready() is None
    import time
    assert j.next_ready(time.time() + 61).folder == "ana+0"


def test_a_later_submission_waits_behind_its_students_postponed_one(tmp_path):
    """ana's first submission met a gradebook that was down and waits for its retry; her second
    must not be graded before it (the first would then replace it as her last), while bo, whose
    queue holds nothing postponed, is served at once."""
    import time

    j = Journal(tmp_path / "j.db")
    j.notice("ana+0", "ana", 100)
    first = j.next_ready()
    j.start(first)
    j.postpone(first, "gradebook unreachable", 60, count_try=False)
    j.notice("ana+1", "ana", 200)
    j.notice("bo+0", "bo", 300)
    assert j.next_ready().folder == "bo+0"
    j.start(j.row_of("bo+0"))
    j.finish(j.row_of("bo+0"), [])
    assert j.next_ready() is None                        # ana+1 waits behind ana+0
    later = time.time() + 61
    assert j.next_ready(later).folder == "ana+0"
    assert j.row_of("ana+0").tries == 0                   # the gradebook's fault, not counted
    j.start(j.row_of("ana+0"))
    assert j.next_ready(later) is None                    # still behind ana+0, now grading
    j.finish(j.row_of("ana+0"), [])
    assert j.next_ready(later).folder == "ana+1"


def test_a_retry_goes_behind_a_student_not_just_served(tmp_path):
    """Students rank by their last start: ana's submission, just tried and queued again for a
    retry that is already due, waits behind bo's, never tried (issue 33: a retry re-queued at
    the head of the queue, 53 times in 60 s)."""
    import time

    j = Journal(tmp_path / "j.db")
    j.notice("bo+0", "bo", 50)                  # bo was served once before
    j.start(j.next_ready())
    j.finish(j.row_of("bo+0"), [])
    j.notice("ana+0", "ana", 100)
    j.start(j.next_ready())
    j.postpone(j.row_of("ana+0"), "grader error", 0)
    j.notice("bo+1", "bo", 200)
    assert j.next_ready(time.time() + 1).folder == "bo+1"


def test_a_charge_is_recorded_once_and_outlives_a_failure(tmp_path):
    j = Journal(tmp_path / "j.db")
    j.notice("ana+0", "ana", 10**9)
    row = j.next_ready()
    j.start(row)
    j.charge(row, [("q1_imaging", "d1", True), ("q2_nuclear", "d2", False)])
    j.charge(row, [("q1_imaging", "d1", True), ("q2_nuclear", "d2", False)])   # a retry
    assert j.charged(row) == {"q1_imaging"}
    assert j.graded_since("ana", "q1_imaging", 0) == 1
    assert j.graded_since("ana", "q2_nuclear", 0) == 0
    assert j.graded_since("ana", "q1_imaging", 0, other_than=row.id) == 0
    assert j.last_digest("ana", "q1_imaging") == "d1"
    assert j.last_digest("ana", "q1_imaging", other_than=row.id) is None
    j.fail(row, "out of tries")
    assert j.graded_since("ana", "q1_imaging", 0) == 1        # still charged ...
    score = j.db.execute("SELECT score FROM notebooks WHERE notebook='q1_imaging'").fetchone()
    assert score == (0.0,)                                    # ... and scored 0


def test_the_time_reserved_by_a_try_is_kept_unless_the_service_was_killed(tmp_path):
    j = Journal(tmp_path / "j.db")
    j.notice("ana+0", "ana", 1)
    row = j.next_ready()
    j.start(row)
    j.reserve(row, 30.0)
    assert j.spent(row) == 30.0
    j.close()                                   # the service is killed mid-try
    j = Journal(tmp_path / "j.db")
    assert j.recover() == 1 and j.spent(row) == 0.0           # its stop is no student's doing
    j.start(row)
    j.reserve(row, 30.0)                        # this try's worker dies: nothing settles it
    j.postpone(row, "worker died", 0)
    j.start(row)                                # the next try keeps what the dead one held
    j.spend(row, 5.0)
    assert j.spent(row) == 35.0
    j.close()
    j = Journal(tmp_path / "j.db")
    j.recover()
    assert j.spent(row) == 35.0                 # nothing reserved any more: nothing given back
