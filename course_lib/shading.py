"""Q5: illumination and reflection with the Phong and Blinn-Phong models.

The exam's model (Q5(a)) gives the intensity of the light of colour ``lambda`` reflected from a
surface point towards the viewer as

.. math::

    I_\\lambda = c_\\lambda (I_a k_a + I_p k_d\\,\\max(\\mathbf L\\cdot\\mathbf N, 0))
                 + I_p k_s\\,\\max(\\mathbf R\\cdot\\mathbf V, 0)^n ,
    \\qquad \\mathbf R = 2(\\mathbf L\\cdot\\mathbf N)\\mathbf N - \\mathbf L ,

with unit vectors ``L`` (towards the light), ``N`` (surface normal), ``V`` (towards the viewer)
and no specular term where the light is behind the surface (``L.N <= 0``). Blinn's variant
(Q5(c)) replaces ``R.V`` by ``N.H`` with the half-way vector ``H = (L + V) / |L + V|``.

Besides the five graded functions this module renders a unit sphere pixel by pixel under either
model (orthographic view, directional light) and locates the highlight analytically, for the
notebook's figures and the Phong explorer. The students' copy holds none of the five, nor the
helpers that compute their answers (``autograder.student_bundle.LEFT_OUT_HELPERS``): its figures
and explorer draw through routines that keep only 8-bit images and readouts at the digits
shown (``INLINE_INTO``; docs/students-copy.md).
"""

from __future__ import annotations

import numpy as np

from ._validate import as_float_array, as_int, as_scalar, as_vectors

__all__ = [
    "EXAM_Q5B",
    "blinn_phong",
    "halfway",
    "highlight_normal",
    "highlight_pixel",
    "normalize",
    "phong",
    "phong_terms",
    "reflect",
    "render_sphere",
    "sphere_normals",
    "view_basis",
]

