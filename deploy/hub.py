"""The 4F9 course on a one-machine JupyterHub: users, environments, exchange, course, hub.

Run as root, from the instructors' virtual environment (``make hub`` does both)::

    .venv/bin/python deploy/hub.py up                     # prepare everything, run the hub
    .venv/bin/python deploy/hub.py add-student crsid      # a Unix user in the students' group
    .venv/bin/python deploy/hub.py add-instructor crsid   # (asks for the password)

What ``up`` builds, under the state folder (default ``/srv/4f9-hub``, owned by root):

- ``envs/student``: the students' environment, a venv of Debian's ``/usr/bin/python3`` holding
  the students' compiled wheel alone (``autograder.student_bundle``) plus ``jupyterhub`` (for
  ``jupyterhub-singleuser``) and :mod:`private_exchange`; every user's server runs in it;
- ``envs/instructor``: the instructors' copy (this repository installed editable, with
  ``jupyterhub`` and :mod:`private_exchange`), readable by the instructors' group only; the hub,
  the formgrader and ``nbgrader collect`` use it;
- ``etc/student``, ``etc/instructor``: the Jupyter config folders of the two (nbgrader's course
  id and exchange, the private submit, the collect that checks owners, links and times, the
  formgrader's ``frame-ancestors`` and the course's guard on its buttons,
  :mod:`autograder.formgrader`);
- ``exchange/``: nbgrader's exchange, root-owned with the sticky bit (so no student can rename or
  remove the course's folder, nbgrader #1225), its ``inbound`` owned by the grader account,
  sticky (no student removes another's submission), readable by the instructors' group through a
  default ACL and by no student;
- ``hub/``: JupyterHub's database, cookie secret and proxy pid (root only, 0700);
- ``hub.json``: the settings ``deploy/jupyterhub_config.py`` reads.

Besides the formgrader, the hub runs the grading service (``python -m autograder watch``,
docs/grading-service.md) as a managed service, as root with the grader account's group
(:func:`grading_command`): every submission is graded as it arrives and its feedback page
handed back through nbgrader's exchange. Its log is
``<course>/service/watch.log``; ``grading_service``, ``grading_jobs`` and ``grading_workers`` in
``hub.json`` switch it off or size it (docs/deploying.md).

The hub itself runs as ``deploy/run_hub.py`` (JupyterHub, patient with the formgrader service,
ended by Ctrl-C with one line).

The course itself (``autograder``'s nbgrader course folder) lives in the grader account's home,
``/home/<grader>/course``, with ``exchange`` a link to the hub's exchange.
"""

from __future__ import annotations

import argparse
import dataclasses
import grp
import hashlib
import json
import os
import pwd
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

DEPLOY = Path(__file__).resolve().parent
REPO = DEPLOY.parent
SYSTEM_PYTHON = "/usr/bin/python3"
SETPRIV = "/usr/bin/setpriv"
#: the shell line that runs its arguments with ``umask 002`` (the grader account's group may
#: change what the command writes)
GROUP_WRITABLE = 'umask 002 && exec "$@"'
#: JupyterHub of the hub and of both environments (the singleuser must match the hub's major)
JUPYTERHUB_REQUIREMENT = "jupyterhub>=5,<6"


