"""Tests of course_lib.ultrasound (exam Q1(c); the phantom's 40 mm blocks, 10 mm water layers
and 5 MHz are the course's reconstruction, not the exam's numbers).

Oracles: the exam's own statements (fat and water shown too long, fat worse; liver too short,
about 10% smaller than the fat block of the same size; the floor closer under the liver and
brighter under the gaps), time-of-flight and decibel arithmetic written out by hand, hypothesis
laws, an RF simulation with pymust (Garcia's MUST) in a medium of the true speed, beamformed
assuming 1540 m/s, and the Rayleigh statistics of fully developed speckle.
"""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from course_lib import ultrasound as us
from course_lib.ultrasound import (
    displayed_depths,
    displayed_thickness,
    round_trip_attenuation_db,
)

C0 = 1540.0
C_FAT = us.MATERIALS["fat"]["c"]
C_LIVER = us.MATERIALS["liver"]["c"]
C_WATER = us.MATERIALS["water"]["c"]

speeds = st.floats(1000.0, 4000.0)
lengths = st.floats(0.0, 500.0)


# --------------------------------------------------------------------------------------------
# the material table is realistic (ranges in Duck 1990, Szabo 2014, Hoskins et al. 2010)


def test_material_table_within_published_ranges():
    assert 1420 <= C_FAT <= 1480 and 1540 < C_LIVER <= 1610 and 1470 <= C_WATER <= 1500
    assert 0.3 <= us.MATERIALS["fat"]["alpha"] <= 1.8
    assert 0.3 <= us.MATERIALS["liver"]["alpha"] <= 1.0
    assert us.MATERIALS["water"]["alpha"] < 0.01
    assert us.MATERIALS["water"]["alpha_power"] == 2.0  # water's loss grows as f^2 (Duck 1990)
    assert {us.MATERIALS[m]["alpha_power"] for m in ("fat", "liver")} == {1.0}
    assert 900 <= us.MATERIALS["fat"]["rho"] < 1000 < us.MATERIALS["liver"]["rho"] <= 1080


# --------------------------------------------------------------------------------------------
# the exam's statements, Q1(c)


def test_exam_fat_and_water_too_long_fat_worse():
    t = 40.0
    fat, water = displayed_thickness(t, C_FAT), displayed_thickness(t, C_WATER)
    assert fat > water > t


def test_exam_liver_too_short_and_about_ten_percent_smaller_than_fat():
    t = 40.0
    liver, fat = displayed_thickness(t, C_LIVER), displayed_thickness(t, C_FAT)
    assert liver < t
    shrink = 1.0 - liver / fat
    assert 0.05 < shrink < 0.12  # "about 10% smaller"
    assert shrink == pytest.approx(1.0 - C_FAT / C_LIVER, rel=1e-12)  # same-size blocks


def test_exam_floor_closer_under_liver_deeper_under_fat():
    layers = [10.0, 40.0, 10.0]
    gap = displayed_depths(layers, [C_WATER] * 3)[-1]
    liver = displayed_depths(layers, [C_WATER, C_LIVER, C_WATER])[-1]
    fat = displayed_depths(layers, [C_WATER, C_FAT, C_WATER])[-1]
    assert liver < gap < fat
    # by hand: 60 mm of water at 1482 m/s shown as 60 * 1540 / 1482
    assert gap == pytest.approx(60.0 * 1540.0 / 1482.0, rel=1e-12)


def test_displayed_thickness_from_time_of_flight():
    # the scanner measures the delay between the two face echoes and halves c_assumed * delay
    t_mm, c = 37.0, 1510.0
    delay = 2 * (t_mm * 1e-3) / c
    assert displayed_thickness(t_mm, c) == pytest.approx(C0 * delay / 2 * 1e3, rel=1e-12)
    assert displayed_thickness(t_mm, c, 1450.0) == pytest.approx(1450.0 * delay / 2 * 1e3)


