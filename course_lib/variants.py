"""Your own numbers: the per-student variant of every graded number item.

Each notebook works the exam's own numbers as its example, and asks the graded number items on
numbers of the student's own. Those numbers, and the order in which each multiple-choice item
lists its options, are a **pure function of (assignment, student id)**: :func:`variant`. Nothing
here knows an answer; the grader computes the expected values from the same numbers with the
course's references, on its own side.

Who the student is (:func:`student_id`), first match wins:

1. ``JUPYTERHUB_USER``: on the course's JupyterHub, the login name;
2. nbgrader's configured student id (``c.CourseDirectory.student_id = "..."`` in an
   ``nbgrader_config.py`` of the working folder or of ``~/.jupyter``);
3. what the student typed in the notebook's ``STUDENT_ID`` cell (just below the setup cell).

The grader always uses the id of the submission's folder, so a notebook that worked another
student's numbers earns nothing for those items (its feedback says whose numbers they were).

The numbers are drawn from SHA-256 of ``"tripos2006|<student>|<notebook>|<label>"`` (the id in
lower case: ``AB123`` and ``ab123`` are one student), in pure
Python (no NumPy random stream, whose algorithms may change between releases), and from small
grids of round values, so they can be worked by hand.

Examples
--------
>>> v = variant("q2_nuclear", "ab123")
>>> v == variant("q2_nuclear", "ab123")        # the same student always gets the same numbers
True
>>> v.numbers == variant("q2_nuclear", "cd456").numbers
False
>>> sorted(v.numbers)
['R', 'd', 'hole_L', 'hole_d', 'pitch', 'rings', 'source_distance', 'z']
>>> problems("q2_nuclear", v.numbers)            # every condition of the draw holds
[]
"""

from __future__ import annotations

import hashlib
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["ASSIGNMENT", "NOTEBOOKS", "Variant", "variant", "problems", "my_variant", "student_id",
           "option_order", "displayed_letters", "canonical_letters"]

ASSIGNMENT = "tripos2006"
LETTERS = "abcdefgh"


# --------------------------------------------------------------------------------------------
# who is working


#: A student id, as the grader accepts a submission folder's name.
_ID = re.compile(r"[A-Za-z0-9][A-Za-z0-9._@+-]{0,127}")


def _clean_id(value, source: str) -> str:
    text = str(value).strip()
    if not text:
        return ""
    if not _ID.fullmatch(text):
        raise ValueError(f"student id {text!r} from {source} is not a plain id (a letter or "
                         "digit, then letters, digits and . _ @ + -, at most 128 characters)")
    return text


_CONFIG_ID = re.compile(r"""^\s*c\.CourseDirectory\.student_id\s*=\s*["']([^"']+)["']""",
                        re.MULTILINE)


def nbgrader_student_id(folders=None) -> str:
    """The ``CourseDirectory.student_id`` of an ``nbgrader_config.py`` in ``folders`` (the
    working folder and ``~/.jupyter`` by default), or ``""``; the wildcard ``"*"`` is ignored."""
    folders = [Path.cwd(), Path.home() / ".jupyter"] if folders is None else folders
    for folder in folders:
        path = Path(folder) / "nbgrader_config.py"
        try:
            text = path.read_text(encoding="utf-8")
        except OSError:
            continue
        match = _CONFIG_ID.search(text)
        if match and match.group(1).strip() not in ("", "*"):
            return _clean_id(match.group(1), str(path))
    return ""


def student_id(typed: str = "") -> str:
    """The id of the student working: ``JUPYTERHUB_USER``, else nbgrader's configured id, else
    ``typed`` (the notebook's ``STUDENT_ID`` cell). ``ValueError`` when none is known or it is
    malformed."""
    hub = _clean_id(os.environ.get("JUPYTERHUB_USER", ""), "JUPYTERHUB_USER")
    if hub:
        return hub
    configured = nbgrader_student_id()
    if configured:
        return configured
    own = _clean_id(typed or "", "STUDENT_ID")
    if own:
        return own
    raise ValueError("no student id: type yours between the quotes of STUDENT_ID = \"\" in the "
                     "notebook's STUDENT_ID cell (just below the setup cell) and run it (on the "
                     "course's JupyterHub this is done for you)")


