"""The student versions, as ``python -m autograder release`` writes them.

- the command writes exactly one release notebook per source notebook into ``OUT/tripos2006/``
  and nothing else;
- no release notebook contains a solution, a hidden test, the in-kernel checker import or a
  model answer (checked here independently of the command's own leak check);
- every release notebook runs to the end with ``allow_errors=True`` and every error in it is
  the ``NotImplementedError`` of an nbgrader stub (checked by ``ename``; the only other error
  allowed is the ``NameError`` a multiple-choice test cell raises for the very answer variable
  whose solution cell was stubbed), and every auto-graded test cell fails (so an untouched
  release can earn no automatic marks).
"""

from __future__ import annotations

import subprocess
import sys

import pytest
from nbtools import CELL_TIMEOUT, errors, execute_shared, graded_items, nbgrader_meta, read

from autograder.course import ASSIGNMENT, NOTEBOOKS_DIR, TEXT_STUB, nbgrader_env, source_notebooks
from autograder.service.policy import PARAGRAPH_MARK

NOTEBOOKS = source_notebooks()
#: one worker runs this module and test_student_experience.py, which share each notebook's run
pytestmark = [pytest.mark.skipif(not NOTEBOOKS, reason="no notebooks/q*.ipynb yet"),
              pytest.mark.xdist_group("release_runs")]

MARKERS = ("BEGIN SOLUTION", "END SOLUTION", "BEGIN HIDDEN TESTS", "END HIDDEN TESTS",
           "autograder.incell")


@pytest.fixture(scope="module")
def released(tmp_path_factory, course, repo_root):
    """``{stem: path}`` of the notebooks written by ``python -m autograder release``."""
    out = tmp_path_factory.mktemp("release_out")
    proc = subprocess.run(
        [sys.executable, "-m", "autograder", "release", "--out", str(out),
         "--course-root", str(course.root), "--no-student-bundle"],  # the wheel: test_student_bundle
        cwd=repo_root, env=nbgrader_env(), capture_output=True, text=True, timeout=600, check=False,
    )
    assert proc.returncode == 0, f"release failed:\n{proc.stdout}\n{proc.stderr}"
    files = sorted((out / ASSIGNMENT).iterdir())
    assert [p.name for p in files] == [p.name for p in NOTEBOOKS], \
        f"release wrote {[p.name for p in files]}, expected one notebook per source"
    assert sorted(p.name for p in out.iterdir()) == [ASSIGNMENT], "release wrote extra files"
    return {p.stem: p for p in files}


def _leaked(source: str, begin: str, end: str, release: str) -> list[str]:
    """Code lines between ``begin`` and ``end`` in ``source`` that also appear in ``release``
    (lines that the source also has outside such a region are not counted)."""
    inside, outside, region = set(), set(), False
    for line in source.splitlines():
        text = line.strip()
        if text.startswith(begin):
            region = True
        elif text.startswith(end):
            region = False
        elif text and not text.startswith("#"):
            (inside if region else outside).add(text)
    shown = {ln.strip() for ln in release.splitlines()}
    return sorted((inside - outside) & shown)


