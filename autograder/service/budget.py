"""Each notebook's time budget, from the reference solution's own cost.

``grade``'s ``--job-timeout`` (600 s) lets one notebook hold a grading slot about 200 times what
an honest notebook needs. The service instead measures, once at start-up, how long the
instructor's own source notebook (the model answers) takes to grade in the same sandbox, and
gives each notebook ``max(floor_seconds, margin x that)`` (:class:`~.policy.Policy`; default
10 x, at least 20 s). The margin covers a slower but honest solution (a Python loop where the
reference is vectorised costs a few times more on these sizes) and a busy machine; the floor
covers the sandbox's start-up jitter on a loaded 2-core host.
"""

from __future__ import annotations

import shutil
import tempfile
import time
from dataclasses import replace
from pathlib import Path

from ..grade.batch import Options, grade_batch
from ..course import ASSIGNMENT
from ..model import SourceNotebook
from .policy import Policy

#: the folder name the reference is graded under (never a student's: ids have no dash first)
REFERENCE = "reference-solution"


def measure(sources: list[SourceNotebook], opts: Options) -> dict[str, float]:
    """Seconds each source notebook takes to grade as a submission (the reference's cost),
    one notebook at a time, with the options' sandbox."""
    folder = Path(tempfile.mkdtemp(prefix="4f9-reference-"))
    try:
        target = folder / REFERENCE / ASSIGNMENT
        target.mkdir(parents=True)
        costs = {}
        for src in sources:
            shutil.copyfile(src.path, target / f"{src.name}.ipynb")
            t0 = time.monotonic()
            grade_batch(folder, [src], replace(opts, progress=False), students=[REFERENCE])
            costs[src.name] = time.monotonic() - t0
        return costs
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def budgets(costs: dict[str, float], policy: Policy) -> dict[str, float]:
    """``{notebook: job timeout in seconds}`` from measured costs (see the module docstring)."""
    return {name: max(policy.floor_seconds, policy.margin * cost) for name, cost in costs.items()}
