"""Figures of Q1(c): the phantom's true geometry, its simulated B-scan and A-lines.

Every function takes an optional ``ax`` and returns the artists it drew, so that the B-scan
explorer (:mod:`course_lib.widgets.ultrasound`) can update them in place.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Rectangle

from .. import ultrasound as us
from ..plotting import COLOURS, new_figure
from .describe import num, set_summary

#: Fill colours of the materials in the true-geometry panel.
MATERIAL_COLOURS = {
    "water": "#cfe8ff",
    "fat": "#f6d55c",
    "liver": "#a0522d",
    "acrylic": "#9e9e9e",
}


def _ax(ax):
    if ax is None:
        _, ax = new_figure(size=5.0)
    return ax


def block_outline(x0, x1, z0, z1):
    """Closed outline ``(xs, zs)`` of a rectangle, for ``Line2D.set_data``."""
    return np.array([x0, x1, x1, x0, x0]), np.array([z0, z0, z1, z1, z0])


def plot_phantom(phantom, ax=None, speeds=None):
    """Q1(c): the true geometry of the phantom (probe on top, depth downwards, mm).

    Parameters
    ----------
    phantom : dict
        As returned by :func:`course_lib.ultrasound.exam_phantom`.
    ax : matplotlib Axes, optional
    speeds : dict, optional
        Sound-speed overrides shown in the labels.

    Returns
    -------
    dict
        ``{"patches": [Rectangle, ...], "labels": [Text, ...], "probe": Line2D}``.
    """
    ax = _ax(ax)
    width, floor = phantom["width"], phantom["floor_depth"]
    bottom = 1.15 * floor
    patches = [Rectangle((0, 0), width, floor, color=MATERIAL_COLOURS[phantom["bath"]]),
               Rectangle((0, floor), width, bottom - floor, color=MATERIAL_COLOURS["acrylic"])]
    labels = []
    for name, x0, x1, z0, z1 in phantom["blocks"]:
        patches.append(Rectangle((x0, z0), x1 - x0, z1 - z0, facecolor=MATERIAL_COLOURS[name],
                                 edgecolor="k", linewidth=1.0))
        c = us.material_properties(name, speeds)["c"]
        labels.append(ax.text((x0 + x1) / 2, (z0 + z1) / 2, f"{name}\n{c:.0f} m/s",
                              ha="center", va="center", fontsize=8,
                              color="white" if name == "liver" else "black"))
    for p in patches:
        ax.add_patch(p)
    labels.append(ax.text(width / 2, (floor + bottom) / 2, "bath floor (acrylic)",
                          ha="center", va="center", fontsize=8))
    c_bath = us.material_properties(phantom["bath"], speeds)["c"]
    labels.append(ax.text(1.0, floor - 1.5, f"{phantom['bath']} {c_bath:.0f} m/s", fontsize=8))
    (probe,) = ax.plot([0, width], [0, 0], color="k", linewidth=6, solid_capstyle="butt")
    ax.set_xlim(0, width)
    ax.set_ylim(bottom, -2)
    ax.set_xlabel("lateral position x (mm)")
    ax.set_ylabel("true depth (mm)")
    ax.set_title("phantom: true geometry")
    return {"patches": patches, "labels": labels, "probe": probe}


def plot_bscan(image, extent, ax=None, phantom=None, speeds=None, c_assumed=us.C_ASSUMED,
               show_displayed=False):
    """A simulated B-scan with the phantom's TRUE outlines overlaid (dashed).

    Parameters
    ----------
    image, extent
        From :func:`course_lib.ultrasound.simulate_bscan`.
    ax : matplotlib Axes, optional
    phantom : dict, optional
        Draws the true outline of each block and the true floor (dashed).
    speeds, c_assumed
        Used with ``show_displayed`` to draw where the scanner puts each block (solid).
    show_displayed : bool
        Also draw the displayed outlines (:func:`displayed_outlines`, at display precision).

    Returns
    -------
    dict
        ``{"image": AxesImage, "true": [Line2D, ...], "displayed": [Line2D, ...],
        "floor": Line2D or None}``.
    """
    ax = _ax(ax)
    im = ax.imshow(image, extent=extent, cmap="gray", vmin=0.0, vmax=1.0, aspect="auto",
                   interpolation="nearest")
    true_lines, shown_lines, floor_line = [], [], None
    if phantom is not None:
        for _, x0, x1, z0, z1 in phantom["blocks"]:
            (line,) = ax.plot(*block_outline(x0, x1, z0, z1), "--", color=COLOURS["reference"],
                              linewidth=1.2)
            true_lines.append(line)
        (floor_line,) = ax.plot([0, phantom["width"]], [phantom["floor_depth"]] * 2, "--",
                                color=COLOURS["reference"], linewidth=1.2, label="true geometry")
        if show_displayed:
            for xs, zs in displayed_outlines(phantom, speeds, c_assumed):
                (line,) = ax.plot(xs, zs, ":", color=COLOURS["received"], linewidth=1.2)
                shown_lines.append(line)
            shown_lines[-1].set_label("where the scanner draws it")
        ax.legend(loc="upper center", ncol=2, fontsize=7, framealpha=0.8)
        set_summary(ax, bscan_summary(phantom, speeds, c_assumed))
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_xlabel("lateral position x (mm)")
    ax.set_ylabel(f"displayed depth (mm), assuming {c_assumed:.0f} m/s")
    ax.set_title("simulated B-scan")
    return {"image": im, "true": true_lines, "displayed": shown_lines, "floor": floor_line}


def bscan_summary(phantom, speeds=None, c_assumed=us.C_ASSUMED) -> str:
    """Q1(c) in words, for the B-scan's text alternative: each block's true depths and
    thickness and where the scanner draws it, then the floor under a gap and its deepest
    displayed point (the numbers a student reads off the picture, three figures)."""
    faces, _x, floor = us.displayed_faces(phantom, speeds, c_assumed)
    parts = []
    for (name, _x0, _x1, z0, z1), (top, bottom) in zip(phantom["blocks"], faces):
        parts.append(f"{name} block {num(z0)} to {num(z1)} mm deep ({num(z1 - z0)} mm thick) "
                     f"drawn from {num(top)} to {num(bottom)} mm ({num(bottom - top)} mm)")
    return (f"Where the scanner, assuming {num(c_assumed)} m/s, draws the phantom: "
            + "; ".join(parts) + f"; the floor, {num(phantom['floor_depth'])} mm deep, drawn "
            f"between {num(np.nanmin(floor))} and {num(np.nanmax(floor))} mm.")


def displayed_outlines(phantom, speeds=None, c_assumed=us.C_ASSUMED):
    """Outlines ``[(xs, zs), ...]`` of each block as displayed, then the displayed floor, at
    display precision (:func:`course_lib.ultrasound.to_display_precision` of the deepest).

    The floor is a step line across the whole width; the blocks are rectangles whose top and
    bottom are the displayed depths of their faces (lateral size unchanged).
    """
    faces, x, floor = us.displayed_faces(phantom, speeds, c_assumed)
    deepest = float(np.nanmax(floor))
    out = [block_outline(x0, x1, *us.to_display_precision(face, deepest))
           for (_, x0, x1, _z0, _z1), face in zip(phantom["blocks"], faces)]
    out.append((x, us.to_display_precision(floor, deepest)))
    return out


def displayed_interfaces(phantom, x, speeds=None, c_assumed=us.C_ASSUMED):
    """Displayed depth of every interface under the column at ``x`` (mm), shallowest first,
    at display precision (Q1(c), for the A-lines' ticks)."""
    _, _true, shown = us.phantom_interfaces(phantom["blocks"], phantom["floor_depth"],
                                           phantom["width"], x=[x], bath=phantom["bath"],
                                           speeds=speeds, c_assumed=c_assumed)
    row = shown[0][np.isfinite(shown[0])]
    return us.to_display_precision(row)


def plot_aline(depth, envelope, x, columns, ax=None, labels=None, phantom=None, speeds=None,
               c_assumed=us.C_ASSUMED):
    """A-line profiles (echo level in dB against displayed depth) of chosen columns.

    Parameters
    ----------
    depth, envelope, x
        From ``simulate_bscan(..., return_envelope=True)``.
    columns : sequence of float
        Lateral positions (mm) of the A-lines; the nearest column is used.
    labels : sequence of str, optional
    phantom : dict, optional
        Marks the true (dotted) and displayed (solid ticks) floor depth of each A-line.

    Returns
    -------
    dict
        ``{"lines": [Line2D, ...], "markers": [Line2D, ...]}``.
    """
    ax = _ax(ax)
    lines, markers = [], []
    colours = [COLOURS["curve"], COLOURS["highlight"], COLOURS["reference"], COLOURS["hull"]]
    for i, xc in enumerate(columns):
        j = int(np.argmin(np.abs(x - xc)))
        level = 20 * np.log10(np.maximum(envelope[:, j], 1e-6))
        label = labels[i] if labels else f"x = {x[j]:.1f} mm"
        # told apart without their colours: a dash pattern is lost along a jagged echo trace
        # of a thousand samples, so each column also carries a marker shape of its own
        (line,) = ax.plot(depth, level, color=colours[i % 4], linewidth=0.8, label=label,
                          linestyle=("-", "--", "-.", ":")[i % 4], marker="osD^"[i % 4],
                          markersize=4, markevery=max(1, len(depth) // 12))
        lines.append(line)
        if phantom is not None:
            for d in displayed_interfaces(phantom, x[j], speeds, c_assumed):
                markers.append(ax.axvline(d, color=colours[i % 4], linewidth=0.6, alpha=0.5))
    if phantom is not None:
        markers.append(ax.axvline(phantom["floor_depth"], color="k", linestyle=":",
                                  linewidth=1.0, label="true floor depth"))
    ax.set_xlabel("displayed depth (mm)")
    ax.set_ylabel("echo level (dB re perfect reflector)")
    ax.set_ylim(-100, 0)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title("A-lines")
    return {"lines": lines, "markers": markers}


def phantom_and_bscan(phantom=None, speeds=None, show_displayed=False, **simulate_kwargs):
    """Q1(c) side by side: true geometry | simulated B-scan with the true outlines overlaid.

    Returns ``(fig, {"phantom": ..., "bscan": ...})``; extra keyword arguments go to
    :func:`course_lib.ultrasound.simulate_bscan`.
    """
    phantom = us.exam_phantom() if phantom is None else phantom
    image, _x, _depth, extent = us.simulate_bscan(**phantom, speeds=speeds, **simulate_kwargs)
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.8), sharey=False)
    fig.set_layout_engine("constrained")
    a = plot_phantom(phantom, ax0, speeds)
    b = plot_bscan(image, extent, ax1, phantom, speeds,
                   simulate_kwargs.get("c_assumed", us.C_ASSUMED), show_displayed)
    ax0.set_ylim(extent[2], extent[3])
    return fig, {"phantom": a, "bscan": b}


def aline_figure(phantom=None, speeds=None, **simulate_kwargs):
    """A-lines through a gap, the fat block and the liver block of the phantom (one figure)."""
    phantom = us.exam_phantom() if phantom is None else phantom
    _, x, depth, _, env = us.simulate_bscan(**phantom, speeds=speeds, return_envelope=True,
                                            **simulate_kwargs)
    centres = {b[0]: (b[1] + b[2]) / 2 for b in phantom["blocks"]}
    cols = [phantom["blocks"][0][1] / 2, centres.get("fat"), centres.get("liver")]
    names = ["through a gap", "through the fat", "through the liver"]
    keep = [i for i, c in enumerate(cols) if c is not None]
    fig, ax = plt.subplots(figsize=(9, 3.8))
    fig.set_layout_engine("constrained")
    art = plot_aline(depth, env, x, [cols[i] for i in keep], ax, [names[i] for i in keep],
                     phantom, speeds, simulate_kwargs.get("c_assumed", us.C_ASSUMED))
    return fig, art
