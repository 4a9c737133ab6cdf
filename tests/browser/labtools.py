"""Starting and stopping ``python -m autograder lab`` for the browser tests."""

from __future__ import annotations

import contextlib
import re
import signal
import subprocess
import sys
import time
import urllib.request
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
