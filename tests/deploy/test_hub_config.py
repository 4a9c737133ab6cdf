"""The hub's Jupyter config folders (``deploy/hub.py``), read back by Jupyter's own tools.

No Unix users, no hub: ``write_jupyter_configs`` only writes files. The oracle is
jupyter_server's own ``ServerApp.find_server_extensions``, run with the config folder on
``JUPYTER_CONFIG_PATH`` as the formgrader service runs, and the extension loader's check that
each extension switched on imports.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import hubtools  # noqa: F401  (puts deploy/ on sys.path)

import hub  # deploy/hub.py

GUARD = "autograder.formgrader"


#: what a Jupyter server finds switched on in its config path, and whether each imports
FIND = """
import json
from jupyter_server.extension.manager import ExtensionPackage
from jupyter_server.serverapp import ServerApp
app = ServerApp()
app.find_server_extensions()
print(json.dumps({name: on and ExtensionPackage(name=name, enabled=True).validate()
                  for name, on in app.jpserver_extensions.items()}))
"""


def _server_extensions(config_dir: str) -> dict:
    """``{module: True}`` for each server extension a Jupyter server started with
    ``JUPYTER_CONFIG_PATH=config_dir`` switches on and can load."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("JUPYTER")}
    env.update(JUPYTER_CONFIG_PATH=config_dir, HOME=config_dir)  # no ~/.jupyter of the tester
    proc = subprocess.run([sys.executable, "-c", FIND], capture_output=True, text=True, env=env,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_the_formgrader_service_loads_the_courses_guard(tmp_path):
    settings = hub.HubSettings(state=str(tmp_path / "state"), grader="t4f9nobody")
    hub.write_jupyter_configs(settings)
    instructor = _server_extensions(settings.paths["instructor_config"])
    assert instructor.get(GUARD) is True, instructor
    # nbgrader's formgrader, whose API the guard answers in front of, stays on beside it
    assert instructor.get("nbgrader.server_extensions.formgrader") is True, instructor
    # the students' servers never get it (their environment does not hold autograder)
    student = Path(settings.paths["student_config"])
    assert GUARD not in "".join(p.read_text() for p in student.iterdir())
    # the frame-ancestors header the Formgrader's iframe needs is still written beside it
    assert "frame-ancestors" in (Path(settings.paths["instructor_config"])
                                 / "jupyter_server_config.py").read_text()


def _hub_config(tmp_path, monkeypatch, **settings) -> dict:
    """``deploy/jupyterhub_config.py`` as JupyterHub loads it, for a hub.json of ``settings``."""
    from traitlets.config.loader import PyFileConfigLoader

    s = hub.HubSettings(state=str(tmp_path / "state"), grader="t4f9nobody", **settings)
    path = tmp_path / "hub.json"
    path.write_text(json.dumps(s.as_json()))
    monkeypatch.setenv("COURSE_HUB_SETTINGS", str(path))
    config = PyFileConfigLoader("jupyterhub_config.py", path=str(hub.DEPLOY)).load_config()
    return s, {svc["name"]: svc for svc in config.JupyterHub.services}


def test_the_hub_runs_the_grading_service_as_the_grader(tmp_path, monkeypatch):
    s, services = _hub_config(tmp_path, monkeypatch, grading_jobs=3, grading_workers=2)
    watch = services[f"{s.course_id}-grading"]
    assert watch["user"] == s.grader and "url" not in watch      # managed, no web page
    cmd = watch["command"]
    python = cmd.index(f"{s.paths['instructor_env']}/bin/python")
    args = cmd[python + 1:]
    assert args[:3] == ["-m", "autograder", "watch"]
    for flag, value in (("--exchange", s.paths["exchange"]), ("--course", s.paths["course_dir"]),
                        ("--jobs", "3"), ("--workers", "2")):
        assert args[args.index(flag) + 1] == value
    assert watch["environment"]["JUPYTER_CONFIG_PATH"] == s.paths["instructor_config"]
    # the formgrader service is still there beside it
    assert s.course_id in services
    # switched off in hub.json: no grading service
    _, services = _hub_config(tmp_path, monkeypatch, grading_service=False)
    assert f"{s.course_id}-grading" not in services


def test_the_grading_services_log_gets_its_output(tmp_path, monkeypatch):
    """The service's command line, run with this Python in place of the instructors': the
    shell makes the log's folder and the service's errors land in the log."""
    s, services = _hub_config(tmp_path, monkeypatch)
    cmd = list(services[f"{s.course_id}-grading"]["command"])
    cmd[cmd.index(f"{s.paths['instructor_env']}/bin/python")] = sys.executable
    # the course folder and its log here, not in the (absent) grader's home
    course = tmp_path / "course"
    assert cmd[3] == str(Path(s.paths["course_dir"]) / "service" / "watch.log")
    cmd[3] = str(course / "service" / "watch.log")
    cmd[cmd.index("--course") + 1] = str(course)
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2 and proc.stdout == "" and proc.stderr == ""
    said = (course / "service" / "watch.log").read_text()
    assert "is not a folder (the exchange's inbound)" in said, said


def test_bad_grading_service_sizes_are_refused():
    import pytest

    for bad in ({"grading_jobs": 0}, {"grading_workers": "2"}):
        with pytest.raises(ValueError, match="at least 1"):
            hub.HubSettings(state="/nonexistent", grader="t4f9nobody", **bad)
