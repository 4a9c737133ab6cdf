"""Q5(d): spectral Phong shading and colour aliasing.

The Phong model of Q5 treats colour as three numbers, the red, green and blue intensities of the
light and the surface's reflectance in those three primaries. Light and reflectance are really
continuous spectra, and the colour we see is the *product* of the two, projected on the eye's
three colour-matching functions. Projecting each spectrum on RGB first and multiplying the three
numbers afterwards is a severe undersampling of the spectra: the result can be the wrong colour
(*colour aliasing*), most visibly under spiky lights (fluorescent lines) and with narrow-band
reflectances. Sampling the spectra at ``n`` wavelengths, evaluating the model per wavelength and
reducing the result to RGB only at the end (Q5(d)) removes most of the error.

This module holds the CIE 1931 2-degree colour-matching functions (the published 5 nm table,
380-780 nm), XYZ to linear sRGB, CIELAB and the CIE 1976 colour difference, a few analytic
spectra and the comparison of the three treatments of colour (three RGB samples, ``n``
wavelength samples, the converged integral). The per-wavelength Phong model and the spectrally
shaded sphere are in :mod:`course_lib.spectral_render` (the instructors' copy only).

Conventions: wavelengths in nm; spectra are callables ``f(wavelengths) -> values`` or arrays
sampled at given wavelengths; XYZ are scaled so that the equal-energy spectrum ``S = 1`` has
``Y = 1`` (and a light is rescaled to ``Y = 1`` before it illuminates a surface).
"""

from __future__ import annotations

import numpy as np

from ._validate import as_float_array, as_int, as_positive, as_scalar

__all__ = [
    "CIE_1931_2DEG",
    "LAMBDA_MAX",
    "LAMBDA_MIN",
    "SPECTRAL_SPHERES",
    "XYZ_TO_LINEAR_SRGB",
    "XYZ_to_Lab",
    "XYZ_to_linear_srgb",
    "band_averages",
    "band_edges",
    "blackbody",
    "cmfs",
    "colour_aliasing",
    "delta_E",
    "equal_energy",
    "gaussian_band",
    "linear_srgb_to_XYZ",
    "linear_srgb_to_srgb",
    "reflected_XYZ",
    "reflected_colour",
    "rgb_model_colour",
    "sample_wavelengths",
    "spectrum_to_XYZ",
    "trapezoid_weights",
    "triband_fluorescent",
]

LAMBDA_MIN = 380.0
LAMBDA_MAX = 780.0

