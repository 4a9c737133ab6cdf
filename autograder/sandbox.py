"""Run one graded name of one submission in a separate, resource-limited process.

The batch grader (:mod:`autograder.grading`) never runs a student's code in its own process. For
every (student, notebook, graded name) it calls :func:`run_job`, which starts a fresh Python
(``python -I -B autograder/sandbox.py --child DIR``) that

1. limits itself (``RLIMIT_CPU``, ``RLIMIT_AS``, ``RLIMIT_FSIZE``, ``RLIMIT_NPROC``, no core
   dumps) and runs with one BLAS/OpenMP thread, a scrubbed environment and a fresh scratch
   directory as its working directory and ``HOME``; when the grader runs as root the child also
   runs as an unprivileged uid (one per worker slot, gid ``nogroup``), so the operating system
   keeps it away from other students' files, the gradebook, the course secret and the sources;
2. executes the instructor's setup cell (taken from the *source* notebook, never from the
   submission), then replaces every ``course_lib`` reference implementation of a graded name by a
   stub that raises :class:`ReferenceUsed` (a graded function that calls the reference scores 0
   with status ``reference-used``);
3. installs an audit hook (:pep:`578`) that denies opening files outside the scratch directory and
   Python's own libraries (so the course's sources, the registry and other submissions cannot be
   read even when the uid cannot be dropped), starting processes, sending signals, sockets and
   ``ctypes``; ``sys.exit``/``os._exit`` become ordinary exceptions. The hook calls no code the
   student can patch (no ``builtins`` lookups, no ``posixpath``; only exact ``str``/``bytes``
   paths) and keeps its configuration out of reach (``gc`` introspection, tracing and changing
   a function's defaults are denied); the builtins are restored after every cell and case;
4. executes the student's solution cells in notebook order (IPython magics and shell lines
   removed), each under a time limit, so one broken cell costs only what depends on it;
5. calls the graded function on each case under a per-case time limit and *streams* each
   outcome to the grader as it happens: a JSON line on a pipe, arrays in ``case_<i>.npz``. A case
   that crashes or hangs the process therefore keeps every earlier case's result, and the grader
   restarts the child for the remaining cases (a bounded number of times).

Only plain data crosses back (JSON scalars, strings, tuples and numeric arrays loaded with
``np.load(..., allow_pickle=False)`` after checking the file); the comparison with the reference
runs in the grader's process (:mod:`autograder.grading`), so an object whose ``__eq__`` always
returns True never meets the expected value at all.

This module is also the child's program, so its top level imports nothing beyond the standard
library (NumPy is imported where needed): ``autograder`` itself is not readable from the child.
"""

from __future__ import annotations

import json
import os
import select
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from typing import Any

#: The first uid used for sandboxed children when the grader runs as root (worker slot k runs as
#: ``SANDBOX_UID_BASE + k``, so two children never share a uid and cannot signal each other).
SANDBOX_UID_BASE = 64000
#: Their gid (Debian's ``nogroup``).
SANDBOX_GID = 65534

MANIFEST_FD_ENV = "AUTOGRADER_MANIFEST_FD"
_MANIFEST_CAP = 8 * 2**20          # bytes of manifest the grader reads before giving up
_NPZ_CAP = 256 * 2**20             # bytes of one case's arrays the grader accepts
_STRING_CAP = 20_000               # characters of a returned string
_GRACE = 1.0                       # seconds the grader waits beyond the child's own alarm
_TIMEOUTS_IN_A_ROW = 3             # after this many, a function's remaining cases are not run


@dataclass
class Limits:
    """Resource limits of one sandboxed run (the defaults suit the course's exercises)."""

    case_timeout: float = 10.0       #: seconds per case (wall clock)
    load_timeout: float = 60.0       #: seconds for the setup cell and the solution cells
    memory_mb: int = 2048            #: address space (RLIMIT_AS)
    fsize_mb: int = 64               #: largest file the child may write (RLIMIT_FSIZE)
    nproc: int = 64                  #: processes/threads of the sandbox uid (RLIMIT_NPROC)
    output_bytes: int = 20_000       #: captured stdout/stderr kept for the feedback
    max_launches: int = 3            #: child processes per graded name (restarts after a crash)


@dataclass
class SandboxJob:
    """Everything the child needs: code, the graded name and the cases' inputs (plain data)."""

    name: str                                   #: the graded name (function or choice variable)
    kind: str                                   #: "function" or "choice"
    setup_source: str                           #: the instructor's setup cell
    cells: list[tuple[str, str]]                #: (label, python source) of the student's cells
    cases: list[tuple[tuple, dict]]             #: (args, kwargs) per case; one empty for choice
    reference_targets: list[tuple[str, str]] = field(default_factory=list)  #: (module, qualname)
    #: graded names: a course_lib function of that name is stubbed wherever it is found
    graded_names: list[str] = field(default_factory=list)
    protected_prefixes: list[str] = field(default_factory=lambda: ["course_lib"])
    deny_paths: list[str] = field(default_factory=list)    #: directories the child may not read


@dataclass
class CaseOutcome:
    """What happened in one case, as observed by the grader (no verdict yet)."""

    index: int
    #: returned | raised | timeout | crashed | rejected | reference-used | not-run
    kind: str
    value: Any = None   #: the decoded plain data for ``returned``
    error_type: str = ""
    error_mro: tuple = ()
    message: str = ""
    seconds: float = 0.0


@dataclass
class SandboxResult:
    outcomes: list[CaseOutcome]
    defined: bool = True             #: the graded name existed after the cells ran
    load_notes: list[str] = field(default_factory=list)
    stdout: str = ""
    stderr: str = ""
    launches: int = 0
    seconds: float = 0.0


# ============================================================================================
# the grader's side


def sandbox_identity(slot: int = 0) -> tuple[int, int] | None:
    """``(uid, gid)`` for worker ``slot`` when running as root, else ``None`` (no uid change)."""
    if os.name != "posix" or os.geteuid() != 0:
        return None
    return SANDBOX_UID_BASE + int(slot), SANDBOX_GID


