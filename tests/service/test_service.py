"""The service end to end: gradebook as the policy says, pages where Fetch Feedback looks,
unchanged notebooks free, the time budget, and ``python -m autograder watch``."""

from __future__ import annotations

import os
from dataclasses import replace

import pytest
from gradingtools import function_names
from servicetools import auto_scores, exchange_page, honest, later, submit, with_cell

from autograder.course import ASSIGNMENT
from autograder.service import budget, loop
from autograder.service.policy import Policy, attempts_line


def _broken(src, student):
    """``src``'s model answer with its first graded function returning None."""
    name = function_names(src)[0]
    return name, with_cell(honest(src, student), name, f"def {name}(*a, **k):\n    return None\n")


@pytest.mark.parametrize("counts", ["last", "best"])
def test_the_gradebook_keeps_what_the_policy_counts(service, q1, counts):
    svc = service(counts=counts)
    name, broken = _broken(q1, "gb123")
    test_id = next(t for n, t, _ in q1.graded if n == name)
    points = next(p for n, _, p in q1.graded if n == name)
    submit(svc, "gb123", {q1.name: honest(q1, "gb123")})
    loop.notice(svc, now=later())
    loop.drain(svc)
    assert auto_scores(svc, "gb123", q1.name)[test_id] == pytest.approx(points)
    submit(svc, "gb123", {q1.name: broken})       # a worse attempt afterwards
    loop.notice(svc, now=later())
    loop.drain(svc)
    expected = points if counts == "best" else 0.0
    assert auto_scores(svc, "gb123", q1.name)[test_id] == pytest.approx(expected)
    assert (svc.course / "submitted" / "gb123" / ASSIGNMENT / "timestamp.txt").is_file()


def test_pages_land_where_fetch_feedback_looks(service, q1):
    svc = service()
    folder = submit(svc, "pg123", {q1.name: honest(q1, "pg123")})
    loop.notice(svc, now=later())
    loop.drain(svc)
    local = svc.course / "feedback" / "pg123" / ASSIGNMENT
    assert {p.name for p in local.iterdir()} >= {f"{q1.name}.html", "timestamp.txt",
                                                 "submission_secret.txt"}
    assert exchange_page(svc, folder, q1.name) == (local / f"{q1.name}.html").read_text()
    # the time on record is the kernel's (the folder's ctime), not the student's timestamp.txt
    stamp = (local / "timestamp.txt").read_text()
    ctime = os.lstat(svc.inbound / folder).st_ctime
    import datetime as dt
    on_record = dt.datetime.strptime(stamp, "%Y-%m-%d %H:%M:%S.%f %Z")
    assert abs(on_record.replace(tzinfo=dt.timezone.utc).timestamp() - ctime) < 1.0


def test_an_unchanged_notebook_costs_no_attempt(service, sources, q1):
    svc = service(attempts=2)
    other = next(s for s in sources if s.name != q1.name)
    first = {q1.name: honest(q1, "un123"), other.name: honest(other, "un123")}
    submit(svc, "un123", first)
    loop.notice(svc, now=later())
    loop.drain(svc)
    _name, broken = _broken(other, "un123")
    folder = submit(svc, "un123", {q1.name: first[q1.name], other.name: broken})
    loop.notice(svc, now=later())
    loop.drain(svc)
    assert svc.journal.graded_since("un123", q1.name, 0) == 1
    assert svc.journal.graded_since("un123", other.name, 0) == 2
    assert attempts_line(0, 2) in exchange_page(svc, folder, other.name)
    # the unchanged notebook's last graded page comes with this submission too, line updated
    again = exchange_page(svc, folder, q1.name)
    assert attempts_line(1, 2) in again and "Hidden cases" in again


def test_budgets_come_from_the_reference_cost(q1, mode):
    from gradingtools import SECRET

    from autograder.grade.batch import Options

    costs = budget.measure([q1], Options(out=None, secret=SECRET, mode=mode, progress=False))
    assert 0 < costs[q1.name] < 120
    got = budget.budgets({"a": 0.5, "b": 7.0}, Policy(margin=10, floor_seconds=20))
    assert got == {"a": 20.0, "b": 70.0}