#: CIE 1931 2-degree standard observer, the published 5 nm table (ISO/CIE 11664-1), rows
#: ``[wavelength nm, xbar, ybar, zbar]`` from 380 to 780 nm.
CIE_1931_2DEG = np.array([
    [380, 0.001368, 0.000039, 0.006450],
    [385, 0.002236, 0.000064, 0.010550],
    [390, 0.004243, 0.000120, 0.020050],
    [395, 0.007650, 0.000217, 0.036210],
    [400, 0.014310, 0.000396, 0.067850],
    [405, 0.023190, 0.000640, 0.110200],
    [410, 0.043510, 0.001210, 0.207400],
    [415, 0.077630, 0.002180, 0.371300],
    [420, 0.134380, 0.004000, 0.645600],
    [425, 0.214770, 0.007300, 1.039050],
    [430, 0.283900, 0.011600, 1.385600],
    [435, 0.328500, 0.016840, 1.622960],
    [440, 0.348280, 0.023000, 1.747060],
    [445, 0.348060, 0.029800, 1.782600],
    [450, 0.336200, 0.038000, 1.772110],
    [455, 0.318700, 0.048000, 1.744100],
    [460, 0.290800, 0.060000, 1.669200],
    [465, 0.251100, 0.073900, 1.528100],
    [470, 0.195360, 0.090980, 1.287640],
    [475, 0.142100, 0.112600, 1.041900],
    [480, 0.095640, 0.139020, 0.812950],
    [485, 0.057950, 0.169300, 0.616200],
    [490, 0.032010, 0.208020, 0.465180],
    [495, 0.014700, 0.258600, 0.353300],
    [500, 0.004900, 0.323000, 0.272000],
    [505, 0.002400, 0.407300, 0.212300],
    [510, 0.009300, 0.503000, 0.158200],
    [515, 0.029100, 0.608200, 0.111700],
    [520, 0.063270, 0.710000, 0.078250],
    [525, 0.109600, 0.793200, 0.057250],
    [530, 0.165500, 0.862000, 0.042160],
    [535, 0.225750, 0.914850, 0.029840],
    [540, 0.290400, 0.954000, 0.020300],
    [545, 0.359700, 0.980300, 0.013400],
    [550, 0.433450, 0.994950, 0.008750],
    [555, 0.512050, 1.000000, 0.005750],
    [560, 0.594500, 0.995000, 0.003900],
    [565, 0.678400, 0.978600, 0.002750],
    [570, 0.762100, 0.952000, 0.002100],
    [575, 0.842500, 0.915400, 0.001800],
    [580, 0.916300, 0.870000, 0.001650],
    [585, 0.978600, 0.816300, 0.001400],
    [590, 1.026300, 0.757000, 0.001100],
    [595, 1.056700, 0.694900, 0.001000],
    [600, 1.062200, 0.631000, 0.000800],
    [605, 1.045600, 0.566800, 0.000600],
    [610, 1.002600, 0.503000, 0.000340],
    [615, 0.938400, 0.441200, 0.000240],
    [620, 0.854450, 0.381000, 0.000190],
    [625, 0.751400, 0.321000, 0.000100],
    [630, 0.642400, 0.265000, 0.000050],
    [635, 0.541900, 0.217000, 0.000030],
    [640, 0.447900, 0.175000, 0.000020],
    [645, 0.360800, 0.138200, 0.000010],
    [650, 0.283500, 0.107000, 0.000000],
    [655, 0.218700, 0.081600, 0.000000],
    [660, 0.164900, 0.061000, 0.000000],
    [665, 0.121200, 0.044580, 0.000000],
    [670, 0.087400, 0.032000, 0.000000],
    [675, 0.063600, 0.023200, 0.000000],
    [680, 0.046770, 0.017000, 0.000000],
    [685, 0.032900, 0.011920, 0.000000],
    [690, 0.022700, 0.008210, 0.000000],
    [695, 0.015840, 0.005723, 0.000000],
    [700, 0.011359, 0.004102, 0.000000],
    [705, 0.008111, 0.002929, 0.000000],
    [710, 0.005790, 0.002091, 0.000000],
    [715, 0.004109, 0.001484, 0.000000],
    [720, 0.002899, 0.001047, 0.000000],
    [725, 0.002049, 0.000740, 0.000000],
    [730, 0.001440, 0.000520, 0.000000],
    [735, 0.001000, 0.000361, 0.000000],
    [740, 0.000690, 0.000249, 0.000000],
    [745, 0.000476, 0.000172, 0.000000],
    [750, 0.000332, 0.000120, 0.000000],
    [755, 0.000235, 0.000085, 0.000000],
    [760, 0.000166, 0.000060, 0.000000],
    [765, 0.000117, 0.000042, 0.000000],
    [770, 0.000083, 0.000030, 0.000000],
    [775, 0.000059, 0.000021, 0.000000],
    [780, 0.000042, 0.000015, 0.000000],
])

#: XYZ (D65 white, Y = 1) to linear sRGB, IEC 61966-2-1:1999.
XYZ_TO_LINEAR_SRGB = np.array([
    [3.2406, -1.5372, -0.4986],
    [-0.9689, 1.8758, 0.0415],
    [0.0557, -0.2040, 1.0570],
])

#: The fixed inputs of the notebook's spectral spheres (Q5(d), going further;
#: :func:`course_lib.plots.shading.plot_spectral_spheres`): a green dye (a Gaussian band,
#: ``(centre, fwhm, peak, floor)`` of :func:`gaussian_band`) under :func:`triband_fluorescent`,
#: rendered by :func:`course_lib.spectral_render.render_sphere_spectral` with ``Ia = Ip = 1``
#: by the RGB model, by each ``ns`` wavelength samples (point sampling) and converged.
SPECTRAL_SPHERES = {"dye": (525.0, 25.0, 0.9, 0.05), "ka": 0.2, "kd": 0.7, "ks": 0.5,
                    "n": 30.0, "L": (1.0, -1.0, 1.0), "V": (0.0, -1.0, 0.2), "ns": (9, 16),
                    "size": 128}

