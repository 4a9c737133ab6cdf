"""The batch: one isolated job per (student, notebook), judged as soon as it returns.

:func:`grade_batch` takes every student and source notebook through five stages: **read** the
submission (:mod:`.reading`), **plan** its cells (:mod:`.planning`; rows that need no sandbox,
such as a missing notebook or any choice or number item, judged on its own cell's literal, are
decided here), build one :class:`NotebookJob` whose cases are
drawn per student (:mod:`.cases`), **run** the jobs on an executor (:mod:`.executors`:
``--jobs`` threads each waiting on a local sandbox, or the workers of a dask cluster,
``--scheduler``), **judge** each returned :class:`~autograder.model.NameRun` at once
(:func:`autograder.judging.judge_cell`), and keep as **rows** only what the outputs need:
verdicts, reasons, small values or summaries of big ones, and hidden cases' details only when
they are to be revealed. So the grader's memory does not grow with what students return,
whatever the batch's size.
"""

from __future__ import annotations

import functools
import sys
import traceback
from dataclasses import dataclass, field
from pathlib import Path

from .. import judging
from ..course import ASSIGNMENT, TEXT_STUB
from ..exercises import REGISTRY
from ..isolation import CaseInput, Limits, Mode, NameJob, NotebookJob
from ..isolation.allowlist import OFF_LIMITS
from ..isolation.jobs import wire_kind
from ..model import (AnswerHint, Batch, CaseOutcome, CaseRecord, CellKind, CellResult,
                     GradedTest, NameRun, OutcomeKind, SourceNotebook, Status, Submission, Verdict)
from . import keeping
from .cases import DrawnCase, case_seed, draw, job_digest
from .executors import make_executor
from .planning import MAX_CELL_CODE, NOT_TYPED, CellPlan, answer_hint, plan_cells, typed_answer
from .progress import Progress
from .reading import MAX_NOTEBOOK_MB, discover_students, read_submission
from .whose import other_students


@dataclass
class Options:
    """How a batch is graded (the command line's choices)."""

    out: Path
    jobs: int = 1
    limits: Limits = field(default_factory=Limits)
    secret: bytes = b""
    reveal_hidden: bool = False
    mode: Mode = Mode.ISOLATED
    scheduler: str | None = None    #: a dask scheduler's address: run the jobs on its workers
    max_notebook_mb: float = MAX_NOTEBOOK_MB
    progress: bool = True
    #: folder id -> the id whose numbers and option letters its notebooks are judged on (an
    #: instructor's remedy for an honest wrong STUDENT_ID: ``grade --graded-as``)
    graded_as: dict[str, str] = field(default_factory=dict)


@dataclass
class NotebookWork:
    """One student's notebook, read and planned, with the graded names to run."""

    student: str
    src: SourceNotebook
    sub: Submission
    plan: CellPlan
    names: list[GradedTest]                 #: the graded tests its job runs
    variant: str = ""                       #: whose numbers and letters (default: the student)

    @property
    def variant_id(self) -> str:
        return self.variant or self.student


@dataclass
class ReadNotebook:
    """One notebook once read and planned: the submission (None if reading failed), the rows
    decided without the sandbox, and the work left for it (None if nothing is to run)."""

    submission: Submission | None
    rows: list[CellResult]
    work: NotebookWork | None = None


@dataclass
class PreparedName:
    """One graded name of a job: what the sandbox runs, the cases drawn, what its source shows."""

    job: NameJob
    drawn: list[DrawnCase]
    hint: AnswerHint


def grade_batch(submitted: Path, sources: list[SourceNotebook], opts: Options,
                students: list[str] | None = None) -> Batch:
    """Grade every student's notebooks: one :class:`CellResult` per graded cell."""
    submitted = Path(submitted)
    students = discover_students(submitted) if students is None else students
    results: list[CellResult] = []
    works: list[NotebookWork] = []
    subs: dict[tuple[str, str], Submission] = {}
    for student in students:
        for src in sources:
            read = _read_and_prepare(submitted, student, src, opts)
            if read.submission is not None:
                subs[(student, src.name)] = read.submission
            results.extend(read.rows)
            if read.work is not None:
                works.append(read.work)
    results.extend(_run_all(works, opts))
    order = {s.name: i for i, s in enumerate(sources)}
    cell_order = {(s.name, c.meta.get("grade_id")): i for s in sources
                  for i, c in enumerate(s.cells)}
    results.sort(key=lambda r: (r.student, order.get(r.notebook, 99),
                                cell_order.get((r.notebook, r.grade_id), 999)))
    return Batch(results, subs, list(students))


