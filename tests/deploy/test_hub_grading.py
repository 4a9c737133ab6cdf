"""The grading service on the course's real hub, and a deadline burst of 30 real Unix users.

The hub ``deploy/hub.py`` prepares runs ``python -m autograder watch`` as a managed service of
the grader account (``deploy/jupyterhub_config.py``). Students, each their own Unix user
(``runuser``), fetch and submit with nbgrader's own commands in the students' environment, and
read their feedback with ``nbgrader fetch_feedback``: no instructor command is run.

- **alone**: three students submit one after the other, each when the service is idle; each gets
  a page per notebook, fetchable, saying "4 of 5 graded attempts left today";
- **burst**: 30 students submit within 60 seconds (one every two seconds) while another logs in
  through the hub's login form three times (during the submits and the drain); every
  submission is graded exactly once (one journal row, one try, every notebook recorded once),
  started in the order the exchange saw them, and its pages reach the exchange's feedback
  folder; every login succeeds.

Submit -> feedback-fetchable latency is measured from the submission's own time (the kernel's
ctime, as the journal holds it) to the newest of its pages in the exchange; the numbers go to
``test-artifacts/deploy/hub-burst.json`` (``python -m benchmarks --only bench_hub_burst`` runs
this module and prints them). About 10 minutes on the 2-core machine once the environments are
cached (``tests/deploy/conftest.py``); the first run builds them (about 15 minutes more).
Two of the 30 log in and submit in Chromium (the Assignments panel, as ``test_hub_term.py``
does); the other 28 use ``nbgrader submit``.
"""

from __future__ import annotations

import concurrent.futures
import json
import os
import re
import sqlite3
import statistics
import threading
import time
from pathlib import Path

import pytest
from hubtools import ARTIFACTS, BURST, CHROMIUM, LONE

import hub  # deploy/hub.py

# the first run builds the two environments inside the fixture (about 15 minutes)
pytestmark = [pytest.mark.xdist_group("hub"), pytest.mark.slow, pytest.mark.browser,
              pytest.mark.timeout(3600)]

A = "tripos2006"
NOTEBOOKS = ("q1_imaging", "q2_nuclear", "q3_marching_cubes", "q4_splines", "q5_phong",
             "q6_clipping")
ALONE = LONE[0]
RESULTS = ARTIFACTS / "hub-burst.json"
#: two of the burst submit in Chromium, through the Assignments panel (the others with
#: ``nbgrader submit``)
IN_BROWSER = BURST[:2]
#: seconds between two students' submits in the burst: 30 students within 60 s
SPACING = 2.0
#: how long the test waits for the service (not a speed target: bench_hub_burst reports speed)
PATIENCE = 900.0


def _student(settings, user: str, *args: str) -> str:
    """``nbgrader ARGS`` as ``user`` in the students' environment; its output."""
    env_dir = settings.paths["student_env"]
    proc = hub.as_user(user, [f"{env_dir}/bin/python", "-m", "nbgrader", *args],
                       env={"PATH": f"{env_dir}/bin:/usr/bin:/bin", "VIRTUAL_ENV": env_dir,
                            "JUPYTER_CONFIG_PATH": settings.paths["student_config"]},
                       timeout=300)
    assert proc.returncode == 0 and "[ERROR]" not in proc.stderr, (user, args, proc.stderr[-3000:])
    return proc.stdout + proc.stderr


def _journal(settings) -> sqlite3.Connection:
    path = Path(settings.paths["course_dir"]) / "service" / "journal.db"
    return sqlite3.connect(str(path), timeout=30)


def _rows(settings, users) -> dict[str, list[tuple]]:
    """``{student: [(folder, ctime_ns, state, tries, started, finished), ...]}``."""
    marks = ",".join("?" * len(users))
    got: dict[str, list[tuple]] = {u: [] for u in users}
    try:
        with _journal(settings) as db:
            for row in db.execute(
                    "SELECT student, folder, ctime_ns, state, tries, started, finished FROM "
                    f"submissions WHERE student IN ({marks}) ORDER BY ctime_ns", tuple(users)):
                got[row[0]].append(row[1:])
    except sqlite3.OperationalError:       # the service has not made its journal yet
        pass
    return got


def _pages(settings, folder: str) -> list[Path]:
    """The submission ``folder``'s pages in the exchange's feedback folder (what
    ``fetch_feedback`` looks up, by the submission's secret)."""
    from nbgrader.utils import notebook_hash

    exchange = Path(settings.paths["exchange"]) / settings.course_id
    secret = (exchange / "inbound" / folder / "submission_secret.txt").read_text()
    return [exchange / "feedback" / f"{notebook_hash(secret=secret, notebook_id=nb)}.html"
            for nb in NOTEBOOKS]


