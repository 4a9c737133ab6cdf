"""Grading service: submit → feedback-fetchable latency, one student alone and a burst, vs batch.

The submissions are the six source notebooks (model answers) handed in by each student through
a filesystem exchange, as nbgrader's submit lays them out. The service (``python -m autograder
watch``'s loop, :mod:`autograder.service`, ``--jobs 2``, the gradebook updated) notices them
and grades them one submission at a time; a submission's latency runs from its folder being
written to its last page being released to the exchange's feedback folder.

- **alone**: three students, each submitting when the service is idle: p50 and p95 latency;
- **burst**: N students submitting at once (10; 2 with ``--smoke``): p50 and p95 latency and
  the time to drain the burst, against the peer ``grade`` gives the same burst: one batch
  (``grade_batch`` with ``--jobs 2`` over all N), after which every student's feedback is ready,
  so its every student's latency is the batch's wall time.

This is an in-process burst on one machine; the hub's burst (real Unix users through the hub's
API, logins meanwhile) is not measured here.
"""

from __future__ import annotations

import os
import secrets
import shutil
import statistics
import tempfile
import time
from pathlib import Path

from .harness import Row

SECTION = "grading service"
SECRET = b"benchmark-service-secret-0123"


def _service(work: Path, sources, mode, gradebook: bool):
    from autograder.course import COURSE_ID
    from autograder.grade.batch import Options
    from autograder.isolation import Limits
    from autograder.outputs.gradebook import register_cells
    from autograder.service.grading import Service
    from autograder.service.journal import Journal
    from autograder.service.policy import Policy

    course, exchange = work / "course", work / "exchange"
    (exchange / COURSE_ID / "inbound").mkdir(parents=True)
    (course / "service").mkdir(parents=True)
    db_url = f"sqlite:///{course / 'gradebook.db'}" if gradebook else None
    if db_url:
        register_cells(db_url, sources)
    opts = Options(out=course / "service", jobs=2, limits=Limits(case_timeout=10.0),
                   secret=SECRET, mode=mode, progress=False)
    return Service(course, exchange / COURSE_ID / "inbound", exchange,
                   Journal(course / "service" / "journal.db"), Policy(attempts=100), sources,
                   opts, {s.name: 60.0 for s in sources}, db_url,
                   uid_of=lambda _student: os.getuid())


def _submit(svc, student: str, sources) -> float:
    """One student's submission written into the inbound; when (perf_counter)."""
    from autograder.course import ASSIGNMENT

    stamp = time.strftime("%Y-%m-%d %H:%M:%S.000000 UTC", time.gmtime())
    folder = svc.inbound / f"{student}+{ASSIGNMENT}+{stamp}+{secrets.token_hex(9)}"
    folder.mkdir()
    for src in sources:
        shutil.copyfile(src.path, folder / f"{src.name}.ipynb")
    (folder / "timestamp.txt").write_text(stamp)
    (folder / "submission_secret.txt").write_text(secrets.token_hex(16))
    return time.perf_counter()


def _serve(svc) -> dict[str, float]:
    """Grade everything queued, one submission at a time; when each student's was done."""
    from autograder.service import loop
    from autograder.service.grading import process

    loop.notice(svc, now=time.time() + 3600)
    done = {}
    while True:
        row = svc.journal.next_ready()
        if row is None:
            return done
        process(svc, row)
        done[row.student] = time.perf_counter()


def _p(samples: list[float], q: float) -> float:
    samples = sorted(samples)
    return samples[min(len(samples) - 1, int(round(q * (len(samples) - 1))))]


def _batch_seconds(work: Path, sources, mode, students: list[str]) -> float:
    from autograder.grade.batch import Options, grade_batch
    from autograder.isolation import Limits
    from autograder.course import ASSIGNMENT

    submitted = work / "batch" / "submitted"
    for s in students:
        (submitted / s / ASSIGNMENT).mkdir(parents=True)
        for src in sources:
            shutil.copyfile(src.path, submitted / s / ASSIGNMENT / f"{src.name}.ipynb")
    opts = Options(out=work / "batch", jobs=2, limits=Limits(case_timeout=10.0),
                   secret=SECRET, mode=mode, progress=False)
    t0 = time.perf_counter()
    grade_batch(submitted, sources, opts, students=students)
    return time.perf_counter() - t0


def run(smoke: bool = False) -> list[Row]:
    from autograder.exercises import REGISTRY
    from autograder.grade.sources import default_sources, load_source
    from autograder.isolation import probe

    sources = [s for s in map(load_source, default_sources())
               if any(n in REGISTRY for n, _, _ in s.graded)]
    if smoke:
        sources = sources[:1]
    mode = probe()
    work = Path(tempfile.mkdtemp(prefix="4f9-bench-service-"))
    try:
        svc = _service(work, sources, mode, gradebook=not smoke)
        alone = []
        for i in range(1 if smoke else 3):
            sent = _submit(svc, f"alone{i}", sources)
            alone.append(_serve(svc)[f"alone{i}"] - sent)
        n = 2 if smoke else 10
        sent = {f"burst{i:02d}": _submit(svc, f"burst{i:02d}", sources) for i in range(n)}
        t0 = time.perf_counter()
        done = _serve(svc)
        drained = time.perf_counter() - t0
        burst = [done[s] - sent[s] for s in sent]
        batch = _batch_seconds(work, sources, mode, list(sent))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    what = f"{len(sources)} notebooks per submission"
    return [
        Row(SECTION, "one student alone", "submit → feedback p50", statistics.median(alone),
            unit="s", notes=what),
        Row(SECTION, "one student alone", "submit → feedback p95", _p(alone, 0.95), unit="s",
            notes=what),
        Row(SECTION, f"burst of {n}", "submit → feedback p50", statistics.median(burst),
            peer=batch, peer_name="batch grade, all at once", unit="s", notes=what),
        Row(SECTION, f"burst of {n}", "submit → feedback p95", _p(burst, 0.95), peer=batch,
            peer_name="batch grade, all at once", unit="s", notes=what),
        Row(SECTION, f"burst of {n}", "drained", drained, peer=batch,
            peer_name="batch grade, all at once", unit="s",
            notes="the service grades one submission at a time, round-robin"),
    ]
