"""``python -m autograder lab``: JupyterLab on the student or the instructor view of the course.

``--role student`` (``make lab``)
    releases the assignment through nbgrader (``course/release/tripos2006/``, solutions stubbed)
    and opens JupyterLab on ``course/release/`` with the assignment folder open. With
    ``--student-env DIR`` (``make lab`` passes ``.venv-student``) JupyterLab and the kernels run
    in that environment of their own, holding the students' wheel and nothing of this
    repository (:mod:`autograder.student_bundle`; built and installed when the sources change),
    so the view is exactly what students get. When that wheel still has to be built (a fresh
    clone, a changed module), JupyterLab opens at once in the environment holding the wheel's
    requirements but no ``course_lib`` at all, and the wheel is installed there when it is built
    (:class:`WheelInstall`, which says so): the first notebook shows within the time of a
    release and an install of the requirements, and the kernel never sees anything a student
    could not have, not even briefly. Without it the instructors' environment serves
    the release, a quick preview in which ``course_lib`` sources stay readable. The nbgrader
    "Create Assignment", "Formgrader" and "Course List" plugins are disabled for this launch (and
    the formgrader / course-list server extensions with them); the "Validate" button and the
    "Assignments" panel stay.
``--role instructor`` (``make instructor``)
    opens JupyterLab on the nbgrader course root ``course/`` (``source/tripos2006/`` holds the
    instructor's notebooks with solutions and hidden tests; ``nbgrader_config.py`` and the
    gradebook sit beside it), with every nbgrader plugin enabled, the formgrader included.

Extensions are switched per launch, not by editing anyone's installation: the launcher writes a
throw-away Jupyter config directory (``labconfig/page_config.json`` with ``disabledExtensions``,
the documented JupyterLab mechanism behind ``jupyter labextension disable``;
``jupyter_server_config.json`` for server extensions; a student ``nbgrader_config.py``) and puts
it first on ``JUPYTER_CONFIG_PATH`` for the server it starts. A user-level ``~/.jupyter`` still
takes precedence, as Jupyter's config path always gives it.

The server listens on 127.0.0.1 with a random token unless ``--ip`` / ``--token`` say otherwise;
the URL to open is printed.
"""

from __future__ import annotations

import argparse
import json
import os
import secrets
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from .course import (
    ASSIGNMENT,
    DEFAULT_COURSE_ROOT,
    nbgrader_env,
    prepare_course,
    student_config_text,
)
from .formgrader import EXTENSION as FORMGRADER_GUARD
from .student_bundle import (
    STUDENT_DISABLED_PLUGINS,
    STUDENT_DISABLED_SERVER_EXTENSIONS,
    build_wheel,
    cached_wheel,
    default_build_cache,
    ensure_student_env,
    ensure_student_requirements,
    student_env_vars,
)

#: JupyterLab 4 plugin ids of nbgrader 0.9 (``@jupyter/nbgrader`` since 0.9.3).
NBGRADER_PLUGINS = (
    "@jupyter/nbgrader:formgrader",
    "@jupyter/nbgrader:create-assignment",
    "@jupyter/nbgrader:course-list",
    "@jupyter/nbgrader:assignment-list",
    "@jupyter/nbgrader:validate-assignment",
)
# What a student must not have (STUDENT_DISABLED_PLUGINS, STUDENT_DISABLED_SERVER_EXTENSIONS)
# is defined beside the students' wheel, which switches the same things off where it is installed.
ROLES = ("student", "instructor")
#: JupyterLab's news/announcements plugin, off in both views.
NEWS_PLUGIN = "@jupyterlab/apputils-extension:announcements"


def page_config(role: str) -> dict:
    """The ``labconfig/page_config.json`` of a launch: ``{"disabledExtensions": {id: bool}}``."""
    if role not in ROLES:
        raise ValueError(f"role must be one of {ROLES}, not {role!r}")
    disabled = STUDENT_DISABLED_PLUGINS if role == "student" else ()
    config = {p: (p in disabled) for p in NBGRADER_PLUGINS}
    # no "get notified about Jupyter news?" pop-up over the course (it also calls out to the net)
    config[NEWS_PLUGIN] = True
    return {"disabledExtensions": config}


def server_config(role: str) -> dict:
    """The ``jupyter_server_config.json`` of a launch (server extensions on or off)."""
    if role == "instructor":
        # the Formgrader's buttons go through the course's guard (autograder/formgrader/)
        return {"ServerApp": {"jpserver_extensions": {FORMGRADER_GUARD: True}}}
    off = {ext: False for ext in STUDENT_DISABLED_SERVER_EXTENSIONS}
    return {"ServerApp": {"jpserver_extensions": off}}


