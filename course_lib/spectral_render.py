"""Q5(d), going further: the Phong model per wavelength and a spectrally shaded sphere.

The instructors' copy only: both compute with the Phong model's reference
(:mod:`course_lib.shading`), so the students' wheel does not carry this module
(``autograder.student_bundle.INSTRUCTORS_ONLY``). The notebook's spectral spheres are rendered
here when the wheel is built and shipped as pixels (:mod:`course_lib._spectral_spheres_data`).
"""

from __future__ import annotations

import numpy as np

from . import shading
from ._validate import as_float_array
from .spectral import XYZ_to_linear_srgb, equal_energy, reflected_XYZ, rgb_model_colour

__all__ = ["render_sphere_spectral", "spectral_phong"]


def spectral_phong(reflectance, light, Ia, ka, Ip, kd, ks, n, L, N, V) -> np.ndarray:
    """The Phong model evaluated at every wavelength sample.

    .. math:: I(\\lambda) = E(\\lambda)\\left[\\rho(\\lambda)(I_a k_a + I_p k_d
              \\max(\\mathbf L\\cdot\\mathbf N, 0)) + I_p k_s\\max(\\mathbf R\\cdot\\mathbf V,0)^n
              \\right]

    Parameters
    ----------
    reflectance : array_like, shape (..., m)
        The surface's spectral reflectance ``rho`` (the spectral ``c_lambda``) at ``m``
        wavelengths.
    light : array_like, shape (m,)
        The light's relative spectrum ``E`` (ambient and point light alike).
    Ia, ka, Ip, kd, ks, n, L, N, V
        As :func:`course_lib.shading.phong`; the geometry's leading shape broadcasts with
        ``reflectance``'s.

    Returns
    -------
    ndarray, shape (..., m)
        Reflected spectrum; reduce it with :func:`course_lib.spectral.spectrum_to_XYZ`.

    Notes
    -----
    Q5(d): the improvement the examiners describe — run the model once per sampled wavelength
    (n samples of each spectrum) and only then reduce the result to RGB.
    The specular term reflects the light's own spectrum (a white highlight under white light).
    """
    rho = as_float_array(reflectance, "reflectance")
    E = as_float_array(light, "light")
    if E.ndim != 1 or rho.ndim == 0 or rho.shape[-1] != E.size:
        raise ValueError(f"light must have shape (m,) and reflectance (..., m); got "
                         f"{E.shape} and {rho.shape}")
    _, k = shading._coefficients(0.0, Ia, ka, Ip, kd, ks, n)
    diffuse, spec = shading.phong_terms(L, N, V, k["n"])
    body = (k["Ia"] * k["ka"] + k["Ip"] * k["kd"] * diffuse)[..., None]
    return E * (rho * body + (k["Ip"] * k["ks"] * spec)[..., None])


def render_sphere_spectral(light, reflectance, Ia, ka, Ip, kd, ks, n, L, V, size: int = 128,
                           n_samples: int | None = None, method: str = "point",
                           rgb_model: bool = False):
    """A unit sphere shaded by the per-wavelength Phong model, as a linear sRGB image.

    With one light spectrum and one material the per-wavelength model separates: at every pixel
    ``I(lambda) = body * E(lambda) rho(lambda) + spec * E(lambda)`` with the scalar geometry
    factors ``body = Ia ka + Ip kd max(L.N, 0)`` and ``spec = Ip ks max(R.V, 0)^n``, so the
    image is ``body * XYZ(E rho) + spec * XYZ(E)``: two tristimulus vectors, worked out once by
    :func:`reflected_XYZ` (``n_samples`` wavelengths, or converged for ``None``).

    With ``rgb_model=True`` the diffuse colour is instead the three-sample product
    :func:`rgb_model_colour` (the Phong model as the exam states it, with the light's colour).

    Returns
    -------
    image : ndarray, shape (size, size, 3)
        Linear sRGB (unclipped); 0 off the sphere.

    Notes
    -----
    Q5(d): the same geometry rendered both ways shows where three samples go wrong (only the
    diffuse body colour differs; the highlight has the light's colour in both).
    """
    normals, mask = shading.sphere_normals(V, size)
    diffuse, spec = shading.phong_terms(L, normals[mask], V, n)
    _, k = shading._coefficients(0.0, Ia, ka, Ip, kd, ks, n)
    body = k["Ia"] * k["ka"] + k["Ip"] * k["kd"] * diffuse
    white = XYZ_to_linear_srgb(reflected_XYZ(light, equal_energy, n_samples, method))
    if rgb_model:
        surface = rgb_model_colour(light, reflectance)
    else:
        surface = XYZ_to_linear_srgb(reflected_XYZ(light, reflectance, n_samples, method))
    image = np.zeros(normals.shape)
    image[mask] = body[:, None] * surface + (k["Ip"] * k["ks"] * spec)[:, None] * white
    return image
