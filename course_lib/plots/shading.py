"""Figures for Q5: the reflection vectors, shaded spheres, spectra and colour aliasing.

Every function takes an optional ``ax`` (or ``axes``) and returns the artists it drew, so the
Phong explorer can update them in place.
"""

from __future__ import annotations

import numpy as np
from matplotlib.patches import Arc

from .. import shading, spectral
from ..plotting import COLOURS, new_figure
from .describe import num, set_summary

__all__ = [
    "ALIASING_CASES",
    "plot_aliasing_convergence",
    "plot_aliasing_swatches",
    "plot_reflection_vectors",
    "plot_spectra",
    "drawn_vectors",
    "plot_spectral_spheres",
    "sphere_pair",
    "update_sphere_pair",
]

_VEC_COLOURS = {"L": "#ff7f0e", "N": "#2ca02c", "R": "#d62728", "V": "#1f77b4", "H": "#9467bd"}


def _arrow(ax, v, colour, label, lw=2.0, ls="-", offset=0.08):
    art = ax.annotate("", xy=(v[0], v[1]), xytext=(0, 0),
                      arrowprops={"arrowstyle": "-|>", "color": colour, "lw": lw,
                                  "linestyle": ls, "shrinkA": 0, "shrinkB": 0})
    u = np.asarray(v[:2]) / max(np.linalg.norm(v[:2]), 1e-9)
    txt = ax.text(v[0] + offset * u[0], v[1] + offset * u[1], label, color=colour,
                  ha="center", va="center", fontsize=12, fontweight="bold")
    return art, txt


def plot_reflection_vectors(incidence_deg: float = 40.0, view_deg: float = -15.0, ax=None,
                            construction: bool = True):
    """The L, N, R, V, H diagram of Q5(a) in the plane of incidence.

    Parameters
    ----------
    incidence_deg : float
        Angle of ``L`` from the normal, measured towards the left.
    view_deg : float
        Angle of ``V`` from the normal, measured towards the left (negative: to the right).
    construction : bool
        Also draw the derivation of ``R``: ``(L.N) N``, ``S = (L.N) N - L`` added twice.

    Returns
    -------
    dict of artists (``"L"``, ``"N"``, ``"R"``, ``"V"``, ``"H"``, ...).

    Notes
    -----
    Q5(a): ``R = (L.N) N + S`` with ``S = (L.N) N - L``, so ``R = 2 (L.N) N - L``; the angle of
    reflection equals the angle of incidence, and ``H`` bisects ``L`` and ``V``.
    """
    if ax is None:
        _, ax = new_figure(size=4.5)
    drawn = drawn_vectors(incidence_deg, view_deg)
    L, N, R, V, H = (drawn[k] for k in "LNRVH")
    art = {"surface": ax.plot([-1.2, 1.2], [0, 0], color="k", lw=2)[0]}
    ax.fill_between([-1.2, 1.2], [0, 0], [-0.15, -0.15], color="0.85", zorder=0)
    for name, v in (("N", N), ("L", L), ("R", R), ("V", V), ("H", H)):
        art[name] = _arrow(ax, v, _VEC_COLOURS[name], name, ls="--" if name == "H" else "-")
    if construction:
        P = (L @ N) * N
        S = P - L
        art["projection"] = ax.plot([L[0], P[0]], [L[1], P[1]], ":", color="0.4")[0]
        art["S"] = ax.annotate("", xy=(R[0], R[1]), xytext=(P[0], P[1]),
                               arrowprops={"arrowstyle": "-|>", "color": "0.4", "lw": 1.2})
        ax.text(*(P[:2] + 0.5 * S[:2] + [0.0, 0.06]), "S", color="0.3", ha="center")
        ax.text(P[0] - 0.03, P[1] - 0.08, "(L·N)N", color="0.3", fontsize=9, ha="right")
    for v0, v1, r in ((N, L, 0.35), (N, R, 0.42)):
        a0, a1 = np.degrees(np.arctan2(v0[1], v0[0])), np.degrees(np.arctan2(v1[1], v1[0]))
        lo, hi = min(a0, a1), max(a0, a1)
        ax.add_patch(Arc((0, 0), 2 * r, 2 * r, theta1=lo, theta2=hi, color="0.3"))
    ax.text(-0.2, 0.45, "θ", fontsize=11)
    ax.text(0.22, 0.5, "θ", fontsize=11)
    ax.set_aspect("equal", adjustable="box")
    ax.set_title("Phong vectors: R = 2(L·N)N − L")
    set_summary(ax, _vectors_summary({"L": L, "R": R, "V": V, "H": H}))
    ax.set_xlim(-1.3, 1.3)
    ax.set_ylim(-0.2, 1.3)
    ax.set_axis_off()
    return art


