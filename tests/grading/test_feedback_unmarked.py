"""``python -m autograder feedback`` says which written answers it hands back unmarked (a partial
hand-back is legitimate, so it still releases), and ``--require-marked`` stops it instead."""

from __future__ import annotations

import argparse

import pytest

from autograder import cli_feedback
from autograder.outputs import handback


def _notebook(student, marked_a, marked_b=True):
    return handback.NotebookMarks(student, "q1_imaging", [
        handback.Mark("q1a_answer", 4.0, 6.0, True, marked_a, ""),
        handback.Mark("q1b_answer", 0.0, 4.0, True, marked_b, ""),
        handback.Mark("q1c_test", 2.0, 2.0, False, True, ""),
    ])


@pytest.fixture
def course(tmp_path, monkeypatch):
    (tmp_path / "course" / "autograded").mkdir(parents=True)
    (tmp_path / "grading").mkdir()
    calls = []
    monkeypatch.setattr(handback, "write_pages",
                        lambda marks, grading, root: calls.append("write") or (len(marks), 0))
    monkeypatch.setattr(handback, "missing_secrets", lambda root: [])
    monkeypatch.setattr(handback, "release", lambda root, db, exclude=(): calls.append("release"))
    return tmp_path, calls


def _run(tmp_path, marks, monkeypatch, *extra):
    monkeypatch.setattr(handback, "read_marks", lambda db_url, order=None: marks)
    parser = argparse.ArgumentParser()
    cli_feedback.add_arguments(parser)
    return cli_feedback.main(parser.parse_args(["--grading", str(tmp_path / "grading"),
                                                "--course", str(tmp_path / "course"), *extra]))


def test_unmarked_answers_are_listed_and_the_pages_still_released(course, monkeypatch, capsys):
    tmp_path, calls = course
    marks = [_notebook("ann", True), _notebook("bob", False, False), _notebook("cy", False)]
    assert _run(tmp_path, marks, monkeypatch) == 0
    err = capsys.readouterr().err
    assert "warning: 3 written answers are not marked yet" in err
    for name in ("bob/q1_imaging/q1a_answer", "bob/q1_imaging/q1b_answer",
                 "cy/q1_imaging/q1a_answer"):
        assert name in err
    assert "ann/" not in err and "q1c_test" not in err        # marked, or not written
    assert calls == ["write", "release"]


def test_require_marked_refuses_and_the_list_is_capped(course, monkeypatch, capsys):
    tmp_path, calls = course
    marks = [_notebook(f"s{i:02d}", False) for i in range(25)]
    assert _run(tmp_path, marks, monkeypatch, "--require-marked") == 1
    err = capsys.readouterr().err
    assert "error: 25 written answers are not marked yet" in err
    assert err.count("/q1_imaging/q1a_answer") == cli_feedback.LISTED
    assert "and 5 more" in err and calls == []                # nothing written or released


def test_all_marked_says_nothing_extra(course, monkeypatch, capsys):
    tmp_path, calls = course
    assert _run(tmp_path, [_notebook("ann", True)], monkeypatch, "--require-marked") == 0
    assert "not marked" not in capsys.readouterr().err and calls == ["write", "release"]