@dataclasses.dataclass
class HubSettings:
    """Names, ports and folders of one hub (written to ``<state>/hub.json``)."""

    state: str = "/srv/4f9-hub"
    ip: str = "127.0.0.1"
    port: int = 8000
    hub_port: int = 0
    proxy_api_port: int = 0
    service_port: int = 0
    course_id: str = "4f9"
    grader: str = "grader-4f9"
    students_group: str = "4f9-students"
    instructors_group: str = "4f9-instructors"
    proxy_command: str = "/usr/bin/configurable-http-proxy"
    #: where the two environments live (default ``<state>/envs``; the tests keep them cached)
    envs: str = ""
    #: the grading service (``python -m autograder watch``) as a hub-managed service of the
    #: grader account; its sandboxes at a time (``--jobs``) and submissions at once (``--workers``)
    grading_service: bool = True
    grading_jobs: int = 2
    grading_workers: int = 2

    def __post_init__(self):
        for name in ("hub_port", "proxy_api_port", "service_port"):
            if not getattr(self, name):
                setattr(self, name, free_port())
        for name in ("grader", "students_group", "instructors_group", "course_id"):
            if not getattr(self, name).replace("-", "").replace("_", "").isalnum():
                raise ValueError(f"{name} must be letters, digits, '-' or '_': {getattr(self, name)!r}")
        for name in ("grading_jobs", "grading_workers"):
            if not isinstance(getattr(self, name), int) or getattr(self, name) < 1:
                raise ValueError(f"{name} must be a whole number, at least 1: "
                                 f"{getattr(self, name)!r}")

    @property
    def paths(self) -> dict:
        state = Path(self.state)
        envs = Path(self.envs) if self.envs else state / "envs"
        return {"student_env": str(envs / "student"), "instructor_env": str(envs / "instructor"),
                "student_config": str(state / "etc" / "student"),
                "instructor_config": str(state / "etc" / "instructor"),
                "exchange": str(state / "exchange"), "hub_dir": str(state / "hub"),
                "course_dir": str(Path(home_of(self.grader)) / "course")}

    def as_json(self) -> dict:
        return {**dataclasses.asdict(self), **self.paths}


def free_port() -> int:
    """A TCP port free on localhost now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def home_of(user: str) -> str:
    """``user``'s home folder (``/home/<user>`` before the account exists)."""
    try:
        return pwd.getpwnam(user).pw_dir
    except KeyError:
        return f"/home/{user}"


def run(cmd: list[str], **kwargs) -> subprocess.CompletedProcess:
    """``cmd``, failing with its output's tail."""
    proc = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, **kwargs)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, cmd))} failed ({proc.returncode}):\n"
                           f"{proc.stdout[-2000:]}\n{proc.stderr[-3000:]}")
    return proc


# --- Unix accounts ----------------------------------------------------------------------------

def ensure_group(name: str) -> None:
    """The Unix group ``name`` (a system group) exists."""
    try:
        grp.getgrnam(name)
    except KeyError:
        run(["groupadd", "--system", name])


def ensure_user(name: str, groups: list[str], password: str | None = None) -> None:
    """A Unix user ``name`` with a private home (0700), in ``groups``, with ``password``."""
    if not name.replace("-", "").replace("_", "").isalnum():
        raise ValueError(f"user name must be letters, digits, '-' or '_': {name!r}")
    for group in groups:
        ensure_group(group)
    try:
        pwd.getpwnam(name)
    except KeyError:
        run(["useradd", "--create-home", "--user-group", "--shell", "/bin/bash", name])
    if groups:
        run(["usermod", "--append", "--groups", ",".join(groups), name])
    os.chmod(home_of(name), 0o700)
    if password is not None:
        run(["chpasswd"], input=f"{name}:{password}\n")


def as_user(user: str, cmd: list[str], env: dict | None = None, cwd: str | None = None,
            timeout: float = 900) -> subprocess.CompletedProcess:
    """``cmd`` run as ``user`` (``runuser``), with ``HOME`` and ``USER`` of that account."""
    home = home_of(user)
    full = {"HOME": home, "USER": user, "LOGNAME": user, "PATH": "/usr/bin:/bin",
            "LANG": "C.UTF-8", **(env or {})}
    return subprocess.run(["runuser", "-u", user, "--", "env", "-i",
                           *[f"{k}={v}" for k, v in full.items()], *map(str, cmd)],
                          capture_output=True, text=True, cwd=cwd or home, timeout=timeout,
                          check=False)


# --- the two environments ---------------------------------------------------------------------

def _pip(env_dir: Path, *args: str) -> None:
    run([env_dir / "bin" / "python", "-m", "pip", "install", "--quiet",
         "--disable-pip-version-check", *args], timeout=1800)


def _site_packages(env_dir: Path) -> Path:
    found = sorted(env_dir.glob("lib/python3*/site-packages"))
    if len(found) != 1:
        raise RuntimeError(f"no single site-packages in {env_dir}: {found}")
    return found[0]


