"""nbgrader's filesystem exchange: each submission private, and collected only as its author's.

nbgrader's own ``ExchangeSubmit`` leaves every submission world-readable (files 0644, folder
0777, in ``<exchange>/<course>/inbound/``; nbgrader issues #978 and #1225). The inbound folder
cannot be listed by students (nbgrader makes it 2733), so a classmate needs the folder's name,
``<student>+<assignment>+<timestamp>+<random>``, but the name is all that protects the work.

This class keeps nbgrader's submit and takes the "other" bits away: files 0640 and folders 0750
(the submission's own folder 0770, so the graders can tidy up the inbound). The group of a
submission is the inbound folder's group, inherited through its setgid bit: the deployment
(``deploy/hub.py``) gives the inbound to the graders' group, which no student is in. Installed
in the students' environment by ``deploy/hub.py`` and switched on in their
``nbgrader_config.py`` with ``c.ExchangeFactory.submit = "private_exchange.PrivateExchangeSubmit"``.

``PrivateExchangeCollect`` is the graders' side (the instructors' environment, named in their
``nbgrader_config.py`` as ``c.ExchangeFactory.collect``). nbgrader's own collect believes the
inbound: a folder named ``<classmate>+...`` by another student is collected as the classmate's
(nbgrader only warns, "cheating attempt?"), ``copytree`` follows a submitted symbolic link as the
grader account (the course's source notebooks, a classmate's collected work), and the
submission's time is the student's ``timestamp.txt`` and folder name, so a late submission can be
backdated and a classmate's buried under a 2099 one. This class trusts only what the kernel
records: who owns each file (``lstat``) and when it last changed (``ctime``).
"""

from __future__ import annotations

import datetime
import fnmatch
import glob
import os
import pwd
import shutil
import stat
import tempfile

from nbgrader.api import Gradebook, MissingEntry
from nbgrader.exchange.default.collect import ExchangeCollect, groupby
from nbgrader.exchange.default.submit import ExchangeSubmit
from nbgrader.utils import check_mode, parse_utc

#: permission bits a submission never gets: nothing for "other"
OTHERS = 0o007
#: the submission's own folder: its author and the graders' group may read, write and enter it
SUBMISSION_DIR_MODE = 0o770


class PrivateExchangeSubmit(ExchangeSubmit):
    """``nbgrader submit`` whose submission no other student can read, even knowing its name."""

    def set_perms(self, dest, fileperms, dirperms):
        """nbgrader's modes without the bits for others (files 0640, folders 0750)."""
        super().set_perms(dest, fileperms & ~OTHERS, dirperms & ~OTHERS)

    def copy_files(self):
        """Submit as nbgrader does, then close the folder nbgrader leaves at 0777."""
        super().copy_files()
        os.chmod(os.path.join(self.inbound_path, self.assignment_filename), SUBMISSION_DIR_MODE)


# --- collect --------------------------------------------------------------------------------------

#: the name of nbgrader's timestamp file, in a submission and in its collected copy
TIMESTAMP_FILE = "timestamp.txt"


class SubmissionRefused(Exception):
    """A submission holding something the grader must not follow or copy (the reason)."""


def _refusal(path: str, st: os.stat_result, uid: int) -> str | None:
    """Why ``path`` (its ``lstat`` is ``st``) may not be part of a submission by ``uid``."""
    if stat.S_ISLNK(st.st_mode):
        return f"{path} is a symbolic link"
    if not (stat.S_ISREG(st.st_mode) or stat.S_ISDIR(st.st_mode)):
        return f"{path} is not a regular file or folder"
    if st.st_uid != uid:
        return f"{path} is owned by {_user_name(st.st_uid)}, not by the student"
    if stat.S_ISREG(st.st_mode) and st.st_nlink > 1:
        return f"{path} is a hard link ({st.st_nlink} names)"
    return None


def _user_name(uid: int) -> str:
    try:
        return pwd.getpwuid(uid).pw_name
    except KeyError:
        return f"uid {uid}"


#: a submission deeper or larger than this is refused before anything is read (a folder 1900
#: levels deep made nbgrader's own size count overflow Python's stack)
MAX_DEPTH, MAX_ENTRIES = 16, 5000


