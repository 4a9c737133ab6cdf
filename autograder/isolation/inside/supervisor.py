"""The supervisor: the sandbox's first process, which never runs student code.

For each graded name it forks a worker (:mod:`.worker`), hands it one case at a time (read from
the cases file's descriptor when the case is due: the worker never holds a case it is not yet
running, nor another name's), forwards the worker's records to the ONE channel the grader
reads, restarts a crashed or hung worker for the remaining cases (at most ``max_launches``
processes per name) under deadlines of its own that no record of a worker can move (per case,
its CPU time limit on the worker's CPU clock and a fixed wall-clock backstop,
:data:`~.confine.WALL_FACTOR` times the limit; a hard end per name and per notebook,
``job_timeout``), and kills every leftover
process and empties the scratch folder before each name's first worker (so nothing a worker
saw reaches another name's). When it is PID 1 of its own PID namespace (the sandbox), ``kill(-1, SIGKILL)``
cannot reach it, and clears everything else.

Standard library only: this module runs inside the sandbox (the grader imports it for
:func:`name_budget`).
"""

from __future__ import annotations

import os
import select
import signal
import stat
import time

from .confine import WALL_FACTOR, process_cpu_seconds
from .failures import Policy, describe_status
from .wire import CaseStream, FrameReader, frame, record_cap, write_all
from .worker import worker_main

GRACE = 1.0                        #: seconds the supervisor waits beyond a worker's own alarm
TIMEOUTS_IN_A_ROW = 3              #: after this many timeouts the rest of a name is not run
CPU_POLL = 0.1                     #: seconds between two looks at a running case's CPU clock
#: The ``by`` of a case record the supervisor made (a worker's record with a ``by`` is refused),
#: so the grader knows which messages no student code wrote.
SUPERVISOR = "supervisor"


def name_budget(limits: dict, n_cases: int) -> float:
    """The most wall seconds one graded name may take: every launch's load budget and every
    case's time limit (the grader's job budget adds these up)."""
    load = float(limits["load_timeout"]) + GRACE
    case = float(limits["case_timeout"]) + GRACE
    return int(limits["max_launches"]) * load + max(1, n_cases) * case


def kill_leftovers(worker_pid: int | None) -> None:
    """Kill every process of the job but this one (as PID 1 of the sandbox: ``kill(-1)``;
    elsewhere the worker's process group) and reap them."""
    if os.getpid() != 1:
        if worker_pid:
            try:
                os.killpg(worker_pid, signal.SIGKILL)
            except OSError:
                pass
            try:
                os.waitpid(worker_pid, 0)
            except ChildProcessError:
                pass
        return
    end = time.monotonic() + 5.0
    while time.monotonic() < end:
        try:
            os.kill(-1, signal.SIGKILL)
        except ProcessLookupError:
            pass
        try:
            while os.waitpid(-1, os.WNOHANG)[0] > 0:
                pass
        except ChildProcessError:
            return
        time.sleep(0.002)


def empty_folder(path: str) -> bool:
    """Remove everything inside ``path`` (the sandbox's private scratch; ``""``: nothing), in
    a child process: the names a worker chose (they may spell a case's inputs) never enter
    this process's memory, which every later worker inherits. True when ``path`` is empty
    afterwards (the child's exit status says so)."""
    if not path:
        return True
    try:
        pid = os.fork()
    except OSError:
        return False
    if pid == 0:
        empty = False
        try:
            _remove_inside(path)
            empty = not os.listdir(path)
        finally:
            os._exit(0 if empty else 1)
    try:
        _, status = os.waitpid(pid, 0)
    except ChildProcessError:
        return False
    return os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0


