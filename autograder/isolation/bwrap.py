"""How the sandbox is made: the probe, the modes, and the bubblewrap command line.

The sandbox is bubblewrap (``bwrap``): its own mount, PID, network, IPC and UTS namespaces, a
read-only filesystem holding only ``/usr``, the base interpreter, NumPy and the allow-listed
``course_lib`` tables, a private size-limited tmpfs ``/tmp``, its own ``/proc`` (read-only: a
write to ``/proc/self/mem`` ignores page protections, so it could patch the interpreter's
code) and a minimal ``/dev``. The only mount the job can write is ``/tmp``, of the job's scratch
size, and ``noexec`` (bubblewrap cannot mount its tmpfs so, so a first shell inside remounts
``/tmp`` before dropping its capabilities); ``/`` and ``/dev`` are bubblewrap's tmpfs mounts,
remounted read-only, so nothing is stored in memory beyond the scratch.

Grading needs root (:func:`probe` refuses otherwise): the child then becomes a uid of its own
with ``setpriv`` (:mod:`.identity`; no groups, no capabilities, ``no_new_privs``), and the job
runs in a cgroup of its own (:mod:`.cgroup`: memory, processes, one CPU). Without root neither
exists: an unprivileged user namespace maps every job to the same host uid, and no cgroup
would cap the job's memory, processes or CPU. Inside, the worker that runs student code adds a
seccomp filter (:mod:`.seccomp`; no new executable memory, no ``execve``, no new namespaces).
"""

from __future__ import annotations

import enum
import functools
import os
import shutil
import subprocess
import sys
import sysconfig

from . import cgroup, seccomp
from .allowlist import NUMBERS_VARIABLE

BWRAP = "/usr/bin/bwrap"
SETPRIV = "/usr/bin/setpriv"
SITE = "/sandbox/site"          #: where NumPy and the allow-listed tables appear inside
PROGRAM = "/sandbox/inside"     #: where the sandbox program's folder appears inside
CHILD = PROGRAM + "/__main__.py"  #: the child program started inside
JOB = "/job"                    #: where the job file appears inside
#: Run first inside the sandbox (as root, before the uid changes): the private network
#: namespace's loopback goes down too, so the sandbox has no working interface at all.
LOOPBACK_DOWN = 'if [ -x /usr/bin/ip ]; then /usr/bin/ip link set lo down || exit 125; fi; '
#: Then the one mount the job can write, ``/tmp``, becomes ``noexec`` (bubblewrap makes its
#: tmpfs without; ``/`` and ``/dev`` are bubblewrap's too, but root's and mode 0755).
NOEXEC = '/usr/bin/mount -o remount,noexec,nosuid,nodev /tmp || exit 125; exec "$@"'
#: Last of the mounts: bubblewrap's own tmpfs mounts ``/`` (the mount points) and ``/dev`` (its
#: ``shm`` folder included) become read-only, so the job stores nothing in memory outside its
#: scratch. Device nodes stay usable (``/dev/null`` is a bind mount of its own).
READ_ONLY_TMPFS = ["--remount-ro", "/", "--remount-ro", "/dev"]
INSTALL_HINT = "install it with `apt-get install bubblewrap` (or `make sandbox-deps`)"

#: What an instructor loses with ``--unsafe-no-isolation`` (printed by the caller).
UNSAFE_WARNING = (
    "WARNING: --unsafe-no-isolation: students' code will run WITHOUT the operating-system "
    "sandbox, as your own user, with your files and your network. It can read the course's "
    "model answers, keys and other students' submissions, change or delete any file you can, "
    "open network connections, and leave processes running. Grades from such a run cannot be "
    "trusted. Use it only to debug the grader on code you trust.")


class IsolationUnavailable(RuntimeError):
    """The operating-system sandbox cannot be made here (the message says what to install)."""


class IsolationError(RuntimeError):
    """The sandbox failed for a reason that is not the student's (bwrap refused to start)."""


class Mode(enum.Enum):
    """How jobs run: ``ISOLATED`` (bubblewrap) or ``UNSAFE`` (the same child, no sandbox; only
    with the instructor's explicit ``--unsafe-no-isolation``)."""

    ISOLATED = "isolated"
    UNSAFE = "unsafe"


