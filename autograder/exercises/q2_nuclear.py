"""Q2: the photomultiplier tube and the parallel-hole collimator (notebook ``q2_nuclear``).

Five graded functions (``course_lib.gamma_camera``) and the multiple-choice items of Q2(a)-(d).
Visible cases of Q2(c) use other numbers than the question's (1 mm holes resolving 2 mm at 200 mm
are 200 mm long: the students derive that in a written answer); hidden cases vary d, L and z.
Q2(d)'s visible cases carry the exam's numbers as reconstructed in the notebook: a 50 mm-radius
collimator of 1 mm holes 40 mm long on rings 10 mm apart, source on axis at 1 m: 25 holes open,
0.25 %. Hidden cases are drawn from ``rng`` alone; bad input must raise ``ValueError``.
"""

from __future__ import annotations

import numpy as np

from course_lib import gamma_camera

from ..model import CellKind
from .base import Case, Exercise, close, number_item, up_to, wrong_shape, wrong_value

NB = "q2_nuclear"
_REL = close(rtol=1e-9, atol=1e-12)


# --------------------------------------------------------------------------------- pmt_gain


def _pmt_gain_cases(rng):
    yield Case(args=(4.0, 10), label="typical tube: delta = 4, 10 dynodes", visible=True)
    yield Case(args=(2.0, 3), label="delta = 2, 3 dynodes: 8 electrons", visible=True)
    yield Case(args=(5.0, 0), label="no dynodes: gain 1", visible=True)
    for _ in range(6):
        yield Case(args=(float(rng.uniform(1.5, 7.0)), int(rng.integers(1, 15))),
                   label="random delta and number of dynodes")
    yield Case(args=(float(rng.uniform(0.2, 0.9)), int(rng.integers(2, 8))),
               label="delta below 1 (each stage loses electrons)")
    yield Case(args=(0.0, 10), label="delta = 0", raises=ValueError)
    yield Case(args=(-4.0, 10), label="negative delta", raises=ValueError)
    yield Case(args=(4.0, 2.5), label="non-integer number of dynodes", raises=ValueError)
    yield Case(args=(4.0, -1), label="negative number of dynodes", raises=ValueError)


# --------------------------------------------------------------------- collimator_resolution


def _resolution_cases(rng):
    yield Case(args=(1.5, 30.0, 100.0), label="d = 1.5 mm, L = 30 mm, z = 100 mm: R = 6.5 mm",
               visible=True)
    yield Case(args=(1.0, 200.0, 0.0), label="source on the face: R = d", visible=True)
    yield Case(args=(1.0, 40.0, 1000.0), label="Q2(d)'s collimator, source at 1 m", visible=True)
    for _ in range(6):
        d = float(rng.uniform(0.5, 4.0))
        yield Case(args=(d, float(rng.uniform(10.0, 80.0)), float(rng.uniform(0.0, 300.0))),
                   label="random hole and distance")
    yield Case(args=(0.0, 40.0, 100.0), label="d = 0", raises=ValueError)
    yield Case(args=(1.0, -40.0, 100.0), label="negative L", raises=ValueError)
    yield Case(args=(1.0, 0.0, 100.0), label="L = 0", raises=ValueError)
    yield Case(args=(1.0, 40.0, -10.0), label="source behind the face (z < 0)",
               raises=ValueError)


def _length_cases(rng):
    yield Case(args=(2.0, 3.0, 150.0), label="2 mm holes, 3 mm at 150 mm -> 300 mm",
               visible=True)
    yield Case(args=(1.0, 26.0, 1000.0), label="Q2(d)'s source: 26 mm at 1 m -> 40 mm",
               visible=True)
    for _ in range(6):
        d = float(rng.uniform(0.5, 4.0))
        yield Case(args=(d, d * float(rng.uniform(1.05, 10.0)), float(rng.uniform(5.0, 500.0))),
                   label="random requirement")
    yield Case(args=(1.0, 1.0, 100.0), label="R = d: no finite length", raises=ValueError)
    yield Case(args=(2.0, 1.5, 100.0), label="R < d", raises=ValueError)
    yield Case(args=(-1.0, 2.0, 100.0), label="negative d", raises=ValueError)


# ----------------------------------------------------------------------- ring_hole_positions


