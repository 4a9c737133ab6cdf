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

from ..course import ASSIGNMENT, REPO_ROOT
from .handout import SECRET_FILE

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


#: a secret larger than this is no secret nbgrader wrote (it writes 32 hex digits)
SECRET_BYTES = 4096
_FILE_FLAGS = os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK


@dataclass(frozen=True)
class Collected:
    """A submission copied for grading: the folder, and the notebooks left out as too large
    (``{notebook: bytes}``), each to get a page saying so."""

    folder: Path
    too_large: dict


def collect(inbound: Path, folder: str, student: str, ctime_ns: int, dest: Path,
            notebooks: list[str], max_bytes: int, uid_of=unix_uid) -> Collected:
    """Copy the assignment's ``notebooks`` (names without ``.ipynb``) and the secret of the
    submission ``inbound/folder`` to ``dest/<student>/tripos2006/``, its ``timestamp.txt`` the
    kernel's time (UTC). Raises the rules' ``SubmissionRefused`` or :class:`Changed`.

    Only those files are read, whatever else the folder holds: a student's 50 MB of anything
    else cost a copy per try. Each is opened with ``O_NOFOLLOW`` relative to the folder's own
    descriptor and checked *as opened* (a regular file of the student's, one name), and its size
    is taken from that descriptor before a byte is read: a notebook over ``max_bytes`` is not
    read at all (a 95 MB one cost the grader's process 2.3 GB when parsed) and is named in
    :attr:`Collected.too_large`. The whole folder is then walked again by the collect rules
    (``newest_ctime_ns``: no links or foreign files anywhere) and its time compared."""
    rules = exchange_rules()
    src = Path(inbound) / folder
    uid = uid_of(student)
    target = Path(dest) / student / ASSIGNMENT
    target.mkdir(parents=True, exist_ok=True)
    top = _open_folder(src, uid)
    too_large = {}
    try:
        for name in notebooks:
            size = _copy_one(top, src / f"{name}.ipynb", target, uid, max_bytes)
            if size is not None and size > max_bytes:
                too_large[name] = size
        secret = _copy_one(top, src / SECRET_FILE, target, uid, SECRET_BYTES)
        if secret is not None and secret > SECRET_BYTES:
            raise rules.SubmissionRefused(f"its {SECRET_FILE} holds {secret} bytes, not a "
                                          "secret nbgrader wrote")
    finally:
        os.close(top)
    now_ns = rules.newest_ctime_ns(str(src), uid)
    if now_ns != ctime_ns:
        raise Changed(f"{folder} changed since it was noticed", now_ns)
    stamp = rules.utc_stamp(ctime_ns, "%Y-%m-%d %H:%M:%S.%f %Z")
    (target / rules.TIMESTAMP_FILE).write_text(stamp, encoding="utf-8")
    return Collected(target, too_large)


def collect_secret(inbound: Path, folder: str, student: str, dest: Path,
                   uid_of=unix_uid) -> Path:
    """Copy only the submission's secret to ``dest/<student>/tripos2006/`` (what a page about
    the whole submission needs to be released), as :func:`collect` does; returns that folder,
    without the secret when it cannot be taken."""
    target = Path(dest) / student / ASSIGNMENT
    target.mkdir(parents=True, exist_ok=True)
    try:
        uid = uid_of(student)
        top = _open_folder(Path(inbound) / folder, uid)
    except (KeyError, exchange_rules().SubmissionRefused):
        return target
    try:
        got = _copy_one(top, Path(inbound) / folder / SECRET_FILE, target, uid, SECRET_BYTES)
        if got is not None and got > SECRET_BYTES:
            (target / SECRET_FILE).unlink(missing_ok=True)
    except exchange_rules().SubmissionRefused:
        (target / SECRET_FILE).unlink(missing_ok=True)
    finally:
        os.close(top)
    return target


def _open_folder(path: Path, uid: int) -> int:
    """A descriptor of the submission folder ``path``, not followed, checked as opened."""
    rules = exchange_rules()
    try:
        fd = os.open(path, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW)
    except OSError as err:
        raise rules.SubmissionRefused(f"{path} cannot be opened as a folder: {err}") from err
    st = os.fstat(fd)
    if st.st_uid != uid:
        os.close(fd)
        raise rules.SubmissionRefused(f"{path} is not owned by the student")
    return fd


def _copy_one(folder_fd: int, where: Path, target: Path, uid: int, limit: int) -> int | None:
    """Copy the file ``where.name`` of the open folder into ``target`` unless it is over
    ``limit`` bytes; its size (None when there is no such file). Nothing is read of a file
    over the limit, and a file that grows past it while read is not kept."""
    rules = exchange_rules()
    try:
        fd = os.open(where.name, _FILE_FLAGS, dir_fd=folder_fd)
    except FileNotFoundError:
        return None
    except OSError as err:      # ELOOP: a symbolic link
        raise rules.SubmissionRefused(f"{where} cannot be opened without following it: "
                                      f"{err}") from err
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise rules.SubmissionRefused(f"{where} is not a regular file")
        if st.st_uid != uid:
            raise rules.SubmissionRefused(f"{where} is not owned by the student")
        if st.st_nlink > 1:
            raise rules.SubmissionRefused(f"{where} is a hard link ({st.st_nlink} names)")
        if st.st_size > limit:
            return st.st_size
        data = bytearray()
        while len(data) <= limit and (block := os.read(fd, min(1 << 20, limit + 1 - len(data)))):
            data += block
    finally:
        os.close(fd)
    if len(data) > limit:
        return len(data)
    out = target / where.name
    with open(os.open(out, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o640), "wb") as fh:
        fh.write(data)
    return len(data)
