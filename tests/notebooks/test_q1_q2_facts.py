"""Facts of the q1 and q2 notebooks that once were wrong, pinned against independent numbers.

- Q1: water's attenuation grows as f^2 (0.0022 dB/cm/MHz^2, Duck 1990), so 4 cm of water cost
  about 0.44 dB down and back at 5 MHz, not "about 0.1 dB"; the phantom's sizes are the course's
  reconstruction, not the exam's.
- Q2: the photomultiplier figure draws as many dynodes as the text works with (ten), and the
  similar-triangles resolution is asked for before the notebook states it.
- Both: the marks of each part follow the exam's percentages of 20 marks.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from nbtools import nbgrader_meta, read

from autograder.course import NOTEBOOKS_DIR
from autograder.exercises import for_notebook

Q1 = NOTEBOOKS_DIR / "q1_imaging.ipynb"
Q2 = NOTEBOOKS_DIR / "q2_nuclear.ipynb"
pytestmark = pytest.mark.skipif(not (Q1.exists() and Q2.exists()), reason="notebooks missing")


def _markdown(path) -> str:
    return "\n".join(c.source for c in read(path).cells if c.cell_type == "markdown")


def test_q1_water_loss_is_the_f_squared_value():
    text = _markdown(Q1)
    by_hand = 2 * 4.0 * 0.0022 * 5.0**2  # two ways, 4 cm, Duck's coefficient times f^2
    assert f"{by_hand:.2f}" == "0.44"
    assert "0.44" in text and "f^2" in text
    assert "about 0.1 dB" not in text


def test_q1_phantom_called_a_reconstruction_not_the_exam():
    text = _markdown(Q1)
    assert "reconstruction" in text
    for ex in for_notebook("q1_imaging"):
        if ex.cases is None:
            continue
        for case in ex.draw_cases(np.random.default_rng(0)):
            assert "exam Q1(c)" not in case.label, f"{ex.name}: {case.label}"
    for cell in read(Q1).cells:
        if cell.cell_type == "code":
            assert "exam Q1(c)" not in cell.source


def test_q2_pmt_figure_has_the_texts_ten_dynodes():
    nb = read(Q2)
    calls = [c.source for c in nb.cells if c.cell_type == "code" and "plot_pmt_cascade(" in c.source]
    assert calls, "no photomultiplier figure"
    counts = {int(m) for s in calls for m in re.findall(r"n_dynodes\s*=\s*(\d+)", s)}
    assert counts == {10}, counts
    assert "ten dynodes" in _markdown(Q2)
    assert 4.0**10 == pytest.approx(1e6, rel=0.05)  # "about a million" with delta = 4


def test_q2_resolution_formula_comes_after_the_students_attempt():
    cells = read(Q2).cells
    first_test = next(i for i, c in enumerate(cells)
                      if nbgrader_meta(c).get("grade_id") == "test_collimator_length_for_resolution")
    answer = next(i for i, c in enumerate(cells) if nbgrader_meta(c).get("grade_id") == "q2c_answer")
    formula = re.compile(r"L\s*\+\s*z|R\s*-\s*d")
    for i, cell in enumerate(cells[:first_test + 1]):
        if nbgrader_meta(cell).get("solution"):
            # the model solution (hidden in the release) is allowed the formula
            body = cell.source.split("### BEGIN SOLUTION")[0]
        else:
            body = cell.source
        assert not formula.search(body), f"cell {i} states the resolution before it is asked for"
    assert answer > first_test


def _marks_by_part(path, header: str) -> dict[str, float]:
    marks, part = {}, None
    for cell in read(path).cells:
        m = re.match(header, cell.source) if cell.cell_type == "markdown" else None
        if m:
            part = m.group(1)
        meta = nbgrader_meta(cell)
        if meta.get("grade") and part:
            marks[part] = marks.get(part, 0.0) + float(meta.get("points", 0))
    return marks


def test_marks_follow_the_exams_percentages():
    # Q1: (a) 40 %, (b) 10 %, (c) 50 %; Q2: (a) 35 %, (b) 10 %, (c) 25 %, (d) 30 % of 20 marks
    assert _marks_by_part(Q1, r"## Part \((\w)\)") == {"a": 8.0, "b": 2.0, "c": 10.0}
    assert _marks_by_part(Q2, r"## \((\w)\)") == {"a": 7.0, "b": 2.0, "c": 5.0, "d": 6.0}
