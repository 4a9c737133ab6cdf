"""``python -m autograder feedback``: hand back marks, comments and test results.

    python -m autograder feedback --grading OUT [--course ROOT] [--db-url URL] [--no-release]
                                  [--require-marked]

Run after ``grade`` (``OUT`` is its ``--out``) and after marking. Writes one page per student
and notebook into ``ROOT/feedback/<student>/tripos2006/`` (only the pages whose content
changed) and releases them through nbgrader's exchange (``nbgrader release_feedback``), from
which students fetch them (``nbgrader fetch_feedback`` or the Assignments panel). See
:mod:`autograder.outputs.handback`. Written answers not marked yet are listed (a partial hand-back
is legitimate: their pages say "not marked yet"); with ``--require-marked`` they stop it (exit
status 1). Exit status 0 on success, 2 for a usage error.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .course import ASSIGNMENT, DEFAULT_COURSE_ROOT, default_db_url
from .outputs.gradebook_url import MissingDriver, resolve_db_url
from .grade.sources import default_sources, load_source
from .outputs import handback


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``feedback``."""
    add = parser.add_argument
    add("--grading", type=Path, required=True,
        help="the --out folder of `python -m autograder grade` (its feedback/ pages)")
    add("--course", "--course-root", dest="course", type=Path, default=DEFAULT_COURSE_ROOT,
        help="the nbgrader course root (default: course/ in the repository)")
    add("--db-url", default=None, help="the gradebook (default sqlite:///<course>/gradebook.db)")
    add("--no-release", action="store_true",
        help="write the pages only; do not run nbgrader release_feedback")
    add("--require-marked", action="store_true", help="refuse (exit status 1, nothing written "
        "or released) while a written answer is not marked yet")


#: Unmarked answers listed by name before "and N more".
LISTED = 20


def unmarked(marks: list[handback.NotebookMarks]) -> list[str]:
    """``student/notebook/grade_id`` of every written answer no marker has marked yet."""
    return [f"{nb.student}/{nb.notebook}/{m.grade_id}" for nb in marks for m in nb.marks
            if m.written and not m.marked]


def say_unmarked(waiting: list[str], refuse: bool) -> None:
    """Say which written answers are handed back unmarked (or, with ``refuse``, block it)."""
    if not waiting:
        return
    shown = ", ".join(waiting[:LISTED]) + (f" and {len(waiting) - LISTED} more"
                                           if len(waiting) > LISTED else "")
    if refuse:
        print(f"error: {len(waiting)} written answers are not marked yet: {shown}; mark them "
              "in the Formgrader, or hand back without --require-marked", file=sys.stderr)
    else:
        print(f"warning: {len(waiting)} written answers are not marked yet; their pages say "
              f"\"not marked yet\" until you mark them and run feedback again: {shown}",
              file=sys.stderr)


def main(args: argparse.Namespace) -> int:
    """Write the hand-back pages and release them; the exit status."""
    root = Path(args.course).resolve()
    if not (root / "autograded").is_dir() or not Path(args.grading).is_dir():
        print(f"error: run `python -m autograder grade` first: no {root / 'autograded'} or "
              f"no {args.grading} (a course folder other than ./course: pass --course DIR)",
              file=sys.stderr)
        return 2
    try:
        db_url = resolve_db_url(args.db_url or default_db_url(root))
    except (MissingDriver, ValueError) as exc:
        print(f"error: --db-url: {exc}", file=sys.stderr)
        return 2
    marks = handback.read_marks(db_url, handback.cell_order(
        [load_source(p) for p in default_sources()]))
    waiting = unmarked(marks)
    say_unmarked(waiting, args.require_marked)
    if waiting and args.require_marked:
        return 1
    written, unchanged = handback.write_pages(marks, Path(args.grading), root)
    print(f"feedback: {written} pages written, {unchanged} unchanged, in {root / 'feedback'}",
          file=sys.stderr)
    if args.no_release:
        return 0
    lacking = handback.missing_secrets(root)
    if lacking:
        print("warning: not released (no timestamp.txt or submission_secret.txt, i.e. not "
              f"collected through nbgrader's exchange): {', '.join(lacking)}", file=sys.stderr)
    handback.release(root, db_url, exclude=lacking)
    print("feedback released to the exchange: students run `nbgrader fetch_feedback "
          f"{ASSIGNMENT}` or use the Assignments panel", file=sys.stderr)
    return 0
