"""``python -m autograder lab``: the student and instructor views really differ.

Each test starts the real command on a free port (course root in a temporary directory), waits
for the server, reads the page config that ``/lab`` embeds in its HTML (``jupyter-config-data``,
what the JupyterLab front end reads its ``disabledExtensions`` from) and probes the nbgrader
server extensions: students get no formgrader / course list / create-assignment, instructors get
all of them; both keep validate and the assignments list. The instructor's formgrader lists
``tripos2006`` from the course gradebook, a request without the token is refused, and (on Linux)
the server's environment carries the per-launch config dir and no ``MPLBACKEND``.
"""

from __future__ import annotations

import html
import json
import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.parse
import urllib.request
from pathlib import Path

import pytest

from autograder.course import ASSIGNMENT, nbgrader_env, source_notebooks

pytestmark = [
    pytest.mark.skipif(not source_notebooks(), reason="no notebooks/q*.ipynb yet"),
    pytest.mark.timeout(300),
]

STUDENT_OFF = {"@jupyter/nbgrader:formgrader", "@jupyter/nbgrader:create-assignment",
               "@jupyter/nbgrader:course-list"}
ALWAYS_ON = {"@jupyter/nbgrader:validate-assignment", "@jupyter/nbgrader:assignment-list"}


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _get(url: str) -> tuple[int, str]:
    try:
        with urllib.request.urlopen(url, timeout=10) as r:
            return r.status, r.read().decode()
    except urllib.error.HTTPError as e:
        return e.code, ""


@pytest.fixture(params=["student", "instructor"])
def lab(request, course, repo_root, tmp_path):
    role, port = request.param, _free_port()
    log = open(tmp_path / "lab.log", "w+")
    proc = subprocess.Popen(
        [sys.executable, "-m", "autograder", "lab", "--role", role, "--port", str(port),
         "--no-browser", "--course-root", str(course.root)],
        cwd=repo_root, env=nbgrader_env(), stdout=log, stderr=subprocess.STDOUT, text=True,
    )
    try:
        deadline, url = time.monotonic() + 120, None
        while time.monotonic() < deadline and proc.poll() is None:
            log.seek(0)
            text = log.read()
            if url is None:
                m = re.search(rf"(http://localhost:{port}/\S*\?token=(\w+))", text)
                url = m and m.group(1)
            if url and "is running at" in text:
                try:
                    if _get(url)[0] == 200:
                        break
                except OSError:
                    pass
            time.sleep(0.3)
        else:
            log.seek(0)
            pytest.fail(f"the {role} lab did not come up:\n{log.read()[-3000:]}")
        token = re.search(r"token=(\w+)", url).group(1)
        yield role, port, token, url, proc.pid
    finally:
        proc.send_signal(signal.SIGINT)  # as Ctrl-C: the launcher stops JupyterLab
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
        log.close()


def _server_environ(launcher_pid: int) -> dict[str, str] | None:
    """The environment of the JupyterLab process the launcher started (Linux /proc only)."""
    children = Path(f"/proc/{launcher_pid}/task/{launcher_pid}/children")
    if not children.exists():
        return None
    pids = children.read_text().split()
    if not pids:
        return None
    raw = Path(f"/proc/{pids[0]}/environ").read_bytes().split(b"\0")
    return dict(item.decode().split("=", 1) for item in raw if b"=" in item)


def test_lab_views(lab):
    role, port, token, url, launcher_pid = lab
    assert "MPLBACKEND" in os.environ  # tests/conftest.py sets Agg, as `make` does
    env = _server_environ(launcher_pid)
    if env is not None:
        # kernels choose their own backend in a lab (inline or the notebook's ipympl)
        assert "MPLBACKEND" not in env
        assert env["JUPYTER_CONFIG_PATH"].split(os.pathsep)[0].startswith(tempfile.gettempdir())
    assert url.startswith(f"http://localhost:{port}/lab")
    # a request without the token is refused
    status, _ = _get(f"http://127.0.0.1:{port}/api/contents")
    assert status == 403
    status, page = _get(url)
    assert status == 200
    m = re.search(r'<script id="jupyter-config-data" type="application/json">(.*?)</script>',
                  page, re.DOTALL)
    assert m, "no page config in /lab"
    config = json.loads(html.unescape(m.group(1)))
    disabled = set(config.get("disabledExtensions", []))
    base = f"http://127.0.0.1:{port}"
    formgrader = _get(f"{base}/formgrader?token={token}")[0]
    course_list = _get(f"{base}/formgraders?token={token}")[0]
    assignments = _get(f"{base}/courses?token={token}")[0]
    root = config.get("serverRoot", "")
    if role == "student":
        assert STUDENT_OFF <= disabled
        assert not ALWAYS_ON & disabled
        assert (formgrader, course_list) == (404, 404)
        assert root.endswith("/release")
        assert config.get("treePath") == ASSIGNMENT, "the student lab opens on the assignment"
        # the Validate button's endpoint works: an untouched student version does not validate
        nb = min(source_notebooks(), key=lambda p: p.stat().st_size).name
        request = urllib.request.Request(
            f"{base}/assignments/validate?token={token}", method="POST",
            data=urllib.parse.urlencode({"path": f"{ASSIGNMENT}/{nb}"}).encode())
        with urllib.request.urlopen(request, timeout=240) as r:
            answer = json.loads(r.read())
        assert answer["success"], answer
        assert answer["value"].get("failed"), "an unanswered notebook passed validation"
    else:
        assert not {p for p in disabled if p.startswith("@jupyter/nbgrader")}
        assert (formgrader, course_list) == (200, 200)
        assert not root.endswith("/release")
        # the formgrader works on this course: it lists the assignment from its gradebook
        status, body = _get(f"{base}/formgrader/api/assignments?token={token}")
        assert status == 200
        assert ASSIGNMENT in {a.get("name") for a in json.loads(body)}
    assert assignments == 200
