"""A cgroup per job: the memory, process and CPU limits of the WHOLE job (all its processes and
its tmpfs scratch). Grading never runs without one (:func:`check`, from the probe; a job whose
cgroup cannot be made raises :class:`CgroupError`).

Both layouts are supported: cgroup v2 (``memory.max``, ``pids.max``, ``cpu.max``,
``cpu.weight``; the controllers are switched on in the parents' ``cgroup.subtree_control`` when
they are not) and cgroup v1, alone or beside an empty v2 mount (hybrid: one hierarchy per
controller under ``/sys/fs/cgroup/<controller>``; ``cpu.cfs_quota_us``, ``cpu.shares``, usage in
``cpuacct.usage``).

The CPU limit is what keeps one job from slowing the others: every job gets at most
:data:`CPUS` CPU and the same weight, whatever it does. Processes the job starts with
``setsid()`` stay in its cgroup, and the kernel's autogroups (one scheduling group per session)
apply only to tasks of the root CPU cgroup, so sixty sessions in one job still share one job's
CPU.
"""

from __future__ import annotations

import os
import time

from .identity import kill_until_gone

V1_ROOT = "/sys/fs/cgroup"      #: where the v1 hierarchies are mounted, one per controller
V2_ROOT = "/sys/fs/cgroup"      #: the v2 hierarchy, when it is the only one
GROUP = "autograder-isolation"  #: the parent of every job's cgroup
CPUS = 1                        #: CPUs a job may use at most
CPU_PERIOD_US = 100_000         #: the CFS period the quota is counted in
V1_CPU_SHARES = 1024            #: equal weight for every job (the v1 default)
V2_CPU_WEIGHT = 100             #: equal weight for every job (the v2 default)
V2_CONTROLLERS = ("cpu", "memory", "pids")
#: what to do when no cgroup can be made (part of every CgroupError's message)
HINT = ("Grading needs a cgroup per job (memory, pids and cpu limits) and must run as root: "
        "cgroup v2 with the cpu, memory and pids controllers, or the v1 hierarchies memory, "
        "pids, cpu and cpuacct under /sys/fs/cgroup, writable by root.")


class CgroupError(RuntimeError):
    """No cgroup with the job's limits can be made here (the message says what is missing)."""


def _write(path: str, text: str) -> None:
    with open(path, "w") as f:
        f.write(text)


def _read(path: str) -> str:
    with open(path) as f:
        return f.read()


def is_v2() -> bool:
    """True when ``/sys/fs/cgroup`` is a pure v2 hierarchy (not v1, not hybrid)."""
    return os.path.exists(os.path.join(V2_ROOT, "cgroup.controllers"))


def v1_settings(memory: str, pids: int) -> dict[str, dict[str, str]]:
    """``{controller: {file: value}}`` of a v1 job cgroup (``cpuacct``: none, only its usage)."""
    quota = str(CPUS * CPU_PERIOD_US)
    return {"memory": {"memory.limit_in_bytes": memory, "memory.memsw.limit_in_bytes": memory},
            "pids": {"pids.max": str(pids)},
            "cpu": {"cpu.cfs_period_us": str(CPU_PERIOD_US), "cpu.cfs_quota_us": quota,
                    "cpu.shares": str(V1_CPU_SHARES)},
            "cpuacct": {}}


#: v1 files that may be missing without loss: swap accounting is often off (then there is no
#: swap to account either: ``memory.limit_in_bytes`` holds)
V1_OPTIONAL = {"memory.memsw.limit_in_bytes"}


def v2_settings(memory: str, pids: int) -> dict[str, str]:
    """``{file: value}`` of a v2 job cgroup."""
    return {"memory.max": memory, "memory.swap.max": "0", "pids.max": str(pids),
            "cpu.max": f"{CPUS * CPU_PERIOD_US} {CPU_PERIOD_US}",
            "cpu.weight": str(V2_CPU_WEIGHT)}


V2_OPTIONAL = {"memory.swap.max"}   #: absent when the kernel has no swap accounting


