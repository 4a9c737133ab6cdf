"""Figures of Q2: the photomultiplier's dynode cascade and the parallel-hole collimator.

Every function takes an optional ``ax`` and returns a dict of the artists it drew, so that an
explorer can update them in place (``set_data``, ``set_array``, ``set_radius``).

The numbers a figure shows that the graded functions (or their helpers) compute come from a few
small routines that return them at display precision only: text as the figure writes it,
numbers to the 4 significant figures of the readouts, plotted data to about 1e-4 of the axes'
span (far finer than a pixel, far coarser than the grader's comparison):
:func:`cascade_labels`, :func:`shown_resolution`, :func:`hole_verdicts`,
:func:`profile_curves` and :func:`model_curves`. In the students' copy of the library only
those routines compute with the left-out functions (docs/students-copy.md).
"""

from __future__ import annotations

import numpy as np
from matplotlib.collections import PatchCollection
from matplotlib.patches import Circle, FancyArrowPatch, FancyBboxPatch, Rectangle

from .. import gamma_camera as gc
from .._validate import as_scalar
from ..plotting import COLOURS, new_figure

SEPTUM = "#8c8c8c"
OPEN = "#2ca02c"
SHUT = "#d9d9d9"


def _ax(ax, size=5.0):
    if ax is None:
        _, ax = new_figure(size=size)
    return ax


# ---------------------------------------------------------------------------------------------
# display precision


def significant(x, digits=4) -> float:
    """``x`` to ``digits`` significant figures, exactly as a readout writes it (``"%.4g"``)."""
    return float(f"{float(x):.{int(digits)}g}")


def display_rounded(x, span) -> np.ndarray:
    """``x`` rounded to the power of ten at or below 1e-4 of ``span`` (the axes' span, or the
    largest value drawn): plotted data at display precision."""
    span = float(span)
    decimals = int(np.ceil(-np.log10(1e-4 * span))) if span > 0 and np.isfinite(span) else 4
    return np.round(np.asarray(x, dtype=np.float64), decimals)


def shares_shown(share) -> np.ndarray:
    """Per-hole shares of photons that pass (0 to 1) to 4 decimals, a share that is not 0 kept
    above 0 (the face figures draw exactly 0 grey)."""
    share = np.asarray(share, dtype=np.float64)
    return np.where(share > 0, np.maximum(np.round(share, 4), 1e-4), 0.0)


# ---------------------------------------------------------------------------------------------
# Q2(a): photomultiplier tube


