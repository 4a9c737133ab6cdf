"""Items that ask before they tell: no answer is given away by an answer variable's name, by the
notebook's explanation cells (which the release leaves out) or by the options cell's source.

Oracles: the registry's keys (``autograder.exercises``), the options of each item
(``course_lib.item_options``) and the source notebooks' cells, read here directly.
"""

from __future__ import annotations

import re

import pytest
from nbtools import nbgrader_meta, read

from autograder import explanations
from autograder.course import source_notebooks
from autograder.exercises import REGISTRY
from autograder.outputs import feedback
from autograder.model import CellKind, CellResult, Status
from course_lib.item_options import OPTIONS

NOTEBOOKS = source_notebooks()
CHOICES = sorted(n for n, ex in REGISTRY.items() if ex.kind == "choice")


def _words(text: str) -> set[str]:
    return {w for w in re.split(r"[^a-z0-9]+", text.lower()) if w}


@pytest.mark.parametrize("name", CHOICES)
def test_no_answer_name_contains_a_word_of_its_key(name):
    ex = REGISTRY[name]
    key = set(ex.key_for(None))
    key_text = " ".join(OPTIONS[name][ord(k) - ord("a")] for k in key)
    shared = _words(name.replace("_", " ")) & _words(key_text)
    assert not shared, f"{name}: its name shares {sorted(shared)} with its key option(s)"
    assert re.fullmatch(r"q[1-6]_item\d+", name), f"{name}: not a neutral name"


@pytest.mark.parametrize("name", CHOICES)
def test_options_are_kept_once_and_shown_by_the_call_alone(name):
    """The options cell's source is the call alone, so the student reads the options once, in
    their own order; the registry's options match the texts."""
    ex = REGISTRY[name]
    assert len(OPTIONS[name]) == len(ex.options), name
    nb = read(next(p for p in NOTEBOOKS if p.stem == ex.notebook))
    cell = next(c for c in nb.cells if nbgrader_meta(c).get("grade_id") == f"options_{name}")
    assert cell.source.strip() == f'mine.options("{name}")'
    code = "".join(c.source for c in nb.cells if c.cell_type == "code")
    for text in OPTIONS[name]:
        assert text not in code, f"{name}: an option's text in a code cell's source"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_explanations_follow_their_items_and_name_real_ones(path):
    nb = read(path)
    where = {nbgrader_meta(c).get("grade_id"): i for i, c in enumerate(nb.cells)}
    found = explanations.of_notebook(path)
    for name in found:
        assert REGISTRY[name].notebook == path.stem, name
        first = min(i for i, c in enumerate(nb.cells) if name in explanations.explained_items(c))
        assert first > where[f"test_{name}"], f"{name}: explained before it is asked"
    for i, cell in enumerate(nb.cells):
        text = cell.source if not explanations.is_explanation(cell) else ""
        assert not re.search(r"Items? Q\d\.\d+(, | and Q\d\.\d+, )explained", text), \
            f"{path.name} cell {i}: an item's explanation outside an explanation cell"


def test_strip_removes_only_explanation_cells(tmp_path):
    import shutil

    path = NOTEBOOKS[-1]
    copy = tmp_path / path.name
    shutil.copyfile(path, copy)
    before = read(copy).cells
    removed = explanations.strip(copy)
    after = read(copy).cells
    assert removed == sum(explanations.is_explanation(c) for c in before) > 0
    assert [c.source for c in after] == [c.source for c in before
                                         if not explanations.is_explanation(c)]


def test_feedback_shows_an_items_explanation_only_when_revealed():
    path = next(p for p in NOTEBOOKS if p.stem == "q5_phong")
    text = explanations.of_notebook(path)["q5_item1"][0]
    row = CellResult(student="ab123", notebook="q5_phong", grade_id="test_q5_item1",
                     name="q5_item1", score=0.0, max_score=1.0, status=Status.FAILED,
                     message="wrong answer", kind=CellKind.CHOICE)
    shown = {"q5_item1": [text]}
    hidden = feedback.render("ab123", "q5_phong", [row], False, shown)
    revealed = feedback.render("ab123", "q5_phong", [row], True, shown)
    assert "explanation of this item" not in hidden and "narrows the lobe" not in hidden
    assert "explanation of this item" in revealed and "narrows the lobe" in revealed


_PROMISE = re.compile(r"explanation[^.]*\b(feedback|follows?)\b[^.]*\.", re.S)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_a_promised_explanation_says_when_and_exists(path):
    """A release sentence that promises an item's explanation says when it comes (with the
    feedback after the due date: before it, the feedback shows none), and every choice item of
    that part ("## " heading) has an explanation cell to show then. Cell 0 is the notebook's
    own introduction, about the explanations in general."""
    nb = read(path)
    found = explanations.of_notebook(path)
    part, promised = 0, {}
    for i, cell in enumerate(nb.cells[1:], start=1):
        if cell.cell_type == "markdown" and cell.source.lstrip().startswith("## "):
            part = i
        if cell.cell_type != "markdown" or explanations.is_explanation(cell):
            continue
        for sentence in _PROMISE.finditer(cell.source):
            text = " ".join(sentence.group(0).split())
            if "item" in text.lower() or "feedback" in text.lower():
                assert "feedback after the due date" in text, f"{path.stem} cell {i}: {text!r}"
                promised.setdefault(part, [])
    items_by_part, part = {}, 0
    for i, cell in enumerate(nb.cells[1:], start=1):
        if cell.cell_type == "markdown" and cell.source.lstrip().startswith("## "):
            part = i
        gid = nbgrader_meta(cell).get("grade_id", "")
        if gid in CHOICES:
            items_by_part.setdefault(part, []).append(gid)
    assert promised or path.stem == "q4_splines", f"{path.stem}: no promise found to check"
    for part in promised:
        missing = [name for name in items_by_part.get(part, []) if name not in found]
        assert not missing, f"{path.stem}: {missing} promised an explanation but have none"


@pytest.mark.parametrize("name", CHOICES)
def test_every_choice_item_has_an_explanation_for_its_feedback(name):
    """Each notebook promises that every multiple-choice item's own explanation comes with the
    feedback after the due date; that holds only if its source notebook has an explanation cell
    naming it (the release leaves such cells out, so reading on gives nothing away)."""
    path = next(p for p in NOTEBOOKS if p.stem == REGISTRY[name].notebook)
    texts = explanations.of_notebook(path).get(name, [])
    assert any(t.strip() for t in texts), \
        f"{name}: no explanation cell in {path.name} (its explanation is missing, or still in the release)"
