"""The batch: one isolated job per (student, notebook), judged as soon as it returns.

For every student and source notebook :func:`grade_batch` reads the submission, plans its cells,
and (for the graded names it has) builds one :class:`NotebookJob` whose cases are drawn per
student (:mod:`.cases`). The jobs run on an executor (:mod:`.executors`): ``--jobs`` threads
each waiting on a local sandbox, or the workers of a dask cluster (``--scheduler``); each
returned :class:`~autograder.model.NameRun` is judged at once (:mod:`autograder.judging`) and
only what the outputs need is kept: verdicts, reasons, small values or summaries of big ones,
and hidden cases' details only when they are to be revealed. So the grader's memory does not
grow with what students return, whatever the batch's size.
"""

from __future__ import annotations

import sys
import traceback
from dataclasses import dataclass, field, replace
from pathlib import Path

from .. import judging
from ..course import ASSIGNMENT, TEXT_STUB
from ..exercises import REGISTRY
from ..isolation import CaseInput, Limits, Mode, NameJob, NotebookJob
from ..isolation.allowlist import OFF_LIMITS
from ..isolation.jobs import CHOICE, FUNCTION
from ..model import (AnswerHint, AnswerShape, Batch, CaseOutcome, CaseRecord, CellKind,
                     CellResult, NameRun, OutcomeKind, SourceNotebook, Status, Submission, Verdict)
from .cases import DrawnCase, case_seed, draw, job_digest
from .executors import make_executor
from .planning import MAX_CELL_CODE, NOT_TYPED, CellPlan, answer_hint, plan_cells, typed_answer
from .progress import Progress
from .reading import MAX_NOTEBOOK_MB, discover_students, read_submission
from .whose import other_students

#: Characters of printed output kept per graded cell for its feedback.
PRINTED_CAP = 20_000


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
    names: list[tuple[str, str, float]]     #: (name, test grade_id, points)
    variant: str = ""                       #: whose numbers and letters (default: the student)

    @property
    def variant_id(self) -> str:
        return self.variant or self.student


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
            work = _read_and_prepare(submitted, student, src, opts, subs, results)
            if work is not None:
                works.append(work)
    results.extend(_run_all(works, opts))
    order = {s.name: i for i, s in enumerate(sources)}
    cell_order = {(s.name, c.meta.get("grade_id")): i for s in sources
                  for i, c in enumerate(s.cells)}
    results.sort(key=lambda r: (r.student, order.get(r.notebook, 99),
                                cell_order.get((r.notebook, r.grade_id), 999)))
    return Batch(results, subs, list(students))


def _read_and_prepare(submitted: Path, student: str, src: SourceNotebook, opts: Options,
                      subs: dict, results: list[CellResult]) -> NotebookWork | None:
    """Read and plan one notebook; an internal error gives that notebook ``grader-error`` rows
    (the traceback on stderr) and never stops the batch."""
    rows: list[CellResult] = []
    try:
        sub = read_submission(submitted / student / ASSIGNMENT, student, src.name,
                              opts.max_notebook_mb)
        subs[(student, src.name)] = sub
        work = _prepare(student, src, sub, rows)
        if work is not None:
            work.variant = opts.graded_as.get(student, "")
    except Exception as exc:  # noqa: BLE001 - one broken notebook never stops the batch
        traceback.print_exc()
        print(f"error: the grader failed on {student}/{src.name}", file=sys.stderr)
        results.extend(CellResult(student, src.name, test_id, name, 0.0, points,
                                  Status.GRADER_ERROR, _grader_failed(exc), kind=_kind(name))
                       for name, test_id, points in src.graded)
        return None
    results.extend(rows)
    return work


def _grader_failed(exc: BaseException) -> str:
    return (f"the grader failed on this test ({type(exc).__name__}); the instructor will look "
            "into it")


