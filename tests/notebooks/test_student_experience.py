"""What a student meets in an untouched release notebook (issue 12).

(a) Run All goes through: each release notebook, exactly as ``nbgrader generate_assignment``
    writes it, executes under nbclient *without* ``allow_errors`` (nbclient, like JupyterLab,
    runs on past a cell tagged ``raises-exception``); every cell that draws shows a figure or an
    explorer, and every auto-graded test cell still shows its failure.
(b) Multiple-choice items cannot be answered by form: over all items of all notebooks, the
    strictly longest option is a correct one no more often than chance allows.
(c) Every manually graded answer cell has its prompt in the markdown cell directly above it.
(d) Every visible test of a multiple-choice item checks the answer's form with
    ``course_lib.answers.choice_letters`` and never contains the key.

The keys come from the registry (``autograder.exercises``), the options from the notebooks.
"""

from __future__ import annotations

import ast
import math
import re

import pytest
from nbtools import (CELL_TIMEOUT, execute_shared, first_untagged_error, nbgrader_meta,
                     option_texts, read)

from autograder.course import NOTEBOOKS_DIR, source_notebooks
from autograder.exercises import REGISTRY
from course_lib.answers import choice_letters

NOTEBOOKS = source_notebooks()
#: one worker runs this module and test_release.py, which share each release notebook's run
pytestmark = [pytest.mark.skipif(not NOTEBOOKS, reason="no notebooks/q*.ipynb yet"),
              pytest.mark.xdist_group("release_runs")]

FIGURE_MIME = ("image/png", "application/vnd.jupyter.widget-view+json")
#: A code line that draws: a plot helper, pyplot, an explorer.
DRAWS = re.compile(r"\bplot\w*\(|\bplt\.|\b\w+_explorer\(|\bimshow\(|\bsubplots\(")
#: An option line of a multiple-choice item: "- **(a)** text" (bold and bullet optional).


def _is_graded_code(cell, key: str) -> bool:
    return cell.cell_type == "code" and bool(nbgrader_meta(cell).get(key))


def _drawing_lines(source: str) -> list[str]:
    """The lines of a cell that are neither imports, magics nor comments."""
    return [ln for ln in source.splitlines()
            if ln.strip() and not ln.lstrip().startswith(("import ", "from ", "%", "#"))]


# (a) ----------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def released(course):
    """``{stem: path}`` of the untouched release notebooks nbgrader generated for the course."""
    return {p.stem: p for p in course.release_notebooks()}


