"""A determined student against the service (issue 33, findings 4 and 9): no graded page without
a charged attempt, no free retries, nobody delayed by another's tries, nothing huge read.

The grader is replaced here by a stand-in (:class:`Grader`) that answers as the real one does
for the notebooks it is given: full marks for the model answers, and ``grader-error`` on every
test of a notebook the student broke it with (the symptom of finding 3: one line in a solution
cell that makes the grader's decoding raise). A notebook that "sleeps" uses its whole job time
limit, on a clock of the test's own, so the time each submission is allowed is counted exactly
and nothing waits on the wall clock. The submissions are the model answers, handed in as
nbgrader's submit writes them.
"""

from __future__ import annotations

import json
import os
import time
import tracemalloc

import pytest
from servicetools import exchange_page, honest, later, submit, with_cell

from autograder.grade.batch import graded_row
from autograder.model import Batch, CellKind, Status
from autograder.exercises import REGISTRY
from autograder.service import grading, handout, inbox, loop, pages

#: a function of q5 and of q6 whose solution cell the tests edit
BROKEN_MARK = "# breaks the grader's decoding\n"
SLEEP_MARK = "# sleeps until stopped\n"


class Grader:
    """A stand-in for ``grade_batch`` (see the module docstring); ``calls`` records each call:
    ``(student, [notebooks], job timeout, waves)``; ``clock`` is the time the sleepers used."""

    def __init__(self):
        self.calls, self.clock, self.listed = [], 0.0, []

    def __call__(self, submitted, sources, opts, students):
        (student,) = students
        folder = submitted / student / "tripos2006"
        self.listed.append(sorted(p.name for p in folder.iterdir()))
        texts = {s.name: (folder / f"{s.name}.ipynb").read_text() for s in sources}
        timeout = opts.limits.job_timeout
        waves = -(-len(sources) // max(1, opts.jobs))
        self.calls.append((student, [s.name for s in sources], timeout, waves))
        if any(SLEEP_MARK.strip() in t for t in texts.values()):
            self.clock += timeout * waves          # each wave held until its time limit
        rows = []
        for src in sources:
            broken = BROKEN_MARK.strip() in texts[src.name]
            for test in src.graded:
                kind = REGISTRY[test.name].kind if test.name in REGISTRY else CellKind.FUNCTION
                status = Status.GRADER_ERROR if broken else Status.OK
                rows.append(graded_row(student, src.name, test, status, "",
                                       score=0.0 if broken else test.points,
                                       kind=CellKind(kind)))
        return Batch(rows, {}, [student])


@pytest.fixture
def grader(monkeypatch):
    stand_in = Grader()
    monkeypatch.setattr(grading, "grade_batch", stand_in)
    try:        # the time a try takes is the stand-in's (main, before issue 33, had no clock)
        from autograder.service import tries
    except ImportError:
        return stand_in
    monkeypatch.setattr(tries, "clock", lambda: stand_in.clock)
    return stand_in


def _by_name(sources, name):
    return next(s for s in sources if s.name == name)


def _edited(src, student, mark, k=0):
    """``src``'s model answer with ``mark`` (and a version number) atop its first function."""
    name = next(n for n, _, _ in src.graded if REGISTRY[n].kind == "function")
    nb = honest(src, student)
    cell = next(c for c in nb["cells"] if c.get("metadata", {}).get("nbgrader", {})
                .get("grade_id") == name)
    text = "".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]
    return with_cell(nb, name, f"{mark}# version {k}\n{text}")


def _graded_page(html: str) -> bool:
    """Whether a page shows grading results (a graded function's status badge)."""
    return "class='badge " in html


