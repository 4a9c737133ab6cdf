"""The sandbox program's start: the supervisor limits itself, executes the instructor's setup
cell, then runs each graded name (:class:`~.supervisor.NameSupervisor`).

In order: the parent-death signal and non-dumpable (so a worker of the same uid can neither
ptrace it nor open its descriptors via ``/proc``), its rlimits (inherited, and never raised
again), ``sys.path`` cut to the interpreter's standard library and the site dir (NumPy, the
allow-listed tables), the allowed modules loaded while compiled code still may be, the setup
cell (trusted, from the source notebook), and one :class:`~.supervisor.NameSupervisor` per
graded name. Everything it needs comes in the job document: the limits, the setup cell, the
names and where their cases are (the inputs themselves come through an inherited descriptor,
:class:`~.supervisor.NameSupervisor`), the modules to preload, the grader's ``course_lib``
policy and the seccomp filter every worker installs before any student text runs.

Standard library and NumPy only: this module runs inside the sandbox.
"""

from __future__ import annotations

import base64
import json
import os
import signal
import sys
import time

from .confine import (PR_SET_DUMPABLE, PR_SET_PDEATHSIG, preload, prctl, seccomp_supported,
                      set_rlimits)
from .failures import Policy, exc_name, safe_str
from .supervisor import NameSupervisor
from .wire import CaseStream, frame, write_all
from .worker import Capture, CaseTimeout


def _notebook_helpers(ns: dict) -> None:
    """What a notebook cell may expect from IPython (magics were stripped by the grader)."""

    class NoIPython:
        def __getattr__(self, name):
            return lambda *a, **k: None

    no_ipython = NoIPython()
    ns.setdefault("display", lambda *a, **k: None)
    ns.setdefault("get_ipython", lambda: no_ipython)


def run_setup(source: str, ns: dict, timeout: float) -> list:
    """Execute the instructor's setup cell (trusted) under a time limit; notes on failure."""
    def on_alarm(signum, frame_):
        raise CaseTimeout("time limit")

    signal.signal(signal.SIGALRM, on_alarm)
    notes = []
    try:
        try:
            signal.setitimer(signal.ITIMER_REAL, timeout)
            exec(compile(source, "<setup cell>", "exec"), ns)
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
    except CaseTimeout:
        notes.append(f"the setup cell did not finish within {timeout:g} s")
    except BaseException as exc:  # noqa: BLE001 - reported, never fatal
        notes.append(f"the setup cell raised {exc_name(exc)}: {safe_str(exc, 300)}")
    signal.signal(signal.SIGALRM, signal.SIG_IGN)
    _notebook_helpers(ns)
    return notes


def _parse_args(argv: list) -> dict:
    opts = {"--job": "/job", "--site": "", "--channel-fd": "", "--cases-fd": ""}
    it = iter(argv)
    for arg in it:
        if arg not in opts:
            raise SystemExit(f"the sandbox program: unknown argument {arg!r}")
        opts[arg] = next(it)
    return opts


def main(argv: list) -> None:
    """The supervisor's entry point (``__main__.py --job FILE --site DIR --channel-fd N
    --cases-fd M``)."""
    opts = _parse_args(argv)
    channel, cases_fd = int(opts["--channel-fd"]), int(opts["--cases-fd"])
    prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
    prctl(PR_SET_DUMPABLE, 0)
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, signal.SIG_DFL)
    with open(opts["--job"], "rb") as f:
        job = json.loads(f.read())
    limits, policy = job["limits"], Policy.from_job(job)
    job_deadline = time.monotonic() + float(limits["job_timeout"])
    set_rlimits(limits, float(limits["budget_seconds"]))
    # the interpreter's own standard library, then the site dir (NumPy, the allowed tables)
    stdlib = [p for p in sys.path if p.startswith(sys.base_prefix + os.sep)]
    sys.path[:] = stdlib + ([opts["--site"]] if opts["--site"] else [])
    import builtins

    import numpy  # noqa: F401 - imported once here, inherited by every worker

    bpf = base64.b64decode(job.get("filter") or "")
    if bpf and not seccomp_supported():   # before any record: the grader's problem
        raise SystemExit("the sandbox program: this kernel cannot install seccomp "
                         "filters")
    notes = preload(list(job.get("modules") or ()))
    sys.stdout = sys.stderr = Capture(int(limits["output_bytes"]))
    ns = {"__name__": "__main__", "__builtins__": builtins}
    for note in notes + run_setup(job["setup"], ns, float(limits["load_timeout"])):
        write_all(channel, frame({"t": "note", "name": None, "text": note}))
    import gc

    gc.freeze()   # what the workers inherit is never collected there: no copy-on-write storm
    cases, first = CaseStream(cases_fd), 0
    for nj in job["names"]:
        NameSupervisor(nj, ns, limits, policy, (channel, cases), job_deadline, bpf,
                       str(job.get("scratch") or ""), first).run()
        first += len(nj["cases"])
    write_all(channel, frame({"t": "done"}))
    os._exit(0)

