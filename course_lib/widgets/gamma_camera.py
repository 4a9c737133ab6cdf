"""The collimator explorer of Q2(c)-(d): which holes pass photons, and how sharp is the image.

:class:`CollimatorExplorer` shows a parallel-hole collimator built like the one of Q2(d): a
centre hole and rings of ``8k`` holes ``k * pitch`` from the axis, on a face whose radius is one
pitch beyond the last ring, with an on-axis point source a distance ``z`` in front of it.
Sliders set the hole diameter ``d``, the hole length ``L``, the source distance ``z``, the ring
pitch and the number of rings. Three panels:

* **exam model** (Q2(d)): the face with each hole green when the exam's all-or-nothing rule
  ``r L / z <= d`` lets it through and grey when it does not; the dashed circle is the cut-off
  radius ``d z / L``;
* **exact**: the same face with each hole coloured by the share of the photons falling on its
  mouth that leave its back, from the exact lens-overlap model of
  :mod:`course_lib.gamma_camera` (``hole_pass_area``); the dotted circle is the exact cut-off
  ``d z / L + d / 2`` beyond which no straight ray passes;
* **side view** (Q2(c)), a schematic not to scale: one hole, the two lines from the crystal
  behind its centre through the edges of its mouth, and the patch of the source plane they
  span, ``R = d (L + z) / L`` by similar triangles (the dashed lines are the extreme edge-to-edge rays).

The readout compares the exam's open fraction (open holes' area over the face area) with the
exact transmission (uniform over the face, as the exam assumes, and for an isotropic point
source) and gives the resolution. The button "Exam Q2(d)" restores the notebook's givens: 1 mm
holes 40 mm long, 10 mm pitch, 4 rings (a 50 mm face, 81 holes), source at 1000 mm: 25 holes
open, 0.25 %.

Every change calls :meth:`CollimatorExplorer.update`, which replaces the paths and colour values
of the existing hole collections (``set_paths``, ``set_array``), moves the circles, rectangles
and lines (``set_radius``, ``set_bounds``, ``set_data``) and redraws; no artist is created.
The browser paints what changed over the cached axes (:mod:`course_lib.widgets._view`).
A change of an axes' limits means drawing its ticks again with Agg (a new
background, the one costly kind of update), so: a move of ``d``, ``L`` or ``z`` never changes
them (the side view keeps its data in mm and fits them into fixed axes with one scaling,
``side_limits`` holding the mm shown; it has no ticks, its labels give the sizes), and a move
of the pitch or the rings changes the face views' limits only when the face crosses one of
the sizes in :data:`FACE_LIMITS`.

In a notebook (any matplotlib backend)::

    from course_lib.widgets.gamma_camera import collimator_explorer
    collimator_explorer()
"""

from __future__ import annotations

import ipywidgets as W
import matplotlib as mpl
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import PatchCollection
from matplotlib.colors import ListedColormap
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Patch, Rectangle
from matplotlib.transforms import Affine2D

from .. import gamma_camera as gc
from ..plotting import COLOURS
from ..plots.gamma_camera import (OPEN, SEPTUM, SHUT, display_rounded, shares_shown,
                                  significant)
from ._view import FigureExplorer, one_at_a_time, readout_html

__all__ = ["CollimatorExplorer", "EXAM_SETTINGS", "collimator_explorer", "collimator_model",
           "face_limit", "face_radius", "hole_draw_radius"]

#: The notebook's givens for Q2(d) (our reconstruction of the question, see the notebook).
EXAM_SETTINGS = {"d": 1.0, "L": 40.0, "z": 1000.0, "pitch": 10.0, "n_rings": 4}


def face_radius(pitch: float, n_rings: int) -> float:
    """Radius of the collimator face: one pitch beyond the last ring (Q2(d): 5 x 10 = 50 mm)."""
    return (int(n_rings) + 1) * float(pitch)


