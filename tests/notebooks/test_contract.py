"""The notebooks against the exercise contract and the house conventions.

- ``../shared/tools/check_contract.py`` (the contract's own checker) reports 0 shortfalls;
- notebooks are committed with outputs cleared, kernel ``python3``, nbgrader schema 3;
- grade_ids are unique across the whole assignment (nbgrader restores cells by grade_id);
- the "your numbers" items (registry kind ``value``) are practice: their test cells carry 0 points;
  every other graded cell has points > 0, and each notebook totals 20 marks;
- the setup cell comes first and is locked;
- the auto-graded items of a notebook (solution cell ``name`` + graded test cell ``test_name``)
  are exactly the registry's entries for that notebook, of the same kind, and every test cell
  ends with the hidden ``check("name", name)`` of its item.
"""

from __future__ import annotations

import re
import subprocess
import sys
from collections import Counter

import pytest
from nbtools import all_points, graded_items, nbgrader_meta, read

from autograder.course import REPO_ROOT, source_notebooks
from autograder.facts import MARKS_PER_NOTEBOOK

NOTEBOOKS = source_notebooks()
CHECKER = REPO_ROOT.parent / "shared" / "tools" / "check_contract.py"
ids = [p.stem for p in NOTEBOOKS]


@pytest.mark.skipif(not CHECKER.exists(),
                    reason=f"{CHECKER} not found (no ../shared beside the repository)")
def test_contract_checker_reports_no_shortfalls():
    proc = subprocess.run([sys.executable, str(CHECKER)], cwd=REPO_ROOT, capture_output=True,
                          check=False,
                          text=True, timeout=120)
    summary = re.search(r"contract: (\d+) functions, (\d+) shortfalls", proc.stdout)
    assert summary, f"unexpected checker output:\n{proc.stdout}\n{proc.stderr}"
    assert int(summary.group(1)) > 0
    assert summary.group(2) == "0" and proc.returncode == 0, proc.stdout


@pytest.mark.parametrize("path", NOTEBOOKS, ids=ids)
def test_committed_cleared(path):
    nb = read(path)
    assert nb.nbformat == 4
    assert nb.metadata.get("kernelspec", {}).get("name") == "python3"
    dirty = [i for i, c in enumerate(nb.cells)
             if c.cell_type == "code" and (c.get("outputs") or c.get("execution_count"))]
    assert not dirty, f"cells {dirty} carry outputs: run jupyter nbconvert --clear-output --inplace"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=ids)
def test_cell_metadata(path):
    nb = read(path)
    metas = [(c, nbgrader_meta(c)) for c in nb.cells if nbgrader_meta(c)]
    for cell, meta in metas:
        assert meta.get("schema_version") == 3, meta
        assert meta.get("grade_id"), f"an nbgrader cell without grade_id: {cell.source[:60]!r}"
        if meta.get("grade") and cell.cell_type == "code":
            assert meta.get("locked"), f"{meta['grade_id']}: test cells must be locked"
    first_code = next(c for c in nb.cells if c.cell_type == "code")
    setup = nbgrader_meta(first_code)
    assert setup.get("grade_id") == f"setup_{path.stem}", "the first code cell is the setup cell"
    assert setup.get("locked") and not setup.get("grade") and not setup.get("solution")


def test_grade_ids_unique_across_assignment():
    if not NOTEBOOKS:
        pytest.skip("no notebooks/q*.ipynb yet")
    where = Counter()
    for path in NOTEBOOKS:
        for cell in read(path).cells:
            gid = nbgrader_meta(cell).get("grade_id")
            if gid:
                where[gid] += 1
    dup = sorted(g for g, n in where.items() if n > 1)
    assert not dup, f"grade_ids used more than once: {dup}"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=ids)
def test_points(path):
    points = all_points(read(path))
    assert points, "no graded cells"
    from autograder.exercises import for_notebook

    practice = {f"test_{ex.name}" for ex in for_notebook(path.stem) if ex.kind == "value"}
    assert practice and practice <= set(points), (practice, sorted(points))
    # a number item is answered by typing what a shipped explorer or one's own function gives:
    # the marks sit on the functions the grader runs itself
    assert {g: points[g] for g in practice} == dict.fromkeys(practice, 0.0)
    earning = {g: p for g, p in points.items() if g not in practice}
    assert all(p > 0 for p in earning.values()), {g: p for g, p in earning.items() if p <= 0}
    assert sum(points.values()) == pytest.approx(MARKS_PER_NOTEBOOK), points


@pytest.mark.parametrize("path", NOTEBOOKS, ids=ids)
def test_graded_items_match_registry(path):
    from autograder.exercises import for_notebook

    nb = read(path)
    items = graded_items(nb)
    registered = {ex.name: ex.kind for ex in for_notebook(path.stem)}
    assert sorted(items) == sorted(registered), (
        f"in the notebook only: {sorted(set(items) - set(registered))}; "
        f"in the registry only: {sorted(set(registered) - set(items))}")
    assert items == registered, "a function/choice kind differs between notebook and registry"
    tests = {nbgrader_meta(c).get("grade_id"): c.source for c in nb.cells}
    for name in items:
        hidden = tests[f"test_{name}"].split("### BEGIN HIDDEN TESTS", 1)
        assert len(hidden) == 2, f"test_{name} has no hidden tests"
        assert re.search(rf"check\(\s*['\"]{name}['\"]\s*,\s*{name}\s*\)", hidden[1]), \
            f"test_{name}: the hidden part does not call check({name!r}, {name})"
