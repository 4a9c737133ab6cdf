"""The variant self-test gate: every student's numbers measure the item, not the examiners'
named mistakes.

For 10,000 ids per notebook this checks, with arithmetic written here, each generator's
conditions (well posed, not degenerate, the asked quantity not read off without the item's
arithmetic), and for every mistake the notebook or its rubric names it computes the mistaken
answer with code of its own and asserts that the grader's own rule for the item (the number
items' tolerance, 0.5 % or 0.001) rejects it, while the course reference's answer passes.

Oracles: the course references (``course_lib.ultrasound``, ``gamma_camera``, ``marching_cubes``,
``splines``, ``shading``, ``clipping``) for the right answers; independent NumPy here for the
mistaken ones.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from autograder.exercises import REGISTRY
from autograder.exercises.base import NUMBER_ATOL, NUMBER_RTOL
from course_lib import clipping, gamma_camera, shading, splines, ultrasound
from course_lib import marching_cubes as mc
from course_lib import variants as variants_module
from course_lib.variants import NOTEBOOKS, problems, variant

IDS = [f"s{k:05d}" for k in range(10_000)]


@pytest.fixture(scope="module")
def numbers():
    """Each notebook's numbers for the 10,000 ids, drawn once (and kept under ``.cache/`` until
    ``course_lib/variants.py``, a pure function of notebook and id, changes)."""
    from diskcache import cached

    return cached("variant-numbers", [Path(variants_module.__file__)],
                  lambda: {nb: [variant(nb, sid).numbers for sid in IDS] for nb in NOTEBOOKS})


def _rejected(item: str, expected, mistaken) -> bool:
    """The grader's rule for ``item`` calls ``mistaken`` a wrong value."""
    why = REGISTRY[item].compare(expected, mistaken)
    return why is not None and why.kind == "wrong-value"


def _accepted(item: str, expected, answer) -> bool:
    return REGISTRY[item].compare(expected, answer) is None


def _plain(x):
    x = np.asarray(x, dtype=float)
    return float(x) if x.ndim == 0 else x


def _rejected_all(item: str, expected, mistaken, sample: int = 300) -> np.ndarray:
    """Per id, whether the item's tolerance rejects ``mistaken`` (arrays over the ids), computed
    at once; on the first ``sample`` ids the grader's own rule is asked too and must agree."""
    e, m = np.asarray(expected, dtype=float), np.asarray(mistaken, dtype=float)
    near = np.abs(m - e) <= NUMBER_ATOL + NUMBER_RTOL * np.abs(e)
    rejected = ~near.reshape(len(e), -1).all(axis=1)
    for k in range(min(sample, len(e))):
        assert _rejected(item, _plain(e[k]), _plain(m[k])) == rejected[k], (item, IDS[k])
    return rejected


def _assert_all(flags, what: str) -> None:
    flags = np.asarray(flags, dtype=bool)
    bad = [IDS[k] for k in np.flatnonzero(~flags)[:5]]
    assert flags.all(), f"{what}: fails for {int((~flags).sum())} of {len(flags)} ids, e.g. {bad}"


@pytest.mark.parametrize("notebook", NOTEBOOKS)
def test_every_draw_meets_its_own_stated_conditions(numbers, notebook):
    _assert_all([not problems(notebook, v) for v in numbers[notebook]],
                f"{notebook}: the generator's conditions")


# --------------------------------------------------------------------------------- Q1(c)

