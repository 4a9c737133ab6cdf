"""The worker: a process the supervisor forks per graded name, the only one that runs student
code. It makes itself a worker (own session, memory limit, prints captured, and last the
seccomp filter), executes the name's cells within ONE load time limit, then runs the cases
the supervisor hands it one at a time over a pipe (it holds no other case), each under an
alarm, streaming each case's encoded record back over another pipe.

Nothing here is trusted by anyone: the student's code owns this process and may replace any
of it. The supervisor keeps the deadlines; the grader re-validates every record.

Standard library and NumPy only: this module runs inside the sandbox.
"""

from __future__ import annotations

import os
import signal
import sys
import time

from .confine import WALL_FACTOR, arm_case_timers, disarm_case_timers, install_filter
from .failures import (MISSING_AFTER_REFUSAL, REFUSED_CODE, Policy, exc_mro, exc_name,
                       reference_module, refused_code, safe_str)
from .wire import (MAX_FRAME, Budget, FrameReader, NotPlain, TooLarge, decode_value,
                   encode_value, frame, record_cap, write_all)


class CaseTimeout(BaseException):
    """Raised by the worker's alarms when a cell or a case runs out of time."""


def _on_alarm(signum, frame_):
    raise CaseTimeout("time limit")


class Capture:
    """``sys.stdout``/``sys.stderr`` of a worker: keeps the first ``cap`` characters written
    (a flood of prints costs time, never memory)."""

    encoding = "utf-8"
    errors = "replace"

    def __init__(self, cap: int):
        self.cap, self.parts, self.kept, self.lost = int(cap), [], 0, 0

    def write(self, s) -> int:
        if type(s) is not str:
            s = safe_str(s, self.cap)
        room = self.cap - self.kept
        if room > 0:
            self.parts.append(s[:room])
            self.kept += min(len(s), room)
        self.lost += max(0, len(s) - max(room, 0))
        return len(s)

    def take(self) -> str:
        """What was written since the last call (capped), and forget it."""
        text = "".join(self.parts)
        if self.lost:
            text += f"\n... [{self.lost} more characters not shown]"
        self.parts, self.kept, self.lost = [], 0, 0
        return text

    def writelines(self, lines) -> None:
        for line in lines:
            self.write(line)

    def flush(self) -> None:
        pass

    def isatty(self) -> bool:
        return False

    def fileno(self) -> int:
        return 1

    def readable(self) -> bool:
        return False

    def writable(self) -> bool:
        return True


class Worker:
    """One graded name's cells and cases in this process (``nj``: the name's part of the job;
    ``ns``: the namespace the setup cell filled; ``out_fd``: the pipe to the supervisor)."""

    def __init__(self, nj: dict, ns: dict, limits: dict, policy: Policy, out_fd: int,
                 capture: Capture):
        self.nj, self.ns, self.limits, self.policy = nj, ns, limits, policy
        self.out_fd, self.capture = out_fd, capture

    def send(self, rec: dict) -> None:
        write_all(self.out_fd, frame(rec))

    def load_cells(self) -> tuple[str, bool]:
        """Execute the name's cells in order, all of them within ONE load time limit, each
        failure a note. Returns what of ``course_lib`` a failing cell tried to use (``""`` if
        none), and whether the sandbox refused a cell's compiled code (:func:`refused_code`)."""
        nj = self.nj
        reference, refused = "", False
        end = time.monotonic() + float(self.limits["load_timeout"])   # ONE budget for all
        for label, source in nj["cells"]:
            self.send({"t": "cell", "name": nj["name"], "label": label})
            left = end - time.monotonic()
            note, ref = self.run_cell(label, source, left) if left > 0.05 else \
                (f"cell {label} was not run: the cells before it used up the time limit", "")
            if ref == REFUSED_CODE:
                refused = True
            else:
                reference = reference or ref
            if note:
                self.send({"t": "note", "name": nj["name"], "text": note})
        return reference, refused

    def run_cell(self, label: str, source: str, timeout: float) -> tuple[str, str]:
        """``(note, reference)`` of one cell: why it failed (``""`` if it did not), and what of
        ``course_lib`` it tried to use (:data:`REFUSED_CODE` when the sandbox refused its
        code)."""
        try:
            code = compile(source, f"<cell {label}>", "exec")
            try:
                signal.setitimer(signal.ITIMER_REAL, timeout)
                exec(code, self.ns)
            finally:
                signal.setitimer(signal.ITIMER_REAL, 0)
        except CaseTimeout:
            return f"cell {label} was stopped: the solution cells together used up their time " \
                   "limit (an endless loop at a cell's top level?)", ""
        except SystemExit as exc:
            return f"cell {label} called sys.exit({safe_str(exc, 100)}): ignored", ""
        except BaseException as exc:  # noqa: BLE001 - student code may raise anything
            ref = reference_module(exc, self.policy.course_modules)
            note = f"cell {label} raised {exc_name(exc)}: {safe_str(exc, 300)}"
            if ref:
                note += f" ({ref} is from {self.policy.off_limits})"
            elif refused_code(exc):
                ref = REFUSED_CODE
                note += f" ({REFUSED_CODE})"
            return note, ref
        return "", ""

    def call_case(self, case: dict, refused: bool = False) -> dict:
        """Run one case; the record's ``kind`` and its value or error (``rejected-code`` when
        it failed because the sandbox refused compiled code, in this case or in the cells
        before)."""
        timeout = float(self.limits["case_timeout"])
        try:
            try:
                unlimited = Budget(1 << 62)
                args = decode_value(case["args"], unlimited)
                kwargs = decode_value(case["kwargs"], unlimited)
                target = self.ns[self.nj["name"]]
                arm_case_timers(timeout)
                value = target(*args, **kwargs) if self.nj["kind"] == "function" else target
            finally:
                disarm_case_timers()
        except CaseTimeout:
            return {"kind": "timeout", "message": f"took more than {timeout:g} s of CPU time "
                                                  f"or {WALL_FACTOR * timeout:g} s in all"}
        except BaseException as exc:  # noqa: BLE001
            ref = reference_module(exc, self.policy.course_modules)
            if ref:
                return {"kind": "reference-used",
                        "message": f"used {ref}, from {self.policy.off_limits}"}
            if refused_code(exc) or (refused and isinstance(exc, MISSING_AFTER_REFUSAL)):
                return {"kind": "rejected-code",
                        "message": f"raised {exc_name(exc)}: {safe_str(exc, 300)} "
                                   f"({REFUSED_CODE})"}
            return {"kind": "raised", "etype": exc_name(exc), "mro": exc_mro(exc),
                    "message": safe_str(exc, 500)}
        return _encode_result(value, int(case["cap"]))

    def case_record(self, given: dict, loaded: tuple[str, bool]) -> bytes:
        """The record of the case the supervisor handed over (``given``: its index, args and
        kwargs) as bytes on the wire, within its size cap."""
        nj, i = self.nj, given["i"]
        case = dict(nj["cases"][i], args=given["args"], kwargs=given["kwargs"])
        reference, refused = loaded
        self.capture.take()
        t0 = time.monotonic()
        if nj["name"] in self.ns:
            rec = self.call_case(case, refused)
        elif reference:
            rec = {"kind": "reference-used",
                   "message": f"{nj['name']!r} is not defined: its cell used {reference}, "
                              f"from {self.policy.off_limits}"}
        elif refused:
            rec = {"kind": "rejected-code",
                   "message": f"{nj['name']!r} is not defined: {REFUSED_CODE}"}
        else:
            rec = {"kind": "not-run", "message": f"{nj['name']!r} is not defined after its cells"}
        rec.update(t="case", name=nj["name"], i=i, seconds=time.monotonic() - t0,
                   printed=self.capture.take())
        try:
            data = frame(rec)
        except (ValueError, TypeError, RecursionError):
            rec.update(kind="rejected", value=None, message="the result could not be encoded")
            data = frame(rec)
        if len(data) > record_cap(case["cap"], self.limits["output_bytes"]):
            rec.update(kind="rejected", value=None, printed=rec["printed"][:1000],
                       message=f"result too large (more than {case['cap']} bytes)")
            data = frame(rec)
        return data


