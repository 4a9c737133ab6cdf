"""Helpers for the notebook tests: execute with nbclient, read nbgrader cell metadata."""

from __future__ import annotations

import copy
import hashlib
import os
import re
from dataclasses import dataclass
from pathlib import Path

import nbformat
from nbclient import NotebookClient

#: Per-cell timeout (s) when the tests execute a notebook (nbgrader's own is set in course.py).
CELL_TIMEOUT = 120


def read(path: Path) -> nbformat.NotebookNode:
    return nbformat.read(str(path), as_version=4)


def execute(path: Path, cwd: Path, allow_errors: bool = False, timeout: int = CELL_TIMEOUT):
    """Run ``path`` top to bottom in a fresh ``python3`` kernel with working directory ``cwd``.

    With ``allow_errors=False`` the first failing cell raises ``nbclient`` 's
    ``CellExecutionError`` (its message names the cell and shows the traceback).
    """
    nb = read(path)
    client = NotebookClient(
        nb,
        timeout=timeout,
        kernel_name="python3",
        allow_errors=allow_errors,
        resources={"metadata": {"path": str(cwd)}},
    )
    client.execute()
    return nb


#: what a kernel inherits from the test that changes a run: the student id, home, font cache
_RUN_ENV = ("JUPYTERHUB_USER", "HOME", "MPLCONFIGDIR")
_RUNS: dict = {}


def execute_shared(path: Path, cwd: Path, timeout: int = CELL_TIMEOUT):
    """``execute(path, cwd, allow_errors=True)``, run once per test process for the same
    notebook bytes, working folder, timeout and environment; each caller gets its own copy.

    The release notebooks are run by two test modules (errors only at the stubs; Run All goes
    through): one run serves both. Without ``allow_errors`` nbclient would have stopped at
    :func:`first_untagged_error`, which callers that need Run All to go through check.
    """
    key = (hashlib.sha256(Path(path).read_bytes()).hexdigest(), str(cwd), timeout,
           tuple(os.environ.get(k) for k in _RUN_ENV))
    if key not in _RUNS:
        _RUNS[key] = execute(path, cwd, allow_errors=True, timeout=timeout)
    return copy.deepcopy(_RUNS[key])


def first_untagged_error(nb) -> str | None:
    """The error nbclient's ``allow_errors=False`` stops Run All at (as JupyterLab does): the
    first error output of a code cell not tagged ``raises-exception``, with its traceback."""
    for i, cell in enumerate(nb.cells):
        if cell.cell_type != "code" or "raises-exception" in cell.metadata.get("tags", []):
            continue
        for out in cell.get("outputs", []):
            if out.get("output_type") == "error":
                trace = re.sub(r"\x1b\[[0-9;]*m", "", "\n".join(out.get("traceback", [])))
                return f"cell {i}: {cell.source[:200]}\n{out.get('ename')}: {out.get('evalue')}\n{trace}"
    return None


def nbgrader_meta(cell) -> dict:
    return cell.get("metadata", {}).get("nbgrader", {}) or {}


@dataclass(frozen=True)
class CellError:
    index: int
    grade_id: str | None
    ename: str
    evalue: str

    def __str__(self) -> str:
        where = f"cell {self.index}" + (f" ({self.grade_id})" if self.grade_id else "")
        return f"{where}: {self.ename}: {self.evalue[:200]}"


def errors(nb) -> list[CellError]:
    """Every error output of an executed notebook."""
    found = []
    for i, cell in enumerate(nb.cells):
        if cell.cell_type != "code":
            continue
        for out in cell.get("outputs", []):
            if out.get("output_type") == "error":
                found.append(CellError(i, nbgrader_meta(cell).get("grade_id"),
                                       out.get("ename", ""), out.get("evalue", "")))
    return found