def test_q1_speeds_keep_the_table_order_and_the_mistakes_fail(numbers):
    rows = numbers["q1_imaging"]
    T = np.array([v["thicknesses"] for v in rows])
    c = np.array([v["speeds"] for v in rows])
    tissues = [v["tissues"] for v in rows]
    assert np.all(T > 0) and np.all(c > 0)
    # only the materials of the notebook's table, ranked by its speeds (fat slowest); no two
    # layers share a speed
    nominal = {name: ultrasound.MATERIALS[name]["c"] for name in ("water", "fat", "liver")}
    _assert_all([set(t) <= set(nominal) for t in tissues], "Q1(c) only the table's materials")
    order_kept = [all((nominal[a] < nominal[b]) == (ca < cb) for a, ca in zip(t, s)
                      for b, cb in zip(t, s) if a != b) for t, s in zip(tissues, c)]
    _assert_all(order_kept, "Q1(c) the speeds follow the table's order")
    _assert_all([all(cf < co for tf, cf in zip(t, s) for to, co in zip(t, s)
                     if tf == "fat" and to != "fat") for t, s in zip(tissues, c)],
                "Q1(c) fat is the slowest layer")
    _assert_all(np.all(np.diff(c, axis=1) != 0, axis=1), "Q1(c) adjacent layers differ")
    right = np.array([ultrasound.displayed_depths(t, s) for t, s in zip(T, c)])
    mistakes = {"speed ratio inverted (T c / 1540)": np.cumsum(T * c / 1540.0, axis=1),
                "no correction (T as it is)": np.cumsum(T, axis=1)}
    _assert_all(~_rejected_all("q1c_your_depths", right, np.cumsum(T * 1540.0 / c, axis=1)),
                "Q1(c) the arithmetic written here passes")
    for what, wrong in mistakes.items():
        _assert_all(_rejected_all("q1c_your_depths", right, wrong), f"Q1(c) mistake '{what}'")


# --------------------------------------------------------------------------------- Q2(c), (d)

def test_q2c_length_mistakes_fail(numbers):
    rows = numbers["q2_nuclear"]
    d, R, z = (np.array([v[k] for v in rows]) for k in ("d", "R", "z"))
    assert np.all(R > d) and np.all(d > 0) and np.all(z > 0)
    right = np.array([gamma_camera.collimator_length_for_resolution(*x) for x in zip(d, R, z)])
    mistakes = {"cone measured from the face (R = d z / L)": d * z / R,
                "widths and distances swapped (L = z (R - d) / d)": z * (R - d) / d,
                "R + d for R - d": d * z / (R + d)}
    for what, wrong in mistakes.items():
        _assert_all(_rejected_all("q2c_your_length", right, wrong), f"Q2(c) mistake '{what}'")


def _q2d_fraction(v, cutoff, holes_per_ring=lambda k: 8 * k):
    """Open area / face area of the ring collimator, counted here ring by ring."""
    n_open = 1 + sum(holes_per_ring(k) for k in range(1, v["rings"] + 1)
                     if k * v["pitch"] <= cutoff)
    return n_open * (v["hole_d"] / 2) ** 2 / ((v["rings"] + 1) * v["pitch"]) ** 2