DROP_ENV = "AUTOGRADER_DROP_TO"
#: Standard modules imported before the privilege drop (the interpreter's own files may be
#: unreadable to the sandbox uid afterwards, e.g. under ``/root/.pyenv``).
_PRELOAD = ("math", "cmath", "fractions", "decimal", "statistics", "itertools", "functools",
            "collections", "collections.abc", "dataclasses", "typing", "warnings", "re", "copy",
            "heapq", "bisect", "operator", "random", "string", "textwrap", "enum", "numbers",
            "contextlib", "traceback", "json", "numpy.linalg", "numpy.fft", "numpy.random",
            "numpy.polynomial", "numpy.testing", "unittest", "inspect", "ast", "dis", "pprint",
            "datetime", "array", "struct", "io", "pathlib", "glob", "csv", "copyreg", "weakref",
            "types", "time", "calendar", "hashlib", "base64", "itertools", "difflib", "locale",
            "string", "random", "secrets", "bisect", "queue", "threading", "signal", "os",
            "collections", "numbers", "decimal", "fractions", "statistics", "operator",
            "functools", "typing", "warnings", "textwrap", "re", "copy", "abc", "enum",
            "contextlib", "dataclasses", "heapq", "math", "cmath", "unicodedata", "zlib",
            "gzip", "zipfile", "tempfile", "shutil", "fnmatch", "sqlite3", "pickle")


def protected_dirs() -> list[str]:
    """Package directories the child must never read (course_lib's and autograder's sources)."""
    here = os.path.dirname(os.path.abspath(__file__))
    dirs = [here]
    try:
        import course_lib

        dirs.extend(os.path.abspath(p) for p in course_lib.__path__)
    except ImportError:  # pragma: no cover - course_lib is part of the project
        pass
    return dirs


def run_job(job: SandboxJob, limits: Limits, workdir: str, slot: int = 0,
            zygote: Zygote | None = None) -> SandboxResult:
    """Run ``job`` in a fresh child (restarted after a crash) and return every case's outcome.

    ``workdir`` is a directory of the grader's (the scratch directories are created inside it and
    removed afterwards); ``zygote`` (optional) starts the child by forking a warm interpreter.
    Never raises because of what the student's code did.
    """
    t0 = time.monotonic()
    n = len(job.cases)
    outcomes: dict[int, CaseOutcome] = {}
    result = SandboxResult(outcomes=[])
    start = 0
    stdout_parts, stderr_parts = [], []
    while start < n and result.launches < limits.max_launches:
        result.launches += 1
        run = _launch(job, limits, workdir, slot, start, zygote)
        stdout_parts.append(run["stdout"])
        stderr_parts.append(run["stderr"])
        if result.launches == 1:
            result.defined = run["defined"]
            result.load_notes = run["load_notes"]
        outcomes.update(run["outcomes"])
        if run["done"]:
            break
        if run["failed_at"] is None:  # died while loading: restarting would do the same
            why = run["load_failure"]
            for i in range(start, n):
                outcomes.setdefault(i, CaseOutcome(i, why[0], message=why[1]))
            break
        start = run["failed_at"] + 1
    for i in range(n):
        if i not in outcomes:
            last = _last_failure(outcomes)
            outcomes[i] = CaseOutcome(
                i, "not-run",
                message=f"not run: your code {last} on earlier cases, so the rest were skipped")
    result.outcomes = [outcomes[i] for i in range(n)]
    result.stdout = _join_capped(stdout_parts, limits.output_bytes + 256)
    result.stderr = _join_capped(stderr_parts, limits.output_bytes + 256)
    result.seconds = time.monotonic() - t0
    return result


def _last_failure(outcomes: dict[int, CaseOutcome]) -> str:
    kinds = [o.kind for o in outcomes.values()]
    if "timeout" in kinds:
        return "ran out of time"
    return "crashed the Python process"


def _join_capped(parts: list[str], cap: int) -> str:
    text = "".join(parts)
    if len(text) > cap:
        text = text[:cap] + f"\n... [{len(text) - cap} more characters not shown]"
    return text


def _encode_inputs(job: SandboxJob, start: int) -> tuple[dict, dict]:
    import numpy as np

    arrays: dict[str, Any] = {}

    def enc(v):
        if v is None or type(v) in (bool, int, float, str):
            return v
        if isinstance(v, np.ndarray):
            key = f"a{len(arrays)}"
            arrays[key] = np.ascontiguousarray(v)
            return {"__array__": key}
        if isinstance(v, np.generic):
            return v.item()
        if isinstance(v, tuple):
            return {"__tuple__": [enc(x) for x in v]}
        if isinstance(v, list):
            return {"__list__": [enc(x) for x in v]}
        if isinstance(v, dict):
            return {"__dict__": [[str(k), enc(x)] for k, x in v.items()]}
        raise TypeError(f"case input of type {type(v).__name__} is not plain data")

    cases = [{"args": enc(tuple(a)), "kwargs": enc(dict(k))} for a, k in job.cases]
    spec = {
        "name": job.name,
        "kind": job.kind,
        "setup": job.setup_source,
        "cells": [list(c) for c in job.cells],
        "cases": cases,
        "start": start,
        "reference_targets": [list(t) for t in job.reference_targets],
        "graded_names": list(job.graded_names),
        "protected_prefixes": list(job.protected_prefixes),
        "deny_paths": list(job.deny_paths),
    }
    return spec, arrays


def _job_env(scratch: str) -> dict:
    return {
        "PATH": "/usr/bin:/bin", "HOME": os.path.join(scratch, "home"), "TMPDIR": scratch,
        "LANG": "C.UTF-8", "LC_ALL": "C.UTF-8", "MPLBACKEND": "Agg",
        "MPLCONFIGDIR": os.path.join(scratch, "home"),
        "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
        "NUMEXPR_NUM_THREADS": "1", "VECLIB_MAXIMUM_THREADS": "1",
    }


