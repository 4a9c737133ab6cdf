"""The spline end-condition explorer of Q4(c): drag the points, change the rule, watch the end.

:class:`SplineEndExplorer` shows one multi-segment curve, Catmull-Rom or B-spline, terminated at
both ends by a phantom point made by a rule of Q4(c) (``d = b``, ``d = 2c - b``, ``d = c``) or
placed freely. It draws the control polygon, the segments in their own colours, the curve's end
``p(1)`` with its first and second derivative vectors and, for the B-spline, the convex hull of
the control points, and it writes the formulas of ``p``, ``p'`` and ``p''`` for the chosen case
(Q4(b) general form, then with the rule substituted, then the numbers).

Control points move by dragging them on the figure or with the point selector and its two
sliders. Every change calls :meth:`update`, which moves the existing artists (``set_data``,
``set_xy``, ``set_positions``) and redraws: the browser paints the changed artists over the
cached axes, grid and ticks (:mod:`course_lib.widgets._view`), so a dragged point
follows the mouse.

In a notebook (any matplotlib backend)::

    from course_lib.widgets.splines import spline_end_explorer
    spline_end_explorer()
"""

from __future__ import annotations

from fractions import Fraction

import ipywidgets as W
import matplotlib.pyplot as plt
import numpy as np

from ..plots.splines import EXAMPLE_POINTS, draw_curve, spline_scene, update_curve
from ..spline_weights import end_weights_text
from ._slider_echoes import MOVE, STALE, SliderEchoes
from ._view import FigureExplorer, one_at_a_time
from ..plotting import new_figure

__all__ = ["SplineEndExplorer", "combination_tex", "formulas_html", "spline_end_explorer"]

_KIND_OPTIONS = (("Catmull-Rom", "catmull-rom"), ("B-spline", "b-spline"))
_RULE_OPTIONS = (("d = b", "d=b"), ("d = 2c − b", "d=2c-b"), ("d = c", "d=c"),
                 ("free d", "free"))
_RULE_TEX = {"d=b": r"\mathbf d = \mathbf b", "d=2c-b": r"\mathbf d = 2\mathbf c - \mathbf b",
             "d=c": r"\mathbf d = \mathbf c"}
_KIND_TITLE = {value: label for label, value in _KIND_OPTIONS}
_RULE_TITLE = {value: label for label, value in _RULE_OPTIONS}
_PICK_RADIUS_PX = 12.0


def combination_tex(weights, names="abcd") -> str:
    """LaTeX for a linear combination of points, e.g. ``[0, 1/6, 4/6, 1/6]`` ->
    ``\\tfrac{1}{6}(\\mathbf b + 4\\mathbf c + \\mathbf d)``.

    Weights are read as fractions with small denominators (the Q4 weights are multiples of
    1/6), or given as fractions in text (``"-1/2"``, as :mod:`course_lib.spline_weights`
    gives them); a common denominator is factored out, and a two-term combination that starts
    with a minus sign is written the other way round (``c - b`` rather than ``-b + c``).
    """
    fr = [Fraction(w) if isinstance(w, str) else Fraction(float(w)).limit_denominator(120)
          for w in weights]
    terms = [(f, n) for f, n in zip(fr, names) if f != 0]
    if not terms:
        return r"\mathbf 0"
    den = int(np.lcm.reduce([f.denominator for f, _ in terms]))
    ints = [(int(f * den), n) for f, n in terms]
    if len(ints) == 2 and ints[0][0] < 0 < ints[1][0]:
        ints = ints[::-1]
    body = ""
    for i, (k, n) in enumerate(ints):
        sign = "-" if k < 0 else ("+" if i else "")
        mag = "" if abs(k) == 1 else str(abs(k))
        body += (f" {sign} " if i else sign) + f"{mag}\\mathbf {n}"
    if den == 1:
        return body
    return rf"\tfrac{{1}}{{{den}}}({body})" if len(ints) > 1 else \
        rf"\tfrac{{{ints[0][0]}}}{{{den}}}\mathbf {ints[0][1]}"


