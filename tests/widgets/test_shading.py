"""The Phong explorer (Q5) driven from Python, headless (Agg)."""

from __future__ import annotations


import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

from course_lib.widgets import shading as ws

SQ3 = np.sqrt(3.0)


@pytest.fixture
def explorer():
    ex = ws.PhongExplorer(size=96)
    yield ex
    import matplotlib.pyplot as plt

    plt.close(ex.fig)


def _image(ex, k):
    """The sphere as drawn: 8-bit RGB, here as fractions of 255."""
    data = ex.art["images"][k].get_array()
    assert data.dtype == np.uint8
    return np.asarray(data, dtype=float) / 255

#: one level of an 8-bit channel (the images hold int(255 I))
LEVEL = 1 / 255


def test_direction_angles_round_trip():
    rng = np.random.default_rng(0)
    for v in rng.normal(size=(10, 3)):
        u = v / np.linalg.norm(v)
        a = ws.angles(v)              # to 0.01 degree: 0.005 degree is 8.7e-5 rad
        assert a == tuple(round(x, 2) for x in a)
        np.testing.assert_allclose(ws.direction(*a), u, rtol=0, atol=1.3e-4)
    np.testing.assert_allclose(ws.direction(90.0, 0.0), [0.0, 1.0, 0.0], atol=1e-15)
    assert ws.angles([1.0, -1.0, 1.0]) == pytest.approx((-45.0, np.degrees(np.arcsin(1 / SQ3))),
                                                        abs=0.005)


