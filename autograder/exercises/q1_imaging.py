"""Q1 imaging modalities and B-scan artefacts: grading rules.

Three graded functions of Q1(c) (``course_lib.ultrasound``) and the multiple-choice items of
Q1(a) and Q1(b). The visible cases carry the course's phantom, a reconstruction (the exam gives
no sizes: 40 mm blocks of fat, liver and water under 10 mm of water, 5 MHz; the scanner's
1540 m/s is the exam's); the hidden ones are drawn from ``rng``.
"""

from __future__ import annotations

import numpy as np

from course_lib import ultrasound

from ..model import CellKind
from .base import Case, Exercise, close, number_item

# speeds (m/s) and attenuations (dB/cm/MHz) of the course's material table
_C = {name: p["c"] for name, p in ultrasound.MATERIALS.items()}
# attenuation as a frequency-proportional coefficient (dB/cm/MHz) at the phantom's 5 MHz: water's
# loss grows as f^2, so its coefficient holds only at that frequency
_F_MHZ = 5.0
_ALPHA = {name: ultrasound.attenuation_db_per_cm(name, _F_MHZ) / _F_MHZ
          for name in ultrasound.MATERIALS}


def _displayed_thickness_cases(rng):
    yield Case(args=(40.0, _C["fat"]), label="course phantom: 40 mm of fat", visible=True)
    yield Case(args=(40.0, _C["liver"]), label="course phantom: 40 mm of liver", visible=True)
    yield Case(args=(40.0, _C["water"]), label="course phantom: 40 mm of water", visible=True)
    yield Case(args=(25.0, 1540.0), label="speed equal to the assumed one", visible=True)
    yield Case(args=(-1.0, 1450.0), label="negative thickness", raises=ValueError, visible=True)
    # hidden: random scalars, batches, broadcasting, a different assumed speed, edges
    for _ in range(5):
        yield Case(args=(float(rng.uniform(0.1, 200.0)), float(rng.uniform(1300.0, 1700.0))),
                   label="random layer")
    yield Case(args=(rng.uniform(0.0, 100.0, 7), rng.uniform(1400.0, 1650.0, 7)),
               label="batch of 7 layers")
    yield Case(args=(rng.uniform(0.0, 100.0, (3, 4)), float(rng.uniform(1400.0, 1650.0))),
               label="(3, 4) thicknesses, one speed (broadcast)")
    yield Case(args=(rng.uniform(1.0, 50.0, 5), rng.uniform(1400.0, 1650.0, 5)),
               kwargs={"c_assumed": float(rng.uniform(1450.0, 1600.0))},
               label="a scanner assuming another speed")
    thickness = rng.uniform(0.1, 100.0, 4)
    thickness[rng.integers(4)] = 0.0
    yield Case(args=(thickness, rng.uniform(1400.0, 1650.0, 4)),
               label="4 layers, one of zero thickness")
    yield Case(args=(float(rng.uniform(5.0, 30.0)), float(rng.uniform(3500.0, 4100.0))),
               label="bone-like speed (displayed much too short)")
    yield Case(args=(10.0, 0.0), label="zero speed", raises=ValueError)
    yield Case(args=(10.0, -1450.0), label="negative speed", raises=ValueError)
    yield Case(args=(10.0, 1450.0), kwargs={"c_assumed": 0.0}, label="zero assumed speed",
               raises=ValueError)
    yield Case(args=(rng.uniform(0, 10, 3), rng.uniform(1400, 1600, 4)),
               label="shapes that do not broadcast", raises=ValueError)


def _displayed_depths_cases(rng):
    yield Case(args=((10.0, 40.0, 10.0), (_C["water"], _C["fat"], _C["water"])),
               label="course phantom: water, fat block, water down to the floor", visible=True)
    yield Case(args=((10.0, 40.0, 10.0), (_C["water"], _C["liver"], _C["water"])),
               label="course phantom: water, liver block, water down to the floor", visible=True)
    yield Case(args=((10.0, 20.0), (1500.0, 1600.0, 1540.0)), label="mismatched lengths",
               raises=ValueError, visible=True)
    # hidden
    for n in (1, 2, 5, 9):
        yield Case(args=(rng.uniform(0.5, 30.0, n), rng.uniform(1400.0, 1650.0, n)),
                   label=f"random stack of {n} layers")
    yield Case(args=(rng.uniform(0.5, 30.0, 4), rng.uniform(1400.0, 1650.0, 4)),
               kwargs={"c_assumed": 1480.0}, label="scanner assuming 1480 m/s")
    outer = rng.uniform(0.5, 30.0, 2)
    yield Case(args=((float(outer[0]), 0.0, float(outer[1])),
                     tuple(float(c) for c in rng.uniform(1400.0, 1650.0, 3))),
               label="a zero-thickness layer")
    yield Case(args=([float(t) for t in rng.uniform(0.5, 30.0, 3)], [1540.0, 1540.0, 1540.0]),
               label="every layer at 1540 m/s (lists)")
    yield Case(args=((10.0, -5.0), (1500.0, 1500.0)), label="negative thickness",
               raises=ValueError)
    yield Case(args=((10.0, 5.0), (1500.0, 0.0)), label="zero speed", raises=ValueError)
    yield Case(args=(rng.uniform(1, 2, 3), rng.uniform(1400, 1600, 2)),
               label="thicknesses longer than speeds", raises=ValueError)


