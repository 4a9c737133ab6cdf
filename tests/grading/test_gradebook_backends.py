"""The gradebook on PostgreSQL holds exactly what it holds on SQLite.

One small class is graded twice, from empty gradebooks: ``--db-url sqlite:///...`` and
``--db-url postgresql://...`` on a throw-away server (``postgres_url``, tests/postgres.py).
Both runs go through ``nbgrader generate_assignment`` (the course's first run) and the sync.
Every grade row (auto score, manual score, the "needs manual grade" flag) and every
submission's total must agree between the two databases, and agree with the points the source
notebooks' metadata give: alice hands in the model answers (full points), bob the release
(0, written answers left blank so no marker is needed), carol one wrong function per notebook
and one notebook short. A re-grade on PostgreSQL keeps a marker's score and comment.
A gradebook URL whose driver is missing stops ``grade`` before it grades (exit 2, the driver
named).
"""

from __future__ import annotations

import sys

import pytest

from autograder.outputs.gradebook_url import MissingDriver, resolve_db_url
from gradingtools import (SECRET, cell_index, function_names, model_version, read_grades,
                          release_version, run_grade, write_nb)
from postgres import fresh_database

A = "tripos2006"
ONE_SERVER = pytest.mark.xdist_group("postgres")   #: the tests that share the graded class


def _carol(src) -> dict:
    nb = model_version(src)
    names = function_names(src)
    if names:
        nb["cells"][cell_index(nb, names[0])]["source"] = (
            f"def {names[0]}(*args, **kwargs):\n    return 'wrong'\n")
    return nb


def _write_class(submitted, sources) -> None:
    for src in sources:
        write_nb(submitted / "alice" / A / f"{src.name}.ipynb", model_version(src))
        write_nb(submitted / "bob" / A / f"{src.name}.ipynb", release_version(src))
    for src in sources[:-1] if len(sources) > 1 else sources:
        write_nb(submitted / "carol" / A / f"{src.name}.ipynb", _carol(src))


def _gradebook_rows(db_url: str) -> dict:
    """``{(student, notebook, grade_id): (auto, manual, needs_manual_grade)}`` and the totals."""
    from nbgrader.api import Gradebook

    rows, totals = {}, {}
    with Gradebook(db_url, course_id="4f9") as gb:
        for student in gb.students:
            sub = gb.find_submission(A, student.id)
            totals[student.id] = sub.score
            for nb in sub.notebooks:
                for g in nb.grades:
                    rows[(student.id, nb.name, g.name)] = (g.auto_score, g.manual_score,
                                                           g.needs_manual_grade)
    return rows, totals


@pytest.fixture(scope="module")
def graded(tmp_path_factory, sources, postgres_url):
    root = tmp_path_factory.mktemp("backends")
    secret = root / "secret"
    secret.write_bytes(SECRET + b"\n")
    _write_class(root / "submitted", sources)
    urls = {"sqlite": f"sqlite:///{root / 'out-sqlite' / 'gradebook.db'}",
            "postgresql": fresh_database(postgres_url, "gradebook_backends")
            .replace("postgresql+psycopg://", "postgresql://", 1)}
    runs = {}
    for backend, url in urls.items():
        out = root / f"out-{backend}"
        out.mkdir()
        run_grade(root / "submitted", out, "--db-url", url, secret_file=secret)
        runs[backend] = {"out": out, "csv": (out / "grades.csv").read_text(),
                         "gradebook": _gradebook_rows(resolve_db_url(url))}
    return {"root": root, "secret": secret, "urls": urls, "runs": runs}


@ONE_SERVER
@pytest.mark.slow
def test_postgres_holds_every_row_sqlite_holds(graded):
    sqlite_rows, sqlite_totals = graded["runs"]["sqlite"]["gradebook"]
    pg_rows, pg_totals = graded["runs"]["postgresql"]["gradebook"]
    assert graded["runs"]["sqlite"]["csv"] == graded["runs"]["postgresql"]["csv"]
    assert sqlite_rows and set(pg_rows) == set(sqlite_rows)
    for key, (auto, manual, flag) in sqlite_rows.items():
        pg_auto, pg_manual, pg_flag = pg_rows[key]
        assert (pg_manual, pg_flag) == (manual, flag), key
        assert (pg_auto is None) == (auto is None), key
        if auto is not None:
            assert pg_auto == pytest.approx(auto, abs=1e-9), key
    assert set(pg_totals) == {"alice", "bob", "carol"}
    for student, total in sqlite_totals.items():
        assert pg_totals[student] == pytest.approx(total, abs=1e-9), student


