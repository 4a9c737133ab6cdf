"""Figure helpers shared by the notebooks' figures and the explorers.

Topic figures live in ``course_lib/plots/<topic>.py`` and explorers in
``course_lib/widgets/<topic>.py``; both use these helpers so that every figure of the course looks
alike and every explorer can update its artists in place.
"""

from __future__ import annotations

import matplotlib.pyplot as plt

#: Colours used across the course: reference/expected vs student/received, etc. Okabe and Ito's
#: palette for colour-blind viewers (with a darker grey): every two of them stay at least 10
#: apart in CAM02-UCS under simulated deuteranopia, protanopia and tritanopia
#: (``tests/course_lib/test_colours.py``), and figures tell their curves apart by line style,
#: marker or a label as well, never by colour alone.
COLOURS = {
    "curve": "#0072b2",
    "control": "#555555",
    "highlight": "#d55e00",
    "reference": "#009e73",
    "received": "#e69f00",
    "hull": "#cc79a7",
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


# -- figures with a text alternative in the notebook ------------------------------------------
# JupyterLab 4 shows an ``image/png`` output as an <img> without ``alt`` (its image renderer
# reads no metadata for one), so a screen reader says "image" and nothing else. A figure is
# shown here also as ``text/html``: the same PNG in an <img> whose ``alt`` is the figure's
# text alternative (``plots.describe.alt_text``), which JupyterLab prefers to the PNG and which
# stays in the saved notebook; ``text/plain`` carries the same words for text-only frontends.
# The ``image/png`` output stays (nbconvert, the grader's pages and other frontends use it).


def figure_html(fig) -> str | None:
    """The HTML of ``fig`` as the notebook shows it: its PNG in an ``<img>`` whose ``alt`` is
    :func:`course_lib.plots.describe.alt_text` of the figure (``None`` for an empty figure,
    which the inline backend does not show either)."""
    import base64
    import html

    from .plots.describe import alt_text

    if not fig.axes and not fig.texts and not fig.images:
        return None
    png = base64.b64encode(_figure_png(fig)).decode("ascii")
    return (f'<img src="data:image/png;base64,{png}" alt="{html.escape(alt_text(fig), quote=True)}"/>')


def _figure_png(fig) -> bytes:
    """``fig`` as PNG bytes, drawn as the inline backend draws it (tight box, its options)."""
    from IPython.core.pylabtools import print_figure

    kwargs = {"bbox_inches": "tight"}
    try:
        from matplotlib_inline.config import InlineBackend

        if InlineBackend.initialized():
            kwargs.update(InlineBackend.instance().print_figure_kwargs)
    except ImportError:  # pragma: no cover - matplotlib-inline comes with ipykernel
        pass
    return print_figure(fig, "png", **kwargs)


def _plain(fig, printer, cycle) -> None:
    from .plots.describe import alt_text

    printer.text(alt_text(fig))


def install_alt_text(shell=None) -> bool:
    """Show every matplotlib figure of this IPython session with its text alternative (see
    :func:`figure_html`). Done when :mod:`course_lib.plotting` is imported in a kernel, and
    again before each cell, since ``%matplotlib inline`` clears the figure formatters.
    Returns whether a shell was there to install into."""
    from matplotlib.figure import Figure

    if shell is None:
        try:
            from IPython import get_ipython
        except ImportError:  # pragma: no cover - IPython comes with the course
            return False
        shell = get_ipython()
    formatters = getattr(getattr(shell, "display_formatter", None), "formatters", None)
    if not formatters or "text/html" not in formatters:
        return False
    formatters["text/html"].for_type(Figure, figure_html)
    formatters["text/plain"].for_type(Figure, _plain)
    events = getattr(shell, "events", None)
    if events is not None and _reinstall not in events.callbacks.get("pre_run_cell", []):
        events.register("pre_run_cell", _reinstall)
    return True


def _reinstall(*_info) -> None:
    install_alt_text()


install_alt_text()