class Zygote:
    """A warm, trusted Python (NumPy and the course's reference modules imported) that forks one
    child per run: starting a child costs milliseconds instead of a fresh interpreter's ~0.4 s.

    It runs no student code itself. Each forked child starts a new session, takes the manifest
    pipe and the output files passed over the control socket (``SCM_RIGHTS``), closes the
    socket, then runs :func:`_child_main` (which drops to the sandbox uid before any student
    code). One zygote serves one worker slot; :meth:`close` ends it.
    """

    def __init__(self, preload: list[str] = ()):
        import socket

        self._sock, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        self.exits: dict[int, int] = {}
        try:
            self.proc = subprocess.Popen(
                [sys.executable, "-I", "-B", os.path.abspath(__file__), "--zygote",
                 str(theirs.fileno())],
                cwd="/", env=_job_env(tempfile.gettempdir()), stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                pass_fds=(theirs.fileno(),), start_new_session=True)
        finally:
            theirs.close()
        self._send({"preload": list(preload)})
        reply = self._recv(timeout=120)
        if not reply or not reply.get("ready"):
            self.close()
            raise RuntimeError("the sandbox zygote did not start")

    def _send(self, msg: dict, fds: list[int] = ()) -> None:
        import socket

        socket.send_fds(self._sock, [json.dumps(msg).encode()], list(fds))

    def _recv(self, timeout: float | None) -> dict | None:
        ready, _, _ = select.select([self._sock], [], [], timeout)
        if not ready:
            return None
        data = self._sock.recv(65536)
        if not data:
            return None
        return json.loads(data)

    def fileno(self) -> int:
        return self._sock.fileno()

    def poll_messages(self) -> None:
        """Collect exit reports without blocking."""
        while True:
            msg = self._recv(0)
            if msg is None:
                return
            if "exit" in msg:
                self.exits[int(msg["exit"])] = int(msg["code"])

    def spawn(self, request: dict, fds: list[int]) -> int:
        self._send(request, fds)
        while True:
            msg = self._recv(timeout=30)
            if msg is None:
                raise RuntimeError("the sandbox zygote stopped answering")
            if "exit" in msg:
                self.exits[int(msg["exit"])] = int(msg["code"])
            elif "pid" in msg:
                return int(msg["pid"])
            elif "error" in msg:
                raise RuntimeError(f"the sandbox zygote could not fork: {msg['error']}")

    def alive(self) -> bool:
        return self.proc.poll() is None

    def close(self) -> None:
        try:
            self._sock.close()
        finally:
            if self.proc.poll() is None:
                try:
                    os.killpg(self.proc.pid, signal.SIGKILL)
                except (ProcessLookupError, PermissionError):
                    self.proc.kill()
            self.proc.wait()


