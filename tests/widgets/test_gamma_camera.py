"""The collimator explorer (Q2(c)-(d)) driven from Python, headless (Agg).

Oracles: the exam's own Q2(d) numbers (25 of 81 holes open, 19.635 mm^2 over 7853.98 mm^2 =
0.25 %), the analytic cut-off ``d z / L``, the similar-triangles resolution ``d (L + z) / L``
written out here, the ring count ``1 + 4 n (n + 1)``, the on-axis transmission ``s^2`` and a
Monte Carlo photon trace for the exact fraction.
"""

from __future__ import annotations

import re

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

from course_lib import gamma_camera as gc  # noqa: E402
from course_lib.widgets import gamma_camera as wg  # noqa: E402


@pytest.fixture
def explorer():
    ex = wg.CollimatorExplorer()
    yield ex
    plt.close(ex.fig)


def _percent(html, label):
    """The first percentage after ``label`` in the readout."""
    m = re.search(re.escape(label) + r".*?([0-9.]+) %", html)
    assert m, f"{label!r} not in the readout: {html}"
    return float(m.group(1))


def test_exam_button_restores_q2d(explorer):
    """Q2(d): the centre, 8 and 16 holes open (25 of 81); 19.635 / 7853.98 = 0.25 %."""
    explorer.set(d=3.0, L=100.0, z=420.0, pitch=4.0, n_rings=7)   # 12.6 mm: rings 0-3
    assert explorer.results["n_open"] == 1 + 8 + 16 + 24
    explorer.exam_button.click()
    assert (explorer.d.value, explorer.L.value, explorer.z.value, explorer.pitch.value,
            explorer.n_rings.value) == (1.0, 40.0, 1000.0, 10.0, 4)
    exam_colours = np.asarray(explorer.art["exam"]["holes"].get_array())
    assert exam_colours.shape == (81,) and exam_colours.sum() == 25
    assert explorer.art["exam"]["face"].get_radius() == 50.0
    html = explorer.readout.value
    assert "25 of 81 holes open" in html
    assert _percent(html, "open fraction") == pytest.approx(0.25)
    assert explorer.results["exam_fraction"] == pytest.approx(19.635 / 7853.98, rel=1e-4)
    assert "25 of 81" in explorer.ax_exam.get_title()
    # the open holes are exactly those within the exam's 25 mm (rings 0, 1, 2 of 10 mm pitch)
    r = np.hypot(*explorer.holes.T)
    np.testing.assert_array_equal(exam_colours == 1, r <= 25.0 + 1e-9)


def test_doubling_z_doubles_the_cutoff(explorer):
    """Q2(d): the exam's cut-off radius d z / L is proportional to z."""
    cut = explorer.art["exam"]["cutoffs"][0]
    explorer.z.value = 500.0
    r1 = cut.get_radius()
    assert r1 == pytest.approx(1.0 * 500.0 / 40.0)
    assert explorer.results["n_open"] == 1 + 8          # 12.5 mm: the centre and ring 1
    explorer.z.value = 1000.0
    assert cut.get_radius() == pytest.approx(2 * r1)
    # the exact cut-off is half a hole further out, on both faces
    for key in ("exam", "exact"):
        inner, outer = explorer.art[key]["cutoffs"]
        assert inner.get_radius() == pytest.approx(25.0)
        assert outer.get_radius() == pytest.approx(25.5)


@pytest.mark.parametrize("d, L, z", [(1.0, 200.0, 200.0), (2.0, 40.0, 1000.0),
                                     (0.5, 30.0, 10.0)])
def test_side_view_resolution_matches_similar_triangles(explorer, d, L, z):
    """Q2(c): the bracket at the source plane is R = d (L + z) / L wide; the rays from the
    crystal behind the hole's centre pass through the edges of its mouth."""
    explorer.set(d=d, L=L, z=z)
    R = d * (L + z) / L
    assert R == pytest.approx(gc.collimator_resolution(d, L, z))
    x, y = explorer.art["side"]["bracket"].get_data()
    assert np.ptp(x) == pytest.approx(R, rel=5e-4) and list(y) == [z, z]   # 4 figures
    for ray in explorer.art["side"]["rays"]:
        (x0, x1), (y0, y1) = ray.get_data()
        assert (x0, y0) == (0.0, -L)
        # at the face (y = 0) the ray is at the mouth's edge, +-d/2
        x_face = x0 + (x1 - x0) * (0.0 - y0) / (y1 - y0)
        assert abs(x_face) == pytest.approx(d / 2, rel=5e-4)
    left, right = explorer.art["side"]["septa"]
    assert right.get_x() == pytest.approx(d / 2) and right.get_height() == pytest.approx(L)
    assert left.get_x() + left.get_width() == pytest.approx(-d / 2)
    assert f"{R:.4g} mm" in explorer.readout.value