def test_q2d_cutoff_and_fraction_discriminate(numbers):
    rows = numbers["q2_nuclear"]
    cut = np.array([v["hole_d"] * v["source_distance"] / v["hole_L"] for v in rows])
    pitch = np.array([v["pitch"] for v in rows])
    rings = np.array([v["rings"] for v in rows])
    k_open = np.floor(cut / pitch)
    _assert_all((k_open >= 2) & (k_open < rings), "Q2(d) some rings open, some closed")
    # the hole-centre rule r L / z <= d decides nothing at the boundary: a strict < gives the
    # same holes
    _assert_all(np.abs(cut / pitch - np.round(cut / pitch)) >= 0.2 - 1e-9,
                "Q2(d) the cut-off well away from every ring")
    right = 100 * np.array([gamma_camera.open_fraction(
        gamma_camera.ring_hole_positions(v["pitch"], v["rings"]), v["hole_d"], v["hole_L"],
        v["source_distance"], (v["rings"] + 1) * v["pitch"]) for v in rows])
    _assert_all(np.isclose(right, [100 * _q2d_fraction(v, c) for v, c in zip(rows, cut)],
                           rtol=1e-12, atol=0), "Q2(d) the reference agrees with ring counting")
    inverted = np.array([v["hole_d"] * v["hole_L"] / v["source_distance"] for v in rows])
    _assert_all(_rejected_all("q2d_your_cutoff", cut, inverted), "Q2(d) mistake 'L / z for z / L'")
    reference_cut = [gamma_camera.exam_cutoff_radius(v["hole_d"], v["hole_L"],
                                                     v["source_distance"]) for v in rows]
    _assert_all(np.isclose(reference_cut, cut, rtol=1e-12), "Q2(d) the reference's cut-off")
    mistakes = {
        "8 holes on every ring": [_q2d_fraction(v, c, lambda k: 8) for v, c in zip(rows, cut)],
        "every hole open": [_q2d_fraction(v, np.inf) for v in rows],
        "the diameter taken as the radius": [4 * r / 100 for r in right],
        "the face radius taken as rings x pitch": [
            r / 100 * ((v["rings"] + 1) / v["rings"]) ** 2 for r, v in zip(right, rows)],
        "one ring too many open": [_q2d_fraction(v, c + v["pitch"]) for v, c in zip(rows, cut)],
        "one ring too few open": [_q2d_fraction(v, c - v["pitch"]) for v, c in zip(rows, cut)],
    }
    _assert_all(_rejected_all("q2d_your_percent", right, right / 100),
                "Q2(d) mistake 'a fraction for the percentage'")
    for what, wrong in mistakes.items():
        _assert_all(_rejected_all("q2d_your_percent", right, 100 * np.array(wrong)),
                    f"Q2(d) mistake '{what}'")


# --------------------------------------------------------------------------------- Q3(a)

def test_q3a_vertex_and_case_mistakes_fail(numbers):
    rows = numbers["q3_marching_cubes"]
    p0, p1 = (np.array([v[k] for v in rows]) for k in ("p0", "p1"))
    v0, v1, iso = (np.array([v[k] for v in rows]) for k in ("v0", "v1", "iso"))
    assert np.all((np.minimum(v0, v1) < iso) & (iso < np.maximum(v0, v1)))
    right = np.array([mc.interpolate_edge(a, b, x, y, s)
                      for a, b, x, y, s in zip(p0, p1, v0, v1, iso)])
    t = ((iso - v0) / (v1 - v0))[:, None]
    mistakes = {"the mid-point": (p0 + p1) / 2, "the fraction from the wrong end":
                p0 + (1 - t) * (p1 - p0), "the end nearer the iso-level":
                np.where(np.abs(v0 - iso)[:, None] < np.abs(v1 - iso)[:, None], p0, p1)}
    _assert_all(~_rejected_all("q3a_your_vertex", right, p0 + t * (p1 - p0)),
                "Q3(a) interpolation written here passes")
    for what, wrong in mistakes.items():
        _assert_all(_rejected_all("q3a_your_vertex", right, wrong), f"Q3(a) mistake '{what}'")
    corners = np.array([v["corner_values"] for v in rows])
    below = corners < iso[:, None]
    _assert_all(below.any(axis=1) & ~below.all(axis=1), "Q3(a) the cell is cut")
    _assert_all(~np.any(corners == iso[:, None], axis=1), "Q3(a) no corner on the iso-level")
    cases = [int(mc.cube_index(c, s)) for c, s in zip(corners, iso)]
    above_bits = (~below * (1 << np.arange(8))).sum(axis=1)
    _assert_all([_rejected("q3a_your_case", k, int(m)) for k, m in zip(cases, above_bits)],
                "Q3(a) mistake 'bit set for corners above the iso-level'")


# --------------------------------------------------------------------------------- Q4(c)(i)

_CR = 0.5 * np.array([[-1, 3, -3, 1], [2, -5, 4, -1], [-1, 0, 1, 0], [0, 2, 0, 0]], float)
_BS = np.array([[-1, 3, -3, 1], [3, -6, 3, 0], [-3, 0, 3, 0], [1, 4, 1, 0]], float) / 6