def formulas_html(kind: str, rule: str, end=None) -> str:
    """The HTML+LaTeX of ``p, p', p''`` at ``t = 1`` for ``kind`` terminated by ``rule``.

    Q4(b) general rows first, then with the rule substituted (Q4(c)(i)); with ``end = (p, p1,
    p2)`` the current numeric values are appended. One equation per line, indented under its
    heading, so the panel never needs scrolling sideways.
    """
    general = end_weights_text(kind, "free")   # ValueError for an unknown kind
    names = ("\\mathbf p", "\\mathbf p'", "\\mathbf p''")

    def block(heading, rows):
        lines = "<br>".join(f"${n} = {row}$" for n, row in zip(names, rows))
        return f"{heading}<div style='margin-left: 1.5em'>{lines}</div>"

    html = [f"<b>{_KIND_TITLE[kind]}</b>, end of the last segment (t = 1):<br>",
            block("general (Q4(b)):", map(combination_tex, general))]
    if rule == "free":
        html.append("phantom point <b>d</b> placed freely: the general rows apply.")
    else:
        html.append(block(f"with ${_RULE_TEX[rule]}$:",
                          map(combination_tex, end_weights_text(kind, rule))))
    if end is not None:
        html.append(block("here:", (f"({v[0]:.2f},\\ {v[1]:.2f})" for v in end)))
    return "".join(html)


def end_summary(kind: str, rule: str, end) -> str:
    """One line a screen reader announces after each move (Q4(c)): the spline, its end rule
    and ``p, p', p''`` at ``t = 1`` (the typeset panel beside it is read on demand)."""
    values = ", ".join(f"{n} = ({v[0]:.2f}, {v[1]:.2f})" for n, v in zip(("p", "p'", "p''"), end))
    return f"{_KIND_TITLE[kind]}, end rule {_RULE_TITLE[rule]}: at t = 1, {values}"


