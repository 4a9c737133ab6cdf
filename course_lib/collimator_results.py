"""Q2's fixed examples, worked by the course's references: the exam's collimator and a thin one.

The "going further" cells of the Q2 notebook start from the collimator of Q2(d) as this
notebook reconstructs it (:data:`EXAM`: 1 mm holes 40 mm long on four rings 10 mm apart, a
50 mm face, the source 1 m away) and compare the exam's all-or-nothing open fraction with the
exact transmission, there and on a thin collimator (:data:`THIN`: 5 mm holes 1 mm long).

The students' copy of the library holds the hole centres and the exam's fractions on these
fixed inputs, computed when it was built by ``ring_hole_positions`` and ``open_fraction``, and
not those functions (writing them is the question). Every function here returns the same
numbers in both copies; none takes an input of yours.
"""

from __future__ import annotations

import numpy as np

__all__ = ["EXAM", "THIN", "exam_holes", "exam_open_fraction", "thin_open_fraction"]

#: Q2(d)'s collimator: ``ring_hole_positions(pitch, n_rings)`` on a face of radius
#: ``collimator_radius``, holes ``d`` wide and ``L`` long, source ``source_distance`` away (mm)
EXAM = {"pitch": 10.0, "n_rings": 4, "d": 1.0, "L": 40.0, "source_distance": 1000.0,
        "collimator_radius": 50.0}
#: the thin collimator of "where does the exam's model hold?": the same holes' centres and face,
#: 5 mm holes 1 mm long, source 1 m away
THIN = {"d": 5.0, "L": 1.0, "source_distance": 1000.0, "collimator_radius": 50.0}


def _data() -> dict:
    from ._collimator_results_data import load

    return load()


def exam_holes() -> np.ndarray:
    """The 81 hole centres of :data:`EXAM`, shape ``(81, 2)`` (read-only): the centre, then the
    rings of 8, 16, 24 and 32 holes, each anticlockwise from angle 0 (Q2(d))."""
    return _data()["exam_holes"]


def exam_open_fraction() -> float:
    """The exam's open fraction of :data:`EXAM` (Q2(d)): 25 holes of 1 mm on a 50 mm face."""
    return float(_data()["exam_fraction"])


def thin_open_fraction() -> float:
    """The exam's open fraction of :data:`THIN`'s collimator (every hole open)."""
    return float(_data()["thin_fraction"])
