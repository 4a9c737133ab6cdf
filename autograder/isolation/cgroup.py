"""A cgroup per job: the memory and process limits of the WHOLE job (all its processes and
its tmpfs scratch), when a cgroup hierarchy is writable. cgroup v1 (``memory``, ``pids``
controllers) and v2 (``memory.max``, ``pids.max``) are both supported; without either, the
job is limited by rlimits alone.
"""

from __future__ import annotations

import os
import time

from .identity import kill_until_gone

V1_ROOT = "/sys/fs/cgroup"
V2_ROOT = "/sys/fs/cgroup"
GROUP = "autograder-isolation"


def _write(path: str, text: str) -> None:
    with open(path, "w") as f:
        f.write(text)


class JobCgroup:
    """The cgroup directories of one job (empty when none could be made)."""

    def __init__(self, name: str, memory_mb: int, pids: int):
        self.dirs: list[str] = []
        memory = str(int(memory_mb) * 2**20)
        try:
            if os.path.exists(os.path.join(V2_ROOT, "cgroup.controllers")):
                self._make_v2(name, memory, pids)
            else:
                self._make_v1(name, memory, pids)
        except OSError:
            self.remove()
            self.dirs = []

    def _make_v1(self, name: str, memory: str, pids: int) -> None:
        settings = {"memory": {"memory.limit_in_bytes": memory,
                               "memory.memsw.limit_in_bytes": memory},
                    "pids": {"pids.max": str(pids)}}
        for controller, files in settings.items():
            base = os.path.join(V1_ROOT, controller)
            if not os.path.isdir(base):
                continue
            path = self._fresh_dir(os.path.join(base, GROUP, name))
            for key, value in files.items():
                if os.path.exists(os.path.join(path, key)):
                    _write(os.path.join(path, key), value)

    def _make_v2(self, name: str, memory: str, pids: int) -> None:
        base = os.path.join(V2_ROOT, GROUP)
        os.makedirs(base, exist_ok=True)
        _write(os.path.join(base, "cgroup.subtree_control"), "+memory +pids")
        path = self._fresh_dir(os.path.join(base, name))
        _write(os.path.join(path, "memory.max"), memory)
        _write(os.path.join(path, "memory.swap.max"), "0")
        _write(os.path.join(path, "pids.max"), str(pids))

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


def _empty(path: str) -> None:
    """Kill every process left in the cgroup at ``path``."""
    def members() -> list[int]:
        try:
            with open(os.path.join(path, "cgroup.procs")) as f:
                return [int(x) for x in f.read().split()]
        except OSError:
            return []
    kill_until_gone(members, patience=1.0)