def _wait_done(settings, users, count: int) -> dict[str, list[tuple]]:
    """Until each of ``users`` has ``count`` submissions settled (done or failed)."""
    deadline = time.monotonic() + PATIENCE
    while time.monotonic() < deadline:
        rows = _rows(settings, users)
        if all(len(r) >= count and all(x[2] in ("done", "failed") for x in r)
               for r in rows.values()):
            return rows
        time.sleep(1.0)
    log = Path(settings.paths["course_dir"]) / "service" / "watch.log"
    pytest.fail(f"not graded within {PATIENCE:g} s: {_rows(settings, users)}\n"
                f"{log.read_text(errors='replace')[-4000:] if log.exists() else 'no watch.log'}")


def _wait_ready(settings) -> None:
    """Until the service has measured its budgets (its start-up) and is watching."""
    log = Path(settings.paths["course_dir"]) / "service" / "watch.log"
    deadline = time.monotonic() + PATIENCE
    while time.monotonic() < deadline:
        if log.exists() and "time budget per notebook" in log.read_text(errors="replace"):
            return
        time.sleep(1.0)
    pytest.fail(f"the service never started: {log.read_text()[-3000:] if log.exists() else ''}")


def _latency(settings, row: tuple) -> float:
    """Seconds from the submission's time to its newest page in the exchange."""
    pages = _pages(settings, row[0])
    assert all(p.is_file() for p in pages), [p for p in pages if not p.is_file()]
    return max(p.stat().st_mtime for p in pages) - row[1] / 1e9


def _login(url: str, user: str, password: str) -> tuple[bool, float]:
    """A login through the hub's form (PAM): whether it succeeded, and its seconds. The
    redirect is not followed (it would start the user's server)."""
    import requests

    t0 = time.perf_counter()
    with requests.Session() as s:
        form = s.get(f"{url}/hub/login", timeout=120)
        xsrf = re.search(r'name="_xsrf"\s+value="([^"]+)"', form.text)
        data = {"username": user, "password": password}
        if xsrf:
            data["_xsrf"] = xsrf.group(1)
        resp = s.post(f"{url}/hub/login", data=data, allow_redirects=False, timeout=120)
        ok = resp.status_code == 302 and any("hub-login" in c.name for c in s.cookies)
    return ok, time.perf_counter() - t0


