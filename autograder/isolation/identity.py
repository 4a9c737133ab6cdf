"""A uid (and gid) that no other job on the machine uses while this one runs.

Uids come from a range reserved for grading (:data:`UID_BASE` onwards, above any normal
account). A job holds an exclusive ``fcntl.flock`` on ``LOCK_DIR/<uid>.lock`` (a root-only
directory) for as long as it runs, so two threads, or two grading processes, never share a
uid: the kernel's per-uid accounting (``RLIMIT_NPROC``) and permission checks (signals,
ptrace, files) then separate them.
"""

from __future__ import annotations

import fcntl
import os
import random
import signal
import time

UID_BASE = 200_000          #: the first uid handed to a sandbox
UID_COUNT = 4096            #: how many jobs may run at once on one machine
LOCK_DIR = "/run/autograder-isolation/uids"


class UidLease:
    """An exclusive uid for one job; :meth:`release` when the job is over (kills leftovers)."""

    def __init__(self, uid: int, lock_fd: int):
        self.uid, self._fd = uid, lock_fd

    def release(self) -> None:
        if self._fd < 0:
            return
        try:
            kill_uid_processes(self.uid)
        finally:
            os.close(self._fd)
            self._fd = -1


def _lock_dir() -> str:
    os.makedirs(LOCK_DIR, mode=0o700, exist_ok=True)
    parent = os.path.dirname(LOCK_DIR)
    for path in (parent, LOCK_DIR):
        st = os.lstat(path)
        if st.st_uid != 0 or st.st_mode & 0o022:
            os.chmod(path, 0o700)
    return LOCK_DIR


def allocate_uid() -> UidLease:
    """Lock and return a free uid of the range (``RuntimeError`` if all are taken). The search
    starts at a random place, so a uid just released is rarely handed out again at once."""
    directory = _lock_dir()
    start = random.randrange(UID_COUNT)
    for k in range(UID_COUNT):
        uid = UID_BASE + (start + k) % UID_COUNT
        fd = os.open(os.path.join(directory, f"{uid}.lock"),
                     os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o600)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            continue
        kill_uid_processes(uid)  # a crashed grader's leftovers (none, normally)
        return UidLease(uid, fd)
    raise RuntimeError(f"all {UID_COUNT} sandbox uids from {UID_BASE} are in use")


def uid_processes(uid: int) -> list[int]:
    """Pids of the live processes whose real or effective uid is ``uid`` (from ``/proc``;
    zombies, which run nothing and only wait for their parent to collect them, are left out)."""
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/status", "rb") as f:
                status = dict(line.split(b":", 1) for line in f.read().splitlines()
                              if b":" in line)
        except OSError:
            continue
        uids = status.get(b"Uid", b"").split()[:2]
        if str(uid).encode() in uids and not status.get(b"State", b"").strip().startswith(b"Z"):
            found.append(int(entry))
    return found


def kill_uid_processes(uid: int, patience: float = 5.0) -> None:
    """SIGKILL every process of ``uid`` until none is left (or ``patience`` runs out)."""
    kill_until_gone(lambda: uid_processes(uid), patience)


def kill_until_gone(list_pids, patience: float = 5.0) -> None:
    """SIGKILL every pid ``list_pids()`` names until it names none (or ``patience`` runs out)."""
    end = time.monotonic() + patience
    while True:
        pids = list_pids()
        if not pids or time.monotonic() > end:
            return
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
        time.sleep(0.01)