class _Handle:
    """The running child: a ``Popen`` (direct start) or a pid forked by a :class:`Zygote`."""

    def __init__(self, proc: subprocess.Popen | None = None, pid: int | None = None,
                 zygote: Zygote | None = None):
        self.proc, self.zygote = proc, zygote
        self.pid = proc.pid if proc is not None else pid

    def extra_fds(self) -> list[int]:
        return [self.zygote.fileno()] if self.zygote is not None else []

    def on_ready(self, fd: int) -> None:
        if self.zygote is not None and fd == self.zygote.fileno():
            self.zygote.poll_messages()

    def returncode(self, wait: float = 0.0) -> int | None:
        deadline = time.monotonic() + wait
        while True:
            if self.proc is not None:
                code = self.proc.poll()
            else:
                self.zygote.poll_messages()
                code = self.zygote.exits.get(self.pid)
            if code is not None or time.monotonic() >= deadline:
                return code
            time.sleep(0.01)

    def kill(self) -> None:
        if self.returncode() is None:
            try:
                os.killpg(self.pid, signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                if self.proc is not None:
                    self.proc.kill()
        if self.proc is not None:
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:  # pragma: no cover - SIGKILL always ends it
                pass
        else:
            self.returncode(wait=5.0)
            self.zygote.exits.pop(self.pid, None)


def _launch(job: SandboxJob, limits: Limits, workdir: str, slot: int, start: int,
            zygote: Zygote | None = None) -> dict:
    import numpy as np

    ident = sandbox_identity(slot)
    scratch = tempfile.mkdtemp(prefix=f"{job.name}-", dir=workdir)
    out = {"outcomes": {}, "done": False, "failed_at": None, "defined": True,
           "load_notes": [], "load_failure": ("crashed", ""), "stdout": "", "stderr": "",
           "returncode": None}
    try:
        spec, arrays = _encode_inputs(job, start)
        spec["limits"] = {
            "case_timeout": limits.case_timeout, "memory_mb": limits.memory_mb,
            "fsize_mb": limits.fsize_mb, "nproc": limits.nproc,
            "cpu_seconds": int(limits.load_timeout
                               + limits.case_timeout * (len(job.cases) + 1)) + 5,
            "output_bytes": limits.output_bytes,
        }
        spec["scratch"] = scratch
        with open(os.path.join(scratch, "job.json"), "w", encoding="utf-8") as f:
            json.dump(spec, f)
        np.savez(os.path.join(scratch, "inputs.npz"), **arrays)
        os.mkdir(os.path.join(scratch, "home"))
        if ident is not None:
            for dirpath, dirnames, filenames in os.walk(scratch):
                for name in dirnames + filenames:
                    os.chown(os.path.join(dirpath, name), *ident)
            os.chown(scratch, *ident)
        os.chmod(scratch, 0o700)
        env = _job_env(scratch)
        drop = f"{ident[0]}:{ident[1]}" if ident is not None else ""
        rfd, wfd = os.pipe()
        with tempfile.TemporaryFile(dir=workdir) as fout, \
                tempfile.TemporaryFile(dir=workdir) as ferr:
            try:
                if zygote is not None:
                    pid = zygote.spawn({"scratch": scratch, "env": env, "drop": drop},
                                       [wfd, fout.fileno(), ferr.fileno()])
                    handle = _Handle(pid=pid, zygote=zygote)
                else:
                    env[MANIFEST_FD_ENV] = str(wfd)
                    env[DROP_ENV] = drop
                    proc = subprocess.Popen(
                        [sys.executable, "-I", "-B", os.path.abspath(__file__), "--child", scratch],
                        cwd=scratch, env=env, stdin=subprocess.DEVNULL, stdout=fout, stderr=ferr,
                        pass_fds=(wfd,), start_new_session=True)
                    handle = _Handle(proc=proc)
            finally:
                os.close(wfd)
            try:
                _watch(handle, rfd, job, limits, start, scratch, out)
            finally:
                os.close(rfd)
                code = handle.returncode(wait=0.5 if not out["done"] else 0.0)
                handle.kill()
            out["returncode"] = code
            out["stdout"] = _read_capped(fout, limits.output_bytes + 256)
            out["stderr"] = _read_capped(ferr, limits.output_bytes + 256)
            if not out["done"] and code not in (None, 0):
                note = _describe_exit(code)
                for o in out["outcomes"].values():
                    if o.kind == "crashed" and not o.message:
                        o.message = note
                if out["load_failure"][0] == "crashed" and not out["load_failure"][1]:
                    out["load_failure"] = ("crashed", "your notebook's code crashed the Python "
                                           f"process while loading ({note})")
    finally:
        _rmtree(scratch)
    return out


def _describe_exit(code: int) -> str:
    if code < 0:
        try:
            name = signal.Signals(-code).name
        except ValueError:
            name = f"signal {-code}"
        hint = {"SIGKILL": "probably out of memory", "SIGSEGV": "a segmentation fault",
                "SIGXCPU": "out of CPU time", "SIGXFSZ": "a file grew too large"}.get(name, "")
        return f"killed by {name}" + (f", {hint}" if hint else "")
    return f"exit code {code}"


def _rmtree(path: str) -> None:
    import shutil

    shutil.rmtree(path, ignore_errors=True)


def _read_capped(f, cap: int) -> str:
    f.seek(0)
    data = f.read(cap + 1)
    text = data[:cap].decode("utf-8", errors="replace")
    if len(data) > cap:
        f.seek(0, os.SEEK_END)
        text += f"\n... [output truncated: {f.tell() - cap} more bytes not shown]"
    return text


def _watch(handle: _Handle, rfd, job: SandboxJob, limits: Limits, start: int, scratch: str,
           out: dict) -> None:
    """Read the child's manifest until it is done, dies, or misses a deadline."""
    buf = b""
    total = 0
    current: int | None = None       # the case running now
    loading = True
    deadline = time.monotonic() + limits.load_timeout
    started_at = time.monotonic()
    loading_label = "the setup cell"
    while True:
        wait = deadline - time.monotonic()
        if wait <= 0:
            if loading:
                out["load_failure"] = ("timeout", f"{loading_label} did not finish within "
                                       f"{limits.load_timeout:g} s (an endless loop at the top "
                                       "level of a cell?)")
                out["failed_at"] = None
                return
            if current is not None:
                out["outcomes"][current] = CaseOutcome(
                    current, "timeout", seconds=time.monotonic() - started_at,
                    message=f"took longer than {limits.case_timeout:g} s")
                out["failed_at"] = current
            else:  # hung between cases (e.g. in a finaliser): blame the next case
                nxt = max(out["outcomes"], default=start - 1) + 1
                out["outcomes"][nxt] = CaseOutcome(nxt, "timeout",
                                                   message="the process stopped responding")
                out["failed_at"] = nxt
            return
        ready, _, _ = select.select([rfd, *handle.extra_fds()], [], [], min(wait, 1.0))
        for fd in ready:
            if fd != rfd:
                handle.on_ready(fd)
        if rfd not in ready:
            continue
        chunk = os.read(rfd, 65536)
        if not chunk:  # EOF: the child exited (or closed the pipe)
            if current is not None:
                out["outcomes"][current] = CaseOutcome(current, "crashed")
                out["failed_at"] = current
            elif not loading and not out["done"]:
                nxt = max(out["outcomes"], default=start - 1) + 1
                if nxt < len(job.cases):
                    out["outcomes"][nxt] = CaseOutcome(nxt, "crashed")
                    out["failed_at"] = nxt
            return
        total += len(chunk)
        if total > _MANIFEST_CAP:
            idx = current if current is not None else max(out["outcomes"], default=start - 1) + 1
            out["outcomes"][idx] = CaseOutcome(idx, "rejected",
                                               message="produced far too much output")
            out["failed_at"] = idx if not loading else None
            out["load_failure"] = ("rejected", "produced far too much output while loading")
            return
        buf += chunk
        *lines, buf = buf.split(b"\n")
        for line in lines:
            try:
                ev = json.loads(line)
            except ValueError:
                continue
            if not isinstance(ev, dict):
                continue
            kind = ev.get("ev")
            now = time.monotonic()
            if kind == "cell" and loading:
                loading_label = f"the cell {str(ev.get('label'))[:80]!s}"
            elif kind == "note" and loading:
                out["load_notes"].append(str(ev.get("text", ""))[:2000])
            elif kind == "loaded" and loading:
                loading = False
                out["defined"] = bool(ev.get("defined"))
                deadline = now + limits.case_timeout + _GRACE
            elif kind == "start" and not loading:
                i = ev.get("i")
                if type(i) is int and start <= i < len(job.cases):
                    current = i
                    started_at = now
                    deadline = now + limits.case_timeout + _GRACE
            elif kind == "case" and not loading:
                i = ev.get("i")
                if type(i) is int and start <= i < len(job.cases) and i not in out["outcomes"]:
                    out["outcomes"][i] = _decode_case(ev, i, scratch)
                current = None
                deadline = now + limits.case_timeout + _GRACE
            elif kind == "done" and not loading:
                out["done"] = True
                return


def _decode_case(ev: dict, i: int, scratch: str) -> CaseOutcome:
    kind = ev.get("kind")
    secs = ev.get("seconds")
    secs = float(secs) if type(secs) in (int, float) else 0.0
    msg = str(ev.get("message", ""))[:2000]
    if kind == "returned":
        try:
            arrays = (_load_arrays(os.path.join(scratch, f"case_{i}.npz"))
                      if ev.get("arrays") else {})
            value = _decode_value(ev.get("value"), arrays, 0)
        except _BadOutput as exc:
            return CaseOutcome(i, "rejected", message=str(exc), seconds=secs)
        return CaseOutcome(i, "returned", value=value, seconds=secs)
    if kind == "raised":
        mro = ev.get("mro")
        mro = tuple(str(m)[:200] for m in mro[:20]) if isinstance(mro, list) else ()
        return CaseOutcome(i, "raised", error_type=str(ev.get("etype", "?"))[:200],
                           error_mro=mro, message=msg, seconds=secs)
    if kind in ("timeout", "rejected", "reference-used"):
        return CaseOutcome(i, kind, message=msg, seconds=secs)
    return CaseOutcome(i, "rejected", message="unrecognised result", seconds=secs)


class _BadOutput(Exception):
    pass


def _load_arrays(path: str) -> dict:
    """Load a child's ``.npz`` safely: no symlinks, bounded size, ``allow_pickle=False``."""
    import zipfile

    import numpy as np

    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | getattr(os, "O_NONBLOCK", 0))
    except OSError:
        raise _BadOutput("its result file is missing (was it deleted?)") from None
    with os.fdopen(fd, "rb") as f:
        st = os.fstat(f.fileno())
        import stat

        if not stat.S_ISREG(st.st_mode):
            raise _BadOutput("its result file is not a regular file")
        if st.st_size > _NPZ_CAP:
            raise _BadOutput("the result is too large")
        data = f.read(_NPZ_CAP + 1)
    import io

    try:
        with zipfile.ZipFile(io.BytesIO(data)) as zf:
            if sum(info.file_size for info in zf.infolist()) > _NPZ_CAP:
                raise _BadOutput("the result is too large")
        with np.load(io.BytesIO(data), allow_pickle=False) as npz:
            return {k: npz[k] for k in npz.files}
    except _BadOutput:
        raise
    except Exception as exc:  # noqa: BLE001 - any malformed file is the student's output
        raise _BadOutput(f"its result could not be read ({type(exc).__name__})") from None


