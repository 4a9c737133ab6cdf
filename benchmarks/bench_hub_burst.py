"""The grading service on the real hub: submit → feedback-fetchable latency alone and in a burst
of 30 real Unix users, and login time during the burst.

Runs ``tests/deploy/test_hub_grading.py`` (as root: it makes real Unix users, starts the course's
JupyterHub with its grading service, and logs in through PAM; see that module), which writes
what it measured to ``test-artifacts/deploy/hub-burst.json``; this section reads it and prints:

- **alone**: three students submitting one after the other, the service idle: latency p50/p95
  from the submission's own time (the kernel's ctime) to the newest of its six pages in the
  exchange's feedback folder (what ``nbgrader fetch_feedback`` fetches);
- **burst**: 30 students submitting within 60 s (one every 2 s): latency p50/p95 against the
  lone students' p50 of the same run (the peer), and the time from the first submission to the
  last one graded;
- **logins**: p95 of three logins through the hub's login form during the burst and its drain,
  against three logins on the idle hub just before it.

``--smoke`` does not run the hub (minutes, root): it prints the last results if there are any,
else one row saying it measured nothing.
"""

from __future__ import annotations

import json
import math
import os
import statistics
import subprocess
import sys

from .harness import REPO, Row

SECTION = "grading service on the hub"
RESULTS = REPO / "test-artifacts" / "deploy" / "hub-burst.json"


def _p(samples: list[float], q: float) -> float:
    """The ``q`` quantile, nearest rank (3 samples: p95 is the largest)."""
    samples = sorted(samples)
    return samples[min(len(samples) - 1, int(round(q * (len(samples) - 1))))]


def _measure() -> None:
    if os.geteuid() != 0:
        raise RuntimeError("bench_hub_burst makes real Unix users: run it as root")
    RESULTS.unlink(missing_ok=True)
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:randomly",
                           "-p", "no:cacheprovider", "-n", "0",
                           "tests/deploy/test_hub_grading.py"], cwd=REPO, timeout=3600,
                          capture_output=True, text=True, check=False)
    if proc.returncode != 0 or not RESULTS.exists():
        tail = (proc.stdout + proc.stderr).strip().splitlines()[-5:]
        raise RuntimeError("the hub burst test failed: " + " | ".join(tail))


def run(smoke: bool = False) -> list[Row]:
    if not smoke:
        _measure()
    if not RESULTS.exists():       # --smoke on a fresh clone: say so, measure nothing
        return [Row(SECTION, "burst", "not measured", math.nan, unit="s",
                    notes="needs root and about 10 minutes: run without --smoke")]
    got = json.loads(RESULTS.read_text())
    alone, burst = got["alone_latency_s"], got["burst_latency_s"]
    login, idle = got["login_s"], got.get("login_idle_s")
    load = f"load average {got['load_avg_1min']:.1f} on {got['cpus']} CPUs at the end"
    n = got["burst_students"]
    return [
        Row(SECTION, "one student alone", "submit → fetchable p50", statistics.median(alone),
            unit="s", notes=f"{len(alone)} students, six notebooks each"),
        Row(SECTION, "one student alone", "submit → fetchable p95", _p(alone, 0.95), unit="s",
            notes="target: under 20 s"),
        Row(SECTION, f"burst of {n} in 60 s", "submit → fetchable p50", statistics.median(burst),
            peer=statistics.median(alone), peer_name="alone p50", unit="s",
            notes="--workers 2 --jobs 2"),
        Row(SECTION, f"burst of {n} in 60 s", "submit → fetchable p95", _p(burst, 0.95),
            peer=statistics.median(alone), peer_name="alone p50", unit="s", notes=load),
        Row(SECTION, f"burst of {n} in 60 s", "drained (first submit → last graded)",
            got["burst_drained_s"], unit="s", notes="target: within 180 s"),
        Row(SECTION, f"burst of {n} in 60 s", "login p95 (hub's form, PAM)", _p(login, 0.95),
            peer=_p(idle, 0.95) if idle else None, peer_name="idle hub p95", unit="s",
            notes=f"{len(login)} logins during the burst"),
    ]
