"""The marching-cubes case explorer of Q3(a)-(c): pick a case, toggle corners, move the level.

:class:`CaseExplorer` shows one cell of the grid: its corners (red inside, white outside), the
triangles the lookup table gives for its case, and, for the six ambiguous cases, a switch to the
alternative triangulation of Q3(c): shown for Lorensen's representative of each (the one the
"Lorensen case" menu picks, as in the notebook's figure); the other orientations are for the
student to work out, (c.1). The corner values are 0 (inside) and 1 (outside), so the
iso-level slider moves every vertex along its edge to the fraction ``iso`` of the way from the
inside corner: the linear interpolation of Q3(a) (the table says *which* edge, the data say
*where* on it).

Choose a case three ways: Lorensen's number (one of the 15 classes, Q3(b)), the case index
0 ... 255, or the eight corner toggles; the three stay in step. Every change calls
:meth:`CaseExplorer.update`, which moves the existing artists (``set_verts`` on the triangles,
marker colours on the corners) and redraws: the browser paints the projected triangles and
corners over the cached 3-D panes and ticks (:mod:`course_lib.widgets._view`).

In a notebook (any matplotlib backend)::

    from course_lib.widgets.marching_cubes import case_explorer
    case_explorer()
"""

from __future__ import annotations

import ipywidgets as W
import matplotlib.pyplot as plt
import numpy as np

from .. import _mc_case_data
from .. import marching_cubes as mc
from ._view import FigureExplorer, one_at_a_time
from ..plots.marching_cubes import case_values, draw_case, shows_alternative, update_case

__all__ = ["CaseExplorer", "case_explorer", "case_summary"]


def case_summary(index: int, alternative: bool = False) -> str:
    """One line of HTML about case ``index``: corners inside, class, triangles, ambiguity."""
    inside = [c for c in range(8) if (index >> c) & 1]
    amb = mc.ambiguous_faces(index)
    alternative = bool(alternative and amb and shows_alternative(index))
    ntri = (len(_mc_case_data.shown_alternatives()[index]) if alternative
            else int(mc.N_TRIANGLES[index]))
    text = (f"index <b>{index}</b> = 0b{index:08b}; inside corners {inside or 'none'}; "
            f"Lorensen case <b>{mc.case_of(index)}</b>; {ntri} triangle(s)")
    if amb:
        which = "joined (alternative)" if alternative else "kept apart (our table)"
        text += f"; {len(amb)} ambiguous face(s), inside corners {which}"
        if not shows_alternative(index):
            text += ("; the alternative is drawn for this case's representative (choose it "
                     "under Lorensen case); this orientation's is yours to work out, (c.1)")
    return text