def test_exact_colours_follow_the_lens_model(explorer):
    """Centre hole passes s^2 = (z / (z + L))^2 of its mouth; none beyond d z / L + d / 2;
    an open hole of the exam passes only part of its photons."""
    explorer.load_exam()
    share = np.asarray(explorer.art["exact"]["holes"].get_array())
    r = np.hypot(*explorer.holes.T)
    assert share[0] == pytest.approx((1000.0 / 1040.0) ** 2, abs=0.5e-4)    # 4 decimals
    assert np.all(share[r > 25.5] == 0.0)
    ring2 = (r > 15) & (r < 25)
    assert np.all((share[ring2] > 0) & (share[ring2] < 0.5))
    # exam / exact (uniform) on the exam's collimator: ~3.75, the exam overstates
    assert explorer.results["exam_fraction"] / explorer.results["exact_fraction"] > 3


def test_exact_fraction_agrees_with_monte_carlo(explorer):
    """The readout's exact transmission (photons uniform over the face) against a photon trace."""
    explorer.set(d=1.5, L=30.0, z=600.0, pitch=8.0, n_rings=3)
    Rf = 4 * 8.0
    holes = gc.ring_hole_positions(8.0, 3)
    f, se, _ = gc.trace_photons(holes, 1.5, 30.0, 600.0, Rf, 400_000, rng=7, emission="uniform")
    exact = explorer.results["exact_fraction"]
    assert abs(exact - f) < 4 * se
    assert _percent(explorer.readout.value, "exact transmission") == pytest.approx(
        100 * exact, rel=1e-3)


@pytest.mark.parametrize("n", [0, 1, 3, 8])
def test_rings_change_the_hole_count_and_face(explorer, n):
    """1 + 4 n (n + 1) holes on a face one pitch beyond the last ring."""
    explorer.set(n_rings=n, pitch=6.0)
    count = 1 + 4 * n * (n + 1)
    for key in ("exam", "exact"):
        coll = explorer.art[key]["holes"]
        assert len(coll.get_paths()) == count and len(coll.get_array()) == count
        assert explorer.art[key]["face"].get_radius() == pytest.approx((n + 1) * 6.0)
    # the drawn hole centres are the ring positions
    centres = np.array([(p.vertices.min(axis=0) + p.vertices.max(axis=0)) / 2 for p in
                        explorer.art["exam"]["holes"].get_paths()])
    np.testing.assert_allclose(np.sort(np.hypot(*centres.T)),
                               np.sort(np.hypot(*gc.ring_hole_positions(6.0, n).T)),
                               atol=1e-4 * (n + 1) * 6.0)       # display precision


def test_updates_create_no_new_artists(explorer):
    def snapshot():
        return [list(ax.get_children()) for ax in explorer.fig.axes]

    before = snapshot()
    for name, value in [("d", 2.0), ("L", 120.0), ("z", 250.0), ("pitch", 4.0),
                        ("n_rings", 7), ("n_rings", 1), ("z", 3000.0)]:
        getattr(explorer, name).value = value
    explorer.exam_button.click()
    after = snapshot()
    assert len(before) == len(after)
    for b, a in zip(before, after):
        assert len(b) == len(a) and all(x is y for x, y in zip(b, a))


def test_overlapping_holes_are_flagged(explorer):
    explorer.set(pitch=2.0, d=2.0)          # ring-1 spacing 2 * 2 sin(pi/8) = 1.53 mm < d
    assert explorer.results["overlap"] and "overlap" in explorer.readout.value
    # the models' fractions are meaningless then (they count overlapping areas twice and
    # pass 100 % for wider holes): not shown
    assert "holes open" not in explorer.readout.value and " %" not in explorer.readout.value
    assert "resolution" in explorer.readout.value
    explorer.load_exam()
    assert not explorer.results["overlap"] and "overlap" not in explorer.readout.value
    assert "holes open" in explorer.readout.value


def test_widget_layout(explorer):
    """The layout holds the readout and is built once (update speed: benchmarks/bench_widgets.py)."""
    import ipywidgets as W

    box = explorer.widget
    assert isinstance(box, W.VBox) and explorer.readout in box.children
    assert explorer.widget is box


def test_factory():
    ex = wg.collimator_explorer(d=2.0, n_rings=2)
    try:
        assert isinstance(ex, wg.CollimatorExplorer)
        assert ex.d.value == 2.0 and ex.results["n_holes"] == 25
    finally:
        plt.close(ex.fig)


def test_face_views_step_through_fixed_sizes_that_hold_the_whole_face():
    """Every pitch and ring count the sliders allow: the face views' half-width is one of
    ``FACE_LIMITS``, holds the face and every drawn hole with a margin, and at most 1.35 times
    what is needed; a half-pitch step keeps the limits in most cases (no new background)."""
    from course_lib.widgets.gamma_camera import (FACE_LIMITS, face_limit, face_radius,
                                                 hole_draw_radius)
    from course_lib.gamma_camera import ring_hole_positions

    kept = changed = 0
    for n in range(0, 9):
        previous = None
        for pitch in np.arange(2.0, 20.01, 0.5):
            r = np.hypot(*ring_hole_positions(pitch, n).T)
            reach = max(face_radius(pitch, n), r.max() + hole_draw_radius(5.0, pitch, n))
            lim = face_limit(reach)
            assert lim in FACE_LIMITS and 1.04 * reach <= lim <= 1.35 * 1.04 * reach
            if previous is not None:
                kept, changed = kept + (lim == previous), changed + (lim != previous)
            previous = lim
    assert kept > 2 * changed