#: Spacing of the dense grid used for the converged integrals (nm).
DENSE_STEP = 0.1


# --------------------------------------------------------------------------------------------
# colour-matching functions, sampling, XYZ


def cmfs(wavelengths) -> np.ndarray:
    """CIE 1931 2-degree colour-matching functions at the given wavelengths.

    Parameters
    ----------
    wavelengths : array_like, shape (...)
        In nm.

    Returns
    -------
    ndarray, shape (..., 3)
        ``(xbar, ybar, zbar)``: the published values at multiples of 5 nm, linear
        interpolation between them, 0 outside 380-780 nm.

    Notes
    -----
    Q5(d): the three numbers a spectrum is finally reduced to are its integrals against these
    three functions. They are smooth (no feature narrower than a few tens of nm), which is why a
    modest number of wavelength samples suffices for smooth spectra.
    """
    wl = as_float_array(wavelengths, "wavelengths")
    table = CIE_1931_2DEG
    out = np.stack([np.interp(wl, table[:, 0], table[:, j], left=0.0, right=0.0)
                    for j in (1, 2, 3)], axis=-1)
    return out


def sample_wavelengths(n: int, lo: float = LAMBDA_MIN, hi: float = LAMBDA_MAX) -> np.ndarray:
    """``n`` equally spaced wavelengths from ``lo`` to ``hi`` inclusive (nm).

    ``n = 81`` over 380-780 nm gives the CIE's 5 nm grid, ``n = 9`` a sample every 50 nm.
    """
    n = as_int(n, "n", minimum=2)
    lo, hi = as_scalar(lo, "lo"), as_scalar(hi, "hi")
    if not hi > lo:
        raise ValueError(f"hi must exceed lo, got lo={lo}, hi={hi}")
    return np.linspace(lo, hi, n)


def trapezoid_weights(wavelengths) -> np.ndarray:
    """Quadrature weights (nm) of the trapezoid rule on increasing sample wavelengths.

    Sample ``i`` stands for the band from the midpoint with its left neighbour to the midpoint
    with its right neighbour (half bands at the two ends); the weights sum to ``hi - lo``.
    """
    wl = as_float_array(wavelengths, "wavelengths")
    if wl.ndim != 1 or wl.size < 2:
        raise ValueError(f"wavelengths must be a 1-D array of at least 2, got shape {wl.shape}")
    if np.any(np.diff(wl) <= 0):
        raise ValueError("wavelengths must be strictly increasing")
    edges = band_edges(wl)
    return np.diff(edges)


def band_edges(wavelengths) -> np.ndarray:
    """Edges of the bands the samples stand for: ends and the midpoints between samples."""
    wl = as_float_array(wavelengths, "wavelengths")
    return np.concatenate([[wl[0]], 0.5 * (wl[1:] + wl[:-1]), [wl[-1]]])


#: ``integral of ybar`` over 380-780 nm (trapezoid on the 5 nm table, exact for the piecewise
#: linear interpolant), the factor that gives the equal-energy spectrum ``Y = 1``.
Y_INTEGRAL = float(np.sum(CIE_1931_2DEG[:, 2] * trapezoid_weights(CIE_1931_2DEG[:, 0])))


def spectrum_to_XYZ(spectrum, wavelengths, weights=None, cmf_values=None) -> np.ndarray:
    """Tristimulus values of spectra sampled at ``wavelengths``.

    .. math:: X = \\frac{1}{K}\\sum_i S(\\lambda_i)\\,\\bar x(\\lambda_i)\\,w_i,
              \\quad K = \\int \\bar y\\, d\\lambda

    (likewise ``Y``, ``Z``), so that ``S = 1`` has ``Y = 1``.

    Parameters
    ----------
    spectrum : array_like, shape (..., m)
        Spectral values at the ``m`` wavelengths (a batch of spectra along leading axes).
    wavelengths : array_like, shape (m,)
        Increasing, in nm.
    weights : array_like, shape (m,), optional
        Quadrature weights in nm; trapezoid weights by default.
    cmf_values : array_like, shape (m, 3), optional
        Colour-matching values to use instead of :func:`cmfs` at the samples (the band averages
        of box sampling).

    Returns
    -------
    ndarray, shape (..., 3)

    Notes
    -----
    Q5(d): the "post-processing stage" that reduces ``n`` wavelength samples to a colour.
    """
    wl = as_float_array(wavelengths, "wavelengths")
    s = as_float_array(spectrum, "spectrum")
    if s.ndim == 0 or s.shape[-1] != wl.size:
        raise ValueError(f"spectrum must have shape (..., {wl.size}) to match wavelengths, "
                         f"got shape {s.shape}")
    w = trapezoid_weights(wl) if weights is None else as_float_array(weights, "weights")
    c = cmfs(wl) if cmf_values is None else as_float_array(cmf_values, "cmf_values")
    if w.shape != wl.shape or c.shape != wl.shape + (3,):
        raise ValueError("weights must have shape (m,) and cmf_values shape (m, 3)")
    return (s * w) @ c / Y_INTEGRAL


