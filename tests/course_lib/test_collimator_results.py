"""Q2's shipped results (``course_lib.collimator_results``): the students' copy holds the
numbers the references give on the notebook's fixed inputs. Checked against the references,
against the exam's own numbers and closed forms, and the generated students' module is checked
to give the same arrays bit for bit while naming none of the maths."""

from __future__ import annotations

import numpy as np
import pytest

from autograder import student_bundle
from course_lib import _collimator_results_data, collimator_results
from course_lib import gamma_camera as gc

EXAM = collimator_results.EXAM


@pytest.fixture(scope="module")
def students_load():
    """``load`` of the module text the students' wheel gets, run here."""
    namespace = {"__name__": "students_copy"}
    exec(compile(_collimator_results_data.students_copy(), "students_copy", "exec"), namespace)
    return namespace["load"]


def test_students_copy_gives_the_references_arrays_bit_for_bit(students_load):
    ours, theirs = _collimator_results_data.load(), students_load()
    assert sorted(ours) == sorted(theirs) == ["exam_fraction", "exam_holes", "thin_fraction"]
    for name in ours:
        assert theirs[name].dtype == ours[name].dtype, name
        np.testing.assert_array_equal(theirs[name], ours[name], err_msg=name)
        assert not theirs[name].flags.writeable, name
    np.testing.assert_array_equal(ours["exam_holes"], gc.ring_hole_positions(10.0, 4))
    assert float(ours["exam_fraction"]) == gc.open_fraction(
        gc.ring_hole_positions(10.0, 4), 1.0, 40.0, 1000.0, 50.0)


def test_students_copy_names_none_of_the_maths():
    """The generated text passes the build's own checks and defines nothing but ``load``."""
    name = "course_lib._collimator_results_data"
    assert name in student_bundle.GENERATED_MODULES
    rel = next(p for p in student_bundle.library_files() if student_bundle.module_name(p) == name)
    withheld = student_bundle.left_out()
    gone = {n for names in withheld.values() for n in names}
    text = student_bundle.staged_text(rel, withheld, gone)
    imported = student_bundle.imported_modules(text, name)
    assert {m.partition(".")[0] for m in imported} == {"base64", "functools", "numpy"}, imported
    used = student_bundle.names_used(text)
    assert not used & {"compute", "gamma_camera", "ring_hole_positions", "open_fraction"}


def test_exam_holes_are_the_rings_of_q2d():
    """The centre, then 8k holes on radius 10k (k = 1..4), anticlockwise from angle 0."""
    holes = collimator_results.exam_holes()
    assert holes.shape == (81, 2) and not holes.flags.writeable
    np.testing.assert_array_equal(holes[0], [0.0, 0.0])
    start = 1
    for k in range(1, 5):
        ring = holes[start:start + 8 * k]
        angles = 2 * np.pi * np.arange(8 * k) / (8 * k)
        np.testing.assert_allclose(ring, 10.0 * k * np.column_stack([np.cos(angles),
                                                                       np.sin(angles)]),
                                   rtol=0, atol=1e-12)
        start += 8 * k


def test_fractions_are_the_exams_numbers():
    """Q2(d): 25 holes of radius 0.5 mm open on a 50 mm face: 19.635 / 7853.98 = 0.25 %; the
    thin collimator (5 mm holes 1 mm long) opens all 81: 81 x 2.5^2 / 50^2."""
    assert collimator_results.exam_open_fraction() == pytest.approx(19.635 / 7853.98, rel=1e-4)
    assert collimator_results.exam_open_fraction() == pytest.approx(25 * 0.5**2 / 50.0**2,
                                                                    rel=1e-12)
    assert collimator_results.thin_open_fraction() == pytest.approx(81 * 2.5**2 / 50.0**2,
                                                                    rel=1e-12)
    assert EXAM["d"] * EXAM["source_distance"] / EXAM["L"] == 25.0   # the cut-off: rings 0-2


def test_the_notebooks_cells_use_these_inputs():
    """The Q2 notebook's "going further" cells read these results for the collimators they
    describe: the exam's (1 mm, 40 mm, 1000 mm, 50 mm face) and the thin one of :data:`THIN`."""
    import nbformat

    from autograder.course import REPO_ROOT

    nb = nbformat.read(REPO_ROOT / "notebooks" / "q2_nuclear.ipynb", as_version=4)
    code = "\n".join(c.source for c in nb.cells if c.cell_type == "code")
    assert "collimator_results.exam_open_fraction()" in code
    assert "collimator_results.thin_open_fraction()" in code
    thin = collimator_results.THIN
    assert (f"thin = dict(d={thin['d']}, L={thin['L']}, source_distance={thin['source_distance']}, "
            f"collimator_radius={thin['collimator_radius']})") in code
    assert "plot_hole_rings(holes, 1.0, 40.0, 1000.0, 50.0" in code
    assert (EXAM["d"], EXAM["L"], EXAM["source_distance"], EXAM["collimator_radius"]) == (
        1.0, 40.0, 1000.0, 50.0)
