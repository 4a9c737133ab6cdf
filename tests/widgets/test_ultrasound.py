"""The Q1(c) B-scan explorer: controls set from Python move the artists as the maths says.

Oracles: displayed height = true height * 1540 / c (time of flight, written out here), the
bath floor's displayed depth under a gap = floor depth * 1540 / c_water, the pulse length
scaling as 1 / frequency; and the per-update compute budget (< 50 ms).
"""

from __future__ import annotations


import matplotlib
import numpy as np
import pytest

from course_lib.widgets.ultrasound import BScanExplorer, bscan_explorer

matplotlib.use("Agg")


@pytest.fixture
def ex():
    e = bscan_explorer(nx=96, seed=1)
    yield e
    matplotlib.pyplot.close(e.fig)


def _outline_height(line):
    zs = np.asarray(line.get_ydata())
    return zs.max() - zs.min()


def _outline_top(line):
    return np.asarray(line.get_ydata()).min()


def test_factory_builds_an_explorer_with_controls(ex):
    assert isinstance(ex, BScanExplorer)
    assert len(ex.controls) == 8
    assert ex.im.get_array().shape[1] == 96
    assert len(ex.true_lines) == 3 and len(ex.shown_lines) == 4  # 3 blocks + the floor


def test_liver_speed_sets_its_displayed_height(ex):
    ex.c_liver.value = 1600.0
    liver = ex.shown_lines[1]
    # outlines are drawn at display precision (faces on a 0.01 mm grid): a height within 0.01
    assert _outline_height(liver) == pytest.approx(40.0 * 1540.0 / 1600.0, abs=0.01)
    ex.c_liver.value = 1540.0  # no distortion at the assumed speed
    assert _outline_height(liver) == pytest.approx(40.0, abs=0.01)
    # the true outline never moves
    assert _outline_height(ex.true_lines[1]) == pytest.approx(40.0)


def test_block_height_moves_true_and_displayed_outlines(ex):
    ex.t_fat.value = 25.0
    assert _outline_height(ex.true_lines[0]) == pytest.approx(25.0)
    c_fat = ex.c_fat.value
    assert _outline_height(ex.shown_lines[0]) == pytest.approx(25.0 * 1540.0 / c_fat, abs=0.01)
    assert "fat 25 -> " in ex.readout.value


def test_water_speed_moves_every_displayed_top_face(ex):
    ex.c_water.value = 1450.0
    for line in ex.shown_lines[:3]:
        assert _outline_top(line) == pytest.approx(10.0 * 1540.0 / 1450.0, abs=0.005)


def test_displayed_outlines_are_drawn_at_display_precision(ex):
    # 0.01 mm steps: finer than a pixel, coarser than the grader's 1e-6 of a graded answer
    ex.c_fat.value, ex.t_liver.value = 1432.0, 33.0
    for line in ex.shown_lines:
        zs = np.asarray(line.get_ydata())
        np.testing.assert_allclose(zs * 100, np.round(zs * 100), atol=1e-6)
    fat_top, fat_bottom = np.unique(np.asarray(ex.shown_lines[0].get_ydata()))
    exact = 10 * 1540 / ex.c_water.value + 40 * 1540 / 1432.0
    assert fat_bottom == pytest.approx(exact, abs=0.005) and fat_bottom != exact
    # the readout, text only, from the exact heights: 0.1 mm and a 3-decimal ratio
    assert f"fat 40 -> {40 * 1540 / 1432.0:.1f} mm" in ex.readout.value
    ratio = (33.0 * 1540 / ex.c_liver.value) / (40 * 1540 / 1432.0)
    assert f"liver / fat as displayed: {ratio:.3f}" in ex.readout.value
    assert not hasattr(ex, "displayed_heights")


def test_floor_echo_in_the_gap_a_line_follows_water_speed(ex):
    for c in (1450.0, 1540.0, 1620.0):
        ex.c_water.value = c
        depth, level = (np.asarray(a) for a in ex.a_lines[0].get_data())
        window = (depth > 50) & (depth < 70)
        peak = depth[window][np.argmax(level[window])]
        assert peak == pytest.approx(60.0 * 1540.0 / c, abs=0.1)


def test_image_pixels_change_in_place(ex):
    before = np.array(ex.im.get_array())
    im_id = id(ex.im)
    ex.c_fat.value = 1600.0
    after = np.array(ex.im.get_array())
    assert id(ex.im) == im_id and len(ex.ax_img.images) == 1  # no re-plotting
    assert before.shape == after.shape and not np.array_equal(before, after)


def test_frequency_scales_the_axial_sampling(ex):
    ex.freq.value = 4.0
    rows4 = ex.im.get_array().shape[0]
    ex.freq.value = 8.0
    rows8 = ex.im.get_array().shape[0]
    # the pulse (and the row spacing) shrink as 1 / frequency
    assert rows8 / rows4 == pytest.approx(2.0, rel=0.02)


def test_tgc_brightens_deep_tissue(ex):
    before = np.array(ex.im.get_array())
    ex.tgc.value = True
    after = np.array(ex.im.get_array())
    deep = slice(int(0.6 * before.shape[0]), int(0.7 * before.shape[0]))
    assert after[deep].mean() > before[deep].mean()


def test_readout_reports_the_exam_ratio(ex):
    # default speeds: liver / fat = 1450 / 1578 for equal true heights
    text = ex.readout.value
    assert f"{1450.0 / 1578.0:.3f}" in text