class JobCgroup:
    """The cgroup directories of one job, made with its limits (``CgroupError`` when they
    cannot be); :meth:`remove` when the job is over."""

    def __init__(self, name: str, memory_mb: int, pids: int):
        self.dirs: list[str] = []
        self.usage_file = ""
        memory = str(int(memory_mb) * 2**20)
        try:
            if is_v2():
                self._make_v2(name, memory, pids)
            else:
                self._make_v1(name, memory, pids)
        except CgroupError:
            self.remove()
            raise
        except OSError as exc:
            self.remove()
            raise CgroupError(f"cannot make the job's cgroup ({exc}). {HINT}") from None

    def _make_v1(self, name: str, memory: str, pids: int) -> None:
        made: dict[str, str] = {}   # a co-mounted pair (cpu,cpuacct) is one directory
        for controller, files in v1_settings(memory, pids).items():
            base = os.path.join(V1_ROOT, controller)
            if not os.path.isdir(base):
                raise CgroupError(f"the cgroup v1 controller {controller!r} is not mounted at "
                                  f"{base}. {HINT}")
            real = os.path.realpath(base)
            path = made.get(real) or self._fresh_dir(os.path.join(base, GROUP, name))
            made[real] = path
            for key, value in files.items():
                if key in V1_OPTIONAL and not os.path.exists(os.path.join(path, key)):
                    continue
                _write(os.path.join(path, key), value)
            if controller == "cpuacct":
                self.usage_file = os.path.join(path, "cpuacct.usage")

    def _make_v2(self, name: str, memory: str, pids: int) -> None:
        base = os.path.join(V2_ROOT, GROUP)
        os.makedirs(base, exist_ok=True)
        for parent in (V2_ROOT, base):
            enable_v2_controllers(parent)
        path = self._fresh_dir(os.path.join(base, name))
        for key, value in v2_settings(memory, pids).items():
            if key in V2_OPTIONAL and not os.path.exists(os.path.join(path, key)):
                continue
            _write(os.path.join(path, key), value)
        self.usage_file = os.path.join(path, "cpu.stat")

    def _fresh_dir(self, path: str) -> str:
        if os.path.isdir(path):
            _empty(path)
            os.rmdir(path)
        os.makedirs(path)
        self.dirs.append(path)
        return path

    def procs_files(self) -> list[str]:
        """The files a process writes its pid into to join the job's cgroup."""
        return [os.path.join(d, "cgroup.procs") for d in self.dirs]

    def cpu_seconds(self) -> float:
        """CPU seconds every process of the job has used so far (the job's CPU clock)."""
        text = _read(self.usage_file)
        if self.usage_file.endswith("cpuacct.usage"):
            return int(text) / 1e9
        usage = dict(line.split() for line in text.splitlines() if line.strip())
        return int(usage["usage_usec"]) / 1e6

    def remove(self) -> None:
        """Kill whatever is still in the cgroup, then remove it."""
        for path in self.dirs:
            _empty(path)
            for _ in range(200):
                try:
                    os.rmdir(path)
                    break
                except FileNotFoundError:
                    break
                except OSError:
                    time.sleep(0.01)


def enable_v2_controllers(path: str) -> None:
    """Switch :data:`V2_CONTROLLERS` on for the children of the v2 cgroup ``path``
    (``CgroupError`` when ``path`` does not offer them: a parent has to delegate them first)."""
    offered = set(_read(os.path.join(path, "cgroup.controllers")).split())
    missing = [c for c in V2_CONTROLLERS if c not in offered]
    if missing:
        raise CgroupError(f"the cgroup v2 controllers {', '.join(missing)} are not available "
                          f"in {path}. {HINT}")
    on = set(_read(os.path.join(path, "cgroup.subtree_control")).split())
    wanted = " ".join(f"+{c}" for c in V2_CONTROLLERS if c not in on)
    if wanted:
        _write(os.path.join(path, "cgroup.subtree_control"), wanted)


def check() -> None:
    """Make and remove one cgroup with a job's limits: ``CgroupError`` (saying what is missing)
    when grading could not give a job its cgroup here."""
    if os.geteuid() != 0:
        raise CgroupError(f"the grader does not run as root. {HINT}")
    JobCgroup(f"probe-{os.getpid()}", 64, 8).remove()


def _empty(path: str) -> None:
    """Kill every process left in the cgroup at ``path``."""
    def members() -> list[int]:
        try:
            with open(os.path.join(path, "cgroup.procs")) as f:
                return [int(x) for x in f.read().split()]
        except OSError:
            return []
    kill_until_gone(members, patience=1.0)