def XYZ_to_linear_srgb(XYZ) -> np.ndarray:
    """Linear sRGB (D65 white, unclipped) of ``XYZ`` (``Y = 1`` is full intensity).

    Negative components mean the colour lies outside the sRGB gamut.
    """
    XYZ = as_float_array(XYZ, "XYZ")
    if XYZ.ndim == 0 or XYZ.shape[-1] != 3:
        raise ValueError(f"XYZ must have shape (..., 3), got shape {XYZ.shape}")
    return XYZ @ XYZ_TO_LINEAR_SRGB.T


def linear_srgb_to_XYZ(rgb) -> np.ndarray:
    """XYZ of linear sRGB values: the inverse of :func:`XYZ_to_linear_srgb`."""
    rgb = as_float_array(rgb, "rgb")
    if rgb.ndim == 0 or rgb.shape[-1] != 3:
        raise ValueError(f"rgb must have shape (..., 3), got shape {rgb.shape}")
    return rgb @ np.linalg.inv(XYZ_TO_LINEAR_SRGB).T


def linear_srgb_to_srgb(rgb) -> np.ndarray:
    """Encode linear sRGB for display: clip to [0, 1], then the sRGB transfer function."""
    rgb = np.clip(as_float_array(rgb, "rgb"), 0.0, 1.0)
    return np.where(rgb <= 0.0031308, 12.92 * rgb, 1.055 * rgb ** (1 / 2.4) - 0.055)


def XYZ_to_Lab(XYZ, white) -> np.ndarray:
    """CIE 1976 L*a*b* of ``XYZ`` relative to the reference ``white`` (same scale)."""
    XYZ = as_float_array(XYZ, "XYZ")
    white = as_float_array(white, "white")
    if XYZ.ndim == 0 or XYZ.shape[-1] != 3 or white.ndim == 0 or white.shape[-1] != 3:
        raise ValueError("XYZ and white must have shape (..., 3)")
    if np.any(white <= 0):
        raise ValueError("white must be positive")
    t = XYZ / white
    d = 6.0 / 29.0
    f = np.where(t > d ** 3, np.cbrt(t), t / (3 * d * d) + 4.0 / 29.0)
    L = 116.0 * f[..., 1] - 16.0
    a = 500.0 * (f[..., 0] - f[..., 1])
    b = 200.0 * (f[..., 1] - f[..., 2])
    return np.stack([L, a, b], axis=-1)


def delta_E(Lab1, Lab2) -> np.ndarray:
    """CIE 1976 colour difference: the Euclidean distance in L*a*b* (about 2.3 is just
    noticeable)."""
    d = as_float_array(Lab1, "Lab1") - as_float_array(Lab2, "Lab2")
    return np.sqrt(np.sum(d * d, axis=-1))


# --------------------------------------------------------------------------------------------
# spectra (callables of wavelength in nm)


def equal_energy(wavelengths) -> np.ndarray:
    """The equal-energy spectrum (CIE illuminant E): 1 at every wavelength."""
    return np.ones_like(as_float_array(wavelengths, "wavelengths"))


def gaussian_band(wavelengths, centre: float, fwhm: float, peak: float = 1.0,
                  floor: float = 0.0) -> np.ndarray:
    """``floor + (peak - floor) exp(-4 ln2 (lambda - centre)^2 / fwhm^2)``: a band of full width
    ``fwhm`` at half maximum. A narrow band models a saturated paint or a spectral line."""
    wl = as_float_array(wavelengths, "wavelengths")
    fwhm = float(as_positive(as_scalar(fwhm, "fwhm"), "fwhm"))
    return floor + (peak - floor) * np.exp(-4.0 * np.log(2.0) * ((wl - centre) / fwhm) ** 2)