@ONE_SERVER
@pytest.mark.slow
def test_postgres_scores_follow_the_notebooks_points(graded, sources):
    rows, totals = graded["runs"]["postgresql"]["gradebook"]
    csv_rows = read_grades(graded["runs"]["postgresql"]["out"])
    full = 0.0
    for src in sources:
        for name, test_id, points in src.graded:
            assert rows[("alice", src.name, test_id)][0] == pytest.approx(points, abs=1e-9), name
            assert rows[("bob", src.name, test_id)][0] == pytest.approx(0.0, abs=1e-9), name
            full += points
        for gid, _points in src.manual:
            assert rows[("alice", src.name, gid)][2] is True     # waits for a marker
            assert rows[("bob", src.name, gid)][:3:2] == (0.0, False)   # blank: 0, no marker
    assert totals["alice"] == pytest.approx(full, abs=1e-9)
    carol_csv = sum(float(r["score"] or 0) for (s, _, _), r in csv_rows.items() if s == "carol")
    assert totals["carol"] == pytest.approx(carol_csv, abs=1e-9)
    assert totals["carol"] < totals["alice"]


@ONE_SERVER
@pytest.mark.slow
def test_regrade_on_postgres_keeps_the_markers_work(graded, sources):
    from nbgrader.api import Gradebook

    src = next(s for s in sources if s.manual)
    gid = src.manual[0][0]
    url = resolve_db_url(graded["urls"]["postgresql"])
    with Gradebook(url, course_id="4f9") as gb:
        grade = gb.find_grade(gid, src.name, A, "alice")
        grade.manual_score, grade.needs_manual_grade = 0.5, False
        gb.find_comment(gid, src.name, A, "alice").manual_comment = "Clear and correct."
        gb.db.commit()
    before, _ = _gradebook_rows(url)
    out = graded["runs"]["postgresql"]["out"]
    run_grade(graded["root"] / "submitted", out, "--db-url", graded["urls"]["postgresql"],
              secret_file=graded["secret"])
    after, _ = _gradebook_rows(url)
    assert after == before
    assert after[("alice", src.name, gid)][1:] == (0.5, False)
    with Gradebook(url, course_id="4f9") as gb:
        assert gb.find_comment(gid, src.name, A, "alice").manual_comment == "Clear and correct."


def test_plain_postgresql_url_uses_psycopg_3():
    assert resolve_db_url("postgresql://grader@db.example:5432/gradebook") == \
        "postgresql+psycopg://grader@db.example:5432/gradebook"
    assert resolve_db_url("sqlite:////tmp/gradebook.db") == "sqlite:////tmp/gradebook.db"


def test_missing_driver_is_named(monkeypatch):
    monkeypatch.setitem(sys.modules, "psycopg2", None)
    monkeypatch.setitem(sys.modules, "psycopg", None)
    with pytest.raises(MissingDriver, match="driver 'psycopg2?'.*not installed: pip install"):
        resolve_db_url("postgresql://grader@db.example/gradebook")
    with pytest.raises(ValueError, match="db_url"):
        resolve_db_url("not a url")


def test_grade_stops_before_grading_when_the_driver_is_missing(tmp_path, sources, monkeypatch):
    """psycopg shadowed by a module that cannot be imported, as on an install without the
    ``postgres`` extra: exit 2, psycopg named, nothing graded."""
    shadow = tmp_path / "shadow" / "psycopg"
    shadow.mkdir(parents=True)
    (shadow / "__init__.py").write_text(
        "raise ModuleNotFoundError(\"No module named 'psycopg'\", name='psycopg')\n")
    monkeypatch.setenv("PYTHONPATH", str(tmp_path / "shadow"))
    write_nb(tmp_path / "submitted" / "alice" / A / f"{sources[0].name}.ipynb",
             model_version(sources[0]))
    out = tmp_path / "out"
    proc = run_grade(tmp_path / "submitted", out, "--db-url",
                     "postgresql://grader@127.0.0.1:1/gradebook", check=False)
    assert proc.returncode == 2, proc.stderr[-2000:]
    assert "psycopg" in proc.stderr and "postgres" in proc.stderr
    assert not (out / "grades.csv").exists()
