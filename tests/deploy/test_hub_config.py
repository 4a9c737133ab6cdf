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

import pytest

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


def _service_args(cmd: list[str], s) -> list[str]:
    """The arguments of ``python -m autograder`` in the service's command line."""
    python = cmd.index(f"{s.paths['instructor_env']}/bin/python")
    assert cmd[python + 1:python + 3] == ["-m", "autograder"]
    return cmd[python + 3:]


def test_the_hub_runs_the_grading_service_as_root_with_the_graders_group(tmp_path, monkeypatch):
    """Root, because every sandbox job needs a uid and a cgroup of its own (the grader refuses
    to grade without them); the grader account's group, so what it writes stays the grader's."""
    s, services = _hub_config(tmp_path, monkeypatch, grading_jobs=3, grading_workers=2)
    watch = services[f"{s.course_id}-grading"]
    assert watch["user"] == "root" and "url" not in watch      # managed, no web page
    cmd = watch["command"]
    assert cmd[cmd.index(hub.SETPRIV) + 1] == f"--regid={s.grader}"
    assert f"HOME={hub.home_of(s.grader)}" in cmd              # the grader's course secret
    args = _service_args(cmd, s)
    assert args[0] == "watch"
    for flag, value in (("--exchange", s.paths["exchange"]), ("--course", s.paths["course_dir"]),
                        ("--jobs", "3"), ("--workers", "2")):
        assert args[args.index(flag) + 1] == value
    assert watch["environment"]["JUPYTER_CONFIG_PATH"] == s.paths["instructor_config"]
    # the formgrader service is still there beside it
    assert s.course_id in services
    # switched off in hub.json: no grading service
    _, services = _hub_config(tmp_path, monkeypatch, grading_service=False)
    assert f"{s.course_id}-grading" not in services


def _runnable_here(cmd: list[str], s) -> list[str]:
    """The service's command line with this Python in place of the instructors', and the
    group of root in place of the (absent) grader account's."""
    cmd = list(cmd)
    cmd[cmd.index(f"{s.paths['instructor_env']}/bin/python")] = sys.executable
    cmd[cmd.index(f"--regid={s.grader}")] = "--regid=0"
    return cmd


def test_the_grading_services_log_gets_its_output(tmp_path, monkeypatch):
    """The service's command line, run with this Python in place of the instructors': the
    shell makes the log's folder and the service's errors land in the log."""
    if os.geteuid() != 0:
        pytest.skip("the service's command runs as root (setpriv)")
    s, services = _hub_config(tmp_path, monkeypatch)
    cmd = _runnable_here(services[f"{s.course_id}-grading"]["command"], s)
    # the course folder and its log here, not in the (absent) grader's home
    course = tmp_path / "course"
    assert cmd[3] == str(Path(s.paths["course_dir"]) / "service" / "watch.log")
    cmd[3] = str(course / "service" / "watch.log")
    cmd[cmd.index("--course") + 1] = str(course)
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2 and proc.stdout == "" and proc.stderr == ""
    said = (course / "service" / "watch.log").read_text()
    assert "is not a folder (the exchange's inbound)" in said, said


#: a hostile graded function: 480 MB into /, /dev/shm and /dev, processes past the cap, its ids
HOSTILE_CELL = """
import errno, os, time
def caps(k):
    if k < 3:
        written = 0
        try:
            with open(["/big", "/dev/shm/big", "/dev/big"][k], "wb") as f:
                for _ in range(480):
                    f.write(bytes(2**20))
                    written += 1
        except OSError as exc:
            return written, errno.errorcode.get(exc.errno, "?")
        return written, "written"
    if k == 3:
        n = 0
        for _ in range(200):
            try:
                pid = os.fork()
            except OSError:
                break
            if pid == 0:
                time.sleep(60)
                os._exit(0)
            n += 1
        return n
    return os.getuid(), os.getgid()
"""

#: run in the grading service's place (its command line, ``-c`` for ``-m autograder watch``):
#: one job of the hostile cell, through the probe and ``run_notebook`` as the service runs
#: them, the job's cgroup files read back from the kernel as it is made
HOSTILE_JOB = """
import json, os, sys
from autograder.isolation import CaseInput, Limits, NameJob, NotebookJob, cgroup, probe, runner
from autograder.isolation import run_notebook

WANTED = {"memory.limit_in_bytes", "memory.max", "pids.max", "cpu.cfs_quota_us",
          "cpu.cfs_period_us", "cpu.max", "cpu.shares", "cpu.weight"}
seen = {}


class Spy(cgroup.JobCgroup):
    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        for d in self.dirs:
            for name in set(os.listdir(d)) & WANTED:
                with open(os.path.join(d, name)) as f:
                    seen[name] = f.read().strip()


runner.JobCgroup = Spy
limits = Limits(case_timeout=20.0)
job = NotebookJob("hub", "", [NameJob("caps", "function", [("c", sys.argv[1])],
                                      [CaseInput((k,), {}) for k in range(5)])])
run = run_notebook(job, limits, probe())["caps"]
print(json.dumps({"cgroup": seen, "memory": limits.memory_mb * 2**20, "pids": limits.pids,
                  "values": [o.value for o in run.outcomes],
                  "kinds": [o.kind.value for o in run.outcomes]}))
"""


def test_a_job_of_the_hubs_grading_service_is_capped(tmp_path, monkeypatch):
    """A hostile job run as the hub's grading service runs (its command line): its own uid,
    its own cgroup with the memory, process and CPU limits, ``/`` and ``/dev`` take no byte,
    and forks past the process cap fail."""
    from autograder.isolation import identity

    s, services = _hub_config(tmp_path, monkeypatch)
    watch = services[f"{s.course_id}-grading"]
    assert watch["user"] == "root"
    if os.geteuid() != 0:
        pytest.skip("the hub runs its grading service as root")
    cmd = _runnable_here(watch["command"], s)
    python = cmd.index(sys.executable)
    cmd = cmd[4:python + 1] + ["-c", HOSTILE_JOB, HOSTILE_CELL]   # no log file; the job
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600, cwd=hub.REPO,
                          env=dict(os.environ, PYTHONPATH=str(hub.REPO)))
    assert proc.returncode == 0, proc.stderr[-3000:]
    got = json.loads(proc.stdout.strip().splitlines()[-1])
    assert got["kinds"] == ["returned"] * 5, got
    for written, why in got["values"][:3]:
        assert written == 0 and why in ("EROFS", "EACCES"), got["values"]
    assert 0 < got["values"][3] < got["pids"]
    uid, gid = got["values"][4]
    assert uid == gid and identity.UID_BASE <= uid < identity.UID_BASE + identity.UID_COUNT
    cg = got["cgroup"]
    assert cg.get("memory.limit_in_bytes", cg.get("memory.max")) == str(got["memory"]), cg
    assert cg["pids.max"] == str(got["pids"])
    if "cpu.max" in cg:
        quota, period = cg["cpu.max"].split()
        assert cg["cpu.weight"] == "100"
    else:
        quota, period = cg["cpu.cfs_quota_us"], cg["cpu.cfs_period_us"]
        assert cg["cpu.shares"] == "1024"
    assert quota != "max" and 0 < int(quota) <= int(period)     # one CPU at most


def test_bad_grading_service_sizes_are_refused():
    for bad in ({"grading_jobs": 0}, {"grading_workers": "2"}):
        with pytest.raises(ValueError, match="at least 1"):
            hub.HubSettings(state="/nonexistent", grader="t4f9nobody", **bad)
