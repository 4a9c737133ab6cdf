"""The instructor's source notebooks: what the grader takes from them (never from a submission)."""

from __future__ import annotations

import json
from pathlib import Path

from ..cells import CellRole, cell_role, join_source
from ..model import SourceCell, SourceNotebook


def load_source(path: Path) -> SourceNotebook:
    """Parse one source notebook: its setup cell, solution cells, tests and their points."""
    nb = json.loads(Path(path).read_text(encoding="utf-8"))
    name = Path(path).stem
    cells = []
    for i, c in enumerate(nb.get("cells", [])):
        meta = (c.get("metadata") or {}).get("nbgrader") or {}
        cells.append(SourceCell(i, c.get("cell_type", ""), join_source(c.get("source", "")), meta))
    setup = next((c for c in cells if c.meta.get("grade_id") == f"setup_{name}"), None)
    if setup is None:
        setup = next((c for c in cells if c.cell_type == "code"
                      and str(c.meta.get("grade_id", "")).startswith("setup")), None)
    solution_ids, graded, manual = [], [], []
    for c in cells:
        gid = c.meta.get("grade_id")
        if not gid:
            continue
        role = cell_role(c.meta)
        if c.cell_type == "code" and role is CellRole.ANSWER:
            solution_ids.append(gid)
        elif c.cell_type == "code" and role is CellRole.TESTS:
            target = gid[len("test_"):] if gid.startswith("test_") else gid
            graded.append((target, gid, float(c.meta.get("points", 0) or 0)))
        elif role is CellRole.MANUAL:
            manual.append((gid, float(c.meta.get("points", 0) or 0)))
    return SourceNotebook(name, Path(path), nb, setup.source if setup else "", cells,
                          solution_ids, graded, manual)


def default_sources() -> list[Path]:
    """The course's source notebooks (``notebooks/q*_*.ipynb``)."""
    from ..course import source_notebooks

    return source_notebooks()