@pytest.mark.parametrize("crash", ["grader-error", "page"])
def test_a_notebook_that_breaks_the_grading_gets_no_free_graded_page(service, sources, grader,
                                                                    monkeypatch, crash):
    """Finding 4: q6 breaks the grading after q5's page would be written. Every graded page
    leaves only after its attempt is charged, and with 2 attempts a day three such submissions
    get at most 2 graded pages of q5 (main: 3, and no attempt charged)."""
    q5, q6 = _by_name(sources, "q5_phong"), _by_name(sources, "q6_clipping")
    svc = service(attempts=2)
    if crash == "page":          # the grading step itself raises on q6, after q5's page
        real_page = pages.open_page

        def render(student, notebook, rows, line):
            if notebook == q6.name:
                raise RuntimeError("rendering q6 failed")
            return real_page(student, notebook, rows, line)
        monkeypatch.setattr(pages, "open_page", render)
    sent = []
    real_hand_out = handout.hand_out

    def hand_out(course, exchange, collected, student, notebook, html):
        # at the moment a page leaves, how many attempts of its notebook were charged
        sent.append((notebook, _graded_page(html),
                     svc.journal.graded_since(student, notebook, 0)))
        return real_hand_out(course, exchange, collected, student, notebook, html)
    monkeypatch.setattr(handout, "hand_out", hand_out)
    folders = []
    for k in range(3):
        six = _edited(q6, "br123", BROKEN_MARK if crash == "grader-error" else "", k)
        folders.append(submit(svc, "br123", {q5.name: _edited(q5, "br123", "", k),
                                             q6.name: six}))
        loop.notice(svc, now=later())
        loop.drain(svc, now=later())        # every retry, at once
    graded_q5 = [f for f in folders if _graded_page(exchange_page(svc, f, q5.name))]
    # grader-error: the last try scores q6 0 and hands q5's page; a page that cannot be made:
    # the submission fails whole, with a page saying so
    assert len(graded_q5) == (2 if crash == "grader-error" else 0)
    assert svc.journal.graded_since("br123", q5.name, 0) == 2
    assert svc.journal.graded_since("br123", q6.name, 0) == 2
    shown = [n for n, graded, _ in sent if graded and n == q5.name]
    assert len(shown) == len(graded_q5)      # one graded page per charged attempt, no more
    for i, (notebook, graded, charged) in enumerate(sent):
        if graded:                           # charged before it left
            earlier = sum(1 for n, g, _ in sent[:i] if g and n == notebook)
            assert charged > earlier, sent
    # the third submission is over the day's attempts: recorded, not graded
    assert "no graded attempt is left today" in exchange_page(svc, folders[2], q5.name)
    # the sandbox ran each charged submission a limited number of times
    assert len(grader.calls) <= 2 * grading.MAX_TRIES


def test_sleepers_and_retries_hold_the_worker_for_one_budget_and_go_behind(service, sources,
                                                                          grader):
    """Finding 9: two students hand in five sleeping notebooks each, plus q6 broken so that
    every try is retried; a third student hands in one honest notebook after them. All the
    tries of a sleeping submission together are allowed its one budget (the sum of its
    notebooks'), and the honest student's grading starts after one try of each of the two,
    never behind their retries (main: 25 budgets' worth, and the retries first)."""
    svc = service()
    budget_each = 10.0
    svc.budgets = {s.name: budget_each for s in sources}
    five = [s for s in sources if s.name != "q6_clipping"][:5]
    q6 = _by_name(sources, "q6_clipping")
    for student in ("sa123", "sb123"):
        nbs = {s.name: _edited(s, student, SLEEP_MARK) for s in five}
        nbs[q6.name] = _edited(q6, student, BROKEN_MARK)
        submit(svc, student, nbs)
    q1 = _by_name(sources, "q1_imaging")
    submit(svc, "hn123", {q1.name: honest(q1, "hn123")})
    loop.notice(svc, now=later())
    loop.drain(svc, now=later())
    students = [c[0] for c in grader.calls]
    first_honest = students.index("hn123")
    assert sorted(students[:first_honest]) == ["sa123", "sb123"]   # one try of each, no more
    whole = budget_each * 6                  # the submission's budget: its six notebooks'
    for student in ("sa123", "sb123"):
        allowed = sum(timeout * waves for s, _, timeout, waves in grader.calls if s == student)
        assert allowed <= whole + 1e-6, (student, allowed)
        row = svc.journal.db.execute("SELECT state, spent FROM submissions WHERE student=?",
                                     (student,)).fetchone()
        assert row[0] == "failed" and row[1] <= whole + 1e-6
    assert svc.journal.graded_since("hn123", q1.name, 0) == 1