class SplineEndExplorer(FigureExplorer):
    """Interactive explorer of Q4(c)'s end conditions (see the module docstring).

    Parameters
    ----------
    points : array_like, shape (m, 2), m >= 2
        The initial control points (the last three are Q4's ``a, b, c``).
    kind : {"catmull-rom", "b-spline"}
    rule : {"d=b", "d=2c-b", "d=c", "free"}
    n_per_segment : int
        Samples per segment of the drawn curve.

    Attributes
    ----------
    fig, ax, art
        The figure, its axes and the artists of :func:`course_lib.plots.splines.draw_curve`.
    kind, rule, point, x, y, show_hull, formulas
        The controls (ipywidgets); set their ``.value`` from Python to drive the explorer.
    points, phantoms
        Current control points ``(m, 2)`` and free phantom points ``(2, 2)``.
    scene
        The last :func:`course_lib.plots.splines.spline_scene`.
    """

    def __init__(self, points=None, kind="catmull-rom", rule="d=b", n_per_segment=40):
        P = EXAMPLE_POINTS if points is None else points
        self.points = np.array(P, dtype=float)
        if self.points.ndim != 2 or self.points.shape[1] != 2 or len(self.points) < 2:
            raise ValueError(f"points must have shape (m, 2) with m >= 2, "
                             f"got shape {self.points.shape}")
        self.n_per_segment = int(n_per_segment)
        self.phantoms = self._rule_phantoms(kind, "d=2c-b")
        self._drag = None
        self._syncing = False
        self._echoes = SliderEchoes()

        lo, hi = self.points.min(axis=0), self.points.max(axis=0)
        span = max(float(np.max(hi - lo)), 1.0)
        centre = (lo + hi) / 2
        half = 0.5 * span + 0.45 * span
        self.limits = np.array([centre - half, centre + half])  # [[xmin, ymin], [xmax, ymax]]

        self.kind = W.ToggleButtons(options=_KIND_OPTIONS, value=kind, description="spline")
        self.rule = W.ToggleButtons(options=_RULE_OPTIONS, value=rule, description="end rule")
        self.point = W.Dropdown(options=self._point_options(rule), value=len(self.points) - 1,
                                description="move")
        # the tooltips name the sliders in full for a screen reader (and on hover)
        self.x = W.FloatSlider(description="x", min=self.limits[0, 0], max=self.limits[1, 0],
                               step=0.01, continuous_update=True, readout_format=".2f",
                               tooltip="x of the point chosen in 'move'")
        self.y = W.FloatSlider(description="y", min=self.limits[0, 1], max=self.limits[1, 1],
                               step=0.01, continuous_update=True, readout_format=".2f",
                               tooltip="y of the point chosen in 'move'")
        self.show_hull = W.Checkbox(value=True, description="B-spline convex hull")
        self.formulas = W.HTMLMath(layout=W.Layout(width="420px"))
        self.summary = W.Label()
        self.status = W.Label()

        with plt.ioff():
            self.fig, self.ax = new_figure(size=5.5)
        self.scene = self._scene()
        self.art = draw_curve(self.scene, self.ax, legend=True)
        self.ax.set_xlim(self.limits[:, 0])
        self.ax.set_ylim(self.limits[:, 1])
        canvas = self.fig.canvas
        for attr, value in (("header_visible", False), ("resizable", False)):
            if hasattr(canvas, attr):
                setattr(canvas, attr, value)
        self._cids = [canvas.mpl_connect("button_press_event", self._on_press),
                      canvas.mpl_connect("motion_notify_event", self._on_motion),
                      canvas.mpl_connect("button_release_event", self._on_release)]

        self._sync_sliders()
        self.kind.observe(self._on_control, names="value")
        self.rule.observe(self._on_rule, names="value")
        self.point.observe(self._on_point, names="value")
        self.x.observe(self._on_slider, names="value")
        self.y.observe(self._on_slider, names="value")
        self.show_hull.observe(self._on_control, names="value")
        self.update()

    # ---------------------------------------------------------------------------------------
    # the model

    def _scene(self):
        return spline_scene(self.points, self.kind.value, self.rule.value,
                            phantoms=self.phantoms, n_per_segment=self.n_per_segment)

    def _rule_phantoms(self, kind, rule):
        """The two phantom points ``rule`` makes for the current points (as drawn)."""
        return spline_scene(self.points, kind, rule, n_per_segment=1)["phantoms"].copy()

    @one_at_a_time
    def update(self):
        """Recompute the curve and move the artists in place; refresh the formulas."""
        self.scene = self._scene()
        self.art["show_hull"] = self.show_hull.value
        update_curve(self.art, self.scene)
        rule = self.rule.value
        self.ax.set_title(f"{_KIND_TITLE[self.kind.value]}, end rule {_RULE_TITLE[rule]}")
        self._redraw()  # the figure first: the page typesets the formulas after painting it
        self.formulas.value = formulas_html(self.kind.value, rule, self.scene["end"])
        self.summary.value = end_summary(self.kind.value, rule, self.scene["end"])

    def get_point(self, index):
        """Control point ``index`` (0 .. m-1), or ``"start"`` / ``"end"`` for a free phantom."""
        if index == "start":
            return self.phantoms[0].copy()
        if index == "end":
            return self.phantoms[1].copy()
        return self.points[index].copy()

    def set_point(self, index, xy):
        """Move control point ``index`` (or the free phantom ``"start"``/``"end"``) to ``xy``."""
        xy = np.clip(np.asarray(xy, dtype=float), self.limits[0], self.limits[1])
        if index in ("start", "end"):
            self.phantoms[0 if index == "start" else 1] = xy
        else:
            self.points[index] = xy
        if self.point.value == index:
            self._sync_sliders()
        self.update()

    # ---------------------------------------------------------------------------------------
    # controls

    def _point_options(self, rule):
        m = len(self.points)
        names = {m - 3: " = a", m - 2: " = b", m - 1: " = c"}
        opts = [(f"p{i}{names.get(i, '')}", i) for i in range(m)]
        if rule == "free":
            opts += [("d (end phantom)", "end"), ("start phantom", "start")]
        return opts

    def _on_control(self, change):
        self.update()

    def _on_rule(self, change):
        old, new = change["old"], change["new"]
        if new == "free" and old != "free":
            # the free phantoms start where the previous rule had put them
            self.phantoms = self._rule_phantoms(self.kind.value, old)
        keep = self.point.value
        self._syncing = True
        self.point.options = self._point_options(new)
        self.point.value = keep if keep in [v for _, v in self.point.options] else \
            len(self.points) - 1
        self._syncing = False
        self._sync_sliders()
        self.update()

    def _on_point(self, change):
        if not self._syncing:
            self._sync_sliders()

    def _on_slider(self, change):
        """A slider moved: the student's move sets that one coordinate of the selected point;
        the page's echo of a value set here does not (:mod:`._slider_echoes`), and after the
        late echo of an older value the sliders are set back to the point (a drag sets them
        at its next move anyway)."""
        if self._syncing:
            return
        c = 0 if change["owner"] is self.x else 1
        xy = self.get_point(self.point.value)
        verdict = self._echoes.judge(change, xy[c])
        if verdict == STALE and self._drag is None:
            self._sync_sliders()
        if verdict != MOVE:
            return
        xy[c] = change["new"]
        self.set_point(self.point.value, xy)

    def _sync_sliders(self):
        xy = self.get_point(self.point.value)
        self._syncing = True
        try:
            self._echoes.set(self.x, float(xy[0]))
            self._echoes.set(self.y, float(xy[1]))
        finally:
            self._syncing = False

    # ---------------------------------------------------------------------------------------
    # dragging (the canvas' mouse events, as matplotlib MouseEvents; synthetic ones work too)

    def _draggable(self):
        items = [(i, p) for i, p in enumerate(self.points)]
        if self.rule.value == "free":
            items += [("start", self.phantoms[0]), ("end", self.phantoms[1])]
        return items

    def _pick(self, event):
        """The draggable point nearest the mouse within the pick radius, or None."""
        items = self._draggable()
        xy = self.ax.transData.transform(np.array([p for _, p in items]))
        dist = np.hypot(xy[:, 0] - event.x, xy[:, 1] - event.y)
        k = int(np.argmin(dist))
        return items[k][0] if dist[k] <= _PICK_RADIUS_PX else None

    def _on_press(self, event):
        if event.inaxes is not self.ax or event.button != 1:
            return
        toolbar = getattr(self.fig.canvas, "toolbar", None)
        if toolbar is not None and getattr(toolbar, "mode", ""):
            return  # pan/zoom is active
        self._drag = self._pick(event)
        if self._drag is not None:
            self._syncing = True
            self.point.value = self._drag
            self._syncing = False
            self.status.value = f"dragging {self._label(self._drag)}"

    def _on_motion(self, event):
        if self._drag is None or event.inaxes is not self.ax or event.xdata is None:
            return
        self._move_to(self._drag, (event.xdata, event.ydata))

    def _on_release(self, event):
        if self._drag is not None and event.inaxes is self.ax and event.xdata is not None:
            self._move_to(self._drag, (event.xdata, event.ydata))
        self._drag = None
        self.status.value = ""

    def _move_to(self, index, xy):
        if self.point.value != index:
            self._syncing = True
            self.point.value = index
            self._syncing = False
        self.set_point(index, xy)
        self._sync_sliders()

    def _label(self, index):
        return {value: label for label, value in self.point.options}.get(index, str(index))

    # ---------------------------------------------------------------------------------------
    # display

    def _build_layout(self, view):
        """The explorer's layout: the figure beside the controls and the formulas."""
        controls = W.VBox([self.kind, self.rule, self.point, self.x, self.y,
                           self.show_hull, self.summary, self.formulas, self.status])
        return W.HBox([view, controls])


def spline_end_explorer(points=None, kind="catmull-rom", rule="d=b") -> SplineEndExplorer:
    """The Q4(c) end-condition explorer (display it as a cell's last expression)."""
    return SplineEndExplorer(points, kind=kind, rule=rule)
