"""Counts and marks stated in prose agree with the registry and the cells' ``points``.

The facts are the registry (``autograder/exercises/``) and each graded cell's nbgrader
``points``; the notebooks' intro tables, part headers and prompts ("*[1 mark]*"), the docs'
counts ("all 36 graded functions") and the registry modules' docstrings are copies, which
``autograder.facts`` and ``autograder.marks`` read (``python -m autograder facts --check``).
The oracles here are ``nbtools`` (the notebook tests' own reading of the cells) and edits of
scratch copies whose effect is known, so that each check is seen to fail when a copy drifts.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from nbtools import all_points, autograded_points, graded_items, read

from autograder import facts, marks
from autograder.course import REPO_ROOT, source_notebooks

NOTEBOOKS = source_notebooks()
ids = [p.stem for p in NOTEBOOKS]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=ids)
def test_intro_table_part_headers_and_prompts_state_the_cells_points(path):
    found = marks.problems(marks.notebook_marks(path), facts.MARKS_PER_NOTEBOOK)
    assert found == []


@pytest.mark.parametrize("path", NOTEBOOKS, ids=ids)
def test_every_graded_cell_belongs_to_one_part_and_one_prompt(path):
    """The parts and prompts the reader finds partition the points nbtools reads."""
    read_back = marks.notebook_marks(path)
    points = all_points(read(path))
    assert read_back.points == points
    in_parts = {g: p for part in read_back.parts for g, p in part.cells.items()}
    assert in_parts == points and not read_back.outside
    earning = {g: p for g, p in points.items() if p > 0}
    prompted = {g: p for pr in read_back.prompts for g, p in pr.cells.items() if p > 0}
    assert prompted == earning
    assert len(read_back.table) == len(read_back.parts) >= 2


def test_course_counts_are_the_notebooks_counts():
    """The registry's counts against the cells nbtools finds in the notebooks."""
    found = facts.course_facts()
    kinds, automatic = [], 0.0
    for path in NOTEBOOKS:
        nb = read(path)
        items = graded_items(nb)
        kinds += items.values()
        pts = autograded_points(nb)
        automatic += sum(pts[f"test_{name}"] for name in items)
    assert found["graded functions"] == kinds.count("function") > 0
    assert found["multiple-choice items"] == kinds.count("choice") > 0
    assert found["number items"] == kinds.count("value") > 0
    assert found["automatically graded cells"] == len(kinds)
    assert found["automatic marks"] == pytest.approx(automatic, abs=1e-9)


def test_docs_notebook_intros_and_registry_docstrings_state_the_counts():
    assert facts.problems() == []


@pytest.mark.parametrize("sentence, fact, stated", [
    ("the wheel leaves out all 37 graded functions' references", "graded functions", 37),
    ("Not one of the 12 graded functions", "graded functions", 12),
    ("(all 36 references and the helpers)", "graded functions", 36),
    ("the 64 automatic marks are unchanged", "automatic marks", 64),
    ("500 students on all 76 automatically graded cells", "automatically graded cells", 76),
    ("every question notebook is worth **20 marks**", "marks per notebook", 20),
])
def test_each_kind_of_doc_claim_is_read(sentence, fact, stated):
    """A pattern that matches nothing checks nothing: each reads the wording the docs use."""
    facts_now = facts.course_facts()
    found = facts._claims_in(f"Some text;\n{sentence}, more.", "doc", facts.DOC_CLAIMS, facts_now)
    assert [(c.fact, c.stated) for c in found] == [(fact, stated)]


def test_the_notebooks_counts_in_words_are_read():
    assert {c.fact for c in facts.notebook_claims()} == {"function", "choice", "value"}


def _scratch(tmp_path: Path) -> Path:
    """A copy of what the checks read: notebooks, docs, the registry's modules."""
    root = tmp_path / "repo"
    shutil.copytree(REPO_ROOT / "notebooks", root / "notebooks")
    shutil.copytree(REPO_ROOT / "docs", root / "docs", ignore=shutil.ignore_patterns("images"))
    shutil.copytree(REPO_ROOT / "autograder" / "exercises", root / "autograder" / "exercises")
    for name in ("README.md", "CONTRIBUTING.md"):
        shutil.copy(REPO_ROOT / name, root / name)
    return root


