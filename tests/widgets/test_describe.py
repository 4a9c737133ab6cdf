"""Text alternatives of figures written from their data (``course_lib.plots.describe``), how
they reach the notebook (an ``<img alt>`` beside the PNG, ``course_lib.plotting``) and the
explorers' canvases (``FigureCanvas.alt``, updated with each frame)."""

from __future__ import annotations

import base64
import html
import io
import re

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from PIL import Image  # noqa: E402

from course_lib.plots.describe import alt_text, num, set_summary  # noqa: E402
from course_lib.plotting import figure_html, install_alt_text  # noqa: E402

from .figure_catalogue import figures  # noqa: E402

FIGURES = figures()


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def test_a_curve_is_described_by_its_axes_and_extremes():
    """y = 4 - (x - 1)^2 on [-1, 3] (300 samples, x = 1 among them): highest 4 at x = 1,
    lowest 0 at both ends; the axis labels with their units."""
    fig, ax = plt.subplots()
    x = np.linspace(-1.0, 3.0, 301)
    ax.plot(x, 4 - (x - 1) ** 2, label="parabola")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("height (m)")
    ax.set_title("a throw")
    text = alt_text(fig)
    assert text.startswith("a throw.")
    assert "x axis time (s)" in text and "y axis height (m)" in text
    assert "'parabola' from (-1, 0) to (3, 0)" in text
    assert "highest 4 at x = 1" in text


def test_an_image_gives_its_size_and_value_range():
    fig, ax = plt.subplots()
    data = np.arange(12.0).reshape(3, 4) - 3.0          # -3 .. 8
    ax.imshow(data, cmap="viridis")
    assert "An image of 4 by 3 pixels, values from -3 to 8 shown on the viridis" in alt_text(fig)


def test_a_colour_image_gives_where_it_is_brightest():
    fig, ax = plt.subplots()
    rgb = np.zeros((5, 7, 3))
    rgb[3, 5] = 1.0                                     # one white pixel: luminance 1
    rgb[1, 1] = [0.0, 0.0, 1.0]                         # blue: luminance 0.0722
    ax.imshow(rgb)
    text = alt_text(fig)
    assert "brightest 1 at column 5, row 3" in text
    assert f"mean brightness {num((1 + 0.0722) / 35)}" in text


def test_bars_and_summaries_come_first():
    fig, (a, b) = plt.subplots(1, 2)
    a.bar([1, 2, 3], [5.0, 7.5, 2.25], label="counts")
    set_summary(fig, "Three bars, the tallest second.")
    set_summary(b, "Nothing here yet.")
    text = alt_text(fig)
    assert text.startswith("Three bars, the tallest second. Panel 1 of 2")
    assert "Bars 'counts' of heights 5, 7.5, 2.25." in text
    assert "Panel 2 of 2: Nothing here yet." in text


@pytest.mark.parametrize("draw", [d for _, d in FIGURES], ids=[n for n, _ in FIGURES])
def test_every_course_figure_has_a_text_alternative_from_its_data(draw):
    """At least a dozen words, numbers among them, and every axis label of the figure."""
    draw()
    for fig in map(plt.figure, plt.get_fignums()):
        text = alt_text(fig)
        assert len(text.split()) >= 12 and re.search(r"\d", text), text
        for ax in fig.axes:
            for label in (ax.get_xlabel(), ax.get_ylabel()):
                plain = re.sub(r"[${}\\]", "", label)
                assert " ".join(plain.split()) in text, (label, text)


def test_the_notebook_shows_the_png_with_its_alt():
    fig, ax = plt.subplots(figsize=(3, 2), dpi=50)
    ax.plot([0, 1], [0, 2], label='say "two"')
    ax.legend()
    out = figure_html(fig)
    alt = html.unescape(re.search(r'alt="([^"]*)"', out).group(1))
    assert alt == alt_text(fig) and 'say "two"' in alt
    png = base64.b64decode(re.search(r'src="data:image/png;base64,([^"]+)"', out).group(1))
    assert Image.open(io.BytesIO(png)).format == "PNG"
    assert figure_html(Figure()) is None                 # an empty figure shows nothing


def test_ipython_shows_every_figure_with_its_alt_even_after_the_inline_magic():
    from IPython.core.interactiveshell import InteractiveShell

    shell = InteractiveShell.instance()
    try:
        assert install_alt_text(shell)
        fig, ax = plt.subplots()
        ax.plot([0, 1, 2], [3, 1, 2])
        data, _ = shell.display_formatter.format(fig)
        assert 'alt="' in data["text/html"] and data["text/plain"] == alt_text(fig)
        # %matplotlib inline drops every formatter of Figure; the next cell brings it back
        for formatter in shell.display_formatter.formatters.values():
            formatter.pop(Figure, None)
        assert "text/html" not in shell.display_formatter.format(fig)[0]
        shell.events.trigger("pre_run_cell", None)
        assert 'alt="' in shell.display_formatter.format(fig)[0]["text/html"]
    finally:
        InteractiveShell.clear_instance()


def test_explorer_canvas_label_follows_the_figure():
    """The Phong explorer's canvas carries the figure's text alternative, rewritten when the
    light moves (the azimuth slider's new value is in it), and its readout is a live region."""
    from course_lib.widgets.shading import phong_explorer

    ex = phong_explorer()
    layout = ex.widget
    canvas = ex._view.widget(ex.fig)
    before = canvas.alt
    assert "lit from azimuth -45 degrees" in before and before == alt_text(ex.fig)
    ex.light_azimuth.value = 30.0
    assert "lit from azimuth 30 degrees" in canvas.alt
    assert "course-live" in ex.readout._dom_classes
    assert layout is ex.widget