def build_student_env(env_dir: Path, wheel_cache: Path) -> Path:
    """The students' environment: their wheel (built on first use), ``jupyterhub``, the submit.

    Built from Debian's Python, whose files every user may run (a ``pyenv`` Python under
    ``/root`` would not be). Returns the environment's folder.
    """
    from autograder import student_bundle

    wheel = student_bundle.build_wheel(wheel_cache)
    student_bundle.ensure_student_env(env_dir, wheel, base_python=SYSTEM_PYTHON)
    stamp = env_dir / ".hub-extras"
    if not stamp.exists() or stamp.read_text() != JUPYTERHUB_REQUIREMENT:
        _pip(env_dir, JUPYTERHUB_REQUIREMENT)
        stamp.write_text(JUPYTERHUB_REQUIREMENT)
    shutil.copyfile(DEPLOY / "private_exchange.py", _site_packages(env_dir) / "private_exchange.py")
    _no_news(env_dir)
    return env_dir


def _no_news(env_dir: Path) -> None:
    """No "get notified about Jupyter news?" pop-up in the environment's JupyterLab."""
    settings = env_dir / "share" / "jupyter" / "lab" / "settings"
    settings.mkdir(parents=True, exist_ok=True)
    (settings / "overrides.json").write_text(json.dumps(
        {"@jupyterlab/apputils-extension:notification": {"fetchNews": "false"}}) + "\n")


def _instructor_digest() -> str:
    return hashlib.sha256((REPO / "pyproject.toml").read_bytes()
                          + JUPYTERHUB_REQUIREMENT.encode()).hexdigest()


def build_instructor_env(env_dir: Path, group: str) -> Path:
    """The instructors' environment: this repository (editable) with ``jupyterhub`` and the
    collect class (:mod:`private_exchange`).

    Readable by root and ``group`` only (0750): it can import the references and the grader.
    """
    if not (env_dir / "bin" / "python").exists():
        run([SYSTEM_PYTHON, "-m", "venv", env_dir], timeout=600)
    stamp = env_dir / ".hub-instructor"
    if not stamp.exists() or stamp.read_text() != _instructor_digest():
        _pip(env_dir, "-e", f"{REPO}[hub]")
        stamp.write_text(_instructor_digest())
    shutil.copyfile(DEPLOY / "private_exchange.py", _site_packages(env_dir) / "private_exchange.py")
    _no_news(env_dir)
    shutil.chown(env_dir, "root", group)
    os.chmod(env_dir, 0o750)
    return env_dir


# --- configuration ----------------------------------------------------------------------------

def _nbgrader_config(s: HubSettings, extra: list[str]) -> str:
    return "\n".join(["c = get_config()  # noqa: F821", f"c.CourseDirectory.course_id = {s.course_id!r}",
                      f"c.Exchange.root = {s.paths['exchange']!r}", *extra]) + "\n"


def write_jupyter_configs(s: HubSettings) -> None:
    """``etc/student`` and ``etc/instructor``: nbgrader's settings for each side."""
    student = Path(s.paths["student_config"])
    instructor = Path(s.paths["instructor_config"])
    for folder in (student, instructor):
        folder.mkdir(parents=True, exist_ok=True)
        os.chmod(folder, 0o755)
    (student / "nbgrader_config.py").write_text(_nbgrader_config(s, [
        "# each submission readable by its author and the graders only (deploy/private_exchange.py)",
        "c.ExchangeFactory.submit = 'private_exchange.PrivateExchangeSubmit'"]))
    (instructor / "nbgrader_config.py").write_text(_nbgrader_config(s, [
        f"c.CourseDirectory.root = {s.paths['course_dir']!r}",
        "# only a student's own files, never a link, timed by the exchange (deploy/private_exchange.py)",
        "c.ExchangeFactory.collect = 'private_exchange.PrivateExchangeCollect'"]))
    # JupyterHub >= 4.1 forbids framing by default; the formgrader is an iframe of the lab
    (instructor / "jupyter_server_config.py").write_text(
        "c = get_config()  # noqa: F821\n"
        "c.ServerApp.tornado_settings = {'headers': "
        "{'Content-Security-Policy': \"frame-ancestors 'self'\"}}\n")
    # the Formgrader's buttons go through the course's guard (autograder/formgrader/), as in
    # `make instructor`: the same server-extension switch, read by Jupyter from JSON config
    from autograder.lab import server_config

    (instructor / "jupyter_server_config.json").write_text(
        json.dumps(server_config("instructor"), indent=1) + "\n")


