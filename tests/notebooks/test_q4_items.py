"""The q4_splines notebook's items against issue 12: ask before telling, fair multiple choice.

- the multiple-choice options of every item are parsed from the markdown above its solution
  cell; the correct option (from the registry's key) is the strictly longest, as rendered, in at
  most a quarter of the items, and the visible test checks only the answer's form with
  ``course_lib.answers.choice_letters`` (the key never appears in it);
- the worked answers come after the attempts they answer: the part (b) result table after the
  last part (b) test cell, the four substituted end conditions after the written (c)(i) answer,
  and the basis matrices nowhere before the student writes them;
- every manually graded answer has its prompt in the markdown cell directly above it;
- no figure or explorer cell calls a function the student writes;
- the notebook states that the B-spline with d = b does not reach the last point, and never
  that the phantom-extended curve "spans all" the points.
"""

from __future__ import annotations

import re

import pytest
from nbtools import nbgrader_meta, option_texts, read

from autograder.course import NOTEBOOKS_DIR
from autograder.exercises import for_notebook

NB_PATH = NOTEBOOKS_DIR / "q4_splines.ipynb"
pytestmark = pytest.mark.skipif(not NB_PATH.exists(), reason="no q4_splines notebook")


@pytest.fixture(scope="module")
def cells():
    return read(NB_PATH).cells


def _index(cells, grade_id):
    return next(i for i, c in enumerate(cells) if nbgrader_meta(c).get("grade_id") == grade_id)


def rendered(text: str) -> str:
    """The option as a reader sees it: LaTeX commands, dollars and braces dropped."""
    text = re.sub(r"\\(mathbf|tfrac|frac)\s*", "", text)
    text = re.sub(r"[${}\\]", "", text)
    return re.sub(r"\s+", " ", text).strip()


def test_rendered_drops_latex():
    assert rendered(r"At $\tfrac13(\mathbf b + 2\mathbf c)$, at rest") == "At 13(b + 2c), at rest"


def choice_items(cells):
    """``(exercise, {letter: option}, test cell source, key)`` of every choice item."""
    nb = read(NB_PATH)
    for ex in for_notebook("q4_splines"):
        if ex.kind == "choice":
            i = _index(cells, ex.name)
            key = ex.answer if isinstance(ex.answer, frozenset) else frozenset(ex.answer)
            yield ex, option_texts(nb, ex.name), cells[i + 1].source, key


def test_choice_options_match_the_registry(cells):
    for ex, opts, _, key in choice_items(cells):
        assert tuple(sorted(opts)) == tuple(ex.options), (ex.name, sorted(opts))
        assert key <= set(opts), ex.name


def test_correct_option_is_rarely_the_longest(cells):
    items = list(choice_items(cells))
    assert len(items) >= 6
    longest_correct = []
    for ex, opts, _, key in items:
        lengths = {k: len(rendered(v)) for k, v in opts.items()}
        top = max(lengths.values())
        winners = [k for k, n in lengths.items() if n == top]
        if len(winners) == 1 and winners[0] in key:
            longest_correct.append(ex.name)
    assert len(longest_correct) <= len(items) / 4, longest_correct


def test_visible_choice_tests_check_form_only(cells):
    for ex, _, test_source, key in choice_items(cells):
        visible = test_source.split("### BEGIN HIDDEN TESTS")[0]
        assert "choice_letters(" in visible and f'name="{ex.name}"' in visible, ex.name
        answer = "".join(sorted(key))
        assert not re.search(rf"""['"]{answer}['"]""", visible), f"{ex.name}: key in visible test"


def test_worked_answers_follow_the_attempts(cells):
    text = [c.source for c in cells]
    table_b = next(i for i, s in enumerate(text) if "### The answer to part (b)" in s)
    assert table_b > _index(cells, "test_end_derivatives")
    worked_c = next(i for i, s in enumerate(text) if "### The four cases, worked" in s)
    assert worked_c > _index(cells, "q4ci_answer")
    explorer = next(i for i, s in enumerate(text) if "spline_end_explorer()" in s)
    assert explorer > worked_c
    # the basis matrices (e.g. the Catmull-Rom row 2, -5, 4, -1) are not shown before the attempt
    first_basis = _index(cells, "catmull_rom_basis")
    for s in text[:first_basis]:
        assert not re.search(r"2\s*&\s*-5\s*&\s*4\s*&\s*-1", s)
        assert "-5*c" not in s.replace(" ", "") and r"5\mathbf c + 2\mathbf d" not in s


def test_manual_answers_have_their_prompt_directly_above(cells):
    for i, c in enumerate(cells):
        meta = nbgrader_meta(c)
        if c.cell_type == "markdown" and meta.get("solution") and meta.get("grade"):
            above = cells[i - 1]
            assert above.cell_type == "markdown" and not nbgrader_meta(above), meta["grade_id"]
            assert f"[{meta['points']:g} mark" in above.source, meta["grade_id"]
            assert "Rubric" in c.source, meta["grade_id"]


def test_sketch_item_says_how_to_hand_in(cells):
    prompt = cells[_index(cells, "q4ci_answer") - 1].source
    assert "sketch" in prompt and "attachment" in prompt and "matplotlib" in prompt


def test_figures_do_not_call_student_functions(cells):
    graded = [ex.name for ex in for_notebook("q4_splines") if ex.kind == "function"]
    for c in cells:
        if c.cell_type == "code" and not nbgrader_meta(c):
            code = "\n".join(ln for ln in c.source.splitlines() if not ln.lstrip().startswith("#"))
            called = [n for n in graded if re.search(rf"(?<![\w.]){n}\(", code)]
            assert not called, f"a figure/explorer cell calls {called}"


def test_solution_and_test_cells_may_raise(cells):
    for c in cells:
        meta = nbgrader_meta(c)
        if c.cell_type == "code" and (meta.get("solution") or meta.get("grade")):
            assert "raises-exception" in c.metadata.get("tags", []), meta["grade_id"]


def test_no_claim_that_every_b_spline_spans_its_points(cells):
    text = "\n".join(c.source for c in cells)
    assert "spans all of them" not in text and "spans every" not in text
    assert re.search(r"B-spline reaches \$\\mathbf c\$\s+only with", text)