class CaseExplorer(FigureExplorer):
    """Interactive view of one marching-cubes cell (see the module docstring).

    Parameters
    ----------
    index : int
        The initial case index (0 ... 255).
    iso : float
        The initial iso-level in (0, 1): the fraction of each crossed edge from its inside end.

    Attributes
    ----------
    fig, ax, art
        The figure, its 3-D axes and the artists of
        :func:`course_lib.plots.marching_cubes.draw_case` (``art["surface"]`` is the
        ``Poly3DCollection`` of the triangles, ``art["corners"]`` the eight corner markers).
    case, index, corners, alternative, iso
        The controls (ipywidgets); set their ``.value`` from Python to drive the explorer.
    triangles
        The triangles drawn by the last update, shape ``(t, 3, 3)``.
    """

    def __init__(self, index: int = 1, iso: float = 0.5):
        index = int(index)
        if not 0 <= index <= 255:
            raise ValueError(f"index must be in 0 ... 255, got {index}")
        if not 0.0 < iso < 1.0:
            raise ValueError(f"iso must lie strictly between 0 and 1, got {iso}")
        self._syncing = False

        self.case = W.Dropdown(
            options=[(f"{c.number}{' (ambiguous)' if c.ambiguous else ''}", c.number)
                     for c in mc.BASE_CASES],
            value=mc.case_of(index), description="Lorensen case")
        self.index = W.IntSlider(value=index, min=0, max=255, description="case index",
                                 continuous_update=True)
        self.corners = [W.ToggleButton(value=bool((index >> c) & 1), description=str(c),
                                       tooltip=f"corner {c} inside",
                                       layout=W.Layout(width="40px"))
                        for c in range(8)]
        self.alternative = W.Checkbox(value=False, description="alternative triangulation")
        self.iso = W.FloatSlider(value=iso, min=0.02, max=0.98, step=0.01,
                                 description="iso-level", continuous_update=True)
        self.info = W.HTML()

        with plt.ioff():
            self.fig = plt.figure(figsize=(5.0, 5.0))
            self.ax = self.fig.add_subplot(projection="3d")
        self.art = draw_case(index, self.ax, iso=iso)
        self.art["corner_labels"] = [
            self.ax.text(*(1.1 * (p - 0.5) + 0.5), str(c), fontsize=9, ha="center")
            for c, p in enumerate(mc.CORNERS.astype(float))]
        self.title = self.ax.set_title("", fontsize=10)
        canvas = self.fig.canvas
        for attr, value in (("header_visible", False), ("resizable", False)):
            if hasattr(canvas, attr):
                setattr(canvas, attr, value)

        self.case.observe(self._on_case, names="value")
        self.index.observe(self._on_index, names="value")
        for button in self.corners:
            button.observe(self._on_corner, names="value")
        self.alternative.observe(self._on_control, names="value")
        self.iso.observe(self._on_control, names="value")
        self.triangles = np.zeros((0, 3, 3))
        self.update()

    # ---------------------------------------------------------------------------------------
    # state

    @property
    def values(self) -> np.ndarray:
        """The corner values of the current case (0 inside, 1 outside)."""
        return case_values(self.index.value)

    @one_at_a_time
    def update(self):
        """Move the triangles and corner colours to the current controls and redraw."""
        index = self.index.value
        shown = bool(mc.ambiguous_faces(index)) and shows_alternative(index)
        self.alternative.disabled = not shown
        alt = self.alternative.value and shown
        self.triangles = update_case(self.art, index, alternative=alt, iso=self.iso.value)
        self.title.set_text(f"case index {index} (Lorensen case {mc.case_of(index)}), "
                            f"iso {self.iso.value:.2f}")
        self._redraw()  # the figure's frame first, the text after it
        self.info.value = case_summary(index, alt)

    def _set_index(self, index: int):
        """Bring all three case controls to ``index`` without re-entering the callbacks."""
        self._syncing = True
        try:
            self.index.value = index
            for c, button in enumerate(self.corners):
                button.value = bool((index >> c) & 1)
            self.case.value = mc.case_of(index)
        finally:
            self._syncing = False
        self.update()

    def _on_case(self, change):
        if self._syncing:
            return
        self._set_index(mc.BASE_CASES[change["new"]].index)

    def _on_index(self, change):
        if self._syncing:
            return
        self._set_index(int(change["new"]))

    def _on_corner(self, change):
        if self._syncing:
            return
        self._set_index(sum(1 << c for c, b in enumerate(self.corners) if b.value))

    def _on_control(self, change):
        if not self._syncing:
            self.update()

    # ---------------------------------------------------------------------------------------
    # display

    def _build_layout(self, view):
        """The explorer's layout: the figure beside the controls."""
        controls = W.VBox([self.case, self.index,
                           W.HBox([W.Label("inside corners")] + self.corners),
                           self.alternative, self.iso, self.info],
                          layout=W.Layout(width="460px"))
        return W.HBox([view, controls])


def case_explorer(index: int = 1, iso: float = 0.5) -> CaseExplorer:
    """The Q3 case explorer (display it as a cell's last expression)."""
    return CaseExplorer(index=index, iso=iso)
