"""The Phong explorer of Q5: one sphere shaded by Phong and by Blinn-Phong, side by side.

:class:`PhongExplorer` renders a unit sphere, seen orthographically, lit by a directional light,
under both specular models of Q5(a) and Q5(c). Sliders set the coefficients ``ka``, ``kd``,
``ks``, the exponent ``n``, the surface colour (a colour picker) and the directions of the light
and the viewer (azimuth and elevation); each highlight's rendered peak is ringed and the
analytic position (the point whose normal is ``H``) crossed. A probe point (the exam's normal
``N = (0, 1/2, sqrt(3)/2)`` by default) is marked with a square and its RGB intensity printed
under both models. The button "Exam Q5(b)" loads the worked example, whose Phong intensity is
``(0.0931, 0.0931, 0.699)`` (with the exam's exact directions until a direction slider is moved,
since a slider can show the light's elevation of 35.26 degrees only to its step).

Every change calls :meth:`PhongExplorer.update`, which re-renders into the existing images with
``set_data`` (two 128 x 128 renders, a few milliseconds) and moves the markers. The browser
paints the figure (:mod:`course_lib.widgets._view`): the axes frames and titles stay
cached, and only the two images (at 128 x 128, scaled by the page), the markers and the legend
are sent again.

In a notebook (any matplotlib backend)::

    from course_lib.widgets.shading import phong_explorer
    phong_explorer()

Directions: azimuth ``a`` from the x axis towards y, elevation ``e`` from the xy plane towards z:
``d = (cos e cos a, cos e sin a, sin e)``; the screen's up is the world's z axis.
"""

from __future__ import annotations

import ipywidgets as W
import matplotlib.pyplot as plt
import numpy as np

from .. import shading
from ..plots.describe import num, set_summary
from ..plots.shading import sphere_pair, update_sphere_pair
from ._view import FigureExplorer, one_at_a_time, readout_html
from ..plotting import new_figure

__all__ = ["PhongExplorer", "angles", "direction", "hex_to_rgb", "phong_explorer", "rgb_to_hex"]


def direction(azimuth_deg: float, elevation_deg: float) -> np.ndarray:
    """Unit vector of the given azimuth (from x towards y) and elevation (above the xy plane)."""
    a, e = np.radians(azimuth_deg), np.radians(elevation_deg)
    return np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])


def angles(v) -> tuple[float, float]:
    """``(azimuth, elevation)`` in degrees of the direction ``v`` (inverse of :func:`direction`),
    to 0.01 degree (the sliders' step is 0.5)."""
    v = shading.normalize(v)
    return (round(float(np.degrees(np.arctan2(v[1], v[0]))), 2),
            round(float(np.degrees(np.arcsin(v[2]))), 2))


def hex_to_rgb(text: str) -> np.ndarray:
    """``"#rrggbb"`` (or ``"#rgb"``) as RGB fractions in [0, 1]."""
    h = text.strip().lstrip("#")
    if len(h) == 3:
        h = "".join(c * 2 for c in h)
    if len(h) != 6:
        raise ValueError(f"colour must be '#rrggbb', got {text!r}")
    return np.array([int(h[i:i + 2], 16) / 255.0 for i in (0, 2, 4)])


def rgb_to_hex(rgb) -> str:
    """RGB fractions as ``"#rrggbb"``."""
    r = np.clip(np.round(np.asarray(rgb, dtype=float) * 255), 0, 255).astype(int)
    return "#{:02x}{:02x}{:02x}".format(*r)


#: The exam's directions of Q5(b) as unit vectors (fixed inputs: the explorer's "exact" mode).
_EXAM_UNIT = {k: np.asarray(shading.EXAM_Q5B[k], dtype=float)
              / np.linalg.norm(shading.EXAM_Q5B[k]) for k in ("L", "N", "V")}

