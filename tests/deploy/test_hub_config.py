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