# --------------------------------------------------------------------------------------------
# a reproducible draw


class _Draw:
    """Choices made from SHA-256 of (assignment, student, notebook, label, counter); the id is
    taken in lower case (JupyterHub lower-cases logins, so ``AB123`` typed offline is ``ab123``)."""

    def __init__(self, student: str, notebook: str):
        self._prefix = f"{ASSIGNMENT}|{student.lower()}|{notebook}|"
        self._counter = 0

    def unit(self, label: str) -> float:
        """A number in [0, 1) for ``label`` (each call draws a new one)."""
        self._counter += 1
        digest = hashlib.sha256(f"{self._prefix}{label}|{self._counter}".encode()).digest()
        return int.from_bytes(digest[:8], "big") / 2.0**64

    def pick(self, label: str, options):
        options = list(options)
        return options[int(self.unit(label) * len(options))]

    def grid(self, label: str, lo: float, hi: float, step: float) -> float:
        """One of lo, lo + step, ..., hi (rounded to the step's decimals)."""
        n = int(round((hi - lo) / step))
        decimals = max(0, -int(f"{step:e}".split("e")[1]))
        return round(lo + step * int(self.unit(label) * (n + 1)), decimals)

    def permutation(self, label: str, n: int) -> tuple[int, ...]:
        items = list(range(n))
        order = []
        while items:
            order.append(items.pop(int(self.unit(label) * len(items))))
        return tuple(order)


# --------------------------------------------------------------------------------------------
# each notebook's numbers
#
# Every generator draws, then checks its numbers against its conditions (``_qN_problems``: the
# numbers are well posed, not degenerate, and the quantity asked for cannot be read off without
# the item's arithmetic) and draws again, from the same hash stream, until none is left. The
# conditions are written so that every mistake the notebook or its rubric names lands outside
# the number items' tolerance (0.5 % or 0.001); tests/course_lib/test_variants_gate.py computes
# those mistaken answers for 10,000 ids and checks it.

#: Draws before a generator gives up (none comes close: the conditions keep a fair share).
MAX_DRAWS = 2000


def _until_sound(draw: _Draw, make, problems) -> dict:
    """``make(draw)`` again and again until ``problems(numbers)`` is empty."""
    for _ in range(MAX_DRAWS):
        numbers = make(draw)
        if not problems(numbers):
            return numbers
    raise RuntimeError("no sound variant found: the conditions are too strict")  # pragma: no cover


def _dot(a, b) -> float:
    return sum(x * y for x, y in zip(a, b))


# Q1(c): the materials of the notebook's table (course_lib.ultrasound.MATERIALS) with its speeds
# (m/s), slowest first: a student meets no tissue the notebook does not describe. The notebook
# says sound is slowest in fat; a student's jittered speeds keep the table's ranking.
_TISSUES = (("fat", 1450.0), ("water", 1482.0), ("liver", 1578.0))
_RANK = {name: k for k, (name, _) in enumerate(_TISSUES)}
#: Smallest gap (m/s) between a layer's speed and the scanner's 1540 m/s, and between the
#: speeds of two layers: at 10 m/s the speed correction is 0.65 %, above the tolerance.
_SPEED_GAP = 10.0


def _q1_draw(draw: _Draw) -> dict:
    picked = []
    while len(picked) < 3:
        tissue = draw.pick("tissue", _TISSUES)
        if not picked or tissue[0] != picked[-1][0]:
            picked.append(tissue)
    return {"tissues": tuple(t[0] for t in picked),
            "speeds": tuple(t[1] + draw.grid("speed", -20.0, 20.0, 5.0) for t in picked),
            "thicknesses": tuple(draw.grid("thickness", 10.0, 50.0, 5.0) for _ in picked)}


def _q1_problems(v: dict) -> list[str]:
    """Q1(c): the jitter keeps the table's order (fat slowest), no two layers share a speed, and
    every layer is at least 10 m/s from 1540 m/s (so neither the uncorrected thickness nor the
    inverted ratio c/1540 comes within the tolerance)."""
    out = []
    pairs = list(zip(v["tissues"], v["speeds"]))
    for (t1, c1) in pairs:
        for (t2, c2) in pairs:
            if _RANK[t1] < _RANK[t2] and not c1 + _SPEED_GAP <= c2:
                out.append(f"{t1} not slower than {t2}")
    if any(abs(c - 1540.0) < _SPEED_GAP for c in v["speeds"]):
        out.append("a speed too close to the scanner's 1540 m/s")
    return out


