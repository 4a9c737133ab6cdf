"""The grader's side: run one student's notebook in one sandbox, read what comes back.

:func:`run_notebook` writes the job (plain data only) into a private directory, takes a uid no
other job uses, makes the job's cgroup (memory, processes, one CPU), starts the sandbox
program (:mod:`.inside`, "the child") inside bubblewrap, and reads its ONE channel with a hard
byte cap and a wall-clock budget. Every record is re-validated here (:class:`Collector`); nothing the child
announces is trusted. When
the job ends, for whatever reason, the sandbox is killed, and as root no process of its uid is
left when this returns. In the sandbox mode there is no job without its uid and its cgroup:
when either cannot be had, the job is not run (:class:`~.bwrap.IsolationError`).
"""

from __future__ import annotations

import base64
import json
import math
import os
import shutil
import subprocess
import tempfile
import time

from autograder.model import CaseOutcome, NameRun, OutcomeKind

from . import allowlist, bwrap, seccomp
from .inside import wire
from .inside.supervisor import GRACE, SUPERVISOR, name_budget
from .cgroup import CgroupError, JobCgroup
from .identity import allocate_uid
from .jobs import Limits, NotebookJob, validate_job

#: Seconds the sandbox may take to start (mounts, the interpreter, NumPy) beyond the limits.
STARTUP_SECONDS = 15.0
#: Seconds per name the supervisor may spend clearing processes after the name's time is up.
CLEANUP_SECONDS = 6.0
#: The sandbox program's folder, bound read-only into the sandbox (:mod:`.inside`).
PROGRAM_DIR = os.path.dirname(os.path.realpath(wire.__file__))
NOTE_CHARS = 2000               #: characters kept of one load note
#: The shell line that puts the sandbox into its cgroup(s) before anything in it starts.
JOIN_CGROUP = 'while [ "$1" != -- ]; do echo $$ > "$1" || exit 125; shift; done; shift; exec "$@"'
#: Why the cases the child never reported have no result, by how the channel ended.
ENDINGS = {
    "done": (OutcomeKind.NOT_RUN, "not reported by the sandbox"),
    "timeout": (OutcomeKind.NOT_RUN, "not run: the notebook used up its time"),
    "too-large": (OutcomeKind.REJECTED, "result too large"),
    "garbage": (OutcomeKind.REJECTED, "the sandbox's output was not understood"),
    "eof": (OutcomeKind.CRASHED, "the sandbox ended before this case"),
}


def job_budget(job: NotebookJob, limits: Limits) -> float:
    """Wall seconds the whole job may take: the supervisor's own limits (the setup cell, then
    per name :func:`~autograder.isolation.inside.supervisor.name_budget`), never more
    than ``limits.job_timeout``, plus the time to start the sandbox and to clear processes."""
    lim = {k: getattr(limits, k) for k in Limits.__dataclass_fields__}
    total = limits.load_timeout + GRACE
    for nj in job.names:
        total += name_budget(lim, len(nj.cases)) + 0.5 * len(nj.cases)
    return STARTUP_SECONDS + min(total, limits.job_timeout) + CLEANUP_SECONDS * len(job.names)


def _text(value, cap: int) -> str:
    """A text field of a record: ``""`` unless a str, at most ``cap`` characters, valid UTF-8
    (JSON carries lone surrogates, which no page, log or CSV could write)."""
    text = value if type(value) is str else ""
    return wire.plain_text(text if len(text) <= cap else text[:cap] + "...")