#: Why grading refuses to run without root (the probe's message).
NEEDS_ROOT = (
    "grading must run as root: every job gets a uid of its own (setpriv) and a cgroup of its "
    "own (memory, processes, one CPU), and only root can give it either. Run `grade` with sudo; "
    "on the hub, deploy/ runs the grading service as root (docs/deploying.md).")


def privileged() -> bool:
    """True when the grader runs as root (the sandbox then gets a uid of its own)."""
    return os.geteuid() == 0


@functools.lru_cache(maxsize=1)
def probe() -> Mode:
    """``Mode.ISOLATED`` when a sandbox with a uid and a cgroup of its own can be made for
    every job here; else raise :class:`IsolationUnavailable` saying what is missing."""
    if not os.access(BWRAP, os.X_OK):
        raise IsolationUnavailable(f"bubblewrap ({BWRAP}) is not installed: {INSTALL_HINT}")
    if not privileged():
        raise IsolationUnavailable(NEEDS_ROOT)
    if not os.access(SETPRIV, os.X_OK):
        raise IsolationUnavailable(f"{SETPRIV} is missing: install it with "
                                   "`apt-get install util-linux`")
    if not seccomp.available():
        raise IsolationUnavailable("the seccomp filter cannot be built: install libseccomp2 "
                                   "(`make sandbox-deps`) and the Python package pyseccomp")
    try:
        cgroup.check()
    except cgroup.CgroupError as exc:
        raise IsolationUnavailable(str(exc)) from None
    argv = [BWRAP, *namespace_args(), "--ro-bind", "/usr", "/usr", *system_links(),
            "--", "/usr/bin/true"]
    try:
        done = subprocess.run(argv, capture_output=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise IsolationUnavailable(f"bubblewrap could not run: {exc}") from None
    if done.returncode != 0:
        why = done.stderr.decode("utf-8", "replace").strip()[:500]
        raise IsolationUnavailable(
            f"bubblewrap cannot create a sandbox here ({why}).")
    return Mode.ISOLATED


def namespace_args() -> list[str]:
    """New namespaces for everything but the user one (a user namespace would map only uid 0,
    and the child must become a real host uid of its own, see :mod:`.identity`)."""
    return ["--unshare-ipc", "--unshare-pid", "--unshare-net", "--unshare-uts",
            "--unshare-cgroup-try", "--die-with-parent", "--new-session"]


def system_links() -> list[str]:
    """``/lib``, ``/lib64``, ``/bin``, ``/sbin``: symlinks into ``/usr`` as on the host."""
    args = []
    for path in ("/lib", "/lib64", "/bin", "/sbin"):
        if os.path.islink(path):
            args += ["--symlink", os.readlink(path), path]
        elif os.path.isdir(path):
            args += ["--ro-bind", path, path]
    return args


def interpreter() -> str:
    """The base interpreter's executable (a venv's python is a link to it)."""
    real = os.path.realpath(sys.executable)
    if real.startswith(os.path.realpath(sys.base_prefix) + os.sep):
        return real
    return os.path.join(sys.base_prefix, "bin", f"python{sys.version_info[0]}")


def numpy_dirs() -> list[str]:
    """NumPy's package directory (and ``numpy.libs`` beside it) in the grader's environment."""
    import numpy

    pkg = os.path.dirname(os.path.realpath(numpy.__file__))
    libs = os.path.join(os.path.dirname(pkg), "numpy.libs")
    return [pkg] + ([libs] if os.path.isdir(libs) else [])


def interpreter_mounts() -> list[str]:
    """The base interpreter's prefix, read-only, with its own site-packages hidden."""
    prefix = os.path.realpath(sys.base_prefix)
    args = []
    if not prefix.startswith("/usr/"):
        parts = prefix.strip("/").split("/")[:-1]
        for k in range(len(parts)):   # traversable parents, whatever their host modes
            args += ["--perms", "0755", "--dir", "/" + "/".join(parts[:k + 1])]
        args += ["--ro-bind", prefix, prefix]
    paths = sysconfig.get_paths(vars={"base": prefix, "platbase": prefix})
    for path in sorted({paths["purelib"], paths["platlib"]}):
        if os.path.isdir(path):
            args += ["--tmpfs", path]
    return args


def bwrap_command(job_file: str, allowlist_dir: str, program_dir: str, fds: tuple[int, int],
                  scratch_mb: int, uid: int) -> list[str]:
    """The command that runs the child (the sandbox program of ``program_dir``, bound read-only)
    in a fresh sandbox, as ``uid``; ``fds``: the channel's write end and the cases file,
    inherited (the cases are in no file the sandbox can open)."""
    argv = [BWRAP, *namespace_args(), "--ro-bind", "/usr", "/usr", *system_links(),
            *interpreter_mounts(), "--perms", "0755", "--dir", os.path.dirname(PROGRAM),
            "--perms", "0755", "--dir", SITE]
    for path in numpy_dirs():
        argv += ["--ro-bind", path, f"{SITE}/{os.path.basename(path)}"]
    argv += ["--ro-bind", os.path.join(allowlist_dir, "course_lib"), f"{SITE}/course_lib",
             "--ro-bind", job_file, JOB, "--ro-bind", program_dir, PROGRAM,
             "--proc", "/proc", "--remount-ro", "/proc", "--dev", "/dev",
             "--size", str(int(scratch_mb) * 2**20), "--perms", "1777", "--tmpfs", "/tmp",
             "--chdir", "/tmp", *READ_ONLY_TMPFS]
    # loopback down, noexec, then a uid of its own, no capability
    argv += ["--cap-drop", "ALL", "--cap-add", "CAP_SETUID", "--cap-add", "CAP_SETGID",
             "--cap-add", "CAP_SETPCAP", "--cap-add", "CAP_NET_ADMIN",
             "--cap-add", "CAP_SYS_ADMIN", "--as-pid-1", "--",
             "/bin/sh", "-c", LOOPBACK_DOWN + NOEXEC, "sh",
             SETPRIV, f"--reuid={uid}", f"--regid={uid}", "--clear-groups",
             "--inh-caps=-all", "--bounding-set=-all", "--no-new-privs"]
    return argv + [interpreter(), "-I", "-S", "-B", CHILD, "--job", JOB, "--site", SITE,
                   "--channel-fd", str(fds[0]), "--cases-fd", str(fds[1])]


def unsafe_command(job_file: str, site_dir: str, program_dir: str,
                   fds: tuple[int, int]) -> list[str]:
    """The same child without any sandbox (``Mode.UNSAFE``)."""
    return [interpreter(), "-I", "-S", "-B", os.path.join(program_dir, "__main__.py"),
            "--job", job_file, "--site", site_dir, "--channel-fd", str(fds[0]),
            "--cases-fd", str(fds[1])]


def student_numbers(student: str) -> str:
    """``student``'s numbers for every notebook, as JSON (``{}`` for an id that draws none):
    drawn here, on the grader's side, so the sandbox needs no generator."""
    import json

    from course_lib import variants

    try:
        return json.dumps({nb: variants.variant(nb, student).numbers
                           for nb in variants.NOTEBOOKS})
    except ValueError:
        return "{}"


def child_env(home: str, student: str = "") -> dict[str, str]:
    """The child's whole environment: one BLAS thread, a private HOME, nothing of ours, and
    the student whose notebook it is as ``JUPYTERHUB_USER`` (their numbers)."""
    env = {"PATH": "/usr/bin:/bin", "HOME": home, "TMPDIR": home, "LANG": "C.UTF-8",
           "LC_ALL": "C.UTF-8", "MPLBACKEND": "Agg", "MPLCONFIGDIR": home}
    if student:
        env["JUPYTERHUB_USER"] = student
        env[NUMBERS_VARIABLE] = student_numbers(student)
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS",
                "NUMEXPR_NUM_THREADS", "VECLIB_MAXIMUM_THREADS"):
        env[var] = "1"
    return env


def posix_shell() -> str:
    """The POSIX shell used to put the sandbox into its cgroup before it starts."""
    return shutil.which("sh", path="/usr/bin:/bin") or "/bin/sh"