def _same_points(tol=1e-9):
    """Compare two ``(N, 2)`` point sets up to the order of the points.

    The contract fixes where the holes are (the centre, then ``8k`` on radius ``k * pitch``, the
    first at angle 0) but not which way round a ring is listed, so any order is accepted.
    """

    def rule(expected, received):
        if not isinstance(received, np.ndarray):
            return wrong_shape(f"wrong type (expected an (N, 2) array, got {type(received).__name__})")
        e = np.asarray(expected, dtype=float)
        r = np.asarray(received, dtype=float)
        if r.shape != e.shape:
            return wrong_shape(f"wrong shape (expected {e.shape}, got {r.shape})")
        if not np.all(np.isfinite(r)):
            return wrong_value("wrong value (NaN or inf in the answer)")
        if e.size == 0:
            return None
        scale = max(1.0, float(np.abs(e).max()))
        dist = np.hypot(*(e[:, None, :] - r[None, :, :]).transpose(2, 0, 1))
        nearest = dist.argmin(axis=1)
        missing = dist[np.arange(len(e)), nearest] > tol * scale
        if np.any(missing):
            x, y = e[np.flatnonzero(missing)[0]]
            return wrong_value(f"no hole at ({x:.4g}, {y:.4g}) ({int(missing.sum())} holes missing)")
        if len(np.unique(nearest)) != len(e):
            return wrong_value("some holes are repeated")
        return None

    rule.__doc__ = "the same set of points, in any order, within 1e-9 (relative)"
    return up_to("the order of the points")(rule)


def _ring_cases(rng):
    yield Case(args=(10.0, 2), label="exam Q2(d): centre, 8 and 16 holes (25)", visible=True)
    yield Case(args=(10.0, 4), label="Q2(d)'s face: four rings, 81 holes", visible=True)
    yield Case(args=(2.5, 0), label="no rings: only the centre hole", visible=True)
    for _ in range(4):
        yield Case(args=(float(rng.uniform(0.5, 20.0)), int(rng.integers(1, 8))),
                   label="random pitch and number of rings")
    yield Case(args=(0.0, 2), label="pitch = 0", raises=ValueError)
    yield Case(args=(-1.0, 2), label="negative pitch", raises=ValueError)
    yield Case(args=(10.0, -1), label="n_rings < 0", raises=ValueError)
    yield Case(args=(10.0, 1.5), label="non-integer n_rings", raises=ValueError)


# ----------------------------------------------------------------------------- open_fraction


def _open_fraction_cases(rng):
    exam_holes = gamma_camera.ring_hole_positions(10.0, 4)
    yield Case(args=(exam_holes, 1.0, 40.0, 1000.0, 50.0),
               label="exam Q2(d): 25 of 81 holes open, 19.635 / 7853.98 = 0.25 %", visible=True)
    yield Case(args=(exam_holes, 1.0, 40.0, 300.0, 50.0),
               label="source at 30 cm: only the centre hole (cut-off 7.5 mm)", visible=True)
    yield Case(args=(exam_holes, 1.0, 40.0, 1e5, 50.0),
               label="very distant source: all 81 holes", visible=True)
    # d a power of two, so that r L / z = 25 d * 40 / 1000 = d holds exactly in floating point
    d = float(rng.choice([0.5, 1.0, 2.0]))
    yield Case(args=(np.array([[25.0, 0.0], [0.0, -25.0], [30.0, 0.0]]) * d, d, 40.0, 1000.0,
                     float(rng.uniform(40.0, 80.0)) * d),
               label="holes exactly on the cut-off r L / z = d count as open")
    for _ in range(4):
        pitch = float(rng.uniform(2.0, 12.0))
        n = int(rng.integers(1, 7))
        d = float(rng.uniform(0.5, 0.45 * pitch))
        yield Case(args=(gamma_camera.ring_hole_positions(pitch, n), d,
                         float(rng.uniform(10.0, 80.0)), float(rng.uniform(100.0, 3000.0)),
                         (n + 1) * pitch), label=f"random ring collimator, {n} rings")
    for _ in range(3):
        m = int(rng.integers(5, 60))
        holes = rng.uniform(-40.0, 40.0, size=(m, 2))
        yield Case(args=(holes, float(rng.uniform(0.5, 3.0)), float(rng.uniform(10.0, 60.0)),
                         float(rng.uniform(200.0, 2000.0)), 60.0),
                   label=f"{m} holes at random places")
    good = (exam_holes, 1.0, 40.0, 1000.0, 50.0)
    yield Case(args=(np.zeros((4, 3)),) + good[1:], label="holes of shape (4, 3)",
               raises=ValueError)
    for i, name in ((1, "d"), (2, "L"), (3, "source_distance"), (4, "collimator_radius")):
        bad = list(good)
        bad[i] = 0.0 if i != 2 else -40.0
        yield Case(args=tuple(bad), label=f"non-positive {name}", raises=ValueError)


