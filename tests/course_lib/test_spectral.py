"""Tests of course_lib.spectral (Q5(d)) against colour-science, the exam and exact laws."""

from __future__ import annotations

import numpy as np
import pytest

from course_lib import shading
from course_lib import spectral as sp
from course_lib import spectral_render as sr

colour = pytest.importorskip("colour")

CMFS_NAME = "CIE 1931 2 Degree Standard Observer"


@pytest.fixture(scope="module")
def cie_cmfs():
    return colour.MSDS_CMFS[CMFS_NAME]


# ------------------------------------------------------------------------ the CIE table


def test_embedded_table_is_the_published_5nm_table(cie_cmfs):
    wl = sp.CIE_1931_2DEG[:, 0]
    np.testing.assert_array_equal(wl, np.arange(380, 781, 5))
    np.testing.assert_allclose(sp.CIE_1931_2DEG[:, 1:], cie_cmfs[wl], atol=5e-7, rtol=0)


def test_cmfs_between_table_points(cie_cmfs):
    """colour-science's 1 nm table was interpolated by the CIE with a smoother method; linear
    interpolation of the 5 nm table stays within 1 % of the peak everywhere."""
    wl = np.arange(380, 781, 1.0)
    np.testing.assert_allclose(sp.cmfs(wl), cie_cmfs[wl], atol=0.01 * 1.8)
    np.testing.assert_array_equal(sp.cmfs([300.0, 800.0]), 0.0)


def test_y_integral(cie_cmfs):
    wl = np.arange(380, 781, 1.0)
    assert sp.Y_INTEGRAL == pytest.approx(np.sum(cie_cmfs[wl][:, 1]), rel=1e-3)


def test_equal_energy_spectrum_has_equal_XYZ():
    """By the CIE's construction, x, y and z have (nearly) equal areas: E has X = Y = Z = 1."""
    wl = sp.sample_wavelengths(81)
    np.testing.assert_allclose(sp.spectrum_to_XYZ(np.ones(81), wl), 1.0, rtol=2e-3, atol=1e-12)
    assert sp.spectrum_to_XYZ(np.ones(81), wl)[1] == pytest.approx(1.0, rel=1e-12)


# ---------------------------------------------------------------- XYZ, sRGB, Lab vs colour


def test_xyz_to_linear_srgb_matches_colour_science():
    rng = np.random.default_rng(0)
    XYZ = rng.uniform(0.0, 1.0, (20, 3))
    expected = colour.XYZ_to_sRGB(XYZ, apply_cctf_encoding=False)
    np.testing.assert_allclose(sp.XYZ_to_linear_srgb(XYZ), expected, atol=1e-6)
    np.testing.assert_allclose(sp.linear_srgb_to_XYZ(sp.XYZ_to_linear_srgb(XYZ)), XYZ,
                               atol=1e-12)


def test_srgb_encoding_matches_colour_science():
    x = np.linspace(0.0, 1.0, 101)
    np.testing.assert_allclose(sp.linear_srgb_to_srgb(x), colour.cctf_encoding(x, "sRGB"),
                               atol=1e-9)
    np.testing.assert_allclose(sp.linear_srgb_to_srgb([-0.2, 1.5]), [0.0, 1.0], atol=1e-12)


def test_lab_and_delta_e_match_colour_science():
    rng = np.random.default_rng(1)
    XYZ = rng.uniform(0.0, 1.0, (20, 3))
    white = np.array([0.9, 1.0, 0.7])
    expected = colour.XYZ_to_Lab(XYZ, colour.XYZ_to_xy(white))
    Lab = sp.XYZ_to_Lab(XYZ, white)
    np.testing.assert_allclose(Lab, expected, atol=1e-9)
    np.testing.assert_allclose(sp.delta_E(Lab[:10], Lab[10:]),
                               colour.delta_E(Lab[:10], Lab[10:], method="CIE 1976"), atol=1e-9)


def _tabulated(sd):
    """A colour-science spectral distribution as a callable (linear interpolation)."""
    return lambda wl: np.interp(wl, sd.wavelengths, sd.values)


@pytest.mark.parametrize("illuminant", ["FL2", "FL11", "A", "D65"])
def test_reflected_xyz_matches_colour_sd_to_xyz(cie_cmfs, illuminant):
    """The converged surface colour equals colour-science's integration (same spectra at 1 nm;
    the remaining difference is the CMF interpolation)."""
    ill = colour.SDS_ILLUMINANTS[illuminant]
    wl = np.arange(380, 781, 1.0)
    rho = 0.05 + 0.85 * np.exp(-0.5 * ((wl - 610.0) / 25.0) ** 2)
    E = _tabulated(ill)(wl)
    shape = colour.SpectralShape(380, 780, 1)
    expected = colour.sd_to_XYZ(colour.SpectralDistribution(rho, wl),
                                cmfs=cie_cmfs.copy().align(shape),
                                illuminant=colour.SpectralDistribution(E, wl),
                                method="Integration") / 100.0
    # the same integral by our functions: the samples as given, and as callables
    direct = sp.spectrum_to_XYZ(E * rho, wl) / sp.spectrum_to_XYZ(E, wl)[1]
    converged = sp.reflected_XYZ(_tabulated(ill),
                                 lambda w: 0.05 + 0.85 * np.exp(-0.5 * ((w - 610) / 25) ** 2))
    np.testing.assert_allclose(direct, expected, rtol=5e-3, atol=2e-4)
    np.testing.assert_allclose(converged, expected, rtol=5e-3, atol=2e-4)


