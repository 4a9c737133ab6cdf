"""Compare two grade snapshots byte for byte: the check that a refactor changed no grade.

Usage::

    # before the change, then after it (a fixed --basetemp keeps the paths in messages equal)
    GRADES_SNAPSHOT=/tmp/before .venv/bin/python -m pytest tests/grading/test_bank.py \\
        tests/grading/test_attacks.py -q -p no:randomly -n 0 --basetemp=/tmp/grades-base
    GRADES_SNAPSHOT=/tmp/after  .venv/bin/python -m pytest ... (the same command)
    python tests/tools/compare_grades.py /tmp/before /tmp/after

Every ``python -m autograder grade`` the grading tests run (``gradingtools.run_grade``) leaves
its ``grades.csv`` and feedback pages under ``$GRADES_SNAPSHOT/<test>--<n>/``. This script
compares every file present in both snapshots and exits 1 on the first difference it lists
(``--csv-only``: only the ``grades.csv`` files). Runs present in one snapshot only are listed,
not failed (a partial run of the suite).
"""

from __future__ import annotations

import argparse
import difflib
import sys
from pathlib import Path


def _files(root: Path, csv_only: bool) -> dict[str, Path]:
    pattern = "*/grades.csv" if csv_only else "**/*"
    return {str(p.relative_to(root)): p for p in root.glob(pattern) if p.is_file()}


def compare(before: Path, after: Path, csv_only: bool = False) -> int:
    """Print the differences between two snapshots; the number of files that differ."""
    a, b = _files(before, csv_only), _files(after, csv_only)
    if not a or not b:
        raise ValueError(f"an empty snapshot: {before} has {len(a)} files, {after} {len(b)}")
    runs_a = {k.split("/")[0] for k in a}
    runs_b = {k.split("/")[0] for k in b}
    for run in sorted(runs_a ^ runs_b):
        print(f"only in {'before' if run in runs_a else 'after'}: {run}")
    differ = 0
    common = sorted(k for k in a.keys() & b.keys())
    for key in common:
        if a[key].read_bytes() != b[key].read_bytes():
            differ += 1
            print(f"DIFFERS: {key}")
            lines = difflib.unified_diff(
                a[key].read_text("utf-8", "replace").splitlines(),
                b[key].read_text("utf-8", "replace").splitlines(), "before", "after", lineterm="")
            print("\n".join(list(lines)[:40]))
    for key in sorted(a.keys() ^ b.keys()):
        if key.split("/")[0] in runs_a & runs_b:
            differ += 1
            print(f"DIFFERS (file in one snapshot only): {key}")
    print(f"{len(common)} files compared in {len(runs_a & runs_b)} runs; {differ} differ")
    return differ


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before", type=Path)
    parser.add_argument("after", type=Path)
    parser.add_argument("--csv-only", action="store_true", help="compare only grades.csv")
    args = parser.parse_args(argv)
    return 1 if compare(args.before, args.after, args.csv_only) else 0


if __name__ == "__main__":
    sys.exit(main())