def _prepare(student: str, src: SourceNotebook, sub: Submission,
             results: list[CellResult]) -> NotebookWork | None:
    """Rows that need no sandbox go to ``results``; the rest becomes a :class:`NotebookWork`."""
    if sub.status is not Status.OK:
        for name, test_id, points in src.graded:
            results.append(CellResult(student, src.name, test_id, name, 0.0, points, sub.status,
                                      sub.message, kind=_kind(name), whole_notebook=True))
        for gid, points in src.manual:
            results.append(CellResult(student, src.name, gid, gid, 0.0, points, sub.status,
                                      sub.message, kind=CellKind.MANUAL, whole_notebook=True))
        return None
    plan = plan_cells(src, sub)
    sub.found_by_name = dict(plan.by_name)
    names = []
    for name, test_id, points in src.graded:
        if name not in REGISTRY:
            results.append(CellResult(
                student, src.name, test_id, name, 0.0, points, Status.GRADER_ERROR,
                f"the autograder has no rule for {test_id} (instructor: register {name!r} in "
                "autograder/exercises)"))
        elif name in plan.blocked:
            status, message = plan.blocked[name]
            code = sub.cells[plan.chosen[name]]["source"]
            results.append(CellResult(student, src.name, test_id, name, 0.0, points, status,
                                      message, kind=_kind(name),
                                      code=code if len(code) <= MAX_CELL_CODE else ""))
        elif name in plan.missing:
            results.append(CellResult(
                student, src.name, test_id, name, 0.0, points, Status.MISSING,
                f"no solution cell for {name}: the cell (grade_id {name!r}) was deleted and no "
                "other cell defines it; copy it back from the released notebook, answer it and "
                "resubmit", kind=_kind(name)))
        else:
            names.append((name, test_id, points))
    results.extend(_manual_rows(student, src, sub))
    return NotebookWork(student, src, sub, plan, names) if names else None


def _kind(name: str) -> CellKind:
    ex = REGISTRY.get(name)
    return CellKind(ex.kind) if ex is not None else CellKind.FUNCTION


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
            student, src.name, gid, gid, None if status is Status.MANUAL else 0.0, points,
            status, message, kind=CellKind.MANUAL, code=answer[-1] if answer else ""))
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
    planned: dict[int, tuple[NotebookWork, dict]] = {}

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


def plan_notebook(work: NotebookWork, opts: Options) -> tuple[NotebookJob, dict]:
    """The sandbox's job for one notebook, and per graded name its drawn cases and hint."""
    prepared = {name: _prepare_name(work, name, opts) for name, _, _ in work.names}
    job = NotebookJob(f"{work.student}--{work.src.name}", work.src.setup_source,
                      [p[0] for p in prepared.values()], student=work.variant_id)
    return job, prepared


def judge_notebook(work: NotebookWork, prepared: dict, runs: dict[str, NameRun],
                   opts: Options) -> list[CellResult]:
    """Judge every graded name of one notebook from what its job returned; never raises."""
    try:
        held_hidden = any(not d.case.visible for _job, drawn, _hint in prepared.values()
                          for d in drawn)
        others = other_students(work.sub)
        return [judge_name(work, name, test_id, points, prepared[name][1], prepared[name][2],
                           runs.get(name), opts.reveal_hidden,
                           show_output=opts.reveal_hidden or not held_hidden, others=others)
                for name, test_id, points in work.names]
    except Exception as exc:  # noqa: BLE001 - one broken notebook never stops the batch
        return _failed_notebook(work, exc)


def _failed_notebook(work: NotebookWork, exc: BaseException) -> list[CellResult]:
    """``grader-error`` rows for every graded name of a notebook the grader failed on (the
    traceback goes to stderr)."""
    traceback.print_exception(type(exc), exc, exc.__traceback__)
    print(f"error: the grader failed on {work.student}/{work.src.name}", file=sys.stderr)
    return [CellResult(work.student, work.src.name, test_id, name, 0.0, points,
                       Status.GRADER_ERROR, _grader_failed(exc), kind=_kind(name))
            for name, test_id, points in work.names]


