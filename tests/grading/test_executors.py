"""The executors behind ``grade --jobs`` and ``grade --scheduler`` (autograder/grade/executors.py).

The sandbox itself is replaced by a stand-in here (its own tests are test_isolation.py and the
batch tests): these check what the executors promise the batch. Every job comes back exactly
once under its key, a job that raises comes back as its exception, only a bounded number of
jobs are planned ahead of the ones finished, and a scheduler that cannot be reached is a
:class:`ClusterUnavailable` that says where.
"""

from __future__ import annotations

import threading
import time

import pytest

from autograder.grade import executors
from autograder.isolation import Limits, Mode, NotebookJob


def _job(k: int) -> NotebookJob:
    return NotebookJob(f"student{k}--q1", "import numpy as np\n", [])


@pytest.fixture
def fake_sandbox(monkeypatch):
    """``run_sandboxed`` replaced: job ``student3`` raises, the others answer their job id."""
    running = {"now": 0, "most": 0}
    lock = threading.Lock()

    def fake(job, limits, mode):
        with lock:
            running["now"] += 1
            running["most"] = max(running["most"], running["now"])
        time.sleep(0.01)
        with lock:
            running["now"] -= 1
        if job.job_id.startswith("student3-"):
            raise RuntimeError("the sandbox did not start")
        return {"answer": job.job_id}

    monkeypatch.setattr(executors, "run_sandboxed", fake)
    return running


def test_every_job_comes_back_once_under_its_key(fake_sandbox):
    got = dict(executors.ThreadExecutor(3).run(((k, _job(k)) for k in range(20)), Limits(),
                                               Mode.UNSAFE))
    assert sorted(got) == list(range(20))
    assert isinstance(got[3], RuntimeError)
    assert all(got[k] == {"answer": f"student{k}--q1"} for k in range(20) if k != 3)
    assert fake_sandbox["most"] <= 3


def test_jobs_are_planned_only_a_little_ahead(fake_sandbox):
    pulled, finished, ahead = [0], [0], []

    def planned():
        for k in range(30):
            pulled[0] += 1
            ahead.append(pulled[0] - finished[0])
            yield k, _job(k)

    for _key, _outcome in executors.ThreadExecutor(2).run(planned(), Limits(), Mode.UNSAFE):
        finished[0] += 1
    assert finished[0] == 30
    assert max(ahead) <= 2 * 2 + 1


def test_bad_arguments_are_named():
    with pytest.raises(ValueError, match="jobs"):
        executors.ThreadExecutor(0)
    with pytest.raises(ValueError, match="scheduler"):
        executors.DaskExecutor("localhost:8786")
    assert isinstance(executors.make_executor(2, None), executors.ThreadExecutor)
    assert isinstance(executors.make_executor(2, "tcp://127.0.0.1:8786"), executors.DaskExecutor)


def test_an_unreachable_scheduler_is_named(monkeypatch):
    import socket

    with socket.socket() as s:          # a port nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    monkeypatch.setattr(executors, "CONNECT_SECONDS", 2.0)
    runs = executors.DaskExecutor(f"tcp://127.0.0.1:{port}").run([(0, _job(0))], Limits(),
                                                                  Mode.UNSAFE)
    with pytest.raises(executors.ClusterUnavailable, match=f"127.0.0.1:{port}"):
        next(runs)