def test_light_colour_matches_colour_science():
    """The linear sRGB of illuminant D65 at Y = 1 is white (1, 1, 1)."""
    d65 = _tabulated(colour.SDS_ILLUMINANTS["D65"])
    np.testing.assert_allclose(sp.reflected_colour(d65, sp.equal_energy), 1.0, atol=5e-3)


# ---------------------------------------------------------------------- the analytic spectra


def test_gaussian_band_full_width_at_half_maximum():
    v = sp.gaussian_band([550.0, 530.0, 570.0], 550.0, 40.0, peak=0.8, floor=0.2)
    np.testing.assert_allclose(v, [0.8, 0.5, 0.5], atol=1e-12)


def test_blackbody_wien_peak_and_colour_science():
    wl = np.arange(380.0, 780.01, 0.1)
    T = 5000.0
    assert wl[np.argmax(sp.blackbody(wl, T))] == pytest.approx(2.897771955e6 / T, abs=0.2)
    sd = colour.sd_blackbody(T, colour.SpectralShape(380, 780, 5))
    ratio = sp.blackbody(sd.wavelengths, T) / sd.values
    np.testing.assert_allclose(ratio, ratio[0], rtol=1e-5, atol=1e-12)


# ------------------------------------------------------------------ the spectral Phong model


def test_spectral_phong_reproduces_the_exam_per_wavelength():
    """Q5(b) per wavelength: a reflectance 0, 0, 1 at three samples under a flat light gives
    the exam's (0.0931, 0.0931, 0.699)."""
    g = shading.EXAM_Q5B
    out = sr.spectral_phong([0.0, 0.0, 1.0], np.ones(3), g["Ia"], g["ka"], g["Ip"], g["kd"],
                            g["ks"], g["n"], g["L"], g["N"], g["V"])
    np.testing.assert_allclose(out, [0.0931, 0.0931, 0.699], atol=5e-4)


def test_spectral_phong_batches_and_light_scaling():
    rng = np.random.default_rng(2)
    N = rng.normal(size=(5, 3))
    rho = rng.uniform(0, 1, (5, 7))
    E = rng.uniform(0.5, 2.0, 7)
    out = sr.spectral_phong(rho, E, 1.0, 0.2, 1.0, 0.6, 0.5, 20, (1, 1, 1), N, (0, 0, 1))
    assert out.shape == (5, 7)
    for i in range(5):
        # per wavelength the model is phong for a grey of that reflectance, times the light
        np.testing.assert_allclose(out[i], E * _per_wl(rho[i], N[i]), rtol=1e-12, atol=1e-12)


def _per_wl(rho, N):
    return np.array([shading.phong((r, r, r), 1.0, 0.2, 1.0, 0.6, 0.5, 20, (1, 1, 1), N,
                                   (0, 0, 1))[0] for r in rho])


# ------------------------------------------------------------ the three treatments of colour


def test_rgb_model_exact_for_a_white_surface():
    """A grey surface reflects the light's own colour: three samples lose nothing."""
    for light in (sp.triband_fluorescent, lambda w: sp.blackbody(w, 2856)):
        np.testing.assert_allclose(sp.rgb_model_colour(light, lambda w: 0.6 + 0 * w),
                                   sp.reflected_colour(light, lambda w: 0.6 + 0 * w),
                                   atol=1e-12)


def test_rgb_model_exact_under_the_reference_white():
    """Under the equal-energy light the RGB surface colour is defined from, RGB is exact."""
    refl = lambda w: sp.gaussian_band(w, 520.0, 20.0, 0.9, 0.02)
    np.testing.assert_allclose(sp.rgb_model_colour(sp.equal_energy, refl),
                               sp.reflected_colour(sp.equal_energy, refl), atol=1e-12)


def test_box_sampling_exact_for_flat_spectra():
    """Band averages reproduce the integral exactly when the spectra are constant, for any n."""
    for n in (3, 9, 16):
        np.testing.assert_allclose(sp.reflected_XYZ(sp.equal_energy, lambda w: 0.5 + 0 * w, n,
                                                    "box"),
                                   sp.reflected_XYZ(sp.equal_energy, lambda w: 0.5 + 0 * w),
                                   atol=1e-9)


