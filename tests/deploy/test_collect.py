"""``nbgrader collect`` on the hub's exchange believes nothing a student wrote into it.

The red team's attacks (``findings7`` §2–4), each made by a real Unix user as their own uid
(``runuser``) in an exchange prepared by ``deploy/hub.py`` itself (inbound 3733 and its default
ACL), then the real ``nbgrader collect`` as the hub runs it: as the grader account, in the
instructors' environment ``deploy/hub.py`` builds (cached in ``test-artifacts/deploy/envs/``, shared
with the hub test), with the Jupyter config it writes, which names the deployment's collect class
(``deploy/private_exchange.py``). ``COLLECT_CLASS_UNDER_TEST`` names another on the command line,
e.g. nbgrader's own ``nbgrader.exchange.default.collect.ExchangeCollect``: every attack test
here fails with it.

- §2: a student makes a folder named for a classmate (2099 in its name); the classmate's own
  work must be collected, the impostor's folder skipped, and nobody may rename another's folder;
- §3: a submitted symbolic link to the course's model answers or to a classmate's collected
  work, and a hard link to a classmate's file: refused, the attacker's earlier valid submission
  collected instead;
- §4: a backdated ``timestamp.txt`` and a 2099 folder name: the submission collected is the one
  the exchange saw last, stamped with when it was written;
- and a submission written to while it is being copied is refused (a collect class that writes
  during its own copy stands in for the student).

Oracles: each notebook's content is a marker the test wrote, and each true time is the test's
own clock around the write. Skipped when not root, or without ``useradd``, ``setfacl`` or
Debian's ``python3-venv``.
"""

from __future__ import annotations

import datetime
import os
import shutil
import stat
import subprocess
import tempfile
import time
from pathlib import Path

import pytest
from hubtools import ENVS, missing_for_accounts

import hub  # deploy/hub.py (hubtools, imported by conftest, puts deploy/ on sys.path)

pytestmark = [pytest.mark.xdist_group("hub")]

A, NB, COURSE = "tripos2006", "q5_phong.ipynb", "4f9"
PREFIX = "t4c8"
VICTIM, MALLORY, EVE, HONEST = (f"{PREFIX}{n}" for n in ("vic", "mal", "eve", "hon"))
STUDENTS = (VICTIM, MALLORY, EVE, HONEST)
GRADER, INSTRUCTORS, STUDENTS_GROUP = f"{PREFIX}grader", f"{PREFIX}-inst", f"{PREFIX}-stud"
#: ``--ExchangeFactory.collect=...``: another collect than the deployment's (see above)
COLLECT = os.environ.get("COLLECT_CLASS_UNDER_TEST")
#: how far a collected time may sit outside the test's clock around the write (ctime is coarse)
SLACK = datetime.timedelta(seconds=1)
NOW_STAMP = "%Y-%m-%d %H:%M:%S.%f UTC"


def _skip_reason() -> str | None:
    return missing_for_accounts("the collect test creates Unix users",
                                (("/usr/sbin/useradd", "passwd"), ("/usr/bin/setfacl", "acl"),
                                 ("/usr/sbin/runuser", "util-linux")))


def _remove_accounts() -> None:
    for name in (*STUDENTS, GRADER):
        subprocess.run(["userdel", "--remove", name], capture_output=True)
    for group in (INSTRUCTORS, STUDENTS_GROUP):
        subprocess.run(["groupdel", group], capture_output=True)


@pytest.fixture(scope="module")
def accounts():
    """The accounts, and the instructors' environment (with ``private_exchange`` installed)."""
    reason = _skip_reason()
    if reason:
        pytest.skip(reason)
    _remove_accounts()  # a run killed half-way leaves them behind
    try:
        hub.ensure_user(GRADER, [INSTRUCTORS])
        for name in STUDENTS:
            hub.ensure_user(name, [STUDENTS_GROUP])
        hub.build_instructor_env(ENVS / "instructor", INSTRUCTORS)
        yield
    finally:
        _remove_accounts()