def write_launch_config(config_dir: Path, role: str, course_root: Path) -> Path:
    """Fill ``config_dir`` with the per-launch Jupyter configuration for ``role``."""
    config_dir = Path(config_dir)
    (config_dir / "labconfig").mkdir(parents=True, exist_ok=True)
    (config_dir / "labconfig" / "page_config.json").write_text(
        json.dumps(page_config(role), indent=1))
    (config_dir / "jupyter_server_config.json").write_text(
        json.dumps(server_config(role), indent=1))
    if role == "student":
        # the Assignments panel reads nbgrader config from the Jupyter config path: point it at
        # the course's local exchange instead of /srv/nbgrader/exchange
        (config_dir / "nbgrader_config.py").write_text(
            student_config_text(Path(course_root) / "exchange"))
    return config_dir


def lab_command(
    role: str, root_dir: Path, port: int, ip: str, token: str, open_browser: bool, default_url: str,
    python: str | Path | None = None,
) -> list[str]:
    """The ``python -m jupyterlab ...`` command line of a launch (``python``: default this one)."""
    return [
        str(python or sys.executable), "-m", "jupyterlab",
        f"--ServerApp.root_dir={root_dir}",
        f"--ServerApp.ip={ip}",
        f"--ServerApp.port={port}",
        "--ServerApp.port_retries=0",
        f"--IdentityProvider.token={token}",
        f"--ServerApp.open_browser={open_browser}",
        f"--LabApp.default_url={default_url}",
        # Jupyter refuses to start as root without this (containers, CI); say it explicitly
        *(["--ServerApp.allow_root=True"] if hasattr(os, "geteuid") and os.geteuid() == 0 else []),
    ]


def launch(
    role: str,
    course_root: Path = DEFAULT_COURSE_ROOT,
    port: int = 8888,
    ip: str = "127.0.0.1",
    token: str | None = None,
    open_browser: bool = True,
    config_dir: Path | None = None,
    stdout=None,
    stderr=None,
    student_env: Path | None = None,
    build_cache: Path | None = None,
) -> tuple[subprocess.Popen, str]:
    """Prepare the course, start JupyterLab for ``role`` and return ``(process, url)``.

    ``config_dir`` is the per-launch Jupyter config directory (the caller owns it).
    ``student_env`` (student role only): run JupyterLab in that virtual environment, made or
    refreshed with the students' wheel (compiled into ``build_cache``, default
    ``<course_root>/.student-build``).
    """
    if role not in ROLES:
        raise ValueError(f"role must be one of {ROLES}, not {role!r}")
    if config_dir is None:
        raise ValueError("launch() needs a config_dir for the per-launch Jupyter config")
    course = prepare_course(Path(course_root))
    if role == "student":
        root_dir, default_url = course.release_dir.parent, f"/lab/tree/{ASSIGNMENT}"
    else:
        root_dir, default_url = course.root, "/lab"
    token = secrets.token_hex(24) if token is None else token
    write_launch_config(config_dir, role, course.root)
    python, env, pending = launch_environment(role, course.root, student_env, build_cache)
    # the kernels must pick their backend as in any JupyterLab (inline, or a student's own
    # ``%matplotlib widget``): the Agg that ``make`` and the test runs export would hide figures
    env.pop("MPLBACKEND", None)
    env["JUPYTER_CONFIG_PATH"] = os.pathsep.join(
        [str(config_dir), *[p for p in env.get("JUPYTER_CONFIG_PATH", "").split(os.pathsep) if p]]
    )
    cmd = lab_command(role, root_dir, port, ip, token, open_browser, default_url, python)
    proc = subprocess.Popen(cmd, cwd=root_dir, env=env, stdout=stdout, stderr=stderr)
    host = "localhost" if ip in ("127.0.0.1", "localhost", "") else ip
    url = f"http://{host}:{port}{default_url}" + (f"?token={token}" if token else "")
    if pending is not None:
        pending.start()
    return proc, url


def launch_environment(
    role: str, course_root: Path, student_env: Path | None, build_cache: Path | None
) -> tuple[Path | None, dict, WheelInstall | None]:
    """``(python, environment variables, pending)`` of the JupyterLab a launch starts.

    ``python`` is ``None`` for this interpreter (the instructors' environment). When the
    students' wheel of the current sources is not built yet, the environment is opened with
    its requirements alone (no ``course_lib``: nothing a student could not have) and
    ``pending`` is the :class:`WheelInstall` that builds the wheel and installs it there once
    the server is up (a fresh clone compiles every module: minutes); otherwise ``None``.
    """
    if student_env is None:
        return None, nbgrader_env(), None
    if role != "student":
        raise ValueError("student_env is for role 'student' only")
    cache = build_cache or default_build_cache(course_root)
    wheel = cached_wheel(cache)
    pending = None
    if wheel is not None:
        python = ensure_student_env(Path(student_env), wheel)
    else:
        python = ensure_student_requirements(Path(student_env))
        pending = WheelInstall(cache, Path(student_env))
    env = student_env_vars(Path(student_env))
    env.setdefault("PYTHONIOENCODING", "utf-8")
    return python, env, pending