def prepare_exchange(s: HubSettings) -> Path:
    """``exchange/`` root-owned 1777 (sticky), ``exchange/<course>`` owned by the grader."""
    root = Path(s.paths["exchange"])
    root.mkdir(parents=True, exist_ok=True)
    os.chown(root, 0, 0)
    os.chmod(root, 0o1777)
    course = root / s.course_id
    course.mkdir(exist_ok=True)
    shutil.chown(course, s.grader, s.instructors_group)
    os.chmod(course, 0o755)
    # the grader's, as nbgrader's release_feedback makes it, before the grading service (root)
    # puts a page there
    feedback = course / "feedback"
    feedback.mkdir(exist_ok=True)
    shutil.chown(feedback, s.grader, s.grader)
    os.chmod(feedback, 0o711)
    return root


def grader_env(s: HubSettings) -> dict:
    """Environment of the grader account's commands: the instructors' venv and config."""
    env_dir = s.paths["instructor_env"]
    return {"PATH": f"{env_dir}/bin:/usr/bin:/bin", "VIRTUAL_ENV": env_dir,
            "JUPYTER_CONFIG_PATH": s.paths["instructor_config"], "MPLBACKEND": "Agg"}


def as_grader(s: HubSettings, args: list[str], timeout: float = 900) -> subprocess.CompletedProcess:
    """``args`` run as the grader account, in the course folder; fails with the output's tail."""
    proc = as_user(s.grader, args, env=grader_env(s), cwd=s.paths["course_dir"], timeout=timeout)
    if proc.returncode != 0 or "[ERROR]" in proc.stderr:
        raise RuntimeError(f"{' '.join(map(str, args))} as {s.grader} failed:\n{proc.stderr[-4000:]}")
    return proc


def grading_command(s: HubSettings, args: list[str]) -> list[str]:
    """``python -m autograder ARGS`` from the instructors' environment as grading must run:
    as root (the caller's uid), because only root gives every sandbox job a uid and a cgroup of
    its own (memory, processes, one CPU), and ``grade`` and ``watch`` refuse to grade without
    both (docs/grading.md); with the grader account's group and ``umask 002``, so what it
    writes in the course folder (pages, its journal, grades) stays the grader account's to
    read and replace; and the grader's ``HOME``, so it reads the course secret the grader's
    commands read."""
    return [SETPRIV, f"--regid={s.grader}", "--clear-groups", "--",
            "/usr/bin/env", f"HOME={home_of(s.grader)}", "/bin/sh", "-c", GROUP_WRITABLE, "sh",
            f"{s.paths['instructor_env']}/bin/python", "-m", "autograder", *args]


def run_grading(s: HubSettings, args: list[str], timeout: float | None = None) -> int:
    """:func:`grading_command` of ``args`` in the course folder (as root), with the grader
    account's environment; its exit status (its output goes to ours)."""
    if os.geteuid() != 0:
        raise PermissionError("grading runs as root (every sandbox job gets a uid and a cgroup "
                              "of its own): run this with sudo")
    env = dict(grader_env(s), LANG="C.UTF-8")
    return subprocess.run(grading_command(s, args), cwd=s.paths["course_dir"], env=env,
                          timeout=timeout, check=False).returncode


