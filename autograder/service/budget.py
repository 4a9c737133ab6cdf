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
from ..isolation.inside.confine import WALL_FACTOR
from ..isolation.inside.supervisor import GRACE, TIMEOUTS_IN_A_ROW
from ..exercises import REGISTRY
from ..model import CellKind, SourceNotebook
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


#: graded functions of one notebook whose hangs the budget makes room for: a student's one or
#: two endless loops cost those functions' points only, while a notebook written to hang holds a
#: worker at most this many functions' stopping time longer (a live red team held one for 318 s
#: with room for all nine of q3's)
HANGS_ALLOWED = 2


def hang_allowance(sources: list[SourceNotebook], case_timeout: float) -> dict[str, float]:
    """``{notebook: seconds}`` the sandbox may spend stopping graded functions that hang: each
    is stopped after :data:`TIMEOUTS_IN_A_ROW` cases, each at most the case limit's wall-clock
    backstop (:data:`~autograder.isolation.inside.confine.WALL_FACTOR` × ``case_timeout``: a case
    that sleeps uses no CPU time) plus the supervisor's grace, room for :data:`HANGS_ALLOWED`
    of them. Added to a budget, one or two hanging functions cost their own points only, as
    under ``grade`` (an instructor's playtest: two hung cases used up a 20 s budget and a
    correct function beside them scored 0)."""
    per_function = TIMEOUTS_IN_A_ROW * (WALL_FACTOR * case_timeout + GRACE)

    def runs_code(name: str) -> bool:   # as the batch judges it: an unknown name is a function
        return getattr(REGISTRY.get(name), "kind", CellKind.FUNCTION) is CellKind.FUNCTION

    return {s.name: per_function * min(HANGS_ALLOWED, sum(runs_code(g.name) for g in s.graded))
            for s in sources}


def budgets(costs: dict[str, float], policy: Policy,
            allowance: dict[str, float] | None = None) -> dict[str, float]:
    """``{notebook: job timeout in seconds}``: ``max(floor_seconds, margin x cost)`` from the
    measured costs (see the module docstring), plus the notebook's ``allowance`` for hangs
    (:func:`hang_allowance`), which an honest notebook never uses."""
    extra = allowance or {}
    return {name: max(policy.floor_seconds, policy.margin * cost) + extra.get(name, 0.0)
            for name, cost in costs.items()}


#: seconds of budget below which a try grades nothing: the sandbox alone takes about a second to
#: start, so less left is a budget used up
MIN_TRY_SECONDS = 1.0


def submission_budget(budgets: dict[str, float], notebooks: list[str], default: float) -> float:
    """The time budget of a submission grading ``notebooks``: the sum of their budgets
    (``default`` for one without). One budget for the whole submission and all its tries, not
    one per notebook per try: five sleeping notebooks re-queued four times held a worker 25
    budgets long while the next student waited (issue 33)."""
    return sum(budgets.get(name, default) for name in notebooks)


def batch_timeout(left: float, notebooks: int, jobs: int, longest: float) -> tuple[float, int]:
    """``(job timeout, waves)`` of one batch of ``notebooks`` run ``jobs`` at a time with
    ``left`` seconds of the submission's budget: each notebook gets at most ``longest`` (the
    largest of their own budgets) and the waves of ``jobs`` notebooks together at most ``left``,
    so the batch holds its worker no longer than the budget left (plus the sandbox's own
    start-up and clean-up)."""
    if notebooks < 1 or jobs < 1:
        raise ValueError(f"a batch needs notebooks and jobs, got {notebooks} and {jobs}")
    waves = -(-notebooks // jobs)
    return min(longest, left / waves), waves