class NameState:
    """What the grader has received for one name so far."""

    def __init__(self, nj, limits: Limits):
        self.nj, self.limits = nj, limits
        self.outcomes: dict[int, CaseOutcome] = {}
        self.defined, self.reached = True, False
        self.notes: list[str] = []
        self.printed, self.launches = "", 1
        self.started = self.ended = 0.0

    def take_case(self, rec: dict, size: int) -> None:
        """Case ``rec["i"]``'s outcome from its record; never raises for the record's content
        (a field that cannot be read makes the case ``rejected``, never the grader's error)."""
        i = rec.get("i")
        if type(i) is not int or not 0 <= i < len(self.nj.cases) or i in self.outcomes:
            return
        try:
            self.outcomes[i] = self._outcome(i, rec, size)
        except Exception:  # noqa: BLE001 - the record is hostile data: its case, not the grader
            self.outcomes[i] = CaseOutcome(i, OutcomeKind.REJECTED,
                                           message="unrecognised result")

    def _outcome(self, i: int, rec: dict, size: int) -> CaseOutcome:
        case = self.nj.cases[i]
        seconds = rec.get("seconds")
        seconds = float(seconds) if type(seconds) in (int, float) and 0 <= seconds < 1e6 else 0.0
        out = CaseOutcome(i, OutcomeKind.REJECTED, seconds=seconds,
                          printed=_text(rec.get("printed"), self.limits.output_bytes + 100),
                          message=_text(rec.get("message"), NOTE_CHARS),
                          said_by_student=rec.get("by") != SUPERVISOR)
        kinds = {k.value: k for k in OutcomeKind}
        kind = kinds.get(rec.get("kind")) if type(rec.get("kind")) is str else None
        if size > wire.record_cap(case.result_cap, self.limits.output_bytes):
            out.message, out.said_by_student = "result too large", False
        elif kind is None:
            out.message, out.said_by_student = "unrecognised result", False
        elif kind is OutcomeKind.RETURNED:
            try:
                out.value = wire.decode_value(rec.get("value"), wire.Budget(case.result_cap))
                out.kind, out.message = kind, ""
            except wire.BadValue as exc:
                out.message, out.said_by_student = str(exc), False     # the grader's words
        else:
            out.kind = kind
            if kind is OutcomeKind.RAISED:
                mro = rec.get("mro")
                out.error_type = _text(rec.get("etype"), 200)
                out.error_mro = tuple(_text(m, 200) for m in mro[:20]) \
                    if type(mro) is list else ()
        return out

    def result(self, ending: str, setup_notes: list[str]) -> NameRun:
        kind, message = ENDINGS.get(ending, ENDINGS["eof"])
        notes = list(setup_notes) + self.notes
        if not self.reached:
            notes.append(f"the sandbox did not reach {self.nj.name!r} ({message})")
        outcomes = [self.outcomes.get(i) or CaseOutcome(i, kind, message=message)
                    for i in range(len(self.nj.cases))]
        seconds = max(0.0, (self.ended or time.monotonic()) - self.started) \
            if self.started else 0.0
        return NameRun(self.nj.name, outcomes, defined=self.defined, load_notes=notes,
                       printed=self.printed, launches=self.launches, seconds=seconds)


class Collector:
    """Validates the child's records into per-name results; caps every count and size."""

    def __init__(self, job: NotebookJob, limits: Limits):
        self.limits = limits
        self.names = {nj.name: NameState(nj, limits) for nj in job.names}
        self.setup_notes: list[str] = []
        self.records = 0

    def frame_cap(self) -> int:
        caps = [c.result_cap for s in self.names.values() for c in s.nj.cases] or [0]
        return max(wire.record_cap(max(caps), self.limits.output_bytes),
                   wire.record_cap(0, 2 * self.limits.output_bytes))

    def total_cap(self) -> int:
        """The most bytes the channel may carry: every case's record cap, plus notes."""
        out = self.limits.output_bytes
        total = wire.RECORD_OVERHEAD
        for state in self.names.values():
            total += sum(wire.record_cap(c.result_cap, out) for c in state.nj.cases)
            total += wire.record_cap(0, 2 * out) + (len(state.nj.cells) + 4) * 12 * NOTE_CHARS
        return total

    def take(self, rec: dict, raw: bytes) -> bool:
        """One record; True when the child said it is done."""
        self.records += 1
        t, name = rec.get("t"), rec.get("name")
        if t == "done":
            return True
        if t == "note" and name is None and len(self.setup_notes) < 10:
            self.setup_notes.append(_text(rec.get("text"), NOTE_CHARS))
        state = self.names.get(name) if type(name) is str else None
        if state is None:
            return False
        if t == "name":
            state.reached, state.started = True, time.monotonic()
        elif t == "note" and len(state.notes) < len(state.nj.cells) + 4:
            state.notes.append(_text(rec.get("text"), NOTE_CHARS))
        elif t == "loaded":
            state.defined = rec.get("defined") is True
            state.printed = _text(rec.get("printed"), self.limits.output_bytes + 100)
        elif t == "case":
            state.take_case(rec, len(raw))
        elif t == "end":
            n = rec.get("launches")
            state.launches = n if type(n) is int and 1 <= n <= self.limits.max_launches else 1
            state.ended = time.monotonic()
        return False

    def results(self, ending: str) -> dict[str, NameRun]:
        return {name: s.result(ending, self.setup_notes) for name, s in self.names.items()}


