"""Gradebook sync: nbgrader's gradebook on PostgreSQL vs on SQLite, 200 students.

:func:`autograder.outputs.gradebook.sync` writes one batch's scores (every auto-graded and
written-answer cell of the six notebooks, for every student) into nbgrader's gradebook and
the ``autograded/`` notebooks. The same synthetic batch (random scores, a fixed seed) is
synced into two gradebooks that already know the assignment's cells (registered beforehand
with nbgrader's own ``SaveCells``, untimed):

- **PostgreSQL**: a throw-away server of Debian's ``postgresql`` on 127.0.0.1 (started by
  ``tests/postgres.py``, durability settings off as for any test server), through psycopg 3;
- **SQLite**: ``sqlite:///.../gradebook.db`` on the local disk (nbgrader's default).

Two rows, each the wall time per student: the first sync (students and submissions
created) and a re-sync of the same batch (every grade read and rewritten unchanged, as a
re-grade does). The notes say whether both gradebooks ended with the same totals. With
``--smoke``: 5 students. The PostgreSQL figure is NaN when the server binaries are missing
(``make postgres-deps``).
"""

from __future__ import annotations

import importlib.util
import math
import random
import shutil
import sys
import tempfile
import time
from pathlib import Path

from .harness import REPO, Row

SECTION = "gradebook"
STUDENTS = 200
SMOKE_STUDENTS = 5


def _postgres_helpers():
    """``tests/postgres.py`` (the throw-away server the tests use), loaded by path."""
    spec = importlib.util.spec_from_file_location("bench_postgres_server",
                                                  REPO / "tests" / "postgres.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def synthetic_batch(sources, n: int):
    """A :class:`~autograder.model.Batch` of ``n`` students with random scores (seeded)."""
    from autograder.model import Batch, CellKind, CellResult, Status

    rng = random.Random(2006)
    rows, students = [], [f"student{k:03d}" for k in range(n)]
    for student in students:
        for src in sources:
            for name, test_id, points in src.graded:
                score = rng.choice([0.0, points / 2, points])
                rows.append(CellResult(student, src.name, test_id, name, score, points,
                                       Status.OK if score == points else Status.FAILED, ""))
            for gid, points in src.manual:
                rows.append(CellResult(student, src.name, gid, gid, None, points, Status.MANUAL,
                                       "", kind=CellKind.MANUAL))
    return Batch(rows, {}, students)


def _totals(db_url: str) -> dict[str, float]:
    from nbgrader.api import Gradebook

    with Gradebook(db_url, course_id="4f9") as gb:
        return {s.id: round(gb.find_submission("tripos2006", s.id).score, 6)
                for s in gb.students}


def _timed_syncs(batch, sources, db_url: str, work: Path) -> tuple[float, float, dict]:
    """Seconds of the first sync and of a re-sync, and the gradebook's totals after."""
    from autograder.outputs.gradebook import register_cells, sync

    register_cells(db_url, sources)
    submitted = work / "submitted"
    submitted.mkdir(parents=True, exist_ok=True)
    times = []
    for _ in range(2):
        t0 = time.perf_counter()
        sync(batch, sources, submitted=submitted, out=work / "out", db_url=db_url)
        times.append(time.perf_counter() - t0)
    return times[0], times[1], _totals(db_url)


def _sources():
    from autograder.course import source_notebooks
    from autograder.grade.sources import load_source

    return [load_source(p) for p in source_notebooks()]


def run(smoke: bool = False) -> list[Row]:
    n = SMOKE_STUDENTS if smoke else STUDENTS
    sources = _sources()
    batch = synthetic_batch(sources, n)
    work = Path(tempfile.mkdtemp(prefix="bench-gradebook-"))
    server = None
    try:
        sqlite = _timed_syncs(batch, sources, f"sqlite:///{work / 'gradebook.db'}",
                              work / "sqlite")
        try:
            helpers = _postgres_helpers()
            server = helpers.start_server()
            url = helpers.fresh_database(server.url(), "bench_gradebook")
            postgres = _timed_syncs(batch, sources, url, work / "postgres")
        except Exception as exc:  # noqa: BLE001 - reported in the table; SQLite still counts
            print(f"warning: PostgreSQL not measured: {exc}", file=sys.stderr)
            postgres = (math.nan, math.nan, {})
    finally:
        if server is not None:
            server.stop()
        shutil.rmtree(work, ignore_errors=True)
    cells = len(batch.results) // max(1, n)
    agree = ("both gradebooks hold the same totals" if postgres[2] == sqlite[2]
             else "PostgreSQL not measured" if not postgres[2] else "TOTALS DIFFER")
    what = f"{n} students × {cells} graded cells"
    return [Row(SECTION, what, f"{label}, time per student", postgres[k] / n, sqlite[k] / n,
                "SQLite gradebook", unit="s", notes=f"ours = PostgreSQL 15 on 127.0.0.1 "
                f"(psycopg 3); {agree}")
            for k, label in ((0, "first sync"), (1, "re-sync"))]
