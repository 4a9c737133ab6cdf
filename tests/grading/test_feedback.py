"""Feedback after the deadline (``--reveal-hidden``), plots of geometric answers, and the
default gradebook (an nbgrader course created on the fly in ``OUT``)."""

from __future__ import annotations

import html
import json
import re

import numpy as np
import pytest

from autograder.exercises import REGISTRY
from gradingtools import (SECRET, append_cell, cases_of, model_version, read_grades, run_grade,
                          target_of, write_nb)

pytestmark = [pytest.mark.xdist_group("feedback")]

#: Names whose answers are curves, polygons or meshes, and a wrong-but-plausible variant.
GEOMETRIC = ("sample_curve", "clip_polygon", "marching_cubes")
SHIFT = """
_model_{name} = {name}
def {name}(*args, **kwargs):
    out = _model_{name}(*args, **kwargs)
    if isinstance(out, tuple):                       # a mesh: move its vertices
        return (np.asarray(out[0], float) + 0.25,) + tuple(out[1:])
    out = np.array(out, dtype=float)
    if out.size:
        out[..., 0] += 0.25 * (out[..., -1] if out.shape[-1] == 4 else 1.0)
    return out
"""


@pytest.fixture(scope="module")
def revealed(tmp_path_factory, sources):
    root = tmp_path_factory.mktemp("reveal")
    (root / "secret").write_bytes(SECRET + b"\n")
    made = {}
    for src in sources:
        nb = model_version(src)
        name = target_of(src)
        append_cell(nb, name, f"def {name}(*args, **kwargs):\n    return 'wrong'\n")
        shifted = [n for n, _, _ in src.graded if n in GEOMETRIC and n != name]
        for g in shifted:
            append_cell(nb, g, SHIFT.format(name=g))
        write_nb(root / "submitted" / "late" / "tripos2006" / f"{src.name}.ipynb", nb)
        made[src.name] = (name, shifted)
    run_grade(root / "submitted", root / "out", "--reveal-hidden", "--no-gradebook",
              secret_file=root / "secret")
    return root, made


def test_reveal_shows_failing_hidden_inputs_and_expected_values(revealed, sources):
    root, made = revealed
    for src in sources:
        name, _ = made[src.name]
        page = html.unescape((root / "out" / "feedback" / "late" / f"{src.name}.html")
                             .read_text(encoding="utf-8"))
        submitted = root / "submitted" / "late" / "tripos2006" / f"{src.name}.ipynb"
        hidden = [c for c in cases_of("late", name, submitted) if not c.visible]
        if not hidden:
            continue
        assert "failing hidden case" in page
        assert f"Hidden cases: 0 of {len(hidden)} passed" in page
        shown = [c for c in hidden[:20] if c.label and c.label in page]
        assert shown, "the failing hidden cases are listed by label"
        ex = REGISTRY[name]
        for case in hidden[:20]:
            if case.raises is None:
                expected = ex.expected(case)
                if isinstance(expected, float):
                    assert f"{expected:.8g}" in page, (name, case.label)
            else:
                assert f"raises {case.raises.__name__}" in page
        assert "BEGIN HIDDEN TESTS" not in page and "autograder.incell" not in page


def test_geometric_answers_are_drawn(revealed, sources):
    root, made = revealed
    drawn = 0
    for src in sources:
        for name in made[src.name][1]:
            page = (root / "out" / "feedback" / "late" / f"{src.name}.html").read_text()
            section = page.split(f"<h2>{name} ", 1)[1].split("<h2>", 1)[0]
            assert "<svg" in section and re.search(r"<(polyline|polygon) points=", section), name
            assert "expected" in section and "your answer" in section
            drawn += 1
    if not drawn:
        pytest.skip("no geometric exercise in the notebooks yet")


def test_scores_of_the_late_run(revealed, sources):
    root, made = revealed
    rows = read_grades(root / "out")
    for src in sources:
        name, shifted = made[src.name]
        assert rows[("late", src.name, f"test_{name}")]["score"] == "0"
        for g in shifted:
            row = rows[("late", src.name, f"test_{g}")]
            assert row["status"] == "failed"
            assert float(row["score"]) < float(row["max_score"])


@pytest.mark.slow
def test_default_gradebook_is_an_nbgrader_course_in_out(tmp_path, sources):
    """Without --db-url the grader makes OUT an nbgrader course (generate_assignment) and
    fills its gradebook; formgrader can then be started there."""
    src = sources[0]
    write_nb(tmp_path / "submitted" / "kim" / "tripos2006" / f"{src.name}.ipynb",
             model_version(src))
    out = tmp_path / "out"
    run_grade(tmp_path / "submitted", out)
    from nbgrader.api import Gradebook

    assert (out / "gradebook.db").exists()
    assert (out / "autograded" / "kim" / "tripos2006" / f"{src.name}.ipynb").exists()
    rows = read_grades(out)
    with Gradebook(f"sqlite:///{out / 'gradebook.db'}") as gb:
        for _, tid, pts in src.graded:
            assert gb.find_grade(tid, src.name, "tripos2006", "kim").auto_score == pts
            assert rows[("kim", src.name, tid)]["status"] == "ok"
    nb = json.loads((out / "autograded" / "kim" / "tripos2006" / f"{src.name}.ipynb").read_text())
    assert nb["nbformat"] == 4
    assert np.isclose(sum(float(r["score"] or 0) for r in rows.values()),
                      sum(p for _, _, p in src.graded))
    # nbgrader's own feedback, generated from our autograded notebooks, shows our scores and no
    # hidden test (plain nbgrader leaks them: nbgrader #917, #1363)
    from autograder.course import run_nbgrader

    run_nbgrader(["generate_feedback", "tripos2006", "--force"], out)
    page = (out / "feedback" / "kim" / "tripos2006" / f"{src.name}.html").read_text()
    assert "BEGIN HIDDEN TESTS" not in page and "autograder.incell" not in page
    total = sum(p for _, _, p in src.graded)
    assert re.search(rf"Score: {total:.1f} / \d", page)
