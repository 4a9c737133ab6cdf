"""Ctrl-C on the course's JupyterHub (``deploy/run_hub.py``) ends with one line, no traceback.

No Unix users: the hub runs as this account with JupyterHub's ``DummyAuthenticator``, Debian's
``configurable-http-proxy`` on free ports, and in one case a managed service that never answers
(``sleep``), the way the formgrader service keeps a first ``make hub`` waiting. SIGINT, what
Ctrl-C sends the hub, comes once the hub runs, or while it still waits for that service (before
JupyterHub installs its own handler). Oracles: the exit status, the last line of the output, no
``Traceback`` in it, and the proxy's and the service's processes gone afterwards.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from hubtools import ARTIFACTS, ENVS

import hub  # deploy/hub.py

pytestmark = [pytest.mark.xdist_group("hub"), pytest.mark.slow]

PROXY = Path("/usr/bin/configurable-http-proxy")
CONFIG = """
import os
c = get_config()  # noqa: F821
s = {k[len("T_"):]: v for k, v in os.environ.items() if k.startswith("T_")}
c.JupyterHub.ip = c.JupyterHub.hub_ip = "127.0.0.1"
c.JupyterHub.port, c.JupyterHub.hub_port = int(s["PORT"]), int(s["HUB_PORT"])
c.ConfigurableHTTPProxy.api_url = "http://127.0.0.1:" + s["API_PORT"]
c.ConfigurableHTTPProxy.command = [s["PROXY"]]
c.ConfigurableHTTPProxy.pid_file = os.path.join(s["DIR"], "proxy.pid")
c.JupyterHub.db_url = "sqlite:///" + os.path.join(s["DIR"], "jupyterhub.sqlite")
c.JupyterHub.cookie_secret_file = os.path.join(s["DIR"], "cookie_secret")
c.JupyterHub.authenticator_class = "dummy"
if s.get("SERVICE_PORT"):
    # answers never: the hub waits for it as for a slow formgrader service
    c.JupyterHub.services = [{
        "name": "slow", "url": "http://127.0.0.1:" + s["SERVICE_PORT"],
        "command": ["sh", "-c", "echo $$ > service.pid; exec sleep 600"], "cwd": s["DIR"]}]
"""


def _python_with_jupyterhub() -> Path:
    """A Python that imports JupyterHub: one of the hub test's cached environments, else a
    small venv of its own (Debian's Python and ``jupyterhub``, kept for the next runs)."""
    for env in (ENVS / "instructor", ENVS / "student", ARTIFACTS / "jupyterhub-only"):
        python = env / "bin" / "python"
        if python.exists() and subprocess.run([python, "-c", "import jupyterhub"],
                                              capture_output=True).returncode == 0:
            return python
    env = ARTIFACTS / "jupyterhub-only"
    hub.run([hub.SYSTEM_PYTHON, "-m", "venv", env], timeout=600)
    hub._pip(env, hub.JUPYTERHUB_REQUIREMENT)
    return env / "bin" / "python"


def _gone(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return True
    return state in ("Z", "X")   # a zombie has stopped; its reaper is not the hub


def _wait_for(pred, what: str, timeout: float = 60) -> None:
    deadline = time.monotonic() + timeout
    while not pred():
        if time.monotonic() > deadline:
            pytest.fail(f"timed out waiting for {what}")
        time.sleep(0.2)


@pytest.mark.parametrize("when", ["running", "waiting for a service"])
def test_ctrl_c_stops_the_hub_with_one_line_and_leaves_nothing_running(tmp_path, when):
    if sys.platform != "linux" or not PROXY.exists():
        pytest.skip(f"{PROXY} is missing (Debian's node-configurable-http-proxy; make hub-deps)")
    if subprocess.run([hub.SYSTEM_PYTHON, "-c", "import ensurepip, venv"],
                      capture_output=True).returncode != 0:
        pytest.skip("Debian's python3-venv is missing (make hub-deps)")
    python = _python_with_jupyterhub()
    (tmp_path / "config.py").write_text(CONFIG)
    env = {"PATH": "/usr/bin:/bin", "LANG": "C.UTF-8", "HOME": str(tmp_path),
           "NODE_PATH": "/usr/share/nodejs:/usr/lib/nodejs", "T_PROXY": str(PROXY),
           "T_DIR": str(tmp_path), **{f"T_{k}": str(hub.free_port())
                                      for k in ("PORT", "HUB_PORT", "API_PORT")}}
    slow = when != "running"
    if slow:
        env["T_SERVICE_PORT"] = str(hub.free_port())
    proc = subprocess.Popen([python, hub.DEPLOY / "run_hub.py", "-f", tmp_path / "config.py"],
                            env=env, cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    lines: list[str] = []
    reader = threading.Thread(target=lambda: lines.extend(proc.stdout), daemon=True)
    reader.start()
    started: list[int] = []         # the proxy's and the service's pids, ended here on failure
    try:
        ready = "Still waiting for service slow" if slow else "JupyterHub is now running"
        _wait_for(lambda: proc.poll() is not None or any(ready in x for x in lines), ready, 180)
        assert proc.poll() is None, "".join(lines)[-3000:]
        started.append(int((tmp_path / "proxy.pid").read_text()))
        if slow:
            started.append(int((tmp_path / "service.pid").read_text()))
        proc.send_signal(signal.SIGINT)
        returncode = proc.wait(timeout=120)
        reader.join(10)
        out = "".join(lines)
        assert returncode == 0, out[-3000:]
        assert "Traceback" not in out, out[-3000:]
        last = [x for x in out.splitlines() if x.strip()][-1]
        assert last.startswith("hub: stopped; `make hub` starts it again"), out[-3000:]
        for pid in started:
            _wait_for(lambda pid=pid: _gone(pid), f"process {pid} (proxy, service) to end", 30)
    finally:
        if proc.poll() is None:
            proc.kill()
        for pid in started:
            if not _gone(pid):
                os.kill(pid, signal.SIGKILL)