def test_point_sampling_81_is_the_cie_5nm_sum():
    """n = 81 over 380-780 nm samples exactly the CIE's 5 nm grid."""
    np.testing.assert_allclose(sp.sample_wavelengths(81), sp.CIE_1931_2DEG[:, 0], rtol=0, atol=1e-9)


def test_smooth_spectra_nine_samples_are_enough():
    """Q5(d)'s "n = 9 is sufficient for most applications": with smooth spectra (a tungsten
    black body, broad reflectances) nine point samples come within a few Delta E (2.3 is just
    noticeable) of the converged colour, several times closer than the three-sample RGB model,
    and sixteen samples are within one just-noticeable difference."""
    light = lambda w: sp.blackbody(w, 2856.0)
    for centre in (450.0, 520.0, 600.0):
        refl = lambda w, c=centre: sp.gaussian_band(w, c, 100.0, 0.9, 0.05)
        _, err = sp.colour_aliasing(light, refl, ns=(9, 16, 81))
        assert err[-1] == pytest.approx(0.0, abs=1e-9)   # the converged colour against itself
        assert err[1] < 4.0
        assert err[1] < err[0] / 4
        assert err[2] < 2.3
        assert err[3] < 0.5


def test_spiky_light_shows_colour_aliasing():
    """A fluorescent line spectrum and a narrow red reflectance: three RGB samples and nine
    point samples are visibly wrong; the error falls well below visibility as n grows."""
    refl = lambda w: sp.gaussian_band(w, 610.0, 30.0, 0.9, 0.05)
    rgb, err = sp.colour_aliasing(sp.triband_fluorescent, refl, ns=(9, 16, 81, 401))
    assert rgb.shape == (6, 3) and err.shape == (6,)
    assert err[0] > 5.0
    assert err[1] > 5.0
    assert err[4] < 1.0
    # prefiltering (box) helps the coarse samples
    _, err_box = sp.colour_aliasing(sp.triband_fluorescent, refl, ns=(9,), method="box")
    assert err_box[1] < err[1]


def test_value_errors():
    with pytest.raises(ValueError, match="n"):
        sp.sample_wavelengths(1)
    with pytest.raises(ValueError, match="spectrum"):
        sp.spectrum_to_XYZ(np.ones(5), sp.sample_wavelengths(6))
    with pytest.raises(ValueError, match="method"):
        sp.reflected_XYZ(sp.equal_energy, sp.equal_energy, 9, method="nearest")
    with pytest.raises(ValueError, match="callable"):
        sp.reflected_XYZ(np.ones(9), sp.equal_energy)
    with pytest.raises(ValueError, match="luminance"):
        sp.reflected_XYZ(lambda w: 0.0 * w, sp.equal_energy)
    with pytest.raises(ValueError, match="increasing"):
        sp.trapezoid_weights([500.0, 450.0, 600.0])


def test_spectral_sphere_pixel_equals_per_wavelength_model():
    """A pixel of the spectral sphere equals the per-wavelength Phong spectrum at that normal,
    integrated against the CMFs (here on a 1 nm grid, computed independently per pixel)."""
    light = sp.triband_fluorescent
    refl = lambda w: sp.gaussian_band(w, 525.0, 25.0, 0.9, 0.05)
    L, V, size = (1.0, -1.0, 1.0), (0.0, -1.0, 0.2), 24
    img = sr.render_sphere_spectral(light, refl, 1.0, 0.2, 1.0, 0.7, 0.5, 30.0, L, V, size)
    normals, mask = shading.sphere_normals(V, size)
    wl = np.linspace(380.0, 780.0, 4001)
    E = light(wl) / sp.spectrum_to_XYZ(light(wl), wl)[1]
    rng = np.random.default_rng(5)
    rows, cols = np.nonzero(mask)
    for i in rng.choice(len(rows), 8, replace=False):
        N = normals[rows[i], cols[i]]
        spd = sr.spectral_phong(refl(wl), E, 1.0, 0.2, 1.0, 0.7, 0.5, 30.0, L, N, V)
        expected = sp.XYZ_to_linear_srgb(sp.spectrum_to_XYZ(spd, wl))
        np.testing.assert_allclose(img[rows[i], cols[i]], expected, rtol=1e-9, atol=1e-12)
    assert np.all(img[~mask] == 0)


def test_spectral_sphere_grey_surface_rgb_equals_spectral():
    grey = lambda w: 0.4 + 0 * w
    args = (sp.triband_fluorescent, grey, 1.0, 0.2, 1.0, 0.7, 0.5, 30.0, (1, 1, 1), (0, 0, 1), 16)
    np.testing.assert_allclose(sr.render_sphere_spectral(*args, rgb_model=True),
                               sr.render_sphere_spectral(*args), atol=1e-12)