def _q1_imaging(draw: _Draw) -> dict:
    """Q1(c): a stack of three layers under the probe (mm and m/s)."""
    return _until_sound(draw, _q1_draw, _q1_problems)


def _q2c_draw(draw: _Draw) -> dict:
    d = draw.grid("d", 1.0, 3.0, 0.5)
    return {"d": d, "z": draw.grid("z", 50.0, 200.0, 10.0),
            "R": round(d + draw.grid("R", 1.0, 6.0, 0.5), 1)}


def _q2d_draw(draw: _Draw) -> dict:
    """The collimator first, then a source distance among those that suit it (if any)."""
    v = {"hole_d": draw.grid("hole_d", 1.0, 2.0, 0.5),
         "hole_L": draw.grid("hole_L", 20.0, 60.0, 5.0),
         "pitch": draw.grid("pitch", 5.0, 12.0, 1.0),
         "rings": int(draw.grid("rings", 3.0, 6.0, 1.0)), "source_distance": 0.0}
    suit = [z for z in range(200, 1501, 50) if not _q2_problems({**v, "source_distance": z})]
    v["source_distance"] = float(draw.pick("source_distance", suit or [0]))
    return v


def _q2_open_rings(v: dict) -> float:
    """How many pitches the cut-off radius d z / L of Q2(d) spans (a float)."""
    return v["hole_d"] * v["source_distance"] / v["hole_L"] / v["pitch"]


def _q2_problems(v: dict) -> list[str]:
    """Q2(c): R - d is not d (the swapped ratio z (R - d) / d would give the right length).
    Q2(d): the cut-off radius opens at least two rings and closes at least one, and lies at
    least a fifth of a pitch from every ring (the boundary convention decides nothing)."""
    out = []
    if "R" in v and abs((v["R"] - v["d"]) - v["d"]) < 0.5:
        out.append("R - d too close to d")
    if "pitch" not in v:
        return out
    k = _q2_open_rings(v)
    if not 2.2 <= k <= v["rings"] - 0.8:
        out.append("the cut-off does not fall between the second and the last ring")
    if abs(k - round(k)) < 0.2:
        out.append("the cut-off too close to a ring")
    return out


def _q2_nuclear(draw: _Draw) -> dict:
    """Q2(c): hole diameter d, source distance z and the resolution R wanted there (mm).
    Q2(d): a ring collimator (hole diameter and length, ring pitch, number of rings; its face's
    radius is (rings + 1) pitch) and the distance of an on-axis point source (mm)."""
    return {**_until_sound(draw, _q2c_draw, _q2_problems),
            **_until_sound(draw, _q2d_draw, _q2_problems)}


def _q3_draw(draw: _Draw) -> dict:
    iso = draw.grid("iso", 50.0, 150.0, 10.0)
    below, above = draw.grid("below", 1.0, 40.0, 1.0), draw.grid("above", 1.0, 40.0, 1.0)
    v0, v1 = (iso - below, iso + above) if draw.unit("side") < 0.5 else (iso + above, iso - below)
    axis = int(draw.unit("axis") * 3)
    p0 = tuple(draw.grid("p0", 0.0, 9.0, 1.0) for _ in range(3))
    p1 = tuple(c + (1.0 if k == axis else 0.0) for k, c in enumerate(p0))
    corners = ()
    while not corners or all(c < iso for c in corners) or all(c > iso for c in corners):
        corners = tuple(draw.grid("corner", iso - 30.0, iso + 30.0, 5.0) + 0.5 for _ in range(8))
    return {"p0": p0, "p1": p1, "v0": v0, "v1": v1, "iso": iso, "corner_values": corners}


