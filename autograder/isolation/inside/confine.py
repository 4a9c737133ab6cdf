"""How the sandbox's processes confine themselves: resource limits, ``prctl`` (the parent-death
signal, non-dumpable), the modules loaded while compiled code still may be, the seccomp
filter a worker installs before any student text runs, and the clocks a case is timed on.

A case's time limit is CPU time, on the worker's own CPU clock: a busy machine or a neighbour
slows an honest case's wall clock, not its CPU clock, so neither turns it into a timeout. A case
that passes its time off the CPU (asleep, waiting on a child) is stopped by a wall-clock
backstop, :data:`WALL_FACTOR` times the limit.

Standard library only: this module runs inside the sandbox.
"""

from __future__ import annotations

import os
import signal

#: The wall-clock backstop of a case, in multiples of its CPU time limit.
WALL_FACTOR = 3.0
_KEPT: list = []      #: libraries loaded for good before the filter
PR_SET_PDEATHSIG = 1
PR_SET_DUMPABLE = 4
PR_GET_SECCOMP = 21
PR_SET_SECCOMP = 22
SECCOMP_MODE_FILTER = 2
PR_SET_NO_NEW_PRIVS = 38


def prctl(option: int, arg: int) -> None:
    """``prctl(option, arg)`` (Linux); silently nothing elsewhere."""
    try:
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(option, arg, 0, 0, 0)
    except (OSError, AttributeError):
        pass


def install_filter(bpf: bytes) -> None:
    """Install the seccomp filter ``bpf`` (classic BPF from the grader, see
    ``autograder.isolation.seccomp``) on this process, for good; ``OSError`` if the kernel
    refuses. ``no_new_privs`` first: the kernel demands it of a process without privileges."""
    import ctypes

    class SockFprog(ctypes.Structure):
        _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.c_void_p)]

    libc = ctypes.CDLL(None, use_errno=True)
    code = ctypes.create_string_buffer(bpf, len(bpf))
    prog = SockFprog(len(bpf) // 8, ctypes.addressof(code))
    if libc.prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0 or \
            libc.prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, ctypes.byref(prog), 0, 0) != 0:
        err = ctypes.get_errno()
        raise OSError(err, f"the seccomp filter could not be installed ({os.strerror(err)})")


def seccomp_supported() -> bool:
    """True when this kernel can install seccomp filters (``PR_GET_SECCOMP`` answers)."""
    import ctypes

    try:
        return ctypes.CDLL(None, use_errno=True).prctl(PR_GET_SECCOMP, 0, 0, 0, 0) >= 0
    except (OSError, AttributeError):
        return False


def preload(modules: list) -> list:
    """Import the modules a solution may use (the grader's allow-list) while compiled code can
    still be loaded, and ``libgcc_s`` (glibc loads it when a thread ends); what failed, as
    notes."""
    import ctypes
    import importlib

    notes = []
    try:
        _KEPT.append(ctypes.CDLL("libgcc_s.so.1"))   # kept loaded: glibc finds it there later
    except OSError:
        notes.append("the sandbox could not load libgcc_s.so.1: threads may fail")
    for name in modules:
        try:
            importlib.import_module(name)
        except ImportError as exc:
            notes.append(f"the sandbox could not load the allowed module {name} ({exc})")
    return notes


def set_rlimits(limits: dict, budget_seconds: float) -> None:
    """The supervisor's own limits (no core files, the scratch's size, CPU seconds, processes
    when root gave the job a uid of its own): every worker inherits them and cannot raise them."""
    import resource

    mb = 2**20
    wanted = [(resource.RLIMIT_CORE, 0), (resource.RLIMIT_FSIZE, (limits["scratch_mb"] + 1) * mb),
              (resource.RLIMIT_CPU, int(budget_seconds) + 5)]
    if limits.get("nproc"):
        wanted.append((resource.RLIMIT_NPROC, int(limits["pids"])))
    for which, value in wanted:
        try:
            _soft, hard = resource.getrlimit(which)
            value = value if hard == resource.RLIM_INFINITY else min(value, hard)
            resource.setrlimit(which, (value, value))
        except (ValueError, OSError):
            pass



def arm_case_timers(seconds: float) -> None:
    """Signal this process after ``seconds`` of its CPU time (``SIGPROF``) or ``WALL_FACTOR``
    times that in wall-clock time (``SIGALRM``), whichever comes first."""
    signal.setitimer(signal.ITIMER_PROF, seconds)
    signal.setitimer(signal.ITIMER_REAL, WALL_FACTOR * seconds)


def disarm_case_timers() -> None:
    signal.setitimer(signal.ITIMER_PROF, 0)
    signal.setitimer(signal.ITIMER_REAL, 0)


def process_cpu_seconds(pid: int) -> float:
    """CPU seconds used by process ``pid``: all its threads, and its children it has waited
    for (``/proc/<pid>/stat``: utime, stime, cutime, cstime); 0.0 once it is gone."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            text = f.read()
        fields = text[text.rindex(b")") + 2:].split()   # from field 3 (the state) on
        ticks = sum(int(x) for x in fields[11:15])       # fields 14 to 17
    except (OSError, ValueError):
        return 0.0
    return ticks / os.sysconf("SC_CLK_TCK")