def blackbody(wavelengths, temperature: float = 6500.0) -> np.ndarray:
    """Planck's law for a black body at ``temperature`` kelvin, scaled to 1 at 560 nm
    (incandescent light near 2850 K, daylight-like near 6500 K)."""
    wl = as_float_array(wavelengths, "wavelengths")
    T = float(as_positive(as_scalar(temperature, "temperature"), "temperature"))
    c2 = 1.4388e7  # second radiation constant h c / k in nm K

    def planck(lam):
        return lam ** -5.0 / np.expm1(c2 / (lam * T))

    return planck(wl) / planck(560.0)


def triband_fluorescent(wavelengths, line_fwhm: float = 3.0) -> np.ndarray:
    """A tri-phosphor fluorescent lamp: narrow lines at 436 nm (mercury), 546 nm (terbium,
    green) and 611 nm (europium, red) on a weak continuum, the shape of CIE FL11-type lamps.

    Sampled coarsely, its energy falls between the samples or on them by accident: the spiky
    illuminant that makes colour aliasing visible.
    """
    wl = as_float_array(wavelengths, "wavelengths")
    return (0.04 * gaussian_band(wl, 560.0, 250.0)
            + 0.6 * gaussian_band(wl, 436.0, line_fwhm)
            + 1.0 * gaussian_band(wl, 546.0, line_fwhm)
            + 0.9 * gaussian_band(wl, 611.0, 2.0 * line_fwhm))


# --------------------------------------------------------------------------------------------
# the model per wavelength and the three treatments of colour


def _check_spectrum(f, name):
    if not callable(f):
        raise ValueError(  # noqa: TRY004 - the course's rule: every bad input is a ValueError
            f"{name} must be a callable of wavelength (nm), got {type(f).__name__}")
    return f


def _dense_grid(lo=LAMBDA_MIN, hi=LAMBDA_MAX):
    m = round((hi - lo) / DENSE_STEP) + 1
    return np.linspace(lo, hi, m)


def _light_scale(light) -> float:
    """1 / Y of the light on the dense grid: lights are compared at equal luminance."""
    wl = _dense_grid()
    Y = spectrum_to_XYZ(light(wl), wl)[1]
    if not Y > 0:
        raise ValueError("light must have positive luminance (Y > 0) over 380-780 nm")
    return 1.0 / Y


def band_averages(values, wl_dense, edges):
    """Average of densely sampled ``values`` (..., M) over each band ``[edges[i], edges[i+1]]``.

    Band integrals are differences of the cumulative trapezoid integral (interpolated at the
    edges), so they add up exactly to the integral over the whole range.
    """
    steps = 0.5 * (values[..., 1:] + values[..., :-1]) * np.diff(wl_dense)
    cumulative = np.concatenate([np.zeros(values.shape[:-1] + (1,)), np.cumsum(steps, -1)], -1)
    at_edges = np.apply_along_axis(lambda c: np.interp(edges, wl_dense, c), -1, cumulative)
    return np.diff(at_edges, axis=-1) / np.diff(edges)