def drawn_vectors(incidence_deg: float, view_deg: float) -> dict:
    """The arrows of :func:`plot_reflection_vectors` as drawn: ``{"L", "N", "R", "V", "H"}``,
    unit vectors in the plane of incidence (``N`` straight up), rounded to 1e-4 (display
    precision: the axes span 2.6).

    Notes
    -----
    Q5(a) and Q5(c): ``R = 2 (L.N) N - L`` and ``H = (L + V) / |L + V|``.
    """
    t, p = np.radians(incidence_deg), np.radians(view_deg)
    N = np.array([0.0, 1.0, 0.0])
    L = np.array([-np.sin(t), np.cos(t), 0.0])
    V = np.array([-np.sin(p), np.cos(p), 0.0])
    R = shading.reflect(L, N)
    H = shading.halfway(L, V)
    return {"L": np.round(L, 4), "N": N, "R": np.round(R, 4), "V": np.round(V, 4),
            "H": np.round(H, 4)}


_VEC_MEANING = {"L": "towards the light", "R": "the mirror reflection of L",
                "V": "towards the viewer", "H": "halfway between L and V"}


def _vectors_summary(vectors) -> str:
    """Q5(a)'s arrows in words: each one's angle from the normal N (which points straight up
    from the horizontal surface), to the left or the right."""
    said = []
    for name, v in vectors.items():
        angle = float(np.degrees(np.arctan2(-v[0], v[1])))    # positive: towards the left
        side = "along N" if abs(angle) < 0.05 else \
            f"{num(abs(angle))} degrees {'left' if angle > 0 else 'right'} of N"
        said.append(f"{name} ({_VEC_MEANING[name]}) {side}")
    return ("A horizontal surface with its normal N pointing straight up; arrows from the "
            "point of incidence: " + "; ".join(said) + ".")


def sphere_pair(colour, Ia, ka, Ip, kd, ks, n, L, V, size: int = 128, axes=None,
                up=(0.0, 0.0, 1.0)):
    """Phong and Blinn-Phong renderings of the unit sphere side by side, highlights marked.

    The rendered argmax of the specular term is a ring, the analytic position (the projection
    of ``H``, :func:`course_lib.shading.highlight_pixel`) a cross: they coincide, because both
    models peak where ``N = H`` (Q5(c)).

    Returns
    -------
    dict with ``"images"`` (two AxesImage), ``"peaks"`` (two Line2D rings), ``"analytic"``
    (two Line2D crosses), ``"titles"`` and ``"axes"``.
    """
    if axes is None:
        _, axes = new_figure(2, size=3.6)
    axes = list(np.ravel(axes))
    art = {"images": [], "peaks": [], "analytic": [], "titles": [], "axes": list(axes)}
    for ax, name in zip(axes, ("Phong  (R·V)ⁿ", "Blinn-Phong  (N·H)ⁿ")):
        im = ax.imshow(np.zeros((size, size, 3)), interpolation="nearest",
                       extent=(-0.5, size - 0.5, size - 0.5, -0.5))
        peak, = ax.plot([], [], "o", mfc="none", mec=COLOURS["highlight"], ms=12, mew=1.8,
                        label="rendered peak")
        cross, = ax.plot([], [], "+", color="#00bcd4", ms=14, mew=1.8,
                         label="analytic: N = H")
        art["images"].append(im)
        art["peaks"].append(peak)
        art["analytic"].append(cross)
        art["titles"].append(ax.set_title(name))
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_xlim(-0.5, size - 0.5)
        ax.set_ylim(size - 0.5, -0.5)
    axes[1].legend(loc="lower right", fontsize=7, framealpha=0.7)
    update_sphere_pair(art, colour, Ia, ka, Ip, kd, ks, n, L, V, size, up)
    return art


def update_sphere_pair(art, colour, Ia, ka, Ip, kd, ks, n, L, V, size: int = 128,
                       up=(0.0, 0.0, 1.0)):
    """Re-render both spheres into the artists of :func:`sphere_pair` (``set_data``).

    Returns the two highlight pixels ``(row, col)`` (or ``None``) as rendered. The images are
    8-bit RGB (the intensities clipped to [0, 1], then ``int(255 x)``, the bytes matplotlib
    would draw from the float image) and the analytic crosses are placed to 0.01 pixel:
    nothing here keeps an intensity or a direction at more than display precision.
    """
    peaks = []
    analytic = None
    try:
        analytic = np.round(shading.highlight_pixel(L, V, size, up), 2)
    except ValueError:  # L = -V: no half-way vector, no highlight
        pass
    for k, model in enumerate(("Phong", "Blinn-Phong")):
        try:
            img, peak = shading.render_sphere(colour, Ia, ka, Ip, kd, ks, n, L, V, size,
                                              model=model, up=up)
        except ValueError:
            img, peak = np.zeros((size, size, 3)), None
        art["images"][k].set_data((np.clip(img, 0.0, 1.0) * 255).astype(np.uint8))
        if peak is None:
            art["peaks"][k].set_data([], [])
        else:
            art["peaks"][k].set_data([peak[1]], [peak[0]])
        if analytic is None or peak is None:
            art["analytic"][k].set_data([], [])
        else:
            art["analytic"][k].set_data([analytic[1]], [analytic[0]])
        peaks.append(peak)
    return peaks


