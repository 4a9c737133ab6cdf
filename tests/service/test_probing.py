"""The anti-oracle policy, played by the student it is meant to stop.

A student spends the whole day's budget of graded attempts of ``q1_imaging`` probing one item:
Q1(a)(i)'s brightness letter (``q1_item1``), every option one at a time, everything else of the
notebook their honest work. The grader itself tells the options apart (the journal records the
right one at full marks and the others at zero, against the registry's key for this student:
an independent oracle), yet every page the student receives is the same, apart from the
attempts line. The same holds for a number item (Q1(c)'s displayed depths) probed digit by
digit.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from servicetools import auto_scores, exchange_page, honest, later, submit, with_cell

from autograder.exercises import REGISTRY
from autograder.service import loop
from autograder.service.policy import attempts_line

STUDENT = "pr123"
ATTEMPTS_LINE = re.compile(r"\d+ of \d+ graded attempts left today")


def _probe(svc, src, item, answers):
    """Submit one notebook per answer of ``item``; the pages received, in order."""
    base = honest(src, STUDENT)
    folders = []
    for answer in answers:
        folders.append(submit(svc, STUDENT, {src.name: with_cell(
            base, item, f"{item} = {answer!r}\n")}))
        loop.notice(svc, now=later())
        loop.drain(svc)
    return folders, [exchange_page(svc, f, src.name) for f in folders]


def _scores(svc, item):
    return [row[4] for row in svc.journal.attempts_rows() if row[2] == item]


def test_probing_a_choice_item_learns_nothing(service, q1):
    svc = service(attempts=5)
    item = "q1_item1"
    ex = REGISTRY[item]
    options = list(ex.options)
    right = ex.key_for(STUDENT)
    answers = options + options[:2]     # every option, the budget (5) spent, then one more
    folders, pages = _probe(svc, q1, item, answers)
    # the grader knew: the right letter scored full marks, every other none (registry's key)
    scores = _scores(svc, item)
    assert len(scores) == 5
    points = next(p for name, _, p in q1.graded if name == item)
    assert scores == [points if a == right else 0.0 for a in answers[:5]]
    # ... and the student learned nothing: the pages differ only in the attempts line
    for i, page in enumerate(pages[:5]):
        assert attempts_line(4 - i, 5) in page
    stripped = {ATTEMPTS_LINE.sub("", p) for p in pages[:5]}
    assert len(stripped) == 1
    page = stripped.pop()
    assert "recorded; revealed after the due date" in page
    assert "Total" not in page and "automatically graded" not in page
    # the sixth attempt is over the budget: recorded, not graded, and says so
    assert attempts_line(0, 5) in pages[5] and "not graded" in pages[5]
    assert svc.journal.graded_since(STUDENT, q1.name, 0) == 5


def test_probing_a_number_item_learns_nothing(service, q1):
    svc = service(attempts=3)
    item = "q1c_your_depths"
    exact = np.asarray(REGISTRY[item].value_for(STUDENT), dtype=float)
    nudged = exact.copy()
    nudged[0] += 1.0                           # one digit changed
    answers = [exact.tolist(), nudged.tolist(), (exact * 10).tolist()]
    _folders, pages = _probe(svc, q1, item, answers)
    scores = _scores(svc, item)
    points = next(p for name, _, p in q1.graded if name == item)
    assert scores[0] == pytest.approx(points) and scores[1] == 0.0 and scores[2] == 0.0
    assert len({ATTEMPTS_LINE.sub("", p) for p in pages}) == 1


def test_after_the_due_date_the_page_tells(service, q1):
    import datetime as dt

    svc = service(attempts=5, due=dt.datetime(2000, 1, 1, tzinfo=dt.timezone.utc))
    item = "q1_item1"
    wrong = next(o for o in REGISTRY[item].options if o != REGISTRY[item].key_for(STUDENT))
    _folders, pages = _probe(svc, q1, item, [wrong])
    assert "recorded; revealed after the due date" not in pages[0]
    assert "automatically graded" in pages[0] and attempts_line(4, 5) in pages[0]


def test_best_attempt_does_not_keep_an_item_the_student_only_guessed(service, q1):
    """With ``counts: best``, a student who answers an item differently in each attempt (the
    right letter first, a wrong one after, everything else the same) does not keep the right
    one: attempts are ranked by their graded functions alone, ties going to the later, so the
    gradebook holds the later, wrong letter (the registry's key decides which is right)."""
    svc = service(attempts=5, counts="best")
    item = "q1_item1"
    ex = REGISTRY[item]
    right = ex.key_for(STUDENT)
    wrong = next(o for o in ex.options if o != right)
    _probe(svc, q1, item, [right, wrong])
    assert _scores(svc, item)[0] > 0 and _scores(svc, item)[1] == 0.0   # the grader knew
    test_id = next(t for name, t, _ in q1.graded if name == item)
    scores = auto_scores(svc, STUDENT, q1.name)
    assert scores[test_id] == pytest.approx(0.0)
