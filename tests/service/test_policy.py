"""The service's policy: defaults, the course's file, clear errors, the day's window."""

from __future__ import annotations

import datetime as dt
import json

import pytest

from autograder.service.policy import POLICY_FILE, Policy, attempts_line, load_policy


def test_defaults_without_a_file(tmp_path):
    policy = load_policy(tmp_path)
    assert policy == Policy()
    assert (policy.attempts, policy.counts, policy.due) == (5, "last", None)


def test_the_course_file_is_read(tmp_path):
    (tmp_path / POLICY_FILE).write_text(json.dumps(
        {"attempts": 3, "counts": "best", "due": "2026-03-13T16:00:00+00:00"}))
    policy = load_policy(tmp_path)
    assert policy.attempts == 3 and policy.counts == "best"
    assert policy.due == dt.datetime(2026, 3, 13, 16, tzinfo=dt.timezone.utc)
    assert policy.is_open(dt.datetime(2026, 3, 13, 15, 59, tzinfo=dt.timezone.utc))
    assert not policy.is_open(dt.datetime(2026, 3, 13, 16, tzinfo=dt.timezone.utc))


@pytest.mark.parametrize("data, words", [
    ({"attempts": 0}, "attempts"), ({"attempts": 2.5}, "attempts"),
    ({"counts": "first"}, "counts"), ({"timezone": "Mars/Olympus"}, "time zone"),
    ({"due": "next friday"}, "ISO 8601"), ({"due": "2026-03-13T16:00:00"}, "UTC offset"),
    ({"margin": -1}, "margin"), ({"attemps": 3}, "unknown key"), ([1, 2], "JSON object"),
])
def test_bad_policies_say_what_is_wrong(tmp_path, data, words):
    (tmp_path / POLICY_FILE).write_text(json.dumps(data))
    with pytest.raises(ValueError, match=words) as info:
        load_policy(tmp_path)
    assert POLICY_FILE in str(info.value)


def test_the_window_is_the_local_calendar_day_across_summer_time():
    policy = Policy(timezone="Europe/London")
    # Sunday 29 March 2026: UK clocks go forward at 01:00 UTC, so that day lasts 23 hours
    when = dt.datetime(2026, 3, 29, 12, tzinfo=dt.timezone.utc)
    start, end = policy.day_start(when), policy.next_day(when)
    assert start.astimezone(dt.timezone.utc) == dt.datetime(2026, 3, 29, 0,
                                                            tzinfo=dt.timezone.utc)
    assert end.astimezone(dt.timezone.utc) == dt.datetime(2026, 3, 29, 23,
                                                          tzinfo=dt.timezone.utc)
    # a summer evening 23:30 BST is already the next day in London, not in UTC
    late = dt.datetime(2026, 6, 1, 23, 30, tzinfo=dt.timezone.utc)
    assert policy.day_start(late).date() == dt.date(2026, 6, 2)


def test_attempts_line():
    assert attempts_line(2, 5) == "2 of 5 graded attempts left today"


def test_the_paragraph_says_an_attempt_is_charged_even_if_its_grading_fails():
    """Students read the service's rules in the release's first cell: that includes the one
    a student could otherwise take for a free attempt (issue 33, finding 4)."""
    from autograder.service.policy import policy_paragraph

    text = policy_paragraph(Policy(attempts=2))
    assert "costs its attempt as soon as the service takes it, even if its grading then " \
           "fails" in text
    assert "**2 graded attempts per notebook per day**" in text