def _job_document(job: NotebookJob, limits: Limits, privileged: bool, bpf: bytes = b"",
                  scratch: str = "") -> dict:
    """The job as the child reads it: limits, setup, names, each case's place in the cases
    file (:func:`_job_contents`), the modules to load before any student text runs, the
    ``course_lib`` policy (:func:`allowlist.sandbox_policy`), the seccomp filter to install
    then, and the scratch folder emptied before each worker (``""``: none)."""
    return _job_contents(job, limits, privileged, bpf, scratch)[0]


def _job_contents(job: NotebookJob, limits: Limits, privileged: bool, bpf: bytes = b"",
                  scratch: str = "") -> tuple[dict, bytes]:
    """``(document, cases)``: the job document, which holds no case's inputs nor anything that
    tells one case from another (no offsets, no lengths: a hidden case's size would describe
    it to the student code that can read the document), and the cases file, every case's
    inputs as one wire frame (``{"t": "case", "i", "args", "kwargs"}``), the names' cases one
    after another in the document's order (:class:`~.inside.wire.CaseStream`).

    The cases file never appears in the sandbox's filesystem: the supervisor reads each case
    from an inherited descriptor when it is due and hands it to the worker, so the process that
    runs student code never holds a case it is not running (nor another name's)."""
    names, blob = [], bytearray()
    for k, nj in enumerate(job.names):
        cases = []
        for i, case in enumerate(nj.cases):
            try:
                unlimited = wire.Budget(1 << 62)
                args = wire.encode_value(tuple(case.args), unlimited)
                kwargs = wire.encode_value(dict(case.kwargs), unlimited)
            except wire.NotPlain as exc:
                raise ValueError(f"job.names[{k}].cases[{i}] holds {exc}, not plain "
                                 "data") from None
            data = wire.frame({"t": "case", "i": i, "args": args, "kwargs": kwargs})
            cases.append({"cap": case.result_cap})
            blob += data
        names.append({"name": nj.name, "kind": nj.kind, "cells": [list(c) for c in nj.cells],
                      "cases": cases})
    lim = {k: getattr(limits, k) for k in Limits.__dataclass_fields__}
    lim.update(nproc=privileged, budget_seconds=math.ceil(job_budget(job, limits)))
    return {"limits": lim, "setup": job.setup_source, "names": names,
            "modules": list(allowlist.ALLOWED_MODULES), "policy": allowlist.sandbox_policy(),
            "filter": base64.b64encode(bpf).decode("ascii"), "scratch": scratch}, bytes(blob)


def _filter(mode: bwrap.Mode) -> bytes:
    """The seccomp filter: required in the sandbox (the probe checked), best effort without."""
    if mode is bwrap.Mode.ISOLATED or seccomp.available():
        return seccomp.filter_bytes()
    return b""


def _write_job_files(job: NotebookJob, limits: Limits, workdir: str, privileged: bool,
                     mode: bwrap.Mode, cases_file) -> str:
    """Write the job document (``job.json``, bound into the sandbox) and the cases into
    ``cases_file`` (unlinked: only its descriptor reaches the sandbox)."""
    scratch = "/tmp" if mode is bwrap.Mode.ISOLATED else ""
    doc, cases = _job_contents(job, limits, privileged, _filter(mode), scratch)
    path = os.path.join(workdir, "job.json")
    with open(path, "w", encoding="utf-8") as f:
        json.dump(doc, f)
    os.chmod(path, 0o644)
    cases_file.write(cases)
    cases_file.flush()
    allowlist.write_package(os.path.join(workdir, "site"))
    return path


def _command(mode: bwrap.Mode, workdir: str, job_file: str, fds: tuple[int, int],
             limits: Limits, uid: int | None) -> tuple[list[str], str]:
    """``(argv, cwd)`` of the child (``fds``: the channel's write end, the cases file)."""
    if mode is bwrap.Mode.ISOLATED:
        return bwrap.bwrap_command(job_file, os.path.join(workdir, "site"), PROGRAM_DIR,
                                   fds, limits.scratch_mb, uid), "/"
    site = os.path.join(workdir, "site")
    for path in bwrap.numpy_dirs():
        os.symlink(path, os.path.join(site, os.path.basename(path)))
    scratch = os.path.join(workdir, "scratch")
    os.mkdir(scratch)
    return bwrap.unsafe_command(job_file, site, PROGRAM_DIR, fds), scratch