@pytest.mark.parametrize("size", [95 * 10**6])
def test_a_huge_notebook_is_refused_before_it_is_read(service, sources, grader, monkeypatch,
                                                      size):
    """Finding 9: a 95 MB notebook cost a worker 2.3 GB (``digest`` parsed it before any size
    check). Its size is taken from the opened file before a byte is read: the JSON parser never
    sees it, memory stays small, the page says why, and no attempt is charged."""
    import nbgrader.utils  # noqa: F401 - imported before measuring: its import is not the cost

    q1 = _by_name(sources, "q1_imaging")
    svc = service()
    folder = submit(svc, "hg123", {q1.name: honest(q1, "hg123")})
    path = svc.inbound / folder / f"{q1.name}.ipynb"
    os.truncate(path, size)                  # sparse: 95 MB that costs the disk nothing
    loop.notice(svc, now=later())
    parsed = []
    real_loads = json.loads

    def loads(s, *args, **kwargs):
        parsed.append(len(s))
        return real_loads(s, *args, **kwargs)
    monkeypatch.setattr(json, "loads", loads)
    tracemalloc.start()
    try:
        loop.drain(svc, now=later())
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert not [n for n in parsed if n >= 10**6], parsed
    assert peak < 16 * 2**20, peak
    assert grader.calls == []
    page = exchange_page(svc, folder, q1.name)
    assert f"{size / 2**20:.1f} MB, over the limit" in page and "cost no attempt" in page
    assert svc.journal.graded_since("hg123", q1.name, 0) == 0


def test_only_the_assignments_notebooks_are_copied(service, sources, grader):
    """Whatever else the inbound folder holds is never copied (a 50 MB file was copied on every
    try, issue 33): the grader sees the notebooks, the secret and the kernel's timestamp."""
    q1 = _by_name(sources, "q1_imaging")
    svc = service()
    folder = submit(svc, "cp123", {q1.name: honest(q1, "cp123")})
    with open(svc.inbound / folder / "data.bin", "wb") as fh:
        fh.truncate(50 * 10**6)             # sparse: costs the disk nothing until copied
    (svc.inbound / folder / "extra").mkdir()
    (svc.inbound / folder / "extra" / "notes.ipynb").write_text("{}")
    loop.notice(svc, now=later())
    loop.drain(svc, now=later())
    assert grader.listed == [sorted([f"{q1.name}.ipynb", "submission_secret.txt",
                                     "timestamp.txt"])]


def test_touching_the_folder_during_the_copy_is_a_counted_try_with_back_off(service, sources,
                                                                            grader,
                                                                            monkeypatch):
    """Finding 9: touching one's own inbound folder while it is copied re-queued the submission
    at once, at the head of the queue, without limit (main: 53 copies in 60 s). Each such try
    counts, waits longer than the one before, goes behind a classmate already served, and
    after the limit the submission is failed with a page saying so."""
    q1 = _by_name(sources, "q1_imaging")
    svc = service()
    submit(svc, "ot123", {q1.name: honest(q1, "ot123")})
    loop.notice(svc, now=later())
    loop.drain(svc, now=later())             # the classmate was served once already
    mine = submit(svc, "tc123", {q1.name: honest(q1, "tc123")})
    theirs = submit(svc, "ot123", {q1.name: _edited(q1, "ot123", "", 1)})
    loop.notice(svc, now=later())
    rules = inbox.exchange_rules()
    real = rules.newest_ctime_ns
    touched = svc.inbound / mine / f"{q1.name}.ipynb"

    def touch_then_look(path, uid):          # the student touches the folder meanwhile
        if path.endswith(mine):
            before = os.lstat(touched).st_ctime_ns
            for _ in range(1000):
                os.chmod(touched, 0o640 if os.lstat(touched).st_mode & 0o004 else 0o644)
                if os.lstat(touched).st_ctime_ns != before:
                    break
                time.sleep(0.005)
        return real(path, uid)
    monkeypatch.setattr(rules, "newest_ctime_ns", touch_then_look)
    order, delays = [], []
    for _ in range(grading.MAX_TRIES + 3):
        said = loop.drain(svc, limit=1, now=later())
        if not said:
            break
        order.append(said[0].split(":")[0])
        row = svc.journal.db.execute("SELECT state, retry_at FROM submissions WHERE folder=?",
                                     (mine,)).fetchone()
        if said[0].startswith("tc123") and row[0] == "queued":
            delays.append(row[1] - time.time())
    assert order[:2] == ["tc123", "ot123"]   # the retry went behind the classmate
    assert order.count("tc123") == grading.MAX_TRIES
    assert len(delays) == grading.MAX_TRIES - 1
    assert all(b > a for a, b in zip(delays, delays[1:])), delays    # back-off
    state, tries = svc.journal.db.execute("SELECT state, tries FROM submissions WHERE folder=?",
                                          (mine,)).fetchone()
    assert (state, tries) == ("failed", grading.MAX_TRIES)
    assert "kept changing while it was being collected" in exchange_page(svc, mine, q1.name)
    assert svc.journal.row_of(theirs).state == "done"