def test_displayed_depths_from_echo_times():
    thick = np.array([3.0, 12.0, 0.5, 7.0])
    c = np.array([1480.0, 1600.0, 2500.0, 1450.0])
    arrival = np.array([2 * sum(thick[: i + 1] / c[: i + 1]) for i in range(4)])  # per mm
    np.testing.assert_allclose(displayed_depths(thick, c), C0 * arrival / 2, rtol=1e-12, atol=1e-12)


def test_displayed_thickness_broadcasts_and_returns_float_for_scalars():
    assert type(displayed_thickness(10.0, 1500.0)) is float
    out = displayed_thickness(np.ones((3, 1)), np.array([1400.0, 1540.0, 1700.0]))
    assert out.shape == (3, 3)
    np.testing.assert_allclose(out[0], [1540 / 1400, 1.0, 1540 / 1700], atol=1e-12)


# --------------------------------------------------------------------------------------------
# attenuation


def test_round_trip_exam_numbers_by_hand():
    # 4 cm of fat at 5 MHz, 0.6 dB/cm/MHz: 0.6 * 5 * 4 = 12 dB each way
    assert round_trip_attenuation_db(0.6, 5.0, 4.0) == pytest.approx(24.0)
    assert type(round_trip_attenuation_db(0.6, 5.0, 4.0)) is float


def test_round_trip_equals_product_of_intensity_transmissions():
    rng = np.random.default_rng(7)
    alpha, thick, f = rng.uniform(0, 1.5, 6), rng.uniform(0, 3, 6), 3.5
    # intensity fraction surviving each layer, each way, multiplied together
    survive = 1.0
    for a, d in zip(alpha, thick):
        survive *= (10 ** (-a * f * d / 10)) ** 2
    assert round_trip_attenuation_db(alpha, f, thick) == pytest.approx(
        -10 * math.log10(survive), rel=1e-9)


@settings(max_examples=50, deadline=None)
@given(st.floats(0, 2), st.floats(0.5, 20), st.floats(0, 10), st.floats(0, 1))
def test_round_trip_splitting_a_layer_changes_nothing(alpha, f, thick, share):
    whole = round_trip_attenuation_db(alpha, f, thick)
    split = round_trip_attenuation_db([alpha, alpha], f, [thick * share, thick * (1 - share)])
    assert split == pytest.approx(whole, rel=1e-9, abs=1e-12)
    assert round_trip_attenuation_db(alpha, 2 * f, thick) == pytest.approx(2 * whole, abs=1e-9)


def test_water_attenuation_grows_as_frequency_squared():
    # Duck (1990): pure water at 20 C, 0.0022 dB/cm/MHz^2, so 0.0022 * 25 = 0.055 dB/cm at 5 MHz
    assert us.attenuation_db_per_cm("water", 5.0) == pytest.approx(0.055, rel=1e-12)
    assert us.attenuation_db_per_cm("water", 10.0) == pytest.approx(
        4 * us.attenuation_db_per_cm("water", 5.0), rel=1e-12)
    assert us.attenuation_db_per_cm("liver", 10.0) == pytest.approx(
        2 * us.attenuation_db_per_cm("liver", 5.0), rel=1e-12)
    # 4 cm of water, down and back, at 5 MHz: 2 * 4 * 0.055 = 0.44 dB (not 0.1 dB)
    water = us.attenuation_db_per_cm("water", 5.0) / 5.0
    assert round_trip_attenuation_db(water, 5.0, 4.0) == pytest.approx(0.44, rel=1e-12)


def test_attenuation_db_per_cm_rejects_bad_input():
    with pytest.raises(ValueError, match="unknown material"):
        us.attenuation_db_per_cm("bone", 5.0)
    with pytest.raises(ValueError, match="freq_mhz"):
        us.attenuation_db_per_cm("water", 0.0)


# --------------------------------------------------------------------------------------------
# hypothesis laws


