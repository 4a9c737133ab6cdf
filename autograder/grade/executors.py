"""Where the batch's sandboxes run: threads on this machine, or the workers of a dask cluster.

:func:`grade_batch <autograder.grade.batch.grade_batch>` plans every student's notebook here,
on the instructor's machine (the hidden cases are drawn from the course secret, and the
expected values computed, before anything leaves it), then hands the plain
:class:`~autograder.isolation.NotebookJob` of each notebook to an executor:

- :class:`ThreadExecutor` (``--jobs N``): N threads, each waiting on one local sandbox;
- :class:`DaskExecutor` (``--scheduler tcp://HOST:PORT``): one dask.distributed task per
  notebook. The task (:func:`run_sandboxed`) carries everything a worker needs (the setup
  cell, the student's planned cells, the cases' inputs) and returns the plain
  ``{name: NameRun}``; the worker runs it in its own host's sandbox. Neither the secret, nor
  the expected values, nor the model answers are sent. The client alone judges and writes the
  outputs and the gradebook.

A job is idempotent (a fresh sandbox, a fresh temporary folder and a uid lease each time, no
output written by the worker), so dask may run it again when the worker running it dies; the
scores cannot change with the number of attempts.
"""

from __future__ import annotations

import itertools
import uuid
from collections.abc import Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

from ..isolation import Limits, Mode, NotebookJob, probe, run_notebook
from ..model import NameRun

#: Seconds a client waits for the scheduler, and then for its first worker.
CONNECT_SECONDS = 30.0
#: Jobs handed to a cluster ahead of its workers, per worker thread (at least
#: :data:`MIN_CLUSTER_WINDOW`): enough to keep every worker busy, few enough that the grader
#: never holds every notebook's drawn cases and expected values at once.
AHEAD_PER_THREAD = 4
MIN_CLUSTER_WINDOW = 16

#: A job to run, under the caller's key (an index of its own notebooks).
Keyed = tuple[int, NotebookJob]
#: What a finished job gives back: its key, and its runs or the exception it raised (a grader
#: problem; the caller turns it into ``grader-error`` rows).
Finished = tuple[int, "dict[str, NameRun] | BaseException"]


class ClusterUnavailable(RuntimeError):
    """``--scheduler`` cannot be used: dask.distributed is missing or the scheduler is unreachable."""


def run_sandboxed(job: NotebookJob, limits: Limits, mode: Mode) -> dict[str, NameRun]:
    """Run one notebook's job in this host's sandbox (the task a worker runs).

    With ``mode`` ISOLATED the host's own sandbox is probed first, so a worker host without
    bubblewrap fails with :class:`~autograder.isolation.IsolationUnavailable` instead of
    running students' code unconfined.
    """
    if mode is Mode.ISOLATED:
        probe()
    return run_notebook(job, limits, mode)


class ThreadExecutor:
    """``jobs`` threads on this machine, each waiting on one sandbox (``--jobs``)."""

    def __init__(self, jobs: int = 1):
        if type(jobs) is not int or jobs < 1:
            raise ValueError(f"jobs must be a positive int, got {jobs!r}")
        self.jobs = jobs

    def run(self, keyed: Iterable[Keyed], limits: Limits, mode: Mode) -> Iterator[Finished]:
        """Yield ``(key, runs or exception)`` for every job, in the order they finish; at most
        twice as many jobs as threads are taken from ``keyed`` before one has finished."""
        todo = iter(keyed)
        with ThreadPoolExecutor(max_workers=self.jobs) as pool:
            pending = {pool.submit(run_sandboxed, job, limits, mode): key
                       for key, job in itertools.islice(todo, 2 * self.jobs)}
            while pending:
                done, _ = wait(pending, return_when=FIRST_COMPLETED)
                for fut in done:
                    exc = fut.exception()
                    yield pending.pop(fut), exc if exc is not None else fut.result()
                    for key, job in itertools.islice(todo, 1):
                        pending[pool.submit(run_sandboxed, job, limits, mode)] = key


class DaskExecutor:
    """One dask.distributed task per job on the cluster at ``address`` (``--scheduler``)."""

    def __init__(self, address: str):
        if type(address) is not str or "://" not in address:
            raise ValueError(f"scheduler must be an address such as tcp://HOST:8786, got "
                             f"{address!r}")
        self.address = address

    def _client(self):
        try:
            from distributed import Client
        except ImportError:
            raise ClusterUnavailable(
                "--scheduler needs dask.distributed, which is not installed: pip install "
                "'4f9-course[cluster]' (or `pip install distributed`)") from None
        try:
            client = Client(self.address, timeout=CONNECT_SECONDS, set_as_default=False)
        except (OSError, TimeoutError) as exc:
            raise ClusterUnavailable(f"cannot reach the dask scheduler at {self.address}: "
                                     f"{exc}") from None
        try:
            client.wait_for_workers(1, timeout=CONNECT_SECONDS)
        except (OSError, TimeoutError):
            client.close()
            raise ClusterUnavailable(f"the dask scheduler at {self.address} has no worker "
                                     f"(start one with `dask worker {self.address}`)") from None
        return client

    def run(self, keyed: Iterable[Keyed], limits: Limits, mode: Mode) -> Iterator[Finished]:
        """Yield ``(key, runs or exception)`` for every job, in the order they finish; jobs are
        taken from ``keyed`` only as far ahead of the workers as :data:`AHEAD_PER_THREAD`."""
        from distributed import as_completed as dask_completed

        client = self._client()
        try:
            batch_id = uuid.uuid4().hex[:12]
            threads = sum(client.nthreads().values())
            window = max(MIN_CLUSTER_WINDOW, AHEAD_PER_THREAD * threads)
            todo, keys = iter(keyed), {}
            finished = dask_completed(loop=client.loop)

            def submit(key: int, job: NotebookJob) -> None:
                fut = client.submit(run_sandboxed, job, limits, mode,
                                    key=f"autograder-{batch_id}-{key}")
                keys[fut.key] = key
                finished.add(fut)

            for key, job in itertools.islice(todo, window):
                submit(key, job)
            for fut in finished:
                outcome = _result(fut)
                fut.release()
                yield keys.pop(fut.key), outcome
                for key, job in itertools.islice(todo, 1):
                    submit(key, job)
        finally:
            client.close()


def _result(fut):
    """A finished future's result, or the exception it raised (the task's own, or
    ``KilledWorker`` when the job's workers died more often than the scheduler allows)."""
    try:
        return fut.result()
    except Exception as exc:  # noqa: BLE001 - reported as that notebook's grader error
        return exc


def make_executor(jobs: int = 1, scheduler: str | None = None):
    """The executor of a batch: a :class:`DaskExecutor` when ``scheduler`` is given, else a
    :class:`ThreadExecutor` of ``jobs`` threads."""
    return DaskExecutor(scheduler) if scheduler else ThreadExecutor(max(1, jobs))
