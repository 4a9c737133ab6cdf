"""The job the grader hands to the sandbox: plain dataclasses, the interface of this package.

A :class:`NotebookJob` is one student's notebook: the instructor's setup cell, then for every
graded name the cells to run first and the cases to call it on. :func:`run_notebook
<autograder.isolation.runner.run_notebook>` runs the whole job in ONE sandbox and answers one
:class:`autograder.model.NameRun` per name.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..model import CellKind

#: The kinds of a job's names, as the wire spells them (the values of
#: :class:`~autograder.model.CellKind`): a function is called once per case; a choice or
#: number item is a variable whose one case's "result" is its value.
FUNCTION = CellKind.FUNCTION.value
CHOICE = CellKind.CHOICE.value
KINDS = (FUNCTION, CHOICE)


def wire_kind(kind: CellKind) -> str:
    """How the sandbox runs a graded cell of ``kind``: ``FUNCTION`` for a graded function,
    ``CHOICE`` (read a variable) for a choice or number item."""
    kind = CellKind(kind)
    if kind is CellKind.MANUAL:
        raise ValueError("a written answer (CellKind.MANUAL) is not run in the sandbox")
    return FUNCTION if kind is CellKind.FUNCTION else CHOICE


@dataclass(frozen=True)
class Limits:
    """Resource limits of one job (the defaults suit the course's exercises). Every job also
    gets at most one CPU, at the same weight as every other (:mod:`~.cgroup`)."""

    #: CPU seconds per case, on the worker's CPU clock (stopped in any case after
    #: :data:`~.inside.confine.WALL_FACTOR` times this in wall-clock time)
    case_timeout: float = 10.0
    load_timeout: float = 40.0    #: wall seconds for the setup cell, and for ALL of a name's cells
    job_timeout: float = 600.0    #: wall seconds for the whole notebook (every name, every restart)
    memory_mb: int = 2048         #: the WHOLE job (all its processes, incl. its tmpfs scratch)
    scratch_mb: int = 64          #: size of the private tmpfs (/tmp, HOME, cwd)
    pids: int = 64                #: processes + threads of the whole job
    output_bytes: int = 20_000    #: captured output kept per name / per case
    max_launches: int = 3         #: worker processes per name (restarts after a crash)

    def __post_init__(self):
        for name in ("case_timeout", "load_timeout", "job_timeout"):
            if not float(getattr(self, name)) > 0:
                raise ValueError(f"Limits.{name} must be a positive number of seconds")
        for name in ("memory_mb", "scratch_mb", "pids", "output_bytes", "max_launches"):
            value = getattr(self, name)
            if type(value) is not int or value < 1:
                raise ValueError(f"Limits.{name} must be a positive int, got {value!r}")


@dataclass
class CaseInput:
    """The inputs of one case (plain data) and how many bytes its encoded result may take."""

    args: tuple
    kwargs: dict
    result_cap: int = 1_000_000


@dataclass
class NameJob:
    """One graded name: its cells (run in order first), then its cases.

    For ``kind="choice"`` there is exactly one ``CaseInput(args=(), kwargs={})`` and its result
    is the variable's value.
    """

    name: str
    kind: str                       #: ``FUNCTION`` or ``CHOICE``, as :func:`wire_kind` gives it
    cells: list[tuple[str, str]]
    cases: list[CaseInput] = field(default_factory=list)


@dataclass
class NotebookJob:
    """One student's notebook: everything the sandbox runs for it."""

    job_id: str
    setup_source: str
    names: list[NameJob]
    #: whose notebook it is: the sandbox's ``JUPYTERHUB_USER``, so ``course_lib.variants``
    #: draws this student's numbers whatever the notebook's first cell says
    student: str = ""


def validate_job(job: NotebookJob) -> None:
    """Raise ``ValueError`` naming the field when ``job`` is malformed (the caller's bug)."""
    if not isinstance(job, NotebookJob):
        raise ValueError(f"job must be a NotebookJob, got {type(job).__name__}")
    if type(job.setup_source) is not str:
        raise ValueError("job.setup_source must be a str")
    if type(job.student) is not str or "\0" in job.student or "\n" in job.student:
        raise ValueError("job.student must be a one-line str")
    seen = set()
    for nj in job.names:
        if type(nj.name) is not str or not nj.name.isidentifier():
            raise ValueError(f"NameJob.name must be a Python identifier, got {nj.name!r}")
        if nj.name in seen:
            raise ValueError(f"NameJob.name {nj.name!r} appears twice in job.names")
        seen.add(nj.name)
        if nj.kind not in KINDS:
            raise ValueError(f"NameJob.kind must be one of {KINDS}, got {nj.kind!r}")
        if any(type(lbl) is not str or type(src) is not str for lbl, src in nj.cells):
            raise ValueError(f"NameJob.cells of {nj.name!r} must be (label, source) str pairs")
        if nj.kind == CHOICE and (len(nj.cases) != 1 or nj.cases[0].args != ()
                                  or nj.cases[0].kwargs != {}):
            raise ValueError(f"NameJob.cases of choice {nj.name!r} must be exactly one "
                             "CaseInput(args=(), kwargs={})")
        for case in nj.cases:
            if type(case.result_cap) is not int or case.result_cap < 1:
                raise ValueError(f"CaseInput.result_cap of {nj.name!r} must be a positive int")
