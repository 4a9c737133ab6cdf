"""A real nbgrader round trip of ``tripos2006``.

``prepare_course`` (``generate_assignment``) → three students' notebooks copied into
``submitted/<student>/tripos2006/`` → one ``nbgrader autograde tripos2006`` call → the gradebook
(``nbgrader.api.Gradebook``):

- ``solution`` submits the instructor's source notebooks: every auto-graded test cell earns its
  full points (the oracle is the ``points`` metadata of the source notebooks' test cells);
- ``untouched`` submits the release notebooks as they were handed out: 0 marks in every
  auto-graded cell and 0 in total;
- ``one_wrong`` submits the source notebooks with, in each notebook, one graded function made to
  return a wrong value (a wrapper around the model answer perturbs every value it returns, bad
  input still raises): exactly that function's test cell scores 0, every other cell in full.
  This submission also drops the ungraded code cells (figures, explorers): the graded cells must
  not depend on them (the batch grader never runs them), and it keeps the run short.

The course root is shared with the other tests of this worker (one xdist group).
"""

from __future__ import annotations

import re
import shutil
import textwrap

import nbformat
import pytest
from nbtools import autograded_points, graded_items, nbgrader_meta, read

from autograder.course import ASSIGNMENT, source_notebooks

NOTEBOOKS = source_notebooks()
pytestmark = [
    pytest.mark.skipif(not NOTEBOOKS, reason="no notebooks/q*.ipynb yet"),
    pytest.mark.slow,
    pytest.mark.xdist_group("nbgrader_roundtrip"),
    pytest.mark.timeout(1200),
]

STUDENTS = ("solution", "untouched", "one_wrong")

#: Appended to the solution cell of the function chosen to be wrong.
WRONG = '''

# --- made wrong on purpose by tests/notebooks/test_nbgrader_roundtrip.py ---
def _rt_wrong_value(value):
    import numpy as _np
    if value is None:
        return (0.0, 1.0)
    if isinstance(value, (bool, _np.bool_)):
        return not value
    if isinstance(value, (int, float, _np.number)):
        return value + 1
    if isinstance(value, _np.ndarray):
        if value.dtype == bool:
            return ~value
        if value.size == 0:
            return _np.ones((1,) + value.shape[1:], dtype=value.dtype)
        return value + 1
    if isinstance(value, (tuple, list)):
        return type(value)(_rt_wrong_value(v) for v in value)
    return None


def _rt_make_wrong(func):
    import functools

    @functools.wraps(func)
    def wrong(*args, **kwargs):
        return _rt_wrong_value(func(*args, **kwargs))

    return wrong


{name} = _rt_make_wrong({name})
'''


def choose_wrong_function(nb) -> str:
    """The graded function to break: one that no other graded cell uses (so breaking it cannot
    cost another cell its marks); the last such one in the notebook."""
    items = graded_items(nb)
    graded = [c for c in nb.cells if c.cell_type == "code"
              and (nbgrader_meta(c).get("grade") or nbgrader_meta(c).get("solution"))]
    candidates = []
    for name, kind in items.items():
        if kind != "function":
            continue
        own = {name, f"test_{name}"}
        used_elsewhere = any(
            re.search(rf"\b{re.escape(name)}\b", c.source)
            for c in graded if nbgrader_meta(c).get("grade_id") not in own
        )
        if not used_elsewhere:
            candidates.append(name)
    assert candidates, "every graded function is used by another graded cell"
    return candidates[-1]


def strip_ungraded_code(nb):
    """Drop the code cells without nbgrader metadata (figures, explorers): what the batch grader
    runs anyway, and the house rule says graded cells must not depend on them."""
    nb.cells = [c for c in nb.cells if c.cell_type != "code" or nbgrader_meta(c)]
    return nb


def make_wrong(nb, name: str):
    for cell in nb.cells:
        if nbgrader_meta(cell).get("grade_id") == name:
            cell.source = cell.source.rstrip() + textwrap.dedent(WRONG).format(name=name)
            return nb
    raise KeyError(name)


@pytest.fixture(scope="module")
def graded(course):
    """Submit, autograde once, and return ``{student: {notebook: {grade_id: (score, max)}}}``
    plus the chosen wrong functions."""
    wrong = {}
    for student in STUDENTS:
        dest = course.submitted_dir(student)
        if dest.exists():
            shutil.rmtree(dest)
        dest.mkdir(parents=True)
    for src in NOTEBOOKS:
        shutil.copyfile(src, course.submitted_dir("solution") / src.name)
        shutil.copyfile(course.release_dir / src.name, course.submitted_dir("untouched") / src.name)
        nb = read(src)
        wrong[src.stem] = choose_wrong_function(nb)
        nb = strip_ungraded_code(make_wrong(nb, wrong[src.stem]))
        nbformat.write(nb, str(course.submitted_dir("one_wrong") / src.name))

    course.nbgrader(["autograde", ASSIGNMENT, "--force"])

    scores = {}
    with course.gradebook() as gb:
        for student in STUDENTS:
            sub = gb.find_submission(ASSIGNMENT, student)
            per_nb = {}
            for snb in sub.notebooks:
                per_nb[snb.name] = {
                    g.name: (g.score, g.max_score, g.cell.cell_type) for g in snb.grades
                }
            scores[student] = {"notebooks": per_nb, "code_score": sub.code_score,
                               "max_code_score": sub.max_code_score, "score": sub.score}
    return scores, wrong


def _auto(per_cell: dict) -> dict:
    return {gid: score for gid, (score, _max, kind) in per_cell.items() if kind == "code"}


@pytest.mark.parametrize("source", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_solutions_score_full_marks(graded, source):
    scores, _ = graded
    expected = autograded_points(read(source))
    got = scores["solution"]["notebooks"][source.stem]
    assert {g: m for g, (_s, m, k) in got.items() if k == "code"} == expected, \
        "the gradebook's maximum marks differ from the notebook's test-cell points"
    assert _auto(got) == expected, "the model solutions lost marks"


def test_solutions_total(graded):
    scores, _ = graded
    total = sum(sum(autograded_points(read(p)).values()) for p in NOTEBOOKS)
    assert scores["solution"]["max_code_score"] == pytest.approx(total)
    assert scores["solution"]["code_score"] == pytest.approx(total)


@pytest.mark.parametrize("source", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_untouched_release_scores_zero(graded, source):
    scores, _ = graded
    got = _auto(scores["untouched"]["notebooks"][source.stem])
    assert got.keys() == autograded_points(read(source)).keys()
    assert all(score == 0 for score in got.values()), {g: s for g, s in got.items() if s}


def test_untouched_release_total_zero(graded):
    scores, _ = graded
    assert scores["untouched"]["code_score"] == 0
    assert scores["untouched"]["score"] == 0


@pytest.mark.parametrize("source", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_one_wrong_function_loses_exactly_its_points(graded, source):
    scores, wrong = graded
    name = wrong[source.stem]
    points = autograded_points(read(source))
    expected = {gid: (0.0 if gid == f"test_{name}" else pts) for gid, pts in points.items()}
    assert _auto(scores["one_wrong"]["notebooks"][source.stem]) == expected, \
        f"breaking {name}() should cost exactly test_{name}'s {points[f'test_{name}']} points"
