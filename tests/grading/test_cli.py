"""``python -m autograder grade`` without the operating-system sandbox: it refuses, with why,
unless ``--unsafe-no-isolation`` is given, and then it says so loudly (never silently)."""

from __future__ import annotations

import argparse

import pytest
from gradingtools import SECRET, model_version, read_grades, write_nb

from autograder.grade import cli
from autograder.isolation import UNSAFE_WARNING, IsolationUnavailable


def _args(tmp_path, *extra):
    parser = argparse.ArgumentParser()
    cli.add_arguments(parser)
    (tmp_path / "secret").write_bytes(SECRET + b"\n")
    return parser.parse_args([str(tmp_path / "submitted"), "--out", str(tmp_path / "out"),
                              "--secret-file", str(tmp_path / "secret"), "--no-gradebook",
                              "--quiet", "--jobs", "1", "--timeout", "2", *extra])


@pytest.fixture
def no_sandbox(monkeypatch):
    def probe():
        raise IsolationUnavailable("bubblewrap is not installed (test)")
    monkeypatch.setattr(cli, "probe", probe)


def test_refuses_without_the_sandbox(tmp_path, capsys, no_sandbox, sources):
    write_nb(tmp_path / "submitted" / "kim" / "tripos2006" / f"{sources[0].name}.ipynb",
             model_version(sources[0]))
    assert cli.main(_args(tmp_path)) == 2
    err = capsys.readouterr().err
    assert "sandbox is unavailable" in err and "bubblewrap is not installed (test)" in err
    assert "--unsafe-no-isolation" in err
    assert not (tmp_path / "out" / "grades.csv").exists()


def test_unsafe_flag_grades_and_warns(tmp_path, capsys, no_sandbox, sources):
    src = sources[0]
    write_nb(tmp_path / "submitted" / "kim" / "tripos2006" / f"{src.name}.ipynb",
             model_version(src))
    assert cli.main(_args(tmp_path, "--unsafe-no-isolation", "--source",
                          str(src.path.parent))) == 0
    assert UNSAFE_WARNING in capsys.readouterr().err
    rows = read_grades(tmp_path / "out")
    for _, tid, pts in src.graded:
        assert float(rows[("kim", src.name, tid)]["score"]) == pytest.approx(pts)
