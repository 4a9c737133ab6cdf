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
    return np.asarray(ex.art["images"][k].get_array(), dtype=float)


def test_direction_angles_round_trip():
    rng = np.random.default_rng(0)
    for v in rng.normal(size=(10, 3)):
        u = v / np.linalg.norm(v)
        np.testing.assert_allclose(ws.direction(*ws.angles(v)), u, atol=1e-12)
    np.testing.assert_allclose(ws.direction(90.0, 0.0), [0.0, 1.0, 0.0], atol=1e-15)
    assert ws.angles([1.0, -1.0, 1.0]) == pytest.approx((-45.0, np.degrees(np.arcsin(1 / SQ3))))


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
    np.testing.assert_allclose(explorer.probe_values["phong"], [0.0931, 0.0931, 0.699],
                               atol=5e-4)
    html = explorer.readout.value
    assert "0.0931" in html and "0.6988" in html
    # the browser rounds the sliders to their step (elevation 35.26 -> 35.5): still the exam's
    explorer.light_elevation.value = 35.5
    np.testing.assert_allclose(explorer.probe_values["phong"][2], 0.5 + 0.25 * (1 - 1 / SQ3)
                               + (0.5 + 0.5 / SQ3) ** 10, rtol=1e-12, atol=1e-12)
    # moving a direction slider by a step or more leaves the exam's directions
    explorer.light_elevation.value = 36.0
    np.testing.assert_allclose(explorer.L, ws.direction(-45.0, 36.0), atol=1e-12)
    assert "0.0931" not in explorer.readout.value
    explorer.load_exam()
    # and the probe is drawn where N = (0, 1/2, sqrt3/2) lands seen from +y (right = -x, up = z)
    row_col = (explorer.probe_markers[0].get_ydata()[0], explorer.probe_markers[0].get_xdata()[0])
    x, y = 0.0, SQ3 / 2
    assert row_col == pytest.approx(((1 - y) * 48 - 0.5, (x + 1) * 48 - 0.5))


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
                               atol=1e-9)


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
            assert cross == pytest.approx(expected)
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
    assert np.all(img[unclipped][:, 0] - img[unclipped][:, 1] >= 0.3 - 1e-9)
    assert np.all(img[unclipped][:, 0] - img[unclipped][:, 1] <= 0.8 + 1e-9)


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
