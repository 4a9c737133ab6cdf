"""``python -m autograder release``: the student versions of ``tripos2006``.

The student notebooks come out of nbgrader's own ``generate_assignment`` (run in an nbgrader
course root, ``course/`` at the repository root unless ``--course-root`` says otherwise, whose
gradebook then holds the assignment for grading). They are copied to ``--out/tripos2006/`` only
after a leak check: no solution or hidden-test delimiters, no import of the in-kernel checker
(``autograder.incell``), no model answer of a manually graded cell, no item's explanation
(:mod:`autograder.explanations`: it comes with the feedback), no outputs; and every
solution and test code cell tagged ``raises-exception``, so that Run All on an untouched release
runs past the stubs to every figure and explorer. Each notebook's first cell ends with the
grading service's policy in words, from ``COURSE_ROOT/grading_service.json`` at release time
(:func:`autograder.course.state_policy`). With ``--out`` the command also writes what
students install, ``--out/student/`` (a wheel of ``course_lib`` whose graded references are
compiled, and a README: :mod:`autograder.student_bundle`).

    python -m autograder release --out dist/   # -> dist/tripos2006/q1_imaging.ipynb ...
                                               #    dist/student/4f9_course_student-*.whl, README.md
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

import nbformat

from . import explanations, student_bundle
from .cells import CellRole, cell_role
from .course import (
    ASSIGNMENT,
    DEFAULT_COURSE_ROOT,
    TEXT_STUB,
    CourseDir,
    prepare_course,
    source_notebooks,
)

#: Text that must never reach a student (checked in every cell of every release notebook).
FORBIDDEN = (
    "BEGIN SOLUTION",
    "END SOLUTION",
    "BEGIN HIDDEN TESTS",
    "END HIDDEN TESTS",
    "autograder.incell",
)


#: Cell tag that lets Run All (JupyterLab, nbclient) continue past a cell that raises.
RUN_ALL_TAG = "raises-exception"


class ReleaseLeak(RuntimeError):
    """A release notebook contains something a student must not see."""


class ReleaseNotRunnable(RuntimeError):
    """Run All on an untouched release notebook would stop at a stub or a failing test."""


def leaks(notebook: Path) -> list[str]:
    """Every problem that makes ``notebook`` unfit to give to a student (empty when fine)."""
    nb = nbformat.read(str(notebook), as_version=4)
    problems = []
    for i, cell in enumerate(nb.cells):
        meta = cell.get("metadata", {}).get("nbgrader", {})
        where = f"{notebook.name} cell {i}"
        if meta.get("grade_id"):
            where += f" ({meta['grade_id']})"
        for marker in FORBIDDEN:
            if marker.lower() in cell.source.lower():
                problems.append(f"{where}: contains {marker!r}")
        if (cell.cell_type == "markdown" and cell_role(meta) is CellRole.MANUAL
                and cell.source.strip() != TEXT_STUB):
            problems.append(f"{where}: a manually graded answer cell is not the stub {TEXT_STUB!r}")
        if explanations.is_explanation(cell):
            problems.append(f"{where}: an item's explanation (it reaches students with the "
                            "feedback, not in the release)")
        if cell.cell_type == "code" and (cell.get("outputs") or cell.get("execution_count")):
            problems.append(f"{where}: carries outputs")
    return problems


def untagged_cells(notebook: Path) -> list[str]:
    """Solution and test code cells of ``notebook`` without the ``raises-exception`` tag.

    On an untouched release every solution cell is a stub that raises and every test cell fails;
    the tag (kept by nbgrader from the source notebook) lets Run All go on to the figures below.
    """
    nb = nbformat.read(str(notebook), as_version=4)
    problems = []
    for i, cell in enumerate(nb.cells):
        meta = cell.get("metadata", {})
        grading = meta.get("nbgrader", {})
        if cell.cell_type != "code" or cell_role(grading) is CellRole.OTHER:
            continue
        if RUN_ALL_TAG not in meta.get("tags", []):
            problems.append(f"{notebook.name} cell {i} ({grading.get('grade_id')}): "
                            f"no {RUN_ALL_TAG!r} tag")
    return problems


def check_release(notebooks: list[Path]) -> None:
    """Raise :class:`ReleaseLeak` listing every leak in ``notebooks``, then
    :class:`ReleaseNotRunnable` listing every solution/test cell that would stop Run All."""
    problems = [p for nb in notebooks for p in leaks(Path(nb))]
    if problems:
        raise ReleaseLeak(
            "the student versions would leak instructor material:\n  " + "\n  ".join(problems)
        )
    untagged = [p for nb in notebooks for p in untagged_cells(Path(nb))]
    if untagged:
        raise ReleaseNotRunnable(
            "Run All would stop on these cells (tag them in the source notebook):\n  "
            + "\n  ".join(untagged)
        )


def release(out: Path | None = None, course_root: Path | None = None) -> list[Path]:
    """Generate the student versions and copy them to ``out/tripos2006/``; return their paths.

    With ``out`` ``None`` the notebooks stay in ``<course_root>/release/tripos2006/``.
    """
    course: CourseDir = prepare_course(Path(course_root or DEFAULT_COURSE_ROOT))
    released = course.release_notebooks()
    check_release(released)
    if out is None:
        return released
    dest = Path(out).resolve() / ASSIGNMENT
    if dest == course.release_dir.resolve():
        return released
    dest.mkdir(parents=True, exist_ok=True)
    written = []
    for nb in released:
        target = dest / nb.name
        shutil.copyfile(nb, target)
        written.append(target)
    return written


def release_for_students(out: Path, course_root: Path, build_cache: Path | None = None) -> list[Path]:
    """:func:`release` to ``out/tripos2006/`` plus the students' wheel and README in ``out/student/``."""
    written = release(out, course_root)
    cache = build_cache if build_cache is not None else student_bundle.default_build_cache(course_root)
    return written + student_bundle.write_bundle(out, cache)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.description = "Write the student versions of the assignment through nbgrader."
    parser.add_argument(
        "--out", type=Path, default=None,
        help=f"write DIR/{ASSIGNMENT}/*.ipynb (default: leave them in COURSE_ROOT/release/)",
    )
    parser.add_argument(
        "--course-root", type=Path, default=DEFAULT_COURSE_ROOT,
        help="the nbgrader course root holding source/, release/ and the gradebook "
             f"(default: {DEFAULT_COURSE_ROOT})",
    )
    parser.add_argument(
        "--no-student-bundle", action="store_true",
        help="with --out, write only the notebooks, not DIR/student/ (the wheel and its README)",
    )
    parser.add_argument(
        "--build-cache", type=Path, default=None,
        help="folder keeping compiled student wheels between runs "
             "(default: COURSE_ROOT/.student-build)",
    )


def main(args: argparse.Namespace) -> int:
    if not source_notebooks():
        print("error: no notebooks/q*.ipynb to release", file=sys.stderr)
        return 1
    try:
        if args.out is not None and not args.no_student_bundle:
            written = release_for_students(args.out, args.course_root, args.build_cache)
        else:
            written = release(args.out, args.course_root)
    except (ReleaseLeak, student_bundle.WheelLeak) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except (RuntimeError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    for path in written:
        print(path)
    return 0
