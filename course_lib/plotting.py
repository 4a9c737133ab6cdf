"""Figure helpers shared by the notebooks' figures and the explorers.

Topic figures live in ``course_lib/plots/<topic>.py`` and explorers in
``course_lib/widgets/<topic>.py``; both use these helpers so that every figure of the course looks
alike and every explorer can update its artists in place.
"""

from __future__ import annotations

import matplotlib.pyplot as plt

#: Colours used across the course: reference/expected vs student/received, etc.
COLOURS = {
    "curve": "#1f77b4",
    "control": "#7f7f7f",
    "highlight": "#d62728",
    "reference": "#2ca02c",
    "received": "#ff7f0e",
    "hull": "#9467bd",
}


def new_figure(ncols: int = 1, nrows: int = 1, size: float = 4.0, **kwargs):
    """A figure of ``nrows x ncols`` square panels ``size`` inches wide; returns ``(fig, axes)``."""
    fig, axes = plt.subplots(nrows, ncols, figsize=(size * ncols, size * nrows),
                             squeeze=False, **kwargs)
    fig.set_layout_engine("constrained")
    return fig, axes if axes.size > 1 else axes[0, 0]


def equal_axes(ax, title: str | None = None, grid: bool = True):
    """Equal aspect ratio, optional title and a light grid."""
    ax.set_aspect("equal", adjustable="datalim")
    if title:
        ax.set_title(title)
    if grid:
        ax.grid(True, alpha=0.3)
    return ax
