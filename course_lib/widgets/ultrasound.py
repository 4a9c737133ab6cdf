"""B-scan explorer for Q1(c): change tissue speeds, block sizes and frequency, watch the image.

Built from explicit ipywidgets controls with ``.observe`` callbacks (no ``interact``): the
figure is drawn once and :meth:`BScanExplorer.update` changes its artists in place
(``AxesImage.set_data``, ``Line2D.set_data``), under any matplotlib backend. The browser paints
the figure (:mod:`course_lib.widgets._view`): axes, ticks and labels stay cached, and
only the image (at its own resolution, scaled by the page), the outlines and the A-lines are
sent again; the displayed block heights are a text readout under the figure, sent after it
(text that changes in the figure would be laid out and outlined in the kernel on every move).
"""

from __future__ import annotations

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np

from .. import ultrasound as us
from ..plots import ultrasound as uplots
from ..plots.describe import set_summary
from ._view import FigureView, one_at_a_time, one_message_at_a_time, readout_html


class BScanExplorer:
    """Interactive B-scan of the exam phantom.

    Controls: the true sound speed of fat, liver and water, the height of each block, the probe
    frequency and time-gain compensation. The left panel is the simulated image with the true
    outlines (dashed) and the displayed outlines (dotted); the right panel shows the A-lines
    through a gap and through the liver (before time-gain compensation: the echoes as they
    return); the readout under the figure (``readout``, HTML) gives the true and displayed
    block heights and the displayed liver / fat ratio.

    Parameters
    ----------
    nx : int
        Scan lines of the image (128 keeps an update well under 50 ms).
    seed : int
        Speckle seed (kept fixed so only the physics changes between updates).
    """

    DEPTH_MAX = 72.0

    def __init__(self, nx: int = 128, seed: int = 0):
        self.nx, self.seed = nx, seed
        style = {"description_width": "140px"}
        layout = widgets.Layout(width="360px")

        def slider(desc, value, lo, hi, step, fmt=".0f"):
            return widgets.FloatSlider(value=value, min=lo, max=hi, step=step, description=desc,
                                       continuous_update=False, readout_format=fmt,
                                       style=style, layout=layout)

        m = us.MATERIALS
        self.c_fat = slider("fat speed (m/s)", m["fat"]["c"], 1400, 1700, 2)
        self.c_liver = slider("liver speed (m/s)", m["liver"]["c"], 1400, 1700, 2)
        self.c_water = slider("water speed (m/s)", m["water"]["c"], 1400, 1700, 2)
        self.t_fat = slider("fat height (mm)", 40, 5, 45, 1)
        self.t_liver = slider("liver height (mm)", 40, 5, 45, 1)
        self.t_water = slider("water height (mm)", 40, 5, 45, 1)
        self.freq = slider("frequency (MHz)", 5.0, 2.0, 10.0, 0.5, ".1f")
        self.tgc = widgets.Checkbox(value=False, description="TGC (0.5 dB/cm/MHz)")
        self.controls = [self.c_fat, self.c_liver, self.c_water, self.t_fat, self.t_liver,
                         self.t_water, self.freq, self.tgc]

        with plt.ioff():
            self.fig, (self.ax_img, self.ax_line) = plt.subplots(
                1, 2, figsize=(10, 4.4), gridspec_kw={"width_ratios": [1.3, 1]})
        self.fig.set_layout_engine("constrained")
        phantom, sim = self._simulate()
        image, x, depth, extent, env = sim
        art = uplots.plot_bscan(image, extent, self.ax_img, phantom, self.speeds,
                                show_displayed=True)
        self.im, self.true_lines = art["image"], art["true"]
        self.shown_lines, self.true_floor = art["displayed"], art["floor"]
        self.ax_img.set_ylim(self.DEPTH_MAX, 0)
        self.a_lines = []
        for xc, label in ((self._gap_x(phantom), "through a gap"),
                          (self._liver_x(phantom), "through the liver")):
            (line,) = self.ax_line.plot(depth, self._aline(env, x, xc), linewidth=0.8,
                                        label=label)
            self.a_lines.append(line)
        self.ax_line.set_xlim(0, self.DEPTH_MAX)
        self.ax_line.set_ylim(-100, 0)
        self.ax_line.set_xlabel("displayed depth (mm)")
        self.ax_line.set_ylabel("echo level before TGC (dB)")
        self.ax_line.grid(True, alpha=0.3)
        self.ax_line.legend(fontsize=7, loc="upper right")
        self.readout = widgets.HTML()
        self._write_readout()

        for w in self.controls:
            w.observe(self._on_change, names="value")
        left = widgets.VBox(self.controls[:3] + [self.freq])
        right = widgets.VBox(self.controls[3:6] + [self.tgc])
        self._view = FigureView()                  # painted by the browser
        view = self._view.widget(self.fig)
        self.widget = one_message_at_a_time(
            widgets.VBox([widgets.HBox([left, right]), view, self.readout]), self.fig)
        self._view.redraw(self.fig)                # the first frame

    # ---------------------------------------------------------------------------------------
    @property
    def speeds(self) -> dict:
        return {"fat": self.c_fat.value, "liver": self.c_liver.value,
                "water": self.c_water.value}

    def phantom(self) -> dict:
        """The phantom of the current control values."""
        return us.exam_phantom(fat_thickness=self.t_fat.value,
                               liver_thickness=self.t_liver.value,
                               water_thickness=self.t_water.value)

    def _simulate(self):
        phantom = self.phantom()
        sim = us.simulate_bscan(**phantom, speeds=self.speeds, freq_mhz=self.freq.value,
                                nx=self.nx, seed=self.seed, depth_max=self.DEPTH_MAX,
                                tgc_db_per_cm_mhz=0.5 if self.tgc.value else 0.0,
                                return_envelope=True)
        return phantom, sim

    @staticmethod
    def _gap_x(phantom):
        return phantom["blocks"][0][1] / 2

    @staticmethod
    def _liver_x(phantom):
        b = next(b for b in phantom["blocks"] if b[0] == "liver")
        return (b[1] + b[2]) / 2

    @staticmethod
    def _aline(env, x, xc):
        j = int(np.argmin(np.abs(x - xc)))
        return 20 * np.log10(np.maximum(env[:, j], 1e-6))

    def _write_readout(self):
        """The readout: each block's true and displayed height (0.1 mm), and the displayed
        liver / fat ratio (3 decimals), Q1(c). Only this text leaves the routine: the students'
        copy computes the heights inside it and keeps none of them."""
        true = {"fat": self.t_fat.value, "liver": self.t_liver.value, "water": self.t_water.value}
        sp = self.speeds
        fat = us.displayed_thickness(true["fat"], sp["fat"])
        liver = us.displayed_thickness(true["liver"], sp["liver"])
        water = us.displayed_thickness(true["water"], sp["water"])
        parts = [f"fat {true['fat']:.0f} -> {fat:.1f} mm",
                 f"liver {true['liver']:.0f} -> {liver:.1f} mm",
                 f"water {true['water']:.0f} -> {water:.1f} mm"]
        self.readout.value = readout_html(
            f"block heights, true -> displayed: {', '.join(parts)}",
            f"liver / fat as displayed: {liver / fat:.3f}")

    # ---------------------------------------------------------------------------------------
    @one_at_a_time
    def update(self):
        """Re-simulate with the current controls, change the artists in place, redraw, then
        refresh the readout (sent after the figure's frame)."""
        with self.readout.hold_sync():
            self._update_figure()
            self._write_readout()

    def _update_figure(self):
        phantom, (image, x, depth, extent, env) = self._simulate()
        self.im.set_data(image)
        self.im.set_extent(extent)
        for line, (_, x0, x1, z0, z1) in zip(self.true_lines, phantom["blocks"]):
            line.set_data(*uplots.block_outline(x0, x1, z0, z1))
        outlines = uplots.displayed_outlines(phantom, self.speeds)
        for line, (xs, zs) in zip(self.shown_lines, outlines):
            line.set_data(xs, zs)
        speeds = None if self.speeds is None else dict(self.speeds)   # as of this frame
        set_summary(self.ax_img, lambda: uplots.bscan_summary(phantom, speeds))
        for line, xc in zip(self.a_lines, (self._gap_x(phantom), self._liver_x(phantom))):
            line.set_data(depth, self._aline(env, x, xc))
        self._view.redraw(self.fig)

    def _on_change(self, change):
        self.update()

    def _ipython_display_(self):
        from IPython.display import display
        display(self.widget)


def bscan_explorer(**kwargs) -> BScanExplorer:
    """The Q1(c) B-scan explorer: ``bscan_explorer()`` in a notebook cell shows it."""
    return BScanExplorer(**kwargs)