def _q3_problems(v: dict) -> list[str]:
    """Q3(a): the edge is crossed at least a tenth of its length from its mid-point and from
    either end (so the mid-point, the mirror-image fraction taken from the wrong end and the
    end nearer the iso-level all miss by more than the tolerance on coordinates up to 10), and
    the cell's corners are neither all in nor all out."""
    out = []
    t = (v["iso"] - v["v0"]) / (v["v1"] - v["v0"])
    if not 0.0 < t < 1.0:
        out.append("the edge is not crossed")
    elif abs(t - 0.5) < 0.1 or min(t, 1.0 - t) < 0.1:
        out.append("the crossing too close to the mid-point or to an end")
    below = [c < v["iso"] for c in v["corner_values"]]
    if all(below) or not any(below) or v["iso"] in v["corner_values"]:
        out.append("the cell is not cut cleanly")
    return out


def _q3_marching_cubes(draw: _Draw) -> dict:
    """Q3(a): one crossed cell edge (end points, values, iso-level), and one cell's corners."""
    return _until_sound(draw, _q3_draw, _q3_problems)


#: Q4(c)(i): the (spline kind, end rule) combinations whose end needs no arithmetic, and why:
#: two of the three rows p(1), p'(1), p''(1) would be read off. Every other combination reads
#: off at most one row (p(1) = c of any Catmull-Rom end; p'(1) = 0 of the B-spline with d = b).
_Q4_TRIVIAL = {
    ("b-spline", "d=2c-b"): "the B-spline with d = 2c - b ends at (c, c - b, 0)",
    ("catmull-rom", "d=b"): "the Catmull-Rom with d = b ends at p(1) = c with p'(1) = 0",
}
#: Q4(c)(i): the spline kinds and end rules asked for: all but the trivial ones.
_Q4_CASES = tuple(case for case in (("catmull-rom", "d=b"), ("catmull-rom", "d=2c-b"),
                                    ("b-spline", "d=b"), ("b-spline", "d=2c-b"))
                  if case not in _Q4_TRIVIAL)


def _q4_draw(draw: _Draw) -> dict:
    points = []
    while len(points) < 3:
        p = (draw.grid("x", -5.0, 5.0, 1.0), draw.grid("y", -5.0, 5.0, 1.0))
        if p not in points:
            points.append(p)
    kind, rule = draw.pick("case", _Q4_CASES)
    return {"a": points[0], "b": points[1], "c": points[2], "kind": kind, "rule": rule}


def _q4_problems(v: dict) -> list[str]:
    """Q4(c)(i): three distinct points, not on one line (the end's acceleration is then never
    zero and no two rules or kinds give the same end), and not a trivial case
    (:data:`_Q4_TRIVIAL`: two of the three rows read off without arithmetic)."""
    (ax, ay), (bx, by), (cx, cy) = v["a"], v["b"], v["c"]
    out = []
    if (bx - ax) * (cy - by) - (by - ay) * (cx - bx) == 0:
        out.append("a, b, c on one line")
    if (v["kind"], v["rule"]) in _Q4_TRIVIAL:
        out.append(f"a case read off without arithmetic: {_Q4_TRIVIAL[v['kind'], v['rule']]}")
    return out


def _q4_splines(draw: _Draw) -> dict:
    """Q4(c): the last three given points a, b, c of a curve, a spline kind and an end rule."""
    return _until_sound(draw, _q4_draw, _q4_problems)


def _q5_direction(draw: _Draw, name: str) -> tuple:
    return tuple(draw.grid(name, -3.0, 3.0, 1.0) for _ in range(3))


def _q5_coefficients(draw: _Draw) -> dict:
    return {"n": draw.pick("n", (2, 3, 4, 5, 8, 10)),
            "Ia": draw.grid("Ia", 0.5, 1.0, 0.1), "Ip": draw.grid("Ip", 0.5, 1.0, 0.1),
            "ka": draw.grid("ka", 0.1, 0.5, 0.1), "kd": draw.grid("kd", 0.2, 0.8, 0.1),
            "ks": draw.grid("ks", 0.2, 0.8, 0.1),
            "colour": tuple(draw.grid("colour", 0.0, 1.0, 0.1) for _ in range(3))}


def _q5_cosines(v: dict) -> tuple[float, float, float] | None:
    """(L.N, V.N, R.V) as cosines, or None when a vector is zero or of unit length."""
    N, L, V = v["N"], v["L"], v["V"]
    nn, ll, vv = _dot(N, N), _dot(L, L), _dot(V, V)
    if min(nn, ll, vv) <= 1:
        return None
    R = tuple(2 * _dot(L, N) / nn * n - l for n, l in zip(N, L))
    return (_dot(L, N) / (ll * nn) ** 0.5, _dot(V, N) / (vv * nn) ** 0.5,
            _dot(R, V) / (ll * vv) ** 0.5)