def _read_channel(proc: subprocess.Popen, rfd: int, collector: Collector,
                  deadline: float) -> str:
    """Feed the channel's records to ``collector``; how it ended (a key of ENDINGS)."""
    reader = wire.FrameReader(rfd, collector.frame_cap(), collector.total_cap())
    while True:
        event, payload = reader.next(deadline)
        if event != "record":
            return event
        if collector.take(*payload):
            return "done"


def _stop(proc: subprocess.Popen, ending: str) -> None:
    """End the sandbox: killing bubblewrap kills its PID namespace (the supervisor is PID 1,
    with the parent-death signal set), and with it every process of the job. After a normal
    end, bubblewrap is first given a moment to collect the supervisor and exit by itself."""
    if ending == "done":
        try:
            proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            pass
    if proc.poll() is None:
        try:
            os.killpg(proc.pid, 9)
        except OSError:
            proc.kill()
    try:
        proc.wait(timeout=30)
    except subprocess.TimeoutExpired:  # pragma: no cover - SIGKILL always ends it
        pass


def _spawn(argv: list[str], cwd: str, env: dict, fds: tuple[int, int], errfile,
           cgroup) -> subprocess.Popen:
    if cgroup is not None:
        argv = [bwrap.posix_shell(), "-c", JOIN_CGROUP, "sh", *cgroup.procs_files(), "--", *argv]
    return subprocess.Popen(argv, cwd=cwd, env=env, stdin=subprocess.DEVNULL,
                            stdout=subprocess.DEVNULL, stderr=errfile, pass_fds=fds,
                            start_new_session=True)


def _sandbox_failure(proc: subprocess.Popen, errfile) -> str:
    errfile.seek(0)
    text = errfile.read(4000).decode("utf-8", "replace").strip()
    return f"the sandbox did not start (exit code {proc.returncode}): {text or 'no message'}"


def _job_cgroup(uid: int, limits: Limits) -> JobCgroup:
    """The job's cgroup, named after its uid; never a job without one."""
    try:
        return JobCgroup(f"u{uid}", limits.memory_mb, limits.pids)
    except CgroupError as exc:
        raise bwrap.IsolationError(str(exc)) from None


DEFAULT_LIMITS = Limits()


def run_notebook(job: NotebookJob, limits: Limits = DEFAULT_LIMITS,
                 mode: bwrap.Mode | None = None) -> dict[str, NameRun]:
    """Run one student's notebook in ONE sandbox; one :class:`NameRun` per name of the job.

    Never raises for anything the student's code does: every case gets an outcome. Raises
    ``ValueError`` for a malformed job, :class:`IsolationUnavailable` when ``mode`` is None and
    no sandbox can be made, and :class:`IsolationError` when the sandbox fails before any of
    the student's code ran (the grader's problem). Safe to call from several threads, and
    from several processes on one machine.
    """
    validate_job(job)
    mode = bwrap.probe() if mode is None else mode
    root = mode is bwrap.Mode.ISOLATED
    if root and not bwrap.privileged():
        raise bwrap.IsolationUnavailable(bwrap.NEEDS_ROOT)
    collector = Collector(job, limits)
    workdir = tempfile.mkdtemp(prefix="autograder-isolation-")
    lease = cgroup = None
    try:
        cases_file = tempfile.TemporaryFile(dir=workdir)
        job_file = _write_job_files(job, limits, workdir, root, mode, cases_file)
        lease = allocate_uid() if root else None
        cgroup = _job_cgroup(lease.uid, limits) if root else None
        rfd, wfd = os.pipe()
        fds = (wfd, cases_file.fileno())
        argv, cwd = _command(mode, workdir, job_file, fds, limits, lease.uid if lease else None)
        env = bwrap.child_env("/tmp" if mode is bwrap.Mode.ISOLATED else cwd, job.student)
        with tempfile.TemporaryFile() as errfile:
            try:
                proc = _spawn(argv, cwd, env, fds, errfile, cgroup)
            finally:
                os.close(wfd)
                cases_file.close()
            ending = "eof"
            try:
                ending = _read_channel(proc, rfd, collector,
                                       time.monotonic() + job_budget(job, limits))
            finally:
                os.close(rfd)
                _stop(proc, ending)
            if ending == "eof" and collector.records == 0:
                raise bwrap.IsolationError(_sandbox_failure(proc, errfile))
    finally:
        if cgroup is not None:
            cgroup.remove()
        if lease is not None:
            lease.release()
        shutil.rmtree(workdir, ignore_errors=True)
    return collector.results(ending)
