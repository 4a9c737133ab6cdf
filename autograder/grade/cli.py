"""``python -m autograder grade``: the command line.

    python -m autograder grade SUBMITTED --out OUT [--jobs N | --scheduler tcp://HOST:PORT]
                                                   [--timeout S] [--db-url URL]
                                                   [--reveal-hidden] [--secret-file F]
                                                   [--unsafe-no-isolation]

``SUBMITTED`` has nbgrader's layout, ``SUBMITTED/<student>/tripos2006/<notebook>.ipynb``. The
grader refuses to run when the operating-system sandbox is unavailable (exit status 2, with
why) unless ``--unsafe-no-isolation`` is given, which it announces loudly. Writes
``OUT/grades.csv``, ``OUT/items.csv`` (:mod:`~autograder.outputs.items`),
``OUT/feedback/<student>/<notebook>.html``, ``OUT/report.html`` and keeps
nbgrader's gradebook and ``autograded/`` notebooks in step. Exit status 0 whenever the batch was
graded, whatever the submissions did; 2 for a usage error (no such folder, no source notebooks,
unreadable secret, no sandbox, a gradebook URL whose database driver is not installed, a
``--scheduler`` that cannot be reached), said before any grading starts.
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import time
import traceback
from pathlib import Path

from ..isolation import UNSAFE_WARNING, IsolationUnavailable, Limits, Mode, probe
from ..outputs import csv as csv_output
from ..outputs import feedback, gradebook, items, report
from ..exercises import REGISTRY
from ..model import CellKind
from ..course import default_db_url
from ..outputs.gradebook_url import MissingDriver, resolve_db_url
from ..outputs.similarity import reference_source
from . import ownership, remedy
from ..service.incremental import grade_in_chunks, write_csv_atomic
from .batch import Options
from .executors import ClusterUnavailable
from .reading import MAX_NOTEBOOK_MB
from .secret import read_secret
from .sources import default_sources, load_source


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``grade`` (see the README's table)."""
    add = parser.add_argument
    add("submitted", type=Path,
        help="nbgrader's submitted folder: SUBMITTED/<student>/tripos2006/*.ipynb")
    add("--out", type=Path, required=True,
        help="output folder: grades.csv, feedback/, report.html, autograded/")
    add("--jobs", type=int, default=max(1, min(8, os.cpu_count() or 1)),
        help="sandboxes run in parallel (default: the number of CPUs, at most 8)")
    add("--scheduler", default=None, metavar="tcp://HOST:PORT", help="run the sandboxes on the "
        "workers of this dask.distributed scheduler instead of --jobs local ones (each worker "
        "host needs bubblewrap and the instructors' install; this machine needs no sandbox)")
    add("--timeout", type=float, default=10.0, help="time limit per case, in seconds (default 10)")
    add("--db-url", default=None, help="nbgrader gradebook URL (default sqlite:///<course root>/"
        "gradebook.db; postgresql://... for a shared server)")
    add("--reveal-hidden", action="store_true", help="after the deadline: show the failing "
        "hidden cases' inputs, expected and received values in the feedback")
    add("--secret-file", type=Path, default=None, help="the course secret that seeds the hidden "
        "cases (default ~/.config/4f9/secret; created when missing, but not once the course has "
        "grades, unless --new-secret)")
    add("--new-secret", action="store_true", help="create a new course secret even though the "
        "course already has grades (their hidden cases change on re-grade)")
    add("--source", type=Path, default=None,
        help="folder of the source notebooks (default: the course's notebooks/)")
    add("--load-timeout", type=float, default=None, help="seconds allowed for the setup and "
        "solution cells (default 30 + the per-case time limit)")
    add("--job-timeout", type=float, default=600.0, help="seconds one student's notebook may "
        "take in all (every graded name, every restart; default 600): cases not reached by "
        "then are not run")
    add("--memory-mb", type=int, default=2048,
        help="memory limit of each sandbox, in MB (default 2048)")
    add("--max-notebook-mb", type=float, default=MAX_NOTEBOOK_MB,
        help=f"larger notebook files are rejected (default {MAX_NOTEBOOK_MB:g})")
    add("--no-gradebook", action="store_true",
        help="do not touch nbgrader's gradebook or write autograded notebooks")
    add("--unsafe-no-isolation", action="store_true", help="grade even when the operating-system "
        "sandbox is unavailable (student code then runs with your rights: never on real work)")
    add("--quiet", action="store_true", help="no progress bar")
    add("--graded-as", action="append", default=[], metavar="STUDENT=ID[:REASON]",
        help="judge STUDENT's number items and option letters on ID's (the id the notebook was "
        "worked for, after an honest wrong STUDENT_ID); needs a reason (:REASON or --reason); "
        "logged in OUT/graded-as.log and re-applied by every later grade into OUT; "
        "STUDENT=STUDENT withdraws it (repeat for several students)")
    add("--reason", default="", help="why --graded-as was decided, for those without their "
        "own :REASON (written to the log)")