@pytest.mark.parametrize("source", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_release_hides_solutions(released, source):
    src, rel = read(source), read(released[source.stem])
    for i, cell in enumerate(rel.cells):
        for marker in MARKERS:
            assert marker not in cell.source, f"cell {i} of the release contains {marker!r}"
    src_cells = {nbgrader_meta(c).get("grade_id"): c for c in src.cells if nbgrader_meta(c)}
    rel_cells = {nbgrader_meta(c).get("grade_id"): c for c in rel.cells if nbgrader_meta(c)}
    assert rel_cells.keys() == src_cells.keys(), "the release lost or gained nbgrader cells"
    for gid, cell in src_cells.items():
        meta, rcell = nbgrader_meta(cell), rel_cells[gid]
        if cell.cell_type == "markdown" and meta.get("solution"):
            assert rcell.source.strip() == TEXT_STUB, f"{gid}: model answer reached the release"
        elif cell.cell_type == "code" and meta.get("solution"):
            assert "raise NotImplementedError()" in rcell.source, f"{gid}: no stub in the release"
            leaked = _leaked(cell.source, "### BEGIN SOLUTION", "### END SOLUTION", rcell.source)
            assert not leaked, f"{gid}: solution lines reached the release: {leaked[:3]}"
        if "### BEGIN HIDDEN TESTS" in cell.source:
            leaked = _leaked(cell.source, "### BEGIN HIDDEN TESTS", "### END HIDDEN TESTS",
                             rcell.source)
            assert not leaked, f"{gid}: hidden tests reached the release: {leaked[:3]}"
        for out in rcell.get("outputs", []):
            pytest.fail(f"{gid}: the release carries an output: {str(out)[:200]}")


@pytest.mark.parametrize("source", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_release_leaves_out_every_items_explanation(released, source):
    """An item's explanation reaches the student with the feedback, not in the release: no
    explanation cell of the source (and none of its paragraphs) is in the student version, and
    every other markdown cell is."""
    src, rel = read(source), read(released[source.stem])
    explained = [c.source for c in src.cells if "explanation" in c.metadata.get("tags", [])]
    # the first markdown cell also ends with the grading policy (test_release_policy.py)
    shown = [c.source.split(PARAGRAPH_MARK, 1)[0].rstrip() for c in rel.cells
             if c.cell_type == "markdown"]
    for text in explained:
        first = text.strip().splitlines()[0]
        assert not any(first in r for r in shown), f"an explanation reached the release: {first}"
    kept = [c.source for c in src.cells if c.cell_type == "markdown"
            and "explanation" not in c.metadata.get("tags", []) and not nbgrader_meta(c)]
    assert all(k.rstrip() in shown for k in kept), \
        "the release lost a markdown cell that is not an explanation"


@pytest.mark.slow
@pytest.mark.timeout(900)
@pytest.mark.parametrize("source", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_release_errors_only_at_stubs(released, source):
    nb = execute_shared(released[source.stem], cwd=NOTEBOOKS_DIR, timeout=CELL_TIMEOUT)
    found = errors(nb)
    # the one consequence of a stub that is not itself a NotImplementedError: a multiple-choice
    # answer cell is replaced by the stub, so its variable never exists and its test cell's
    # visible check raises NameError on exactly that name
    stubbed = {e.grade_id for e in found if e.ename == "NotImplementedError" and e.grade_id}
    others = [
        str(e) for e in found
        if e.ename != "NotImplementedError"
        and not (e.ename == "NameError" and e.grade_id and e.grade_id.startswith("test_")
                 and e.grade_id[5:] in stubbed
                 and e.evalue == f"name '{e.grade_id[5:]}' is not defined")
    ]
    assert not others, "errors other than a stub's NotImplementedError:\n" + "\n".join(others)
    failed_tests = {e.grade_id for e in found}
    items = graded_items(read(source))
    assert items, "no auto-graded items found"
    passing = sorted(f"test_{name}" for name in items if f"test_{name}" not in failed_tests)
    assert not passing, f"test cells that pass on the untouched stubs: {passing}"


def test_leak_check_rejects_source_notebooks():
    """The release command's own guard: fed the instructor's notebooks (which do hold solutions
    and hidden tests), it must refuse them and name what leaks."""
    from autograder.release import ReleaseLeak, check_release

    with pytest.raises(ReleaseLeak) as info:
        check_release(NOTEBOOKS)
    message = str(info.value)
    assert "BEGIN SOLUTION" in message and "BEGIN HIDDEN TESTS" in message
    if any(c.cell_type == "markdown" and nbgrader_meta(c).get("solution")
           for p in NOTEBOOKS for c in read(p).cells):
        assert "manually graded answer" in message  # the model answers with their rubrics
    for path in NOTEBOOKS:
        assert path.name in message
