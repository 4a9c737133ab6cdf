"""The private matplotlib and ipywidgets APIs behind :mod:`course_lib._private_apis`.

Each test checks one private name the shim relies on: that it still exists, takes the
arguments the shim passes, and does what the explorers need of it, on real figures and
widgets. A new matplotlib or ipywidgets release that breaks one fails here, by name, before
an explorer misdraws; the upper bound on matplotlib in ``pyproject.toml`` is raised only once
this file passes on the new series.
"""

import inspect
import re
import tomllib
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import ipywidgets as W  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib import font_manager, ft2font  # noqa: E402
from matplotlib.backends.backend_agg import RendererAgg  # noqa: E402
from matplotlib.font_manager import FontProperties  # noqa: E402
from matplotlib.textpath import TextToPath  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Line3DCollection  # noqa: E402
from packaging.requirements import Requirement  # noqa: E402
from packaging.version import Version  # noqa: E402

from course_lib import _private_apis as api  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]


def _params(func) -> list[str]:
    return list(inspect.signature(func).parameters)


@pytest.fixture
def fig():
    figure = plt.figure(figsize=(4, 3), dpi=100)
    yield figure
    plt.close(figure)


# -- the bounds -----------------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["matplotlib", "ipywidgets"])
def test_pyproject_bounds_each_library_to_what_the_shim_was_checked_against(name):
    """The checked series is allowed and nothing newer than it (matplotlib: the next minor
    release; ipywidgets: the next major one) is."""
    deps = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dependencies"]
    spec = next(Requirement(d) for d in deps if Requirement(d).name == name).specifier
    major, minor = (int(v) for v in api.CHECKED[name].split("."))
    newer = Version(f"{major}.{minor + 1}") if name == "matplotlib" else Version(f"{major + 1}.0")
    assert spec.contains(Version(f"{major}.{minor}.0")) and spec.contains(f"{major}.{minor}.99")
    assert not spec.contains(newer), f"{name} {spec} lets in {newer}, which no one checked"


@pytest.mark.parametrize("module", [matplotlib, W])
def test_the_installed_release_is_no_newer_than_the_checked_one(module):
    installed = Version(re.match(r"\d+\.\d+", module.__version__).group())
    assert installed <= Version(api.CHECKED[module.__name__]), (
        f"{module.__name__} {module.__version__} is newer than the {api.CHECKED[module.__name__]} "
        "the private APIs were checked against")


# -- matplotlib -----------------------------------------------------------------------------------

def test_update_title_position_places_a_moved_title_back(fig):
    """``Axes._update_title_position(renderer)``: where a draw puts the title."""
    from matplotlib.axes import Axes

    assert _params(Axes._update_title_position) == ["self", "renderer"]
    ax = fig.add_subplot()
    ax.set_title("a title")
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    placed = ax.title.get_position()
    ax.title.set_y(0.0)
    api.place_title(ax, renderer)
    assert ax.title.get_position() == pytest.approx(placed)
    assert ax.title.get_position()[1] >= 1.0          # above the axes, not where it was moved


@pytest.mark.parametrize("loc, expected", [("best", True), (0, True), ("upper left", False),
                                           (2, False), (None, True)])
def test_legend_loc_tells_a_legend_that_places_itself(fig, loc, expected):
    """``Legend._loc``: 0 for ``"best"`` (an axes legend's default), a code otherwise."""
    ax = fig.add_subplot()
    ax.plot([0, 1], label="line")
    legend = ax.legend(loc=loc) if loc is not None else ax.legend()
    assert api.legend_places_itself(legend) is expected


def test_figure_texts_are_the_suptitle_supxlabel_and_supylabel(fig):
    fig.add_subplot()
    assert api.figure_texts(fig) == [None, None, None]
    assert api.suptitle_text(fig) == ""
    title, xlabel = fig.suptitle("Top"), fig.supxlabel("Across")
    texts = api.figure_texts(fig)
    assert texts[0] is title and texts[1] is xlabel and texts[2] is None
    assert api.suptitle_text(fig) == "Top"
    fig.supylabel("Up")
    assert api.figure_texts(fig)[2].get_text() == "Up"


def test_a_colorbar_axes_knows_its_colorbar(fig):
    ax = fig.add_subplot()
    image = ax.imshow(np.arange(6.0).reshape(2, 3))
    bar = fig.colorbar(image)
    assert api.colorbar_of(bar.ax) is bar
    assert api.colorbar_of(ax) is None