def _decode_value(v, arrays: dict, depth: int):
    import numpy as np

    if depth > 6:
        raise _BadOutput("the result is nested too deeply")
    if v is None or type(v) in (bool, int, float):
        return v
    if type(v) is str:
        if len(v) > _STRING_CAP:
            raise _BadOutput("the returned string is too long")
        return v
    if type(v) is dict and len(v) == 1:
        (tag, inner), = v.items()
        if tag == "__array__" and type(inner) is str and inner in arrays:
            arr = arrays[inner]
            if type(arr) is not np.ndarray or arr.dtype.kind not in "biuf":
                raise _BadOutput("an array that does not hold numbers")
            return arr
        if tag == "__tuple__" and type(inner) is list:
            return tuple(_decode_value(x, arrays, depth + 1) for x in inner)
        if tag == "__set__" and type(inner) is list:
            return frozenset(_decode_value(x, arrays, depth + 1) for x in inner
                             if type(x) in (str, int))
    raise _BadOutput("the result has an unexpected form")


# ============================================================================================
# the child's side (runs the student's code; trusts nothing after the setup cell)


class ReferenceUsed(BaseException):
    """Raised by the stub that replaces a ``course_lib`` reference inside the sandbox."""


class CaseTimeout(BaseException):
    """Raised by the child's own alarm when a case or a cell runs out of time."""


class _NotPlain(Exception):
    pass


def _zygote_main(sockfd: int) -> None:  # pragma: no cover - runs in the zygote
    import importlib
    import socket
    import traceback

    sock = socket.socket(fileno=sockfd)

    def send(msg):
        sock.send(json.dumps(msg).encode())

    data, fds, _, _ = socket.recv_fds(sock, 65536, 8)
    for modname in list(json.loads(data).get("preload", [])) + list(_PRELOAD):
        try:
            importlib.import_module(modname)
        except Exception:  # noqa: BLE001 - a module that fails here fails in the child too
            pass
    send({"ready": True})
    children: set[int] = set()
    while True:
        ready, _, _ = select.select([sock], [], [], 0.05)
        while children:
            try:
                pid, status = os.waitpid(-1, os.WNOHANG)
            except ChildProcessError:
                children.clear()
                break
            if pid == 0:
                break
            children.discard(pid)
            send({"exit": pid, "code": os.waitstatus_to_exitcode(status)})
        if not ready:
            continue
        try:
            data, fds, _, _ = socket.recv_fds(sock, 65536, 8)
        except OSError:
            break
        if not data:
            break
        request = json.loads(data)
        try:
            pid = os.fork()
        except OSError as exc:
            for f in fds:
                os.close(f)
            send({"error": str(exc)})
            continue
        if pid == 0:
            try:
                sock.close()
                os.setsid()
                wfd, fout, ferr = fds
                devnull = os.open(os.devnull, os.O_RDONLY)
                os.dup2(devnull, 0)
                os.dup2(fout, 1)
                os.dup2(ferr, 2)
                for f in (devnull, fout, ferr):
                    os.close(f)
                os.chdir(request["scratch"])
                os.environ.clear()
                os.environ.update(request["env"])
                _child_main(request["scratch"], fd=wfd, drop=request.get("drop") or "")
            except BaseException:  # noqa: BLE001
                traceback.print_exc()
            finally:
                os._exit(1)
        for f in fds:
            os.close(f)
        children.add(pid)
        send({"pid": pid})
    for pid in children:
        try:
            os.killpg(pid, signal.SIGKILL)
        except OSError:
            pass
    os._exit(0)