def reflected_XYZ(light, reflectance, n: int | None = None, method: str = "point") -> np.ndarray:
    """XYZ of the light ``light`` reflected by a surface of reflectance ``reflectance``.

    Parameters
    ----------
    light, reflectance : callable
        Spectra as functions of wavelength (nm). The light is rescaled to ``Y = 1``.
    n : int or None
        Number of wavelength samples over 380-780 nm (:func:`sample_wavelengths`); ``None``
        for the converged answer (a 0.1 nm grid).
    method : {"point", "box"}
        ``"point"`` samples both spectra and the colour-matching functions at the ``n``
        wavelengths (the trapezoid rule). ``"box"`` first averages each of them over the band
        each sample stands for (a box prefilter, as in antialiasing an image), then multiplies
        the band averages.

    Returns
    -------
    ndarray, shape (3,)

    Notes
    -----
    Q5(d). The reflected spectrum is the product ``E(lambda) rho(lambda)``: products of spectra
    have finer detail than either factor, and a spectral line between two samples is simply
    missed by point sampling: colour aliasing.
    """
    light = _check_spectrum(light, "light")
    reflectance = _check_spectrum(reflectance, "reflectance")
    scale = _light_scale(light)
    if n is None:
        wl = _dense_grid()
        return spectrum_to_XYZ(scale * light(wl) * reflectance(wl), wl)
    wl = sample_wavelengths(n)
    if method == "point":
        return spectrum_to_XYZ(scale * light(wl) * reflectance(wl), wl)
    if method == "box":
        dense = _dense_grid()
        edges = band_edges(wl)
        E = band_averages(light(dense), dense, edges)
        rho = band_averages(reflectance(dense), dense, edges)
        c = band_averages(cmfs(dense).T, dense, edges).T
        return spectrum_to_XYZ(scale * E * rho, wl, cmf_values=c)
    raise ValueError(f"method must be 'point' or 'box', got {method!r}")


def reflected_colour(light, reflectance, n: int | None = None, method: str = "point"):
    """Linear sRGB of :func:`reflected_XYZ` (Q5(d): RGB only at the end, to drive a monitor)."""
    return XYZ_to_linear_srgb(reflected_XYZ(light, reflectance, n, method))


def rgb_model_colour(light, reflectance) -> np.ndarray:
    """The three-sample treatment of colour: the Phong model's own ``c_lambda I_lambda``.

    The light becomes one RGB triple (its linear sRGB at ``Y = 1``) and the surface another
    (its linear sRGB under the equal-energy reference white, divided channel by channel by the
    white's, so that the perfect white reflector is ``(1, 1, 1)``); the reflected colour is
    their product per channel.

    Notes
    -----
    Q5(d). Exact for a white (or grey) surface, and exact under the reference white itself; the
    error elsewhere is the colour aliasing the question asks about.
    """
    light = _check_spectrum(light, "light")
    reflectance = _check_spectrum(reflectance, "reflectance")
    wl = _dense_grid()
    light_rgb = XYZ_to_linear_srgb(spectrum_to_XYZ(_light_scale(light) * light(wl), wl))
    white_rgb = XYZ_to_linear_srgb(spectrum_to_XYZ(np.ones_like(wl), wl))
    surface_rgb = XYZ_to_linear_srgb(spectrum_to_XYZ(reflectance(wl), wl)) / white_rgb
    return light_rgb * surface_rgb


def colour_aliasing(light, reflectance, ns=(9, 16, 81), method: str = "point"):
    """The colour of a surface under a light by each treatment of colour, and its error.

    Returns
    -------
    rgb : ndarray, shape (len(ns) + 2, 3)
        Linear sRGB: row 0 the three-sample RGB model (:func:`rgb_model_colour`), then one row
        per ``n`` in ``ns`` (:func:`reflected_colour`), last the converged answer.
    error : ndarray, shape (len(ns) + 2,)
        CIE 1976 colour difference of each row from the converged answer, in L*a*b* relative
        to the white a viewer adapts to: the light reflected by a perfect white surface, worked
        out by the same treatment (so a quadrature error common to every surface, such as a
        slightly wrong luminance of the light, does not count as a colour error); 0 for the last
        row.

    Notes
    -----
    Q5(d): three samples against ``n`` wavelength samples; "n = 9 is usually enough" holds for
    smooth spectra and fails for line spectra unless the samples are prefiltered
    (``method="box"``).
    """
    ns = tuple(as_int(k, "ns", minimum=2) for k in ns)
    white_rgb = rgb_model_colour(light, equal_energy)
    XYZ = [linear_srgb_to_XYZ(rgb_model_colour(light, reflectance))]
    whites = [linear_srgb_to_XYZ(white_rgb)]
    for k in ns:
        XYZ.append(reflected_XYZ(light, reflectance, k, method))
        whites.append(reflected_XYZ(light, equal_energy, k, method))
    XYZ.append(reflected_XYZ(light, reflectance, None))
    whites.append(reflected_XYZ(light, equal_energy, None))
    XYZ, whites = np.array(XYZ), np.array(whites)
    lab = XYZ_to_Lab(XYZ, whites)
    return XYZ_to_linear_srgb(XYZ), delta_E(lab, lab[-1])
