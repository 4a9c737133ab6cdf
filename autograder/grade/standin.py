"""TEMPORARY stand-in for ``autograder.isolation`` (branch ``iso``), same interface.

Runs each name of a :class:`NotebookJob` with the old in-process-hardened
:mod:`autograder.sandbox`. Deleted when the OS-level sandbox lands.
"""

from __future__ import annotations

import enum
import os
import queue
import shutil
import tempfile
from dataclasses import dataclass, field

from .. import sandbox
from ..exercises import REGISTRY
from ..model import CaseOutcome, NameRun, OutcomeKind

UNSAFE_WARNING = ("WARNING: grading WITHOUT operating-system isolation: student code runs with "
                  "this user's rights")


class Mode(str, enum.Enum):
    ISOLATED = "isolated"
    UNSAFE = "unsafe"


class IsolationUnavailable(RuntimeError):
    pass


@dataclass
class Limits:
    case_timeout: float = 10.0
    load_timeout: float = 40.0
    memory_mb: int = 2048
    scratch_mb: int = 64
    pids: int = 64
    output_bytes: int = 20_000
    max_launches: int = 3


@dataclass
class CaseInput:
    args: tuple
    kwargs: dict
    result_cap: int = 2**20


@dataclass
class NameJob:
    name: str
    kind: str
    cells: list
    cases: list[CaseInput] = field(default_factory=list)


@dataclass
class NotebookJob:
    job_id: str
    setup_source: str
    names: list[NameJob]


def probe() -> Mode:
    if os.environ.get("AUTOGRADER_FAKE_NO_ISOLATION"):
        raise IsolationUnavailable("isolation disabled by AUTOGRADER_FAKE_NO_ISOLATION")
    return Mode.ISOLATED


_SLOTS: queue.Queue[int] = queue.Queue()
for _k in range(16):
    _SLOTS.put(_k)


def _targets():
    refs = sorted({(ex.reference.__module__, ex.reference.__name__) for ex in REGISTRY.values()
                   if ex.kind == "function" and ex.reference is not None
                   and str(ex.reference.__module__).startswith("course_lib.")})
    return refs, sorted(n for n, ex in REGISTRY.items() if ex.kind == "function")


#: Folders the children may not read (set by the command line: submissions, sources, output).
DENY: list[str] = []


def run_notebook(job: NotebookJob, limits: Limits, mode: Mode) -> dict[str, NameRun]:
    refs, graded = _targets()
    old = sandbox.Limits(case_timeout=limits.case_timeout, load_timeout=limits.load_timeout,
                         memory_mb=limits.memory_mb, output_bytes=limits.output_bytes,
                         max_launches=limits.max_launches)
    workdir = tempfile.mkdtemp(prefix="4f9-standin-")
    os.chmod(workdir, 0o711)
    slot = _SLOTS.get()
    runs = {}
    try:
        for nj in job.names:
            sj = sandbox.SandboxJob(nj.name, nj.kind, job.setup_source, list(nj.cells),
                                    [(c.args, c.kwargs) for c in nj.cases], refs, graded,
                                    deny_paths=list(sandbox.protected_dirs()) + list(DENY))
            r = sandbox.run_job(sj, old, workdir, slot)
            outs = [CaseOutcome(o.index, OutcomeKind(o.kind), o.value, o.error_type,
                                tuple(o.error_mro), o.message, o.seconds) for o in r.outcomes]
            runs[nj.name] = NameRun(nj.name, outs, r.defined, list(r.load_notes),
                                    (r.stdout + r.stderr), r.launches, r.seconds)
    finally:
        _SLOTS.put(slot)
        shutil.rmtree(workdir, ignore_errors=True)
    return runs