def _child_main(scratch: str, fd: int | None = None,
                drop: str | None = None) -> None:  # pragma: no cover - runs in the child
    import gc
    import resource

    real_exit = os._exit
    write = os.write
    if fd is None:
        fd = int(os.environ.get(MANIFEST_FD_ENV, "-1"))
    if drop is None:
        drop = os.environ.get(DROP_ENV, "")
    os.environ.pop(MANIFEST_FD_ENV, None)
    os.environ.pop(DROP_ENV, None)
    monotonic = time.monotonic
    dumps = json.dumps

    def emit(ev: dict) -> None:
        data = (dumps(ev, separators=(",", ":")) + "\n").encode("utf-8", "replace")
        view = memoryview(data)
        while view:
            n = write(fd, view)
            view = view[n:]

    with open(os.path.join(scratch, "job.json"), encoding="utf-8") as f:
        spec = json.load(f)
    lim = spec["limits"]
    mb = 2**20

    def _limit(which, value):
        try:
            soft, hard = resource.getrlimit(which)
            value = value if hard == resource.RLIM_INFINITY else min(value, hard)
            resource.setrlimit(which, (value, value))
        except (ValueError, OSError):
            pass

    _limit(resource.RLIMIT_CORE, 0)
    _limit(resource.RLIMIT_CPU, int(lim["cpu_seconds"]))
    _limit(resource.RLIMIT_AS, int(lim["memory_mb"]) * mb)
    _limit(resource.RLIMIT_FSIZE, int(lim["fsize_mb"]) * mb)
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)

    import numpy as np

    ndarray = np.ndarray
    savez = np.savez
    with np.load(os.path.join(scratch, "inputs.npz"), allow_pickle=False) as npz:
        in_arrays = {k: npz[k] for k in npz.files}

    def dec(v):
        if type(v) is dict:
            (tag, inner), = v.items()
            if tag == "__array__":
                return in_arrays[inner].copy()
            if tag == "__tuple__":
                return tuple(dec(x) for x in inner)
            if tag == "__list__":
                return [dec(x) for x in inner]
            if tag == "__dict__":
                return {k: dec(x) for k, x in inner}
        return v

    # capped, Python-level stdout/stderr: a print flood costs nothing but time
    cap = int(lim["output_bytes"])

    class Capped:
        encoding = "utf-8"
        errors = "replace"

        def __init__(self, fileno):
            self._fd = fileno
            self._n = 0

        def write(self, s):
            s = str(s) if type(s) is not str else s
            if self._n < cap:
                write(self._fd, s[: cap - self._n].encode("utf-8", "replace"))
                if self._n + len(s) >= cap:
                    write(self._fd, b"\n... [output truncated]\n")
            self._n += len(s)
            return len(s)

        def writelines(self, lines):
            for line in lines:
                self.write(line)

        def flush(self):
            pass

        def isatty(self):
            return False

        def fileno(self):
            return self._fd

        def readable(self):
            return False

        def writable(self):
            return True

    sys.stdout = Capped(1)
    sys.stderr = Capped(2)

    import importlib

    if drop:  # the interpreter's own files may be unreadable once the uid is dropped
        for modname in _PRELOAD:
            try:
                importlib.import_module(modname)
            except Exception:  # noqa: BLE001 - a module missing here is missing for all
                pass

    # the instructor's setup cell (trusted code, from the source notebook)
    ns: dict[str, Any] = {"__name__": "__main__", "__builtins__": __builtins__}
    emit({"ev": "cell", "label": "setup"})
    try:
        exec(compile(spec["setup"], "<setup cell>", "exec"), ns)
    except BaseException as exc:  # noqa: BLE001
        emit({"ev": "note", "text": f"the setup cell failed: {type(exc).__name__}: {exc}"})

    # the reference modules are loaded (cached in a zygote) so that they can be stubbed: a
    # student who imports one gets the stubs, not an ImportError
    for modname in sorted({m for m, _ in spec["reference_targets"]}):
        try:
            importlib.import_module(modname)
        except Exception:  # noqa: BLE001 - a broken module is the instructor's to fix
            pass

    # stub the references of graded names
    state = {"ref": None}

    def make_stub(qualname):
        def reference_stub(*args, **kwargs):
            state["ref"] = qualname
            raise ReferenceUsed(f"{qualname} is the course's reference implementation; "
                                "graded functions must not call it")
        reference_stub.__name__ = qualname.rsplit(".", 1)[-1]
        reference_stub.__qualname__ = reference_stub.__name__
        return reference_stub

    prefixes = tuple(spec["protected_prefixes"])
    originals = {}
    for modname, qual in spec["reference_targets"]:
        mod = sys.modules.get(modname)
        if mod is not None and "." not in qual and callable(getattr(mod, qual, None)):
            originals[id(getattr(mod, qual))] = (getattr(mod, qual), f"{modname}.{qual}")
    names = set(spec["graded_names"])
    for modname, mod in list(sys.modules.items()):
        if mod is None or not modname.startswith(prefixes):
            continue
        for attr in names:
            obj = getattr(mod, attr, None)
            if callable(obj) and not isinstance(obj, type):
                originals.setdefault(id(obj), (obj, f"{modname}.{attr}"))
    stubs = {key: make_stub(qualname) for key, (obj, qualname) in originals.items()}
    if stubs:
        for ref in gc.get_referrers(*(obj for obj, _ in originals.values())):
            if type(ref) is dict:
                for k, v in list(ref.items()):
                    if id(v) in stubs and v is originals[id(v)][0]:
                        ref[k] = stubs[id(v)]
            elif type(ref) is list:
                for j, v in enumerate(ref):
                    if id(v) in stubs and v is originals[id(v)][0]:
                        ref[j] = stubs[id(v)]
            elif type(ref).__name__ == "cell":
                try:
                    v = ref.cell_contents
                except ValueError:
                    continue
                if id(v) in stubs and v is originals[id(v)][0]:
                    ref.cell_contents = stubs[id(v)]
        ref = v = None
    originals.clear()
    gc.collect()

    # helpers a notebook cell may expect
    ns.setdefault("display", lambda *a, **k: None)

    class _NoIPython:
        def run_line_magic(self, *a, **k):
            return None

        def run_cell_magic(self, *a, **k):
            return None

        def system(self, *a, **k):
            return None

        def getoutput(self, *a, **k):
            return []

        def __getattr__(self, name):
            return lambda *a, **k: None

    no_ipython = _NoIPython()
    ns.setdefault("get_ipython", lambda: no_ipython)

    def blocked_exit(*args, **kwargs):
        raise SystemExit("exiting the process is not allowed while grading")

    import posix

    hook = _make_audit_hook(scratch, spec["deny_paths"])
    os._exit = posix._exit = blocked_exit
    os.abort = posix.abort = blocked_exit

    if drop:  # started as root: become the sandbox uid before any student code runs
        uid, gid = (int(x) for x in drop.split(":"))
        os.setgroups([])
        os.setresgid(gid, gid, gid)
        os.setresuid(uid, uid, uid)
        if os.getuid() == 0 or os.geteuid() == 0:
            real_exit(70)
    _limit(resource.RLIMIT_NPROC, int(lim["nproc"]))
    try:  # the one way to start a process that Python 3.11 does not audit
        import _posixsubprocess

        del _posixsubprocess.fork_exec
    except (ImportError, AttributeError):
        pass
    sys.addaudithook(hook)
    del hook  # nothing the student's code can reach refers to the hook any more

    # the student may rebind builtins (``builtins.type = ...``): the grading code below uses
    # them too, so they are put back after every cell and every case
    import builtins

    builtins_dict = builtins.__dict__
    saved_builtins = dict(builtins_dict)
    restore_builtins = builtins_dict.update

    def on_alarm(signum, frame):
        raise CaseTimeout("time limit")

    signal.signal(signal.SIGALRM, on_alarm)
    setitimer = signal.setitimer
    case_timeout = float(lim["case_timeout"])

    # the student's cells, in notebook order, each under the time limit
    for label, source in spec["cells"]:
        emit({"ev": "cell", "label": label})
        try:
            code = compile(source, f"<cell {label}>", "exec")
            setitimer(signal.ITIMER_REAL, case_timeout)
            try:
                exec(code, ns)
            finally:
                setitimer(signal.ITIMER_REAL, 0)
                restore_builtins(saved_builtins)
        except CaseTimeout:
            emit({"ev": "note", "text": f"cell {label}: stopped after {case_timeout:g} s "
                                        "(an endless loop at its top level?)"})
        except BaseException as exc:  # noqa: BLE001 - the student's code may raise anything
            emit({"ev": "note", "text": f"cell {label}: {type(exc).__name__}: "
                                        f"{_safe_str(exc, 300)}"})

    name = spec["name"]
    kind = spec["kind"]
    defined = name in ns
    func = ns.get(name)
    emit({"ev": "loaded", "defined": defined})

    def encode(v, arrays, depth):
        t = type(v)
        if depth > 6:
            raise _NotPlain("a structure nested too deeply")
        if v is None or t in (bool, int, float):
            return v
        if t is str:
            if len(v) > _STRING_CAP:
                raise _NotPlain("a string that is too long")
            return v
        if isinstance(v, np.generic) and t.__module__ == "numpy":
            if v.dtype.kind in "biuf":
                return v.item()
            raise _NotPlain(f"a NumPy scalar of dtype {v.dtype}")
        if t is ndarray:
            if v.dtype.kind not in "biuf":
                raise _NotPlain(f"an array of dtype {v.dtype} (expected numbers)")
            key = f"a{len(arrays)}"
            arrays[key] = v
            return {"__array__": key}
        if t in (tuple, list):
            if len(v) > 100_000:
                raise _NotPlain("a list that is too long")
            return {"__tuple__": [encode(x, arrays, depth + 1) for x in v]}
        if t in (set, frozenset) and kind == "choice":
            return {"__set__": [x for x in v if type(x) in (str, int)][:64]}
        raise _NotPlain(f"an object of type {t.__name__}")

    start = int(spec["start"])
    cases = spec["cases"]
    timeouts_in_a_row = 0
    for i in range(start, len(cases)):
        if timeouts_in_a_row >= _TIMEOUTS_IN_A_ROW:
            emit({"ev": "case", "i": i, "kind": "timeout", "seconds": 0.0,
                  "message": f"not run: the {_TIMEOUTS_IN_A_ROW} cases before it timed out"})
            continue
        emit({"ev": "start", "i": i})
        state["ref"] = None
        ev: dict[str, Any] = {"ev": "case", "i": i}
        t0 = monotonic()
        try:
            args = dec(cases[i]["args"])
            kwargs = dec(cases[i]["kwargs"])
            setitimer(signal.ITIMER_REAL, case_timeout)
            try:
                if not defined:
                    raise NameError(f"name {name!r} is not defined")
                value = func(*args, **kwargs) if kind == "function" else func
            finally:
                setitimer(signal.ITIMER_REAL, 0)
                restore_builtins(saved_builtins)
            ev["kind"] = "returned"
        except CaseTimeout:
            ev["kind"] = "timeout"
            ev["message"] = f"took longer than {case_timeout:g} s"
        except ReferenceUsed as exc:
            ev["kind"] = "reference-used"
            ev["message"] = str(exc)
        except BaseException as exc:  # noqa: BLE001
            ev["kind"] = "raised"
            ev["etype"] = type(exc).__name__
            try:
                ev["mro"] = [f"{c.__module__}.{c.__qualname__}" for c in type(exc).__mro__]
            except BaseException:  # noqa: BLE001
                ev["mro"] = []
            ev["message"] = _safe_str(exc, 500)
        ev["seconds"] = monotonic() - t0
        if state["ref"] is not None:
            ev = {"ev": "case", "i": i, "kind": "reference-used", "seconds": ev["seconds"],
                  "message": f"called {state['ref']}, the course's reference implementation"}
        if ev["kind"] == "returned":
            arrays: dict[str, Any] = {}
            try:
                ev["value"] = encode(value, arrays, 0)
                if arrays:
                    savez(os.path.join(scratch, f"case_{i}.npz"), **arrays)
                    ev["arrays"] = True
            except _NotPlain as exc:
                ev = {"ev": "case", "i": i, "kind": "rejected", "seconds": ev["seconds"],
                      "message": f"returned {exc}, not plain numbers"}
            except BaseException as exc:  # noqa: BLE001 - e.g. a file-size limit
                ev = {"ev": "case", "i": i, "kind": "rejected", "seconds": ev["seconds"],
                      "message": f"the result could not be saved ({type(exc).__name__}: "
                                 "is it enormous?)"}
            del value
        timeouts_in_a_row = timeouts_in_a_row + 1 if ev["kind"] == "timeout" else 0
        try:
            emit(ev)
        except (TypeError, ValueError):
            emit({"ev": "case", "i": i, "kind": "rejected", "message": "unrecognised result"})
    emit({"ev": "done"})
    real_exit(0)