@settings(max_examples=100, deadline=None)
@given(lengths, lengths, st.floats(-3, 3), speeds, speeds)
def test_displayed_thickness_is_linear_in_thickness(t1, t2, a, c, ca):
    combo = abs(a) * t1 + t2
    lhs = displayed_thickness(combo, c, ca)
    rhs = abs(a) * displayed_thickness(t1, c, ca) + displayed_thickness(t2, c, ca)
    assert lhs == pytest.approx(rhs, rel=1e-9, abs=1e-9)


@settings(max_examples=100, deadline=None)
@given(lengths, speeds)
def test_no_distortion_when_speed_is_the_assumed_one(t, c):
    assert displayed_thickness(t, c, c) == pytest.approx(t, rel=1e-12, abs=1e-12)


@settings(max_examples=100, deadline=None)
@given(st.lists(st.tuples(st.floats(0, 100), speeds), min_size=1, max_size=12), speeds)
def test_displayed_depths_are_cumulative(layers, ca):
    thick, c = np.array(layers).T
    depths = displayed_depths(thick, c, ca)
    assert depths.shape == (len(layers),)
    np.testing.assert_allclose(np.diff(depths, prepend=0.0), displayed_thickness(thick, c, ca),
                               rtol=1e-9, atol=1e-9)
    assert np.all(np.diff(depths) >= 0)
    # adding a layer underneath does not move the faces above it
    more = displayed_depths(np.append(thick, 5.0), np.append(c, 1600.0), ca)
    np.testing.assert_allclose(more[:-1], depths, rtol=1e-12, atol=1e-12)


# --------------------------------------------------------------------------------------------
# bad input


@pytest.mark.parametrize("call", [
    lambda: displayed_thickness(-1.0, 1500.0),
    lambda: displayed_thickness(1.0, 0.0),
    lambda: displayed_thickness(1.0, -1500.0),
    lambda: displayed_thickness(1.0, 1500.0, 0.0),
    lambda: displayed_thickness(np.ones(3), np.full(4, 1500.0)),
    lambda: displayed_thickness(np.nan, 1500.0),
    lambda: displayed_thickness("thick", 1500.0),
    lambda: displayed_depths([1.0, 2.0], [1500.0]),
    lambda: displayed_depths([1.0, -2.0], [1500.0, 1500.0]),
    lambda: displayed_depths([1.0, 2.0], [1500.0, 0.0]),
    lambda: displayed_depths([[1.0, 2.0]], [[1500.0, 1500.0]]),
    lambda: displayed_depths([1.0], [1500.0], -1540.0),
    lambda: round_trip_attenuation_db([0.5, 0.6], 5.0, [1.0, 2.0, 3.0]),
    lambda: round_trip_attenuation_db(-0.5, 5.0, 1.0),
    lambda: round_trip_attenuation_db(0.5, 0.0, 1.0),
    lambda: round_trip_attenuation_db(0.5, [5.0, 6.0], 1.0),
    lambda: round_trip_attenuation_db(0.5, 5.0, -1.0),
])
def test_bad_input_raises_value_error(call):
    with pytest.raises(ValueError):
        call()


def test_error_messages_name_the_argument():
    with pytest.raises(ValueError, match="c_true"):
        displayed_thickness(1.0, -3.0)
    with pytest.raises(ValueError, match="same length"):
        displayed_depths([1.0, 2.0], [1500.0])


# --------------------------------------------------------------------------------------------
# pymust oracle: RF of point scatterers in a medium of the TRUE speed, beamformed at 1540 m/s