def test_a_budget_leaves_room_for_two_graded_functions_to_hang(q1):
    """Two graded functions may hang (each stopped after three cases of the per-case limit's
    wall-clock backstop, three times the limit since a sleeping case spends no CPU time, plus
    the supervisor's one-second grace each) and the notebook's budget still reaches the next
    function, so a hang costs only its own points (as under ``grade``); a notebook of one
    function gets room for one."""
    functions = function_names(q1)      # choice and number items run no student code
    assert 2 <= len(functions) < len(q1.graded)
    allowance = budget.hang_allowance([q1], case_timeout=10.0)
    assert allowance == {q1.name: pytest.approx(2 * 3 * (3 * 10.0 + 1.0))}
    got = budget.budgets({q1.name: 1.0}, Policy(margin=10, floor_seconds=20), allowance)
    assert got[q1.name] == pytest.approx(20.0 + 2 * 93.0)
    one = replace(q1, graded=[g for g in q1.graded if g.name == functions[0]])
    assert budget.hang_allowance([one], case_timeout=10.0) == {q1.name: pytest.approx(93.0)}


def test_watch_once_from_the_command_line(tmp_path, q1, mode, capsys, monkeypatch):
    from autograder.__main__ import main
    from autograder.service import inbox

    monkeypatch.setattr(inbox, "SETTLE_SECONDS", 0.0)   # no waiting for the folder to settle

    course, exchange = tmp_path / "course", tmp_path / "exchange"
    (exchange / "4f9" / "inbound").mkdir(parents=True)
    course.mkdir()
    (course / "grading_service.json").write_text('{"attempts": 3}')

    from types import SimpleNamespace     # what servicetools.submit and exchange_page need
    Svc = SimpleNamespace(inbound=exchange / "4f9" / "inbound", exchange=exchange)
    folder = submit(Svc, "root", {q1.name: honest(q1, "root")})   # the tests run as root
    (tmp_path / "secret").write_text("watch-test-secret\n")
    status = main(["watch", "--exchange", str(exchange), "--course", str(course),
                   "--no-gradebook", "--reference-seconds", "2", "--once", "--poll", "0",
                   "--secret-file", str(tmp_path / "secret"), "--source", str(q1.path.parent)])
    err = capsys.readouterr().err
    assert status == 0, err
    # the floor (20 s) plus room for two graded functions to hang: 3 cases of the 10 s limit's
    # 30 s wall-clock backstop + 1 s grace
    budget_q1 = 20 + 2 * 3 * (3 * 10 + 1)
    assert "time budget per notebook" in err and f"q1_imaging {budget_q1} s" in err
    assert "root: graded q1_imaging" in err
    assert exchange_page(Svc, folder, q1.name).count(attempts_line(2, 3)) == 1
    assert attempts_line(2, 3) in (course / "feedback" / "root" / ASSIGNMENT /
                                   f"{q1.name}.html").read_text()


def test_watch_refuses_a_bad_policy(tmp_path, capsys):
    from autograder.__main__ import main

    (tmp_path / "exchange" / "4f9" / "inbound").mkdir(parents=True)
    (tmp_path / "grading_service.json").write_text('{"attempts": -1}')
    status = main(["watch", "--exchange", str(tmp_path / "exchange"), "--course",
                   str(tmp_path), "--once"])
    assert status == 2 and "attempts" in capsys.readouterr().err


def test_a_second_watch_on_the_same_course_is_refused(tmp_path):
    from autograder.service.cli import hold_lock

    first = hold_lock(tmp_path)
    with pytest.raises(ValueError, match="already serving"):
        hold_lock(tmp_path)
    first.close()
    hold_lock(tmp_path).close()            # free again once the first has stopped


def test_a_batch_stays_within_what_is_left_of_its_submissions_budget():
    """Six notebooks two at a time are three waves: each wave gets at most the largest
    notebook budget and the three together at most what is left (computed by hand here)."""
    from autograder.service.tries import retry_delay

    assert budget.submission_budget({"a": 10.0, "b": 20.0}, ["a", "b", "c"], 5.0) == 35.0
    assert budget.batch_timeout(left=60.0, notebooks=6, jobs=2, longest=10.0) == (10.0, 3)
    assert budget.batch_timeout(left=15.0, notebooks=6, jobs=2, longest=10.0) == (5.0, 3)
    assert budget.batch_timeout(left=15.0, notebooks=1, jobs=2, longest=10.0) == (10.0, 1)
    with pytest.raises(ValueError):
        budget.batch_timeout(left=15.0, notebooks=0, jobs=2, longest=10.0)
    assert [retry_delay(60.0, k) for k in (1, 2, 3, 4)] == [60.0, 120.0, 240.0, 480.0]
    with pytest.raises(ValueError):
        retry_delay(60.0, 0)