# ----------------------------------------------------------------------------- the registry


def _function(name, reference, cases, description, compare=_REL):
    return Exercise(name=name, notebook=NB, reference=reference,
                    cases=cases, compare=compare,
                    description=description)


_ABCD = ("a", "b", "c", "d")

EXERCISES = [
    _function("pmt_gain", gamma_camera.pmt_gain, _pmt_gain_cases,
              "Q2(a) electrons at the anode per photo-electron, delta ** n"),
    _function("collimator_resolution", gamma_camera.collimator_resolution, _resolution_cases,
              "Q2(c) R = d (L + z) / L by similar triangles"),
    _function("collimator_length_for_resolution", gamma_camera.collimator_length_for_resolution,
              _length_cases, "Q2(c) L = d z / (R - d); ValueError when R <= d"),
    _function("ring_hole_positions", gamma_camera.ring_hole_positions, _ring_cases,
              "Q2(d) centre hole plus rings of 8k holes at radius k * pitch",
              compare=_same_points()),
    _function("open_fraction", gamma_camera.open_fraction, _open_fraction_cases,
              "Q2(d) all-or-nothing model: open area / face area"),
    # Q2(a): why each dynode is more positive than the last
    Exercise(name="q2_item1", notebook=NB, kind=CellKind.CHOICE, answer="c",
             options=_ABCD, description="Q2(a) the rising dynode potentials accelerate the "
                                        "electrons so that each impact frees several"),
    # Q2(b): select all that apply
    Exercise(name="q2_item2", notebook=NB, kind=CellKind.CHOICE,
             answer=frozenset({"a", "b", "c"}), options=("a", "b", "c", "d", "e"),
             description="Q2(b) proportional output, fast, efficient (not densely packed)"),
    # Q2(b): what the proportional output is good for
    Exercise(name="q2_item3", notebook=NB, kind=CellKind.CHOICE, answer="b",
             options=_ABCD, description="Q2(b) pulse height proportional to energy lets the "
                                        "camera reject scattered photons"),
    # Q2(c): longer holes
    Exercise(name="q2_item4", notebook=NB, kind=CellKind.CHOICE, answer="d",
             options=_ABCD, description="Q2(c) longer holes: better resolution, fewer photons"),
    # Q2(d): the exam's model against straight-ray geometry
    Exercise(name="q2_item5", notebook=NB, kind=CellKind.CHOICE, answer="a",
             options=_ABCD, description="Q2(d) all-or-nothing overstates the transmission"),
]


# Q2(c) on the student's own numbers: the hole length giving resolution R at distance z (mm).
EXERCISES.append(number_item(
    "q2c_your_length", "q2_nuclear",
    lambda v: float(gamma_camera.collimator_length_for_resolution(v.d, v.R, v.z)),
    "Q2(c) on your numbers: the hole length L (mm) that gives resolution R at z"))


def _your_percent(v) -> float:
    """Q2(d) on the student's numbers: the exam's model through the course's references."""
    holes = gamma_camera.ring_hole_positions(v.pitch, v.rings)
    return 100.0 * float(gamma_camera.open_fraction(holes, v.hole_d, v.hole_L, v.source_distance,
                                                    (v.rings + 1) * v.pitch))


# Q2(d) on the student's own numbers, asked before the exam's numbers are worked: the cut-off
# radius (mm) and the percentage of the photons that reach the back.
EXERCISES += [
    number_item("q2d_your_cutoff", NB,
                lambda v: float(gamma_camera.exam_cutoff_radius(v.hole_d, v.hole_L,
                                                                v.source_distance)),
                "Q2(d) on your numbers: the radius out to which the holes are open (mm)"),
    number_item("q2d_your_percent", NB, _your_percent,
                "Q2(d) on your numbers: the percentage of the photons that reach the back"),
]