class WheelInstall(threading.Thread):
    """Builds the students' wheel into ``cache`` and installs it into the students'
    environment ``env_dir`` behind a running JupyterLab, saying what it waits for and when
    ``course_lib`` can be imported (a kernel started before then has none: run the setup cell
    again). ``error`` holds what stopped it, if anything."""

    def __init__(self, cache: Path, env_dir: Path):
        super().__init__(name="4f9-student-wheel", daemon=True)
        self.cache, self.env_dir, self.error = Path(cache), Path(env_dir), None

    def run(self):
        print(WAITING, file=sys.stderr, flush=True)
        try:
            ensure_student_env(self.env_dir, build_wheel(self.cache))
        except (OSError, RuntimeError, ValueError, subprocess.SubprocessError) as exc:
            self.error = exc
            print(f"error: the students' wheel could not be built or installed: {exc}",
                  file=sys.stderr, flush=True)
            return
        print(READY, file=sys.stderr, flush=True)


#: what the student lab says while the wheel is built behind it, and once it is installed
WAITING = ("4F9: waiting for the students' wheel: compiling course_lib's modules (on a fresh "
           "clone all of them, a few minutes). The notebooks are open meanwhile; their setup "
           "cell says 'No module named course_lib' until the next line says ready.")
READY = ("4F9: ready: the students' wheel is installed; run each open notebook's setup cell "
         "again (Kernel > Restart Kernel if it had failed).")


def wait_until_listening(proc: subprocess.Popen, ip: str, port: int, timeout: float = 600,
                         poll: float = 0.25) -> bool:
    """Wait until the server accepts connections on ``(ip, port)``: True; False when the
    process ended first or ``timeout`` seconds passed (the URL is printed only once it works)."""
    host = "127.0.0.1" if ip in ("", "0.0.0.0", "localhost") else ("::1" if ip == "::" else ip)
    deadline = time.monotonic() + timeout
    while proc.poll() is None and time.monotonic() < deadline:
        try:
            with socket.create_connection((host, port), timeout=2):
                return True
        except OSError:
            time.sleep(poll)
    return False


def _interrupt(signum, frame):
    raise KeyboardInterrupt


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.description = "Open JupyterLab on the student or the instructor view of the course."
    parser.add_argument("--role", choices=ROLES, default="student",
                        help="student: released notebooks; instructor: the nbgrader course root")
    parser.add_argument("--port", type=int, default=8888)
    parser.add_argument("--ip", default="127.0.0.1",
                        help="interface to listen on (default: localhost only)")
    parser.add_argument("--token", default=None,
                        help="access token (default: a random one; '' disables it, only do that "
                             "behind another authentication)")
    parser.add_argument("--no-browser", action="store_true", help="do not open a browser")
    parser.add_argument("--course-root", type=Path, default=DEFAULT_COURSE_ROOT,
                        help=f"nbgrader course root (default: {DEFAULT_COURSE_ROOT})")
    parser.add_argument("--student-env", type=Path, default=None,
                        help="student role: run JupyterLab in this virtual environment holding "
                             "the students' wheel only (made or refreshed as needed; make lab "
                             "passes .venv-student); default: this environment, a preview in "
                             "which the course_lib sources are readable")
    parser.add_argument("--build-cache", type=Path, default=None,
                        help="folder keeping compiled student wheels "
                             "(default: COURSE_ROOT/.student-build)")


def main(args: argparse.Namespace) -> int:
    with tempfile.TemporaryDirectory(prefix=f"4f9-lab-{args.role}-") as tmp:
        print(f"4F9: preparing {args.course_root} (a release when the notebooks changed)...",
              file=sys.stderr, flush=True)
        try:
            proc, url = launch(
                args.role, args.course_root, port=args.port, ip=args.ip, token=args.token,
                open_browser=not args.no_browser, config_dir=Path(tmp),
                student_env=args.student_env, build_cache=args.build_cache,
            )
        except (FileNotFoundError, ValueError, RuntimeError, subprocess.CalledProcessError) as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 1
        view = ("student view: the released notebooks (solutions stubbed)" if args.role == "student"
                else "instructor view: the nbgrader course root with the formgrader")
        if args.role == "student" and args.student_env is None:
            view += ("\n  (preview in the instructors' environment: course_lib sources are "
                     "readable here; `make lab` opens the students' own environment)")
        # one Ctrl-C (or a SIGTERM to this launcher) stops JupyterLab without its y/n prompt
        signal.signal(signal.SIGTERM, _interrupt)
        try:
            print(f"4F9: starting JupyterLab on port {args.port}...", file=sys.stderr, flush=True)
            if wait_until_listening(proc, args.ip, args.port):
                print(f"\n4F9 {view}\n  {url}\n", flush=True)
            elif proc.poll() is None:
                print(f"warning: JupyterLab does not answer on port {args.port} yet; try\n"
                      f"  {url}", file=sys.stderr, flush=True)
            return proc.wait()
        except KeyboardInterrupt:
            proc.terminate()
            try:
                return proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                proc.kill()
                return proc.wait()
