"""A whole term, driven as the README's instructor section says, on nbgrader's local exchange.

release → two students fetch, answer and submit with the commands the README gives students
(``course/for-students/nbgrader_config.py`` copied to ``~/.jupyter/``, then nbgrader's own
``fetch_assignment`` and ``submit``, each with a ``HOME`` of their own; ``--student`` stands for
each student's own Unix login, since one account runs them all here) → ``nbgrader collect`` →
``python -m autograder grade`` → written answers marked (one in the Formgrader, in Chromium,
the README's click path; the rest through nbgrader's Gradebook API, as the Formgrader stores
them) →
re-grade with ``--reveal-hidden`` (marks, comments and flags intact) → ``python -m autograder
feedback`` → each student's ``nbgrader fetch_feedback`` → ``python -m autograder export``.

The oracles are independent of the code under test: the points come from the source notebooks'
metadata, the marks and comments are the ones this test typed in, and the exported totals are
compared with nbgrader's own ``SubmittedAssignment.score``.
"""

from __future__ import annotations

import csv
import datetime as dt
import html
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from gradingtools import REPO, SECRET, model_version, release_version, run_grade, write_nb

pytestmark = [pytest.mark.xdist_group("term"), pytest.mark.slow]

A = "tripos2006"
STUDENTS = ("alice", "bob")


