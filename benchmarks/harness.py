"""Timing and memory helpers shared by the benchmark sections.

Time: the median (and 95th percentile) of repeated wall-clock runs with ``time.perf_counter``.
Memory: each measurement runs in a fresh Python process, which reports the growth of its peak
resident set size (``ru_maxrss``) across the measured call alone, so ours and the peer's are
measured the same way and neither inherits the other's heap.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


@dataclass
class Row:
    """One line of the results table: ours against a peer, lower is better for both."""

    section: str
    case: str
    metric: str
    ours: float
    peer: float | None = None
    peer_name: str = ""
    unit: str = "ms"
    notes: str = ""
    extra: dict = field(default_factory=dict)

    @property
    def ratio(self) -> float | None:
        """ours / peer: below 1 means we are faster (or use less memory)."""
        if self.peer in (None, 0) or self.peer != self.peer or self.ours != self.ours:
            return None  # no peer, or a value that could not be measured (NaN)
        return self.ours / self.peer


def timed_grade(cmd: list[str], timeout: float, label: str = "") -> float:
    """Seconds of one ``python -m autograder grade`` run (``cmd``), from the repository with
    nbgrader's environment; ``RuntimeError`` with the last line of output when it fails."""
    from autograder.course import nbgrader_env

    t0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=REPO, env=nbgrader_env(), capture_output=True, text=True,
                          timeout=timeout, check=False)
    elapsed = time.perf_counter() - t0
    if proc.returncode != 0:
        tail = (proc.stderr or proc.stdout).strip().splitlines()[-1:] or ["no output"]
        prefix = f"{label}: " if label else ""
        raise RuntimeError(f"{prefix}exit {proc.returncode}: {tail[0][:160]}")
    return elapsed


def time_call(fn, repeat: int = 5, warmup: int = 1) -> dict:
    """Median and 95th percentile wall time of ``fn()`` in milliseconds."""
    for _ in range(warmup):
        fn()
    samples = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        samples.append((time.perf_counter() - t0) * 1e3)
    samples.sort()
    p95 = samples[min(len(samples) - 1, int(round(0.95 * (len(samples) - 1))))]
    return {"median": statistics.median(samples), "p95": p95, "n": len(samples)}


_MEMORY_SNIPPET = r"""
import json, resource, sys, importlib
from pathlib import Path

def hwm_kib():
    # the peak RSS of this process. A fresh process inherits its parent's ru_maxrss across
    # fork/exec, so the kernel's own VmHWM (reset below via clear_refs) is read where it exists.
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1])
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss

def rss_kib():
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    except OSError:
        pass
    return hwm_kib()

module, func, args = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
mod = importlib.import_module(module)
setup = getattr(mod, func + "_setup", None)
state = setup(*args) if setup else None
try:
    Path("/proc/self/clear_refs").write_text("5")  # reset the peak to the current RSS
except OSError:
    pass
before = rss_kib() if Path("/proc/self/clear_refs").exists() else hwm_kib()
getattr(mod, func)(state, *args)
print(json.dumps({"peak_kib": hwm_kib() - before}))
"""


def peak_memory_mib(module: str, func: str, *args) -> float:
    """Extra peak RSS (MiB) of ``module.func(state, *args)`` in a fresh process.

    The peak is the kernel's high-water mark (``VmHWM``), reset after the set-up through
    ``/proc/self/clear_refs`` so that neither the set-up nor the parent's heap is counted.

    ``module.func_setup(*args)``, when defined, builds the input first so that its memory is not
    counted; only the growth of the peak during the call is reported.
    """
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    out = subprocess.run(
        [sys.executable, "-c", _MEMORY_SNIPPET, module, func, json.dumps(list(args))],
        capture_output=True, text=True, cwd=REPO, env=env, check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])["peak_kib"] / 1024.0


def machine_summary() -> str:
    """One line about the machine the numbers came from."""
    import platform

    import numpy as np

    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem = ""
    try:
        kib = int(Path("/proc/meminfo").read_text().split()[1])
        mem = f", {kib / 2**20:.0f} GiB RAM"
    except (OSError, ValueError, IndexError):
        pass
    return (f"{cpu}, {os.cpu_count()} cores{mem}; Python {platform.python_version()}, "
            f"NumPy {np.__version__}")