def _mode(args) -> Mode | None:
    """The sandbox mode, or None (after saying why) when grading must not start. With
    ``--scheduler`` the sandboxes are the workers': each worker host probes its own before
    every job (:func:`~autograder.grade.executors.run_sandboxed`), and never runs one
    unconfined, so this machine needs none and ``--unsafe-no-isolation`` is not honoured."""
    if args.scheduler:
        return Mode.ISOLATED
    try:
        return probe()
    except IsolationUnavailable as exc:
        if not args.unsafe_no_isolation:
            print(f"error: the grading sandbox is unavailable: {exc}\nFix it, or pass "
                  "--unsafe-no-isolation to grade without isolation (never on real student "
                  "work)", file=sys.stderr)
            return None
    print(UNSAFE_WARNING, file=sys.stderr)
    return Mode.UNSAFE


def _options(args, secret: bytes, mode: Mode) -> Options:
    limits = Limits(case_timeout=args.timeout,
                    load_timeout=args.load_timeout if args.load_timeout else 30.0 + args.timeout,
                    memory_mb=args.memory_mb, job_timeout=args.job_timeout)
    return Options(out=args.out, jobs=max(1, args.jobs), limits=limits, secret=secret,
                   reveal_hidden=args.reveal_hidden, mode=mode, scheduler=args.scheduler,
                   max_notebook_mb=args.max_notebook_mb, progress=not args.quiet,
                   graded_as=getattr(args, "graded_as_map", {}))


def _decisions(args) -> tuple[dict[str, str], list[remedy.Decision]]:
    """``{student: id}`` to judge on (the decisions standing in ``OUT/graded-as.log``,
    updated by this run's ``--graded-as``) and the new decisions to log, each said."""
    new = remedy.parse_graded_as(args.graded_as, args.reason, args.submitted)
    applied, changes = remedy.merge(remedy.standing(args.out), new)
    for d in changes:
        if d.withdrawn:
            print(d.describe(), file=sys.stderr)
    for d in sorted(applied.values(), key=lambda d: d.student):
        print(d.describe() + ("" if d in changes else f"  (from {args.out / remedy.LOG_NAME})"),
              file=sys.stderr)
    for s in sorted(set(new) - {d.student for d in changes}):
        if new[s].withdrawn:
            print(f"note: no --graded-as decision stands for {s}: nothing to withdraw",
                  file=sys.stderr)
    return {s: d.other for s, d in applied.items()}, changes


def _graded(args) -> str:
    """Where this course already has grades (``OUT/grades.csv``, a gradebook with
    submissions), or ``""``: a missing secret is then not silently re-created."""
    found = [str(args.out / "grades.csv")] if (args.out / "grades.csv").is_file() else []
    if not args.no_gradebook:
        db_url = args.db_url or default_db_url(gradebook.course_root(args.submitted, args.out))
        if gradebook.submission_count(db_url):
            found.append(f"the gradebook {db_url}")
    return " and ".join(found)


def _check_db_url(args) -> bool:
    """Resolve ``args.db_url`` (its driver named, :mod:`autograder.outputs.gradebook_url`);
    False, after saying why, when the gradebook could not be written."""
    if args.db_url is None or args.no_gradebook:
        return True
    try:
        args.db_url = resolve_db_url(args.db_url)
    except (MissingDriver, ValueError) as exc:
        print(f"error: --db-url: {exc}", file=sys.stderr)
        return False
    return True