#: The half-widths (mm) the face views step through, so that most pitch or ring changes keep
#: their limits (and ticks) as they were.
FACE_LIMITS = (3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 12.0, 15.0, 20.0, 25.0, 30.0, 40.0, 50.0, 60.0,
               80.0, 100.0, 120.0, 150.0, 200.0, 250.0)


def face_limit(extent: float) -> float:
    """The half-width of the face views for a drawing reaching ``extent`` mm from the axis
    (the face, or a hole drawn beyond it): the first of :data:`FACE_LIMITS` that leaves a 4 %
    margin (Q2(d)'s 50 mm face: 60 mm)."""
    need = 1.04 * float(extent)
    return next((lim for lim in FACE_LIMITS if lim >= need), need)


def hole_draw_radius(d: float, pitch: float, n_rings: int) -> float:
    """Radius at which the holes are drawn on the face.

    Real holes are tiny next to the face (1 mm on 100 mm in Q2(d)), so they are drawn at 35 % of
    the closest spacing between neighbouring holes (``2 pitch sin(pi / 8)`` along ring 1, or the
    pitch itself when there is only the centre hole), or at their true radius if that is larger.
    """
    spacing = 2.0 * pitch * np.sin(np.pi / 8.0) if n_rings >= 1 else float(pitch)
    return max(0.35 * spacing, d / 2.0)


def collimator_model(d, L, z, pitch, n_rings) -> dict:
    """The explorer's numbers for one setting of its sliders, at display precision (Q2(c)-(d)).

    ``{"holes": the hole centres (to 1e-4 of the face radius), "exam_open": each hole's 0/1
    verdict r L / z <= d, "exact_share": the share of its mouth's photons that pass
    (``plots.gamma_camera.shares_shown``), "results": the readout's numbers to the digits it
    shows}``: 4 significant figures, the exam / exact ratio to 3, the hole-equivalents to 2
    decimals, the side view's label of R as text (see :class:`CollimatorExplorer`).
    """
    Rf = face_radius(pitch, n_rings)
    holes = gc.ring_hole_positions(pitch, n_rings)
    r = np.hypot(holes[:, 0], holes[:, 1])
    exam_open = (r * L / z <= d).astype(np.float64)       # the rule of gc.open_fraction
    area = np.atleast_1d(gc.hole_pass_area(r, d, L, z))
    share = area / (np.pi * d**2 / 4.0)
    exam = gc.open_fraction(holes, d, L, z, Rf)
    exact = float(area.sum() / (np.pi * Rf**2))
    resolution = gc.collimator_resolution(d, L, z)
    results = {
        "n_holes": len(holes), "n_open": int(exam_open.sum()), "face_radius": Rf,
        "cutoff_exam": significant(gc.exam_cutoff_radius(d, L, z)),
        "cutoff_exact": significant(gc.exact_cutoff_radius(d, L, z)),
        "exam_fraction": significant(exam), "exact_fraction": significant(exact),
        "isotropic_fraction": significant(gc.exact_open_fraction(holes, d, L, z, Rf,
                                                                 "isotropic")),
        "ratio": significant(exam / exact, 3) if exact > 0 else float("inf"),
        "resolution": significant(resolution), "resolution_label": f"{resolution:.3g}",
        "overlap": bool(n_rings >= 1 and d >= 2.0 * pitch * np.sin(np.pi / 8.0)),
        "hole_equivalents": float(f"{share.sum():.2f}"),
    }
    return {"holes": display_rounded(holes, Rf), "exam_open": exam_open,
            "exact_share": shares_shown(share), "results": results}