def _safe_str(exc: BaseException, cap: int) -> str:  # pragma: no cover - runs in the child
    try:
        text = str(exc)
    except BaseException:  # noqa: BLE001 - a student's __str__ may raise
        text = "<message unavailable>"
    if type(text) is not str:
        text = "<message unavailable>"
    return text if len(text) <= cap else text[:cap] + "..."


def _make_audit_hook(scratch: str, deny: list[str]):  # pragma: no cover - runs in the child
    """The audit hook that denies file access outside the scratch dir and Python's libraries,
    processes, signals, sockets and ctypes (once added, an audit hook cannot be removed).

    The hook runs in the student's process, so it trusts nothing the student can change: it
    calls no Python-level library code (its own path resolution uses ``os.lstat`` and
    ``os.readlink`` captured now, before any student code), looks up no builtins at call time
    (``builtins.isinstance = ...`` changes nothing), accepts only exact ``str``/``bytes``/``int``
    paths (a path-like object or a ``str`` subclass could answer differently when the hook
    looks and when the file is opened), and denies the introspection that would reach its
    configuration (``gc.get_objects``/``get_referrers``, tracing and profiling hooks, other
    threads' frames)."""
    import stat as _stat
    import sysconfig

    realpath = os.path.realpath
    lstat, readlink, getcwd = os.lstat, os.readlink, os.getcwd
    s_islnk = _stat.S_ISLNK
    str_t, bytes_t, int_t = str, bytes, int
    perm_error, os_error, len_ = PermissionError, OSError, len
    scratch = realpath(scratch)
    read_roots = {scratch}
    for scheme_paths in (sysconfig.get_paths(), sysconfig.get_paths(
            vars={"base": sys.base_prefix, "platbase": sys.base_exec_prefix})):
        for key in ("stdlib", "platstdlib", "purelib", "platlib"):
            if scheme_paths.get(key):
                read_roots.add(realpath(scheme_paths[key]))
    read_roots = tuple(r.rstrip(os.sep) + os.sep for r in read_roots)
    read_files = frozenset({"/dev/null", "/dev/urandom", "/dev/random", "/dev/zero",
                            "/etc/localtime"})
    deny_roots = tuple(realpath(d).rstrip(os.sep) + os.sep for d in deny)
    scratch_root = scratch.rstrip(os.sep) + os.sep
    write_flags = os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_TRUNC | os.O_APPEND

    # Every function below takes what it uses as positional defaults, never from a closure or
    # the module's globals: a frame the student reaches (through a traceback of the
    # PermissionError the hook raises) shows only immutable values, and changing a function's
    # defaults is itself an audited (denied) event.
    def resolve(path, lstat=lstat, readlink=readlink, getcwd=getcwd, s_islnk=s_islnk,
                os_error=os_error):
        """``os.path.realpath`` of an exact str from C functions only (None: a link loop)."""
        if not path.startswith("/"):
            path = getcwd() + "/" + path
        out = []
        todo = path.split("/")
        todo.reverse()
        links = 0
        while todo:
            comp = todo.pop()
            if comp == "" or comp == ".":
                continue
            if comp == "..":
                if out:
                    out.pop()
                continue
            cand = "/" + "/".join(out) + ("/" if out else "") + comp
            try:
                st = lstat(cand)
            except os_error:
                out.append(comp)
                continue
            if s_islnk(st.st_mode):
                links += 1
                if links > 40:
                    return None
                target = readlink(cand)
                if target.startswith("/"):
                    out = []
                more = target.split("/")
                more.reverse()
                todo.extend(more)
                continue
            out.append(comp)
        return "/" + "/".join(out)

    def allowed(path, write, resolve=resolve, type_=type, int_t=int_t, str_t=str_t,
                bytes_t=bytes_t, error_t=Exception, scratch=scratch, scratch_root=scratch_root,
                deny_roots=deny_roots, read_roots=read_roots, read_files=read_files) -> bool:
        t = type_(path)
        if t is int_t:
            return True
        if t is bytes_t:
            try:
                path = bytes_t.decode(path, "utf-8", "surrogateescape")
            except error_t:
                return False
        elif t is not str_t:  # a path-like object or a str subclass could lie
            return False
        if not path.startswith("/") and ".." in path.split("/"):
            return False  # it may be relative to a dir_fd the hook cannot see
        p = resolve(path)
        if p is None:
            return False
        if p == scratch or p.startswith(scratch_root):
            return True
        if write:
            return p == "/dev/null"
        if p + "/" in deny_roots or p.startswith(deny_roots):
            return False
        return p in read_files or p.startswith(read_roots) or p + "/" in read_roots

    blocked = frozenset({
        "os.system", "os.exec", "os.posix_spawn", "os.spawn", "os.fork", "os.forkpty",
        "os.kill", "os.killpg", "os.startfile", "subprocess.Popen", "pty.spawn",
        "socket.__new__", "socket.connect", "socket.bind", "socket.getaddrinfo",
        "ctypes.dlopen", "ctypes.dlsym", "ctypes.cdata", "ctypes.addressof",
        "ctypes.string_at", "ctypes.wstring_at", "ctypes.call_function", "ctypes.PyObj_FromPtr",
        "ctypes.set_errno", "sys.remote_exec", "os.setuid", "os.setgid", "os.setresuid",
        "os.chroot", "_posixsubprocess.fork_exec", "mmap.__new__", "winreg.OpenKey",
        "resource.setrlimit", "resource.prlimit", "signal.pthread_kill",
        "sqlite3.connect", "sqlite3.connect/handle", "sqlite3.enable_load_extension",
        "sqlite3.load_extension", "os.add_dll_directory", "os.chdir",
        # introspection that would reach this hook's configuration
        "gc.get_objects", "gc.get_referrers", "gc.get_referents", "sys.settrace",
        "sys.setprofile", "sys._current_frames", "sys._current_exceptions",
        "sys.monitoring.register_callback",
    })
    write_events = frozenset({
        "os.remove", "os.rename", "os.mkdir", "os.rmdir", "os.symlink", "os.link",
        "os.truncate", "os.chmod", "os.chown", "os.utime", "os.chflags", "os.lchown",
        "shutil.rmtree", "shutil.move", "os.mkfifo", "os.mknod",
    })
    read_events = frozenset({"os.listdir", "os.scandir", "glob.glob",
                             "shutil.copyfile", "os.listxattr", "os.getxattr"})
    function_t = type(resolve)

    def hook(event, args, allowed=allowed, blocked=blocked, write_events=write_events,
             read_events=read_events, type_=type, len_=len_, str_t=str_t, int_t=int_t,
             function_t=function_t, perm_error=perm_error, write_flags=write_flags):
        if event == "open":
            path = args[0]
            mode = args[1] if len_(args) > 1 else None
            flags = args[2] if len_(args) > 2 else 0
            write = ((type_(mode) is str_t and ("w" in mode or "a" in mode or "x" in mode
                                                or "+" in mode))
                     or (type_(flags) is int_t and flags & write_flags != 0))
            if not allowed(path, write):
                raise perm_error("opening this file is not allowed while grading")
        elif event in blocked:
            raise perm_error(event + " is not allowed while grading")
        elif event == "object.__setattr__":
            if args and type_(args[0]) is function_t:   # __code__, __defaults__...
                raise perm_error("changing a function's code or defaults is not allowed "
                                 "while grading")
        elif event in write_events:
            for a in args[:2]:
                if a is not None and not allowed(a, True):
                    raise perm_error(event + " outside the working directory is not allowed "
                                     "while grading")
        elif event in read_events:
            a = args[0] if args else None
            if a is not None and not allowed(a, False):
                raise perm_error(event + " is not allowed while grading")

    return hook


if __name__ == "__main__":  # pragma: no cover - the child's entry point
    if len(sys.argv) == 3 and sys.argv[1] == "--child":
        _child_main(sys.argv[2])
    elif len(sys.argv) == 3 and sys.argv[1] == "--zygote":
        _zygote_main(int(sys.argv[2]))
    else:
        sys.exit("usage: sandbox.py --child SCRATCH (started by autograder.grading)")
