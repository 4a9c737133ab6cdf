"""``python -m autograder export``: final grades for Canvas, Moodle and the archive.

    python -m autograder export --out DIR [--course ROOT] [--db-url URL] [--decimals N]
                                [--due ISO] [--late-per-day PERCENT] [--allow-unmarked]
                                [--canvas-questions]

Writes ``DIR/canvas.csv``, ``DIR/moodle.csv``, ``DIR/grades-long.csv`` and ``DIR/items.csv``
(the item analysis of the final marks, written answers included) from nbgrader's gradebook
(see :mod:`autograder.outputs.export`). Refuses (exit status 1, listing them) while written
answers are unmarked, unless ``--allow-unmarked``. Exit status 2 for a usage error.
"""

from __future__ import annotations

import argparse
import datetime as dt
import sys
from pathlib import Path

from .course import ASSIGNMENT, DEFAULT_COURSE_ROOT, default_db_url
from .outputs.gradebook_url import MissingDriver, resolve_db_url
from .exercises import REGISTRY
from .model import CellKind
from .grade.sources import default_sources, load_source
from .outputs import export

#: Unmarked answers listed by name before "and N more".
LISTED = 20


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``export``."""
    add = parser.add_argument
    add("--out", type=Path, required=True, help="folder for canvas.csv, moodle.csv and "
        "grades-long.csv")
    add("--course", "--course-root", dest="course", type=Path, default=DEFAULT_COURSE_ROOT,
        help="the nbgrader course root (default: course/ in the repository)")
    add("--db-url", default=None, help="the gradebook (default sqlite:///<course>/gradebook.db)")
    add("--decimals", type=int, default=1, help="decimal places of every mark (default 1)")
    add("--due", default=None, help="due date, ISO 8601 in UTC (e.g. 2026-12-04T17:00); "
        "default: the assignment's due date in the gradebook, if any")
    add("--late-per-day", type=float, default=0.0, help="late penalty, percent of the "
        "assignment's marks per started day after the due date (default 0)")
    add("--canvas-questions", action="store_true", help="canvas.csv: one column per question "
        "(and the late penalty, negative) instead of the total alone")
    add("--allow-unmarked", action="store_true",
        help="export even while written answers are unmarked (they count 0)")


def _due(text: str | None) -> dt.datetime | None:
    if text is None:
        return None
    return dt.datetime.fromisoformat(text)


def main(args: argparse.Namespace) -> int:
    """Export the grades; the exit status (see the module docstring)."""
    root = Path(args.course).resolve()
    if not (root / "gradebook.db").is_file() and args.db_url is None:
        print(f"error: no gradebook in {root}: run `python -m autograder grade` first, or pass "
              "--course DIR (the course folder) or --db-url", file=sys.stderr)
        return 2
    try:
        due = _due(args.due)
    except ValueError:
        print(f"error: --due must be an ISO 8601 date, got {args.due!r}", file=sys.stderr)
        return 2
    sources = [load_source(p) for p in default_sources()]
    maxima = {s.name: sum(p for *_, p in s.graded) + sum(p for _, p in s.manual)
              for s in sources}
    try:
        db_url = resolve_db_url(args.db_url or default_db_url(root))
    except (MissingDriver, ValueError) as exc:
        print(f"error: --db-url: {exc}", file=sys.stderr)
        return 2
    rows = export.read_gradebook(db_url, list(maxima))
    waiting = export.unmarked(rows)
    if waiting:
        shown = ", ".join(waiting[:LISTED]) + (f" and {len(waiting) - LISTED} more"
                                               if len(waiting) > LISTED else "")
        print(f"{'warning' if args.allow_unmarked else 'error'}: {len(waiting)} written "
              f"answers are not marked yet: {shown}", file=sys.stderr)
        if not args.allow_unmarked:
            print("mark them in the Formgrader, or pass --allow-unmarked to count them as 0",
                  file=sys.stderr)
            return 1
    if args.late_per_day > 0:
        warn_without_due(export.without_due_date(rows, due), args.late_per_day)
    try:
        paths = export.write_all(rows, maxima, args.out, decimals=args.decimals,
                                 late_per_day=args.late_per_day, due=due,
                                 canvas_questions=args.canvas_questions)
        paths.append(export.write_items(rows, cell_kinds(sources), args.out))
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print("exported: " + ", ".join(str(p) for p in paths), file=sys.stderr)
    return 0


def warn_without_due(students: list[str], late_per_day: float) -> None:
    """Say loudly (stderr) that ``--late-per-day`` takes nothing from ``students``, and how to set
    the due date."""
    if not students:
        return
    shown = ", ".join(students[:LISTED]) + (f" and {len(students) - LISTED} more"
                                            if len(students) > LISTED else "")
    print(f"WARNING: --late-per-day {late_per_day:g} but no due date: neither --due nor the "
          f"gradebook gives one, so NO late penalty is taken from {len(students)} students "
          f"({shown}). Pass --due 2026-12-04T16:00 (UTC), or set the gradebook's due date in "
          f"course/: nbgrader db assignment add {ASSIGNMENT} --duedate=2026-12-04T16:00 (or "
          "the Formgrader's Manage Assignments: edit the assignment's due date)",
          file=sys.stderr)


def cell_kinds(sources) -> dict[tuple[str, str], str]:
    """``{(notebook, grade_id): kind}`` of every graded cell of ``sources`` (the gradebook names
    an automatically graded cell by its test cell's grade_id)."""
    kinds = {}
    for s in sources:
        for name, test_id, _ in s.graded:
            kinds[(s.name, test_id)] = (REGISTRY[name].kind if name in REGISTRY
                                         else CellKind.FUNCTION).value
        for gid, _ in s.manual:
            kinds[(s.name, gid)] = CellKind.MANUAL.value
    return kinds