@pytest.fixture
def place(accounts):
    """A fresh exchange and Jupyter config (as ``deploy/hub.py`` makes them), the grader's
    course folder (0700) and a folder anyone may write in (``/tmp``'s modes, same filesystem)."""
    state = Path(tempfile.mkdtemp(prefix="4f9-collect-", dir="/tmp"))
    os.chmod(state, 0o755)
    settings = hub.HubSettings(state=str(state), course_id=COURSE, grader=GRADER,
                               students_group=STUDENTS_GROUP, instructors_group=INSTRUCTORS,
                               envs=str(ENVS))
    hub.write_jupyter_configs(settings)
    hub.prepare_exchange(settings)
    inbound = hub.prepare_inbound(settings)
    course = Path(settings.paths["course_dir"])
    (course / "source" / A).mkdir(parents=True)
    for folder in (course, course / "source", course / "source" / A):
        shutil.chown(folder, GRADER, GRADER)
    os.chmod(course, 0o700)
    public = state / "public"
    public.mkdir()
    os.chmod(public, 0o1777)
    try:
        yield {"inbound": inbound, "course": course, "public": public, "settings": settings}
    finally:
        shutil.rmtree(state, ignore_errors=True)
        shutil.rmtree(course, ignore_errors=True)


def _as(user: str, script: str, **env) -> subprocess.CompletedProcess:
    """``sh -c script`` as ``user``'s uid, the values in ``env`` as variables."""
    return hub.as_user(user, ["sh", "-c", script], env={k: str(v) for k, v in env.items()},
                       timeout=60)


def _submit(place, user: str, marker: str, *, claimed: str | None = None,
            stamp: str | None = None, link: str | None = None, hard: str | None = None) -> dict:
    """A submission as ``user`` leaves it with ``PrivateExchangeSubmit`` (folder 0770, files
    0640): named for ``claimed`` (default ``user``) with ``stamp`` (default: now) in its name and
    ``timestamp.txt``; the notebook holds ``marker``, or is a symbolic (``link``) or hard
    (``hard``) link to that path. Returns the folder and the clock around the write."""
    stamp = stamp or datetime.datetime.now(datetime.timezone.utc).strftime(NOW_STAMP)
    folder = place["inbound"] / f"{claimed or user}+{A}+{stamp}+{os.urandom(9).hex()}"
    make = ('ln -s "$TARGET" "$D/$NB"' if link else 'ln "$TARGET" "$D/$NB"' if hard
            else 'printf %s "$MARKER" > "$D/$NB"; chmod 640 "$D/$NB"')
    before = datetime.datetime.now(datetime.timezone.utc)
    proc = _as(user, f'set -e; mkdir "$D"; {make}; printf %s "$STAMP" > "$D/timestamp.txt"; '
                     'chmod 640 "$D/timestamp.txt"; chmod 770 "$D"',
               D=folder, NB=NB, MARKER=marker, STAMP=stamp, TARGET=link or hard or "")
    after = datetime.datetime.now(datetime.timezone.utc)
    assert proc.returncode == 0, proc.stderr
    return {"folder": folder, "before": before, "after": after}


def _as_grader_file(path: Path, text: str) -> None:
    path.write_text(text)
    shutil.chown(path, GRADER, GRADER)