def _remove_inside(path: str) -> None:
    """Everything below ``path``, without recursion (a worker may nest folders thousands
    deep) and whatever modes a worker left: a folder it made read-only (``chmod 0o555``)
    would keep its files from a plain ``rmtree`` run as the same unprivileged uid, so every
    folder is made writable by its owner first (this process runs as that owner)."""
    folders, stack = [], [path]
    while stack:
        folder = stack.pop()
        try:        # (the scratch's own root may be root's, 1777: nothing to change there)
            os.chmod(folder, stat.S_IMODE(os.lstat(folder).st_mode) | stat.S_IRWXU)
        except OSError:
            pass
        try:
            entries = os.listdir(folder)
        except OSError:
            continue
        folders.append(folder)
        for entry in entries:
            full = os.path.join(folder, entry)
            try:
                if stat.S_ISDIR(os.lstat(full).st_mode):
                    stack.append(full)
                else:
                    os.unlink(full)
            except OSError:
                pass
    for folder in reversed(folders[1:]):        # deepest first; never ``path`` itself
        try:
            os.rmdir(folder)
        except OSError:
            pass


class NameSupervisor:
    """Runs one graded name: launches workers, feeds them its cases one at a time, forwards
    their records, fills in the cases a dead or hung worker could not report.

    ``io``: the channel to the grader and the cases file (this name's case ``i`` is its frame
    ``first + i``); ``scratch``: the folder emptied before each name's first worker starts."""

    def __init__(self, nj: dict, ns: dict, limits: dict, policy: Policy,
                 io: tuple[int, CaseStream], job_deadline: float = float("inf"),
                 bpf: bytes = b"", scratch: str = "", first: int = 0):
        self.nj, self.ns, self.limits = nj, ns, limits
        self.channel, self.cases = io
        self.first = first
        self.scratch = scratch
        self.feed_fd = -1          #: the write end of the current worker's case pipe
        self.policy = policy       #: the grader's allow-list of course_lib, for the workers
        self.bpf = bpf             #: the seccomp filter every worker installs
        self.n = len(nj["cases"])
        #: the hard end of this name: its own budget, never beyond the notebook's
        self.hard = min(job_deadline, time.monotonic() + name_budget(limits, self.n))
        self.job_deadline = job_deadline
        self.deadlines: dict = {}  # case index -> its deadline, fixed once set
        self.next = 0              # the first case without an outcome
        self.launches = 0
        self.timeouts = 0          # timeouts in a row
        self.label = "?"           # the cell running now
        self.pid = 0
        self.status = None         # the worker's wait status, once collected
        self.cpu_start = 0.0       # the worker's CPU clock when the running case was due

    def emit(self, rec: dict) -> None:
        rec.setdefault("name", self.nj["name"])
        write_all(self.channel, frame(rec))

    def settle(self, kind: str, message: str, seconds: float = 0.0) -> None:
        """Give case ``self.next`` an outcome of the supervisor's own."""
        self.emit({"t": "case", "i": self.next, "kind": kind, "message": message,
                   "seconds": seconds, "by": SUPERVISOR})
        self.timeouts = self.timeouts + 1 if kind == "timeout" else 0
        self.next += 1

    def settle_rest(self, kind: str, message: str) -> None:
        while self.next < self.n:
            self.settle(kind, message)

    def run(self) -> None:
        self.emit({"t": "name"})
        while self.next < self.n or self.launches == 0:
            if time.monotonic() >= self.hard:
                self.settle_rest("not-run", self.out_of_time())
                break
            if self.launches >= int(self.limits["max_launches"]):
                self.settle_rest("not-run", f"not run: the process died {self.launches} times")
                break
            if not self.launch():
                break
        self.settle_rest("not-run", "not run")
        kill_leftovers(self.pid)
        self.emit({"t": "end", "launches": self.launches})

    def launch(self) -> bool:
        """One worker process; True when another should continue with the remaining cases."""
        kill_leftovers(self.pid)
        if self.launches == 0:
            # a new name: nothing an earlier name's worker stored is left (a restart keeps it:
            # what it finds is of cases already run, and hidden cases run last); a scratch that
            # cannot be emptied could carry an earlier name's inputs, so this name does not run
            if not empty_folder(self.scratch):
                self.settle_rest("not-run", "not run: the scratch folder could not be emptied "
                                            "of what an earlier function stored there")
                return False
        self.launches += 1
        rfd, wfd = os.pipe()
        crfd, cwfd = os.pipe()
        try:
            pid = os.fork()
        except OSError as exc:
            for fd in (rfd, wfd, crfd, cwfd):
                os.close(fd)
            self.settle_rest("crashed", f"could not start a process ({exc.strerror})")
            return False
        if pid == 0:   # the worker: never returns into the supervisor's code
            try:
                for fd in (rfd, cwfd, self.channel, self.cases.fd):
                    os.close(fd)
                worker_main(self.nj, self.ns, self.limits, self.policy, (crfd, wfd), self.bpf)
            finally:
                os._exit(70)
        os.close(wfd)
        os.close(crfd)
        os.set_blocking(cwfd, False)
        self.pid, self.status, self.feed_fd = pid, None, cwfd
        try:
            return self.watch(FrameReader(rfd, self.frame_cap()))
        finally:
            os.close(rfd)
            self.end_feed()

    def end_feed(self) -> None:
        """Close the worker's case pipe: it has no case left (it then says it is done)."""
        if self.feed_fd >= 0:
            os.close(self.feed_fd)
            self.feed_fd = -1

    def feed(self, deadline: float) -> bool:
        """Hand case ``self.next`` to the worker (or, none left, close its pipe); False when
        the worker did not take it by ``deadline``. The case is read from the cases file into
        a buffer of its own, which is zeroed once written, so no later worker forked from
        this process finds it in memory."""
        if self.next >= self.n:
            self.end_feed()
            return True
        buf = self.cases.read(self.first + self.next)
        try:
            return self._write_by(buf, len(buf), deadline)
        finally:
            buf[:] = bytes(len(buf))

    def _write_by(self, buf: bytearray, n: int, deadline: float) -> bool:
        done = 0
        with memoryview(buf) as view:
            while done < n:
                left = deadline - time.monotonic()
                if left <= 0 or not select.select([], [self.feed_fd], [], left)[1]:
                    return False
                try:
                    done += os.write(self.feed_fd, view[done:n])
                except BlockingIOError:
                    continue
                except OSError:       # the worker is gone: its reader sees the end
                    return True
        return True

    def frame_cap(self) -> int:
        caps = [int(c["cap"]) for c in self.nj["cases"]] or [0]
        return record_cap(max(caps), int(self.limits["output_bytes"]))

    def out_of_time(self) -> str:
        """Why the cases left have no result once the name's or the notebook's time is up."""
        if time.monotonic() >= self.job_deadline:
            return (f"not run: the notebook used up its time ({self.limits['job_timeout']:g} s "
                    "for all its cells and cases)")
        return "not run: this test used up its time (every restart included)"

    def case_deadline(self, i: int, now: float) -> float:
        """Case ``i``'s wall-clock backstop, fixed the first time it is asked for (nothing the
        worker sends can move it); its CPU time starts counting from here."""
        if i not in self.deadlines:
            self.deadlines[i] = now + WALL_FACTOR * float(self.limits["case_timeout"]) + GRACE
        self.cpu_start = process_cpu_seconds(self.pid)
        return min(self.deadlines[i], self.hard)

    def next_event(self, reader: FrameReader, deadline: float, loading: bool):
        """The worker's next event, ``"timeout"`` at the wall-clock ``deadline`` or, while a
        case runs, once the worker has used the case's CPU time limit (plus :data:`GRACE`)
        since the case was due."""
        if loading:
            return reader.next(deadline, self.worker_alive)
        cpu_limit = float(self.limits["case_timeout"]) + GRACE
        while True:
            step = min(deadline, time.monotonic() + CPU_POLL)
            event, payload = reader.next(step, self.worker_alive)
            if event != "timeout" or step >= deadline:
                return event, payload
            if process_cpu_seconds(self.pid) - self.cpu_start >= cpu_limit:
                return "timeout", None

    def watch(self, reader: FrameReader) -> bool:
        """Forward one worker's records. The deadlines are the supervisor's: ONE for loading
        all the cells, one per case (its CPU time, and a wall-clock backstop fixed when the
        case is first due: after loading or after the previous case's result), and the name's
        hard end; frames cannot move them."""
        loading, started = True, time.monotonic()
        deadline = min(started + float(self.limits["load_timeout"]) + GRACE, self.hard)
        while True:
            event, payload = self.next_event(reader, deadline, loading)
            if event != "record":
                return self.failed(event, loading, started)
            rec, raw = payload
            t, now = rec.get("t"), time.monotonic()
            if rec.get("name") != self.nj["name"]:
                return self.failed("garbage", loading, started)
            if t == "cell" and loading:   # the label only: the load deadline stays
                self.label = str(rec.get("label"))[:100]
            elif t == "note" and loading:
                if self.launches == 1:
                    self.emit({"t": "note", "text": str(rec.get("text"))[:2000]})
            elif t == "loaded" and loading:
                loading, started = False, now
                deadline = self.case_deadline(self.next, now)
                if self.launches == 1:
                    self.emit({"t": "loaded", "defined": rec.get("defined") is True,
                               "printed": str(rec.get("printed"))[:2 * self.limits["output_bytes"]]})
                if not self.feed(deadline):
                    return self.failed("timeout", loading, started)
            elif t == "start" and not loading and rec.get("i") == self.next:
                pass      # harmless: the case's deadline was fixed when it was handed over
            elif t == "case" and not loading and rec.get("i") == self.next and "by" not in rec:
                if not self.forward_case(rec, raw):
                    return False
                started, deadline = now, self.case_deadline(self.next, now)
                if not self.feed(deadline):
                    return self.failed("timeout", loading, started)
            elif t == "done" and not loading:
                return False
            else:
                return self.failed("garbage", loading, started)

    def forward_case(self, rec: dict, raw: bytes) -> bool:
        """Pass case ``self.next``'s result on; False when the rest of the name is not run."""
        write_all(self.channel, raw)
        self.timeouts = self.timeouts + 1 if rec.get("kind") == "timeout" else 0
        self.next += 1
        if self.timeouts >= TIMEOUTS_IN_A_ROW:
            self.settle_rest("not-run", f"not run: the {TIMEOUTS_IN_A_ROW} cases "
                                        "before it timed out")
            return False
        return True

    def worker_alive(self) -> bool:
        """False once the worker has exited (its wait status is kept)."""
        if self.status is None:
            try:
                pid, status = os.waitpid(self.pid, os.WNOHANG)
            except ChildProcessError:
                pid, status = self.pid, 0
            if pid:
                self.status = status
        return self.status is None

    def exit_status(self, wait: float) -> str:
        end = time.monotonic() + wait
        while self.worker_alive():
            if time.monotonic() >= end:
                return "the process stopped responding"
            time.sleep(0.005)
        return describe_status(self.status)

    def failed(self, event: str, loading: bool, started: float) -> bool:
        """The worker died, hung or sent something wrong: settle what it left, decide."""
        why = self.exit_status(1.0) if event == "eof" else ""
        kill_leftovers(self.pid)
        spent = time.monotonic() - started
        if event == "timeout" and time.monotonic() >= self.hard:
            self.settle_rest("not-run", self.out_of_time())
            return False
        if loading:
            if event == "timeout":
                self.settle_rest("timeout", f"the cells did not finish within "
                                            f"{self.limits['load_timeout']:g} s (cell "
                                            f"{self.label} was running)")
            elif event == "eof":
                self.settle_rest("crashed", f"crashed while running cell {self.label}: {why}")
            else:
                self.settle_rest("rejected", "the cells produced an unrecognised record")
            return False
        if self.next >= self.n:
            return False
        if event == "timeout":
            limit = float(self.limits["case_timeout"])
            self.settle("timeout", f"took more than {limit:g} s of CPU time or "
                                   f"{WALL_FACTOR * limit:g} s in all (stopped by the "
                                   "supervisor)", spent)
            if self.timeouts >= TIMEOUTS_IN_A_ROW:
                self.settle_rest("not-run", f"not run: the {TIMEOUTS_IN_A_ROW} cases before "
                                            "it timed out")
                return False
        elif event == "eof":
            self.settle("crashed", why, spent)
        elif event == "too-large":
            self.settle("rejected", "result too large", spent)
        else:
            self.settle("rejected", "produced an unrecognised record", spent)
        return True