def _prepare_name(work: NotebookWork, name: str,
                  opts: Options) -> tuple[NameJob, list[DrawnCase], AnswerHint]:
    ex = REGISTRY[name]
    code = work.plan.python.get(work.plan.chosen[name], "")
    kind = CellKind(ex.kind)
    if kind is not CellKind.FUNCTION:
        drawn = []
        inputs = [CaseInput((), {}, 2**16)]
    else:
        digest = job_digest(work.plan.cells)
        seed = case_seed(opts.secret, work.student, name, digest)
        drawn = draw(ex, seed)
        inputs = [CaseInput(tuple(d.case.args), dict(d.case.kwargs), d.result_cap)
                  for d in drawn]
    calls = [(tuple(d.case.args), dict(d.case.kwargs)) for d in drawn[:50]]
    hint = answer_hint(code, name, kind, calls)
    job_kind = FUNCTION if kind is CellKind.FUNCTION else CHOICE   # a choice or value: a variable
    return NameJob(name, job_kind, list(work.plan.cells), inputs), drawn, hint


def judge_name(work: NotebookWork, name: str, test_id: str, points: float,
               drawn: list[DrawnCase], hint: AnswerHint, run: NameRun | None,
               reveal: bool, show_output: bool = True, others=()) -> CellResult:
    """The :class:`CellResult` of one graded name from what its run returned.

    ``show_output`` False (a job that held hidden inputs, before the deadline): nothing the
    student's code printed or wrote into a message reaches the feedback (red-team finding 1).
    """
    ex = REGISTRY[name]
    kind = CellKind(ex.kind)
    code = work.sub.cells[work.plan.chosen[name]]["source"]
    if run is None:
        return CellResult(work.student, work.src.name, test_id, name, 0.0, points,
                          Status.GRADER_ERROR, "the sandbox returned nothing for this test; "
                          "the instructor will look into it", kind=kind, code=code)
    typed = NOT_TYPED
    if kind is not CellKind.FUNCTION:
        typed = typed_answer(work.plan.python.get(work.plan.chosen[name], ""), name)
        if typed is not NOT_TYPED:      # judged on what the cell types, not on what ran
            run = replace(run, outcomes=[CaseOutcome(0, OutcomeKind.RETURNED, value=typed)])
    records = _records(ex, kind, drawn, run, show_output, work.variant_id)
    load_notes = _load_notes(run, show_output)
    score, status, message = judging.summarise(records, points, kind)
    if kind is not CellKind.FUNCTION and typed is NOT_TYPED and hint.shape is AnswerShape.WRITTEN:
        score, status, message = 0.0, Status.FAILED, judging.not_typed(name, kind)
    if hint.reference and kind is CellKind.FUNCTION:
        score, status, message = 0.0, *judging.reference_imported(name, hint.reference)
    elif score == 0 and status not in (Status.REFERENCE_USED, Status.REJECTED_CODE):
        why = "; ".join(judging.clip(n, 200) for n in load_notes[-3:])
        override = judging.unanswered_or_broken(name, kind, hint, run.defined, why)
        if override is not None:
            status, message = override
    notes = list(work.plan.notes.get(name, []))
    if work.variant and kind is not CellKind.FUNCTION:
        notes.append(f"judged on the numbers and option letters of {work.variant}, the id this "
                     "notebook was worked for (the instructor's decision)")
    fits = _fits_other(ex, run, others) if kind in (CellKind.CHOICE, CellKind.VALUE) and \
        status is not Status.OK else ""
    if fits and reveal:
        notes.append(_fits_note(ex, fits, work.student))
    if notes:
        message += ". Note: " + "; ".join(notes)
    printed = _printed(run, records, reveal) if show_output else _hidden_printed(run, records)
    return CellResult(work.student, work.src.name, test_id, name, score, points, status,
                      message, kind=kind, cases=[_kept(r, reveal) for r in records],
                      printed=printed, notes=notes + load_notes,
                      seconds=run.seconds, code=code, fits_other=fits,
                      answer=None if typed is NOT_TYPED else typed)