def _pymust_displayed_separation(c_true, z1=0.015, z2=0.025, fc=5e6, n_el=16):
    pymust = pytest.importorskip("pymust")
    param = pymust.utils.Param()
    param.fc, param.pitch, param.width = fc, 3e-4, 2.7e-4
    param.Nelements, param.bandwidth, param.radius = n_el, 75, np.inf
    param.c, param.fs = c_true, 16 * fc
    opt = pymust.utils.Options()
    opt.WaitBar, opt.ParPool = False, False
    x = np.zeros((1, 2))
    z = np.array([[z1, z2]])
    delays = np.zeros((1, n_el))  # plane wave straight down
    rf, _ = pymust.simus(x, z, np.ones((1, 2)), delays, param, opt)
    scanner = copy.deepcopy(param)
    scanner.c = C0  # the scanner's assumption
    iq = pymust.rf2iq(rf, scanner.fs, scanner.fc)
    peaks = []
    for zt in (z1, z2):
        zz = np.linspace(zt * 0.85, zt * 1.15, 1200).reshape(-1, 1)
        das = pymust.dasmtx(1j * np.array(iq.shape), np.zeros_like(zz), zz, delays, scanner)
        image = np.abs(das @ iq.flatten(order="F"))
        i = int(np.argmax(image))
        # parabolic refinement of the peak
        y0, y1, y2 = image[i - 1], image[i], image[i + 1]
        step = zz[1, 0] - zz[0, 0]
        peaks.append(zz[i, 0] + 0.5 * step * (y0 - y2) / (y0 - 2 * y1 + y2))
    return (peaks[1] - peaks[0]) * 1e3, C0 / fc * 1e3  # displayed separation, wavelength (mm)


@pytest.mark.parametrize("material", ["fat", "water", "liver"])
def test_pymust_beamformed_depth_matches_displayed_thickness(material):
    c_true = us.MATERIALS[material]["c"]
    shown, wavelength = _pymust_displayed_separation(c_true)
    expected = displayed_thickness(10.0, c_true)
    assert abs(shown - expected) < wavelength / 10, (shown, expected)
    # and the distortion is resolved: far from the true 10 mm
    assert abs(expected - 10.0) > 0.2


# --------------------------------------------------------------------------------------------
# the phantom geometry and the simulator


@pytest.fixture(scope="module")
def scan():
    ph = us.exam_phantom()
    image, x, depth, extent, env = us.simulate_bscan(**ph, nx=170, seed=3, return_envelope=True)
    return ph, image, x, depth, extent, env


def _columns(x, x0, x1, margin=1.5):
    return np.flatnonzero((x > x0 + margin) & (x < x1 - margin))


def test_phantom_interfaces_by_hand():
    ph = us.exam_phantom()
    x = np.array([5.0, 17.5, 42.5, 67.5])  # gap, fat, liver, water
    _xs, true, shown = us.phantom_interfaces(ph["blocks"], ph["floor_depth"], ph["width"], x=x)
    np.testing.assert_allclose(true[0, :1], [60.0], atol=1e-12)
    assert np.all(np.isnan(true[0, 1:]))
    np.testing.assert_allclose(true[1:], [[10, 50, 60]] * 3, atol=1e-12)
    k = 1540.0
    water = 10 * k / C_WATER
    np.testing.assert_allclose(shown[1], [water, water + 40 * k / C_FAT,
                                          2 * water + 40 * k / C_FAT], atol=1e-12)
    np.testing.assert_allclose(shown[2], [water, water + 40 * k / C_LIVER,
                                          2 * water + 40 * k / C_LIVER], atol=1e-12)
    np.testing.assert_allclose(shown[3], [water, 5 * water, 6 * water], atol=1e-12)
    np.testing.assert_allclose(shown[0, 0], 6 * water, atol=1e-12)


def test_simulator_returns_drawable_arrays(scan):
    ph, image, x, depth, extent, env = scan
    assert image.shape == env.shape == (depth.size, x.size)
    assert image.min() >= 0 and image.max() <= 1
    assert extent[0] == 0 and extent[1] == ph["width"] and extent[2] > extent[3]
    assert depth[-1] >= ph["floor_depth"]


def test_simulator_is_reproducible_with_a_seed():
    ph = us.exam_phantom()
    a = us.simulate_bscan(**ph, nx=64, seed=11)[0]
    b = us.simulate_bscan(**ph, nx=64, seed=11)[0]
    c = us.simulate_bscan(**ph, nx=64, seed=12)[0]
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


def _floor_echo(env, depth, cols, lo, hi):
    """Depth and level (dB) of the strongest echo between lo and hi, per column, medians."""
    rows = np.flatnonzero((depth >= lo) & (depth <= hi))
    sub = env[np.ix_(rows, cols)]
    where = depth[rows[np.argmax(sub, axis=0)]]
    return float(np.median(where)), float(np.median(20 * np.log10(sub.max(axis=0))))