def newest_ctime_ns(folder: str, uid: int) -> int:
    """The newest ``st_ctime_ns`` over ``folder`` and everything in it, none of it followed.

    ``ctime`` is set by the kernel whenever a file's content, link count or mode changes; no
    user can set it back (unlike ``mtime``, ``touch -d``), so it is when the exchange last saw
    the submission change. Raises :class:`SubmissionRefused` on a symbolic link, a hard-linked
    file, anything not a regular file or folder, anything not owned by ``uid``, more than
    :data:`MAX_ENTRIES` entries or :data:`MAX_DEPTH` levels, or anything the collecting account
    cannot read.
    """
    newest, pending, seen = 0, [(folder, 0)], 0
    try:
        while pending:
            path, depth = pending.pop()
            seen += 1
            if seen > MAX_ENTRIES or depth > MAX_DEPTH:
                raise SubmissionRefused(f"it holds more than {MAX_ENTRIES} entries or "
                                        f"{MAX_DEPTH} levels of folders")
            st = os.lstat(path)
            reason = _refusal(path, st, uid)
            if reason:
                raise SubmissionRefused(reason)
            newest = max(newest, st.st_ctime_ns)
            if stat.S_ISDIR(st.st_mode):
                with os.scandir(path) as entries:
                    for entry in entries:       # capped while listing: a flat folder of
                        if seen + len(pending) >= MAX_ENTRIES:   # millions costs nothing
                            raise SubmissionRefused(f"it holds more than {MAX_ENTRIES} entries")
                        pending.append((entry.path, depth + 1))
    except OSError as err:
        raise SubmissionRefused(f"cannot be read by the collecting account: {err}") from err
    return newest


#: what every entry costs against ``max_dir_size`` whatever its size: an empty file or folder
#: still takes the disk an inode and a block
ENTRY_BYTES = 4096
_DIR_FLAGS = os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW


def copy_submission(src: str, dest: str, uid: int, skipped, max_file_bytes: int,
                    max_total_bytes: int, chunk: int = 1 << 16) -> None:
    """Copy the submission ``src`` into the new folder ``dest``: nothing followed, nothing of
    the student's modes kept, every byte and entry counted.

    The walk goes by file descriptors: each folder and file is opened relative to its parent
    with ``O_NOFOLLOW``, checked *as opened* (a folder or regular file owned by ``uid``, a file
    with one name) and a folder is listed through its descriptor. A path checked and then
    swapped for a link is never followed: a file swapped for a link to ``/dev/zero`` filled the
    disk through ``copytree``, folders swapped for links to big folders after the
    check multiplied the copy. Copies are 0640, folders 0750, with no set-id bits
    or ACLs of the student's. ``skipped(name, st)`` says which entries nbgrader's rules leave
    out. Raises :class:`SubmissionRefused` past :data:`MAX_DEPTH`, :data:`MAX_ENTRIES`,
    ``max_file_bytes`` for a file or ``max_total_bytes`` (each entry costing at least
    :data:`ENTRY_BYTES`) in all.
    """
    budget = {"bytes": max_total_bytes, "entries": MAX_ENTRIES}
    try:
        top = os.open(src, _DIR_FLAGS)
    except OSError as err:
        raise SubmissionRefused(f"{src} cannot be opened as a folder: {err}") from err
    try:
        _check_opened(src, top, uid)
        os.mkdir(dest, 0o750)
        _copy_folder(top, src, dest, uid, skipped, max_file_bytes, budget, chunk, depth=0)
    finally:
        os.close(top)


def _check_opened(path: str, fd: int, uid: int) -> None:
    reason = _refusal(path, os.fstat(fd), uid)
    if reason:
        raise SubmissionRefused(reason)


def _copy_folder(fd: int, path: str, target: str, uid: int, skipped, max_file_bytes: int,
                 budget: dict, chunk: int, depth: int) -> None:
    """Copy the open folder ``fd`` (at ``path``) into ``target`` (see :func:`copy_submission`)."""
    if depth > MAX_DEPTH:
        raise SubmissionRefused(f"it holds more than {MAX_DEPTH} levels of folders")
    for name in sorted(os.listdir(fd)):
        budget["entries"] -= 1
        budget["bytes"] -= ENTRY_BYTES
        if budget["entries"] < 0 or budget["bytes"] < 0:
            raise SubmissionRefused("it grew past the size or entry limits while copied")
        where, out = os.path.join(path, name), os.path.join(target, name)
        st = os.stat(name, dir_fd=fd, follow_symlinks=False)
        if (depth == 0 and name == TIMESTAMP_FILE) or skipped(name, st):
            continue
        flags = _DIR_FLAGS if stat.S_ISDIR(st.st_mode) else os.O_RDONLY | os.O_NOFOLLOW | \
            os.O_NONBLOCK
        try:
            child = os.open(name, flags, dir_fd=fd)
        except OSError as err:
            raise SubmissionRefused(f"{where} cannot be opened without following it: "
                                    f"{err}") from err
        try:
            _check_opened(where, child, uid)
            if stat.S_ISDIR(os.fstat(child).st_mode):
                os.mkdir(out, 0o750)
                _copy_folder(child, where, out, uid, skipped, max_file_bytes, budget, chunk,
                             depth + 1)
            else:
                budget["bytes"] -= _copy_file(child, where, out, min(max_file_bytes,
                                                                     budget["bytes"]), chunk)
        finally:
            os.close(child)


