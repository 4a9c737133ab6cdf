"""``grade --scheduler tcp://...``: the sandboxes run on a dask.distributed cluster's workers.

A ``LocalCluster`` of two worker processes (each with its nanny) stands for the machines of a
real cluster. The same class graded with ``--jobs 2`` on this machine is the oracle: the
cluster's ``grades.csv`` must be the same, byte for byte (the same secret draws the same
cases; nothing is timed in the CSV). Then one worker is killed (SIGKILL) while it runs a job:
the scheduler hands that job to a worker still alive, and the batch still ends with exactly
the same grades. The scheduler's own transition log shows a lost job entered "processing"
twice. A notebook's job takes seconds (one sandbox per graded name), so the kill, a few
milliseconds after the scheduler reports the job running, lands while it runs.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from gradingtools import REPO, SECRET, model_version, release_version, run_grade, write_nb

pytestmark = [pytest.mark.xdist_group("dask"), pytest.mark.slow]

A = "tripos2006"


def _student_notebook(src, k: int) -> dict:
    return model_version(src) if k % 2 == 0 else release_version(src)


@pytest.fixture(scope="module")
def cluster():
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      scheduler_port=0, dashboard_address=None) as local:
        yield local


@pytest.fixture(scope="module")
def classroom(tmp_path_factory, sources):
    """Four students, two notebooks each, graded once with ``--jobs 2`` (the oracle)."""
    root = tmp_path_factory.mktemp("dask")
    (root / "secret").write_bytes(SECRET + b"\n")
    picked = sources[:2]
    for k in range(4):
        for src in picked:
            write_nb(root / "submitted" / f"s{k}" / A / f"{src.name}.ipynb",
                     _student_notebook(src, k))
    run_grade(root / "submitted", root / "local", "--no-gradebook", jobs=2,
              secret_file=root / "secret")
    return {"root": root, "csv": (root / "local" / "grades.csv").read_text(),
            "jobs": 4 * len(picked)}


def _grade_command(classroom, out, address) -> list[str]:
    return [sys.executable, "-m", "autograder", "grade", str(classroom["root"] / "submitted"),
            "--out", str(out), "--scheduler", address, "--timeout", "1.5",
            "--load-timeout", "20", "--secret-file", str(classroom["root"] / "secret"),
            "--quiet", "--no-gradebook"]


def test_cluster_grades_exactly_as_local_jobs(classroom, cluster):
    out = classroom["root"] / "cluster"
    run_grade(classroom["root"] / "submitted", out, "--no-gradebook", "--scheduler",
              cluster.scheduler_address, secret_file=classroom["root"] / "secret")
    assert (out / "grades.csv").read_text() == classroom["csv"]
    assert classroom["csv"].count("\n") > classroom["jobs"]


def _processing(client) -> dict[str, list[str]]:
    """``{worker address: keys of grading jobs it is running}``."""
    return {w: [k for k in keys if str(k).startswith("autograder-")]
            for w, keys in client.processing().items()}


def _kill_a_busy_worker(client, proc, pids: dict[str, int], patience: float = 120.0) -> list[str]:
    """SIGKILL a worker process (``pids``: address -> pid) while it runs a grading job; the
    keys it was running."""
    end = time.monotonic() + patience
    while time.monotonic() < end and proc.poll() is None:
        busy = {w: keys for w, keys in _processing(client).items() if keys}
        if busy:
            worker, keys = next(iter(busy.items()))
            os.kill(pids[worker], signal.SIGKILL)
            return keys
        time.sleep(0.05)
    raise AssertionError("no worker was seen running a grading job")


def _times_processing(client, keys: list[str]) -> dict[str, int]:
    def count(dask_scheduler, keys=tuple(keys)):
        seen = {k: 0 for k in keys}
        for entry in dask_scheduler.transition_log:
            if entry[0] in seen and entry[2] == "processing":
                seen[entry[0]] += 1
        return seen

    return client.run_on_scheduler(count)


def test_a_worker_killed_mid_batch_loses_no_job(classroom, cluster):
    from distributed import Client

    out = classroom["root"] / "killed"
    env = dict(os.environ, MPLBACKEND="Agg")
    with Client(cluster.scheduler_address, set_as_default=False) as client:
        client.wait_for_workers(2, timeout=60)
        pids = client.run(os.getpid)
        proc = subprocess.Popen(_grade_command(classroom, out, cluster.scheduler_address),
                                cwd=REPO, env=env, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
        try:
            lost = _kill_a_busy_worker(client, proc, pids)
            _, stderr = proc.communicate(timeout=600)
        finally:
            if proc.poll() is None:
                proc.kill()
        assert proc.returncode == 0, stderr[-3000:]
        # a job the worker had just finished as it died is not run again: one rerun suffices
        assert lost and any(n >= 2 for n in _times_processing(client, lost).values()), lost
        client.wait_for_workers(2, timeout=60)      # the nanny restarts the killed worker
    assert (out / "grades.csv").read_text() == classroom["csv"]


def test_the_grading_machine_needs_no_sandbox_of_its_own(classroom, cluster, monkeypatch):
    """Only the workers run students' code: with ``--scheduler`` the local probe is not
    consulted (here it would refuse), and the grades are still the oracle's."""
    import argparse

    from autograder.grade import cli
    from autograder.isolation import IsolationUnavailable

    def no_local_sandbox():
        raise IsolationUnavailable("no bubblewrap on the grading machine (test)")

    monkeypatch.setattr(cli, "probe", no_local_sandbox)
    parser = argparse.ArgumentParser()
    cli.add_arguments(parser)
    out = classroom["root"] / "no-local-sandbox"
    args = parser.parse_args(_grade_command(classroom, out, cluster.scheduler_address)[4:])
    assert cli.main(args) == 0
    assert (out / "grades.csv").read_text() == classroom["csv"]