def test_floor_displaced_under_blocks_measured_from_image(scan):
    _ph, _image, x, depth, _extent, env = scan
    gap_cols = np.concatenate([_columns(x, 0, 10), _columns(x, 75, 85)])
    d_gap, _ = _floor_echo(env, depth, gap_cols, 55, 68)
    d_liver, _ = _floor_echo(env, depth, _columns(x, 35, 50), 55, 68)
    d_fat, _ = _floor_echo(env, depth, _columns(x, 10, 25), 55, 68)
    # by hand: 60 mm of water vs 20 mm of water + 40 mm of tissue, times 1540/c
    assert d_gap == pytest.approx(60 * C0 / C_WATER, abs=0.1)
    assert d_liver == pytest.approx(20 * C0 / C_WATER + 40 * C0 / C_LIVER, abs=0.1)
    assert d_fat == pytest.approx(20 * C0 / C_WATER + 40 * C0 / C_FAT, abs=0.1)
    assert d_liver < d_gap - 2.0  # the exam: closer to the probe under the liver


def test_floor_brighter_under_gaps_by_the_tissue_round_trip_loss(scan):
    _ph, _image, x, depth, _extent, env = scan
    gap_cols = np.concatenate([_columns(x, 0, 10), _columns(x, 75, 85)])
    _, gap = _floor_echo(env, depth, gap_cols, 55, 68)
    _, liver = _floor_echo(env, depth, _columns(x, 35, 50), 55, 68)
    _, fat = _floor_echo(env, depth, _columns(x, 10, 25), 55, 68)
    _, water = _floor_echo(env, depth, _columns(x, 60, 75), 55, 68)

    def two_way_interfaces_db(c, rho):
        zw = C_WATER * us.MATERIALS["water"]["rho"]
        r = (c * rho - zw) / (c * rho + zw)
        return -2 * 10 * math.log10(1 - r**2)  # in and out of the block, down and up

    f = 5.0
    # expected difference: 2 * 4 cm * (alpha f of the tissue minus the 0.0022 f^2 dB/cm of the
    # water it displaces, Duck 1990)
    for level, name in ((liver, "liver"), (fat, "fat")):
        p = us.MATERIALS[name]
        loss = 2 * 4.0 * (p["alpha"] * f - 0.0022 * f**2)
        loss += two_way_interfaces_db(p["c"], p["rho"])
        assert gap - level == pytest.approx(loss, abs=0.5), name
    assert gap - liver > 15 and gap - fat > 15
    assert abs(gap - water) < 1.0  # the water block attenuates (almost) nothing


def test_block_lengths_measured_from_image(scan):
    ph, _image, x, depth, _extent, env = scan
    measured = {}
    for name, x0, x1, _z0, _z1 in ph["blocks"]:
        cols = _columns(x, x0, x1)
        top, _ = _floor_echo(env, depth, cols, 8, 12)
        bottom, _ = _floor_echo(env, depth, cols, 46, 56)
        measured[name] = bottom - top
        assert measured[name] == pytest.approx(40 * C0 / us.MATERIALS[name]["c"], abs=0.15)
    assert measured["fat"] > measured["water"] > 40.0 > measured["liver"]
    assert 0.05 < 1 - measured["liver"] / measured["fat"] < 0.12


def test_speckle_in_liver_is_fully_developed_rayleigh():
    # with TGC matched to the liver, the envelope inside the liver is Rayleigh distributed:
    # mean / std = sqrt(pi / (4 - pi)) = 1.913 (Burckhardt 1978; Wagner et al. 1983)
    ph = us.exam_phantom()
    _, x, depth, _, env = us.simulate_bscan(**ph, nx=200, seed=5, return_envelope=True)
    cols = _columns(x, 35, 50)
    rows = np.flatnonzero((depth > 15) & (depth < 25))
    # undo the attenuation profile by normalising each row by its mean intensity
    sample = env[np.ix_(rows, cols)]
    sample = sample / np.sqrt(np.mean(sample**2, axis=1, keepdims=True))
    snr = sample.mean() / sample.std()
    assert snr == pytest.approx(math.sqrt(math.pi / (4 - math.pi)), rel=0.1)