def plot_pmt_cascade(delta=4.0, n_dynodes=6, volts_per_stage=100.0, ax=None):
    """Q2(a): sketch of a photomultiplier tube with the mean electron count after each dynode.

    Light enters at the left and frees a photo-electron from the photocathode; the dynodes,
    staggered top and bottom and each ``volts_per_stage`` more positive than the one before,
    multiply the electrons by ``delta`` per stage; the anode at the right collects
    ``delta ** n`` electrons (:func:`course_lib.gamma_camera.pmt_cascade`).

    Returns
    -------
    dict
        ``{"envelope", "cathode", "dynodes": [Line2D, ...], "paths": [Line2D, ...],
        "counts": [Text, ...], "voltages": [Text, ...], "anode", "photon"}``.
    """
    if ax is None:
        import matplotlib.pyplot as plt
        _, ax = plt.subplots(figsize=(8.0, 3.6), layout="constrained")
    n = int(n_dynodes)
    counts = cascade_labels(delta, n)
    width = 2.0 + n
    envelope = FancyBboxPatch((-0.4, -1.6), width + 0.8, 3.2,
                              boxstyle="round,pad=0.1,rounding_size=0.6",
                              facecolor="#f4f8fc", edgecolor="k", linewidth=1.2)
    ax.add_patch(envelope)
    (cathode,) = ax.plot([0.0, 0.0], [-1.2, 1.2], color="#b8860b", linewidth=5,
                         solid_capstyle="butt")
    ax.text(0.0, -1.45, "photocathode\n0 V", ha="center", va="top", fontsize=8)
    photon = FancyArrowPatch((-1.6, 0.4), (-0.05, 0.4), arrowstyle="-|>", mutation_scale=12,
                             color="#9467bd", linewidth=1.5, linestyle=(0, (4, 2)))
    ax.add_patch(photon)
    ax.text(-1.6, 0.55, "light from\nthe crystal", fontsize=8, va="bottom")
    # dynode k at x = k + 0.5, alternately low and high
    dynodes, voltages, paths, labels = [], [], [], []
    prev = np.array([0.0, 0.4])
    for k in range(1, n + 1):
        x = k + 0.5
        y = -0.7 if k % 2 else 0.7
        tilt = 0.25 if k % 2 else -0.25
        (dyn,) = ax.plot([x - 0.3, x + 0.3], [y - tilt, y + tilt], color="#555555",
                         linewidth=5, solid_capstyle="round")
        dynodes.append(dyn)
        voltages.append(ax.text(x, y + (-0.45 if k % 2 else 0.45),
                                f"+{k * volts_per_stage:.0f} V", ha="center",
                                va="top" if k % 2 else "bottom", fontsize=7))
        here = np.array([x, y])
        (path,) = ax.plot([prev[0], here[0]], [prev[1], here[1]], color=COLOURS["curve"],
                          linewidth=0.8 + 2.2 * (k - 1) / max(n, 1))
        paths.append(path)
        mid = (prev + here) / 2
        labels.append(ax.text(mid[0], mid[1], counts[k - 1], fontsize=7, ha="center",
                              va="center", bbox={"boxstyle": "round,pad=0.15", "fc": "white",
                                                     "ec": "none", "alpha": 0.8}))
        prev = here
    xa = n + 1.6
    (anode,) = ax.plot([xa, xa], [-0.9, 0.9], color="#d62728", linewidth=5,
                       solid_capstyle="butt")
    (path,) = ax.plot([prev[0], xa], [prev[1], 0.0], color=COLOURS["curve"], linewidth=3.0)
    paths.append(path)
    labels.append(ax.text((prev[0] + xa) / 2, prev[1] / 2, counts[-1], fontsize=7,
                          ha="center", va="center",
                          bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none",
                                "alpha": 0.8}))
    ax.text(xa, -1.45, f"anode\n+{(n + 1) * volts_per_stage:.0f} V", ha="center", va="top",
            fontsize=8)
    ax.set_xlim(-1.8, width + 0.8)
    ax.set_ylim(-2.3, 1.9)
    ax.set_aspect("equal")
    ax.axis("off")
    ax.set_title(f"photomultiplier: gain δ^n = {delta:g}^{n} = {counts[-1]} "
                 "electrons per photo-electron", fontsize=9)
    return {"envelope": envelope, "cathode": cathode, "dynodes": dynodes, "paths": paths,
            "counts": labels, "voltages": voltages, "anode": anode, "photon": photon}


def _count(x):
    return f"{x:.0f}" if x < 1e4 else f"{x:.2g}"


def cascade_labels(delta, n_dynodes) -> list[str]:
    """Q2(a): the mean number of electrons after the photocathode and each dynode, ``delta**k``,
    as the tube figure writes them (whole numbers below 10 000, two significant figures above)."""
    counts = gc.pmt_cascade(delta, n_dynodes)
    return [_count(c) for c in counts]


# ---------------------------------------------------------------------------------------------
# Q2(c): similar triangles


def shown_resolution(d, L, z) -> tuple[float, str]:
    """Q2(c)'s resolution ``R = d (L + z) / L`` as the figures show it: ``(R to 4 significant
    figures, R as the side view's label writes it, "%.3g")``."""
    d, L, z = (as_scalar(v, name) for v, name in ((d, "d"), (L, "L"), (z, "z")))
    R = gc.collimator_resolution(d, L, z)
    return significant(R), f"{R:.3g}"


