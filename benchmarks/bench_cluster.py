"""Grading on a dask cluster: ``grade --scheduler`` on a LocalCluster vs ``grade --jobs 2``.

Generated submissions, one notebook each (submission k hands in the k-th source notebook, in
turn, with the model answers left in; nbgrader's layout, one student per submission), are
graded twice with ``--no-gradebook``:

- **ours**: ``grade --scheduler tcp://127.0.0.1:PORT`` against a ``distributed.LocalCluster``
  of two worker processes with one thread each (the same two sandboxes at a time as the peer;
  the jobs travel to the workers and their results back, as to the machines of a real cluster);
- **peer**: ``grade --jobs 2`` on this machine (threads, each waiting on one sandbox).

The figure is the wall time per submission (the cluster's workers started and warm, as
long-lived workers are; the grading command's own start, connection included, is counted);
a ratio near 1 means the cluster costs little
over local threads (its gain is the machines it adds, which this one machine cannot show).
The notes say whether both ``grades.csv`` are identical. Default size: 24 submissions (a few
minutes on 2 cores); ``BENCH_CLUSTER_SUBMISSIONS=200 python -m benchmarks --only
bench_cluster`` runs the 200 of issue 14 (about ten minutes here). With ``--smoke``: 2.
"""

from __future__ import annotations

import importlib
import math
import os
import shutil
import sys
import tempfile
from pathlib import Path

from .harness import Row, timed_grade

SECTION = "cluster"
SUBMISSIONS = 24
SMOKE_SUBMISSIONS = 2
TIMEOUT_S = 3 * 3600


def _submit(submitted: Path, notebooks: list[Path], n: int) -> None:
    for k in range(n):
        nb = notebooks[k % len(notebooks)]
        folder = submitted / f"student{k:03d}" / "tripos2006"
        folder.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(nb, folder / nb.name)


def _grade(work: Path, name: str, *how: str) -> tuple[float, str]:
    """Seconds of one ``grade`` run, and its ``grades.csv``."""

    out = work / name
    cmd = [sys.executable, "-m", "autograder", "grade", str(work / "submitted"), "--out",
           str(out), "--secret-file", str(work / "secret"), "--quiet", "--no-gradebook", *how]
    elapsed = timed_grade(cmd, TIMEOUT_S, name)
    return elapsed, (out / "grades.csv").read_text(encoding="utf-8")


def _on_cluster(work: Path) -> tuple[float, str]:
    """Grade on a fresh LocalCluster whose workers have already imported the grader's side
    (as long-lived workers have: their start is not part of a batch)."""
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      scheduler_port=0, dashboard_address=None) as cluster:
        with Client(cluster.scheduler_address, set_as_default=False) as client:
            client.run(importlib.import_module, "autograder.grade.executors")
        return _grade(work, "cluster", "--scheduler", cluster.scheduler_address)


def _size(smoke: bool) -> int:
    if smoke:
        return SMOKE_SUBMISSIONS
    asked = os.environ.get("BENCH_CLUSTER_SUBMISSIONS", "")
    return int(asked) if asked.isdigit() and int(asked) > 0 else SUBMISSIONS


def run(smoke: bool = False) -> list[Row]:
    from autograder.course import source_notebooks

    n = _size(smoke)
    notebooks = source_notebooks()
    if not notebooks:
        raise RuntimeError("no source notebooks in notebooks/")
    work = Path(tempfile.mkdtemp(prefix="bench-cluster-"))
    try:
        (work / "secret").write_text("benchmark-secret-0123456789abcdef\n")
        _submit(work / "submitted", notebooks, n)
        local_s, local_csv = _grade(work, "local", "--jobs", "2")
        try:
            cluster_s, cluster_csv = _on_cluster(work)
        except Exception as exc:  # noqa: BLE001 - reported in the table
            print(f"warning: the cluster run failed: {exc}", file=sys.stderr)
            cluster_s, cluster_csv = math.nan, None
    finally:
        shutil.rmtree(work, ignore_errors=True)
    same = ("identical grades.csv" if cluster_csv == local_csv
            else "cluster run failed" if cluster_csv is None else "GRADES DIFFER")
    return [Row(SECTION, f"{n} submissions of one notebook", "time per submission",
                cluster_s / n, local_s / n, "grade --jobs 2", unit="s",
                notes=f"ours = LocalCluster, 2 worker processes × 1 thread; {same}")]