def test_spline_explorer_label_gives_the_moved_point():
    from course_lib.widgets.splines import spline_end_explorer

    ex = spline_end_explorer()
    assert ex.widget is not None     # built: the canvas shows the figure
    canvas = ex._view.widget(ex.fig)
    ex.set_point(len(ex.points) - 1, (5.25, -1.5))
    assert "to (5.25, -1.5)" in canvas.alt, canvas.alt


def test_bscan_text_gives_each_block_as_drawn():
    """Q1(c): a block of speed c is drawn (c_assumed / c) times its thickness: the text
    alternative says so for the exam's phantom (fat 1450 m/s, liver 1578 m/s, 1540 assumed)."""
    from course_lib import ultrasound as us
    from course_lib.plots.ultrasound import bscan_summary

    phantom = us.exam_phantom()
    text = bscan_summary(phantom)
    for name, _x0, _x1, z0, z1 in phantom["blocks"]:
        c = us.material_properties(name)["c"]
        m = re.search(rf"{name} block [^;]*drawn from [\d.]+ to [\d.]+ mm \(([\d.]+) mm\)", text)
        assert m, text
        assert float(m.group(1)) == pytest.approx((z1 - z0) * 1540.0 / c, rel=5e-3)


def test_bscan_explorer_text_follows_the_speed():
    from course_lib.widgets.ultrasound import bscan_explorer

    ex = bscan_explorer()
    assert ex.widget is not None
    canvas = ex._view.widget(ex.fig)
    fat = re.search(r"fat block [^;]*\(([\d.]+) mm\);", canvas.alt)
    slider = next(w for w in _sliders(ex.widget) if w.description == "fat speed (m/s)")
    slider.value = slider.max
    fat_after = re.search(r"fat block [^;]*\(([\d.]+) mm\);", canvas.alt)
    assert float(fat_after.group(1)) < float(fat.group(1))   # faster fat: drawn thinner


def _sliders(layout):
    import ipywidgets as W

    todo = [layout]
    while todo:
        w = todo.pop()
        todo.extend(getattr(w, "children", ()))
        if isinstance(w, W.FloatSlider):
            yield w


def test_arrow_keys_turn_a_3d_view_as_dragging_does():
    """What the mouse does to a 3-D view the keyboard does too: an arrow key on the focused
    canvas (a message from the page) turns the view by TURN_DEG, a new frame is sent and the
    text alternative gives the new angles. A 2-D figure's canvas takes no keys."""
    from course_lib.widgets.marching_cubes import case_explorer
    from course_lib.widgets.shading import phong_explorer

    ex = case_explorer(1)
    assert ex.widget is not None
    canvas = ex._view.widget(ex.fig)
    painter = ex._view.blitter
    ax = next(a for a in ex.fig.axes if a.name == "3d")
    assert canvas.turnable
    azim, elev, frame = ax.azim, ax.elev, canvas.frame
    painter._on_msg(canvas, {"type": "key", "key": "ArrowRight"}, [])
    painter._on_msg(canvas, {"type": "key", "key": "ArrowUp", "shift": True}, [])
    painter._on_msg(canvas, {"type": "key", "key": "Enter"}, [])        # ignored
    assert ax.azim == pytest.approx(azim + painter.TURN_DEG)
    assert ax.elev == pytest.approx(elev + 3 * painter.TURN_DEG)
    assert canvas.frame == frame + 2
    assert f"azimuth {num(ax.azim)} degrees, elevation {num(ax.elev)} degrees" in canvas.alt

    flat = phong_explorer()
    assert flat.widget is not None
    assert not flat._view.widget(flat.fig).turnable


def test_a_curve_is_described_as_the_axes_show_it():
    """A trace drawn down to -120 on an axis cut at -100 reads -100 (what is shown); a
    computed zero reads 0, not rounding noise; a rectangle is a closed outline with its
    extent; a lone point is a point; a crowd of unnamed lines is not counted aloud."""
    fig, ax = plt.subplots()
    x = np.linspace(0.0, 10.0, 101)
    ax.plot(x, np.where(x < 5, -120.0, -20.0), label="echo")
    ax.plot([np.cos(np.pi / 2), 4.0], [0.0, -50.0], label="guide")    # cos(pi/2) = 6.1e-17
    ax.plot([2, 4, 4, 2, 2], [-60, -60, -40, -40, -60], label="box")
    ax.plot([3, 3], [-30, -30], label="spot")
    for k in range(6):
        ax.plot([k, k + 1], [-90, -90], color="k")
    ax.set_xlim(0, 10)
    ax.set_ylim(-100, 0)
    text = alt_text(fig)
    assert "'echo' from (0, -100) to (10, -20)" in text and "lowest -100" in text
    assert "-120" not in text
    assert "'guide' through (0, 0), (4, -50)" in text and "e-17" not in text
    assert "'box', a closed outline over x 2 to 4, y -60 to -40" in text
    assert "'spot' at the point (3, -30)" in text
    assert "unnamed" not in text


def test_phong_vectors_give_each_arrow_its_direction():
    """Q5(a) with L 40 degrees left of N and V 15 degrees right: R mirrors L (40 right) and
    H bisects L and V ((40 - 15) / 2 = 12.5 degrees left)."""
    from course_lib.plots.shading import plot_reflection_vectors

    fig, ax = plt.subplots()
    plot_reflection_vectors(40.0, -15.0, ax=ax)
    text = alt_text(fig)
    assert "L (towards the light) 40 degrees left of N" in text
    assert "R (the mirror reflection of L) 40 degrees right of N" in text
    assert "V (towards the viewer) 15 degrees right of N" in text
    assert "H (halfway between L and V) 12.5 degrees left of N" in text
