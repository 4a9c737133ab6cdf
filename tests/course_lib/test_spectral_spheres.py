"""Q5(d)'s spectral spheres as shipped (course_lib._spectral_spheres_data): the students' copy
holds the references' pixels bit for bit, and the pixels are the spectral Phong model worked
out here independently, pixel by pixel (normals, R.V and the CIE integrals by hand)."""

from __future__ import annotations

import ast

import numpy as np

from course_lib import _spectral_spheres_data as data
from course_lib import spectral as sp

SPEC = sp.SPECTRAL_SPHERES
M = np.array([[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]])
trapezoid = getattr(np, "trapezoid", None) or np.trapz


def _students_module() -> dict:
    namespace: dict = {}
    exec(compile(data.students_copy(), "_spectral_spheres_data", "exec"), namespace)
    return namespace


def test_students_copy_is_the_references_pixels_and_nothing_that_renders():
    text = data.students_copy()
    tree = ast.parse(text)
    imported = {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    imported |= {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    assert imported == {"base64", "functools", "zlib", "numpy"}
    for word in ("render_sphere_spectral", "phong", "shading", "spectral_phong"):
        assert word not in {getattr(n, "id", getattr(n, "attr", None)) for n in ast.walk(tree)}
    got = _students_module()["load"]()
    ref = data.compute()
    assert sorted(got) == sorted(ref) == ["images"]
    assert got["images"].dtype == np.uint8 and not got["images"].flags.writeable
    np.testing.assert_array_equal(got["images"], ref["images"])
    size = SPEC["size"]
    assert ref["images"].shape == (2 + len(SPEC["ns"]), size, size, 3)


def _cmfs(wl):
    table = sp.CIE_1931_2DEG
    return np.stack([np.interp(wl, table[:, 0], table[:, j], left=0.0, right=0.0)
                     for j in (1, 2, 3)], -1)


def _srgb_pixel(linear):
    c = np.clip(linear, 0.0, 1.0)
    encoded = np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)
    return (encoded * 255).astype(np.uint8)


def _geometry(row, col, size):
    """``(b, s)``: Ia ka + Ip kd max(L.N, 0) and Ip ks max(R.V, 0)^n at a pixel, by hand."""
    V = np.array(SPEC["V"]) / np.linalg.norm(SPEC["V"])
    L = np.array(SPEC["L"]) / np.linalg.norm(SPEC["L"])
    up = np.array([0.0, 0.0, 1.0]) - V[2] * V
    up /= np.linalg.norm(up)
    right = np.cross(up, V)
    x, y = (col + 0.5) * 2 / size - 1, 1 - (row + 0.5) * 2 / size
    N = x * right + y * up + np.sqrt(1 - x * x - y * y) * V
    LN = L @ N
    R = 2 * LN * N - L
    s = SPEC["ks"] * max(R @ V, 0.0) ** SPEC["n"] if LN > 0 else 0.0
    return SPEC["ka"] + SPEC["kd"] * max(LN, 0.0), s


def _expected_colours():
    """Per panel ``(surface, highlight)`` linear sRGB, the CIE integrals on a 0.1 nm grid
    (lights at Y = 1: the scale is 1 / integral of E ybar, so the table's own normalisation
    cancels)."""
    dense = np.linspace(380.0, 780.0, 4001)
    E = sp.triband_fluorescent(dense)
    rho = sp.gaussian_band(dense, *SPEC["dye"])
    cm = _cmfs(dense)
    per_Y = 1.0 / trapezoid(E * cm[:, 1], dense)

    def xyz(f, wl):
        return trapezoid(f[:, None] * _cmfs(wl), wl, axis=0)

    light = M @ (xyz(E, dense) * per_Y)
    white = M @ xyz(np.ones_like(dense), dense)
    out = [(light * (M @ xyz(rho, dense)) / white, light)]       # the three-sample model
    for k in SPEC["ns"]:
        wl = np.linspace(380.0, 780.0, k)
        Ek, rk = sp.triband_fluorescent(wl), sp.gaussian_band(wl, *SPEC["dye"])
        out.append((M @ (xyz(Ek * rk, wl) * per_Y), M @ (xyz(Ek, wl) * per_Y)))
    out.append((M @ (xyz(E * rho, dense) * per_Y), light))
    return out


def test_pixels_are_the_spectral_model_worked_out_independently():
    images = data.load()["images"]
    size = SPEC["size"]
    rng = np.random.default_rng(11)
    colours = _expected_colours()
    t = (np.arange(size) + 0.5) * 2 / size - 1
    inside = t[None, :] ** 2 + t[:, None] ** 2 < 1
    rows, cols = np.nonzero(inside)
    picks = list(rng.choice(len(rows), 12, replace=False))
    b_s = [_geometry(rows[i], cols[i], size) for i in range(len(rows))]
    picks.append(int(np.argmax([s for _, s in b_s])))             # the highlight's peak
    for panel, (surface, highlight) in enumerate(colours):
        for i in picks:
            b, s = b_s[i]
            want = _srgb_pixel(b * surface + s * highlight).astype(int)
            got = images[panel, rows[i], cols[i]].astype(int)
            assert np.abs(got - want).max() <= 1, (panel, rows[i], cols[i], got, want)
        assert np.all(images[panel][~inside] == 0)
    # colour aliasing, as the notebook says: at n = 9 the highlight itself is off-colour
    peak = picks[-1]
    assert np.abs(images[1, rows[peak], cols[peak]].astype(int)
                  - images[-1, rows[peak], cols[peak]]).max() > 10


def test_figure_draws_the_shipped_pixels():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from course_lib.plots import shading as ps

    art = ps.plot_spectral_spheres()
    try:
        assert [ax.get_title() for ax in art["axes"]] == \
            ["3 samples (RGB)", "9 wavelengths", "16 wavelengths", "converged"]
        for k, image in enumerate(art["images"]):
            np.testing.assert_array_equal(image.get_array(), data.load()["images"][k])
    finally:
        plt.close("all")