def _end(M, G, t=1.0):
    """p, p', p'' at t of segments with bases M (ids, 4, 4) and geometries G (ids, 4, 2)."""
    rows = np.array([[t**3, t**2, t, 1], [3 * t**2, 2 * t, 1, 0], [6 * t, 2, 0, 0]])
    return np.einsum("rk,ikl,ilj->irj", rows, M, G)


def test_q4ci_cases_need_arithmetic_and_the_mistakes_fail(numbers):
    rows = numbers["q4_splines"]
    a, b, c = (np.array([v[k] for v in rows], float) for k in "abc")
    kind = np.array([v["kind"] for v in rows])
    rule = np.array([v["rule"] for v in rows])
    cross = (b - a)[:, 0] * (c - b)[:, 1] - (b - a)[:, 1] * (c - b)[:, 0]
    _assert_all(cross != 0, "Q4(c)(i) a, b, c not on one line")
    _assert_all((kind != "b-spline") | (rule != "d=2c-b"), "Q4(c)(i) not the (c, c - b, 0) case")
    _assert_all((kind != "catmull-rom") | (rule != "d=b"), "Q4(c)(i) not the (c, 0, p'') case")
    assert set(zip(kind, rule)) == {("catmull-rom", "d=2c-b"), ("b-spline", "d=b")}
    right = np.array([splines.end_derivatives(
        splines.catmull_rom_basis() if v["kind"] == "catmull-rom" else splines.bspline_basis(),
        *(np.array(v[k], float) for k in "abc"),
        splines.phantom_point(np.array(v["b"], float), np.array(v["c"], float), v["rule"]))
        for v in rows])
    is_cr = (kind == "catmull-rom")[:, None, None]
    M, other = np.where(is_cr, _CR, _BS), np.where(is_cr, _BS, _CR)
    phantoms = {"d=b": b, "d=2c-b": 2 * c - b, "d=c": c}
    d = np.where((rule == "d=b")[:, None], b, 2 * c - b)
    G = np.stack([a, b, c, d], axis=1)
    _assert_all(~_rejected_all("q4ci_your_end", right, _end(M, G)),
                "Q4(c)(i) the matrices written here pass")
    mistakes = {"the other spline's basis": _end(other, G),
                "the segment's start (t = 0) for its end": _end(M, G, 0.0),
                "the geometry read from the other end, [d; c; b; a]": _end(M, G[:, ::-1])}
    for name, phantom in phantoms.items():
        wrong = _end(M, np.stack([a, b, c, phantom], axis=1))
        mistakes[f"the rule {name}"] = np.where((rule == name)[:, None, None], np.nan, wrong)
    # the Catmull-Rom d = b reading: the end at c, at rest (p = c, p' = 0), p'' right
    at_rest = right.copy()
    at_rest[:, 0], at_rest[:, 1] = c, 0.0
    mistakes["an end at c at rest, p(1) = c and p'(1) = 0"] = at_rest
    # p'(1) = 0 alone is right only for the B-spline with d = b (where p(1) = (b + 2c) / 3 and
    # p''(1) = 2 (b - c) still need the arithmetic): it fails every Catmull-Rom end
    zero_velocity = right.copy()
    zero_velocity[:, 1] = 0.0
    mistakes["p'(1) = 0 for a Catmull-Rom end"] = np.where(is_cr, zero_velocity, np.nan)
    for what, wrong in mistakes.items():
        # NaN marks the student's own rule: no mistake to check there
        flags = _rejected_all("q4ci_your_end", right, np.nan_to_num(wrong, nan=1e9))
        _assert_all(flags, f"Q4(c)(i) mistake '{what}'")


# --------------------------------------------------------------------------------- Q5(b)

def _unit(x):
    return x / np.linalg.norm(x, axis=-1, keepdims=True)