def plot_similar_triangles(d=1.0, L=200.0, z=200.0, ax=None, show_extreme=True):
    """Q2(c): side view of one hole and the patch of the source plane it sees.

    The vertical axis (distance, mm; the crystal below, the source plane above) is not to scale
    with the horizontal one, as in the solutions' sketch. From the point on the crystal behind
    the hole's centre, the two lines through the edges of the hole's mouth form a small triangle
    (height ``L``, base ``d``) and a large one (height ``L + z``, base ``R``): by similar
    triangles ``R = d (L + z) / L``. With ``show_extreme`` the dashed lines are the extreme rays
    that cross the hole from edge to opposite edge: they bound the widest patch,
    ``d (L + 2 z) / L``, from which any photon at all can reach the crystal through the hole.

    Returns
    -------
    dict
        ``{"septa": [Rectangle, Rectangle], "rays": [Line2D, Line2D], "extreme": [...],
        "bracket": Line2D, "labels": [Text, ...]}``.
    """
    ax = _ax(ax)
    R, R_text = shown_resolution(d, L, z)
    w = 1.2 * d
    septa = [Rectangle((-d / 2 - w, -L), w, L, facecolor=SEPTUM, edgecolor="k", hatch="//"),
             Rectangle((d / 2, -L), w, L, facecolor=SEPTUM, edgecolor="k", hatch="//")]
    for p in septa:
        ax.add_patch(p)
    half = R / 2
    rays = [ax.plot([0.0, s * half], [-L, z], color=COLOURS["highlight"], linewidth=1.5)[0]
            for s in (1, -1)]
    extreme = []
    far = significant(d / 2 + d * z / L)   # where the extreme rays cross the source plane
    if show_extreme:
        extreme = [ax.plot([-s * d / 2, s * far], [-L, z], color=COLOURS["control"],
                           linestyle="--", linewidth=1.0)[0] for s in (1, -1)]
    (bracket,) = ax.plot([-half, half], [z, z], color=COLOURS["curve"], linewidth=3)
    ax.axhline(-L, color="#444444", linewidth=4)
    ax.axhline(0.0, color="#444444", linewidth=0.6, linestyle=":")
    labels = [
        ax.text(0, z * 1.03 + 0.02 * L, f"R = d(L+z)/L = {R_text} mm", ha="center", va="bottom",
                color=COLOURS["curve"]),
        ax.text(-d / 2 - w / 2, -L / 2, f"L = {L:g} mm", ha="center", va="center", fontsize=9,
                rotation=90, bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": "none"}),
        ax.text(0, 0.02 * (L + z), f"d = {d:g} mm", ha="center", va="bottom", fontsize=9),
        ax.text(0, z / 2, f"z = {z:g} mm", ha="center", va="center", fontsize=9,
                bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.8}),
        ax.text(0, -L, "crystal", ha="center", va="top", fontsize=9),
    ]
    span = max(half, d / 2 + w) * (1.6 if not show_extreme else 1.1 * far / max(half, 1e-12))
    ax.set_xlim(-span, span)
    ax.set_ylim(-1.12 * L, 1.15 * z + 0.1 * L)
    ax.set_xlabel("lateral position (mm)")
    ax.set_ylabel("distance from the collimator face (mm)")
    ax.set_title("Q2(c): similar triangles (not to scale)")
    return {"septa": septa, "rays": rays, "extreme": extreme, "bracket": bracket,
            "labels": labels}


# ---------------------------------------------------------------------------------------------
# Q2(d): the rings of holes


def hole_verdicts(holes_xy, d, L, source_distance) -> dict:
    """What Q2(d)'s face figures colour each hole by, at display precision.

    ``{"exam": the exam's 0/1 verdict r L / z <= d per hole, "exact": the share of the hole's
    photons that pass (:func:`shares_shown`), "cutoffs": (d z / L, d z / L + d / 2) to 4
    significant figures, "labels": the same as the legend writes them ("%.3g"),
    "equivalents": the exact shares' sum as the title writes it ("%.2f")}``.
    """
    holes = np.asarray(holes_xy, dtype=np.float64)
    r = np.hypot(holes[:, 0], holes[:, 1])
    exact, exam = gc.transmission_profile(r, d, L, source_distance)
    cut_exam = gc.exam_cutoff_radius(d, L, source_distance)
    cut_exact = gc.exact_cutoff_radius(d, L, source_distance)
    return {"exam": exam, "exact": shares_shown(exact),
            "cutoffs": (significant(cut_exam), significant(cut_exact)),
            "labels": (f"{cut_exam:.3g}", f"{cut_exact:.3g}"),
            "equivalents": f"{exact.sum():.2f}"}


