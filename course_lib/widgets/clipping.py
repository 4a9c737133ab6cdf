"""Clipping explorer (exam Q6(b)(iii)): a polygon against the view volume, one plane at a time.

A slider (or the Previous/Next buttons) steps through the six Sutherland-Hodgman passes (left,
right, bottom, top, near, far); a drop-down picks a vertex and four sliders move it in
homogeneous coordinates ``[X, Y, Z, w]`` (so you can watch a vertex go behind the eye, ``w < 0``,
and see the naive divide throw it in front). The left panel is 3-D screen space with the view
volume and the plane being applied; the right panel looks along one screen axis. All artists are
updated in place and painted by the browser (:mod:`course_lib.widgets._view`): the
2-D panel's axes stay cached and the 3-D panel's contents are projected and sent again, to be
drawn over its cached panes and ticks.

The explorer clips with the course's references through one routine, :func:`clip_display`,
which returns only what is shown: vertices at display precision, the vertex table at three
decimals and the inside/outside readout as text. The students' wheel compiles a private copy of
the references into that routine alone (``INLINE_INTO`` in :mod:`autograder.student_bundle`).

In a notebook (any matplotlib backend)::

    from course_lib.widgets.clipping import clipping_explorer
    clipping_explorer()
"""

from __future__ import annotations

import time

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from .. import clipping
from ..plots.clipping import _closed, plot_clipping_2d, plot_view_volume, screen_points
from ._slider_echoes import MOVE, STALE, SliderEchoes
from ._view import FigureView, one_at_a_time, one_message_at_a_time

#: A quadrilateral that sticks out of the volume through four planes, w != 1 for two vertices.
DEFAULT_POLYGON = np.array([
    [-1.5, -0.3, 0.5, 1.0],
    [1.2, -1.4, 0.3, 1.0],
    [0.8, 3.2, 2.8, 2.0],
    [-0.6, 1.1, 0.6, 0.5],
])

#: The six planes as quads in screen space (the faces of the box), in the order of PLANES.
_FACES = np.array([
    [[-1, -1, 0], [-1, 1, 0], [-1, 1, 1], [-1, -1, 1]],
    [[1, -1, 0], [1, 1, 0], [1, 1, 1], [1, -1, 1]],
    [[-1, -1, 0], [1, -1, 0], [1, -1, 1], [-1, -1, 1]],
    [[-1, 1, 0], [1, 1, 0], [1, 1, 1], [-1, 1, 1]],
    [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]],
    [[-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]],
], dtype=float)

_COORDS = ("X", "Y", "Z", "w")


def clip_display(P) -> dict:
    """What the explorer shows of polygon ``P`` (homogeneous, ``(n, 4)``) clipped plane by plane
    (Q6(b)(iii)), at display precision only.

    Returns a dict: ``"steps"``, the polygon before clipping and after each of the six planes
    (homogeneous, rounded to the table's three decimals); ``"screen"``, the same divided by
    ``w`` for drawing (:func:`~course_lib.plots.clipping.display_round`); ``"tables"``, each
    step's vertex table (HTML, three decimals); ``"inside"``, each input vertex in or out of the
    view volume as text (``"yes, no, ..."``), and ``"error"`` (``None``, or why ``P`` cannot be
    clipped, e.g. a vertex ``[0, 0, 0, 0]``: then every step after the input is empty).
    """
    P = np.asarray(P, dtype=float)
    try:
        steps = clipping.clip_steps(P)
        inside = ", ".join("yes" if v else "no" for v in clipping.inside_view_volume(P))
        error = None
    except ValueError as exc:
        steps, inside, error = [P] + [np.zeros((0, 4))] * 6, None, str(exc)
    return {"steps": [np.round(s, 3) for s in steps], "screen": [screen_points(s) for s in steps],
            "tables": [_vertex_table(s) for s in steps], "inside": inside, "error": error}


def _vertex_table(P) -> str:
    """The vertices of a step as an HTML table: homogeneous and divided, three decimals."""
    if len(P) == 0:
        return "<i>no vertices</i>"
    rows = "".join(
        f"<tr><td>{k}</td>" + "".join(f"<td>{v:.3f}</td>" for v in p) +
        "".join(f"<td>{v:.3f}</td>" for v in (p[:3] / p[3] if p[3] else [np.nan] * 3)) +
        "</tr>" for k, p in enumerate(P))
    head = "".join(f"<th>{h}</th>" for h in
                   ("#", "X", "Y", "Z", "w", "x<sub>s</sub>", "y<sub>s</sub>", "z<sub>s</sub>"))
    return f"<table style='font-family:monospace'><tr>{head}</tr>{rows}</table>"