def test_a_3d_line_collection_keeps_its_segments_before_it_is_drawn(fig):
    """``Line3DCollection._segments3d``. (A ``Poly3DCollection`` keeps its faces as ``_faces``
    in matplotlib 3.11: :func:`course_lib.plots.describe.alt_text` counts them from its 2-D
    paths, which it has once drawn.)"""
    ax = fig.add_subplot(projection="3d")
    segments = [[(0, 0, 0), (1, 0, 0)], [(0, 0, 1), (1, 0, 1)], [(0, 0, 2), (1, 0, 2)]]
    collection = ax.add_collection3d(Line3DCollection(segments))
    assert len(collection.get_paths()) == 0
    assert len(api.segments_3d(collection)) == 3
    flat = fig.add_subplot().scatter([0, 1], [0, 1])
    assert api.segments_3d(flat) is None


def test_a_renderer_keeps_a_text_to_path_and_it_finds_the_font_of_a_property():
    """``RendererBase._text2path`` and ``TextToPath._get_font(prop)``: the font file that
    matplotlib's own font lookup picks for the property."""
    assert _params(TextToPath._get_font) == ["self", "prop"]
    text2path = api.text_to_path(RendererAgg(50, 50, 72))
    assert isinstance(text2path, TextToPath)
    prop = FontProperties(family="DejaVu Sans", size=12)
    font = api.font_of(text2path, prop)
    expected = ft2font.FT2Font(font_manager.findfont(prop))
    assert (font.family_name, font.style_name) == (expected.family_name, expected.style_name)
    glyphs = text2path.get_glyphs_with_font(font, "Ab", return_new_glyphs_only=True)[0]
    assert len(glyphs) == 2


def test_the_text_metrics_cache_gives_the_width_agg_measures(fig):
    """``text._get_text_metrics_with_cache(renderer, text, fontprop, ismath, dpi)``."""
    from matplotlib import text as mtext

    assert _params(mtext._get_text_metrics_with_cache) == ["renderer", "text", "fontprop",
                                                           "ismath", "dpi"]
    fig.text(0.5, 0.5, "width of this", fontsize=14)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    prop = FontProperties(size=14)
    width = api.cached_text_width(renderer, "width of this", prop, fig.dpi)
    assert width is not None
    assert width == pytest.approx(renderer.get_text_width_height_descent(
        "width of this", prop, False)[0])
    assert width > 50


def test_an_artist_sets_a_graphics_context_clip_to_its_axes(fig):
    """``Artist._set_gc_clip(gc)``: the clip rectangle of a clipped image is its axes' box."""
    from matplotlib.artist import Artist

    assert _params(Artist._set_gc_clip) == ["self", "gc"]
    ax = fig.add_subplot()
    image = ax.imshow(np.ones((2, 2)))
    fig.canvas.draw()
    gc = fig.canvas.get_renderer().new_gc()
    assert gc.get_clip_rectangle() is None
    api.clip_gc(image, gc)
    assert gc.get_clip_rectangle().bounds == pytest.approx(ax.bbox.bounds)
    gc.restore()


def test_an_image_gives_its_alpha_as_one_number(fig):
    """``_ImageBase._get_scalar_alpha()``: the alpha set, 1 when it is per pixel."""
    ax = fig.add_subplot()
    image = ax.imshow(np.ones((2, 2)))
    assert api.scalar_alpha(image) == 1.0
    image.set_alpha(0.3)
    assert api.scalar_alpha(image) == pytest.approx(0.3)
    image.set_alpha(np.full((2, 2), 0.5))
    assert api.scalar_alpha(image) == 1.0


# -- ipywidgets -----------------------------------------------------------------------------------

def _state_message(state: dict) -> dict:
    """A comm message from the page that sets ``state`` (ipywidgets' "update" method)."""
    return {"content": {"data": {"method": "update", "state": state, "buffer_paths": []}},
            "buffers": []}


def test_a_widget_handles_a_message_from_the_page_and_locks_what_it_sets():
    """``Widget._handle_msg(msg)`` sets the state the page sent and fires the observers with
    the property in ``_property_lock``; a value set in the kernel is not locked."""
    slider = W.IntSlider(value=1, min=0, max=10)
    seen = []
    slider.observe(lambda change: seen.append((change["new"],
                                               api.set_from_page(slider, "value"))), "value")
    handle = api.message_handler(slider)
    assert callable(handle) and handle.__self__ is slider
    handle(_state_message({"value": 7}))
    slider.value = 3
    assert seen == [(7, True), (3, False)]
    assert slider.value == 3