def _round_trip_cases(rng):
    yield Case(args=(_ALPHA["fat"], _F_MHZ, 4.0), label="course phantom: 4 cm of fat at 5 MHz",
               visible=True)
    yield Case(args=((_ALPHA["water"], _ALPHA["liver"], _ALPHA["water"]), _F_MHZ,
                     (1.0, 4.0, 1.0)),
               label="course phantom: water, liver, water down to the floor at 5 MHz",
               visible=True)
    yield Case(args=((0.5, 0.6), 3.5, (1.0, 2.0, 3.0)), label="mismatched lengths",
               raises=ValueError, visible=True)
    # hidden
    for _ in range(3):
        yield Case(args=(float(rng.uniform(0.0, 2.0)), float(rng.uniform(1.0, 15.0)),
                         float(rng.uniform(0.0, 10.0))), label="random single layer")
    for n in (2, 6):
        yield Case(args=(rng.uniform(0.0, 2.0, n), float(rng.uniform(1.0, 15.0)),
                         rng.uniform(0.0, 5.0, n)), label=f"random stack of {n} layers")
    yield Case(args=(0.5, 2.0, rng.uniform(0.1, 3.0, 4)),
               label="one coefficient for every layer (scalar alpha)")
    yield Case(args=((0.0, float(rng.uniform(0.1, 2.0)), 0.0), float(rng.uniform(1.0, 15.0)),
                     rng.uniform(0.5, 5.0, 3)), label="a lossy layer between lossless ones")
    yield Case(args=((0.5, -0.1), 5.0, (1.0, 1.0)), label="negative attenuation",
               raises=ValueError)
    yield Case(args=(0.5, 0.0, 2.0), label="zero frequency", raises=ValueError)
    yield Case(args=(0.5, -3.0, 2.0), label="negative frequency", raises=ValueError)
    yield Case(args=((0.5, 0.6), 5.0, (1.0, -2.0)), label="negative thickness",
               raises=ValueError)


_rel = close(rtol=1e-6, atol=1e-9)
_choices = ("a", "b", "c", "d")

EXERCISES = [
    Exercise(name="displayed_thickness", notebook="q1_imaging",
             reference=ultrasound.displayed_thickness,
             cases=_displayed_thickness_cases, compare=_rel,
             description="Q1(c): thickness shown by a scanner assuming c_assumed"),
    Exercise(name="displayed_depths", notebook="q1_imaging",
             reference=ultrasound.displayed_depths,
             cases=_displayed_depths_cases, compare=_rel,
             description="Q1(c): displayed depth of the far face of each layer"),
    Exercise(name="round_trip_attenuation_db", notebook="q1_imaging",
             reference=ultrasound.round_trip_attenuation_db,
             cases=_round_trip_cases, compare=_rel,
             description="Q1(c): two-way attenuation in dB through a stack of layers"),
    # Q1(a)(i): planar X-ray = line integral of attenuation
    Exercise(name="q1_item1", notebook="q1_imaging", kind=CellKind.CHOICE, answer="c",
             options=_choices, description="Q1(a)(i) planar X-ray brightness"),
    # Q1(a)(ii): CT = attenuation at one point (Hounsfield units)
    Exercise(name="q1_item2", notebook="q1_imaging", kind=CellKind.CHOICE, answer="d",
             options=_choices, description="Q1(a)(ii) CT brightness"),
    # Q1(a)(iii): PET = local rate of positron annihilations of the tracer
    Exercise(name="q1_item3", notebook="q1_imaging", kind=CellKind.CHOICE, answer="b",
             options=_choices, description="Q1(a)(iii) PET brightness"),
    # Q1(a)(iv): B-scan = local back-scatter, weakened by the attenuation above
    Exercise(name="q1_item4", notebook="q1_imaging", kind=CellKind.CHOICE, answer="a",
             options=_choices, description="Q1(a)(iv) B-scan brightness"),
    # Q1(b): select all that apply
    Exercise(name="q1_item5", notebook="q1_imaging", kind=CellKind.CHOICE,
             answer=frozenset({"a", "c"}), options=_choices,
             description="Q1(b) why combine PET and CT (all that apply)"),
    # Q1(c): which way does the floor move under the liver
    Exercise(name="q1_item6", notebook="q1_imaging", kind=CellKind.CHOICE, answer="b",
             options=_choices, description="Q1(c) displayed bath floor under the liver"),
]


# Q1(c) on the student's own numbers (course_lib.variants): where the far face of each of their
# three layers is drawn, in mm, by a scanner that assumes 1540 m/s.
EXERCISES.append(number_item(
    "q1c_your_depths", "q1_imaging",
    lambda v: ultrasound.displayed_depths(np.array(v.thicknesses), np.array(v.speeds)),
    "Q1(c) on your numbers: displayed depths of your three layers' far faces (mm)"))
