"""Your own numbers: the per-student variant of every graded number item (issue 11).

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
['R', 'd', 'z']
"""

from __future__ import annotations

import hashlib
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["ASSIGNMENT", "NOTEBOOKS", "Variant", "variant", "my_variant", "student_id",
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

_TISSUES = (("fat", 1450.0), ("water", 1480.0), ("kidney", 1560.0), ("liver", 1570.0),
            ("blood", 1575.0), ("muscle", 1585.0))


def _q1_imaging(draw: _Draw) -> dict:
    """Q1(c): a stack of three layers under the probe (mm and m/s)."""
    picked = []
    while len(picked) < 3:
        tissue = draw.pick("tissue", _TISSUES)
        if not picked or tissue[0] != picked[-1][0]:
            picked.append(tissue)
    return {"tissues": tuple(t[0] for t in picked),
            "speeds": tuple(t[1] + draw.grid("speed", -20.0, 20.0, 5.0) for t in picked),
            "thicknesses": tuple(draw.grid("thickness", 10.0, 50.0, 5.0) for _ in picked)}


def _q2_nuclear(draw: _Draw) -> dict:
    """Q2(c): hole diameter d, source distance z and the resolution R wanted there (mm)."""
    d = draw.grid("d", 1.0, 3.0, 0.5)
    return {"d": d, "z": draw.grid("z", 50.0, 200.0, 10.0),
            "R": round(d + draw.grid("R", 1.0, 6.0, 0.5), 1)}


def _q3_marching_cubes(draw: _Draw) -> dict:
    """Q3(a): one crossed cell edge (end points, values, iso-level), and one cell's corners."""
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


def _q4_splines(draw: _Draw) -> dict:
    """Q4(c): the last three given points a, b, c of a curve, a spline kind and an end rule."""
    points = []
    while len(points) < 3:
        p = (draw.grid("x", -5.0, 5.0, 1.0), draw.grid("y", -5.0, 5.0, 1.0))
        if p not in points:
            points.append(p)
    return {"a": points[0], "b": points[1], "c": points[2],
            "kind": draw.pick("kind", ("catmull-rom", "b-spline")),
            "rule": draw.pick("rule", ("d=b", "d=2c-b"))}


def _q5_phong(draw: _Draw) -> dict:
    """Q5(b): normal, light and view directions (not unit), coefficients and colour."""
    while True:
        N, L, V = (tuple(draw.grid(k, -3.0, 3.0, 1.0) for _ in range(3)) for k in "NLV")
        nn, ll, vv = (sum(x * x for x in w) for w in (N, L, V))
        if min(nn, ll, vv) == 0:
            continue
        ln = sum(a * b for a, b in zip(L, N))
        R = tuple(2 * ln / nn * n - l for n, l in zip(N, L))
        rv = sum(r * v for r, v in zip(R, V)) / (ll * vv) ** 0.5
        if ln / (ll * nn) ** 0.5 > 0.2 and 0.2 < rv < 0.98:
            break
    return {"N": N, "L": L, "V": V, "n": draw.pick("n", (2, 3, 4, 5, 8, 10)),
            "Ia": draw.grid("Ia", 0.5, 1.0, 0.1), "Ip": draw.grid("Ip", 0.5, 1.0, 0.1),
            "ka": draw.grid("ka", 0.1, 0.5, 0.1), "kd": draw.grid("kd", 0.2, 0.8, 0.1),
            "ks": draw.grid("ks", 0.2, 0.8, 0.1),
            "colour": tuple(draw.grid("colour", 0.0, 1.0, 0.1) for _ in range(3))}


def _q6_clipping(draw: _Draw) -> dict:
    """Q6(b): a triangle's vertices in homogeneous screen coordinates [X Y Z w]."""
    rows = []
    while len(rows) < 3 or all(_inside(r) for r in rows) or not any(_inside(r) for r in rows):
        rows = []
        for _ in range(3):
            w = draw.grid("w", 1.0, 4.0, 1.0)
            rows.append(tuple(draw.grid("xyz", -5.0, 5.0, 1.0) for _ in range(3)) + (w,))
    return {"vertices": tuple(rows)}


def _inside(row) -> bool:
    X, Y, Z, w = row
    return w > 0 and abs(X) <= w and abs(Y) <= w and 0 <= Z <= w


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

    def options(self, name: str, texts) -> None:
        """Show a multiple-choice item's options in this student's order, lettered a, b, ...

        As Markdown in a notebook (so formulas render), as plain lines elsewhere."""
        text = options_text(name, texts, self.student)
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

    def options(self, name: str, texts) -> None:
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


def options_text(name: str, texts, student: str) -> str:
    """The options of item ``name`` as Markdown list lines ``- **(a)** ...`` in ``student``'s
    order (student ``None``: the canonical order, as the instructors' copy shows them)."""
    texts = list(texts)
    order = range(len(texts)) if student is None else option_order(name, len(texts), student)
    return "\n".join(f"- **({LETTERS[k]})** {texts[i]}" for k, i in enumerate(order))
