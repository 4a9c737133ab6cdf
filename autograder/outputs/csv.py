"""``grades.csv``: one row per (student, notebook, graded cell); columns
:data:`~autograder.model.CSV_COLUMNS`."""

from __future__ import annotations

import csv
from pathlib import Path

from ..model import CSV_COLUMNS, CellResult, csv_row


def write_csv(results: list[CellResult], path: Path) -> Path:
    """Write ``results`` (already in the batch's order) to ``path``."""
    with open(path, "w", newline="", encoding="utf-8", errors="replace") as f:
        writer = csv.DictWriter(f, fieldnames=list(CSV_COLUMNS))
        writer.writeheader()
        for r in results:
            writer.writerow(csv_row(r))
    return Path(path)