def prepare_course(s: HubSettings) -> None:
    """The grader's nbgrader course, released to the hub's exchange (inbound: graders' group)."""
    course = Path(s.paths["course_dir"])
    if not course.exists():
        course.mkdir()
        shutil.chown(course, s.grader, s.grader)
    link = course / "exchange"
    if not link.is_symlink():
        if link.exists():
            raise RuntimeError(f"{link} exists and is not a link to the hub's exchange")
        link.symlink_to(s.paths["exchange"])
    from autograder.course import ASSIGNMENT

    python = Path(s.paths["instructor_env"]) / "bin" / "python"
    # the grading service (root) writes its journal and log here and reads the course secret:
    # both made by the grader account first, so they stay its own
    as_grader(s, ["mkdir", "-p", course / "service"])
    as_grader(s, [python, "-c", "from autograder.grade.secret import read_secret; "
                                "read_secret(None)"])
    as_grader(s, [python, "-m", "autograder", "release", "--course-root", course])
    as_grader(s, [python, "-m", "nbgrader", "release_assignment", ASSIGNMENT, "--force"])
    prepare_inbound(s)


def prepare_inbound(s: HubSettings) -> Path:
    """``exchange/<course>/inbound``: students may create a folder there, not list or remove
    one; whatever is made in it the graders' group may read."""
    inbound = Path(s.paths["exchange"]) / s.course_id / "inbound"
    inbound.mkdir(exist_ok=True)
    shutil.chown(inbound, s.grader, s.instructors_group)
    # drwx-wx-wt + setgid: submissions take the graders' group; the sticky bit keeps anyone
    # but a folder's owner (and the grader) from renaming or removing it
    os.chmod(inbound, 0o3733)
    # ... but nbgrader writes timestamp.txt after copytree has reset the submission folder's
    # mode (setgid gone), so that file keeps the student's group: a default ACL gives the graders
    # every file and folder made in the inbound, whatever its group; nothing for "other"
    run(["setfacl", "-d", "-m", f"u::rwx,g::---,o::---,g:{s.instructors_group}:rwX", inbound])
    return inbound


def write_settings(s: HubSettings) -> Path:
    """``<state>/hub.json`` and the folders only root may read (``hub/``)."""
    state = Path(s.state)
    state.mkdir(parents=True, exist_ok=True)
    os.chmod(state, 0o755)
    hub_dir = Path(s.paths["hub_dir"])
    hub_dir.mkdir(exist_ok=True)
    os.chmod(hub_dir, 0o700)
    path = state / "hub.json"
    path.write_text(json.dumps(s.as_json(), indent=1) + "\n")
    return path


def prepare(s: HubSettings, wheel_cache: Path) -> Path:
    """Everything but the hub process; returns the settings file."""
    if os.geteuid() != 0:
        raise PermissionError("the hub must be prepared as root (real users, setuid spawner)")
    for tool in (s.proxy_command, "/usr/bin/setfacl"):
        if not Path(tool).exists():
            raise FileNotFoundError(f"{tool} is missing: `make hub-deps` installs it")
    _step("users and groups")
    ensure_group(s.students_group)
    ensure_user(s.grader, [s.instructors_group])
    settings = write_settings(s)
    _step("the students' environment (the first time: the compiled wheel, about 5 minutes)")
    build_student_env(Path(s.paths["student_env"]), wheel_cache)
    _step("the instructors' environment (the first time: a few minutes)")
    build_instructor_env(Path(s.paths["instructor_env"]), s.instructors_group)
    write_jupyter_configs(s)
    _step("the exchange and the course (release and gradebook)")
    prepare_exchange(s)
    prepare_course(s)
    return settings


def _step(what: str) -> None:
    """A progress line: the first ``make hub`` takes about ten minutes."""
    print(f"hub: {time.strftime('%H:%M:%S')} {what}...", file=sys.stderr, flush=True)


def hub_command(s: HubSettings) -> tuple[list[str], dict]:
    """The command line and environment that run the hub (as root)."""
    env_dir = s.paths["instructor_env"]
    env = {"PATH": f"{env_dir}/bin:/usr/local/bin:/usr/bin:/bin", "LANG": "C.UTF-8",
           "COURSE_HUB_SETTINGS": str(Path(s.state) / "hub.json"),
           # Debian's configurable-http-proxy finds its modules here; Debian's nodejs looks
           # there by itself, a Node.js from elsewhere (nodesource) does not
           "NODE_PATH": "/usr/share/nodejs:/usr/lib/nodejs"}
    return [f"{env_dir}/bin/python", str(DEPLOY / "run_hub.py"), "-f",
            str(DEPLOY / "jupyterhub_config.py")], env


