"""The exchange's inbound, read by nbgrader's private-exchange collect rules.

The rules themselves live in ``deploy/private_exchange.py`` (owner check, no links, the kernel's
``ctime`` as the submission's time, every byte counted); this module only applies them to one
submission at a time: :func:`scan` lists the inbound's submission folders with their owner
checked and their time taken, :func:`collect` copies one into a folder of the service's own.
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
import os
import pwd
import stat
import time
from dataclasses import dataclass
from pathlib import Path

from ..course import REPO_ROOT
from ..course import ASSIGNMENT

#: a submission whose newest change is younger than this is left for the next poll: nbgrader's
#: submit may still be writing it (the collect would refuse it as changing)
SETTLE_SECONDS = 1.0


@functools.lru_cache(maxsize=1)
def exchange_rules():
    """``deploy/private_exchange.py``: installed as ``private_exchange`` in the instructors'
    environment on the hub, else loaded from this repository (once: its exception classes must
    be the same objects wherever they are caught)."""
    try:
        return importlib.import_module("private_exchange")
    except ModuleNotFoundError:
        path = REPO_ROOT / "deploy" / "private_exchange.py"
        spec = importlib.util.spec_from_file_location("private_exchange", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module


def unix_uid(student: str) -> int:
    """The uid of the Unix user ``student`` (on the hub the login is the student id);
    ``KeyError`` when there is none."""
    return pwd.getpwnam(student).pw_uid


@dataclass(frozen=True)
class Found:
    """A submission folder of the inbound: whose, when (ns), or why it does not count."""

    folder: str
    student: str
    ctime_ns: int = 0
    refused: str = ""


def scan(inbound: Path, uid_of=unix_uid, now: float | None = None) -> list[Found]:
    """Every settled submission folder ``<student>+tripos2006+...`` of ``inbound``."""
    rules = exchange_rules()
    now = time.time() if now is None else now
    found = []
    for entry in sorted(os.listdir(inbound)):
        parts = entry.rsplit("+", 3)
        if len(parts) != 4 or parts[1] != ASSIGNMENT:
            continue
        got = _examine(rules, Path(inbound) / entry, parts[0], uid_of)
        if got.refused or got.ctime_ns / 1e9 <= now - SETTLE_SECONDS:
            found.append(got)
    return found


def _examine(rules, path: Path, student: str, uid_of) -> Found:
    """The owner check and the time of one folder (as ``PrivateExchangeCollect`` does)."""
    try:
        uid = uid_of(student)
        top = os.lstat(path)
    except KeyError:
        return Found(path.name, student, refused=f"{student!r} is no Unix user")
    except OSError as err:
        return Found(path.name, student, refused=str(err))
    if top.st_uid != uid or not stat.S_ISDIR(top.st_mode):
        return Found(path.name, student, refused=f"not a folder owned by {student!r}")
    try:
        return Found(path.name, student, rules.newest_ctime_ns(str(path), uid))
    except rules.SubmissionRefused as why:
        return Found(path.name, student, refused=str(why))


class Changed(Exception):
    """The submission changed since it was noticed (still being written): try again later,
    taking its new time (``ctime_ns``)."""

    def __init__(self, message: str, ctime_ns: int):
        super().__init__(message)
        self.ctime_ns = ctime_ns


def collect(inbound: Path, folder: str, student: str, ctime_ns: int, dest: Path,
            uid_of=unix_uid) -> Path:
    """Copy the submission ``inbound/folder`` to ``dest/<student>/tripos2006/`` by the collect
    rules, its ``timestamp.txt`` the kernel's time (UTC); returns that folder. Raises the
    rules' ``SubmissionRefused`` or :class:`Changed`."""
    from nbgrader.coursedir import CourseDirectory

    rules = exchange_rules()
    course = CourseDirectory()          # nbgrader's default ignore globs and size limits
    src = str(Path(inbound) / folder)
    uid = uid_of(student)
    target = Path(dest) / student / ASSIGNMENT
    target.parent.mkdir(parents=True, exist_ok=True)

    def skipped(name, st):
        import fnmatch
        return any(fnmatch.fnmatch(name, p) for p in course.ignore) or (
            stat.S_ISREG(st.st_mode) and st.st_size > 1000 * course.max_file_size)

    rules.copy_submission(src, str(target), uid, skipped, max_file_bytes=1000 *
                          course.max_file_size, max_total_bytes=1000 * course.max_dir_size)
    now_ns = rules.newest_ctime_ns(src, uid)
    if now_ns != ctime_ns:
        raise Changed(f"{folder} changed since it was noticed", now_ns)
    stamp = rules.utc_stamp(ctime_ns, "%Y-%m-%d %H:%M:%S.%f %Z")
    (target / rules.TIMESTAMP_FILE).write_text(stamp, encoding="utf-8")
    return target
