"""Tests of course_lib.shading (Q5) against the exam's numbers, analytic results and laws."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from course_lib import shading as sh

SQ3 = np.sqrt(3.0)

finite = st.floats(-10.0, 10.0, allow_nan=False, allow_infinity=False)
vec3 = arrays(np.float64, (3,), elements=finite).filter(lambda v: np.linalg.norm(v) > 1e-3)
positive = st.floats(0.1, 100.0)


def exam(**changes):
    args = dict(sh.EXAM_Q5B)
    args.update(changes)
    return args


# ------------------------------------------------------------------------------------ the exam


def test_exam_q5b_printed_answer():
    """Q5(b): the printed answer (0.0931, 0.0931, 0.699)."""
    out = sh.phong(**sh.EXAM_Q5B)
    assert out.shape == (3,)
    np.testing.assert_allclose(out, [0.0931, 0.0931, 0.699], atol=5e-4)


def test_exam_q5b_closed_form_terms():
    """Q5(b) worked by hand: L.N = (1 - 1/sqrt3)/2, R.V = (1 + 1/sqrt3)/2, hence the answer."""
    L = sh.normalize(sh.EXAM_Q5B["L"])
    N = np.asarray(sh.EXAM_Q5B["N"])
    V = np.asarray(sh.EXAM_Q5B["V"])
    assert L @ N == pytest.approx(0.5 * (1 - 1 / SQ3))
    assert sh.reflect(L, N) @ V == pytest.approx(0.5 * (1 + 1 / SQ3))
    spec = (0.5 + 0.5 / SQ3) ** 10
    body = 0.5 + 0.25 * (1 - 1 / SQ3)
    np.testing.assert_allclose(sh.phong(**sh.EXAM_Q5B), [spec, spec, spec + body], rtol=1e-12, atol=1e-12)


def test_exam_forgetting_to_normalise_changes_the_answer():
    """The examiners' commonest mistake: with L = (1, -1, 1) unnormalised the raw formula gives
    another answer, while phong (which normalises) is unaffected by the length of L."""
    L = np.array([1.0, -1.0, 1.0])
    N = np.asarray(sh.EXAM_Q5B["N"])
    V = np.asarray(sh.EXAM_Q5B["V"])
    wrong_LN = L @ N
    wrong_RV = (2 * wrong_LN * N - L) @ V
    wrong_blue = 0.5 + 0.5 * wrong_LN + max(wrong_RV, 0) ** 10
    assert abs(wrong_blue - 0.699) > 0.05
    np.testing.assert_allclose(sh.phong(**exam(L=5 * L)), sh.phong(**sh.EXAM_Q5B), rtol=1e-12, atol=1e-12)


# --------------------------------------------------------------------------------- normalize


@given(vec3)
def test_normalize_unit_length(v):
    assert np.linalg.norm(sh.normalize(v)) == pytest.approx(1.0)


@given(vec3, positive)
def test_normalize_scale_invariant_and_parallel(v, s):
    u = sh.normalize(v)
    np.testing.assert_allclose(sh.normalize(s * v), u, atol=1e-12)
    np.testing.assert_allclose(np.cross(u, v), 0.0, atol=1e-9 * np.linalg.norm(v))
    assert u @ v > 0


def test_normalize_batch_and_errors():
    v = np.array([[3.0, 4.0, 0.0], [0.0, 0.0, -2.0]])
    np.testing.assert_allclose(sh.normalize(v), [[0.6, 0.8, 0.0], [0.0, 0.0, -1.0]], atol=1e-12)
    with pytest.raises(ValueError, match="zero-length"):
        sh.normalize([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    with pytest.raises(ValueError):
        sh.normalize(2.0)
    with pytest.raises(ValueError):
        sh.normalize([np.nan, 1.0, 0.0])


# ----------------------------------------------------------------------------------- reflect


@given(vec3, vec3)
def test_reflect_is_an_involution_and_isometry(L, N):
    R = sh.reflect(L, N)
    np.testing.assert_allclose(sh.reflect(R, N), L, atol=1e-9 * (1 + np.linalg.norm(L)))
    assert np.linalg.norm(R) == pytest.approx(np.linalg.norm(L), rel=1e-9)


@given(vec3, vec3)
def test_reflect_angle_of_incidence_equals_angle_of_reflection(L, N):
    """R.N = L.N, R lies in the plane of L and N, and L + R is along N."""
    Lu, Nu = sh.normalize(L), sh.normalize(N)
    R = sh.reflect(Lu, Nu)
    assert R @ Nu == pytest.approx(Lu @ Nu, abs=1e-9)
    assert np.linalg.det(np.stack([Lu, Nu, R])) == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose(np.cross(Lu + R, Nu), 0.0, atol=1e-9)


def test_reflect_known_values_and_batches():
    # a ray coming in at 45 degrees onto the floor goes out at 45 degrees
    np.testing.assert_allclose(sh.reflect([1.0, 1.0, 0.0], [0.0, 1.0, 0.0]), [-1.0, 1.0, 0.0], atol=1e-12)
    # normal incidence: R = L; grazing: R = -L
    np.testing.assert_allclose(sh.reflect([0.0, 0.0, 2.0], [0.0, 0.0, 5.0]), [0.0, 0.0, 2.0], atol=1e-12)
    np.testing.assert_allclose(sh.reflect([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]), [-1.0, 0.0, 0.0], atol=1e-12)
    rng = np.random.default_rng(0)
    L, N = rng.normal(size=(7, 3)), rng.normal(size=(7, 3))
    batch = sh.reflect(L, N)
    assert batch.shape == (7, 3)
    for i in range(7):
        np.testing.assert_allclose(batch[i], sh.reflect(L[i], N[i]), rtol=1e-12, atol=1e-12)
    # one normal for a batch of lights
    assert sh.reflect(L, N[0]).shape == (7, 3)


def test_reflect_errors():
    with pytest.raises(ValueError, match="zero-length"):
        sh.reflect([1.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"\(\.\.\., 3\)"):
        sh.reflect([1.0, 0.0], [0.0, 1.0])


# ----------------------------------------------------------------------------------- halfway


@given(vec3, vec3)
def test_halfway_bisects(L, V):
    Lu, Vu = sh.normalize(L), sh.normalize(V)
    assume(np.linalg.norm(Lu + Vu) > 1e-3)
    H = sh.halfway(L, V)
    assert np.linalg.norm(H) == pytest.approx(1.0)
    assert H @ Lu == pytest.approx(H @ Vu, abs=1e-9)
    assert np.linalg.det(np.stack([Lu, Vu, H])) == pytest.approx(0.0, abs=1e-9)
    # N = H is the mirror normal: reflecting L in it gives V
    np.testing.assert_allclose(sh.reflect(Lu, H), Vu, atol=1e-8)


def test_halfway_errors():
    with pytest.raises(ValueError, match="opposite"):
        sh.halfway([1.0, 2.0, 3.0], [-2.0, -4.0, -6.0])
    with pytest.raises(ValueError, match="zero-length"):
        sh.halfway([0.0, 0.0, 0.0], [0.0, 0.0, 1.0])


# ---------------------------------------------------------------------- phong and blinn-phong


@pytest.mark.parametrize("model", [sh.phong, sh.blinn_phong])
def test_mirror_direction_gives_full_highlight(model):
    """V = reflect(L, N): R = V and H = N, so R.V = N.H = 1 and the specular term is Ip ks."""
    rng = np.random.default_rng(1)
    for _ in range(20):
        N = sh.normalize(rng.normal(size=3))
        L = sh.normalize(rng.normal(size=3))
        if L @ N < 0.05:
            L = sh.reflect(-L, N) if L @ N < -0.05 else sh.normalize(L + N)
        V = sh.reflect(L, N)
        colour = rng.uniform(0, 1, 3)
        Ia, ka, Ip, kd, ks, n = 0.7, 0.3, 1.5, 0.6, 0.4, rng.uniform(1, 100)
        expected = colour * (Ia * ka + Ip * kd * (L @ N)) + Ip * ks
        np.testing.assert_allclose(model(colour, Ia, ka, Ip, kd, ks, n, L, N, V), expected,
                                   rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(sh.halfway(L, V), N, atol=1e-9)


@pytest.mark.parametrize("model", [sh.phong, sh.blinn_phong])
def test_no_specular_at_grazing_or_behind(model):
    """L.N = 0 (grazing) and L.N < 0 (light behind): only the ambient term remains, even when
    the viewer sits (nearly) in the mirror direction."""
    N = np.array([0.0, 0.0, 1.0])
    colour = np.array([0.2, 0.5, 0.9])
    for L, V in (([1.0, 0.0, 0.0], [-1.0, 0.0, 0.01]), ([1.0, 0.0, -0.5], [-1.0, 0.0, -0.5])):
        # exactly 0 by construction: the diffuse factor is clamped with max(L.N, 0)
        assert sh.phong_terms(L, N, sh.reflect(L, N), 1.0)[1] == 0.0
        out = model(colour, 2.0, 0.25, 1.0, 0.8, 1.0, 5, L, N, V)
        np.testing.assert_allclose(out, colour * 0.5, rtol=1e-12, atol=1e-12)


def test_specular_clamped_when_reflection_points_away():
    """R.V < 0 contributes nothing (max(R.V, 0)), not a negative or sign-flipped power."""
    L, N = [0.0, 1.0, 1.0], [0.0, 0.0, 1.0]
    V = -sh.reflect(sh.normalize(L), N)  # R.V = -1
    for n in (2, 3, 2.5):
        out = sh.phong((1, 1, 1), 0, 0, 1, 0, 1, n, L, N, V)
        np.testing.assert_allclose(out, 0.0, atol=1e-15)


def test_coplanar_blinn_angle_is_half():
    """In the plane of L and V, tilting N by t from H turns R by 2t from V:
    R.V = cos 2t while N.H = cos t."""
    L = np.array([np.sin(0.6), 0.0, np.cos(0.6)])
    V = np.array([-np.sin(0.6), 0.0, np.cos(0.6)])
    for t in (0.05, 0.1, 0.2):
        N = np.array([np.sin(t), 0.0, np.cos(t)])
        spec_p = sh.phong(0, 0, 0, 1, 0, 1, 1, L, N, V)[0]
        spec_b = sh.blinn_phong(0, 0, 0, 1, 0, 1, 1, L, N, V)[0]
        assert spec_p == pytest.approx(np.cos(2 * t))
        assert spec_b == pytest.approx(np.cos(t))


@settings(max_examples=50)
@given(vec3, vec3, vec3, positive, positive, positive)
def test_scale_invariance_in_L_N_V(L, N, V, a, b, c):
    """phong and blinn_phong normalise L, N, V themselves."""
    Lu, Vu = sh.normalize(L), sh.normalize(V)
    assume(np.linalg.norm(Lu + Vu) > 1e-3)
    args = ((0.3, 0.6, 0.9), 1.0, 0.2, 1.0, 0.7, 0.5, 8.0)
    for model in (sh.phong, sh.blinn_phong):
        np.testing.assert_allclose(model(*args, a * L, b * N, c * V), model(*args, L, N, V),
                                   rtol=1e-9, atol=1e-12)


def test_batch_equals_one_by_one():
    rng = np.random.default_rng(2)
    L, N, V = (rng.normal(size=(11, 3)) * rng.uniform(0.1, 5, (11, 1)) for _ in range(3))
    colour = rng.uniform(0, 1, (11, 3))
    for model in (sh.phong, sh.blinn_phong):
        batch = model(colour, 1.0, 0.3, 0.9, 0.6, 0.8, 12, L, N, V)
        assert batch.shape == (11, 3)
        for i in range(11):
            one = model(colour[i], 1.0, 0.3, 0.9, 0.6, 0.8, 12, L[i], N[i], V[i])
            np.testing.assert_allclose(batch[i], one, rtol=1e-12, atol=1e-12)
    # one colour for many normals, and many colours for one geometry
    assert sh.phong((1, 0, 0), 1, 0.3, 1, 0.6, 0.8, 12, L[0], N, V[0]).shape == (11, 3)
    assert sh.phong(colour, 1, 0.3, 1, 0.6, 0.8, 12, L[0], N[0], V[0]).shape == (11, 3)
    # a scalar colour is grey
    np.testing.assert_allclose(sh.phong(0.4, 1, 0.3, 1, 0.6, 0.8, 12, L[0], N[0], V[0]),
                               sh.phong((0.4,) * 3, 1, 0.3, 1, 0.6, 0.8, 12, L[0], N[0], V[0]), atol=1e-12)


def test_terms_separately():
    """Each coefficient scales its own term: ambient only, diffuse only (Lambert's cosine)."""
    L, N, V = [0.0, 1.0, 1.0], [0.0, 0.0, 3.0], [1.0, 0.0, 1.0]
    c = np.array([0.1, 0.2, 0.3])
    np.testing.assert_allclose(sh.phong(c, 2.0, 0.5, 1.0, 0.0, 0.0, 5, L, N, V), c * 1.0, atol=1e-12)
    np.testing.assert_allclose(sh.phong(c, 0.0, 0.5, 2.0, 0.5, 0.0, 5, L, N, V),
                               c * np.cos(np.pi / 4), atol=1e-12)


@pytest.mark.parametrize("bad, match", [
    ({"L": (0.0, 0.0, 0.0)}, "zero-length"),
    ({"N": (0.0, 0.0, 0.0)}, "zero-length"),
    ({"V": (0.0, 0.0, 0.0)}, "zero-length"),
    ({"L": (1.0, 0.0)}, "shape"),
    ({"colour": (1.0, 0.0)}, "colour"),
    ({"colour": (-0.1, 0.0, 1.0)}, "colour"),
    ({"n": 0.0}, "n"),
    ({"ks": -1.0}, "ks"),
    ({"ka": (0.1, 0.2)}, "ka"),
])
def test_phong_value_errors(bad, match):
    for model in (sh.phong, sh.blinn_phong):
        with pytest.raises(ValueError, match=match):
            model(**exam(**bad))


def test_blinn_opposite_light_and_viewer():
    with pytest.raises(ValueError, match="opposite"):
        sh.blinn_phong(**exam(V=-np.asarray(sh.EXAM_Q5B["L"])))


# ------------------------------------------------------------------------------ the sphere


def test_sphere_pixels_match_hand_computed_normals():
    """Looking down z (right = x, up = y): pixel (r, c) sees N = (x, y, sqrt(1 - x^2 - y^2))."""
    size = 32
    img, _ = sh.render_sphere((0.2, 0.4, 0.8), 1.0, 0.2, 1.0, 0.7, 0.6, 15,
                              (1.0, 2.0, 3.0), (0.0, 0.0, 1.0), size=size, background=-1.0)
    rng = np.random.default_rng(3)
    for r, c in rng.integers(0, size, (40, 2)):
        x = (c + 0.5) / size * 2 - 1
        y = 1 - (r + 0.5) / size * 2
        if x * x + y * y >= 1:
            np.testing.assert_array_equal(img[r, c], -1.0)
            continue
        N = np.array([x, y, np.sqrt(1 - x * x - y * y)])
        np.testing.assert_allclose(img[r, c], sh.phong((0.2, 0.4, 0.8), 1.0, 0.2, 1.0, 0.7,
                                                       0.6, 15, (1.0, 2.0, 3.0), N,
                                                       (0.0, 0.0, 1.0)), rtol=1e-12, atol=1e-12)


def _random_light_viewer(rng):
    while True:
        L, V = rng.normal(size=3), rng.normal(size=3)
        L, V = L / np.linalg.norm(L), V / np.linalg.norm(V)
        if L @ V > -0.8:
            return L, V


@pytest.mark.parametrize("model", ["Phong", "Blinn-Phong"])
def test_sphere_highlight_at_analytic_position(model):
    """Both peaks sit where N = H: R = V there (Phong) and N.H = 1 (Blinn). The rendered
    argmax must be within a pixel and a half of the projection of H."""
    rng = np.random.default_rng(4)
    for _ in range(15):
        L, V = _random_light_viewer(rng)
        _, (r, c) = sh.render_sphere((1, 1, 1), 0, 0, 1, 0, 1, 60, L, V, size=96, model=model)
        # independent oracle: project H on the screen by the pixel formula
        H = (L + V) / np.linalg.norm(L + V)
        basis = sh.view_basis(V)
        np.testing.assert_allclose(np.cross(basis[0], basis[1]), V, atol=1e-12)
        x, y = H @ basis[0], H @ basis[1]
        assert np.hypot(r - ((1 - y) * 48 - 0.5), c - ((x + 1) * 48 - 0.5)) <= 1.5
        assert np.allclose(sh.highlight_pixel(L, V, 96), ((1 - y) * 48 - 0.5, (x + 1) * 48 - 0.5))


def test_sphere_highlight_none_when_light_behind():
    """Light straight behind the sphere: nothing visible is lit, so no highlight."""
    img, hl = sh.render_sphere((1, 0, 0), 1, 0.1, 1, 0.8, 1, 10, (0, 0, -1), (0, 0, 1), size=24)
    assert hl is None
    disc = img[img[..., 0] > 0]
    assert len(disc) > 300
    np.testing.assert_allclose(disc, np.broadcast_to([0.1, 0.0, 0.0], disc.shape), atol=1e-12)


def test_sphere_phong_highlight_tighter_than_blinn_same_exponent():
    """Viewer and light 90 degrees apart: near the peak R.V ~ cos 2t against N.H ~ cos t, so
    fewer pixels exceed half the peak under Phong (about a quarter of Blinn's area)."""
    args = ((1, 1, 1), 0, 0, 1, 0, 1, 40, (1, 0, 1), (0, 0, 1))
    p, _ = sh.render_sphere(*args, size=128, model="Phong")
    b, _ = sh.render_sphere(*args, size=128, model="Blinn-Phong")
    area_p, area_b = np.sum(p[..., 0] > 0.5), np.sum(b[..., 0] > 0.5)
    assert 0 < area_p < area_b
    assert 0.15 < area_p / area_b < 0.45


def test_view_basis_is_right_handed_and_orthonormal():
    rng = np.random.default_rng(5)
    for V in list(rng.normal(size=(10, 3))) + [np.array([0.0, 0.0, 2.0])]:
        B = sh.view_basis(V)
        np.testing.assert_allclose(B @ B.T, np.eye(3), atol=1e-12)
        assert np.linalg.det(B) == pytest.approx(1.0)
        np.testing.assert_allclose(B[2], V / np.linalg.norm(V), atol=1e-12)


def test_render_errors():
    with pytest.raises(ValueError, match="size"):
        sh.render_sphere((1, 1, 1), 1, 0.1, 1, 0.5, 0.5, 10, (0, 0, 1), (0, 0, 1), size=1)
    with pytest.raises(ValueError, match="model"):
        sh.render_sphere((1, 1, 1), 1, 0.1, 1, 0.5, 0.5, 10, (0, 0, 1), (0, 0, 1), model="x")
    with pytest.raises(ValueError, match="colour"):
        sh.render_sphere(((1, 1, 1), (1, 1, 1)), 1, 0.1, 1, 0.5, 0.5, 10, (0, 0, 1), (0, 0, 1))


# ------------------------------------------------------------------------------ the figures


def test_figures_draw_what_the_maths_says():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from course_lib import spectral
    from course_lib.plots import shading as ps

    art = ps.plot_reflection_vectors(incidence_deg=30.0, view_deg=-10.0)
    # the R arrow ends at the mirror image of L: (sin 30, cos 30), drawn to 1e-4
    np.testing.assert_allclose(art["R"][0].xy, (np.sin(np.radians(30)), np.cos(np.radians(30))),
                               rtol=0, atol=0.5e-4 + 1e-12)
    plt.close("all")

    L, V = (1.0, -1.0, 1.0), (0.0, -1.0, 0.2)
    art = ps.sphere_pair((0.2, 0.3, 1.0), 1, 0.2, 1, 0.6, 0.8, 40, L, V, size=64)
    Lu, Vu = np.array(L) / np.sqrt(3), np.array(V) / np.linalg.norm(V)
    H = (Lu + Vu) / np.linalg.norm(Lu + Vu)
    B = sh.view_basis(V)
    for k in (0, 1):    # the cross to 0.01 pixel, the image 8-bit
        assert art["analytic"][k].get_xdata()[0] == pytest.approx((H @ B[0] + 1) * 32 - 0.5,
                                                                  abs=0.005 + 1e-9)
        assert art["analytic"][k].get_ydata()[0] == pytest.approx((1 - H @ B[1]) * 32 - 0.5,
                                                                  abs=0.005 + 1e-9)
        assert art["images"][k].get_array().shape == (64, 64, 3)
        assert art["images"][k].get_array().dtype == np.uint8
    plt.close("all")

    cases = ps.ALIASING_CASES[-1:]
    art = ps.plot_aliasing_swatches(cases, ns=(9,))
    _, err = spectral.colour_aliasing(cases[0][1], cases[0][2], (9,))
    np.testing.assert_allclose(art["errors"][0], err, atol=1e-12)
    assert art["image"].get_array().shape == (1, 3, 3)
    plt.close("all")


@pytest.mark.parametrize("incidence, view", [(40.0, -15.0), (30.0, -10.0), (-25.0, 60.0),
                                             (0.0, 0.0), (80.0, 5.0)])
def test_drawn_vectors_are_the_plane_geometry_to_display_precision(incidence, view):
    """Q5(a) in the plane of incidence: R is L mirrored about the vertical normal (the angle
    of reflection equals the angle of incidence) and H is at the mean of the two angles; the
    figure gets them to 1e-4 and no finer."""
    from course_lib.plots import shading as ps

    got = ps.drawn_vectors(incidence, view)
    t, p = np.radians(incidence), np.radians(view)
    want = {"N": (0.0, 1.0, 0.0), "L": (-np.sin(t), np.cos(t), 0.0),
            "V": (-np.sin(p), np.cos(p), 0.0), "R": (np.sin(t), np.cos(t), 0.0),
            "H": (-np.sin((t + p) / 2), np.cos((t + p) / 2), 0.0)}
    for name, v in want.items():
        np.testing.assert_allclose(got[name], v, rtol=0, atol=0.5e-4 + 1e-12, err_msg=name)
        np.testing.assert_array_equal(got[name], np.round(got[name], 4), err_msg=name)