def graded_row(student: str, notebook: str, test: GradedTest, status: Status, message: str,
               **fields) -> CellResult:
    """The row of graded test ``test``: 0 points unless ``score`` is given, of its kind unless
    ``kind`` is; the other fields of :class:`CellResult` by keyword."""
    fields.setdefault("score", 0.0)
    fields.setdefault("kind", _kind(test.name))
    return CellResult(student=student, notebook=notebook, grade_id=test.test_id, name=test.name,
                      max_score=test.points, status=status, message=message, **fields)


def _read_and_prepare(submitted: Path, student: str, src: SourceNotebook,
                      opts: Options) -> ReadNotebook:
    """Read and plan one notebook; an internal error gives that notebook ``grader-error`` rows
    (the traceback on stderr) and never stops the batch."""
    sub = None
    try:
        sub = read_submission(submitted / student / ASSIGNMENT, student, src.name,
                              opts.max_notebook_mb)
        rows, work = _prepare(student, src, sub, opts)
        return ReadNotebook(sub, rows, work)
    except Exception as exc:  # noqa: BLE001 - one broken notebook never stops the batch
        traceback.print_exc()
        print(f"error: the grader failed on {student}/{src.name}", file=sys.stderr)
        return ReadNotebook(sub, [graded_row(student, src.name, test, Status.GRADER_ERROR,
                                             _grader_failed(exc)) for test in src.graded])


def _grader_failed(exc: BaseException) -> str:
    return (f"the grader failed on this test ({type(exc).__name__}); the instructor will look "
            "into it")


def _prepare(student: str, src: SourceNotebook, sub: Submission,
             opts: Options) -> tuple[list[CellResult], NotebookWork | None]:
    """The rows that need no sandbox (every item's among them), and the rest as a
    :class:`NotebookWork` (or None)."""
    if sub.status is not Status.OK:
        rows = [graded_row(student, src.name, test, sub.status, sub.message, whole_notebook=True)
                for test in src.graded]
        rows += [CellResult(student=student, notebook=src.name, grade_id=gid, name=gid, score=0.0,
                            max_score=points, status=sub.status, message=sub.message,
                            kind=CellKind.MANUAL, whole_notebook=True)
                 for gid, points in src.manual]
        return rows, None
    plan = plan_cells(src, sub)
    sub.found_by_name = dict(plan.by_name)
    variant = opts.graded_as.get(student, "")
    others = tuple(other_students(sub))     # once per notebook: the scan is bounded per call
    rows, names = [], []
    for test in src.graded:
        row = _decided_without_sandbox(student, src, sub, plan, test)
        if row is None and REGISTRY[test.name].kind.is_item:
            row = judge_typed_item(student, src, sub, plan, test, variant, others,
                                   opts.reveal_hidden)
        if row is None:
            names.append(test)
        else:
            rows.append(row)
    rows.extend(_manual_rows(student, src, sub))
    return rows, (NotebookWork(student, src, sub, plan, names, variant) if names else None)


def judge_typed_item(student: str, src: SourceNotebook, sub: Submission, plan: CellPlan,
                     test: GradedTest, variant: str, others: tuple[str, ...],
                     reveal: bool) -> CellResult:
    """The row of a choice or number item, judged on the literal its own cell types and on
    nothing the student's code computes or sets anywhere (so no sandbox runs for it).

    A variable set by a later cell would let one notebook compute every reader's own letters
    from the key and the public option-order code (issue 33); an item cell left as released,
    emptied or set to None is unanswered whatever runs after it. ``others``: the ids the
    notebook names besides its folder's (:func:`.whose.other_students`)."""
    ex = REGISTRY[test.name]
    code = plan.python.get(plan.chosen[test.name], "")
    typed = typed_answer(code, test.name)
    answer = None if typed is NOT_TYPED else CaseOutcome(0, OutcomeKind.RETURNED, value=typed)
    records = [CaseRecord(0, "your answer", True,
                          *judging.judge_item(ex, answer, variant or student))]
    verdict = judging.judge_cell(judging.CellEvidence(
        ex, test.points, records, answer_hint(code, test.name, ex.kind),
        typed=answer is not None, answer=answer, notes=_notes(plan, variant, test.name),
        others=others, student=student, reveal=reveal))
    return graded_row(student, src.name, test, verdict.status, verdict.message,
                      score=verdict.score, cases=[keeping.kept(r, reveal) for r in records],
                      notes=list(verdict.notes), code=sub.cells[plan.chosen[test.name]]["source"],
                      fits_other=verdict.fits_other, answer=None if answer is None else typed)


