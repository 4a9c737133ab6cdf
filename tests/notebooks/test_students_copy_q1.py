"""Q1(c) in the students' copy: its figures and explorer give the exam phantom's displayed
depths only at display precision, and no q1 graded answer at the grader's (docs/students-copy.md).

An independent check beside the probe (``tests/wheelprobe.py``), which tries callables on a
graded function's own arguments: here the students' copy of ``course_lib.ultrasound`` is used
the way its figures use it, on the exam's Q1 phantom (fat, liver and water blocks in a water
bath), and every number it hands out (outlines, A-line ticks, the explorer's lines, attributes
and readout, each figure's text alternative) is compared with the graded answers for that
phantom, computed here from time of flight and the attenuation law (not by the references):
the displayed depth of each face, each layer's displayed thickness, the two-way loss down to
each face. None may pass the grader's rule (1e-6 relative); each displayed depth must be there
to display precision (0.005 mm), so the check looks at the right numbers.
"""

from __future__ import annotations

import pickle
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest
from nbtools import graded_in

Q1_COPY = r'''
import pickle, sys
import numpy as np
import matplotlib
matplotlib.use("Agg")
from course_lib import ultrasound as us
from course_lib.plots import ultrasound as up
from course_lib.plots.describe import alt_text, summary
from course_lib.widgets.ultrasound import BScanExplorer

ph = us.exam_phantom()
floats, texts = [], []
for _xs, zs in up.displayed_outlines(ph):
    floats.append(zs)
for x in [5.0] + [(b[1] + b[2]) / 2 for b in ph["blocks"]]:
    floats.append(up.displayed_interfaces(ph, x))
texts.append(up.bscan_summary(ph))
figures = [up.phantom_and_bscan(ph, seed=4, nx=64, show_displayed=True)[0]]
fig, art = up.aline_figure(ph, seed=4, nx=64)
figures.append(fig)
floats += [np.asarray(m.get_xdata(), float) for m in art["markers"]]   # the A-lines' ticks
for fig in figures:
    texts.append(alt_text(fig))
    for ax in fig.axes[:1] + fig.axes[1:] * (fig is figures[0]):     # not the echo traces
        floats += [np.asarray(line.get_ydata(), float) for line in ax.get_lines()]
ex = BScanExplorer(nx=64)
floats += [np.asarray(line.get_ydata(), float) for line in ex.shown_lines]
floats += [np.asarray([v], float).ravel() for v in vars(ex).values()
           if isinstance(v, (float, np.floating))]
texts += [ex.readout.value, summary(ex.ax_img), alt_text(ex.fig)]
gone = GRADED_IN_MODULE + ("phantom_interfaces", "displayed_faces")
with open(sys.argv[1], "wb") as f:
    pickle.dump({"floats": np.concatenate([np.ravel(a) for a in floats]), "texts": texts,
                 "present": [n for n in gone if hasattr(us, n)]}, f)
'''.replace(
    "GRADED_IN_MODULE", repr(graded_in("ultrasound")))

C0 = 1540.0
C = {"water": 1482.0, "fat": 1450.0, "liver": 1578.0}        # the course's table (m/s)
ALPHA = {"water": 0.0022 * 5.0, "fat": 0.60, "liver": 0.50}  # dB/cm/MHz at 5 MHz (water: f**2)


def q1_answers():
    """The q1 graded answers for the exam phantom (40 mm blocks 10 mm under the probe, floor
    at 60 mm, 5 MHz), from time of flight and the attenuation law: ``(depths, others)``."""
    stacks = {"gap": [("water", 60.0)]}
    for block in ("fat", "liver", "water"):
        stacks[block] = [("water", 10.0), (block, 40.0), ("water", 10.0)]
    depths, others = [], []
    for layers in stacks.values():
        delay = 0.0          # two-way time of flight (s) down to each far face
        loss = 0.0
        for name, mm in layers:
            delay += 2 * mm * 1e-3 / C[name]
            depths.append(C0 * delay / 2 * 1e3)              # displayed_depths
            others.append(mm * C0 / C[name])                 # displayed_thickness
            loss += 2 * ALPHA[name] * 5.0 * mm / 10.0
            others.append(loss)                              # round_trip_attenuation_db
    return np.unique(depths), np.unique(others)


def check_q1_copy(got):
    numbers = [float(v) for text in got["texts"] for v in re.findall(r"\d+(?:\.\d+)?", text)]
    floats = np.concatenate([got["floats"], numbers])
    floats = floats[np.isfinite(floats)]
    depths, others = q1_answers()
    for answer in np.concatenate([depths, others]):      # the grader's rule: close(1e-6, 1e-9)
        hit = floats[np.isclose(floats, answer, rtol=1e-6, atol=1e-9)]
        assert hit.size == 0, f"the students' copy gives {hit[0]!r}, a graded answer {answer!r}"
    for depth in depths:                                 # ... yet draws every displayed depth
        assert np.any(np.abs(got["floats"] - depth) <= 0.005 + 1e-9), f"no depth {depth}"


def test_q1_answers_are_the_exams_arithmetic():
    depths, others = q1_answers()
    water = 10 * C0 / 1482.0
    # ten faces: the three blocks share their top's depth, the water block's floor is the gap's
    assert depths.size == 10 - 2 - 1
    np.testing.assert_allclose(depths[[0, -1]], [water, 2 * water + 40 * C0 / 1450.0],
                               rtol=1e-12, atol=0)   # the floor is drawn deepest under the fat
    assert np.any(np.isclose(depths, 6 * water, rtol=1e-12))
    assert np.any(np.isclose(others, 40 * C0 / 1450.0)) and np.any(np.isclose(others, 20.22))


def test_check_flags_a_full_precision_depth():
    depths, _ = q1_answers()
    rounded = {"floats": np.round(depths, 2), "texts": []}
    check_q1_copy(rounded)
    with pytest.raises(AssertionError, match="graded answer"):
        check_q1_copy({"floats": np.append(np.round(depths, 2), depths[3]), "texts": []})
    with pytest.raises(AssertionError):                  # a copy that draws nothing
        check_q1_copy({"floats": np.zeros(0), "texts": []})


def _run_copy(python, tmp_path, env=None):
    out = tmp_path / "q1.pkl"
    proc = subprocess.run([str(python), "-I", "-c", Q1_COPY, str(out)], cwd=tmp_path,
                          env=env, capture_output=True, text=True, timeout=600, check=False)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return pickle.loads(out.read_bytes())


def test_instructors_figures_give_q1_depths_at_display_precision_only(tmp_path, monkeypatch):
    monkeypatch.setenv("MPLBACKEND", "Agg")
    got = _run_copy(sys.executable, tmp_path)
    assert set(got["present"]) == {"displayed_thickness", "displayed_depths",
                                   "round_trip_attenuation_db", "phantom_interfaces",
                                   "displayed_faces"}
    check_q1_copy(got)


@pytest.mark.slow
@pytest.mark.xdist_group("student_env")
def test_students_q1_copy_gives_no_graded_answer(tmp_path):
    """In the students' environment: the graded functions and the exact helpers are absent,
    and the figures and explorer give the phantom's displayed depths at display precision only."""
    if shutil.which("gcc") is None:
        pytest.skip("no C compiler (make wheel-deps)")
    import studentenv

    got = _run_copy(studentenv.python(), tmp_path, env=studentenv.env_vars())
    assert got["present"] == []
    check_q1_copy(got)