def main(args: argparse.Namespace) -> int:
    """Grade ``args.submitted`` into ``args.out``; the exit status (see the module docstring)."""
    if not args.submitted.is_dir():
        print(f"error: {args.submitted} is not a folder", file=sys.stderr)
        return 2
    try:
        graded_as, changes = _decisions(args)
    except ValueError as exc:
        print(f"error: --graded-as: {exc}", file=sys.stderr)
        return 2
    paths = (sorted(Path(args.source).glob("q[0-9]*_*.ipynb")) if args.source
             else default_sources())
    if not paths:
        print("error: no source notebooks found", file=sys.stderr)
        return 2
    try:
        secret = read_secret(args.secret_file, "" if args.new_secret else _graded(args))
    except (OSError, ValueError) as exc:
        print(f"error: cannot read the course secret: {exc}", file=sys.stderr)
        return 2
    mode = _mode(args)
    if mode is None or not _check_db_url(args):
        return 2
    sources = [load_source(p) for p in paths]
    args.out.mkdir(parents=True, exist_ok=True)
    os.chmod(args.out, 0o700)
    args.graded_as_map = graded_as
    t0 = time.monotonic()
    try:
        # grades.csv after every chunk of students: a batch stopped early keeps what it graded
        batch = grade_in_chunks(args.submitted, sources, _options(args, secret, mode),
                                on_chunk=lambda b: write_csv_atomic(b, args.out / "grades.csv"))
    except ClusterUnavailable as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    # the decisions are logged first: report.html shows them beside the "Own numbers" evidence
    try:
        logged = [remedy.log(args.out, changes, batch)] if changes else []
        written = _write_outputs(batch, sources, args) + logged
    finally:
        _give_back(args)
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"graded {len(batch.students)} students, {len(batch.results)} cells in "
          f"{time.monotonic() - t0:.0f} s (grader peak memory {peak_mb:.0f} MB); wrote:\n"
          + "\n".join(f"  {w}" for w in written), file=sys.stderr)
    return 0


def _give_back(args) -> None:
    """Run as root (as grading must be), give what was written to the course folder's owner
    (:mod:`~autograder.grade.ownership`): the instructor marks and exports as themselves."""
    root = gradebook.course_root(args.submitted, args.out)
    trees = [args.out, root / "autograded", root / "gradebook.db", root / "gradebook.db-journal"]
    ownership.give_back(root, trees)
    if args.out.resolve() != root and not args.out.resolve().is_relative_to(root):
        ownership.give_back(args.out.parent, [args.out])


def _write_outputs(batch, sources, args) -> list[str]:
    """Write every output; what was written, one line each, for the closing message."""
    out: Path = args.out
    csv_output.write_csv(batch.results, out / "grades.csv")
    written = [f"{out / 'grades.csv'}  (the grader's automatic results)"]
    try:
        items.write_items_csv(items.item_statistics(items.responses(batch.results)),
                              out / "items.csv")
        written.append(f"{out / 'items.csv'}  (item analysis: facility, discrimination, flags)")
    except Exception as exc:  # noqa: BLE001 - grades.csv is written; the feedback follows
        traceback.print_exc(limit=3)
        print(f"warning: items.csv could not be written ({type(exc).__name__})", file=sys.stderr)
    pages = feedback.write_all(batch.results, out / "feedback", reveal_hidden=args.reveal_hidden,
                               ids=remedy.ids_of(batch, getattr(args, "graded_as_map", {})))
    written.append(f"{out / 'feedback'}/<student>/<notebook>.html  ({len(pages)} feedback pages)")
    try:
        report.write_report(batch.results, sources, out / "report.html",
                            references=reference_sources(batch.results), jobs=args.jobs,
                            graded_as=remedy.decisions(out, getattr(args, "graded_as_map", {})))
        written.append(f"{out / 'report.html'}  (histograms, failures, similar solutions)")
    except Exception as exc:  # noqa: BLE001 - the feedback is written; the gradebook follows
        traceback.print_exc(limit=3)
        print(f"warning: the report could not be written ({type(exc).__name__})",
              file=sys.stderr)
    if args.no_gradebook:
        return written
    try:
        root = gradebook.sync(batch, sources, submitted=args.submitted, out=out,
                              db_url=args.db_url)
        written.append(f"{args.db_url or default_db_url(root)}  (the gradebook) and "
                       f"{root / 'autograded'}/  (mark the written answers in the Formgrader)")
    except Exception as exc:  # noqa: BLE001 - grades.csv is written; say what failed
        traceback.print_exc(limit=3)
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        print(f"warning: the gradebook could not be updated ({type(exc).__name__}: {first}); "
              "grades.csv, the feedback and the report are complete", file=sys.stderr)
    return written


def reference_sources(results) -> dict[str, str]:
    """``{graded name: its course_lib reference's source}`` for the report's pasted-code check."""
    names = {r.name for r in results if r.name in REGISTRY}
    out = {}
    for name in sorted(names):
        reference = REGISTRY[name].reference
        if REGISTRY[name].kind is CellKind.FUNCTION and reference is not None:
            out[name] = reference_source(reference)
    return out