def test_hex_colours():
    np.testing.assert_allclose(ws.hex_to_rgb("#0000ff"), [0.0, 0.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(ws.hex_to_rgb("#f80"), [1.0, 136 / 255, 0.0], atol=1e-12)
    assert ws.rgb_to_hex([1.0, 0.5, 0.0]) == "#ff8000"
    with pytest.raises(ValueError):
        ws.hex_to_rgb("#12345")


def test_exam_button_shows_the_printed_answer(explorer):
    """Q5(b): the probe (the exam's N) reads (0.0931, 0.0931, 0.699) under Phong."""
    explorer.exam_button.click()
    np.testing.assert_allclose(explorer.L, np.array([1.0, -1.0, 1.0]) / SQ3, atol=1e-12)
    np.testing.assert_allclose(explorer.V, [0.0, 1.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(explorer.probe_values["Phong"], [0.0931, 0.0931, 0.699],
                               atol=5e-4)
    html = explorer.readout.value
    assert "0.0931" in html and "0.6988" in html
    # the browser rounds the sliders to their step (elevation 35.26 -> 35.5): still the exam's,
    # kept to the readout's 4 decimals
    explorer.light_elevation.value = 35.5
    exact = 0.5 + 0.25 * (1 - 1 / SQ3) + (0.5 + 0.5 / SQ3) ** 10
    np.testing.assert_allclose(explorer.probe_values["Phong"][2], exact, rtol=0,
                               atol=0.5e-4 + 1e-12)
    for values in explorer.probe_values.values():
        np.testing.assert_array_equal(values, np.round(values, 4))
    np.testing.assert_array_equal(explorer.halfway_shown, np.round(explorer.halfway_shown, 3))
    # moving a direction slider by a step or more leaves the exam's directions
    explorer.light_elevation.value = 36.0
    np.testing.assert_allclose(explorer.L, ws.direction(-45.0, 36.0), atol=1e-12)
    assert "0.0931" not in explorer.readout.value
    explorer.load_exam()
    # and the probe is drawn where N = (0, 1/2, sqrt3/2) lands seen from +y (right = -x, up = z)
    row_col = (explorer.probe_markers[0].get_ydata()[0], explorer.probe_markers[0].get_xdata()[0])
    x, y = 0.0, SQ3 / 2
    assert row_col == pytest.approx(((1 - y) * 48 - 0.5, (x + 1) * 48 - 0.5), abs=0.005 + 1e-9)


def test_images_change_in_place_with_the_controls(explorer):
    images = list(explorer.art["images"])
    before = _image(explorer, 0).copy()
    explorer.ka.value = 0.9
    assert explorer.art["images"] == images          # same artists, new data
    after = _image(explorer, 0)
    assert not np.allclose(before, after)
    # ambient raises every pixel on the sphere by c * d(ka) (clipped at 1)
    c = ws.hex_to_rgb(explorer.colour.value)
    mask = before.sum(-1) > 0
    diff = (after - before)[mask]
    unclipped = (after[mask] < 1.0).all(-1)
    np.testing.assert_allclose(diff[unclipped], np.broadcast_to(c * 0.7, diff[unclipped].shape),
                               atol=LEVEL + 1e-9)


def test_highlight_follows_the_light(explorer):
    """The ringed peak and the analytic cross sit where the normal is H = (L + V)/|L + V|."""
    explorer.set(view_azimuth=0.0, view_elevation=0.0)  # looking from +x: right = y, up = z
    for az, el in ((30.0, 20.0), (-40.0, -10.0), (10.0, 50.0)):
        explorer.set(light_azimuth=az, light_elevation=el)
        L, V = ws.direction(az, el), np.array([1.0, 0.0, 0.0])
        H = (L + V) / np.linalg.norm(L + V)
        expected = ((1 - H[2]) * 48 - 0.5, (H[1] + 1) * 48 - 0.5)
        for k in (0, 1):
            ring = (explorer.art["peaks"][k].get_ydata()[0], explorer.art["peaks"][k].get_xdata()[0])
            cross = (explorer.art["analytic"][k].get_ydata()[0],
                     explorer.art["analytic"][k].get_xdata()[0])
            assert cross == pytest.approx(expected, abs=0.005 + 1e-9)
            assert np.hypot(ring[0] - expected[0], ring[1] - expected[1]) <= 1.5


def test_exponent_tightens_the_highlight(explorer):
    """A larger n gives a smaller highlight; Blinn-Phong's is larger than Phong's for the same
    n (near the peak N.H falls off half as fast in angle as R.V, in the plane of L and V)."""
    explorer.set(colour="#000000", ka=0.0, kd=0.0, ks=1.0, view_azimuth=0.0, view_elevation=0.0,
                 light_azimuth=90.0, light_elevation=0.0)
    areas = []
    for n in (5.0, 50.0, 500.0):
        explorer.n.value = n
        areas.append([np.sum(_image(explorer, k)[..., 0] > 0.5) for k in (0, 1)])
    areas = np.array(areas)
    assert np.all(np.diff(areas, axis=0) < 0)
    assert np.all(areas[:, 0] < areas[:, 1])


def test_colour_picker_colours_the_diffuse_not_the_highlight(explorer):
    explorer.set(colour="#ff0000", ka=0.3, kd=0.5, ks=1.0, n=30.0)
    img = _image(explorer, 0)
    r, c = (int(v) for v in explorer.peaks[0])
    assert img[r, c, 1] > 0.5 and img[r, c, 2] > 0.5       # white highlight
    mask = img.sum(-1) > 0
    # green and blue carry only the (white) specular term; red adds c (Ia ka + Ip kd L.N)
    np.testing.assert_allclose(img[mask][:, 1], img[mask][:, 2], atol=1e-12)
    unclipped = mask & (img[..., 0] < 1.0)
    assert np.all(img[unclipped][:, 0] - img[unclipped][:, 1] >= 0.3 - LEVEL - 1e-9)
    assert np.all(img[unclipped][:, 0] - img[unclipped][:, 1] <= 0.8 + LEVEL + 1e-9)


def test_light_behind_no_highlight(explorer):
    explorer.set(view_azimuth=0.0, view_elevation=0.0, light_azimuth=180.0, light_elevation=0.0)
    assert explorer.peaks == [None, None]
    assert len(explorer.art["peaks"][0].get_xdata()) == 0
    assert "undefined" in explorer.readout.value


def test_widget_layout_headless(explorer):
    import ipywidgets as W

    box = explorer.widget
    assert isinstance(box, W.VBox)
    assert explorer.exam_button in box.children[1].children[1].children
    assert ws.phong_explorer(size=32).size == 32


def test_probe_readout_is_the_model_at_the_digits_shown(explorer):
    """The probe's intensities, worked out here by hand from the vectors (R and H built
    independently of course_lib), are what the explorer keeps and prints, to 4 decimals."""
    explorer.set(colour="#3366ff", ka=0.25, kd=0.55, ks=0.9, n=12.0, light_azimuth=60.0,
                 light_elevation=40.0, view_azimuth=100.0, view_elevation=20.0)
    L, V, N = ws.direction(60.0, 40.0), ws.direction(100.0, 20.0), explorer.probe
    c = ws.hex_to_rgb("#3366ff")
    R = 2 * (L @ N) * N - L
    H = (L + V) / np.linalg.norm(L + V)
    assert L @ N > 0 and N @ V > 0
    body = c * (0.25 + 0.55 * (L @ N))
    for key, cosine in (("Phong", R @ V), ("Blinn-Phong", N @ H)):
        want = body + 0.9 * max(cosine, 0.0) ** 12.0
        got = explorer.probe_values[key]
        np.testing.assert_allclose(got, want, rtol=0, atol=0.5e-4 + 1e-12)
        np.testing.assert_array_equal(got, np.round(got, 4))
        assert "(" + ", ".join(f"{x:.4f}" for x in got) + ")" in explorer.readout.value
    np.testing.assert_allclose(explorer.halfway_shown, H, rtol=0, atol=0.5e-3 + 1e-12)


def test_a_given_probe_is_kept_to_its_angles():
    ex = ws.PhongExplorer(size=32, probe=(0.0, 3.0, 1.0))
    try:
        u = np.array([0.0, 3.0, 1.0]) / np.sqrt(10.0)
        np.testing.assert_allclose(ex.probe, u, rtol=0, atol=1.3e-4)
        np.testing.assert_array_equal(ex.probe, ws.direction(*ws.angles(u)))
    finally:
        import matplotlib.pyplot as plt

        plt.close(ex.fig)