#: The givens of Q5(b) as ``phong``'s keyword arguments. The paper's numbers fix ``L``, ``N``,
#: ``V`` and ``n``; the rest is what reproduces the printed answer: a blue surface
#: ``c = (0, 0, 1)`` and ``Ia ka = 0.5``, ``Ip kd = 0.5``, ``Ip ks = 1`` (here with ``Ip = 1``).
EXAM_Q5B = {
    "colour": (0.0, 0.0, 1.0),
    "Ia": 1.0,
    "ka": 0.5,
    "Ip": 1.0,
    "kd": 0.5,
    "ks": 1.0,
    "n": 10.0,
    "L": (1.0, -1.0, 1.0),
    "N": (0.0, 0.5, np.sqrt(3.0) / 2.0),
    "V": (0.0, 1.0, 0.0),
}


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dot product along the last axis, broadcasting the leading axes."""
    return np.einsum("...i,...i->...", a, b)


def _length(v: np.ndarray) -> np.ndarray:
    """Euclidean length along the last axis."""
    return np.sqrt(np.einsum("...i,...i->...", v, v))


def _normalised(v: np.ndarray, name: str) -> np.ndarray:
    """``v`` normalised along its last axis (``np.linalg.norm``); ``ValueError`` for a
    zero-length vector. (It computes :func:`normalize`'s answer, so it goes where that goes.)"""
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    if np.any(norm == 0):
        raise ValueError(f"{name} contains a zero-length vector, which has no direction")
    return v / norm


def _unit(v: np.ndarray, name: str) -> np.ndarray:
    """``v`` normalised along its last axis; ``ValueError`` for a zero-length vector."""
    m = _length(v)
    if np.any(m == 0):
        raise ValueError(f"{name} contains a zero-length vector, which has no direction")
    return v / m[..., None]


def normalize(v) -> np.ndarray:
    """Unit vectors along the last axis.

    Parameters
    ----------
    v : array_like, shape (..., d)
        One vector ``(d,)`` or a batch ``(n, d)`` (any leading shape).

    Returns
    -------
    ndarray, shape (..., d)
        ``v / |v|``, row by row.

    Raises
    ------
    ValueError
        If ``v`` is a scalar, holds NaN/inf, or any vector has zero length (it has no
        direction).

    Notes
    -----
    Q5(b): every vector of the Phong model must be a unit vector; the examiners' most common
    complaint was that candidates forgot to normalise ``L = (1, -1, 1)``.

    Examples
    --------
    >>> normalize([1.0, -1.0, 1.0])
    array([ 0.57735027, -0.57735027,  0.57735027])
    """
    arr = as_float_array(v, "v")
    if arr.ndim == 0 or arr.shape[-1] == 0:
        raise ValueError(f"v must have shape (..., d) with d >= 1, got shape {arr.shape}")
    return _normalised(arr, "v")


def reflect(L, N) -> np.ndarray:
    """The mirror direction ``R = 2 (L.N) N - L`` of ``L`` about the normal ``N``.

    Parameters
    ----------
    L : array_like, shape (..., 3)
        Direction(s) towards the light. ``L`` keeps its length (``|R| = |L|``).
    N : array_like, shape (..., 3)
        Surface normal(s); normalised here, since only a unit normal gives a reflection.

    Returns
    -------
    ndarray, shape (..., 3)
        ``R``, broadcast over the leading axes of ``L`` and ``N``.

    Raises
    ------
    ValueError
        Wrong shape, NaN/inf, or a zero-length normal.

    Notes
    -----
    Q5(a): the component of ``L`` along ``N`` is ``(L.N) N``; mirroring keeps it and flips the
    tangential part ``L - (L.N) N``, so ``R = (L.N) N - (L - (L.N) N) = 2 (L.N) N - L``.
    Reflection is an involution (``reflect(reflect(L, N), N) == L``) and keeps angles:
    ``R.N == L.N``.

    Examples
    --------
    >>> reflect([1.0, 1.0, 0.0], [0.0, 1.0, 0.0])
    array([-1.,  1.,  0.])
    """
    L = as_vectors(L, 3, "L")
    N = _normalised(as_vectors(N, 3, "N"), "N")
    return 2.0 * _dot(L, N)[..., None] * N - L


def halfway(L, V) -> np.ndarray:
    """The unit half-way vector ``H = (L + V) / |L + V|`` of unit ``L`` and ``V``.

    Parameters
    ----------
    L, V : array_like, shape (..., 3)
        Directions towards the light and the viewer (normalised here first).

    Returns
    -------
    ndarray, shape (..., 3)

    Raises
    ------
    ValueError
        Wrong shape, a zero-length ``L`` or ``V``, or ``V = -L`` (then ``L + V = 0`` and no
        half-way direction exists).

    Notes
    -----
    Q5(c): ``H`` bisects the angle between ``L`` and ``V``; ``N.H = 1`` exactly where the
    mirror direction ``R`` points at the viewer. With the light and the viewer at infinity
    ``H`` is the same for every surface point.
    """
    L = _normalised(as_vectors(L, 3, "L"), "L")
    V = _normalised(as_vectors(V, 3, "V"), "V")
    s = L + V
    if np.any(np.linalg.norm(s, axis=-1) < 1e-12):
        raise ValueError("L and V point in opposite directions: the half-way vector is undefined")
    return s / np.linalg.norm(s, axis=-1, keepdims=True)


def _coefficients(colour, Ia, ka, Ip, kd, ks, n):
    colour = as_float_array(colour, "colour")
    if colour.ndim == 0:
        colour = np.full(3, float(colour))
    if colour.shape[-1] != 3:
        raise ValueError(f"colour must have shape (..., 3) (RGB), got shape {colour.shape}")
    if np.any(colour < 0):
        raise ValueError("colour must be non-negative (a fraction of each primary reflected)")
    coef = {}
    for name, value in (("Ia", Ia), ("ka", ka), ("Ip", Ip), ("kd", kd), ("ks", ks)):
        coef[name] = as_scalar(value, name)
        if coef[name] < 0:
            raise ValueError(f"{name} must be non-negative, got {coef[name]}")
    coef["n"] = as_scalar(n, "n")
    if coef["n"] <= 0:
        raise ValueError(f"n (the specular exponent) must be positive, got {coef['n']}")
    return colour, coef


def phong_terms(L, N, V, n, model: str = "Phong"):
    """The geometric factors of the model: ``(max(L.N, 0), specular)``.

    ``specular`` is ``max(R.V, 0)^n`` (``model="Phong"``) or ``max(N.H, 0)^n``
    (``model="Blinn-Phong"``), set to 0 wherever ``L.N <= 0``. ``L``, ``N``, ``V`` are normalised
    here; the two returned arrays have the broadcast leading shape of the three.

    Notes
    -----
    Q5(a) and Q5(c). Used by :func:`phong`, :func:`blinn_phong` and the sphere renderer.
    """
    L = _unit(as_vectors(L, 3, "L"), "L")
    N = as_vectors(N, 3, "N")
    V = _unit(as_vectors(V, 3, "V"), "V")
    n = as_scalar(n, "n")
    if n <= 0:
        raise ValueError(f"n (the specular exponent) must be positive, got {n}")
    # Only dot products are needed, so N is never normalised as a vector (cheaper for large
    # batches): with unit L, V and |N| = m, L.N = (L.N_raw)/m and N.V = (N_raw.V)/m.
    m = _length(N)
    if np.any(m == 0):
        raise ValueError("N contains a zero-length vector, which has no direction")
    LN = _dot(L, N) / m
    NV = _dot(N, V) / m
    if model == "Phong":
        # R.V = (2 (L.N) N - L).V = 2 (L.N)(N.V) - L.V
        c = 2.0 * LN * NV - _dot(L, V)
    elif model == "Blinn-Phong":
        # N.H = N.(L + V) / |L + V|
        norm = _length(L + V)
        if np.any(norm < 1e-12):
            raise ValueError("L and V point in opposite directions: the half-way vector "
                             "is undefined")
        c = (LN + NV) / norm
    else:
        raise ValueError(f"model must be 'Phong' or 'Blinn-Phong', got {model!r}")
    lit = LN > 0
    spec = np.where(lit, np.maximum(c, 0.0), 0.0) ** n
    spec = np.where(lit, spec, 0.0)
    return np.maximum(LN, 0.0), spec


def _shade(colour, Ia, ka, Ip, kd, ks, n, L, N, V, model):
    colour, k = _coefficients(colour, Ia, ka, Ip, kd, ks, n)
    diffuse, spec = phong_terms(L, N, V, k["n"], model)
    body = k["Ia"] * k["ka"] + k["Ip"] * k["kd"] * diffuse
    return colour * body[..., None] + (k["Ip"] * k["ks"] * spec)[..., None]


def phong(colour, Ia, ka, Ip, kd, ks, n, L, N, V) -> np.ndarray:
    """RGB intensity of the Phong model.

    .. math::

        I = c\\,(I_a k_a + I_p k_d \\max(\\mathbf L\\cdot\\mathbf N, 0))
            + I_p k_s \\max(\\mathbf R\\cdot\\mathbf V, 0)^n

    Parameters
    ----------
    colour : array_like, shape (3,) or (..., 3)
        Surface colour ``c`` per channel (RGB fractions in [0, 1]); broadcast against the
        vectors' leading shape. A scalar means grey.
    Ia, ka, Ip, kd, ks : float
        Ambient intensity and coefficient, point-light intensity, diffuse and specular
        coefficients (non-negative).
    n : float
        Specular exponent (positive).
    L, N, V : array_like, shape (..., 3)
        Towards the light, surface normal, towards the viewer. Any length: they are
        normalised here.

    Returns
    -------
    ndarray, shape (..., 3)
        ``(I_r, I_g, I_b)``. The specular highlight takes the light's colour (white), so it is
        added equally to the three channels.

    Raises
    ------
    ValueError
        Wrong shapes, zero-length vectors, negative coefficients, non-positive ``n``.

    Notes
    -----
    Q5(a) defines the terms, Q5(b) evaluates them. Where ``L.N <= 0`` the light is behind the
    surface: no diffuse and no specular term. ``R = 2 (L.N) N - L``.

    Examples
    --------
    The exam's Q5(b): ``L`` along ``(1, -1, 1)``, ``N = (0, 1/2, sqrt(3)/2)``, ``V = (0, 1, 0)``,
    ``n = 10``, a blue surface with ``Ia ka = Ip kd = 0.5`` and ``Ip ks = 1``:

    >>> phong((0, 0, 1), 1, 0.5, 1, 0.5, 1, 10, (1, -1, 1),
    ...       (0, 0.5, 3 ** 0.5 / 2), (0, 1, 0)).round(4)
    array([0.0931, 0.0931, 0.6988])
    """
    return _shade(colour, Ia, ka, Ip, kd, ks, n, L, N, V, "Phong")


def blinn_phong(colour, Ia, ka, Ip, kd, ks, n, L, N, V) -> np.ndarray:
    """RGB intensity of the Blinn-Phong model: :func:`phong` with ``(N.H)^n`` for ``(R.V)^n``.

    Parameters and returns as :func:`phong`; ``H = (L + V)/|L + V|`` (:func:`halfway`).

    Raises
    ------
    ValueError
        As :func:`phong`, and when ``V = -L`` (no half-way vector).

    Notes
    -----
    Q5(c): with the light and the viewer at infinity ``H`` is constant over the scene, so the
    specular term costs one dot product ``N.H`` per point instead of building ``R`` first. Both
    terms equal 1 for the same normal (``N = H`` exactly when ``R = V``), but for the same
    exponent the Blinn-Phong highlight is wider: the angle between ``N`` and ``H`` is about half
    the angle between ``R`` and ``V``.
    """
    return _shade(colour, Ia, ka, Ip, kd, ks, n, L, N, V, "Blinn-Phong")


# --------------------------------------------------------------------------------------------
# the shaded sphere


def highlight_normal(L, V) -> np.ndarray:
    """The unit normal at which the highlight peaks, for both models: ``H``.

    ``R.V = 1`` needs ``R = V``, i.e. ``2 (L.N) N = L + V``, so ``N`` is along ``L + V``;
    ``N.H = 1`` needs ``N = H``: the same normal. (The two highlights peak at the same point of
    a surface lit and viewed from infinity; they differ in size and shape.)

    Notes
    -----
    Q5(c). Raises ``ValueError`` as :func:`halfway`.
    """
    return halfway(L, V)


def view_basis(V, up=(0.0, 0.0, 1.0)):
    """Screen axes ``(right, up, V)`` of an orthographic camera looking along ``-V``.

    ``right x up = V``; ``up`` is the given up vector made orthogonal to ``V`` (the world's
    ``y`` axis is used instead when ``up`` is parallel to ``V``). Returns a ``(3, 3)`` array of
    rows.
    """
    V = _normalised(as_vectors(V, 3, "V"), "V")
    if V.shape != (3,):
        raise ValueError(f"V must be a single vector of shape (3,), got shape {V.shape}")
    u = _normalised(as_vectors(up, 3, "up"), "up")
    e_up = u - (u @ V) * V
    if np.linalg.norm(e_up) < 1e-9:
        alt = np.array([0.0, 1.0, 0.0]) if abs(V[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
        e_up = alt - (alt @ V) * V
    e_up = e_up / np.linalg.norm(e_up)
    e_right = np.cross(e_up, V)
    return np.stack([e_right, e_up, V])


def sphere_normals(V, size: int = 128, up=(0.0, 0.0, 1.0)):
    """Unit normals of the visible half of a unit sphere seen along ``-V``.

    Pixel ``(row, col)`` of a ``size x size`` image covers ``x = (col + 0.5) * 2/size - 1``
    (to the right) and ``y = 1 - (row + 0.5) * 2/size`` (upwards); on the sphere's disc the
    normal is ``x e_right + y e_up + sqrt(1 - x^2 - y^2) V``.

    Returns
    -------
    normals : ndarray, shape (size, size, 3)
        Zero outside the disc.
    mask : ndarray of bool, shape (size, size)
        True on the sphere.
    """
    size = as_int(size, "size", minimum=2)
    basis = view_basis(V, up)
    t = (np.arange(size) + 0.5) * (2.0 / size) - 1.0
    x = t[None, :]
    y = -t[:, None]
    r2 = x * x + y * y
    mask = r2 < 1.0
    z = np.sqrt(np.clip(1.0 - r2, 0.0, None))
    normals = (x[..., None] * basis[0] + y[..., None] * basis[1] + z[..., None] * basis[2])
    normals[~mask] = 0.0
    return normals, mask


def render_sphere(colour, Ia, ka, Ip, kd, ks, n, L, V, size: int = 128, model: str = "Phong",
                  up=(0.0, 0.0, 1.0), background=0.0):
    """Shade a unit sphere pixel by pixel, seen orthographically from direction ``V``.

    Parameters
    ----------
    colour, Ia, ka, Ip, kd, ks, n
        As :func:`phong`; ``colour`` must be a single RGB triple here.
    L, V : array_like, shape (3,)
        Directions towards the (directional) light and the (distant) viewer.
    size : int
        The image is ``size x size`` pixels; the sphere fills it.
    model : {"Phong", "Blinn-Phong"}
    up : array_like, shape (3,)
        World direction shown upwards on screen (see :func:`view_basis`).
    background : float
        Value of the pixels off the sphere.

    Returns
    -------
    image : ndarray, shape (size, size, 3)
        Linear RGB intensities (not clipped: values above 1 mean an over-exposed highlight).
    highlight : tuple of two floats, or None
        ``(row, col)`` of the pixel where the specular factor (``max(R.V, 0)^n`` or
        ``max(N.H, 0)^n``, before scaling by ``Ip ks``) is largest; ``None`` when it is zero at
        every visible pixel (no lit point reflects towards the viewer).

    Notes
    -----
    Q5(a)-(c) per pixel: one normal per pixel, light and viewer at infinity (so ``V`` and, for
    Blinn-Phong, ``H`` are the same at every pixel). The analytic highlight position is
    :func:`highlight_pixel`.
    """
    colour, k = _coefficients(colour, Ia, ka, Ip, kd, ks, n)
    if colour.shape != (3,):
        raise ValueError(f"colour must be one RGB triple of shape (3,), got shape {colour.shape}")
    L = _normalised(as_vectors(L, 3, "L"), "L")
    if L.shape != (3,):
        raise ValueError(f"L must be a single vector of shape (3,), got shape {L.shape}")
    normals, mask = sphere_normals(V, size, up)
    V = _normalised(as_vectors(V, 3, "V"), "V")
    Nv = normals[mask]
    diffuse, spec = phong_terms(L, Nv, V, k["n"], model)
    image = np.full(normals.shape, float(background))
    body = k["Ia"] * k["ka"] + k["Ip"] * k["kd"] * diffuse
    image[mask] = colour * body[:, None] + (k["Ip"] * k["ks"] * spec)[:, None]
    highlight = None
    if spec.size and spec.max() > 0:
        rows, cols = np.nonzero(mask)
        i = int(np.argmax(spec))
        highlight = (float(rows[i]), float(cols[i]))
    return image, highlight


def highlight_pixel(L, V, size: int = 128, up=(0.0, 0.0, 1.0)):
    """Analytic ``(row, col)`` (fractional) of the highlight in :func:`render_sphere`'s image.

    The highlight peaks where the normal is ``H`` (:func:`highlight_normal`); that point of the
    unit sphere projects to ``x = H.e_right``, ``y = H.e_up`` on screen. That point is always
    lit and visible: ``H.V = H.L = sqrt((1 + L.V)/2) > 0`` whenever ``V != -L``.

    Notes
    -----
    Q5(c): both ``R.V`` and ``N.H`` reach 1 at this normal.
    """
    size = as_int(size, "size", minimum=2)
    H = highlight_normal(L, V)
    if H.shape != (3,):
        raise ValueError(f"L and V must be single vectors of shape (3,), got H of shape {H.shape}")
    basis = view_basis(V, up)
    x, y = float(H @ basis[0]), float(H @ basis[1])
    col = (x + 1.0) * size / 2.0 - 0.5
    row = (1.0 - y) * size / 2.0 - 0.5
    return row, col