def _nbgrader(args: list[str], cwd: Path, home: Path | None = None) -> str:
    """``python -m nbgrader ...`` in ``cwd`` (as a student when ``home`` is given: only the
    configuration in that ``HOME``, nothing on the command line, says where the exchange is)."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("JUPYTER")}
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    if home is not None:
        env["HOME"] = str(home)
    proc = subprocess.run([sys.executable, "-m", "nbgrader", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0 and "[ERROR]" not in proc.stderr, proc.stderr[-3000:]
    return proc.stderr


def _autograder(*args: str, check: bool = True) -> subprocess.CompletedProcess:
    env = dict(os.environ, MPLBACKEND="Agg",
               PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}")
    proc = subprocess.run([sys.executable, "-m", "autograder", *args], cwd=REPO, env=env,
                          capture_output=True, text=True, timeout=600)
    if check:
        assert proc.returncode == 0, proc.stderr[-3000:]
    return proc


def _answers(student: str, src, fetched: Path) -> dict:
    """alice: the model code, her own written answers; bob: the release with one answer."""
    if student == "alice":
        nb = model_version(src)
        for cell in nb["cells"]:
            gid = cell["metadata"].get("nbgrader", {}).get("grade_id")
            if gid in dict(src.manual):
                cell["source"] = f"Alice writes about {gid}: attenuation, geometry, reasons."
        return nb
    nb = json.loads(fetched.read_text(encoding="utf-8"))
    if src.manual and src.name == "q1_imaging":
        first = src.manual[0][0]
        for cell in nb["cells"]:
            if cell["metadata"].get("nbgrader", {}).get("grade_id") == first:
                cell["source"] = "Bob's only written answer."
    return nb


@pytest.fixture(scope="module")
def term(tmp_path_factory, sources):
    return build_term(tmp_path_factory.mktemp("term"), sources)


def build_term(base: Path, sources) -> dict:
    """Release, fetch, answer, submit, collect and grade, in the folder ``base``."""
    course = base / "course"
    exchange = course / "exchange"            # the course's own exchange (nbgrader_config.py)
    (base / "secret").write_bytes(SECRET + b"\n")
    _autograder("release", "--course-root", str(course))
    _nbgrader(["release_assignment", A], course)            # README step 1, in course/
    for student in STUDENTS:
        home = base / "home" / student
        (home / ".jupyter").mkdir(parents=True)
        shutil.copyfile(course / "for-students" / "nbgrader_config.py",
                        home / ".jupyter" / "nbgrader_config.py")
        _nbgrader(["fetch_assignment", A, "--course", "4f9"], home, home)
        for src in sources:
            path = home / A / f"{src.name}.ipynb"
            write_nb(path, _answers(student, src, path))
        _nbgrader(["submit", A, "--course", "4f9", f"--student={student}"], home, home)
    _nbgrader(["collect", A], course)
    grading = base / "grading"
    run_grade(course / "submitted", grading, secret_file=base / "secret")
    return {"base": base, "course": course, "exchange": exchange, "grading": grading,
            "db_url": f"sqlite:///{course / 'gradebook.db'}"}


def _gradebook(term):
    from nbgrader.api import Gradebook

    return Gradebook(term["db_url"], course_id="4f9")


def _mark(term, student: str, nb: str, gid: str, score: float, comment: str) -> None:
    """What the Formgrader stores when a marker scores and comments an answer."""
    with _gradebook(term) as gb:
        grade = gb.find_grade(gid, nb, A, student)
        grade.manual_score = score
        grade.needs_manual_grade = False
        gb.find_comment(gid, nb, A, student).manual_comment = comment
        gb.db.commit()


def _mark_in_the_formgrader(term, student, nb, gid, score, comment) -> str:
    import formgrader_ui

    if not formgrader_ui.CHROMIUM.exists():
        pytest.skip("Debian's chromium is not installed (make test installs it when run as root)")
    artifacts = REPO / "test-artifacts" / "browser"
    artifacts.mkdir(parents=True, exist_ok=True)
    return formgrader_ui.mark_in_subprocess(term["course"], student, nb, gid, score, comment,
                                            artifacts)


def _state(term) -> dict:
    with _gradebook(term) as gb:
        return {(s, nb.name, g.name): (g.auto_score, g.manual_score, g.needs_manual_grade)
                for s in STUDENTS for nb in gb.find_submission(A, s).notebooks
                for g in nb.grades}


def test_blank_answers_score_zero_without_a_marker(term, sources):
    state = _state(term)
    for src in sources:
        for gid, _ in src.manual:
            auto, manual, needs = state[("bob", src.name, gid)]
            if src.name == "q1_imaging" and gid == sources[0].manual[0][0]:
                assert auto is None and needs, "bob's one answer waits for a marker"
            else:
                assert auto == pytest.approx(0.0, abs=1e-12) and not needs, gid
            assert state[("alice", src.name, gid)][2], "alice's answers wait for a marker"


def test_autograded_notebooks_show_the_rubric_to_the_marker(term, sources):
    src = sources[0]
    gid = src.manual[0][0]
    nb = json.loads((term["course"] / "autograded" / "alice" / A / f"{src.name}.ipynb")
                    .read_text(encoding="utf-8"))
    at = next(i for i, c in enumerate(nb["cells"])
              if c["metadata"].get("nbgrader", {}).get("grade_id") == gid)
    assert "Rubric" in nb["cells"][at + 1]["source"]
    assert "Alice writes" in nb["cells"][at]["source"]
    released = release_version(src)
    assert not any("Rubric" in c["source"] for c in released["cells"]
                   if c["metadata"].get("nbgrader", {}).get("solution"))


def test_whole_term(term, sources):
    src = sources[0]
    marks = {(src.name, gid): (round(points / 2, 1), f"comment {k} for {gid}")
             for k, (gid, points) in enumerate(src.manual)}
    (nb0, gid0), (score0, comment0) = next(iter(marks.items()))
    text = _mark_in_the_formgrader(term, "alice", nb0, gid0, score0, comment0)
    assert "For the marker of" in text and "Rubric" in text, "the rubric beside the answer"
    with _gradebook(term) as gb:
        grade = gb.find_grade(gid0, nb0, A, "alice")
        assert grade.manual_score == pytest.approx(score0, abs=1e-9)
        assert not grade.needs_manual_grade
        assert gb.find_comment(gid0, nb0, A, "alice").comment == comment0
    for (nb, gid), (score, comment) in list(marks.items())[1:]:
        _mark(term, "alice", nb, gid, score, comment)
    _mark(term, "bob", src.name, src.manual[0][0], 1.0, "Bob: say why the echo moves.")
    before = _state(term)
    run_grade(term["course"] / "submitted", term["grading"], "--reveal-hidden",
              secret_file=term["base"] / "secret")
    assert _state(term) == before, "re-grading changed a marker's work"
    with _gradebook(term) as gb:
        for (nb, gid), (_, comment) in marks.items():
            assert gb.find_comment(gid, nb, A, "alice").comment == comment
    _hand_back(term, src, marks)
    _export(term, sources)


def _hand_back(term, src, marks) -> None:
    _autograder("feedback", "--grading", str(term["grading"]), "--course", str(term["course"]))
    for student in STUDENTS:
        home = term["base"] / "home" / student
        _nbgrader(["fetch_feedback", A, "--course", "4f9", f"--student={student}"], home, home)
        pages = list((home / A / "feedback").rglob(f"{src.name}.html"))
        assert len(pages) == 1, pages
        text = html.unescape(pages[0].read_text(encoding="utf-8"))
        assert "Hidden cases" in text and "Rubric" not in text
        if student == "alice":
            assert all(c in text for _, c in marks.values())
        else:
            assert "Bob: say why the echo moves." in text and "Alice" not in text
    again = _autograder("feedback", "--grading", str(term["grading"]), "--course",
                        str(term["course"]), "--no-release")
    assert " 0 pages written" in again.stderr
    _mark(term, "bob", src.name, src.manual[0][0], 2.0, "Bob, re-marked.")
    third = _autograder("feedback", "--grading", str(term["grading"]), "--course",
                        str(term["course"]), "--no-release")
    assert " 1 pages written" in third.stderr


def _export(term, sources) -> None:
    out = term["base"] / "export"
    refused = _autograder("export", "--out", str(out), "--course", str(term["course"]),
                          check=False)
    assert refused.returncode == 1 and "not marked yet" in refused.stderr
    assert "alice/" in refused.stderr and not (out / "canvas.csv").exists()
    _autograder("export", "--out", str(out), "--course", str(term["course"]), "--allow-unmarked",
                "--decimals", "2")
    maximum = sum(p for s in sources for *_, p in s.graded) + sum(
        p for s in sources for _, p in s.manual)
    points, rows = _canvas_rows(out)
    assert points == {A: f"{maximum:g}"}                    # the total alone, its maximum below
    questions = out / "questions"
    _autograder("export", "--out", str(questions), "--course", str(term["course"]),
                "--allow-unmarked", "--decimals", "2", "--canvas-questions")
    q_points, q_rows = _canvas_rows(questions)
    assert q_points == {f"{A} {s.name}": f"{_maximum(s):g}" for s in sources}
    with _gradebook(term) as gb:
        for student in STUDENTS:
            sub = gb.find_submission(A, student)
            assert float(rows[student][A]) == pytest.approx(sub.score, abs=0.006)
            for nb in sub.notebooks:
                assert float(q_rows[student][f"{A} {nb.name}"]) == pytest.approx(nb.score,
                                                                                abs=0.006)
    _late_export(term, out, maximum)
    auto_max = sum(p for s in sources for *_, p in s.graded)
    alice_auto = sum(v[0] or 0.0 for k, v in _state(term).items() if k[0] == "alice")
    assert alice_auto == pytest.approx(auto_max, abs=1e-6), "the model code earns every mark"


def _maximum(src) -> float:
    return sum(p for *_, p in src.graded) + sum(p for _, p in src.manual)


def _canvas_rows(out: Path) -> tuple[dict[str, str], dict[str, dict]]:
    """canvas.csv's marks columns with their Points Possible, and its rows by SIS User ID."""
    with open(out / "canvas.csv", newline="", encoding="utf-8") as f:
        head, points, *rows = list(csv.reader(f))
    assert points[0].strip() == "Points Possible"
    assert not any(h.rstrip().endswith(")") for h in head), head   # Canvas reads (N) as an id
    by_id = {r[2]: dict(zip(head, r)) for r in rows}
    return dict(zip(head[5:], points[5:])), by_id


def _late_export(term, out: Path, maximum: float) -> None:
    """Due 36 hours before alice handed in, 10 % a started day: two days, 20 % of the marks."""
    with _gradebook(term) as gb:
        subs = {s: (gb.find_submission(A, s).timestamp, gb.find_submission(A, s).score)
                for s in STUDENTS}
    due = subs["alice"][0] - dt.timedelta(hours=36)
    _autograder("export", "--out", str(out), "--course", str(term["course"]), "--allow-unmarked",
                "--due", due.isoformat(), "--late-per-day", "10")
    with open(out / "moodle.csv", newline="", encoding="utf-8") as f:
        rows = {r["ID number"]: r for r in csv.DictReader(f)}
    for student, (stamp, score) in subs.items():
        days = -(-(stamp - due).total_seconds() // 86400)
        penalty = min(score, days * 0.10 * maximum)
        assert float(rows[student]["Late penalty"]) == pytest.approx(penalty, abs=0.06)
        assert float(rows[student]["tripos2006 total"]) == pytest.approx(score - penalty, abs=0.06)