#: The worked example of Q5(b) in the explorer's controls.
_EXAM_L = angles(shading.EXAM_Q5B["L"])
_EXAM_V = angles(shading.EXAM_Q5B["V"])
EXAM_SETTINGS = {
    "colour": "#0000ff", "ka": 0.5, "kd": 0.5, "ks": 1.0, "n": 10.0,
    "light_azimuth": _EXAM_L[0], "light_elevation": _EXAM_L[1],
    "view_azimuth": _EXAM_V[0], "view_elevation": _EXAM_V[1],
}


class PhongExplorer(FigureExplorer):
    """Phong vs Blinn-Phong on a shaded sphere (Q5(a)-(c)).

    Parameters
    ----------
    size : int
        Pixels per side of each rendering.
    probe : array_like, shape (3,)
        A surface normal whose intensity is printed (the exam's ``N`` by default; another is
        kept to the precision of its :func:`angles`).

    Attributes
    ----------
    fig, axes, art
        The figure, its two axes and the artists of :func:`~course_lib.plots.shading.sphere_pair`.
    ka, kd, ks, n, colour, light_azimuth, light_elevation, view_azimuth, view_elevation
        The controls (ipywidgets); ``Ia = Ip = 1``.
    exam_button : ipywidgets.Button
        Loads the Q5(b) example.
    readout : ipywidgets.HTML
        Directions, half-way vector and the probe's intensities.
    peaks : list
        The two rendered highlight pixels ``(row, col)`` (or ``None``) after the last update.
    probe_values : dict
        ``{"Phong": (3,) array, "Blinn-Phong": (3,) array}`` at the probe, to the 4 decimals the
        readout shows, or ``None`` values when the probe is on the hidden side of the sphere.
    halfway_shown : ndarray or None
        The half-way vector to the readout's 3 decimals (``None`` when ``V = -L``).
    """

    def __init__(self, size: int = 128, probe=None):
        self.size = int(size)
        self.probe = _EXAM_UNIT["N"] if probe is None else direction(*angles(probe))
        slider = {"continuous_update": True, "style": {"description_width": "130px"},
                  "layout": W.Layout(width="350px")}
        self.ka = W.FloatSlider(0.2, min=0.0, max=1.0, step=0.01, description="ka (ambient)",
                                **slider)
        self.kd = W.FloatSlider(0.6, min=0.0, max=1.0, step=0.01, description="kd (diffuse)",
                                **slider)
        self.ks = W.FloatSlider(0.8, min=0.0, max=1.0, step=0.01, description="ks (specular)",
                                **slider)
        self.n = W.FloatLogSlider(20.0, base=10, min=0, max=3, step=0.01,
                                  description="n (exponent)", **slider)
        self.colour = W.ColorPicker(value="#3366ff", description="colour c",
                                    style={"description_width": "130px"})
        self.light_azimuth = W.FloatSlider(-45.0, min=-180, max=180, step=0.5,
                                           description="light azimuth°", **slider)
        self.light_elevation = W.FloatSlider(35.0, min=-90, max=90, step=0.5,
                                             description="light elevation°", **slider)
        self.view_azimuth = W.FloatSlider(90.0, min=-180, max=180, step=0.5,
                                          description="viewer azimuth°", **slider)
        self.view_elevation = W.FloatSlider(0.0, min=-90, max=90, step=0.5,
                                            description="viewer elevation°", **slider)
        self.exam_button = W.Button(description="Exam Q5(b)", button_style="info",
                                    tooltip="L ∝ (1,−1,1), N = (0, ½, √3/2), V = (0,1,0), n = 10, "
                                            "blue surface, Ia ka = Ip kd = 0.5, Ip ks = 1")
        self.readout = W.HTML()
        self.peaks = [None, None]
        self.probe_values = {"Phong": None, "Blinn-Phong": None}
        self.halfway_shown = None
        self._holding = False
        self._exam_mode = False

        with plt.ioff():
            self.fig, axes = new_figure(2, size=3.4)
        self.axes = list(np.ravel(axes))
        canvas = self.fig.canvas
        for attr, value in (("header_visible", False), ("resizable", False)):
            if hasattr(canvas, attr):
                setattr(canvas, attr, value)
        args = self._args()
        self.art = sphere_pair(*args, size=self.size, axes=self.axes)
        self.probe_markers = [ax.plot([], [], "s", mfc="none", mec="#ffeb3b", ms=8, mew=1.5)[0]
                              for ax in self.axes]
        for w in self.controls:
            w.observe(self._on_change, names="value")
        self.exam_button.on_click(self.load_exam)
        self.update()

    # ---------------------------------------------------------------------------------------
    # the model

    @property
    def controls(self):
        return (self.ka, self.kd, self.ks, self.n, self.colour, self.light_azimuth,
                self.light_elevation, self.view_azimuth, self.view_elevation)

    @property
    def directions(self):
        """The four direction sliders, by their names in :data:`EXAM_SETTINGS`."""
        return {"light_azimuth": self.light_azimuth, "light_elevation": self.light_elevation,
                "view_azimuth": self.view_azimuth, "view_elevation": self.view_elevation}

    @property
    def L(self) -> np.ndarray:
        """Unit vector towards the light (the exam's exactly, after "Exam Q5(b)")."""
        if self._exam_mode:
            return _EXAM_UNIT["L"]
        return direction(self.light_azimuth.value, self.light_elevation.value)

    @property
    def V(self) -> np.ndarray:
        """Unit vector towards the viewer (the exam's exactly, after "Exam Q5(b)")."""
        if self._exam_mode:
            return _EXAM_UNIT["V"]
        return direction(self.view_azimuth.value, self.view_elevation.value)

    def _args(self):
        return (hex_to_rgb(self.colour.value), 1.0, self.ka.value, 1.0, self.kd.value,
                self.ks.value, self.n.value, self.L, self.V)

    @one_at_a_time
    def update(self):
        """Re-render both spheres in place, refresh the markers and the readout, redraw."""
        with self.readout.hold_sync():  # the figure's frame goes first, the readout after it
            self.refresh()
            self._redraw()

    def refresh(self):
        """The per-update compute: two renders into the images (``set_data``), the markers and
        the readout; no drawing. What it keeps (``probe_values``, ``halfway_shown``, the
        marker's place to 0.01 pixel) is at the precision shown."""
        args = self._args()
        self.peaks = update_sphere_pair(self.art, *args, size=self.size)
        L, V = self.L, self.V
        visible = float(self.probe @ V) > 0
        marker = ([], [])
        if visible:
            basis = shading.view_basis(V)
            x, y = self.probe @ basis[0], self.probe @ basis[1]
            marker = ([round((x + 1) * self.size / 2 - 0.5, 2)],
                      [round((1 - y) * self.size / 2 - 0.5, 2)])
        for m in self.probe_markers:
            m.set_data(*marker)
        at_probe = {"Phong": None, "Blinn-Phong": None}
        h_shown = None
        c, Ia, ka, Ip, kd, ks, n = args[:7]
        if visible:
            try:
                at_probe["Phong"] = np.round(
                    shading.phong(c, Ia, ka, Ip, kd, ks, n, L, self.probe, V), 4)
            except ValueError:
                pass
            try:
                at_probe["Blinn-Phong"] = np.round(
                    shading.blinn_phong(c, Ia, ka, Ip, kd, ks, n, L, self.probe, V), 4)
            except ValueError:  # V = -L: no half-way vector
                pass
        try:
            h_shown = np.round(shading.halfway(L, V), 3)
        except ValueError:
            pass
        self.probe_values = at_probe
        self.halfway_shown = h_shown
        self.readout.value = self._readout_html(L, V)
        set_summary(self.fig, self._summary())

    def _summary(self) -> str:
        """The figure in words (its text alternative's first sentences): the material, the
        light and the viewer, where each model puts its highlight and the probe's colours."""
        def where(peak):
            return "no highlight" if peak is None else \
                f"highlight at column {num(peak[1])}, row {num(peak[0])}"

        def rgb(v):
            return "hidden" if v is None else "(" + ", ".join(num(x) for x in v) + ")"

        return (f"Two spheres of colour {self.colour.value}, ka {num(self.ka.value)}, "
                f"kd {num(self.kd.value)}, ks {num(self.ks.value)}, n {num(self.n.value)}, lit "
                f"from azimuth {num(self.light_azimuth.value)} degrees, elevation "
                f"{num(self.light_elevation.value)} degrees, seen from azimuth "
                f"{num(self.view_azimuth.value)}, elevation {num(self.view_elevation.value)}. "
                f"Phong (left): {where(self.peaks[0])}, probe intensity "
                f"{rgb(self.probe_values['Phong'])}. Blinn-Phong (right): "
                f"{where(self.peaks[1])}, probe intensity {rgb(self.probe_values['Blinn-Phong'])}.")

    def _readout_html(self, L, V) -> str:
        def vec(v):
            return "(" + ", ".join(f"{x:+.3f}" for x in v) + ")"

        def rgb(v):
            return "—  (probe hidden)" if v is None else "(" + ", ".join(f"{x:.4f}" for x in v) + ")"

        H = "undefined (V = −L)" if self.halfway_shown is None else vec(self.halfway_shown)
        return readout_html(
            f"L = {vec(L)}", f"V = {vec(V)}"
            f"{' (the exam&#39;s exact directions)' if self._exam_mode else ''}", f"H = {H}",
            f"probe N = {vec(self.probe)} (yellow square)",
            f"<b>Phong</b> I = {rgb(self.probe_values['Phong'])}",
            f"<b>Blinn-Phong</b> I = {rgb(self.probe_values['Blinn-Phong'])}")

    def load_exam(self, *_):
        """Set the controls to the Q5(b) example (one update at the end).

        The sliders can only show the exam's light elevation, asin(1/sqrt 3) = 35.26 degrees,
        to their step (the browser rounds it), so until a direction slider is moved by more
        than half a step the explorer uses the exam's exact ``L`` and ``V``.
        """
        self._holding = True
        try:
            for name, value in EXAM_SETTINGS.items():
                getattr(self, name).value = value
        finally:
            self._holding = False
        self._exam_mode = True
        self.update()

    def set(self, **values):
        """Set several controls at once (``ka=0.3, light_azimuth=10, colour="#ff0000"``, ...)
        and update once."""
        self._holding = True
        try:
            for name, value in values.items():
                getattr(self, name).value = value
                self._leave_exam_if_moved(name)
        finally:
            self._holding = False
        self.update()

    def _leave_exam_if_moved(self, name):
        slider = self.directions.get(name)
        if (self._exam_mode and slider is not None
                and abs(slider.value - EXAM_SETTINGS[name]) > 0.5 * slider.step + 1e-9):
            self._exam_mode = False

    def _on_change(self, change):
        if self._holding:
            return
        for name, slider in self.directions.items():
            if change["owner"] is slider:
                self._leave_exam_if_moved(name)
        self.update()

    # ---------------------------------------------------------------------------------------
    # display

    def _build_layout(self, view):
        """The explorer's layout: the two spheres above the controls and the readout."""
        left = W.VBox([self.ka, self.kd, self.ks, self.n, self.colour])
        right = W.VBox([self.light_azimuth, self.light_elevation, self.view_azimuth,
                        self.view_elevation, self.exam_button])
        return W.VBox([view, W.HBox([left, right]), self.readout])


def phong_explorer(size: int = 128) -> PhongExplorer:
    """The Q5 Phong explorer (display it as a cell's last expression)."""
    return PhongExplorer(size=size)
