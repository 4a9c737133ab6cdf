"""A real JupyterHub of the course on localhost (``deploy/hub.py``), for one test module.

Real Unix users (two students, an instructor and the grader account) are created for the run
and removed after it; they log in through PAM, JupyterHub's default authenticator, with random
passwords set by ``chpasswd``: the test walks the same path as a class, and each user's server
runs under that user's uid (``LocalProcessSpawner``), so file permissions are really tested.
The students' and instructors' environments are cached in ``test-artifacts/deploy/envs/``
(rebuilt when the wheel or ``pyproject.toml`` changes); the hub's state lives in a fresh folder
under ``/tmp`` (0755: the users must reach their environments' config through it).

Skipped, with the reason, when not root, or when Debian's ``configurable-http-proxy``,
``chromium`` or ``python3-venv`` is missing (``make test`` installs them as root).
"""

from __future__ import annotations

import contextlib
import os
import secrets
import shutil
import subprocess
import tempfile
import time
import urllib.request
from pathlib import Path

import pytest

from hubtools import (ARTIFACTS, BURST, CHROMIUM, ENVS, GRADER, GRADING_PREFIX, INSTRUCTOR, LONE,
                      PREFIX, STUDENTS, missing_for_accounts)

import hub  # deploy/hub.py (hubtools puts deploy/ on sys.path)


def _skip_reason() -> str | None:
    return missing_for_accounts(
        "the hub test creates Unix users and runs a setuid spawner",
        (("/usr/bin/configurable-http-proxy", "node-configurable-http-proxy"),
         (str(CHROMIUM), "chromium"), ("/usr/sbin/useradd", "passwd"),
         ("/usr/bin/setfacl", "acl")))


def _remove_account(name: str) -> None:
    """End what still runs as ``name`` (by pid: the servers and kernels this test started), then
    remove the account and its home."""
    try:
        hub.pwd.getpwnam(name)
    except KeyError:
        return
    ps = subprocess.run(["ps", "-u", name, "-o", "pid="], capture_output=True, text=True)
    for pid in ps.stdout.split():
        try:
            os.kill(int(pid), 9)
        except (ProcessLookupError, ValueError):
            pass
    subprocess.run(["userdel", "--remove", name], capture_output=True)


def _remove_accounts(settings: hub.HubSettings, accounts: tuple[str, ...]) -> None:
    for name in accounts:
        _remove_account(name)
    for group in (settings.students_group, settings.instructors_group):
        subprocess.run(["groupdel", group], capture_output=True)


def _stop_orphaned_proxy(pid_file: Path) -> None:
    """A hub that fails while starting leaves its proxy running: stop it (its pid, from the
    hub's own pid file)."""
    try:
        pid = int(pid_file.read_text().strip())
        cmdline = Path(f"/proc/{pid}/cmdline").read_bytes()
    except (OSError, ValueError):
        return
    if b"configurable-http-proxy" in cmdline:  # not a process that took over a stale pid
        os.kill(pid, 15)


def _wait_for_hub(proc, url: str, log: Path, timeout: float = 120) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and proc.poll() is None:
        try:
            with urllib.request.urlopen(f"{url}/hub/api", timeout=3) as r:
                if r.status == 200:
                    return
        except OSError:
            time.sleep(0.5)
    pytest.fail(f"the hub did not come up:\n{log.read_text()[-4000:]}")


@contextlib.contextmanager
def running_hub(prefix: str = PREFIX, students: tuple[str, ...] = STUDENTS,
                instructor: str = INSTRUCTOR, grader: str = GRADER, log_name: str = "hub.log",
                **options):
    """A running hub whose accounts are named from ``prefix``: ``dict(url, settings, passwords,
    log)``; everything removed afterwards (skips, with the reason, where it cannot run).
    ``options``: more :class:`hub.HubSettings` (e.g. ``grading_service=False``)."""
    reason = _skip_reason()
    if reason:
        pytest.skip(reason)
    import studentenv

    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    state = Path(tempfile.mkdtemp(prefix="4f9-hub-", dir="/tmp"))
    os.chmod(state, 0o755)
    settings = hub.HubSettings(state=str(state), port=hub.free_port(), course_id="4f9",
                               grader=grader, students_group=f"{prefix}-students",
                               instructors_group=f"{prefix}-instructors", envs=str(ENVS),
                               **options)
    accounts = (*students, instructor, grader)
    _remove_accounts(settings, accounts)  # a run killed half-way leaves them behind
    passwords = {name: secrets.token_urlsafe(12) for name in (*students, instructor)}
    log_path = ARTIFACTS / log_name
    proc = None
    try:
        hub.prepare(settings, studentenv.BUILD_CACHE)
        for name in students:
            hub.ensure_user(name, [settings.students_group], passwords[name])
        hub.ensure_user(instructor, [settings.instructors_group], passwords[instructor])
        cmd, env = hub.hub_command(settings)
        log = open(log_path, "w")
        proc = subprocess.Popen(cmd, env=env, cwd=settings.paths["hub_dir"], stdout=log,
                                stderr=subprocess.STDOUT)
        url = f"http://127.0.0.1:{settings.port}"
        _wait_for_hub(proc, url, log_path)
        yield {"url": url, "settings": settings, "passwords": passwords, "log": log_path}
    finally:
        if proc is not None:
            proc.terminate()  # the hub stops the users' servers and its services
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
        _stop_orphaned_proxy(Path(settings.paths["hub_dir"]) / "proxy.pid")
        _remove_accounts(settings, accounts)
        shutil.rmtree(state, ignore_errors=True)


@pytest.fixture(scope="module")
def course_hub():
    """A running hub: ``dict(url, settings, passwords, log)``; everything removed afterwards.

    Its grading service is switched off: the term test walks the batch term (collect, grade,
    mark, hand back after the deadline), which the service's own pages and gradebook writes
    would race; the service has its hub in ``grading_hub``."""
    with running_hub(grading_service=False) as running:
        yield running


@pytest.fixture(scope="module")
def grading_hub():
    """A running hub with the grading service, three lone students and 30 for the burst."""
    with running_hub(GRADING_PREFIX, (*LONE, *BURST), f"{GRADING_PREFIX}prof",
                     f"{GRADING_PREFIX}grader", "hub-grading.log") as running:
        yield running
