"""Colours that survive colour-blindness, and meaning never carried by colour alone.

The course's palettes are checked under simulated deuteranopia, protanopia and tritanopia
(colorspacious: Machado et al. 2009 at severity 100, distances in CAM02-UCS): every two
colours that tell things apart stay at least :data:`MIN_DELTA_E` apart. And in every legend of
the course's figures, two entries differ in something besides colour (line style, marker,
line width, hatch, or the kind of mark), so a reader who cannot tell the colours apart can
still tell the entries apart.
"""

from __future__ import annotations

import itertools

import matplotlib
import numpy as np
import pytest
from matplotlib.colors import to_rgb

matplotlib.use("Agg")
colorspacious = pytest.importorskip("colorspacious")

from .figure_catalogue import figures  # noqa: E402

from course_lib.plots.gamma_camera import OPEN, SEPTUM, SHUT  # noqa: E402
from course_lib.plots.ultrasound import MATERIAL_COLOURS  # noqa: E402
from course_lib.plotting import COLOURS  # noqa: E402

CONDITIONS = (None, "deuteranomaly", "protanomaly", "tritanomaly")
#: the least CAM02-UCS distance between two colours of a palette (about 1 is just noticeable)
MIN_DELTA_E = 10.0
PALETTES = {
    "course": COLOURS,
    "collimator holes": {"open": OPEN, "shut": SHUT, "septum": SEPTUM},
    "phantom materials": MATERIAL_COLOURS,
}


def seen(colour, condition) -> np.ndarray:
    """``colour`` (any matplotlib colour) as sRGB in 0..1, as seen under ``condition``."""
    rgb = np.array(to_rgb(colour))
    if condition is None:
        return rgb
    cvd = {"name": "sRGB1+CVD", "cvd_type": condition, "severity": 100}
    return np.clip(colorspacious.cspace_convert(rgb, cvd, "sRGB1"), 0.0, 1.0)


def closest_pair(palette: dict, condition) -> tuple[float, str, str]:
    return min((colorspacious.deltaE(seen(palette[a], condition), seen(palette[b], condition),
                                     input_space="sRGB1"), a, b)
               for a, b in itertools.combinations(palette, 2))


def test_the_check_tells_a_palette_that_fails():
    """matplotlib's default red and green (the course's colours before) merge under
    deuteranopia: the check must see it."""
    old = {"red": "#d62728", "green": "#2ca02c"}
    assert closest_pair(old, None)[0] > MIN_DELTA_E
    assert closest_pair(old, "deuteranomaly")[0] < MIN_DELTA_E


@pytest.mark.parametrize("condition", CONDITIONS, ids=[c or "normal" for c in CONDITIONS])
@pytest.mark.parametrize("name", PALETTES)
def test_palette_colours_stay_apart(name, condition):
    distance, a, b = closest_pair(PALETTES[name], condition)
    assert distance >= MIN_DELTA_E, \
        f"{name}: {a} and {b} are only {distance:.1f} apart (CAM02-UCS) under {condition}"


DENSE_POINTS = 200
_PLOTTED: dict = {}


def _plotted(handle):
    """The data of the plotted line a legend handle stands for (a handle is a copy)."""
    return _PLOTTED.get(id(handle), handle.get_xdata())


def _style(handle) -> tuple:
    """What tells a legend entry apart besides its colour."""
    from matplotlib.collections import Collection
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    if isinstance(handle, Line2D):
        ls = handle.get_linestyle() if handle.get_linewidth() > 0 else "None"
        # a dash pattern cannot be seen along a jagged line of many samples (an echo trace):
        # there only a marker or a line width tells it apart
        if len(_plotted(handle)) > DENSE_POINTS:
            ls = "dense"
        marker = handle.get_marker() if handle.get_marker() not in ("", " ", None) else "None"
        return ("line", ls, marker, round(float(handle.get_linewidth()), 1),
                handle.get_markerfacecolor() == "none")
    if isinstance(handle, Patch):   # a legend's patch copies the dash pattern, not the style
        edge = handle.get_linewidth() > 0 and handle.get_edgecolor()[3] > 0
        return ("patch", handle.get_hatch(), handle.get_fill(), edge,
                str(getattr(handle, "_unscaled_dash_pattern", None)) if edge else None,
                handle.get_facecolor()[3] == 0)
    if isinstance(handle, Collection):
        return ("collection", type(handle).__name__, str(handle.get_hatch()))
    return (type(handle).__name__,)


FIGURES = figures()


@pytest.mark.parametrize("draw", [d for _, d in FIGURES], ids=[n for n, _ in FIGURES])
def test_legend_entries_differ_by_more_than_colour(draw):
    import matplotlib.pyplot as plt

    plt.close("all")
    draw()
    try:
        for fig in map(plt.figure, plt.get_fignums()):
            for ax in fig.axes:
                legend = ax.get_legend()
                if legend is None:
                    continue
                plotted = {ln.get_label(): ln for ln in ax.get_lines()}
                for t, h in zip(legend.get_texts(), legend.legend_handles):
                    if t.get_text() in plotted:
                        _PLOTTED[id(h)] = plotted[t.get_text()].get_xdata()
                entries = [(t.get_text(), _style(h))
                           for t, h in zip(legend.get_texts(), legend.legend_handles)]
                for (a, sa), (b, sb) in itertools.combinations(entries, 2):
                    assert sa != sb, f"legend entries '{a}' and '{b}' differ only by colour"
    finally:
        plt.close("all")