def _collect(place, *options: str) -> str:
    """``nbgrader collect --update`` of the class, as the README's grader does; its log.
    (``PYTHONPATH``: the grader's home, for a collect class a test puts there.)"""
    settings = place["settings"]
    if COLLECT and not any(o.startswith("--ExchangeFactory.collect=") for o in options):
        options = (f"--ExchangeFactory.collect={COLLECT}", *options)
    env = {**hub.grader_env(settings), "PYTHONPATH": hub.home_of(GRADER)}
    python = Path(settings.paths["instructor_env"]) / "bin" / "python"
    proc = hub.as_user(GRADER, [python, "-m", "nbgrader", "collect", "--update", *options, A],
                       env=env, cwd=str(place["course"]), timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc.stderr


def _collected(place, student: str) -> Path:
    return place["course"] / "submitted" / student / A


def _content(place, student: str) -> str | None:
    notebook = _collected(place, student) / NB
    return notebook.read_text() if notebook.exists() else None


def _assert_true_time(place, student: str, written: dict) -> None:
    """The collected ``timestamp.txt`` is within the test's clock around the write."""
    text = (_collected(place, student) / "timestamp.txt").read_text().strip()
    when = datetime.datetime.strptime(text, NOW_STAMP).replace(tzinfo=datetime.timezone.utc)
    assert written["before"] - SLACK <= when <= written["after"] + SLACK, \
        (student, text, written["before"], written["after"])


def _log_line(log: str, folder: Path, *words: str) -> str:
    """The log's line about ``folder``, which must hold every one of ``words``."""
    lines = [line for line in log.splitlines() if folder.name in line]
    assert lines, f"no log line names {folder.name}:\n{log}"
    assert all(word in lines[0] for word in words), (words, lines[0])
    return lines[0]


def test_a_folder_named_for_a_classmate_is_skipped_and_cannot_displace_theirs(place):
    """§2: Mallory's ``<victim>+...+2099...`` folder is skipped; the victim's own work and true
    time are collected; an honest student's too; no student renames another's folder."""
    victim = _submit(place, VICTIM, "victim's own work")
    honest = _submit(place, HONEST, "honest work")
    forged = _submit(place, MALLORY, "blank release", claimed=VICTIM,
                     stamp="2099-01-01 00:00:00.000000 UTC")
    moved = _as(MALLORY, 'mv "$D" "$IN/stolen"', D=victim["folder"], IN=place["inbound"])
    assert moved.returncode != 0 and "not permitted" in moved.stderr, moved.stderr
    log = _collect(place)
    assert _content(place, VICTIM) == "victim's own work"
    _assert_true_time(place, VICTIM, victim)
    assert _content(place, HONEST) == "honest work"
    _assert_true_time(place, HONEST, honest)
    _log_line(log, forged["folder"], "Skipped", MALLORY, VICTIM)
    assert not _collected(place, MALLORY).exists()


def test_symbolic_links_are_refused_and_the_previous_submission_collected(place):
    """§3: links to the course's model answers and to a classmate's collected notebook refuse
    the whole submission; Eve's earlier valid one is collected, Mallory has none."""
    victim = _submit(place, VICTIM, "victim's own work")
    _collect(place)
    model = place["course"] / "source" / A / NB
    _as_grader_file(model, "model answers")
    eve_before = _submit(place, EVE, "eve's own earlier work")
    time.sleep(1.1)  # the two of Eve's submissions a clear second apart
    to_model = _submit(place, MALLORY, "", link=str(model))
    to_victim = _submit(place, EVE, "", link=str(_collected(place, VICTIM) / NB))
    log = _collect(place)
    assert _content(place, MALLORY) is None and not _collected(place, MALLORY).exists()
    assert _content(place, EVE) == "eve's own earlier work"
    _assert_true_time(place, EVE, eve_before)
    assert _content(place, VICTIM) == "victim's own work"
    _assert_true_time(place, VICTIM, victim)
    _log_line(log, to_model["folder"], "Refused", MALLORY, "symbolic link")
    _log_line(log, to_victim["folder"], "Refused", EVE, "symbolic link")


def test_hard_links_are_refused(place):
    """§3: Eve hard-links the victim's notebook (left writable in a shared folder), Mallory one
    of her own files kept outside the exchange: both refused, nothing of theirs collected."""
    shared = place["public"] / "victim-draft.ipynb"
    made = _as(VICTIM, 'printf %s "victim\'s draft" > "$F"; chmod 666 "$F"', F=shared)
    assert made.returncode == 0, made.stderr
    stash = place["public"] / "mallory-stash.ipynb"
    made = _as(MALLORY, 'printf %s "mallory, changed after the collect" > "$F"', F=stash)
    assert made.returncode == 0, made.stderr
    honest = _submit(place, HONEST, "honest work")
    eve = _submit(place, EVE, "", hard=str(shared))
    mallory = _submit(place, MALLORY, "", hard=str(stash))
    log = _collect(place)
    assert _content(place, EVE) is None and _content(place, MALLORY) is None
    _log_line(log, eve["folder"], "Refused", EVE, f"owned by {VICTIM}")
    _log_line(log, mallory["folder"], "Refused", MALLORY, "hard link")
    assert _content(place, HONEST) == "honest work"
    _assert_true_time(place, HONEST, honest)


def test_the_time_is_the_exchanges_not_the_students(place):
    """§4: a backdated ``timestamp.txt`` (and name) gets the time it was really written; of a
    student's two submissions, the one named 2099 but written first loses to the later one."""
    backdated = _submit(place, MALLORY, "late work", stamp="2026-12-01 15:59:00.000000 UTC")
    _submit(place, EVE, "eve's first", stamp="2099-01-01 00:00:00.000000 UTC")
    time.sleep(1.1)
    eve_last = _submit(place, EVE, "eve's last")
    honest = _submit(place, HONEST, "honest work")
    _collect(place)
    assert _content(place, MALLORY) == "late work"
    _assert_true_time(place, MALLORY, backdated)
    assert _content(place, EVE) == "eve's last"
    _assert_true_time(place, EVE, eve_last)
    assert _content(place, HONEST) == "honest work"
    _assert_true_time(place, HONEST, honest)


#: a collect that appends to the submission it is copying (as a student writing at that moment)
RACY_COLLECT = """
import private_exchange


class RacyCollect(private_exchange.PrivateExchangeCollect):
    def _copy(self, src, dest, uid):
        super()._copy(src, dest, uid)
        if "+{stamp}+" in src:
            with open(src + "/{notebook}", "a") as fh:
                fh.write(" and more")
"""

#: a collect during whose scan-to-copy gap the notebook becomes a link to /dev/zero (red team 9:
#: the student swapped it once collect was busy with larger files; the copy filled the disk)
SWAPPING_COLLECT = """
import os

import private_exchange


class SwappingCollect(private_exchange.PrivateExchangeCollect):
    def _copy(self, src, dest, uid):
        if "+{stamp}+" in src:
            os.replace(src + "/{notebook}", src + "/old")
            os.symlink("/dev/zero", src + "/{notebook}")
        super()._copy(src, dest, uid)
"""


@pytest.mark.parametrize("module, source, cls, reason", [
    ("racy_collect", RACY_COLLECT, "RacyCollect", "changed while being collected"),
    ("swapping_collect", SWAPPING_COLLECT, "SwappingCollect", "without following it"),
], ids=["written-while-copied", "swapped-for-a-link"])
def test_a_submission_changed_under_the_collect_is_refused(place, module, source, cls, reason):
    """A write into the submission during its copy (its ``ctime`` moves), or its notebook
    swapped for a link to ``/dev/zero`` between the scan and the copy (red team 9: the copy
    filled the disk): refused, no staging folder left, and the student's previous submission,
    with its own time, collected instead."""
    first = _submit(place, HONEST, "first")
    time.sleep(1.1)
    late_stamp = "2026-12-02 00:00:00.000000 UTC"
    second = _submit(place, HONEST, "second", stamp=late_stamp)
    opened = _as(HONEST, 'chmod 660 "$F"', F=second["folder"] / NB)  # the grader may write it
    assert opened.returncode == 0, opened.stderr
    _as_grader_file(Path(hub.home_of(GRADER)) / f"{module}.py",
                    source.format(stamp=late_stamp, notebook=NB))
    log = _collect(place, f"--ExchangeFactory.collect={module}.{cls}")
    _log_line(log, second["folder"], "Refused", HONEST, reason)
    assert _content(place, HONEST) == "first"
    _assert_true_time(place, HONEST, first)
    assert not list((place["course"] / "submitted" / HONEST).glob(".collecting-*"))


def test_a_deep_folder_is_refused_and_the_others_still_collected(place):
    """Red team 9: a folder 200 levels deep overflowed nbgrader's size count and stopped the
    collect for everyone after it. Now that submission alone is refused."""
    deep = _submit(place, MALLORY, "deep")
    made = _as(MALLORY, 'cd "$D" && for i in $(seq 200); do mkdir d && cd d; done', D=deep["folder"])
    assert made.returncode == 0, made.stderr
    honest = _submit(place, HONEST, "honest")
    log = _collect(place)
    _log_line(log, deep["folder"], "Refused", MALLORY, "levels of folders")
    assert _content(place, MALLORY) is None and _content(place, HONEST) == "honest"
    _assert_true_time(place, HONEST, honest)


def test_the_collected_copy_keeps_none_of_the_students_modes(place):
    """Red team 9: a set-id, world-writable file came out of collect owned by the grader with
    its modes. Copies are the grader's, 0640 (folders 0750)."""
    sub = _submit(place, MALLORY, "mine")
    made = _as(MALLORY, 'mkdir "$D/sub" && printf x > "$D/sub/tool" && chmod 6777 "$D/sub/tool" '
                        '&& chmod 2777 "$D/sub" && chmod 666 "$D/$NB"', D=sub["folder"], NB=NB)
    assert made.returncode == 0, made.stderr
    _collect(place)
    copy = _collected(place, MALLORY)
    assert _content(place, MALLORY) == "mine"
    for path in (copy / NB, copy / "sub" / "tool", copy / "timestamp.txt"):
        assert stat.S_IMODE(path.lstat().st_mode) == 0o640, (path, oct(path.lstat().st_mode))
    assert stat.S_IMODE((copy / "sub").lstat().st_mode) == 0o750


def test_a_folder_name_cannot_forge_the_log(place):
    """Red team 9: a name with terminal escapes and a newline hid the "Skipped" warning and
    printed a fake "Collecting submission" line. Names are logged as Python literals."""
    forged = place["inbound"] / (f"{VICTIM}+{A}+2026-12-01 00:00:00.000000 UTC+ab\x1b[2K\r"
                                 f"\n[CollectApp | INFO] Collecting submission: {VICTIM} {A}")
    made = _as(MALLORY, 'mkdir "$D" && printf x > "$D/$NB"', D=forged, NB=NB)
    assert made.returncode == 0, made.stderr
    log = _collect(place)
    assert "\x1b" not in log
    lines = log.splitlines()
    assert not any(line.startswith("[CollectApp | INFO] Collecting submission") for line in lines)
    assert any("Skipped" in line and "owned by" in line and MALLORY in line for line in lines)


# -- the copy itself, in this process (no accounts needed) ---------------------------------------

def _tree(root: Path, files: int = 2) -> Path:
    sub = root / "submission"
    (sub / "a").mkdir(parents=True)
    (sub / "b").mkdir()
    for k in range(files):
        (sub / "a" / f"f{k}").write_text("x")
        (sub / "b" / f"g{k}").write_text("y")
    return sub


def test_a_folder_swapped_for_a_link_after_its_check_is_never_listed(tmp_path):
    """Red team 10: folders checked, then swapped for links to big folders before the copy
    listed them, multiplied the copy (100,000 inodes). The walk lists each folder through the
    descriptor it checked, and opens nothing through a link: the swap refuses the submission
    and nothing of the linked folder is copied."""
    import private_exchange as pe

    sub = _tree(tmp_path)
    big = tmp_path / "big"
    big.mkdir()
    for k in range(500):
        (big / f"h{k}").write_text("z")

    def skipped(name, st):
        if name == "b" and not (sub / "b").is_symlink():   # just after "b" was looked at
            shutil.rmtree(sub / "b")
            (sub / "b").symlink_to(big)
        return False

    dest = tmp_path / "copy"
    with pytest.raises(pe.SubmissionRefused, match="without following it"):
        pe.copy_submission(str(sub), str(dest), os.getuid(), skipped, max_file_bytes=10**6,
                           max_total_bytes=10**8)
    copied = [p.name for p in dest.rglob("*")]
    assert not any(name.startswith("h") for name in copied), copied
    assert sorted(n for n in copied if n.startswith("f")) == ["f0", "f1"]   # "a" came first


def test_every_entry_counts_against_the_size_limit(tmp_path):
    """Empty files cost nothing in bytes but an inode each: each entry is charged
    ``ENTRY_BYTES``, so 300 empty files do not fit in 100 entries' worth."""
    import private_exchange as pe

    sub = _tree(tmp_path, files=150)
    for path in sub.rglob("f*"):
        path.write_text("")
    with pytest.raises(pe.SubmissionRefused, match="limits"):
        pe.copy_submission(str(sub), str(tmp_path / "copy"), os.getuid(), lambda n, s: False,
                           max_file_bytes=10**6, max_total_bytes=100 * pe.ENTRY_BYTES)
    pe.copy_submission(str(sub), str(tmp_path / "whole"), os.getuid(), lambda n, s: False,
                       max_file_bytes=10**6, max_total_bytes=400 * pe.ENTRY_BYTES)
    assert len(list((tmp_path / "whole").rglob("*"))) == 2 + 300