# --- command line -----------------------------------------------------------------------------

def _settings(args) -> HubSettings:
    saved = Path(args.state) / "hub.json"
    known = {f.name for f in dataclasses.fields(HubSettings)}
    values = {k: v for k, v in json.loads(saved.read_text()).items() if k in known} \
        if saved.exists() else {"state": args.state}
    if getattr(args, "port", None):
        values["port"] = args.port
    if getattr(args, "ip", None):
        values["ip"] = args.ip
    return HubSettings(**values)


def _warn_if_students_can_read_the_repository() -> None:
    """The instructors' environment imports this clone: model answers and hidden cases."""
    notebooks = REPO / "notebooks"
    if any(os.stat(p).st_mode & 0o004 for p in (REPO, notebooks)) and all(
            os.stat(p).st_mode & 0o001 for p in (REPO.parent, REPO)):
        print(f"warning: {REPO} is readable by every user, students included (model answers in "
              f"{notebooks}); see deploy/README.md, 'Keep the repository unreadable by students'",
              file=sys.stderr, flush=True)


def _up(args) -> int:
    s = _settings(args)
    _warn_if_students_can_read_the_repository()
    prepare(s, Path(args.wheel_cache))
    cmd, env = hub_command(s)
    print(f"\nThe course hub: http://{'localhost' if s.ip in ('127.0.0.1', '0.0.0.0') else s.ip}"
          f":{s.port}/  (formgrader: /services/{s.course_id}/)\n"
          f"As root (sudo from another account):\n"
          f"  add a student:     {sys.executable} {__file__} --state {s.state} add-student NAME\n"
          f"  add an instructor: {sys.executable} {__file__} --state {s.state} add-instructor NAME"
          " (then restart the hub)\n"
          f"  grade (as root):   {sys.executable} {__file__} --state {s.state} autograder grade "
          "submitted --out grading --jobs 2\nStop: Ctrl-C\n", flush=True)
    os.chdir(s.paths["hub_dir"])
    os.execve(cmd[0], cmd, env)
    return 0


def _add(args, group_attr: str) -> int:
    s = _settings(args)
    password = args.password
    if password is None:
        import getpass

        password = getpass.getpass(f"password for {args.name}: ")
        if password != getpass.getpass("again: "):
            raise SystemExit("the two passwords differ")
    ensure_user(args.name, [getattr(s, group_attr)], password)
    print(f"{args.name} can log in at http://localhost:{s.port}/", flush=True)
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--state", default=HubSettings.state, help="the hub's folder (root's)")
    sub = parser.add_subparsers(dest="command", required=True)
    up = sub.add_parser("up", help="prepare users, environments, exchange and course; run the hub")
    up.add_argument("--port", type=int, help="the public port (default 8000)")
    up.add_argument("--ip", help="the address to listen on (default 127.0.0.1)")
    up.add_argument("--wheel-cache", default=str(REPO / "course" / ".student-build"))
    for role in ("student", "instructor"):
        p = sub.add_parser(f"add-{role}", help=f"a Unix user in the {role}s' group")
        p.add_argument("name")
        p.add_argument("password", nargs="?",
                       help="asked for when omitted (a password on the command line shows in ps)")
    grading = sub.add_parser("autograder", help="python -m autograder ARGS as grading runs "
                             "(as root, the grader account's group, in the course folder)")
    grading.add_argument("args", nargs=argparse.REMAINDER)
    args = parser.parse_args(argv)
    try:
        if args.command == "up":
            return _up(args)
        if args.command == "autograder":
            return run_grading(_settings(args), args.args)
        return _add(args, "students_group" if args.command == "add-student"
                    else "instructors_group")
    except KeyboardInterrupt:
        # Ctrl-C while preparing: a line, not a traceback (running `up` again resumes)
        print("\nhub: stopped (Ctrl-C); run the same command again to resume", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
