"""Issue 12 for q5_phong and q6_clipping: the items ask before the text tells, in one format.

- every written-answer cell has its prompt ("Written answer ...") in the markdown cell directly
  above it;
- every solution and test code cell carries the ``raises-exception`` tag, so Run All on an
  untouched release goes on past the stubs;
- multiple-choice items are labelled "Item Qn.k" with options (a)-(d), their visible test checks
  the form with ``choice_letters`` and never names the key, and the correct option is the
  strictly longest (in displayed characters) in at most a quarter of the items;
- each item comes before the explanation that answers it: the markdown cell that discusses an
  item ("Item Qn.k, explained" or the option letters of its distractors) follows its test cell.
"""

from __future__ import annotations

import re

import pytest
from nbtools import nbgrader_meta, option_texts, read

from autograder.course import NOTEBOOKS_DIR
from autograder.exercises import REGISTRY

STEMS = ("q5_phong", "q6_clipping")


def shown_length(text: str) -> int:
    """Characters a reader sees: LaTeX commands and markup dropped."""
    text = re.sub(r"\\[a-zA-Z]+", "", text)
    return len(re.sub(r"[${}*`]", "", text))


def choice_items(nb):
    """``(index of the question cell, name, options)`` of each multiple-choice item."""
    items = []
    for i, cell in enumerate(nb.cells):
        meta = nbgrader_meta(cell)
        ex = REGISTRY.get(meta.get("grade_id", ""))
        if cell.cell_type == "code" and meta.get("solution") and ex is not None \
                and ex.kind == "choice":
            question = next(j for j in range(i - 1, -1, -1) if nb.cells[j].cell_type == "markdown")
            items.append((question, ex, option_texts(nb, ex.name)))
    return items


@pytest.fixture(params=STEMS)
def nb(request):
    return read(NOTEBOOKS_DIR / f"{request.param}.ipynb")


def test_written_answers_have_their_prompt_directly_above(nb):
    for i, cell in enumerate(nb.cells):
        meta = nbgrader_meta(cell)
        if cell.cell_type == "markdown" and meta.get("solution"):
            above = nb.cells[i - 1]
            assert above.cell_type == "markdown" and not nbgrader_meta(above), meta["grade_id"]
            assert "Written answer" in above.source, meta["grade_id"]
            assert "Rubric" in cell.source and "for the prompt above" in cell.source


def test_solution_and_test_cells_are_tagged_for_run_all(nb):
    for cell in nb.cells:
        meta = nbgrader_meta(cell)
        if cell.cell_type == "code" and (meta.get("solution") or meta.get("grade")):
            assert "raises-exception" in cell.metadata.get("tags", []), meta["grade_id"]


def test_choice_items_format_and_form_of_the_correct_option(nb):
    items = choice_items(nb)
    assert len(items) >= 4
    longest = 0
    for question, ex, options in items:
        assert re.search(r"\*\*Item Q[56]\.\d\*\*", nb.cells[question].source), ex.name
        assert sorted(options) == ["a", "b", "c", "d"], ex.name
        test = next(c for c in nb.cells if nbgrader_meta(c).get("grade_id") == f"test_{ex.name}")
        visible = test.source.split("### BEGIN HIDDEN TESTS")[0]
        assert "choice_letters(" in visible, ex.name
        assert not re.search(r"==\s*['\"]", visible), f"{ex.name}: the visible test names a key"
        key = set(ex.answer) if not isinstance(ex.answer, str) else {ex.answer}
        lengths = {k: shown_length(v) for k, v in options.items()}
        best = max(lengths.values())
        if any(lengths[k] == best for k in key) and list(lengths.values()).count(best) == 1:
            longest += 1
    assert longest <= len(items) / 4, f"the key is the longest option in {longest} items"


def test_items_come_before_their_explanation(nb):
    for question, ex, _ in choice_items(nb):
        label = re.search(r"\*\*Item (Q\d\.\d)\*\*", nb.cells[question].source).group(1)
        test_at = next(i for i, c in enumerate(nb.cells)
                       if nbgrader_meta(c).get("grade_id") == f"test_{ex.name}")
        mentions = [i for i, c in enumerate(nb.cells)
                    if c.cell_type == "markdown" and i > question
                    and re.search(rf"Item\s+{re.escape(label)}\b", c.source)
                    and not nbgrader_meta(c)]
        assert mentions, f"Item {label} is never explained"
        assert min(mentions) > test_at, f"Item {label} is explained before it is answered"
