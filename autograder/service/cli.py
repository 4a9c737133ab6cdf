"""``python -m autograder watch``: grade each submission as it arrives, with feedback at once.

    python -m autograder watch --exchange ROOT [--course COURSE] [--poll S] [--jobs N]
                               [--workers W] [--reference-seconds S] [--once]
                               [--unsafe-no-isolation]

Watches ``ROOT/4f9/inbound`` (nbgrader's exchange), journals every submission in
``COURSE/service/journal.db``, and for each: collects it by the private-exchange rules, grades
its changed notebooks in the sandbox within each notebook's budget, updates the gradebook's
automatic scores as the policy (``COURSE/grading_service.json``, :mod:`.policy`) says, and
releases a page per notebook through nbgrader's feedback exchange. See docs/grading-service.md.
Exit status 2 for a usage error (no inbound, a bad policy, no sandbox, an unreadable secret).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from ..course import COURSE_ID, DEFAULT_COURSE_ROOT, NOTEBOOKS_DIR, default_db_url
from ..grade.batch import Options
from ..grade.secret import read_secret
from ..grade.sources import default_sources, load_source
from ..isolation import UNSAFE_WARNING, IsolationUnavailable, Limits, Mode, probe
from . import budget, loop
from .grading import Service
from .journal import Journal
from .policy import load_policy


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``watch``; each help text states its default (``watch --help``)."""
    from ..grade.secret import DEFAULT_SECRET

    add = parser.add_argument
    add("--exchange", type=Path, required=True,
        help=f"nbgrader's exchange root (its {COURSE_ID}/inbound is watched); required")
    add("--course", "--course-root", dest="course", type=Path, default=DEFAULT_COURSE_ROOT,
        help="the nbgrader course folder (gradebook, submitted/, feedback/, "
        "grading_service.json, service/journal.db); default: %(default)s")
    add("--source", type=Path, default=None, help="folder of the source notebooks; default: "
        f"{NOTEBOOKS_DIR}")
    add("--db-url", default=None, help="the gradebook; default: sqlite:///COURSE/gradebook.db")
    add("--no-gradebook", action="store_true",
        help="feedback only, the gradebook untouched; default: off (the gradebook is updated)")
    add("--poll", type=float, default=2.0,
        help="seconds between looks at the inbound; default: %(default)g")
    add("--jobs", type=int, default=max(1, min(8, os.cpu_count() or 1)),
        help="sandboxes run in parallel for a submission's notebooks; default: the CPUs, at "
        "most 8 (here %(default)s)")
    add("--workers", type=int, default=2,
        help="submissions graded at once, each in a process of its own, sharing the --jobs "
        "sandboxes (1: one at a time in the service's process); default: %(default)s")
    add("--timeout", type=float, default=10.0,
        help="time limit per case, in seconds; default: %(default)g")
    add("--memory-mb", type=int, default=2048,
        help="memory limit of each sandbox, in MB; default: %(default)s")
    add("--secret-file", type=Path, default=None,
        help=f"the course secret (as for grade); default: {DEFAULT_SECRET}")
    add("--reference-seconds", type=float, default=None, help="take this as every notebook's "
        "reference cost; default: measured at start-up by grading the model answers once")
    add("--once", action="store_true",
        help="grade what is there, then stop; default: off (serve until stopped)")
    add("--unsafe-no-isolation", action="store_true",
        help="grade without the sandbox (never on real student work); default: off")


def _mode(args) -> Mode | None:
    try:
        return probe()
    except IsolationUnavailable as exc:
        if not args.unsafe_no_isolation:
            print(f"error: the grading sandbox is unavailable: {exc}", file=sys.stderr)
            return None
    print(UNSAFE_WARNING, file=sys.stderr)
    return Mode.UNSAFE


def hold_lock(course: Path):
    """The course's service lock (an open file holding ``flock``): two services grading the
    same journal would grade a submission twice. ``ValueError`` when another one holds it."""
    import fcntl

    path = Path(course) / "service" / "watch.lock"
    path.parent.mkdir(parents=True, exist_ok=True)
    fh = open(path, "w")
    try:
        fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as exc:
        fh.close()
        raise ValueError(f"another `watch` is already serving {course} ({path} is locked)"
                         ) from exc
    return fh


def build(args) -> Service:
    """The service the arguments describe; ``ValueError`` when they cannot work."""
    inbound = Path(args.exchange) / COURSE_ID / "inbound"
    if not inbound.is_dir():
        raise ValueError(f"{inbound} is not a folder (the exchange's inbound)")
    policy = load_policy(args.course)
    paths = sorted(Path(args.source).glob("q[0-9]*_*.ipynb")) if args.source \
        else default_sources()
    if not paths:
        raise ValueError("no source notebooks found")
    sources = [load_source(p) for p in paths]
    journal = Path(args.course) / "service" / "journal.db"
    try:     # a course the service already graded never gets a new secret silently
        secret = read_secret(args.secret_file, str(journal) if journal.exists() else "")
    except (OSError, ValueError) as exc:
        raise ValueError(f"cannot read the course secret: {exc}") from exc
    mode = _mode(args)
    if mode is None:
        raise ValueError("no sandbox")
    limits = Limits(case_timeout=args.timeout, load_timeout=30.0 + args.timeout,
                    memory_mb=args.memory_mb)
    opts = Options(out=Path(args.course) / "service", jobs=max(1, args.jobs), limits=limits,
                   secret=secret, mode=mode, progress=False)
    costs = ({s.name: args.reference_seconds for s in sources}
             if args.reference_seconds else budget.measure(sources, opts))
    budgets = budget.budgets(costs, policy, budget.hang_allowance(sources, args.timeout))
    print("time budget per notebook: " + ", ".join(f"{k} {v:.0f} s (reference {costs[k]:.1f} "
          f"s)" for k, v in budgets.items()), file=sys.stderr)
    db_url = None if args.no_gradebook else (args.db_url or default_db_url(args.course))
    return Service(Path(args.course), inbound, Path(args.exchange),
                   Journal(journal), policy, sources,
                   opts, budgets, db_url, workers=max(1, args.workers))


def main(args: argparse.Namespace) -> int:
    """Serve; the exit status."""
    try:
        lock = hold_lock(args.course)
        svc = build(args)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    try:
        loop.run(svc, poll=args.poll, rounds=1 if args.once else None)
    except KeyboardInterrupt:
        print("stopped; queued submissions wait in the journal", file=sys.stderr)
    finally:
        svc.journal.close()
        lock.close()
    return 0