def graded_items(nb) -> dict[str, str]:
    """``{name: kind}`` of the auto-graded items of a notebook.

    An item is a code solution cell whose grade_id ``name`` has a graded test cell
    ``test_<name>``; its kind is ``"function"`` when the cell defines ``def name(``,
    ``"choice"`` when an ``options_<name>`` cell lists its options (in each student's order)
    and ``"value"`` (a number item on the student's own numbers) otherwise.
    """
    cells = {nbgrader_meta(c).get("grade_id"): c for c in nb.cells if nbgrader_meta(c)}
    items = {}
    for gid, cell in cells.items():
        meta = nbgrader_meta(cell)
        if cell.cell_type != "code" or not meta.get("solution"):
            continue
        test = cells.get(f"test_{gid}")
        if test is None or not nbgrader_meta(test).get("grade"):
            continue
        defines = re.search(rf"^\s*def {re.escape(gid)}\(", cell.source, re.MULTILINE)
        items[gid] = ("function" if defines else
                      "choice" if f"options_{gid}" in cells else "value")
    return items


def graded_in(module: str) -> tuple[str, ...]:
    """The graded functions whose reference is in ``course_lib.<module>``, from the registry
    (a typed list would miss a function added later); the students' wheel leaves them out."""
    from autograder.exercises import REGISTRY

    return tuple(ex.name for ex in REGISTRY.values() if ex.kind == "function"
                 and ex.reference.__module__ == f"course_lib.{module}")


def autograded_points(nb) -> dict[str, float]:
    """``{grade_id: points}`` of the auto-graded (code) test cells."""
    return {
        nbgrader_meta(c)["grade_id"]: float(nbgrader_meta(c).get("points", 0))
        for c in nb.cells
        if c.cell_type == "code" and nbgrader_meta(c).get("grade")
    }


def all_points(nb) -> dict[str, float]:
    """``{grade_id: points}`` of every graded cell, auto-graded and manually graded."""
    return {
        nbgrader_meta(c)["grade_id"]: float(nbgrader_meta(c).get("points", 0))
        for c in nb.cells
        if nbgrader_meta(c).get("grade")
    }


def errors_beyond_stubs(found: list[CellError]) -> list[str]:
    """The errors of an executed release notebook that a stub does not explain.

    A stub raises ``NotImplementedError``; the one other consequence of a stub is the
    ``NameError`` a multiple-choice test cell raises for the very answer variable whose solution
    cell was stubbed (the variable never exists).
    """
    stubbed = {e.grade_id for e in found if e.ename == "NotImplementedError" and e.grade_id}
    return [
        str(e) for e in found
        if e.ename != "NotImplementedError"
        and not (e.ename == "NameError" and e.grade_id and e.grade_id.startswith("test_")
                 and e.grade_id[5:] in stubbed
                 and e.evalue == f"name '{e.grade_id[5:]}' is not defined")
    ]


def option_texts(nb, name: str, student: str = "ci-student") -> dict[str, str]:
    """``{letter: text}`` of multiple-choice item ``name`` in the canonical order: the item's
    options in ``course_lib.item_options``, or the list its ``options_<name>`` cell hands to
    ``mine.options`` (each student sees them shuffled; options
    written with the student's numbers are filled in with ``student``'s)."""
    import ast

    cell = next((c for c in nb.cells if nbgrader_meta(c).get("grade_id") == f"options_{name}"),
                None)
    if cell is None:
        return {}
    call = ast.parse(cell.source).body[0].value
    if len(call.args) == 1:          # the item's own options, kept in course_lib.item_options
        from course_lib.variants import item_texts

        return dict(zip("abcdefgh", item_texts(call.args[0].value)))
    try:
        texts = ast.literal_eval(call.args[1])
    except ValueError:       # options that use the student's numbers (f-strings over ``mine``)
        from autograder.exercises import REGISTRY
        from course_lib.variants import variant

        mine = variant(REGISTRY[name].notebook, student)
        texts = eval(compile(ast.Expression(call.args[1]), "<options>", "eval"), {"mine": mine})
    return dict(zip("abcdefgh", texts))