class ClippingExplorer:
    """Step a homogeneous polygon through the six clipping planes and move its vertices.

    Parameters
    ----------
    P : array_like, shape (n, 4), optional
        The polygon in homogeneous screen coordinates (default :data:`DEFAULT_POLYGON`).
    dims : pair of ints
        Screen axes of the right-hand panel: ``(0, 1)`` the screen, ``(1, 2)`` a side view
        (use it for the exam's edge-on triangles).

    Attributes
    ----------
    P : ndarray
        The current polygon (changed by the vertex sliders).
    shown : dict
        :func:`clip_display` of ``P``: ``shown["steps"][k]`` is the polygon after ``k`` planes
        (homogeneous, three decimals), ``shown["screen"][k]`` the same as drawn.
    step, prev_button, next_button, vertex, coord_sliders
        The controls; set their values from Python to drive the explorer.
    art3d, art2d : dict
        The artists updated in place.
    last_update_ms : float
        Time taken by the last :meth:`update` to recompute and set the artists (not drawing).
    """

    def __init__(self, P=None, dims=(0, 1)):
        self.P = np.array(DEFAULT_POLYGON if P is None else P, dtype=float)
        if self.P.ndim != 2 or self.P.shape[1] != 4 or len(self.P) < 3:
            raise ValueError(f"P must have shape (n, 4) with n >= 3, got {self.P.shape}")
        self.dims = tuple(dims)
        self.shown = clip_display(self.P)
        self.last_update_ms = 0.0
        self._view = FigureView()                  # painted by the browser
        self._syncing = False
        self._echoes = SliderEchoes()

        with plt.ioff():
            self.fig = plt.figure(figsize=(10.0, 4.6))
        self.fig.set_layout_engine("constrained")
        ax3 = self.fig.add_subplot(1, 2, 1, projection="3d")
        ax2 = self.fig.add_subplot(1, 2, 2)
        self.ax3d, self.ax2d = ax3, ax2

        # 3-D panel: the box, the active plane, the input and the current polygon.
        self.art3d = {"box": plot_view_volume(ax3)}
        plane = Poly3DCollection([_FACES[0]], facecolor="#d62728", alpha=0.18,
                                 edgecolor="#d62728")
        ax3.add_collection3d(plane)
        self.art3d["plane"] = plane
        (self.art3d["input"],) = ax3.plot([], [], [], ls="--", marker="o", ms=3,
                                          color="#7f7f7f", label="input, divided by w")
        poly = Poly3DCollection([], facecolor="#1f77b4", alpha=0.35, edgecolor="none")
        ax3.add_collection3d(poly)
        self.art3d["polygon"] = poly
        (self.art3d["edges"],) = ax3.plot([], [], [], color="#1f77b4", lw=2,
                                          label="after these planes")
        (self.art3d["vertices"],) = ax3.plot([], [], [], ls="none", marker="o", ms=5,
                                             color="#d62728")
        ax3.set_xlim(-2, 2)
        ax3.set_ylim(-2, 2)
        ax3.set_zlim(-0.5, 1.5)
        ax3.legend(loc="upper left", fontsize=7)

        # 2-D panel: reuse the static figure's artists.
        self.art2d = plot_clipping_2d(self.P, self.P, ax=ax2, dims=self.dims)
        for text in self.art2d["labels"]:
            text.remove()
        self.art2d["labels"] = []
        i, j = self.dims
        lo = np.array([-1.0, -1.0, 0.0])[[i, j]]
        hi = np.array([1.0, 1.0, 1.0])[[i, j]]
        span = np.max(hi - lo)
        ax2.set_xlim(lo[0] - span, hi[0] + span)
        ax2.set_ylim(lo[1] - span, hi[1] + span)
        (self.art2d["plane"],) = ax2.plot([], [], color="#d62728", lw=3, alpha=0.6)
        self.status = self.fig.suptitle("", fontsize=10)

        # Controls.
        n = len(self.P)
        self.step = widgets.IntSlider(value=0, min=0, max=6, description="planes",
                                      continuous_update=True)
        self.prev_button = widgets.Button(description="Previous", icon="step-backward",
                                          layout=widgets.Layout(width="110px"))
        self.next_button = widgets.Button(description="Next", icon="step-forward",
                                          layout=widgets.Layout(width="110px"))
        self.vertex = widgets.Dropdown(options=[(f"vertex {k}", k) for k in range(n)], value=0,
                                       description="move", layout=widgets.Layout(width="180px"))
        reach = max(4.0, float(np.ceil(np.max(np.abs(self.P)))))   # room for every vertex
        self.coord_sliders = [
            widgets.FloatSlider(min=lo_, max=reach, step=0.05,
                                description=name, continuous_update=True, readout_format=".2f",
                                tooltip=f"{name} of the vertex chosen in 'move' (homogeneous)")
            for c, (name, lo_) in enumerate(zip(_COORDS, (-reach, -reach, -reach, -1.5)))]
        # the vertex table is read on demand; the one-line summary above it is announced
        self.readout = widgets.HTML()
        self.readout.add_class("course-quiet")
        self.summary = widgets.Label()
        self._sync_sliders()
        self.step.observe(self._on_step, names="value")
        self.prev_button.on_click(lambda _: self._nudge(-1))
        self.next_button.on_click(lambda _: self._nudge(+1))
        self.vertex.observe(self._on_vertex, names="value")
        for s in self.coord_sliders:
            s.observe(self._on_coord, names="value")
        self.controls = widgets.VBox([
            widgets.HBox([self.step, self.prev_button, self.next_button]),
            widgets.HBox([self.vertex, *self.coord_sliders[:2]]),
            widgets.HBox([widgets.Label(layout=widgets.Layout(width="180px")),
                          *self.coord_sliders[2:]]),
            self.summary,
            self.readout,
        ])
        self.update()

    # -- callbacks ---------------------------------------------------------------------------

    def _nudge(self, delta: int):
        self.step.value = int(np.clip(self.step.value + delta, 0, 6))

    def _on_step(self, _change):
        self.update(recompute=False)

    def _on_vertex(self, _change):
        self._sync_sliders()

    def _sync_sliders(self):
        """The coordinate sliders to the selected vertex."""
        self._syncing = True
        try:
            for c, s in enumerate(self.coord_sliders):
                self._echoes.set(s, float(self.P[self.vertex.value, c]))
        finally:
            self._syncing = False

    def _on_coord(self, change):
        """A coordinate slider moved: the student's move sets that coordinate of the selected
        vertex; the page's echo of a value set here does not, and after the late echo of an
        older value (the previous vertex's, when the vertex was switched quickly) the sliders
        are set back to the vertex (:mod:`._slider_echoes`)."""
        if self._syncing:
            return
        k, c = self.vertex.value, self.coord_sliders.index(change["owner"])
        verdict = self._echoes.judge(change, self.P[k, c])
        if verdict == STALE:
            self._sync_sliders()
        if verdict != MOVE:
            return
        self.P[k, c] = change["new"]
        self.update()

    # -- drawing -------------------------------------------------------------------------------

    @one_at_a_time
    def update(self, recompute: bool = True):
        """Recompute the clipping steps (if the polygon changed) and update every artist."""
        t0 = time.perf_counter()
        k = self.step.value
        if recompute:
            self.shown = clip_display(self.P)
        shown = self.shown
        inp = _closed(screen_points(self.P))
        cur = shown["screen"][k]
        cur_closed = _closed(cur)

        a3 = self.art3d
        a3["input"].set_data_3d(*inp.T)
        a3["polygon"].set_verts([cur] if len(cur) >= 3 else [])
        a3["edges"].set_data_3d(*(cur_closed.T if len(cur) else ([], [], [])))
        a3["vertices"].set_data_3d(*(cur.T if len(cur) else ([], [], [])))
        if k > 0:
            a3["plane"].set_verts([_FACES[k - 1]])
            a3["plane"].set_visible(True)
        else:
            a3["plane"].set_visible(False)

        i, j = self.dims
        a2 = self.art2d
        a2["original"].set_data(inp[:, i], inp[:, j])
        if len(cur):
            a2["clipped"].set_xy(cur[:, [i, j]])
            a2["clipped"].set_visible(True)
        else:
            a2["clipped"].set_visible(False)
        a2["clipped_vertices"].set_data(cur[:, i], cur[:, j])
        self._plane_line_2d(k)

        if shown["error"]:
            title = f"cannot clip: {shown['error']}"
        elif k == 0:
            title = f"input: {len(cur)} vertices, inside = {shown['inside']}"
        else:
            title = (f"after plane {k} of 6, {clipping.PLANE_NAMES[k - 1]}: "
                     f"{len(cur)} vertices" + ("" if len(cur) >= 3 else " (nothing left)"))
        self.status.set_text(title)
        self.last_update_ms = 1000 * (time.perf_counter() - t0)
        self._view.redraw(self.fig)
        self.readout.value = shown["tables"][k]  # the figure's frame first, the table after it
        self.summary.value = title

    def _plane_line_2d(self, k):
        """The active plane seen edge-on in the 2-D panel (when it is perpendicular to it)."""
        line = self.art2d["plane"]
        if k == 0:
            line.set_data([], [])
            return
        face = _FACES[k - 1][:, list(self.dims)]
        if np.ptp(face[:, 0]) == 0 or np.ptp(face[:, 1]) == 0:
            line.set_data(face[[0, 2], 0], face[[0, 2], 1])
        else:                                        # the plane faces us: outline it
            line.set_data(*_closed(face).T)

    # -- display -------------------------------------------------------------------------------

    def widget(self):
        """The controls and the figure (painted by the browser) in one box."""
        if self.__dict__.get("_layout") is None:
            self._layout = one_message_at_a_time(
                widgets.VBox([self.controls, self._view.widget(self.fig)]), self.fig)
            self._view.redraw(self.fig)
        return self._layout

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget())


def clipping_explorer(P=None, dims=(0, 1)) -> ClippingExplorer:
    """A :class:`ClippingExplorer` for polygon ``P`` (homogeneous, ``(n, 4)``)."""
    return ClippingExplorer(P, dims=dims)