def plot_spectra(light, reflectance, n: int = 9, ax=None, method: str = "point",
                 show_cmfs: bool = True):
    """The light's spectrum, the reflectance, their product and the ``n`` samples of Q5(d).

    Each curve is scaled to a peak of 1 for display; the colour-matching functions are drawn
    faintly behind. Point samples are dots on the light and reflectance curves; with
    ``method="box"`` the band averages are drawn as dotted steps.

    Returns
    -------
    dict of artists: ``"light"``, ``"reflectance"``, ``"product"``, ``"samples"``, ``"cmfs"``.
    """
    if ax is None:
        _, ax = new_figure(size=4.5)
        ax.figure.set_size_inches(7.0, 3.6)
    wl = np.linspace(spectral.LAMBDA_MIN, spectral.LAMBDA_MAX, 4001)
    E, rho = light(wl), reflectance(wl)
    prod = E * rho
    art = {"cmfs": []}
    if show_cmfs:
        c = spectral.cmfs(wl)
        for j, col in enumerate(("#e57373", "#81c784", "#64b5f6")):
            art["cmfs"].append(ax.fill_between(wl, 0, c[:, j] / c.max(), color=col,
                                               alpha=0.15, lw=0))
    art["light"] = ax.plot(wl, E / E.max(), color="#ff9800", lw=1.2, label="light E(λ)")[0]
    art["reflectance"] = ax.plot(wl, rho, color="#555555", lw=1.5,
                                 label="reflectance ρ(λ)")[0]
    art["product"] = ax.plot(wl, prod / max(prod.max(), 1e-12), color="k", lw=1.0, ls="--",
                             label="reflected E·ρ (scaled)")[0]
    ws = spectral.sample_wavelengths(n)
    if method == "box":
        edges = spectral.band_edges(ws)
        pv = spectral.band_averages(prod, wl, edges)
    else:
        pv = light(ws) * reflectance(ws)
    art["samples"] = ax.vlines(ws, 0, pv / max(prod.max(), 1e-12), color=COLOURS["highlight"],
                               lw=2.5, label=f"E·ρ at the {n} samples ({method})")
    if method == "point":
        art["light_samples"] = ax.plot(ws, light(ws) / E.max(), "o", color="#ff9800", ms=5)[0]
        art["reflectance_samples"] = ax.plot(ws, reflectance(ws), "o", color="#555555",
                                             ms=5)[0]
    else:
        art["light_samples"] = ax.stairs(spectral.band_averages(E, wl, edges) / E.max(), edges,
                                         color="#ff9800", lw=1.0, ls=":")
        art["reflectance_samples"] = ax.stairs(spectral.band_averages(rho, wl, edges), edges,
                                               color="#555555", lw=1.0, ls=":")
    ax.set_xlim(spectral.LAMBDA_MIN, spectral.LAMBDA_MAX)
    ax.set_ylim(0, 1.08)
    ax.set_xlabel("wavelength λ (nm)")
    ax.set_ylabel("relative value")
    ax.legend(fontsize=8, loc="upper right")
    return art


def _narrow_red(w):
    return spectral.gaussian_band(w, 610.0, 30.0, 0.9, 0.05)


def _narrow_green(w):
    return spectral.gaussian_band(w, 525.0, 25.0, 0.9, 0.05)


def _broad_blue(w):
    return spectral.gaussian_band(w, 460.0, 100.0, 0.85, 0.05)


def _tungsten(w):
    return spectral.blackbody(w, 2856.0)


def _daylight(w):
    return spectral.blackbody(w, 6500.0)


#: ``(label, light, reflectance)`` triples for the swatch figure: smooth lights and
#: reflectances, where few samples do, and the spiky fluorescent lamp with narrow reflectances,
#: where they do not.
ALIASING_CASES = (
    ("blue paint, daylight", _daylight, _broad_blue),
    ("blue paint, tungsten", _tungsten, _broad_blue),
    ("red dye, tungsten", _tungsten, _narrow_red),
    ("red dye, fluorescent", spectral.triband_fluorescent, _narrow_red),
    ("green dye, fluorescent", spectral.triband_fluorescent, _narrow_green),
)


