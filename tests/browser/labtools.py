"""Starting and stopping ``python -m autograder lab`` for the browser tests."""

from __future__ import annotations

import contextlib
import re
import signal
import subprocess
import sys
import time
import urllib.request
import uuid
from pathlib import Path

import pytest


@contextlib.contextmanager
def running_lab(args: list[str], port: int, log_path: Path, cwd: Path, env: dict,
                what: str = "the lab"):
    """``python -m autograder lab ARGS``: yields its URL once it answers, stops it afterwards."""
    log = open(log_path, "w+")
    proc = subprocess.Popen([sys.executable, "-m", "autograder", "lab", *args, "--port",
                             str(port), "--no-browser"], cwd=cwd, env=env, stdout=log,
                            stderr=subprocess.STDOUT, text=True)
    try:
        deadline, url = time.monotonic() + 180, None
        while time.monotonic() < deadline and proc.poll() is None and url is None:
            log.seek(0)
            m = re.search(rf"(http://localhost:{port}/\S*\?token=\w+)", log.read())
            if m:
                try:
                    with urllib.request.urlopen(m.group(1), timeout=5) as r:
                        url = m.group(1) if r.status == 200 else None
                except OSError:
                    pass
            if url is None:
                time.sleep(0.5)
        if url is None:
            log.seek(0)
            pytest.fail(f"{what} did not come up:\n{log.read()[-3000:]}")
        yield url
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
        log.close()


def open_notebook(page, base: str, query: str, path: str) -> None:
    """Open ``path`` in a JupyterLab workspace of its own, reset, and wait for its cells.

    JupyterLab restores the tabs of the last session (its workspaces live in the user's
    settings, shared by every lab a test run starts): without a workspace of its own the page
    may show another test's notebook in front and this one's cells hidden behind it."""
    workspace = "t" + uuid.uuid4().hex[:12]
    page.goto(f"{base}/lab/workspaces/{workspace}/tree/{path}?reset&{query}")
    page.locator(".jp-NotebookPanel:visible .jp-Notebook .jp-Cell").first.wait_for()


def wait_idle(page, timeout_s: float) -> None:
    """Until the kernel is idle and no cell shows a pending prompt [*]."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        status = page.locator(".jp-StatusBar-Widget").all_inner_texts()
        busy = page.locator(".jp-InputArea-prompt", has_text="[*]").count()
        if busy == 0 and any("Idle" in s for s in status):
            return
        time.sleep(0.5)
    raise AssertionError(f"kernel still busy after {timeout_s} s")


def run_all_cells(page, start_s: float = 120, run_s: float = 300) -> None:
    """Run > Run All Cells once the kernel is up, and wait until it is idle again."""
    wait_idle(page, start_s)
    page.locator(".lm-MenuBar-itemLabel", has_text="Run").first.click()
    page.locator(".lm-Menu-itemLabel", has_text="Run All Cells").first.click()
    time.sleep(1.0)  # the first cell's [*] appears only after the click is handled
    wait_idle(page, run_s)
