"""The instructor's source notebooks: what the grader takes from them (never from a submission)."""

from __future__ import annotations

import json
from pathlib import Path

from ..model import SourceCell, SourceNotebook


def join_source(source) -> str:
    """A notebook cell's ``source`` (a string or a list of strings) as one string."""
    if isinstance(source, list):
        return "".join(str(s) for s in source)
    return source if isinstance(source, str) else ""


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
        if c.cell_type == "code" and c.meta.get("solution") and not c.meta.get("grade"):
            solution_ids.append(gid)
        elif c.cell_type == "code" and c.meta.get("grade") and not c.meta.get("solution"):
            target = gid[len("test_"):] if gid.startswith("test_") else gid
            graded.append((target, gid, float(c.meta.get("points", 0) or 0)))
        elif c.meta.get("grade") and c.meta.get("solution"):
            manual.append((gid, float(c.meta.get("points", 0) or 0)))
    return SourceNotebook(name, Path(path), nb, setup.source if setup else "", cells,
                          solution_ids, graded, manual)


def default_sources() -> list[Path]:
    """The course's source notebooks (``notebooks/q*_*.ipynb``)."""
    from ..course import source_notebooks

    return source_notebooks()