def plot_aliasing_swatches(cases=ALIASING_CASES, ns=(9, 16, 81), method: str = "point",
                           ax=None):
    """Swatches of one surface colour per treatment: 3 RGB samples, ``n`` samples, converged.

    Each row is a light and a surface; each swatch is labelled with its CIE 1976 colour
    difference from the converged colour (about 2.3 is just noticeable).

    Returns
    -------
    dict with ``"image"`` (the AxesImage of the swatches), ``"labels"`` (Text per swatch) and
    ``"errors"`` (array ``(len(cases), len(ns) + 2)`` of Delta E).
    """
    if ax is None:
        _, ax = new_figure(size=4.0)
        ax.figure.set_size_inches(1.5 * (len(ns) + 2) + 2.0, 0.9 * len(cases) + 1.0)
    rows, errors = [], []
    for _, light, refl in cases:
        rgb, err = spectral.colour_aliasing(light, refl, ns, method)
        rows.append(spectral.linear_srgb_to_srgb(rgb))
        errors.append(err)
    swatch = np.array(rows)
    image = ax.imshow(swatch, aspect="auto", interpolation="nearest")
    labels = []
    for i, err in enumerate(errors):
        for j, e in enumerate(err):
            lum = swatch[i, j] @ [0.2126, 0.7152, 0.0722]
            text = "reference" if j == len(err) - 1 else f"ΔE {e:.1f}"
            labels.append(ax.text(j, i, text, ha="center", va="center", fontsize=9,
                                  color="k" if lum > 0.5 else "w"))
    ax.set_xticks(range(len(ns) + 2), ["3 (RGB)"] + [f"n = {k}" for k in ns] + ["converged"])
    ax.set_yticks(range(len(cases)), [c[0] for c in cases])
    ax.tick_params(length=0)
    ax.set_title(f"Colour aliasing ({method} sampling)")
    return {"image": image, "labels": labels, "errors": np.array(errors)}


def plot_aliasing_convergence(cases=ALIASING_CASES, ns=None, ax=None):
    """Delta E against the number of wavelength samples, point (solid) and box (dashed)
    sampling, one colour per case; the three-sample RGB error as a marker at n = 3.

    Returns
    -------
    dict with ``"lines"`` (Line2D per case and method) and ``"rgb"`` (markers).
    """
    if ns is None:
        ns = (5, 7, 9, 12, 16, 24, 32, 48, 64, 81, 120, 160)
    if ax is None:
        _, ax = new_figure(size=4.5)
        ax.figure.set_size_inches(7.0, 4.0)
    art = {"lines": [], "rgb": []}
    for k, (label, light, refl) in enumerate(cases):
        colour = f"C{k}"
        for method, ls in (("point", "-"), ("box", "--")):
            _, err = spectral.colour_aliasing(light, refl, ns, method)
            art["lines"].append(ax.plot(ns, np.maximum(err[1:-1], 1e-3), ls, color=colour,
                                        label=label if method == "point" else None)[0])
        art["rgb"].append(ax.plot([3], [max(err[0], 1e-3)], "s", color=colour)[0])
    ax.axhline(2.3, color="0.5", lw=0.8)
    ax.text(ns[-1], 2.5, "just noticeable", ha="right", va="bottom", fontsize=8, color="0.4")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wavelength samples n (squares: 3 RGB samples)")
    ax.set_ylabel("ΔE*ab from converged")
    ax.set_title("Error against n: point (solid) and box-filtered (dashed)")
    ax.legend(fontsize=7)
    return art


def plot_spectral_spheres(axes=None):
    """A green-dyed sphere under the tri-phosphor fluorescent lamp by the three-sample RGB
    model, by 9 and 16 wavelength samples, and converged (Q5(d), going further).

    The four images are those :func:`course_lib.spectral_render.render_sphere_spectral` makes from
    :data:`course_lib.spectral.SPECTRAL_SPHERES` (``Ia = Ip = 1``), as the 8-bit sRGB pixels
    drawn; they are computed when the course library is built
    (:mod:`course_lib._spectral_spheres_data`), so the figure costs no spectral integration.

    Returns
    -------
    dict with ``"images"`` (AxesImage per panel) and ``"axes"``.
    """
    from .._spectral_spheres_data import load

    images = load()["images"]
    if axes is None:
        _, axes = new_figure(len(images), size=2.8)
    axes = list(np.ravel(axes))
    ns = spectral.SPECTRAL_SPHERES["ns"]
    names = ["3 samples (RGB)"] + [f"{k} wavelengths" for k in ns] + ["converged"]
    art = {"images": [], "axes": axes}
    for ax, img, name in zip(axes, images, names):
        art["images"].append(ax.imshow(img, interpolation="nearest"))
        ax.set_title(name, fontsize=10)
        ax.set_xticks([])
        ax.set_yticks([])
    return art