def _q5_geometry_problems(v: dict) -> list[str]:
    cosines = _q5_cosines(v)
    if cosines is None:
        return ["a zero-length or unit vector"]
    ln, vn, rv = cosines
    out = []
    if ln <= 0.2:
        out.append("the light behind or grazing the surface")
    if vn <= 0.2:
        out.append("the viewer behind or edge-on to the surface")
    if not 0.5 < rv < 0.98:
        out.append("the highlight missed, faint or head-on")
    return out


def _q5_problems(v: dict) -> list[str]:
    """Q5(b): no vector of unit length (so that normalising matters), the light and the viewer
    in front of the surface (cosines with N above 0.2), a highlight neither missed nor head-on
    (0.5 < R.V < 0.98, cosines) and worth at least 0.05 (so that leaving it out, or colouring it
    with c, misses by more than the tolerance), a surface colour with a channel at most 0.5, and
    coefficients that keep every channel at most 1."""
    out = _q5_geometry_problems(v)
    if out:
        return out
    if v["Ip"] * v["ks"] * _q5_cosines(v)[2] ** v["n"] < 0.05:
        out.append("the highlight too faint to matter")
    if min(v["colour"]) > 0.5:
        out.append("a surface almost white: a coloured highlight would look right")
    if max(v["colour"]) * (v["Ia"] * v["ka"] + v["Ip"] * v["kd"]) + v["Ip"] * v["ks"] > 1:
        out.append("a channel could exceed 1")
    return out


def _q5_phong(draw: _Draw) -> dict:
    """Q5(b): normal, light and view directions (not unit), coefficients and colour: the
    directions are drawn until they are sound, then the coefficients until everything is."""
    N = _until_sound(draw, lambda d: {"N": _q5_direction(d, "N")},
                     lambda v: [] if _dot(v["N"], v["N"]) > 1 else ["N zero or unit"])["N"]
    L = _until_sound(draw, lambda d: {"L": _q5_direction(d, "L")},
                     lambda v: [] if _dot(v["L"], v["L"]) > 1 and _dot(v["L"], N) > 0.2 * (
                         _dot(N, N) * _dot(v["L"], v["L"])) ** 0.5 else ["L unsound"])["L"]
    geometry = _until_sound(draw, lambda d: {"N": N, "L": L, "V": _q5_direction(d, "V")},
                            _q5_geometry_problems)
    return _until_sound(draw, lambda d: {**geometry, **_q5_coefficients(d)}, _q5_problems)