def test_tgc_lifts_deep_echoes_by_the_documented_gain():
    ph = us.exam_phantom()
    off = us.simulate_bscan(**ph, nx=48, seed=2, dynamic_range_db=200.0)
    on = us.simulate_bscan(**ph, nx=48, seed=2, dynamic_range_db=200.0, tgc_db_per_cm_mhz=0.5)
    depth = off[2]
    gain_db = (on[0] - off[0]) * 200.0
    row = int(np.searchsorted(depth, 30.0))
    # 2 * 0.5 dB/cm/MHz * 5 MHz * 3 cm = 15 dB at 30 mm, wherever the echo is not clipped
    ok = (off[0][row] > 0) & (on[0][row] < 1)
    np.testing.assert_allclose(gain_db[row, ok], 2 * 0.5 * 5 * depth[row] / 10, atol=1e-6)


def test_speed_override_moves_the_displayed_interfaces():
    ph = us.exam_phantom()
    x = np.array([42.5])
    _, _, shown = us.phantom_interfaces(ph["blocks"], ph["floor_depth"], ph["width"], x=x,
                                        speeds={"liver": 1540.0})
    np.testing.assert_allclose(shown[0, 1] - shown[0, 0], 40.0, atol=1e-12)


@pytest.mark.parametrize("kwargs", [
    {"speeds": {"fat": 0.0}},
    {"freq_mhz": 0.0},
    {"c_assumed": -1.0},
    {"nx": 1},
    {"dynamic_range_db": 0.0},
])
def test_simulator_bad_input(kwargs):
    with pytest.raises(ValueError):
        us.simulate_bscan(**us.exam_phantom(), **kwargs)


def test_phantom_bad_input():
    with pytest.raises(ValueError):
        us.exam_phantom(fat_thickness=-1.0)
    with pytest.raises(ValueError):
        us.exam_phantom(floor_depth=30.0)
    with pytest.raises(ValueError, match="unknown material"):
        us.simulate_bscan((("bone", 0, 1, 1, 2),), 10.0, 5.0)
    with pytest.raises(ValueError, match="overlap"):
        us.simulate_bscan((("fat", 0, 2, 1, 3), ("liver", 1, 3, 2, 4)), 10.0, 5.0)
    with pytest.raises(ValueError, match="bath"):
        us.phantom_interfaces((), 10.0, 5.0, bath="air")


# --------------------------------------------------------------------------------------------
# figures (course_lib.plots.ultrasound): the artists carry the geometry computed by hand


def test_figures_draw_true_and_displayed_geometry():
    import matplotlib.pyplot as plt

    from course_lib.plots import ultrasound as uplots

    ph = us.exam_phantom()
    fig, art = uplots.phantom_and_bscan(ph, nx=48, show_displayed=True)
    try:
        bscan = art["bscan"]
        assert len(fig.axes) == 2 and bscan["image"].get_array().shape[1] == 48
        for line, (_, x0, x1, z0, z1) in zip(bscan["true"], ph["blocks"]):
            xs, zs = line.get_data()
            assert (min(xs), max(xs), min(zs), max(zs)) == (x0, x1, z0, z1)
        # drawn at display precision: on a 0.01 mm grid (1e-4 of the ~62 mm displayed floor,
        # rounded to a power of ten), so within 0.005 mm of the time-of-flight depth
        water = 10 * C0 / C_WATER
        fat_shown = np.asarray(bscan["displayed"][0].get_ydata())
        assert fat_shown.min() == pytest.approx(water, abs=0.005)
        assert fat_shown.max() == pytest.approx(water + 40 * C0 / C_FAT, abs=0.005)
        xs, floor = (np.asarray(a) for a in bscan["displayed"][-1].get_data())
        under_liver = floor[(xs > 36) & (xs < 49)]
        np.testing.assert_allclose(under_liver, 2 * water + 40 * C0 / C_LIVER, atol=0.005)
        in_gap = floor[xs < 9]
        np.testing.assert_allclose(in_gap, 6 * water, atol=0.005)
        for line in bscan["displayed"]:
            zs = np.asarray(line.get_ydata())
            np.testing.assert_allclose(zs * 100, np.round(zs * 100), atol=1e-6)
    finally:
        plt.close(fig)