def plot_hole_rings(holes_xy, d, L, source_distance, collimator_radius, colour_by="open",
                    ax=None, draw_radius=None, colorbar=True):
    """Q2(d): the collimator face with its holes, coloured open/shut or by exact transmission.

    ``colour_by="open"`` uses the exam's all-or-nothing verdict (:func:`open_fraction`'s rule
    ``r L / z <= d``, array values 1/0); ``"transmission"`` the exact share of the radiation
    falling on each hole that leaves its back (:func:`transmission_profile`, 0 to 1). Real holes
    are tiny on this scale, so they are drawn with radius ``draw_radius`` (default: 35 % of the
    closest spacing between holes). Dashed circle: the exam's cut-off ``d z / L``; dotted: the
    exact one ``d z / L + d / 2``.

    Returns
    -------
    dict
        ``{"holes": PatchCollection (its array holds the colour values), "face": Circle,
        "cutoffs": [Circle, Circle], "colorbar": Colorbar or None}``.
    """
    if colour_by not in ("open", "transmission"):
        raise ValueError(f"colour_by must be 'open' or 'transmission', got {colour_by!r}")
    ax = _ax(ax)
    holes = np.asarray(holes_xy, dtype=float)
    shown = hole_verdicts(holes, d, L, source_distance)
    exact, exam = shown["exact"], shown["exam"]
    if draw_radius is None:
        if len(holes) > 1:
            diff = holes[:, None, :] - holes[None, :, :]
            dist = np.hypot(diff[..., 0], diff[..., 1])
            np.fill_diagonal(dist, np.inf)
            draw_radius = max(0.35 * dist.min(), d / 2)
        else:
            draw_radius = d / 2
    coll = PatchCollection([Circle(tuple(c), draw_radius) for c in holes], edgecolor="k",
                           linewidth=0.4)
    if colour_by == "open":
        from matplotlib.colors import ListedColormap
        coll.set_cmap(ListedColormap([SHUT, OPEN]))
        coll.set_array(exam)
        coll.set_clim(0.0, 1.0)
    else:
        import matplotlib as mpl
        cmap = mpl.colormaps["viridis"].with_extremes(under=SHUT)
        coll.set_cmap(cmap)
        coll.set_array(exact)
        coll.set_clim(1e-12, 1.0)     # holes that pass nothing are drawn grey
    face = Circle((0, 0), collimator_radius, facecolor=SEPTUM, alpha=0.35, edgecolor="k")
    ax.add_patch(face)
    ax.add_collection(coll)
    (rc_exam, rc_exact), (text_exam, text_exact) = shown["cutoffs"], shown["labels"]
    cutoffs = [Circle((0, 0), rc_exam, fill=False, linestyle="--", edgecolor=COLOURS["highlight"],
                      label=f"exam cut-off d z / L = {text_exam} mm"),
               Circle((0, 0), rc_exact, fill=False, linestyle=":", edgecolor="k",
                      label=f"exact cut-off + d/2 = {text_exact} mm")]
    for c in cutoffs:
        ax.add_patch(c)
    lim = 1.08 * collimator_radius
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.legend(handles=cutoffs, loc="lower left", fontsize=7, framealpha=0.9)
    scale = draw_radius / (d / 2)
    if colour_by == "open":
        ax.set_title(f"exam model: {int(exam.sum())} of {len(holes)} holes open "
                     f"(holes drawn ×{scale:.2g})", fontsize=9)
    else:
        ax.set_title(f"exact: {shown['equivalents']} hole-equivalents pass "
                     f"(holes drawn ×{scale:.2g})", fontsize=9)
    cb = None
    if colorbar:
        cb = ax.figure.colorbar(coll, ax=ax, shrink=0.8,
                                label="open (1) / shut (0)" if colour_by == "open"
                                else "share of the hole's photons that pass")
    return {"holes": coll, "face": face, "cutoffs": cutoffs, "colorbar": cb}


def plot_hole_lens(r, d, L, source_distance, ax=None, points=None):
    """One hole seen from the source: entrance disc, projected exit disc and their lens.

    The rays that pass the hole at radius ``r`` are exactly those through the lens where the
    entrance disc (radius ``d/2`` at ``r``) overlaps the exit disc projected from the source
    onto the entrance plane (radius ``s d/2`` at ``s r``, ``s = z / (z + L)``). Optional
    ``points``: Monte Carlo entrance points ``(n, 2)`` of photons that passed, drawn as dots.

    Returns
    -------
    dict
        ``{"entrance": Circle, "exit": Circle, "lens": Circle (the exit disc clipped to the
        entrance), "points": Line2D or None, "title": Text}``.
    """
    ax = _ax(ax, size=4.0)
    a = d / 2
    z = source_distance
    s = z / (z + L)
    ent = Circle((r, 0), a, fill=False, edgecolor="k", linewidth=1.5, label="entrance")
    ext = Circle((s * r, 0), s * a, facecolor=COLOURS["reference"], alpha=0.15,
                 edgecolor=COLOURS["reference"], linewidth=1.5,
                 label="exit, projected from the source")
    lens = Circle((s * r, 0), s * a, facecolor=COLOURS["reference"], alpha=0.45,
                  edgecolor="none", label="lens: rays that pass")
    ent.set_zorder(3)
    ax.add_patch(ent)
    ax.add_patch(ext)
    ax.add_patch(lens)
    lens.set_clip_path(ent)     # after ``ent`` joined the axes, so that its transform is set
    pts = None
    if points is not None and len(points):
        (pts,) = ax.plot(points[:, 0], points[:, 1], ".", markersize=2,
                         color=COLOURS["highlight"], label="Monte Carlo photons that pass")
    frac = gc.hole_pass_area(r, d, L, z) / (np.pi * a**2)
    title = ax.set_title(f"hole at r = {r:g} mm: {100 * frac:.1f} % of its mouth passes",
                         fontsize=9)
    ax.set_xlim(r - 1.4 * a, r + 1.4 * a)
    ax.set_ylim(-1.4 * a, 1.4 * a)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x on the entrance plane (mm)")
    ax.legend(loc="upper left", fontsize=6, framealpha=0.9)
    return {"entrance": ent, "exit": ext, "lens": lens, "points": pts, "title": title}