def _q6_vertex(draw: _Draw, role: str) -> tuple:
    """One vertex [X, Y, Z, w] (integers, w from 2 to 5): ``"in"`` strictly inside the view
    volume, ``"edge"`` inside on at least one of its planes, ``"out"`` outside one of them."""
    w = draw.grid("w", 2.0, 5.0, 1.0)
    X, Y = (draw.grid("xy", -w + 1, w - 1, 1.0) for _ in range(2))
    Z = draw.grid("z", 1.0, w - 1, 1.0)
    if role == "in":
        return (X, Y, Z, w)
    plane = int(draw.unit("plane") * 6)
    if role == "edge":
        at = (w, -w, w, -w, 0.0, w)[plane]
    else:
        at = draw.grid("beyond", 1.0, 4.0, 1.0)
        at = (w + at, -w - at, w + at, -w - at, -at, w + at)[plane]
    xyz = [X, Y, Z]
    xyz[plane // 2] = at
    return (*xyz, w)


def _q6_draw(draw: _Draw) -> dict:
    roles = ["in", "edge", "out"]
    order = draw.permutation("roles", 3)
    return {"vertices": tuple(_q6_vertex(draw, roles[k]) for k in order)}


def _q6_problems(v: dict) -> list[str]:
    """Q6(b): one vertex strictly inside, one inside on a boundary plane (so strict inequalities
    change the answer, and the six inequalities, not the boundary rule alone, decide the other),
    one outside (something is clipped; with an inside vertex, never everything); w > 1
    everywhere (the divide changes every vertex)."""
    rows = v["vertices"]
    strict = [w > 0 and -w < X < w and -w < Y < w and 0 < Z < w for X, Y, Z, w in rows]
    inside = [_inside(r) for r in rows]
    out = []
    if not any(strict):
        out.append("no vertex strictly inside")
    if not any(i and not s for i, s in zip(inside, strict)):
        out.append("no vertex on a boundary plane")
    if all(inside):
        out.append("nothing outside")
    if any(r[3] <= 1 for r in rows):
        out.append("w = 1 makes the divide a no-op")
    return out


def _q6_clipping(draw: _Draw) -> dict:
    """Q6(b): a triangle's vertices in homogeneous screen coordinates [X Y Z w]."""
    return _until_sound(draw, _q6_draw, _q6_problems)


def _inside(row) -> bool:
    X, Y, Z, w = row
    return w > 0 and abs(X) <= w and abs(Y) <= w and 0 <= Z <= w


_PROBLEMS = {"q1_imaging": _q1_problems, "q2_nuclear": _q2_problems,
             "q3_marching_cubes": _q3_problems, "q4_splines": _q4_problems,
             "q5_phong": _q5_problems, "q6_clipping": _q6_problems}
_NUMBERS = {"q1_imaging": _q1_imaging, "q2_nuclear": _q2_nuclear,
            "q3_marching_cubes": _q3_marching_cubes, "q4_splines": _q4_splines,
            "q5_phong": _q5_phong, "q6_clipping": _q6_clipping}
NOTEBOOKS = tuple(_NUMBERS)


# --------------------------------------------------------------------------------------------
# the variant


@dataclass(frozen=True)
class Variant:
    """One student's numbers for one notebook; ``mine.speeds`` reads a number by name."""

    notebook: str
    student: str
    numbers: dict = field(compare=True)

    def __getattr__(self, name):
        numbers = object.__getattribute__(self, "numbers")
        if name in numbers:
            return numbers[name]
        raise AttributeError(f"{name!r}: your numbers for {self.notebook} are "
                             f"{', '.join(sorted(numbers))}")

    def __str__(self) -> str:
        lines = [f"Your numbers (student {self.student}), {self.notebook}:"]
        lines += [f"  {k} = {_show(v)}" for k, v in self.numbers.items()]
        return "\n".join(lines)

    def letters(self, name: str, canonical: str, n_options: int) -> str:
        """The letters under which this student sees the options ``canonical`` of item ``name``
        (the instructors' model answers use it; a student simply types the letters shown)."""
        return displayed_letters(name, canonical, n_options, self.student)

    def options(self, name: str, texts=None) -> None:
        """Show a multiple-choice item's options in this student's order, lettered a, b, ...
        (``texts``: the options in the canonical order; by default the item's own, from
        :mod:`course_lib.item_options`).

        As Markdown in a notebook (so formulas render), as plain lines elsewhere."""
        text = options_text(name, item_texts(name) if texts is None else texts, self.student)
        try:
            from IPython import get_ipython
            from IPython.display import Markdown, display
        except ImportError:
            print(text)
            return
        if get_ipython() is None:
            print(text)
        else:
            display(Markdown(text))


def _show(value) -> str:
    if isinstance(value, tuple):
        return "(" + ", ".join(_show(v) for v in value) + ")"
    if isinstance(value, float) and value == int(value):
        return str(int(value)) if abs(value) < 1e15 else repr(value)
    return repr(value) if isinstance(value, str) else str(value)


def variant(notebook: str, student: str) -> Variant:
    """The numbers of ``student`` for ``notebook``: a pure function of the two (and the
    assignment). ``ValueError`` for an unknown notebook or an empty/malformed id."""
    if notebook not in _NUMBERS:
        raise ValueError(f"notebook must be one of {NOTEBOOKS}, got {notebook!r}")
    sid = _clean_id(student, "the student argument")
    if not sid:
        raise ValueError("student must be a non-empty id")
    return Variant(notebook, sid, _NUMBERS[notebook](_Draw(sid, notebook)))


def problems(notebook: str, numbers: dict) -> list[str]:
    """The conditions of ``notebook``'s generator that ``numbers`` break (empty: a sound
    variant). ``ValueError`` for an unknown notebook."""
    if notebook not in _PROBLEMS:
        raise ValueError(f"notebook must be one of {NOTEBOOKS}, got {notebook!r}")
    return _PROBLEMS[notebook](numbers)


def my_variant(notebook: str, typed: str = "", *, quiet: bool = False,
               missing_ok: bool = False):
    """The working student's numbers for ``notebook`` (see :func:`student_id`), printed unless
    ``quiet``. With ``missing_ok``, an unknown student gives a stand-in whose every use says to
    type the id first, instead of a ``ValueError`` now (the setup cell runs before the id cell;
    the id cell itself, so that Run All goes on through an untouched notebook: the cells that
    need the numbers then say what to do), and says so unless ``quiet``."""
    try:
        sid = student_id(typed)
    except ValueError as exc:
        if missing_ok:
            if not quiet:
                why = str(exc)
                print(f"{why[:1].upper()}{why[1:]}.\nUntil then, every cell that uses your "
                      "numbers says so; the others run.")
            return _NoStudentYet(notebook, str(exc))
        raise
    typed_id = _clean_id(typed or "", "STUDENT_ID")
    mine = variant(notebook, sid)
    if not quiet:
        if typed_id and typed_id != sid:
            print(f"Note: you typed {typed_id!r} in STUDENT_ID, but you are {sid!r} here; "
                  f"these are {sid}'s numbers.")
        print(mine)
    return mine


class _NoStudentYet:
    """``mine`` before the student id is known: every use explains what to do. Showing a
    multiple-choice item's options says so without an error (the options come in the student's
    own order, so none can be shown yet), so Run All goes on past them."""

    def __init__(self, notebook: str, why: str):
        self._notebook, self._why = notebook, why

    def options(self, name: str, texts=None) -> None:
        """In place of item ``name``'s options: what to do to see them."""
        print(f"The options of {name} appear here, lettered in your own order, once your "
              "student id is known: type it in STUDENT_ID (near the top) and run that cell, "
              "then this one.")

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        raise ValueError(self._why)

    def __repr__(self) -> str:
        return f"<no student id yet for {self._notebook}: {self._why}>"


# --------------------------------------------------------------------------------------------
# multiple-choice options in each student's order


def option_order(name: str, n_options: int, student: str) -> tuple[int, ...]:
    """``order[k]`` is the canonical index of the option the student sees as letter ``k``."""
    if not 2 <= int(n_options) <= len(LETTERS):
        raise ValueError(f"n_options must be 2 ... {len(LETTERS)}, got {n_options!r}")
    sid = _clean_id(student, "the student argument")
    if not sid:
        raise ValueError("student must be a non-empty id")
    return _Draw(sid, f"choice:{name}").permutation("order", int(n_options))


def displayed_letters(name: str, canonical: str, n_options: int, student: str) -> str:
    """The letters under which ``student`` sees the options ``canonical`` (sorted)."""
    order = option_order(name, n_options, student)
    return "".join(sorted(LETTERS[order.index(LETTERS.index(c))] for c in canonical))


def canonical_letters(name: str, shown: str, n_options: int, student: str) -> str:
    """The canonical letters of the options ``student`` sees as ``shown`` (sorted)."""
    order = option_order(name, n_options, student)
    return "".join(sorted(LETTERS[order[LETTERS.index(c)]] for c in shown))


def item_texts(name: str) -> tuple[str, ...]:
    """The options of multiple-choice item ``name`` in the canonical order; ``ValueError`` for
    an unknown item. (Imported here, not at the top: the grading sandbox runs this module with
    the standard library alone, and never shows options.)"""
    from course_lib.item_options import OPTIONS

    if name not in OPTIONS:
        raise ValueError(f"no multiple-choice item {name!r}; known: {', '.join(sorted(OPTIONS))}")
    return OPTIONS[name]


def options_text(name: str, texts, student: str) -> str:
    """The options of item ``name`` as Markdown list lines ``- **(a)** ...`` in ``student``'s
    order (student ``None``: the canonical order, as the instructors' copy shows them)."""
    texts = list(texts)
    order = range(len(texts)) if student is None else option_order(name, len(texts), student)
    return "\n".join(f"- **({LETTERS[k]})** {texts[i]}" for k, i in enumerate(order))