#: What stands for the student's own text while hidden tests are not revealed.
HIDDEN_OUTPUT = ("not shown before the deadline, because this notebook has hidden tests; run "
                 "your notebook yourself to see it")


def _load_notes(run: NameRun, show: bool) -> list[str]:
    """The notes of running the cells (their text is the student's: error messages, names)."""
    if show or not run.load_notes:
        return list(run.load_notes)
    return [f"{len(run.load_notes)} message(s) from running your cells: {HIDDEN_OUTPUT}"]


def _hidden_printed(run: NameRun, records: list[CaseRecord]) -> str:
    printed = run.printed.strip() or any(r.printed.strip() for r in records)
    return f"(what your code printed is {HIDDEN_OUTPUT})" if printed else ""


def _fits_other(ex, run: NameRun, others) -> str:
    """The first of ``others`` (ids the notebook names) whose numbers or letters this wrong
    answer fits, else ``""``."""
    for other in others:
        try:
            verdict, _ = judging.judge_item(ex, run.outcomes[0], other)
        except Exception:  # noqa: BLE001 - a note only; never fail the grading over it
            continue
        if verdict is Verdict.PASS:
            return other
    return ""


def _fits_note(ex, other: str, student: str) -> str:
    what = "option letters" if ex.kind == "choice" else "numbers"
    return (f"this answer fits the {what} of student {other}, not yours ({student}): every "
            f"student answers on their own {what}, and the grade uses yours")


def _records(ex, kind: CellKind, drawn: list[DrawnCase], run: NameRun,
             show: bool = True, student: str | None = None) -> list[CaseRecord]:
    if kind is not CellKind.FUNCTION:
        verdict, reason = judging.judge_item(ex, run.outcomes[0], student)
        return [CaseRecord(0, "your answer", True, verdict, reason)]
    records = []
    for i, (d, outcome) in enumerate(zip(drawn, run.outcomes, strict=True)):
        verdict, reason = judging.judge_case(ex, d.case, d.expected, outcome)
        if verdict is Verdict.REFERENCE_USED and not (show or d.case.visible):
            reason = f"used {OFF_LIMITS}"
        received = outcome.value if verdict in (Verdict.PASS, Verdict.WRONG_VALUE,
                                                Verdict.WRONG_SHAPE) else None
        records.append(CaseRecord(
            i, d.case.label, bool(d.case.visible), verdict, reason, args=tuple(d.case.args),
            kwargs=dict(d.case.kwargs), expected=d.expected, received=received,
            raises=d.case.raises.__name__ if d.case.raises else "", printed=outcome.printed))
    return records


def _kept(r: CaseRecord, reveal: bool) -> CaseRecord:
    """What the outputs keep of a record: hidden details only when revealed, big values summarised."""
    if not r.visible and not (reveal and r.verdict is not Verdict.PASS):
        return CaseRecord(r.index, "", False, r.verdict)
    keep = judging.keep
    return CaseRecord(r.index, r.label, r.visible, r.verdict, r.reason,
                      args=keep(tuple(r.args)), kwargs={k: keep(v) for k, v in r.kwargs.items()},
                      expected=keep(r.expected), received=keep(r.received), raises=r.raises,
                      printed=judging.clip_block(r.printed, 2000))


def _printed(run: NameRun, records: list[CaseRecord], reveal: bool) -> str:
    """The solution cells' output, then what the visible (and, revealed, hidden) cases printed."""
    parts = [run.printed] if run.printed.strip() else []
    for r in records:
        if r.printed.strip() and (r.visible or reveal):
            parts.append(f"--- while running {r.label or f'case {r.index + 1}'} ---\n{r.printed}")
    return judging.clip_block("\n".join(parts), PRINTED_CAP)