@pytest.mark.parametrize("L, z", [(250.0, 10.0), (40.0, 1000.0), (5.0, 3000.0), (100.0, 100.0)])
def test_side_view_length_label_stays_off_the_crystal(explorer, L, z):
    """The "L = ... mm" label never covers the crystal bar (its 4 pt line at -L), stays inside
    the side view, and sits beside the septa whenever they are tall enough to hold it."""
    explorer.set(L=L, z=z)
    explorer.fig.canvas.draw()
    renderer = explorer.fig.canvas.get_renderer()
    label = explorer.art["side"]["labels"]["L"]
    box = label.get_bbox_patch().get_window_extent(renderer)
    crystal = explorer.art["side"]["crystal"]
    half_bar = crystal.get_linewidth() * explorer.fig.dpi / 72.0 / 2
    bar_y = crystal.get_transform().transform([[0.0, -L]])[0, 1]
    assert box.y1 < bar_y - half_bar or box.y0 > bar_y + half_bar, (box, bar_y)
    axes = explorer.ax_side.get_window_extent(renderer)
    assert axes.x0 <= box.x0 and box.x1 <= axes.x1 and axes.y0 <= box.y0 and box.y1 <= axes.y1
    face_y = crystal.get_transform().transform([[0.0, 0.0]])[0, 1]
    if face_y - bar_y > 3 * box.height:       # septa tall on screen: the label is beside them
        assert bar_y < box.y0 and box.y1 < face_y


def _significant(x, digits=4):
    return float(f"{x:.{digits}g}")


@pytest.mark.parametrize("seed", range(3))
def test_model_keeps_only_display_precision(seed):
    """Q2(c)-(d): everything ``collimator_model`` returns (and the explorer keeps) is the
    references' answer at the digits shown: hole centres within 1e-4 of the face radius and
    never to the grader's 1e-9, readout numbers to 4 significant figures, shares to 4 decimals,
    and none of the graded functions' exact answers."""
    rng = np.random.default_rng(seed)
    d, L, z = round(rng.uniform(0.2, 1.0), 3), rng.uniform(5.0, 250.0), rng.uniform(10.0, 3000.0)
    pitch, n = rng.uniform(5.0, 20.0), int(rng.integers(2, 9))
    model = wg.collimator_model(d, L, z, pitch, n)
    holes, res = model["holes"], model["results"]
    exact_holes = gc.ring_hole_positions(pitch, n)
    Rf = (n + 1) * pitch
    assert np.abs(holes - exact_holes).max() <= 0.5e-4 * Rf
    assert np.abs(holes - exact_holes).max() > 1e-9 * Rf          # not the graded answer
    R = d * (L + z) / L                                           # similar triangles
    assert res["resolution"] == _significant(R) and res["resolution_label"] == f"{R:.3g}"
    assert res["cutoff_exam"] == _significant(d * z / L)
    assert res["cutoff_exact"] == _significant(d * z / L + d / 2)
    r = np.hypot(*exact_holes.T)
    n_open = int(np.count_nonzero(r * L / z <= d))
    assert res["n_open"] == n_open and res["n_holes"] == 1 + 4 * n * (n + 1)
    assert res["exam_fraction"] == _significant(n_open * d**2 / (4 * Rf**2))
    np.testing.assert_array_equal(model["exam_open"], (r * L / z <= d).astype(float))
    share = gc.hole_pass_area(r, d, L, z) / (np.pi * d**2 / 4)
    assert np.abs(model["exact_share"] - share).max() <= 1e-4
    assert np.array_equal(model["exact_share"] > 0, share > 0)
    for key in ("exam_fraction", "exact_fraction", "isotropic_fraction", "resolution",
                "cutoff_exam", "cutoff_exact"):
        assert res[key] == _significant(res[key]), key


def test_explorer_keeps_the_model(explorer):
    explorer.set(d=0.7, L=33.0, z=770.0, pitch=7.5, n_rings=5)
    model = wg.collimator_model(0.7, 33.0, 770.0, 7.5, 5)
    np.testing.assert_array_equal(explorer.holes, model["holes"])
    np.testing.assert_array_equal(explorer.exact_share, model["exact_share"])
    assert explorer.results == model["results"]
    R = 0.7 * (33.0 + 770.0) / 33.0
    assert R != model["results"]["resolution"]                  # 4 figures only
    side = explorer.art["side"]
    for line in (*side["rays"], side["bracket"]):       # from the centre or across: +-R/2
        width = 2 * np.abs(np.asarray(line.get_xdata(), dtype=float)).max()
        assert width == _significant(R)
    for line in side["extreme"]:                          # edge to edge: d/2 + d z / L
        far = np.abs(np.asarray(line.get_xdata(), dtype=float)).max()
        assert far == _significant(0.35 + 0.7 * 770.0 / 33.0)