@pytest.mark.slow
@pytest.mark.timeout(900)
@pytest.mark.parametrize("who", ["hub-student", "no-id-yet"])
@pytest.mark.parametrize("source", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_run_all_on_untouched_release(released, source, who, monkeypatch, tmp_path):
    """On the hub (the id is known), and on a student's own machine before STUDENT_ID is
    typed (playtest 6: Run All stopped at the first item's options there)."""
    if who == "no-id-yet":         # the kernel inherits this: no hub user, no nbgrader id
        import matplotlib

        monkeypatch.delenv("JUPYTERHUB_USER", raising=False)
        monkeypatch.setenv("MPLCONFIGDIR", matplotlib.get_configdir())   # its font cache
        monkeypatch.setenv("HOME", str(tmp_path))

    # only cells tagged raises-exception may fail (nbclient's allow_errors=False, JupyterLab's
    # Run All); the run with the hub's id is shared with test_release.py's
    nb = execute_shared(released[source.stem], cwd=NOTEBOOKS_DIR, timeout=CELL_TIMEOUT)
    stopped = first_untagged_error(nb)
    if stopped:
        pytest.fail(f"Run All stopped at an untagged cell:\n{stopped[:800]}\n...\n{stopped[-400:]}")
    blank, silent_tests = [], []
    for i, cell in enumerate(nb.cells):
        if cell.cell_type != "code":
            continue
        outputs = cell.get("outputs", [])
        if _is_graded_code(cell, "grade"):
            if not any(o.get("output_type") == "error" for o in outputs):
                silent_tests.append(nbgrader_meta(cell)["grade_id"])
        elif not nbgrader_meta(cell) and any(DRAWS.search(ln)
                                             for ln in _drawing_lines(cell.source)):
            if not any(m in o.get("data", {}) for o in outputs for m in FIGURE_MIME):
                blank.append(f"cell {i}: {cell.source.splitlines()[0][:60]}")
    assert not blank, "figure/explorer cells that showed nothing on Run All:\n" + "\n".join(blank)
    assert not silent_tests, f"test cells that do not show a failure on the stubs: {silent_tests}"
    n_figures = sum(m in o.get("data", {}) for c in nb.cells if c.cell_type == "code"
                    for o in c.get("outputs", []) for m in FIGURE_MIME)
    assert n_figures >= 1, "Run All rendered no figure at all"


def test_release_check_names_an_untagged_cell(tmp_path):
    """The release command refuses a notebook whose solution cell lacks the Run All tag."""
    import nbformat

    from autograder.release import ReleaseNotRunnable, check_release

    nb = nbformat.v4.new_notebook()
    cell = nbformat.v4.new_code_cell("# YOUR CODE HERE\nraise NotImplementedError()")
    cell.metadata["nbgrader"] = {"grade": False, "grade_id": "f", "locked": False,
                                 "schema_version": 3, "solution": True, "task": False}
    nb.cells.append(cell)
    path = tmp_path / "q0_demo.ipynb"
    nbformat.write(nb, str(path))
    with pytest.raises(ReleaseNotRunnable, match=r"q0_demo.ipynb cell 0 \(f\)"):
        check_release([path])
    cell.metadata["tags"] = ["raises-exception"]
    nbformat.write(nb, str(path))
    check_release([path])


# (b) ----------------------------------------------------------------------------------------

def _choice_items():
    """``(notebook, name, {letter: option text}, key letters)`` of every multiple-choice item."""
    items = []
    for path in NOTEBOOKS:
        nb = read(path)
        for cell in nb.cells:
            name = nbgrader_meta(cell).get("grade_id")
            exercise = REGISTRY.get(name)
            if not (_is_graded_code(cell, "solution") and exercise and exercise.kind == "choice"):
                continue
            options = option_texts(nb, name)
            key = exercise.answer
            key = "".join(sorted(key)) if not isinstance(key, str) else choice_letters(key, "abcdefgh")
            items.append((path.stem, name, options, key))
    return items


CHOICES = _choice_items()


@pytest.mark.parametrize("item", CHOICES, ids=[f"{nb}-{name}" for nb, name, _, _ in CHOICES])
def test_choice_options_are_above_the_answer_cell(item):
    notebook, name, options, key = item
    assert len(options) >= 3, f"{name}: fewer than three options in the markdown above its cell"
    assert sorted(options) == [chr(ord("a") + k) for k in range(len(options))], \
        f"{name}: options are not lettered (a), (b), ... in order: {sorted(options)}"
    assert set(key) <= set(options), f"{name}: the key {key!r} names an option that is not shown"


def _strictly_longest(options: dict[str, str]) -> str | None:
    lengths = sorted(((len(text), letter) for letter, text in options.items()), reverse=True)
    return lengths[0][1] if len(lengths) < 2 or lengths[0][0] > lengths[1][0] else None


def test_correct_option_is_not_given_away_by_length():
    """Under chance a correct option is the strictly longest in item ``i`` with probability at
    most ``k_i / n_i`` (``k_i`` correct of ``n_i`` options); the count over all items may exceed
    that expectation by one item, an allowance for the integer count (an item or two where the
    right statement is naturally the wordiest is no give-away when the rest are balanced)."""
    longest = [(nb, name) for nb, name, options, key in CHOICES
               if _strictly_longest(options) in set(key)]
    expected = sum(len(key) / len(options) for _, _, options, key in CHOICES if options)
    allowed = math.ceil(expected) + 1
    assert len(longest) <= allowed, (
        f"the correct option is the strictly longest in {len(longest)} of {len(CHOICES)} items "
        f"(chance: {expected:.1f}, allowed {allowed}): {longest}")


# (c) ----------------------------------------------------------------------------------------

def _answer_cells():
    found = []
    for path in NOTEBOOKS:
        cells = read(path).cells
        for i, cell in enumerate(cells):
            meta = nbgrader_meta(cell)
            if cell.cell_type == "markdown" and meta.get("solution") and meta.get("grade"):
                found.append((path.stem, meta["grade_id"], cells[i - 1] if i else None))
    return found


ANSWERS = _answer_cells()


@pytest.mark.parametrize("item", ANSWERS, ids=[f"{nb}-{gid}" for nb, gid, _ in ANSWERS])
def test_written_answer_has_its_prompt_directly_above(item):
    notebook, grade_id, above = item
    assert above is not None and above.cell_type == "markdown", \
        f"{grade_id}: the cell above the answer cell is not a markdown prompt"
    assert not nbgrader_meta(above).get("solution"), \
        f"{grade_id}: the cell above is another answer cell, not a prompt"
    assert len(above.source.split()) >= 8, f"{grade_id}: the prompt above the answer cell is empty"


# (d) ----------------------------------------------------------------------------------------

def _visible_tests():
    found = []
    for path in NOTEBOOKS:
        for cell in read(path).cells:
            gid = nbgrader_meta(cell).get("grade_id") or ""
            exercise = REGISTRY.get(gid[len("test_"):]) if gid.startswith("test_") else None
            if exercise is not None and exercise.kind == "choice":
                visible = cell.source.split("### BEGIN HIDDEN TESTS")[0]
                found.append((path.stem, exercise, visible))
    return found


VISIBLE = _visible_tests()


@pytest.mark.parametrize("item", VISIBLE, ids=[f"{nb}-{ex.name}" for nb, ex, _ in VISIBLE])
def test_visible_choice_test_checks_form_only(item):
    notebook, exercise, visible = item
    tree = ast.parse(visible)
    calls = [n for n in ast.walk(tree) if isinstance(n, ast.Call)
             and getattr(n.func, "id", getattr(n.func, "attr", None)) == "choice_letters"]
    assert calls, f"test_{exercise.name}: the visible test does not call choice_letters"
    assert any(isinstance(a, ast.Name) and a.id == exercise.name for c in calls for a in c.args[:1]), \
        f"test_{exercise.name}: choice_letters is not applied to {exercise.name}"
    key = exercise.answer
    key = set(key) if not isinstance(key, str) else set(choice_letters(key, "abcdefgh"))
    options = "".join(exercise.options) if exercise.options else "abcd"
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            letters = {ch for ch in node.value.lower() if ch not in " ,"}
            if letters == key and set(node.value.lower()) - set(" ,") <= set(options) \
                    and letters != set(options):
                pytest.fail(f"test_{exercise.name}: the visible test contains the key "
                            f"{node.value!r}")