def _set_points(path: Path, grade_id: str, points: float) -> None:
    nb = json.loads(path.read_text(encoding="utf-8"))
    for cell in nb["cells"]:
        if cell["metadata"].get("nbgrader", {}).get("grade_id") == grade_id:
            cell["metadata"]["nbgrader"]["points"] = points
    path.write_text(json.dumps(nb, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")


def test_a_moved_mark_is_named_in_every_place_that_states_it(tmp_path):
    """Half a mark moved from reflect (part (a)) to phong (part (b)) of q5 without the text:
    both parts' headers and intro rows and both prompts are named."""
    root = _scratch(tmp_path)
    q5 = root / "notebooks" / "q5_phong.ipynb"
    _set_points(q5, "test_reflect", 1.0)
    _set_points(q5, "test_phong", 3.5)
    found = "\n".join(marks.problems(marks.notebook_marks(q5), facts.MARKS_PER_NOTEBOOK))
    assert "part (a): the header says 8 marks, its cells carry 7.5" in found
    assert "part (b): the header says 4 marks, its cells carry 4.5" in found
    assert "part (a): the intro table says 8 marks" in found
    assert "part (b): the intro table says 4 marks" in found
    assert "'[½ + 1½ marks]' covers cells carrying 1.5" in found
    assert "'[3 marks]' covers cells carrying 3.5" in found
    assert "add up to" not in found            # the notebook still totals 20


def test_a_count_typed_into_the_docs_is_named(tmp_path):
    root = _scratch(tmp_path)
    doc = root / "docs" / "students-copy.md"
    n = facts.course_facts()["graded functions"]
    doc.write_text(doc.read_text(encoding="utf-8") + f"\nAll {n + 1} graded functions.\n",
                   encoding="utf-8")
    wrong = [c for c in facts.doc_claims(root) if c.stated != c.actual]
    assert [(c.where, c.stated, c.actual) for c in wrong] == [
        ("docs/students-copy.md", n + 1, n)]


def test_a_notebook_intro_count_in_words_is_named(tmp_path):
    root = _scratch(tmp_path)
    q3 = root / "notebooks" / "q3_marching_cubes.ipynb"
    nb = json.loads(q3.read_text(encoding="utf-8"))
    nb["cells"][0]["source"] = "".join(nb["cells"][0]["source"]).replace(
        "Nine short functions", "Ten short functions")
    q3.write_text(json.dumps(nb, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    wrong = [str(c) for c in facts.notebook_claims(root) if c.stated != c.actual]
    assert wrong == ["notebooks/q3_marching_cubes.ipynb (intro): 'Ten short functions' says "
                     "10; the count of function is 9"]


def test_a_bad_notebook_is_a_clear_value_error(tmp_path):
    bad = tmp_path / "q9_broken.ipynb"
    bad.write_text("{not json", encoding="utf-8")
    with pytest.raises(ValueError, match="q9_broken.ipynb: not a readable notebook"):
        marks.notebook_marks(bad)


@pytest.mark.parametrize("text, marks_", [("8 (4 multiple choice × ½ + 6 written)", 8.0),
                                          ("1 choice + 1½ written + 1½ code (`f`); yours", 4.0),
                                          ("½", 0.5), ("7", 7.0)])
def test_table_marks_reads_the_notebooks_wordings(text, marks_):
    assert marks.table_marks(text) == pytest.approx(marks_, abs=1e-12)


def test_facts_command_checks_and_prints(capsys):
    from autograder.__main__ import main

    assert main(["facts", "--check"]) == 0
    out = capsys.readouterr().out
    n = facts.course_facts()["graded functions"]
    assert f"graded functions: {n}" in out and "q5_phong: 20 marks" in out