def test_aline_figure_plots_the_envelope_in_db():
    import matplotlib.pyplot as plt

    from course_lib.plots import ultrasound as uplots

    ph = us.exam_phantom()
    _, x, depth, _, env = us.simulate_bscan(**ph, nx=40, seed=9, return_envelope=True)
    fig, ax = plt.subplots()
    try:
        art = uplots.plot_aline(depth, env, x, [42.5], ax, phantom=ph)
        d, level = art["lines"][0].get_data()
        np.testing.assert_array_equal(d, depth)
        j = int(np.argmin(np.abs(x - 42.5)))
        np.testing.assert_allclose(level, 20 * np.log10(np.maximum(env[:, j], 1e-6)), rtol=1e-6, atol=1e-12)
        assert len(art["markers"]) == 4  # three interfaces under the liver + the true floor
    finally:
        plt.close(fig)


def test_symmetric_blur_is_numpys_same_size_convolution():
    """Q1(c) pulse and beam blur: oracle ``numpy.convolve``'s full convolution, row by row and
    column by column, cropped to the samples the centred kernel lands on (its
    ``mode="same"`` when the kernel is the shorter), for kernels shorter and longer than the
    signal."""
    from course_lib.ultrasound import _symmetric_blur

    rng = np.random.default_rng(5)
    a = (rng.standard_normal((6, 40)) + 1j * rng.standard_normal((6, 40))).astype(np.complex64)
    for taps in (1, 5, 17, 81):
        w = np.exp(-0.5 * np.linspace(-3, 3, taps) ** 2)
        half = taps // 2
        rows = np.array([np.convolve(r, w)[half:half + len(r)] for r in a])
        cols = np.array([np.convolve(c, w)[half:half + len(c)] for c in a.T]).T
        np.testing.assert_allclose(_symmetric_blur(a, w, axis=1), rows, rtol=1e-5, atol=1e-5)
        np.testing.assert_allclose(_symmetric_blur(a, w, axis=0), cols, rtol=1e-5, atol=1e-5)
        assert _symmetric_blur(a, w, axis=1).dtype == np.complex64


def test_speckle_draws_are_the_seeds_draws_kept_read_only():
    """Oracle: ``default_rng(seed)``'s uniform then normal draws. An integer seed's draws are
    kept (read-only, so no caller can spoil the next image); ``None`` draws afresh."""
    from course_lib.ultrasound import _speckle_draws

    uniform, amp = _speckle_draws(7, 3, 11)
    rng = np.random.default_rng(7)
    np.testing.assert_array_equal(uniform, rng.random((3, 11)))
    np.testing.assert_array_equal(amp, rng.standard_normal((3, 11)))
    np.testing.assert_array_equal(_speckle_draws(np.int64(7), 3, 11)[0], uniform)
    with pytest.raises(ValueError):
        uniform[0, 0] = 1.0
    with pytest.raises(ValueError):                      # nor made writable again
        uniform.flags.writeable = True
    assert not np.array_equal(_speckle_draws(None, 3, 11)[1], _speckle_draws(None, 3, 11)[1])


@pytest.mark.parametrize("name", ["displayed_thickness", "displayed_depths", "phantom_interfaces",
                                  "displayed_faces", "simulate_bscan"])
def test_every_default_assumed_speed_is_the_scanners(name):
    import inspect

    default = inspect.signature(getattr(us, name)).parameters["c_assumed"].default
    assert default == us.C_ASSUMED == 1540.0