class CollimatorExplorer(FigureExplorer):
    """Interactive explorer of the parallel-hole collimator of Q2(c)-(d) (see the module docstring).

    Parameters
    ----------
    d, L, z, pitch : float
        Initial hole diameter, hole length, source distance and ring pitch (mm).
    n_rings : int
        Initial number of rings around the centre hole.

    Attributes
    ----------
    fig, ax_exam, ax_exact, ax_side
        The figure and its three axes (exam model, exact transmission, side view).
    d, L, z, pitch, n_rings
        The controls (ipywidgets); set their ``.value`` from Python to drive the explorer.
    exam_button : ipywidgets.Button
        Restores :data:`EXAM_SETTINGS`.
    readout : ipywidgets.HTML
        Open holes, the exam's fraction, the exact transmissions and the resolution.
    art : dict
        The artists that :meth:`update` changes in place.
    holes : numpy.ndarray
        Current hole centres ``(n, 2)``.
    exam_open, exact_share : numpy.ndarray
        Per hole: the exam's 0/1 verdict and the exact share of its mouth's photons that pass.
    results : dict
        ``n_holes``, ``n_open``, ``face_radius``, ``cutoff_exam``, ``cutoff_exact``,
        ``exam_fraction``, ``exact_fraction`` (uniform), ``isotropic_fraction``, ``ratio``
        (exam / exact), ``hole_equivalents`` (the exact shares summed over the holes),
        ``resolution`` and ``resolution_label`` after the last update.

    Every number kept here is at display precision (:func:`collimator_model`).
    """

    def __init__(self, d=1.0, L=40.0, z=1000.0, pitch=10.0, n_rings=4):
        slider = {"continuous_update": True, "style": {"description_width": "175px"},
                  "layout": W.Layout(width="425px")}
        self.d = W.FloatSlider(d, min=0.2, max=5.0, step=0.1, description="hole diameter d (mm)",
                               readout_format=".1f", **slider)
        self.L = W.FloatSlider(L, min=5.0, max=250.0, step=1.0,
                               description="hole length L (mm)", readout_format=".0f", **slider)
        self.z = W.FloatSlider(z, min=10.0, max=3000.0, step=10.0,
                               description="source distance z (mm)", readout_format=".0f",
                               **slider)
        self.pitch = W.FloatSlider(pitch, min=2.0, max=20.0, step=0.5,
                                   description="ring pitch (mm)", readout_format=".1f", **slider)
        self.n_rings = W.IntSlider(n_rings, min=0, max=8, step=1, description="number of rings",
                                   **slider)
        self.exam_button = W.Button(description="Exam Q2(d)", button_style="info",
                                    tooltip="d = 1 mm, L = 40 mm, z = 1000 mm, pitch 10 mm, "
                                            "4 rings on a 50 mm face")
        self.readout = W.HTML()
        self.results: dict = {}
        self._holding = False

        with plt.ioff():
            self.fig, axes = plt.subplots(1, 3, figsize=(13.5, 4.6),
                                          gridspec_kw={"width_ratios": [1, 1.2, 0.9]})
        self.fig.set_layout_engine("constrained")
        self.ax_exam, self.ax_exact, self.ax_side = axes
        canvas = self.fig.canvas
        for attr, value in (("header_visible", False), ("resizable", False)):
            if hasattr(canvas, attr):
                setattr(canvas, attr, value)
        self.art = self._draw()
        for w in self.controls:
            w.observe(self._on_change, names="value")
        self.exam_button.on_click(self.load_exam)
        self.update()

    # ---------------------------------------------------------------------------------------
    # drawing (once)

    def _draw(self) -> dict:
        art = {}
        for key, ax in (("exam", self.ax_exam), ("exact", self.ax_exact)):
            face = Circle((0, 0), 1.0, facecolor=SEPTUM, alpha=0.35, edgecolor="k")
            ax.add_patch(face)
            coll = PatchCollection([], edgecolor="k", linewidth=0.4)
            if key == "exam":
                coll.set_cmap(ListedColormap([SHUT, OPEN]))
                coll.set_clim(0.0, 1.0)
            else:
                coll.set_cmap(mpl.colormaps["viridis"].with_extremes(under=SHUT))
                coll.set_clim(1e-12, 1.0)      # holes that pass nothing are drawn grey
            coll.set_array(np.zeros(0))
            ax.add_collection(coll)
            exam_cut = Circle((0, 0), 1.0, fill=False, linestyle="--", linewidth=1.3,
                              edgecolor=COLOURS["highlight"])
            exact_cut = Circle((0, 0), 1.0, fill=False, linestyle=":", linewidth=1.3,
                               edgecolor="k")
            ax.add_patch(exam_cut)
            ax.add_patch(exact_cut)
            ax.set_aspect("equal")
            ax.set_xlabel("x (mm)")
            art[key] = {"face": face, "holes": coll, "cutoffs": [exam_cut, exact_cut]}
        self.ax_exam.set_ylabel("y (mm)")
        self.ax_exam.legend(
            handles=[Patch(facecolor=OPEN, edgecolor="k", label="open: r L / z ≤ d"),
                     Patch(facecolor=SHUT, edgecolor="k", label="shut"),
                     Line2D([], [], color=COLOURS["highlight"], linestyle="--",
                            label="exam cut-off d z / L")],
            loc="lower left", fontsize=7, framealpha=0.9)
        self.ax_exact.legend(
            handles=[Line2D([], [], color=COLOURS["highlight"], linestyle="--",
                            label="exam cut-off d z / L"),
                     Line2D([], [], color="k", linestyle=":", label="exact cut-off d z / L + d/2")],
            loc="lower left", fontsize=7, framealpha=0.9)
        art["colorbar"] = self.fig.colorbar(art["exact"]["holes"], ax=self.ax_exact, shrink=0.8,
                                            label="share of a hole's photons that pass")

        ax = self.ax_side
        septa = [Rectangle((0, 0), 1, 1, facecolor=SEPTUM, edgecolor="k", hatch="//")
                 for _ in range(2)]
        for p in septa:
            ax.add_patch(p)
        rays = [ax.plot([], [], color=COLOURS["highlight"], linewidth=1.5)[0] for _ in range(2)]
        extreme = [ax.plot([], [], color=COLOURS["control"], linestyle="--", linewidth=1.0)[0]
                   for _ in range(2)]
        (bracket,) = ax.plot([], [], color=COLOURS["curve"], linewidth=3,
                             solid_capstyle="butt")
        (crystal,) = ax.plot([], [], color="#444444", linewidth=4)
        (face_line,) = ax.plot([], [], color="#444444", linewidth=0.6, linestyle=":")
        (source,) = ax.plot([], [], "*", color=COLOURS["received"], markersize=11)
        box = {"boxstyle": "round,pad=0.2", "fc": "white", "ec": "none", "alpha": 0.85}
        labels = {
            "R": ax.text(0, 0, "", ha="center", va="bottom", color=COLOURS["curve"]),
            "L": ax.text(0, 0, "", ha="left", va="center", fontsize=9, bbox=box),
            "d": ax.text(0, 0, "", ha="center", va="bottom", fontsize=9, bbox=box),
            "z": ax.text(0, 0, "", ha="center", va="center", fontsize=9, bbox=box),
            "crystal": ax.text(0, 0, "crystal", ha="right", va="top", fontsize=9),
        }
        ax.set_xlabel("lateral position")
        ax.set_ylabel("distance from the collimator face")
        ax.set_title("Q2(c): one hole, side view (not to scale)", fontsize=9)
        for face_ax in (self.ax_exam, self.ax_exact):
            face_ax.title.set_fontsize(9)
        # The side view keeps its data in mm and fits them to fixed axes through one scaling
        # (set by _update_side): its limits never change, so a slider move keeps the background.
        self._side_fit = Affine2D()
        fitted = self._side_fit + ax.transData
        for artist in (*septa, *rays, *extreme, bracket, crystal, face_line, source,
                       *labels.values()):
            artist.set_transform(fitted)
        ax.set_xlim(-1.0, 1.0)
        ax.set_ylim(0.0, 1.0)
        ax.set_xticks([])
        ax.set_yticks([])
        art["side"] = {"septa": septa, "rays": rays, "extreme": extreme, "bracket": bracket,
                       "crystal": crystal, "face": face_line, "source": source,
                       "labels": labels}
        return art

    # ---------------------------------------------------------------------------------------
    # the model

    @property
    def controls(self):
        return (self.d, self.L, self.z, self.pitch, self.n_rings)

    @one_at_a_time
    def update(self):
        """Recompute, change the artists in place, refresh the readout and redraw."""
        with self.readout.hold_sync():  # the figure's frame goes first, the readout after it
            self.refresh()
            self._redraw()

    def refresh(self):
        """The per-update compute: the holes' verdicts and transmissions, the artists' data and
        the readout; no drawing."""
        d, L, z = self.d.value, self.L.value, self.z.value
        pitch, n = self.pitch.value, int(self.n_rings.value)
        Rf = face_radius(pitch, n)
        model = collimator_model(d, L, z, pitch, n)
        self.holes, self.exam_open = model["holes"], model["exam_open"]
        self.exact_share = model["exact_share"]
        self.results = res = model["results"]

        radius = hole_draw_radius(d, pitch, n)
        lim = face_limit(max(Rf, n * pitch + radius))     # the last ring is n pitches out
        # the holes' outlines change with d, the pitch and the rings only (not with L or z)
        outline = (pitch, n, radius)
        circles = None
        if outline != getattr(self, "_outline", None):
            self._outline = outline
            circles = [Circle(tuple(c), radius) for c in self.holes]
        for key, ax, values in (("exam", self.ax_exam, self.exam_open),
                                ("exact", self.ax_exact, self.exact_share)):
            a = self.art[key]
            if a["face"].get_radius() != Rf:        # unchanged: kept from the last frame
                a["face"].set_radius(Rf)
            if circles is not None:
                # PatchCollection.set_paths takes patches and stores their paths (no new artist)
                a["holes"].set_paths(circles)
            a["holes"].set_array(values)
            a["cutoffs"][0].set_radius(res["cutoff_exam"])
            a["cutoffs"][1].set_radius(res["cutoff_exact"])
            ax.set_xlim(-lim, lim)
            ax.set_ylim(-lim, lim)
        scale = radius / (d / 2.0)
        size = f" (holes drawn ×{scale:.2g})" if scale > 1.0001 else ""
        # set_text marks a title changed only when its text is new: an unchanged title is
        # not laid out and sent again (the exact numbers are in the readout)
        self.ax_exam.title.set_text(f"Q2(d) exam model: {res['n_open']} of {res['n_holes']} "
                                    f"holes open{size}")
        self.ax_exact.title.set_text(f"exact lens-overlap model{size}")
        self._update_side(d, L, z, res["resolution"], res["resolution_label"])
        self.readout.value = self._readout_html(d, L, z, res)

    def _update_side(self, d, L, z, R, R_text):
        """Q2(c): move the side view's septa, rays, bracket and labels to ``d, L, z`` (``R``
        the resolution to 4 significant figures, ``R_text`` as the label writes it)."""
        s = self.art["side"]
        w = 1.2 * d
        s["septa"][0].set_bounds(-d / 2 - w, -L, w, L)
        s["septa"][1].set_bounds(d / 2, -L, w, L)
        for sign, ray in zip((1, -1), s["rays"]):
            ray.set_data([0.0, sign * R / 2], [-L, z])
        far = significant(d / 2 + d * z / L)       # edge-to-edge ray at the source plane
        for sign, ray in zip((1, -1), s["extreme"]):
            ray.set_data([-sign * d / 2, sign * far], [-L, z])
        s["bracket"].set_data([-R / 2, R / 2], [z, z])
        span = 1.12 * max(far, d / 2 + w)
        s["crystal"].set_data([-span, span], [-L, -L])
        s["face"].set_data([-span, span], [0.0, 0.0])
        s["source"].set_data([0.0], [z])
        top = 1.15 * z + 0.1 * L
        lab = s["labels"]
        lab["R"].set_text(f"R = d(L+z)/L = {R_text} mm")
        lab["R"].set_position((0.0, z + 0.03 * (z + L)))
        lab["L"].set_text(f"L = {L:g} mm")
        lab["d"].set_text(f"d = {d:g} mm")
        lab["d"].set_position((0.0, 0.02 * (L + z)))
        lab["z"].set_text(f"z = {z:g} mm")
        lab["z"].set_position((0.0, z / 2))
        lab["crystal"].set_position((0.95 * span, -L - 0.01 * (L + z)))
        self.side_limits = ((-span, span), (-L - 0.12 * (L + z), top + 0.05 * (L + z)))
        (x0, x1), (y0, y1) = self.side_limits
        self._side_fit.clear().translate(-x0, -y0).scale(2.0 / (x1 - x0), 1.0 / (y1 - y0))
        self._side_fit.translate(-1.0, 0.0)
        self._place_length_label(L, z, span)

    def _place_length_label(self, L, z, span):
        """Beside the septa while they stand at least two lines of text tall on screen; below
        the crystal (left, as "crystal" is right) once z dwarfs L, never over the crystal bar."""
        label = self.art["side"]["labels"]["L"]
        (_, _), (y0, y1) = self.side_limits
        septum_px = L / (y1 - y0) * self.ax_side.bbox.height
        line_px = 1.5 * label.get_fontsize() * self.fig.dpi / 72.0
        if septum_px >= 2.0 * line_px:
            label.set_position((-0.97 * span, -L / 2))
            label.set_verticalalignment("center")
        else:
            label.set_position((-0.97 * span, -L - 0.025 * (L + z)))
            label.set_verticalalignment("top")

    def _readout_html(self, d, L, z, res) -> str:
        head = (f"face radius {res['face_radius']:g} mm, {res['n_holes']} holes; "
                f"cut-off d z / L = {res['cutoff_exam']:.4g} mm "
                f"(exact: + d/2 = {res['cutoff_exact']:.4g} mm)")
        resolution = (f"<b>resolution</b> (Q2(c)) at z = {z:g} mm: R = d (L + z) / L = "
                      f"{res['resolution']:.4g} mm")
        if res["overlap"]:  # the models' fractions would pass 100 %: not shown
            return readout_html(
                head, resolution, "<span style='color:#d62728'>the holes are wider than their "
                "spacing and overlap: no septa are left between them, so neither model applies "
                "(no open fraction or transmission is shown)</span>")
        ratio = res["ratio"]
        return readout_html(
            head,
            f"<b>exam model</b> (Q2(d)): {res['n_open']} of {res['n_holes']} holes open, "
            f"open fraction {100 * res['exam_fraction']:.4g} %",
            f"<b>exact transmission</b>: {100 * res['exact_fraction']:.4g} % "
            f"(uniform over the face, as the exam assumes: "
            f"{res['hole_equivalents']:.2f} hole-equivalents pass); "
            f"{100 * res['isotropic_fraction']:.4g} % (isotropic point source); "
            f"exam / exact = {ratio:.3g}",
            resolution)

    # ---------------------------------------------------------------------------------------
    # controls

    def set(self, **values):
        """Set several controls at once (``d=2.0, z=500``, ...) and update once."""
        self._holding = True
        try:
            for name, value in values.items():
                getattr(self, name).value = value
        finally:
            self._holding = False
        self.update()

    def load_exam(self, *_):
        """Restore the notebook's Q2(d) givens (:data:`EXAM_SETTINGS`), with one update."""
        self.set(**EXAM_SETTINGS)

    def _on_change(self, change):
        if not self._holding:
            self.update()

    # ---------------------------------------------------------------------------------------
    # display

    def _build_layout(self, view):
        """The explorer's layout: the figure above the sliders, the button and the readout."""
        left = W.VBox([self.d, self.L, self.z])
        right = W.VBox([self.pitch, self.n_rings, self.exam_button])
        return W.VBox([view, W.HBox([left, right]), self.readout])


def collimator_explorer(d=1.0, L=40.0, z=1000.0, pitch=10.0, n_rings=4) -> CollimatorExplorer:
    """The Q2(c)-(d) collimator explorer (display it as a cell's last expression)."""
    return CollimatorExplorer(d=d, L=L, z=z, pitch=pitch, n_rings=n_rings)