def _copy_file(fd: int, where: str, out: str, limit: int, chunk: int) -> int:
    """Copy the open, checked file ``fd`` to the new file ``out`` (0640); returns its size.
    Raises :class:`SubmissionRefused` once more than ``limit`` bytes come."""
    copied = 0
    with open(os.open(out, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o640), "wb") as target:
        while block := os.read(fd, chunk):
            copied += len(block)
            if copied > limit:
                raise SubmissionRefused(f"{where} grew past the size limits while copied")
            target.write(block)
    return copied


def utc_stamp(ctime_ns: int, timestamp_format: str) -> str:
    """``ctime_ns`` (nanoseconds since the epoch) in nbgrader's ``timestamp_format``, in UTC."""
    epoch = datetime.datetime(1970, 1, 1, tzinfo=datetime.timezone.utc)
    moment = epoch + datetime.timedelta(microseconds=ctime_ns // 1000)  # exact, no float
    return moment.strftime(timestamp_format)


class PrivateExchangeCollect(ExchangeCollect):
    """``nbgrader collect`` that believes nothing a student wrote into the inbound.

    - a folder counts only if its owner is the Unix user it names (on the hub the student id is
      the login); others are skipped and logged;
    - a submission holding a symbolic link, a hard-linked file, anything but regular files and
      folders, or anything not owned by the student is refused whole and logged, so the
      student's previous valid submission, if any, is collected instead;
    - the latest submission is the one the exchange saw last (the newest ``ctime`` in it), and
      the copy's ``timestamp.txt`` is that time (UTC), never the student's own file or name.

    The owner check is always on (``ExchangeCollect.check_owner`` is not consulted).
    """

    def _path_to_record(self, path):
        """The record of the folder ``path``, timed by its ``ctime``; ``None`` when it does not
        count (logged)."""
        name = os.path.basename(path)
        student = name.rsplit("+", 3)[0]
        try:
            top = os.lstat(path)
            uid = pwd.getpwnam(student).pw_uid
        except KeyError:
            self.log.warning("Skipped %r: %r, the student it names, is no Unix user", path, student)
            return None
        except OSError as err:
            self.log.warning("Skipped %r: %r", path, str(err))
            return None
        if top.st_uid != uid:
            self.log.warning("Skipped %r: it claims to be %r's submission but is owned by %r",
                             path, student, _user_name(top.st_uid))
            return None
        try:
            if not stat.S_ISDIR(top.st_mode):
                raise SubmissionRefused(f"{path} is not a folder")
            ctime_ns = newest_ctime_ns(path, uid)
        except SubmissionRefused as why:
            self._log_refusal(path, student, why)
            return None
        stamp = utc_stamp(ctime_ns, self.timestamp_format)
        return {"username": student, "filename": name, "timestamp": parse_utc(stamp),
                "stamp": stamp, "ctime_ns": ctime_ns, "uid": uid}

    def _log_refusal(self, path, student, why):
        # every name and reason as a Python literal: a folder named with terminal escapes and
        # a newline forged a "Collecting submission" line
        self.log.warning("Refused %r, %r's submission: %r (nothing of it collected)",
                         path, student, str(why))

    def init_src(self):
        """Every submission that counts, by student (nbgrader's checks of the course first)."""
        if self.coursedir.course_id == "":
            self.fail("No course id specified. Re-run with --course flag.")
        self.course_path = os.path.join(self.root, self.coursedir.course_id)
        self.inbound_path = os.path.join(self.course_path, "inbound")
        if not os.path.isdir(self.inbound_path):
            self.fail(f"Course not found: {self.inbound_path}")
        if not check_mode(self.inbound_path, read=True, execute=True):
            self.fail(f"You don't have read permissions for the directory: {self.inbound_path}")
        student_id = self.coursedir.student_id or "*"
        pattern = os.path.join(self.inbound_path, f"{student_id}+{self.coursedir.assignment_id}+*")
        records = [r for r in map(self._path_to_record, sorted(glob.glob(pattern))) if r]
        self.by_student = groupby(records, lambda record: record["username"])
        with Gradebook(self.coursedir.db_url, self.coursedir.course_id) as gb:
            try:
                self.duedate = gb.find_assignment(self.coursedir.assignment_id).duedate
            except MissingEntry:
                self.duedate = None
        self.src_records = [self._preferred(v)[0] for v in self.by_student.values()]

    def _preferred(self, records):
        """``records`` newest first; with ``--before-duedate``, those on time first."""
        newest_first = self._sort_by_timestamp(records)
        if self.duedate is None or not self.before_duedate:
            return newest_first
        on_time = [r for r in newest_first if r["timestamp"] <= self.duedate]
        return on_time + [r for r in newest_first if r["timestamp"] > self.duedate]

    def copy_files(self):
        """Each student's preferred submission that survives its copy (see :meth:`_collect`)."""
        if not self.by_student:
            self.log.warning("No submissions of '%s' for course '%s' to collect",
                             self.coursedir.assignment_id, self.coursedir.course_id)
            return
        self.log.info("Processing %d submissions of '%s' for course '%s'", len(self.by_student),
                      self.coursedir.assignment_id, self.coursedir.course_id)
        for records in self.by_student.values():
            for record in self._preferred(records):
                if self._collect(record):
                    break

    def _wanted(self, record, dest):
        """nbgrader's rule: is ``record`` to replace what ``dest`` holds (``--update``,
        ``--before-duedate``)?"""
        if not os.path.isdir(dest):
            return True
        existing = self.coursedir.get_existing_timestamp(dest)
        if self.update and (existing is None or record["timestamp"] > existing):
            return True
        if self.before_duedate and existing != record["timestamp"]:
            return True
        advice = "No newer submission to collect" if self.update else \
            "Submission already exists, use --update to update"
        self.log.info("%s: %s %s", advice, record["username"], self.coursedir.assignment_id)
        return False

    def _collect(self, record) -> bool:
        """Copy ``record`` into the course (``False``: refused, nothing changed). Whatever a
        submission holds, the staging copy goes and the other students are still collected."""
        student, assignment = record["username"], self.coursedir.assignment_id
        dest = self.coursedir.format_path(self.coursedir.submitted_directory, student, assignment)
        if not self._wanted(record, dest):
            return True
        os.makedirs(os.path.dirname(dest), exist_ok=True)
        staging = tempfile.mkdtemp(prefix=".collecting-", dir=os.path.dirname(dest))
        copy = os.path.join(staging, assignment)
        src = os.path.join(self.inbound_path, record["filename"])
        try:
            self._copy(src, copy, record["uid"])
            if newest_ctime_ns(src, record["uid"]) != record["ctime_ns"]:
                raise SubmissionRefused("it changed while being collected")
            with open(os.path.join(copy, TIMESTAMP_FILE), "w") as fh:
                fh.write(record["stamp"])
            os.chmod(os.path.join(copy, TIMESTAMP_FILE), 0o640)
            if os.path.isdir(dest):
                self.log.info("Updating submission: %r %s", student, assignment)
                shutil.rmtree(dest)
            else:
                self.log.info("Collecting submission: %r %s", student, assignment)
            os.rename(copy, dest)
            return True
        except Exception as why:  # noqa: BLE001 - one submission never stops the collect
            self._log_refusal(src, student, why)
            return False
        finally:
            shutil.rmtree(staging, ignore_errors=True)

    def _copy(self, src, dest, uid):
        """nbgrader's copy rules (``CourseDirectory.ignore``/``include`` globs,
        ``max_file_size``, ``max_dir_size``) applied by :func:`copy_submission`: nothing
        followed, every byte counted, the student's ``timestamp.txt`` left out."""
        copy_submission(src, dest, uid, self._skipped,
                        max_file_bytes=1000 * self.coursedir.max_file_size,
                        max_total_bytes=1000 * self.coursedir.max_dir_size)

    def _skipped(self, name: str, st: os.stat_result) -> bool:
        """nbgrader's ``ignore_patterns`` for one entry, on what ``lstat`` says of it (its own
        log printed names raw)."""
        coursedir = self.coursedir
        if any(fnmatch.fnmatch(name, pattern) for pattern in coursedir.ignore):
            return True
        if not stat.S_ISREG(st.st_mode):
            return False
        if coursedir.include and not any(fnmatch.fnmatch(name, p) for p in coursedir.include):
            return True
        if coursedir.max_file_size and st.st_size > 1000 * coursedir.max_file_size:
            self.log.warning("Ignoring file too large %r (see CourseDirectory.max_file_size)",
                             name)
            return True
        return False
