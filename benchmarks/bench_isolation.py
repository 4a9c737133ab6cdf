"""The cost of the OS-level sandbox: one job in bubblewrap vs the same child unsandboxed.

Both contenders run the same :func:`autograder.isolation.run_notebook` job, the peer with
``Mode.UNSAFE`` (the same child program, no bubblewrap, no uid, no cgroup), so the ratio is
what isolation adds to one student's notebook. Two jobs: an empty one (the fixed cost: the
sandbox, the interpreter, NumPy) and a typical one (6 graded names x 10 small cases).
"""

from __future__ import annotations

import numpy as np

from .harness import Row, time_call

SECTION = "isolation"


def _jobs():
    from autograder.isolation import CaseInput, NameJob, NotebookJob

    empty = NotebookJob("empty", "", [])
    typical = NotebookJob("typical", "import numpy as np\n", [
        NameJob(f"f{k}", "function",
                [("cell", f"def f{k}(a):\n    return np.linalg.solve(a, np.ones(len(a)))\n")],
                [CaseInput((np.eye(5) * (i + 1),), {}) for i in range(10)])
        for k in range(6)])
    return {"empty job": empty, "typical job (6 names x 10 cases)": typical}


def run(smoke: bool = False) -> list[Row]:
    from autograder.isolation import IsolationUnavailable, Limits, Mode, probe, run_notebook

    try:
        mode = probe()
    except IsolationUnavailable as exc:
        return [Row(SECTION, "empty job", "time per job", float("nan"), notes=str(exc)[:80])]
    repeat = 1 if smoke else 5
    rows = []
    for case, job in _jobs().items():
        ours = time_call(lambda job=job: run_notebook(job, Limits(), mode), repeat=repeat)
        peer = time_call(lambda job=job: run_notebook(job, Limits(), Mode.UNSAFE),
                         repeat=repeat)
        rows.append(Row(SECTION, case, "time per job", ours["median"], peer["median"],
                        "same child, no sandbox", notes=f"p95 {ours['p95']:.0f} ms"))
    return rows