def _decided_without_sandbox(student: str, src: SourceNotebook, sub: Submission,
                             plan: CellPlan, test: GradedTest) -> CellResult | None:
    """The row of a graded name that is not run (no rule, blocked by planning, no cell)."""
    name = test.name
    if name not in REGISTRY:
        return graded_row(student, src.name, test, Status.GRADER_ERROR,
                          f"the autograder has no rule for {test.test_id} (instructor: register "
                          f"{name!r} in autograder/exercises)")
    if name in plan.blocked:
        status, message = plan.blocked[name]
        code = sub.cells[plan.chosen[name]]["source"]
        return graded_row(student, src.name, test, status, message,
                          code=code if len(code) <= MAX_CELL_CODE else "")
    if name in plan.missing:
        return graded_row(student, src.name, test, Status.MISSING,
                          f"no solution cell for {name}: the cell (grade_id {name!r}) was deleted "
                          "and no other cell defines it; copy it back from the released notebook, "
                          "answer it and resubmit")
    return None


def _kind(name: str) -> CellKind:
    ex = REGISTRY.get(name)
    return ex.kind if ex is not None else CellKind.FUNCTION


def _manual_rows(student: str, src: SourceNotebook, sub: Submission) -> list[CellResult]:
    """The written answers: 0 when missing or left as released (as nbgrader scores an
    unchanged answer cell), otherwise waiting for a marker (score None)."""
    rows = []
    for gid, points in src.manual:
        answer = [c["source"] for c in sub.cells if c["grade_id"] == gid]
        if not answer:
            status, message = Status.MISSING, f"the answer cell {gid} is missing from the notebook"
        elif written_answer_blank(answer[-1]):
            status, message = Status.UNANSWERED, ("left as released (YOUR ANSWER HERE): 0 marks, "
                                                  "nothing for a marker to read")
        else:
            status, message = Status.MANUAL, "marked by hand in formgrader"
        rows.append(CellResult(
            student=student, notebook=src.name, grade_id=gid, name=gid,
            score=None if status is Status.MANUAL else 0.0, max_score=points, status=status,
            message=message, kind=CellKind.MANUAL, code=answer[-1] if answer else ""))
    return rows


def written_answer_blank(source: str) -> bool:
    """Whether a written answer is empty or still the release's ``YOUR ANSWER HERE`` stub."""
    return source.strip() in ("", TEXT_STUB)


def _run_all(works: list[NotebookWork], opts: Options) -> list[CellResult]:
    """Plan each notebook's job here as the executor asks for more (``opts.jobs`` local
    threads, or the dask cluster at ``opts.scheduler``: :mod:`.executors`), and judge each
    notebook as soon as its job returns; only the jobs in flight are held in memory."""
    progress = Progress(len(works), enabled=opts.progress and bool(works))
    results: list[CellResult] = []
    planned: dict[int, tuple[NotebookWork, dict[str, PreparedName]]] = {}

    def jobs():
        for i, work in enumerate(works):
            try:
                job, prepared = plan_notebook(work, opts)
            except Exception as exc:  # noqa: BLE001 - one broken notebook never stops the batch
                results.extend(_failed_notebook(work, exc))
                progress.update()
                continue
            planned[i] = (work, prepared)
            yield i, job

    try:
        executor = make_executor(opts.jobs, opts.scheduler)
        for i, outcome in executor.run(jobs(), opts.limits, opts.mode):
            work, prepared = planned.pop(i)
            results.extend(_failed_notebook(work, outcome) if isinstance(outcome, BaseException)
                           else judge_notebook(work, prepared, outcome, opts))
            progress.update()
    finally:
        progress.close()
    return results


def plan_notebook(work: NotebookWork,
                  opts: Options) -> tuple[NotebookJob, dict[str, PreparedName]]:
    """The sandbox's job for one notebook, and per graded name its drawn cases and hint."""
    prepared = {test.name: _prepare_name(work, test.name, opts) for test in work.names}
    job = NotebookJob(f"{work.student}--{work.src.name}", work.src.setup_source,
                      [p.job for p in prepared.values()], student=work.variant_id)
    return job, prepared


def judge_notebook(work: NotebookWork, prepared: dict[str, PreparedName],
                   runs: dict[str, NameRun], opts: Options) -> list[CellResult]:
    """Judge every graded name of one notebook from what its job returned; never raises."""
    try:
        held_hidden = any(not d.case.visible for p in prepared.values() for d in p.drawn)
        others = tuple(other_students(work.sub))
        return [judge_name(work, test, prepared[test.name], runs.get(test.name),
                           opts.reveal_hidden, show_output=opts.reveal_hidden or not held_hidden,
                           others=others)
                for test in work.names]
    except Exception as exc:  # noqa: BLE001 - one broken notebook never stops the batch
        return _failed_notebook(work, exc)


