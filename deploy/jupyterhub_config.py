"""JupyterHub configuration of the 4F9 course on one machine (read by ``jupyterhub -f``).

Every path, port and name comes from the settings file ``deploy/hub.py`` writes
(``$COURSE_HUB_SETTINGS``, ``<state>/hub.json``), so this file never needs editing. The layout
follows nbgrader's ``demos/demo_one_class_multiple_graders``: real Unix users, the default
``LocalProcessSpawner``, the formgrader as a hub service named after the course, run as the
course's grader account and reachable by the group ``formgrade-<course>``; and the grading
service (``python -m autograder watch``, feedback on every submission) as a second managed service,
which the hub starts, restarts when it exits, and stops with itself. The grading service runs as
root, with the grader account's group (``hub.grading_command``): only root gives every sandbox
job a uid and a cgroup of its own, and the grader refuses to grade without them.
"""

import grp
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import hub  # noqa: E402  (deploy/hub.py: the command grading runs as)

c = get_config()  # noqa: F821

S = json.load(open(os.environ["COURSE_HUB_SETTINGS"]))
COURSE = S["course_id"]


def _members(group):
    try:
        return sorted(grp.getgrnam(group).gr_mem)
    except KeyError:
        return []


def _env(env_dir, config_dir):
    """A server's environment: its venv first on PATH, its Jupyter config, nothing else's."""
    return {"PATH": f"{env_dir}/bin:/usr/local/bin:/usr/bin:/bin", "VIRTUAL_ENV": env_dir,
            "JUPYTER_CONFIG_PATH": config_dir}  # no MPLBACKEND: figures show inline


# --- the hub, the proxy, their state ---------------------------------------------------------
c.JupyterHub.ip = S["ip"]
c.JupyterHub.port = S["port"]
c.JupyterHub.hub_ip = "127.0.0.1"
c.JupyterHub.hub_port = S["hub_port"]
c.ConfigurableHTTPProxy.api_url = f"http://127.0.0.1:{S['proxy_api_port']}"
c.ConfigurableHTTPProxy.command = [S["proxy_command"]]
c.ConfigurableHTTPProxy.pid_file = os.path.join(S["hub_dir"], "proxy.pid")
c.JupyterHub.db_url = f"sqlite:///{S['hub_dir']}/jupyterhub.sqlite"
c.JupyterHub.cookie_secret_file = os.path.join(S["hub_dir"], "jupyterhub_cookie_secret")
c.JupyterHub.cleanup_servers = True

# --- who may log in: the course's Unix groups, checked by PAM ----------------------------------
c.JupyterHub.authenticator_class = "pam"
c.PAMAuthenticator.allowed_groups = {S["students_group"], S["instructors_group"]}
c.PAMAuthenticator.open_sessions = False  # no login session per server (containers lack one)

# --- every user's own server: the students' environment (their wheel alone) --------------------
c.Spawner.cmd = [os.path.join(S["student_env"], "bin", "jupyterhub-singleuser")]
c.Spawner.args = ["--LabApp.news_url=None"]
c.Spawner.default_url = "/lab"
c.Spawner.env_keep = ["LANG", "LC_ALL"]
c.Spawner.environment = _env(S["student_env"], S["student_config"])
c.Spawner.start_timeout = 180
c.Spawner.http_timeout = 180

# --- the formgrader: a service run as the grader account, for the instructors' group ----------
c.JupyterHub.load_groups = {f"formgrade-{COURSE}": {"users": _members(S["instructors_group"])}}
c.JupyterHub.load_roles = [
    {"name": f"formgrade-{COURSE}", "groups": [f"formgrade-{COURSE}"],
     "scopes": [f"access:services!service={COURSE}", "list:services",
                f"read:services!service={COURSE}"]},
]
c.JupyterHub.services = [{
    "name": COURSE,
    "url": f"http://127.0.0.1:{S['service_port']}",
    "command": [os.path.join(S["instructor_env"], "bin", "jupyterhub-singleuser"),
                f"--ServerApp.root_dir={S['course_dir']}", "--LabApp.news_url=None"],
    "user": S["grader"],
    "cwd": S["course_dir"],
    "environment": dict(_env(S["instructor_env"], S["instructor_config"]),
                        JUPYTERHUB_DEFAULT_URL="/lab", MPLBACKEND="Agg"),
    "oauth_no_confirm": True,
}]

# --- the grading service: every submission graded as it arrives, feedback at once -------------
# (docs/grading-service.md); a managed service with no URL: the hub (root) starts it as root,
# starts it again whenever it exits, and stops it with itself. Root, because every sandbox job
# needs a uid and a cgroup of its own (memory, processes, one CPU: docs/deploying.md), with the
# grader account's group and umask 002 so what it writes stays the grader's. Its own log file,
# so its lines (one per submission) are not lost among the hub's.
if S.get("grading_service", True):
    WATCH_LOG = os.path.join(S["course_dir"], "service", "watch.log")
    SETTINGS = hub.HubSettings(**{k: S[k] for k in hub.HubSettings.__dataclass_fields__
                                  if k in S})
    c.JupyterHub.services.append({
        "name": f"{COURSE}-grading",
        "command": ["/bin/sh", "-c", 'mkdir -p "${0%/*}" && exec "$@" >>"$0" 2>&1', WATCH_LOG,
                    *hub.grading_command(SETTINGS, [
                        "watch", "--exchange", S["exchange"], "--course", S["course_dir"],
                        "--jobs", str(S.get("grading_jobs", 2)),
                        "--workers", str(S.get("grading_workers", 2))])],
        "user": "root",
        "cwd": S["course_dir"],
        "environment": dict(_env(S["instructor_env"], S["instructor_config"]),
                            MPLBACKEND="Agg", PYTHONUNBUFFERED="1"),
    })