def _mistaken_phong(q, unit_L=True, unit_N=True, unit_V=True, specular=True,
                    coloured_highlight=False):
    """The Phong model, over all ids at once, as a student with one of the rubric's mistakes
    evaluates it (``q``: arrays over the ids)."""
    N = _unit(q["N"]) if unit_N else q["N"]
    L = _unit(q["L"]) if unit_L else q["L"]
    V = _unit(q["V"]) if unit_V else q["V"]
    ln = np.sum(L * N, axis=1)
    rv = np.sum((2 * ln[:, None] * N - L) * V, axis=1)
    spec = q["Ip"] * q["ks"] * np.maximum(rv, 0.0) ** q["n"] * (ln > 0) * specular
    body = q["colour"] * (q["Ia"] * q["ka"] + q["Ip"] * q["kd"] * np.maximum(ln, 0.0))[:, None]
    return body + (q["colour"] * spec[:, None] if coloured_highlight else spec[:, None])


def test_q5b_numbers_discriminate_the_rubrics_mistakes(numbers):
    rows = numbers["q5_phong"]
    q = {k: np.array([v[k] for v in rows], float) for k in rows[0]}
    for name in "NLV":
        _assert_all(np.abs(np.linalg.norm(q[name], axis=1) - 1) > 0.1,
                    f"Q5(b) {name} is not a unit vector")
    Nu, Lu, Vu = _unit(q["N"]), _unit(q["L"]), _unit(q["V"])
    _assert_all(np.sum(Lu * Nu, axis=1) > 0.2, "Q5(b) the light in front of the surface")
    _assert_all(np.sum(Vu * Nu, axis=1) > 0.2, "Q5(b) the viewer in front of the surface")
    right = np.array([shading.phong(np.array(v["colour"]), v["Ia"], v["ka"], v["Ip"], v["kd"],
                                    v["ks"], v["n"], np.array(v["L"]), np.array(v["N"]),
                                    np.array(v["V"])) for v in rows])
    _assert_all(np.all((right >= 0) & (right <= 1), axis=1), "Q5(b) every channel in [0, 1]")
    _assert_all(~_rejected_all("q5b_your_intensity", right, _mistaken_phong(q)),
                "Q5(b) the model written here passes")
    mistakes = {"L not normalised": dict(unit_L=False), "N not normalised": dict(unit_N=False),
                "V not normalised": dict(unit_V=False),
                "nothing normalised": dict(unit_L=False, unit_N=False, unit_V=False),
                "no specular term": dict(specular=False),
                "the highlight coloured by c": dict(coloured_highlight=True)}
    for what, how in mistakes.items():
        _assert_all(_rejected_all("q5b_your_intensity", right, _mistaken_phong(q, **how)),
                    f"Q5(b) mistake '{what}'")


# --------------------------------------------------------------------------------- Q6(b)

def test_q6b_inequalities_decide_and_the_mistakes_fail(numbers):
    P = np.array([v["vertices"] for v in numbers["q6_clipping"]], float)    # (ids, 3, 4)
    X, Y, Z, w = np.moveaxis(P, -1, 0)
    inside = (np.abs(X) <= w) & (np.abs(Y) <= w) & (Z >= 0) & (Z <= w) & (w > 0)
    strict = (np.abs(X) < w) & (np.abs(Y) < w) & (Z > 0) & (Z < w)
    _assert_all(strict.any(axis=1), "Q6(b) a vertex strictly inside (not the boundary rule alone)")
    _assert_all((inside & ~strict).any(axis=1), "Q6(b) a vertex on a boundary plane")
    _assert_all(~inside.all(axis=1), "Q6(b) a vertex outside")
    for sid, p, s, ins in zip(IDS, P, strict, inside):
        right = clipping.inside_view_volume(p)
        assert np.array_equal(right, ins), sid
        assert _rejected("q6bi_your_inside", right, tuple(bool(x) for x in s)), \
            f"{sid}: strict inequalities pass"
        assert len(clipping.clip_polygon(p)) >= 3, f"{sid}: clips to nothing"
        screen = clipping.to_screen(p)
        assert _rejected("q6bii_your_screen", screen, p[:, :3]), f"{sid}: no divide passes"