def _failed_notebook(work: NotebookWork, exc: BaseException) -> list[CellResult]:
    """``grader-error`` rows for every graded name of a notebook the grader failed on (the
    traceback goes to stderr)."""
    traceback.print_exception(type(exc), exc, exc.__traceback__)
    print(f"error: the grader failed on {work.student}/{work.src.name}", file=sys.stderr)
    return [graded_row(work.student, work.src.name, test, Status.GRADER_ERROR,
                       _grader_failed(exc)) for test in work.names]


def _prepare_name(work: NotebookWork, name: str, opts: Options) -> PreparedName:
    ex = REGISTRY[name]
    code = work.plan.python.get(work.plan.chosen[name], "")
    digest = job_digest(work.plan.cells)
    seed = case_seed(opts.secret, work.student, name, digest)
    drawn = draw(ex, seed)
    inputs = [CaseInput(tuple(d.case.args), dict(d.case.kwargs), d.result_cap) for d in drawn]
    calls = [(tuple(d.case.args), dict(d.case.kwargs)) for d in drawn[:50]]
    hint = answer_hint(code, name, ex.kind, calls)
    return PreparedName(NameJob(name, wire_kind(ex.kind), list(work.plan.cells), inputs),
                        drawn, hint)


def judge_name(work: NotebookWork, test: GradedTest, prepared: PreparedName,
               run: NameRun | None, reveal: bool, show_output: bool = True,
               others: tuple[str, ...] = ()) -> CellResult:
    """The :class:`CellResult` of one graded name from what its run returned.

    ``show_output`` False (a job that held hidden inputs, before the deadline): nothing the
    student's code printed or wrote into a message reaches the feedback.
    """
    ex = REGISTRY[test.name]
    code = work.sub.cells[work.plan.chosen[test.name]]["source"]
    row = functools.partial(graded_row, work.student, work.src.name, test)
    if run is None:
        return row(Status.GRADER_ERROR, "the sandbox returned nothing for this test; the "
                   "instructor will look into it", code=code)
    records = _records(ex, prepared.drawn, run, show_output)
    load_notes = keeping.load_notes(run, show_output)
    verdict = judging.judge_cell(judging.CellEvidence(
        ex, test.points, records, prepared.hint, defined=run.defined, load_notes=load_notes,
        notes=_notes(work.plan, work.variant, test.name), others=others, student=work.student,
        reveal=reveal))
    printed = (keeping.printed(run, records, reveal) if show_output
               else keeping.hidden_printed(run, records))
    return row(verdict.status, verdict.message, score=verdict.score,
               cases=[keeping.kept(r, reveal) for r in records], printed=printed,
               notes=list(verdict.notes) + load_notes, seconds=run.seconds, code=code,
               fits_other=verdict.fits_other)


def _notes(plan: CellPlan, variant: str, name: str) -> list[str]:
    """What planning found about the graded cell of ``name``, and whose numbers an item uses."""
    notes = list(plan.notes.get(name, []))
    if variant and REGISTRY[name].kind.is_item:
        notes.append(f"judged on the numbers and option letters of {variant}, the id this "
                     "notebook was worked for (the instructor's decision)")
    return notes


def _records(ex, drawn: list[DrawnCase], run: NameRun, show: bool = True) -> list[CaseRecord]:
    """The judged cases of one graded function; before the deadline a hidden case's reference
    use is not described."""
    records = []
    for i, (d, outcome) in enumerate(zip(drawn, run.outcomes, strict=True)):
        verdict, reason = judging.judge_case(ex, d.case, d.expected, outcome)
        if verdict is Verdict.REFERENCE_USED and not (show or d.case.visible):
            reason = f"used {OFF_LIMITS}"
        elif not show:
            reason = keeping.withheld_reason(verdict, outcome, d.case.raises) or reason
        # a value is shown only in the answer's own form: no text or other shape can carry
        # anything onto the feedback page
        returned = verdict in (Verdict.PASS, Verdict.WRONG_VALUE, Verdict.WRONG_SHAPE)
        shown = returned and judging.same_form(d.expected, outcome.value)
        records.append(CaseRecord(
            i, d.case.label, bool(d.case.visible), verdict, reason, args=tuple(d.case.args),
            kwargs=dict(d.case.kwargs), expected=d.expected,
            received=outcome.value if shown else None,
            raises=d.case.raises.__name__ if d.case.raises else "", printed=outcome.printed,
            shown=shown or not returned))
    return records