def _encode_result(value, cap: int) -> dict:
    try:
        return {"kind": "returned", "value": encode_value(value, Budget(cap))}
    except NotPlain as exc:
        return {"kind": "rejected", "message": f"returned {exc}, not plain numbers"}
    except TooLarge:
        return {"kind": "rejected", "message": f"result too large (more than {cap} bytes)"}
    except BaseException as exc:  # noqa: BLE001 - e.g. a RecursionError, a MemoryError
        return {"kind": "rejected", "message": f"the result could not be encoded "
                                               f"({exc_name(exc)})"}


def _worker_setup(limits: dict, bpf: bytes = b"") -> Capture:
    """Make this forked process a worker: own session, no descriptors of the supervisor, its
    memory limit, first in line for the OOM killer, prints captured, and last, before any
    student text runs, the seccomp filter ``bpf`` (when the job has one)."""
    import resource

    os.setsid()
    null = os.open(os.devnull, os.O_RDWR)
    for fd in (0, 1, 2):
        os.dup2(null, fd)
    os.close(null)
    try:
        mem = int(limits["memory_mb"]) * 2**20
        resource.setrlimit(resource.RLIMIT_AS, (mem, mem))
    except (ValueError, OSError):
        pass
    try:
        with open("/proc/self/oom_score_adj", "w") as f:
            f.write("1000")
    except OSError:
        pass
    signal.signal(signal.SIGALRM, _on_alarm)
    signal.signal(signal.SIGPROF, _on_alarm)   # a case's CPU time limit (confine)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    capture = Capture(int(limits["output_bytes"]))
    sys.stdout = sys.stderr = capture
    if bpf:
        install_filter(bpf)
    return capture


def worker_main(nj: dict, ns: dict, limits: dict, policy: Policy, fds: tuple[int, int],
                bpf: bytes = b"") -> None:
    """The worker's whole life: cells, then each case the supervisor hands over on ``fds[0]``
    until it closes that pipe, each result streamed on ``fds[1]``; never returns."""
    in_fd, out_fd = fds
    code = 0
    try:
        worker = Worker(nj, ns, limits, policy, out_fd, _worker_setup(limits, bpf))
        loaded = worker.load_cells()
        worker.send({"t": "loaded", "name": nj["name"], "defined": nj["name"] in ns,
                     "printed": worker.capture.take()})
        reader = FrameReader(in_fd, MAX_FRAME)    # the supervisor's frames: no case's length
        while True:
            event, payload = reader.next(float("inf"))
            given = payload[0] if event == "record" else None
            if given is None or given.get("t") != "case" or type(given.get("i")) is not int \
                    or not 0 <= given["i"] < len(nj["cases"]):
                break
            write_all(out_fd, worker.case_record(given, loaded))
        worker.send({"t": "done", "name": nj["name"]})
    except BaseException:  # noqa: BLE001 - e.g. the pipe closed: the supervisor decides
        code = 70
    os._exit(code)