def _service_processes(settings) -> list[tuple[int, int, int]]:
    """``(pid, uid, gid)`` of each ``autograder watch`` process serving this hub's course."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            args = (entry / "cmdline").read_bytes().split(b"\0")
            st = entry.stat()
        except OSError:
            continue
        if b"watch" in args and settings.paths["course_dir"].encode() in args \
                and any(a.endswith(b"python") for a in args[:1]):
            found.append((int(entry.name), st.st_uid, st.st_gid))
    return found


@pytest.fixture(scope="module")
def measured():
    """What the module measured, written for ``bench_hub_burst`` at its end."""
    got: dict = {}
    yield got
    RESULTS.write_text(json.dumps(got, indent=1) + "\n")


def test_the_service_runs_as_root_with_the_graders_group_and_answers_alone(grading_hub,
                                                                           measured):
    from autograder.service.policy import attempts_line

    settings = grading_hub["settings"]
    procs = _service_processes(settings)
    assert procs, "no `autograder watch` process serves the hub's course"
    # root: every sandbox job gets a uid and a cgroup of its own (deploy/jupyterhub_config.py)
    grader_gid = hub.grp.getgrnam(settings.grader).gr_gid
    assert {(uid, gid) for _, uid, gid in procs} == {(0, grader_gid)}, procs
    _wait_ready(settings)       # measured alone: not behind the service's start-up
    lone = []
    for user in LONE:
        _student(settings, user, "fetch_assignment", A)
        _student(settings, user, "submit", A)
        rows = _wait_done(settings, [user], 1)[user]
        assert [r[2:4] for r in rows] == [("done", 1)], rows
        lone.append(_latency(settings, rows[0]))
    # the student reads the pages with nbgrader's own fetch_feedback: no instructor command
    said = _student(settings, ALONE, "fetch_feedback", A)
    fetched = sorted((Path(hub.home_of(ALONE)) / A / "feedback").glob("*/*.html"))
    assert sorted(p.stem for p in fetched) == sorted(NOTEBOOKS), said
    page = fetched[0].read_text(encoding="utf-8")
    assert attempts_line(4, 5) in page and ALONE in page
    # a classmate can neither list the exchange's pages nor so find this student's
    feedback = Path(settings.paths["exchange"]) / settings.course_id / "feedback"
    proc = hub.as_user(LONE[1], ["ls", feedback])
    assert proc.returncode != 0 and "Permission denied" in proc.stderr, proc.stdout[:300]
    measured["alone_latency_s"] = lone


def _in_browser(grading_hub, ready: threading.Event, go: dict) -> list[float]:
    """:data:`IN_BROWSER` in Chromium, in a thread of its own (Playwright's sync API): log in
    through the hub's form and fetch in the Assignments panel, then set ``ready``; once
    ``go["start"]`` is given, press Submit for each at its time in the burst (as
    ``test_hub_term`` does). The submits' end times."""
    from playwright.sync_api import sync_playwright
    from test_hub_term import CHROMIUM_ARGS, _fetch, _submit
    from test_hub_term import _login as _browser_login

    url, passwords = grading_hub["url"], grading_hub["passwords"]
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
        try:
            pages = [_browser_login(browser, url, u, passwords[u]) for u in IN_BROWSER]
            for page, user in zip(pages, IN_BROWSER):
                _fetch(page, user)
            ready.set()
            while "start" not in go:
                time.sleep(0.1)
            ends = []
            for page, user in zip(pages, IN_BROWSER):
                time.sleep(max(0.0, go["start"] + BURST.index(user) * SPACING - time.time()))
                _submit(page, user)
                ends.append(time.time())
            return ends
        finally:
            browser.close()


def _burst(grading_hub, start: float) -> tuple[list[float], list[tuple[bool, float]]]:
    """The submits of all but :data:`IN_BROWSER`, one every :data:`SPACING` s from ``start``,
    with three logins meanwhile; the submits' end times and the logins' results."""
    settings, url = grading_hub["settings"], grading_hub["url"]

    def submit(i: int, user: str) -> float:
        time.sleep(max(0.0, start + i * SPACING - time.time()))
        _student(settings, user, "submit", A)
        return time.time()

    def login(at: float) -> tuple[bool, float]:
        time.sleep(max(0.0, start + at - time.time()))
        return _login(url, ALONE, grading_hub["passwords"][ALONE])

    # a thread for each: every one sleeps until its own time
    with concurrent.futures.ThreadPoolExecutor(len(BURST) + 3) as pool:
        submits = [pool.submit(submit, i, u) for i, u in enumerate(BURST)
                   if u not in IN_BROWSER]
        logins = [pool.submit(login, at) for at in (20.0, 40.0, 75.0)]
        return [f.result() for f in submits], [f.result() for f in logins]


def test_a_deadline_burst_of_30_students(grading_hub, measured):
    settings = grading_hub["settings"]
    ready, go = threading.Event(), {}
    with concurrent.futures.ThreadPoolExecutor(1) as chromium:
        browsing = chromium.submit(_in_browser, grading_hub, ready, go)
        with concurrent.futures.ThreadPoolExecutor(4) as pool:  # fetching is not the burst
            list(pool.map(lambda u: _student(settings, u, "fetch_assignment", A),
                          [u for u in BURST if u not in IN_BROWSER]))
        while not ready.wait(1.0):
            if browsing.done():
                browsing.result()                               # its failure, raised here
        idle = [_login(grading_hub["url"], ALONE, grading_hub["passwords"][ALONE])
                for _ in range(3)]
        assert all(ok for ok, _ in idle), idle
        start = time.time() + 1.0
        go["start"] = start
        ends, logins = _burst(grading_hub, start)
        ends += browsing.result()
    rows = _wait_done(settings, BURST, 1)
    assert all(ok for ok, _ in logins), logins
    # every submission once: one row per student, done at its first try
    assert all(len(rows[u]) == 1 for u in BURST), rows
    burst_rows = [rows[u][0] for u in BURST]
    assert all(r[2:4] == ("done", 1) for r in burst_rows), burst_rows
    # started in the order the exchange saw them (the kernel's ctime)
    by_time = sorted(burst_rows, key=lambda r: r[1])
    assert [r[4] for r in by_time] == sorted(r[4] for r in by_time)
    # every notebook recorded once, graded (all six are new for each of them)
    with _journal(settings) as db:
        for user in BURST:
            counts = dict(db.execute(
                "SELECT notebook, COUNT(*) FROM notebooks WHERE student=? AND graded=1 "
                "GROUP BY notebook", (user,)))
            assert counts == {nb: 1 for nb in NOTEBOOKS}, (user, counts)
    latencies = [_latency(settings, r) for r in burst_rows]
    # and fetchable by the student, with nbgrader's own command
    for user in (BURST[0], BURST[len(BURST) // 2]):
        _student(settings, user, "fetch_feedback", A)
        got = {p.stem for p in (Path(hub.home_of(user)) / A / "feedback").glob("*/*.html")}
        assert got == set(NOTEBOOKS), (user, got)
    measured.update({
        "burst_latency_s": latencies, "burst_students": len(BURST),
        "burst_submits_ended_s": max(ends) - start,
        "burst_submitted_within_s": (max(r[1] for r in burst_rows)
                                     - min(r[1] for r in burst_rows)) / 1e9,
        "burst_drained_s": max(r[5] for r in burst_rows) - min(r[1] / 1e9 for r in burst_rows),
        "login_s": [t for _, t in logins], "login_idle_s": [t for _, t in idle],
        "load_avg_1min": os.getloadavg()[0],
        "cpus": os.cpu_count()})
    assert statistics.median(latencies) > 0
