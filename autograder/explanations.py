"""An item's explanation reaches the student with the feedback, never in the release.

In a source notebook, a markdown cell that explains one or more auto-graded items (why the key
is right, why each other option is wrong) carries the cell tag ``explanation`` and names the
items it explains in its metadata::

    {"tags": ["explanation"], "explains": ["q5_item1"]}

:func:`strip` removes such cells from the student versions (``autograder.course`` runs it on
every notebook nbgrader releases; ``autograder.release`` refuses a release that still holds one),
so reading on past an item gives nothing of its key away; :func:`of_notebook` collects them from
the instructor's notebook for the feedback page, which shows each item's explanation once the
failing hidden cases are revealed (``grade --reveal-hidden``, after the due date).
"""

from __future__ import annotations

from pathlib import Path

import nbformat

#: The cell tag of an explanation cell.
TAG = "explanation"


def is_explanation(cell) -> bool:
    """Whether ``cell`` (a notebook cell) is an item's explanation."""
    return TAG in (cell.get("metadata", {}).get("tags") or [])


def explained_items(cell) -> list[str]:
    """The items an explanation cell names (``metadata.explains``)."""
    names = cell.get("metadata", {}).get("explains") or []
    return [str(n) for n in names]


def of_notebook(path: Path) -> dict[str, list[str]]:
    """``{item name: [markdown source, ...]}`` of the explanation cells of notebook ``path``,
    in notebook order. ``ValueError`` for an explanation cell that names no item or is not
    markdown (it would be shown to no one, or run)."""
    nb = nbformat.read(str(path), as_version=4)
    found: dict[str, list[str]] = {}
    for i, cell in enumerate(nb.cells):
        if not is_explanation(cell):
            continue
        names = explained_items(cell)
        if cell.cell_type != "markdown" or not names:
            raise ValueError(f"{Path(path).name} cell {i}: an explanation cell must be markdown "
                             "and name the items it explains in metadata 'explains'")
        for name in names:
            found.setdefault(name, []).append(cell.source)
    return found


def strip(path: Path) -> int:
    """Remove the explanation cells of notebook ``path`` in place; return how many there were
    (the file is rewritten only when there were some)."""
    nb = nbformat.read(str(path), as_version=4)
    kept = [cell for cell in nb.cells if not is_explanation(cell)]
    removed = len(nb.cells) - len(kept)
    if removed:
        nb.cells = kept
        nbformat.write(nb, str(path))
    return removed
