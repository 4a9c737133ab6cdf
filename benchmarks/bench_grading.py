"""Grading throughput: our ``grade --jobs 1/2`` vs plain ``nbgrader autograde``, same submissions.

The submissions are the six source notebooks (model answers, so every auto-graded cell should
get full marks) copied for N students into nbgrader's layout ``submitted/<student>/tripos2006/``
of a course made by :func:`autograder.course.prepare_course`. Each contender grades the same
files in its own copy of that course (so that neither finds the other's gradebook entries or
``autograded/`` folders):

- **nbgrader**: ``nbgrader autograde tripos2006`` (one kernel per notebook, one notebook at a
  time: nbgrader has no parallel autograde), which runs every cell of the notebook, figures and
  explorers included;
- **ours**: ``python -m autograder grade SUBMITTED --out OUT --jobs N`` (sandboxed, setup and
  solution cells only, seeded hidden cases, feedback, report and the same gradebook and
  ``autograded/`` notebooks written), with ``--jobs 1`` and ``--jobs 2``.

The figure compared is the wall time per submission (one student's whole assignment), so a
ratio below 1 means ours is faster; the notes give submissions per minute and the fraction of
the auto-graded marks awarded, which should be 100 % for model answers. With ``--smoke``: one
submission of one notebook, graded by nbgrader and by ``--jobs 1`` only.
"""

from __future__ import annotations

import csv
import math
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

from .harness import Row, timed_grade

SECTION = "grading"
STUDENTS = 4
SMOKE_STUDENTS = 1
SMOKE_NOTEBOOK = "q4_"
TIMEOUT_S = 3600


def _copy_course(course, dest: Path):
    """A copy of a prepared course at ``dest`` with its own gradebook."""
    from autograder.course import CourseDir, config_text, default_db_url

    shutil.copytree(course.root, dest)
    db_url = default_db_url(dest)
    (dest / "nbgrader_config.py").write_text(config_text(db_url, exchange_root=dest / "exchange"))
    return CourseDir(root=dest, source_dir=dest / "source" / course.source_dir.name,
                     release_dir=dest / "release" / course.release_dir.name, db_url=db_url)


def _submit(course, students: list[str]) -> None:
    """The source notebooks handed in by every student (nbgrader's submitted layout)."""
    for s in students:
        folder = course.submitted_dir(s)
        folder.mkdir(parents=True, exist_ok=True)
        for nb in sorted(course.source_dir.glob("*.ipynb")):
            shutil.copyfile(nb, folder / nb.name)
        (folder / "timestamp.txt").write_text("2026-06-01 12:00:00.000000 UTC\n")


def _nbgrader(course, students) -> tuple[float, str]:
    from autograder.course import ASSIGNMENT

    t0 = time.perf_counter()
    course.nbgrader(["autograde", ASSIGNMENT, "--force", "--create"], timeout=TIMEOUT_S)
    elapsed = time.perf_counter() - t0
    with course.gradebook() as gb:
        got = total = 0.0
        for s in students:
            sub = gb.find_submission(ASSIGNMENT, s)
            got += sub.code_score
            total += sub.max_code_score
    return elapsed, f"{100 * got / total:.0f} % of auto-graded marks" if total else "no marks"


def _ours(course, students, jobs: int, work: Path) -> tuple[float, str]:

    out = work / f"out-jobs{jobs}"
    secret = work / "secret"
    if not secret.exists():
        secret.write_text("benchmark-secret-0123456789abcdef\n")
    cmd = [sys.executable, "-m", "autograder", "grade", str(course.root / "submitted"),
           "--out", str(out), "--jobs", str(jobs), "--secret-file", str(secret),
           "--source", str(course.source_dir), "--quiet"]
    elapsed = timed_grade(cmd, TIMEOUT_S)
    with open(out / "grades.csv", newline="", encoding="utf-8") as f:
        rows = [r for r in csv.DictReader(f) if r["score"] not in ("", None)]
    graded = {r["student"] for r in rows}
    if graded != set(students):
        raise RuntimeError(f"grades.csv covers {len(graded)} of {len(students)} students")
    got = sum(float(r["score"]) for r in rows)
    total = sum(float(r["max_score"]) for r in rows)
    return elapsed, f"{100 * got / total:.0f} % of auto-graded marks" if total else "no marks"


def run(smoke: bool = False) -> list[Row]:
    from autograder.course import nbgrader_env

    # nbgrader's Gradebook runs `alembic` from PATH, in this process too (`make bench` puts the
    # venv's bin/ first; `python -m benchmarks` run by hand may not)
    saved = os.environ.get("PATH")
    os.environ["PATH"] = nbgrader_env()["PATH"]
    try:
        return _run(smoke)
    finally:
        if saved is None:
            os.environ.pop("PATH", None)
        else:
            os.environ["PATH"] = saved


def _run(smoke: bool) -> list[Row]:
    from autograder.course import prepare_course, source_notebooks

    notebooks = source_notebooks()
    if not notebooks:
        raise RuntimeError("no source notebooks in notebooks/")
    if smoke:  # the quickest notebook to release and execute
        quick = [p for p in notebooks if p.name.startswith(SMOKE_NOTEBOOK)]
        notebooks = quick[:1] or notebooks[:1]
    n = SMOKE_STUDENTS if smoke else STUDENTS
    students = [f"student{k:02d}" for k in range(1, n + 1)]
    what = (f"{n} submission{'s' if n > 1 else ''} × {len(notebooks)} notebook"
            f"{'s' if len(notebooks) > 1 else ''}")
    work = Path(tempfile.mkdtemp(prefix="bench-grading-"))
    try:
        base = prepare_course(work / "course", notebooks=notebooks)
        # with one submission --jobs 2 has nothing to share out: the smoke run skips it
        contenders = {"nbgrader": None, 1: None} if smoke else {"nbgrader": None, 1: None, 2: None}
        for key in contenders:
            course = _copy_course(base, work / f"course-{key}")
            _submit(course, students)
            try:
                if key == "nbgrader":
                    contenders[key] = _nbgrader(course, students)
                else:
                    contenders[key] = _ours(course, students, key, work)
            except Exception as exc:  # noqa: BLE001 - reported in the table; the others run
                contenders[key] = exc
                print(f"warning: grading with {key!r} failed: {exc}", file=sys.stderr)
    finally:
        shutil.rmtree(work, ignore_errors=True)

    def per_sub(result):
        return result[0] / n if isinstance(result, tuple) else math.nan

    def rate(result):
        return (f"{60 * n / result[0]:.1f} submissions/min, {result[1]}"
                if isinstance(result, tuple) else f"not available ({result})")

    peer = contenders["nbgrader"]
    peer_s = per_sub(peer) if isinstance(peer, tuple) else None
    rows = []
    for jobs in [j for j in (1, 2) if j in contenders]:
        mine = contenders[jobs]
        note = f"ours: {rate(mine)}; nbgrader: {rate(peer)}"
        rows.append(Row(SECTION, what, f"time per submission, grade --jobs {jobs}",
                        per_sub(mine), peer_s, "nbgrader autograde", unit="s", notes=note))
    if all(isinstance(contenders.get(j), tuple) for j in (1, 2)):
        rows.append(Row(SECTION, what, "scaling: --jobs 2 vs --jobs 1", per_sub(contenders[2]),
                        per_sub(contenders[1]), "our --jobs 1", unit="s",
                        notes="0.5 would be perfect scaling on 2 workers"))
    return rows