def profile_curves(d, L, source_distance, r_max=None) -> dict:
    """The transmission-profile figure's data at display precision: ``{"r": 600 radii from 0 to
    r_max (default 1.4 (d z / L + d / 2)), "exact": lens area / hole area at each,
    "exam": the exam's 0/1 verdict, "cutoffs": (d z / L, d z / L + d / 2)}``, radii and cut-offs
    to 1e-4 of ``r_max``, shares to 1e-4."""
    cut_exam = gc.exam_cutoff_radius(d, L, source_distance)
    cut_exact = gc.exact_cutoff_radius(d, L, source_distance)
    r_max = 1.4 * cut_exact if r_max is None else as_scalar(r_max, "r_max")
    r = np.linspace(0.0, r_max, 600)
    exact, exam = gc.transmission_profile(r, d, L, source_distance)
    return {"r": display_rounded(r, r_max), "exact": np.round(exact, 4), "exam": exam,
            "cutoffs": tuple(display_rounded([cut_exam, cut_exact], r_max).tolist())}


def plot_transmission_profile(d, L, source_distance, ax=None, r_max=None):
    """Per-hole transmission against the hole's radius: exact curve vs the exam's step.

    Returns
    -------
    dict
        ``{"exact": Line2D, "exam": Line2D, "cutoffs": [Line2D, Line2D]}``.
    """
    ax = _ax(ax)
    shown = profile_curves(d, L, source_distance, r_max)
    r, exact, exam = shown["r"], shown["exact"], shown["exam"]
    (le,) = ax.plot(r, exact, color=COLOURS["curve"], label="exact (lens area / hole area)")
    (lx,) = ax.plot(r, exam, color=COLOURS["highlight"], drawstyle="steps-post", linestyle="-.",
                    label="exam: all or nothing")
    cut = [ax.axvline(shown["cutoffs"][0], color=COLOURS["highlight"], linestyle="--",
                      linewidth=0.8),
           ax.axvline(shown["cutoffs"][1], color="k", linestyle=":", linewidth=0.8)]
    ax.set_xlabel("radius of the hole's centre r (mm)")
    ax.set_ylabel("share of the photons reaching the hole that pass")
    ax.set_ylim(-0.03, 1.08)
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    return {"exact": le, "exam": lx, "cutoffs": cut}


def model_curves(holes_xy, d, L, source_distances, collimator_radius) -> tuple:
    """The model-comparison figure's curves, ``(exam, uniform, isotropic)`` in percent of the
    photons hitting the face (see ``gamma_camera.compare_models``), each rounded to 1e-4 of the
    largest value drawn."""
    exam, uni, iso = gc.compare_models(holes_xy, d, L, source_distances, collimator_radius)
    curves = 100.0 * np.stack([exam, uni, iso])
    top = float(np.max(np.abs(curves))) if curves.size else 0.0
    return tuple(display_rounded(c, top) for c in curves)


def plot_model_comparison(holes_xy, d, L, source_distances, collimator_radius, ax=None):
    """Fraction reaching the back against source distance: the exam's model and the exact ones.

    Returns
    -------
    dict
        ``{"exam": Line2D, "uniform": Line2D, "isotropic": Line2D}``.
    """
    ax = _ax(ax)
    zs = np.asarray(source_distances, dtype=float)
    exam, uni, iso = model_curves(holes_xy, d, L, zs, collimator_radius)
    (lx,) = ax.plot(zs, exam, color=COLOURS["highlight"], drawstyle="steps-post", linestyle="-.",
                    label="exam: all or nothing")
    (lu,) = ax.plot(zs, uni, color=COLOURS["curve"], label="exact, uniform over the face")
    (li,) = ax.plot(zs, iso, color=COLOURS["reference"], linestyle="--",
                    label="exact, isotropic point source")
    ax.set_xlabel("source distance z (mm)")
    ax.set_ylabel("photons reaching the back (% of those hitting the face)")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    return {"exam": lx, "uniform": lu, "isotropic": li}
