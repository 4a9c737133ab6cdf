"""The course secret is not silently re-created once the course has grades: a new secret draws
other hidden cases, so a second instructor (another HOME) or a new machine would re-grade the
term on other cases. ``grade`` stops instead, saying where the secret is expected and how to
bring it over, unless ``--new-secret`` is given."""

from __future__ import annotations

import argparse
import sqlite3

import pytest

from autograder.grade import cli
from autograder.grade import secret as secret_mod
from autograder.isolation import IsolationUnavailable


@pytest.fixture
def home(tmp_path, monkeypatch):
    """A fresh HOME's default secret path, and a grade run that stops after reading it."""
    path = tmp_path / "home" / ".config" / "4f9" / "secret"
    monkeypatch.setattr(secret_mod, "DEFAULT_SECRET", path)

    def probe():
        raise IsolationUnavailable("stop here (test)")
    monkeypatch.setattr(cli, "probe", probe)
    (tmp_path / "submitted" / "kim" / "tripos2006").mkdir(parents=True)
    (tmp_path / "out").mkdir()
    return path


def _run(tmp_path, *extra):
    parser = argparse.ArgumentParser()
    cli.add_arguments(parser)
    return cli.main(parser.parse_args([str(tmp_path / "submitted"), "--out",
                                       str(tmp_path / "out"), "--quiet", *extra]))


def _gradebook_with_a_submission(path):
    with sqlite3.connect(path) as db:
        db.execute("CREATE TABLE submitted_assignment (id TEXT)")
        db.execute("INSERT INTO submitted_assignment VALUES ('x')")


@pytest.mark.parametrize("graded_by", ["grades.csv", "gradebook"])
def test_a_graded_course_without_its_secret_stops_and_says_how_to_bring_it(
        tmp_path, home, capsys, graded_by):
    if graded_by == "grades.csv":
        (tmp_path / "out" / "grades.csv").write_text("student\n", encoding="utf-8")
        extra = ("--no-gradebook",)
    else:
        _gradebook_with_a_submission(tmp_path / "gb.db")
        extra = ("--db-url", f"sqlite:///{tmp_path / 'gb.db'}")
    assert _run(tmp_path, *extra) == 2
    err = capsys.readouterr().err
    assert f"{home} does not exist, but this course already has grades" in err
    assert "scp " in err and "--secret-file" in err and "--new-secret" in err
    assert "stop here" not in err                       # stopped before anything else
    assert not home.exists()


def test_new_secret_or_a_course_without_grades_creates_it(tmp_path, home, capsys):
    assert _run(tmp_path, "--no-gradebook") == 2        # the probe stops it after the secret
    assert home.is_file() and len(home.read_text().strip()) == 64
    assert "created the course secret" in capsys.readouterr().err
    home.unlink()
    (tmp_path / "out" / "grades.csv").write_text("student\n", encoding="utf-8")
    assert _run(tmp_path, "--no-gradebook", "--new-secret") == 2
    assert home.is_file()


def test_an_empty_or_missing_gradebook_is_not_grades(tmp_path, home):
    sqlite3.connect(tmp_path / "empty.db").close()
    assert _run(tmp_path, "--db-url", f"sqlite:///{tmp_path / 'empty.db'}") == 2
    assert home.is_file()
    assert not (tmp_path / "out" / "gradebook.db").exists()   # never created by the check


def test_a_secret_file_named_on_the_command_line_follows_the_same_rule(tmp_path, home, capsys):
    """``--secret-file`` at a path that does not exist yet: created for a course without
    grades (or with ``--new-secret``), refused once the course has grades (a mistyped path
    must not draw other hidden cases); the default secret is never touched."""
    chosen = tmp_path / "elsewhere" / "secret"
    assert _run(tmp_path, "--no-gradebook", "--secret-file", str(chosen)) == 2
    assert chosen.is_file() and len(chosen.read_text().strip()) == 64
    assert f"created the course secret {chosen}" in capsys.readouterr().err
    chosen.unlink()
    (tmp_path / "out" / "grades.csv").write_text("student\n", encoding="utf-8")
    assert _run(tmp_path, "--no-gradebook", "--secret-file", str(chosen)) == 2
    assert f"{chosen} does not exist, but this course already has grades" in \
        capsys.readouterr().err
    assert not chosen.exists()
    assert _run(tmp_path, "--no-gradebook", "--secret-file", str(chosen), "--new-secret") == 2
    assert chosen.is_file() and not home.exists()
