"""Attacks on the batch grader, beyond the bank of ``test_bank.py``, against the OS sandbox.

Each attack is a submission built like the bank's (the model answers of one source notebook
with one edit, or the blank release notebook with an attack in it), graded in ONE batch
(``python -m autograder grade --jobs 2``, as an instructor runs it) with an exact expected
score and status for every graded cell. The expected values are decided here: full points from
the source notebook, partial credit from the registry's cases drawn with the grader's documented
seed, and for the attacked function the cases its honest part still gets right.

What the attacks try (and what the grader must do):

- answers that are not plain floats: complex or object arrays, an object whose ``__float__``
  and ``__array__`` tell the right answer, a generator (``rejected-output``); NaN answers
  (``failed``); a 0-d array where a float is expected (full marks: it *is* the number); huge
  returns (``rejected-output``, and the feedback page stays small);
- mutating the input arrays in place after computing the answer (no effect);
- raw memory writes through ``__array_interface__`` (student code owns its whole process), then
  reading a source notebook, ``course_lib``'s sources, the course secret, another student's
  notebook, and writing to the gradebook and the output folder: nothing is there to read or
  write (the blank-notebook attacker scores 0, everyone else's scores are unchanged);
- the reference through a back door: private helpers and constants of ``course_lib``
  (``shading._shade``, ``marching_cubes._march``, ``clipping.clip_polygons``,
  ``gamma_camera.pmt_cascade``, the spline basis constants) are ``reference-used``; scikit-image
  and shapely are not in the sandbox (0); reading the reference's file finds nothing (0);
- walking the interpreter's frames (``sys._getframe(1).f_locals``) for expected values or the
  grader's secrets: there are none in the sandbox;
- printing the hidden inputs, then re-submitting a lookup table of the right answers for them:
  the feedback never showed them, and the changed function draws new hidden cases;
- ignoring ``SIGALRM`` in an endless loop (``timeout``); runaway recursion through C calls
  (``error``);
- defining the graded name in an untagged later cell through ``globals()``/``exec`` (ignored:
  the solution cell is graded), or only through ``exec`` after deleting the solution cell
  (``missing``); zero-width characters in grade_ids; a solution cell whose source is a list of
  numbers (``missing``); ``cells`` that is not a list (``unreadable``); megabytes of notebook
  metadata (graded normally);
- a submission folder that is a symbolic link to another student's folder, a notebook that is
  a symbolic link to ``/etc/passwd`` (``unreadable``), and student folders with odd names
  (skipped with a warning, nobody else affected);
- two ``grade`` processes at once on one machine, on different submission sets: both correct.
"""

from __future__ import annotations

import html
import os
import re
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from gradingtools import (expect_all, expect_full_marks, points_of,
                          SECRET, append_cell, cases_of, cell_index, course_sources,
                          model_version, read_grades, run_grade, set_cell, target_of, write_nb)

from autograder.exercises import REGISTRY

pytestmark = [pytest.mark.xdist_group("grading")]

_ALL = course_sources()
SRC = _ALL[0] if _ALL else None








def _raising_fraction(student: str, name: str, nb: dict) -> tuple[int, int]:
    """(cases where a ValueError is the right answer, all cases) for ``student``'s ``nb``."""
    cases = cases_of(student, name, nb)
    return sum(c.raises is not None and issubclass(ValueError, c.raises) for c in cases), len(cases)


def _target_status(status, score_of=None):
    """Expected rows: the model everywhere, ``status`` for the target's test; the score is the
    bad-input cases (the honest model raises before the attack returns), unless ``score_of``."""
    def expect(src, student):
        name = target_of(src)
        exp = expect_full_marks(src)
        if score_of is not None:
            score = score_of(src, student)
        else:
            raising, n = _raising_fraction(student, name, ATTACKS[student].build(src))
            score = points_of(src, name) * raising / n
        exp[f"test_{name}"] = (score, status)
        return exp
    return expect


def _zero(src, student):
    return 0.0


def _wrap(body: str) -> Callable:
    """Append to the target's solution cell a wrapper around the model answer (``_model``)."""
    def build(src):
        name = target_of(src)
        nb = model_version(src)
        code = (f"_model = {name}\n"
                f"def {name}(*args, **kwargs):\n"
                + "".join("    " + ln + "\n" for ln in body.strip("\n").splitlines()))
        append_cell(nb, name, code)
        return nb
    return build


def _append(code_of: Callable) -> Callable:
    def build(src):
        name = target_of(src)
        nb = model_version(src)
        append_cell(nb, name, code_of(src, name))
        return nb
    return build


# --------------------------------------------------------------------------------------------
# answers that are not plain floats

COMPLEX = "return np.asarray(_model(*args, **kwargs), dtype=float) + 0j"
OBJECT = "return np.array(np.asarray(_model(*args, **kwargs), dtype=float), dtype=object)"
ZERO_D = """
r = _model(*args, **kwargs)
return np.asarray(r) if np.ndim(r) == 0 else r
"""
LIAR = """
r = np.asarray(_model(*args, **kwargs), dtype=float)
class Liar:
    def __float__(self): return float(r)
    def __array__(self, dtype=None, copy=None): return r
    def __eq__(self, other): return True
    __hash__ = object.__hash__
return Liar()
"""
GENERATOR = "return (x for x in np.atleast_1d(_model(*args, **kwargs)))"
NAN = "return np.full(np.shape(_model(*args, **kwargs)), np.nan)"
MUTATE = """
r = _model(*args, **kwargs)
r = np.array(r, dtype=float) if np.ndim(r) else r
for a in list(args) + list(kwargs.values()):
    if isinstance(a, np.ndarray) and a.dtype.kind == "f":
        a[...] = 1e9                  # the grader's own copy is untouched
return r
"""
TYPE_OVERRIDE = """
import builtins
_r = _model(*args, **kwargs)
class Sneaky:
    def __eq__(self, other): return True
    __hash__ = object.__hash__
real_type, real_isinstance = builtins.type, builtins.isinstance
builtins.type = lambda *a: float if len(a) == 1 else real_type(*a)
builtins.isinstance = lambda o, t: True
return Sneaky()
"""

HUGE = """
_model(*args, **kwargs)           # the bad-input cases still raise
return np.ones(30_000_000)        # 240 MB: far beyond the case's result cap
"""

# --------------------------------------------------------------------------------------------
# the reference through a back door (each returns a wrong answer when the read fails)


def _steal(opener: str, prelude: str = "pass") -> Callable:
    def code_of(src, name):
        ref = REGISTRY[name].reference
        path = str(Path(ref.__code__.co_filename).resolve())
        return f"""
def _steal_it():
    try:
        {prelude.replace("{path!r}", repr(path))}
        text = ({opener.replace("{path!r}", repr(path))})
    except BaseException as exc:
        print("BLOCKED", type(exc).__name__)
        return None
    g = {{"__name__": {ref.__module__ + '_stolen'!r}, "__package__": "course_lib"}}
    if type(text) is bytes:
        text = text.decode()
    exec(compile(text, "stolen", "exec"), g)
    print("LEAK stolen source")
    return g[{ref.__name__!r}]
_stolen = _steal_it()
def {name}(*args, **kwargs):
    if _stolen is None:
        return "could not steal it"
    return _stolen(*args, **kwargs)
"""
    return code_of


STEAL_OPEN = _steal("open({path!r}).read()")
STEAL_FSPATH = _steal("open(P()).read()",
                      "P = type('P', (), {'__fspath__': lambda self: {path!r}})")
STEAL_DIRFD = _steal("os.read(os.open(os.path.basename({path!r}), os.O_RDONLY, "
                     "dir_fd=os.open(os.path.dirname({path!r}), os.O_RDONLY)), 10**6)",
                     "import os")
STEAL_LOADER = _steal("importlib.util.find_spec('course_lib.' + os.path.basename({path!r})[:-3])"
                      ".loader.get_data({path!r})", "import importlib.util, os")

#: (notebook, graded name, code of the solution cell): a reference behind the front door.
BACK_DOORS = {
    "rt_private_shade": ("q5_phong", "phong", """
def phong(colour, Ia, ka, Ip, kd, ks, n, L, N, V):
    from course_lib.shading import _shade
    return _shade(colour, Ia, ka, Ip, kd, ks, n, L, N, V, "phong")
"""),
    "rt_private_march": ("q3_marching_cubes", "marching_cubes", """
def marching_cubes(volume, iso, spacing=(1.0, 1.0, 1.0)):
    import course_lib.marching_cubes as mc
    return mc._march(volume, iso, spacing)
"""),
    "rt_batch_clip": ("q6_clipping", "clip_polygon", """
def clip_polygon(P):
    from course_lib.clipping import clip_polygons
    return clip_polygons([P])[0]
"""),
    "rt_pmt_cascade": ("q2_nuclear", "pmt_gain", """
def pmt_gain(delta, n_dynodes):
    from course_lib import gamma_camera
    return float(gamma_camera.pmt_cascade(delta, n_dynodes)[-1])
"""),
    "rt_basis_constant": ("q4_splines", "catmull_rom_basis", """
def catmull_rom_basis():
    from course_lib.splines import _CATMULL_ROM
    return _CATMULL_ROM.copy()
"""),
}
#: Other libraries that answer the question: not in the sandbox, so the function errors (0).
OTHER_LIBRARIES = {
    "rt_skimage": ("q3_marching_cubes", "marching_cubes", """
def marching_cubes(volume, iso, spacing=(1.0, 1.0, 1.0)):
    from skimage.measure import marching_cubes as theirs
    v, f, _, _ = theirs(volume, iso, spacing=spacing)
    return v, f
"""),
    "rt_shapely": ("q6_clipping", "clip_polygon", """
def clip_polygon(P):
    import shapely
    return P[shapely.box(-1, -1, 1, 1).contains(shapely.points(P[:, :2] / P[:, 3:]))]
"""),
}

# --------------------------------------------------------------------------------------------
# the interpreter's own frames, and raw memory

FRAMES = """
import sys
found, k = [], 1
while True:
    try:
        frame = sys._getframe(k)
    except ValueError:
        break
    for key, value in list(frame.f_locals.items()):
        text = str(key).lower()
        if any(w in text for w in ("expected", "secret", "answer", "registry", "hmac")):
            found.append(key)
    k += 1
print("LEAK frames" if found else "BLOCKED frames", found)
raise RuntimeError("nothing to steal")
"""
IGNORE_ALARM = """
import signal
signal.signal(signal.SIGALRM, signal.SIG_IGN)
signal.setitimer(signal.ITIMER_REAL, 0)
while True:
    pass
"""
RECURSION = """
import sys
sys.setrecursionlimit(10**8)
def down(k):                      # through C (map, sum): the C stack overflows
    return sum(map(down, [k + 1]))
return down(0)
"""


def raw_memory_attack(targets: dict[str, list[str]]) -> str:
    """Code that writes raw memory (``__array_interface__``), then tries every read in
    ``targets["read"]``, listing in ``targets["list"]`` and write in ``targets["write"]``."""
    return f"""
import os, numpy as np
class _Raw:
    def __init__(self, address, n):
        self.__array_interface__ = {{"shape": (n,), "typestr": "|u1", "data": (address, False),
                                    "version": 3}}
_victim = bytearray(b"x" * 64)
_address = np.frombuffer(_victim, dtype=np.uint8).__array_interface__["data"][0]
np.asarray(_Raw(_address, 64))[:] = ord("y")           # a write anywhere in this process
print("RAW WRITE", "done" if bytes(_victim) == b"y" * 64 else "failed")
for p in {targets["read"]!r}:
    try:
        with open(p, "rb") as fh:
            fh.read(10)
        print("LEAK read", p)
    except BaseException as exc:
        print("BLOCKED read", type(exc).__name__)
for d in {targets["list"]!r}:
    try:
        os.listdir(d)
        print("LEAK listdir", d)
    except BaseException as exc:
        print("BLOCKED listdir", type(exc).__name__)
for p in {targets["write"]!r}:
    try:
        with open(p, "ab") as fh:
            fh.write(b"garbage")
        print("LEAK write", p)
    except BaseException as exc:
        print("BLOCKED write", type(exc).__name__)
"""


# --------------------------------------------------------------------------------------------
# notebooks and folders


def _untagged_override(src):
    name = target_of(src)
    nb = model_version(src)
    i = cell_index(nb, name)
    nb["cells"].insert(i + 1, {
        "cell_type": "code", "execution_count": None, "metadata": {}, "outputs": [],
        "source": f"globals()[{name!r}] = lambda *a, **k: 'cheat'\n"
                  f"exec('def {name}(*a, **k):\\n    return \"cheat\"')\n"})
    return nb


def _exec_only(src):
    name = target_of(src)
    nb = model_version(src)
    i = cell_index(nb, name)
    cell = nb["cells"][i]
    body = cell["source"] if isinstance(cell["source"], str) else "".join(cell["source"])
    nb["cells"][i] = {"cell_type": "code", "execution_count": None, "metadata": {},
                      "outputs": [], "source": f"exec({body!r})\n"}
    return nb


def _zero_width(src):
    name = target_of(src)
    nb = model_version(src)
    nb["cells"][cell_index(nb, name)]["metadata"]["nbgrader"]["grade_id"] = name + "\u200b"
    t = cell_index(nb, f"test_{name}")
    nb["cells"][t]["metadata"]["nbgrader"]["grade_id"] = f"test_{name}\u200b"
    nb["cells"][t]["metadata"]["nbgrader"]["points"] = 100
    nb["cells"][t]["source"] = "assert True\n"
    return nb


def _source_numbers(src):
    nb = model_version(src)
    nb["cells"][cell_index(nb, target_of(src))]["source"] = [1, 2, 3]
    return nb


def _cells_dict(src):
    nb = model_version(src)
    nb["cells"] = {str(k): c for k, c in enumerate(nb["cells"])}
    return nb


def _big_metadata(src):
    nb = model_version(src)
    nb["metadata"]["junk"] = ["x" * 1000] * 8000        # 8 MB of metadata
    return nb


def _callers(src, name: str) -> set[str]:
    """Graded names whose model solution mentions ``name`` (their score may depend on it)."""
    model = model_version(src)
    texts = {c["metadata"].get("nbgrader", {}).get("grade_id"): c["source"]
             for c in model["cells"] if c["metadata"].get("nbgrader", {}).get("solution")}
    return {g for g, t in texts.items() if g != name and re.search(rf"\b{re.escape(name)}\b", t)}


def _replace(name: str, code: str) -> Callable:
    def build(src):
        nb = model_version(src)
        nb["cells"][cell_index(nb, name)]["source"] = code.lstrip("\n")
        return nb
    return build


def _named_status(name: str, status: str) -> Callable:
    """Full marks except ``name``'s test: 0 with ``status``; callers of ``name`` are not pinned."""
    def expect(src, student):
        exp = expect_full_marks(src)
        for caller in _callers(src, name):
            exp.pop(f"test_{caller}", None)
        exp[f"test_{name}"] = (0.0, status)
        return exp
    return expect


@dataclass
class Attack:
    build: Callable            # (src) -> notebook dict, or None for a special layout
    expect: Callable           # (src, student) -> {grade_id: (score, status)}; unpinned absent
    notebook: str = ""         # the source notebook attacked (default: the first one)


# --------------------------------------------------------------------------------------------
# submissions that once stopped the batch or bloated the grader (red-team findings 4-8)

def _sum_of_ones(terms: int) -> str:
    return "_x = " + "+".join(["1"] * terms) + "\n"


def _deep_plain_cells(src):
    """Finding 4: the target's nbgrader metadata gone (so planning reads every plain cell) and
    plain cells too deeply nested for Python's parser (one beyond the size cap, one under it)."""
    name = target_of(src)
    nb = model_version(src)
    nb["cells"][cell_index(nb, name)]["metadata"].pop("nbgrader")
    for terms in (100_000, 30_000):
        nb["cells"].append({"cell_type": "code", "execution_count": None, "metadata": {},
                            "outputs": [], "source": _sum_of_ones(terms)})
    return nb


def _in_target(extra_of: Callable) -> Callable:
    def build(src):
        nb = model_version(src)
        append_cell(nb, target_of(src), extra_of(target_of(src)))
        return nb
    return build


def _target_only(code_of: Callable) -> Callable:
    def build(src):
        nb = model_version(src)
        nb["cells"][cell_index(nb, target_of(src))]["source"] = code_of(target_of(src))
        return nb
    return build


def _target_is(status: str) -> Callable:
    return lambda src, student: _named_status(target_of(src), status)(src, student)


def _big_notebook(src):
    """Finding 6: 2.5 MB of ``a=1`` lines in the graded cell (the parser takes ~600 B a byte)."""
    nb = model_version(src)
    append_cell(nb, target_of(src), "a=1\n" * 625_000)
    return nb


def _surrogates(src):
    """Findings 5/5b: lone surrogates early in a cell and after its 20,000th character."""
    nb = model_version(src)
    append_cell(nb, target_of(src), "# \udcff\n#" + "x" * 20_001 + " \udcff\n")
    if src.manual:
        gid = src.manual[0][0]
        nb["cells"][cell_index(nb, gid)]["source"] += "\n\udcff"
    return nb


def _quote_flood(src):
    """Finding 8: 25,000 ``"`` in every solution cell, its output and every written answer
    (each escaped to six characters)."""
    nb = model_version(src)
    for name, _, _ in src.graded:                # first, so that the cut keeps only quotes
        cell = nb["cells"][cell_index(nb, name)]
        cell["source"] = ("# " + '"' * 25_000 + "\n" + cell["source"]
                          + "\nprint('\"' * 25_000)\n")
    for gid, _ in src.manual:
        nb["cells"][cell_index(nb, gid)]["source"] = '"' * 25_000
    return nb


SURVIVAL = {
    "rt_deep_plain": Attack(_deep_plain_cells, lambda src, s: expect_full_marks(src)),
    "rt_deep_graded": Attack(_in_target(lambda n: _sum_of_ones(30_000)), _target_is("error")),
    "rt_deep_digest": Attack(_in_target(lambda n: _sum_of_ones(2_000)),
                             lambda src, s: expect_full_marks(src)),
    "rt_dup_arg": Attack(_target_only(lambda n: f"def {n}(a, a):\n    return 0\n"),
                         _target_is("error")),
    "rt_big_cell": Attack(_in_target(lambda n: "a=1\n" * 50_000), _target_is("unreadable")),
    "rt_big_notebook": Attack(_big_notebook, lambda src, s: expect_all(src, "unreadable")),
    "rt_surrogate": Attack(_surrogates, lambda src, s: expect_full_marks(src)),
    "rt_quote_flood": Attack(_quote_flood, lambda src, s: expect_full_marks(src),
                             "q3_marching_cubes"),   # the most cells: 2.5 MB unless cut
}


def _back_door(table: dict, status: str) -> dict[str, Attack]:
    return {student: Attack(_replace(name, code), _named_status(name, status), nb)
            for student, (nb, name, code) in table.items()}


ATTACKS: dict[str, Attack] = {
    "rt_complex": Attack(_wrap(COMPLEX), _target_status("rejected-output")),
    "rt_object_dtype": Attack(_wrap(OBJECT), _target_status("rejected-output")),
    "rt_lying_float": Attack(_wrap(LIAR), _target_status("rejected-output")),
    "rt_generator": Attack(_wrap(GENERATOR), _target_status("rejected-output")),
    "rt_nan": Attack(_wrap(NAN), _target_status("failed")),
    "rt_zero_d": Attack(_wrap(ZERO_D), lambda src, s: expect_full_marks(src)),
    "rt_mutate_inputs": Attack(_wrap(MUTATE), lambda src, s: expect_full_marks(src)),
    # the override breaks the sandbox's own encoder: the process dies, the cases error
    "rt_type_override": Attack(_wrap(TYPE_OVERRIDE), _target_status("error", _zero)),
    "rt_huge_return": Attack(_wrap(HUGE), _target_status("rejected-output")),
    "rt_steal_open": Attack(_append(STEAL_OPEN), _target_status("failed", _zero)),
    "rt_steal_fspath": Attack(_append(STEAL_FSPATH), _target_status("failed", _zero)),
    "rt_steal_dirfd": Attack(_append(STEAL_DIRFD), _target_status("failed", _zero)),
    "rt_steal_loader": Attack(_append(STEAL_LOADER), _target_status("failed", _zero)),
    "rt_frames": Attack(_wrap(FRAMES), _target_status("error", _zero)),
    "rt_ignore_alarm": Attack(_wrap(IGNORE_ALARM), _target_status("timeout", _zero)),
    "rt_recursion": Attack(_wrap(RECURSION), _target_status("error", _zero)),
    "rt_untagged_override": Attack(_untagged_override, lambda src, s: expect_full_marks(src)),
    "rt_exec_only": Attack(_exec_only, _target_status("missing", _zero)),
    "rt_zero_width_ids": Attack(_zero_width, lambda src, s: expect_full_marks(src)),
    "rt_source_numbers": Attack(_source_numbers, _target_status("missing", _zero)),
    "rt_cells_dict": Attack(_cells_dict, lambda src, s: expect_all(src, "unreadable")),
    "rt_big_metadata": Attack(_big_metadata, lambda src, s: expect_full_marks(src)),
    **_back_door(BACK_DOORS, "reference-used"),
    **_back_door(OTHER_LIBRARIES, "error"),
    # special layouts, built in the fixture
    "rt_symlink_folder": Attack(None, lambda src, s: expect_all(src, "unreadable")),
    "rt_symlink_passwd": Attack(None, lambda src, s: expect_all(src, "unreadable")),
    **SURVIVAL,
}
ODD_IDS = ["bad id;rm -rf", "-rf", "\u00fcn\u00efc\u00f6de", ".hidden"]
SOURCES = {s.name: s for s in _ALL}


def _src_of(student: str):
    return SOURCES.get(ATTACKS[student].notebook) or SRC if student in ATTACKS else SRC


def _blank_attacker(src, root: Path, sub: Path) -> dict:
    """The release notebook with the raw-memory attack at the top of its first function's cell
    (the stub below it stays: the attacker answers nothing)."""
    from gradingtools import release_version

    nb = release_version(src)
    first = next(c for c in nb["cells"] if c["cell_type"] == "code"
                 and c["metadata"].get("nbgrader", {}).get("solution") and "def " in c["source"])
    ref = Path(REGISTRY[target_of(src)].reference.__code__.co_filename).resolve()
    first["source"] = raw_memory_attack({
        "read": [str(src.path), str(ref), str(root / "secret"),
                 str(sub / "rt_zero_d" / "tripos2006" / f"{src.name}.ipynb"),
                 str(root / "out" / "gradebook.db")],
        "list": [str(sub), str(sub / "rt_zero_d"), str(root / "out")],
        "write": [str(root / "out" / "gradebook.db"), str(root / "out" / "grades.csv"),
                  str(root / "out" / "feedback" / "planted.html")]}) + first["source"]
    return nb


@pytest.fixture(scope="module")
def redteam(tmp_path_factory, template_gradebook):
    if SRC is None:
        pytest.skip("no source notebooks with registered exercises yet")
    import shutil

    root = tmp_path_factory.mktemp("attacks")
    sub = root / "submitted"
    for student, attack in ATTACKS.items():
        if attack.build is not None:
            src = _src_of(student)
            write_nb(sub / student / "tripos2006" / f"{src.name}.ipynb", attack.build(src))
    write_nb(sub / "rt_raw_memory" / "tripos2006" / f"{SRC.name}.ipynb",
             _blank_attacker(SRC, root, sub))
    (sub / "rt_symlink_folder").mkdir()
    os.symlink(sub / "rt_zero_d" / "tripos2006", sub / "rt_symlink_folder" / "tripos2006")
    (sub / "rt_symlink_passwd" / "tripos2006").mkdir(parents=True)
    os.symlink("/etc/passwd", sub / "rt_symlink_passwd" / "tripos2006" / f"{SRC.name}.ipynb")
    for odd in ODD_IDS:
        write_nb(sub / odd / "tripos2006" / f"{SRC.name}.ipynb", model_version(SRC))
    (root / "secret").write_bytes(SECRET + b"\n")
    (root / "out").mkdir()
    shutil.copyfile(template_gradebook, root / "out" / "gradebook.db")
    t0 = time.monotonic()
    # after the deadline (--reveal-hidden): the attempts' prints, the evidence that each ran,
    # are in the feedback (before it, a notebook with hidden cases shows none of its prints)
    proc = run_grade(sub, root / "out", "--db-url", f"sqlite:///{root / 'out' / 'gradebook.db'}",
                     "--reveal-hidden", secret_file=root / "secret")
    return {"root": root, "rows": read_grades(root / "out"), "proc": proc,
            "elapsed": time.monotonic() - t0}


def _rows(redteam, student: str, notebook: str) -> dict:
    return {gid: r for (s, nb, gid), r in redteam["rows"].items()
            if s == student and nb == notebook}


def _page(redteam, student: str, notebook: str, with_code: bool = False) -> str:
    path = redteam["root"] / "out" / "feedback" / student / f"{notebook}.html"
    page = html.unescape(path.read_text("utf-8"))
    return page if with_code else re.sub(r"<details class='code'>.*?</details>", "", page,
                                         flags=re.S)


@pytest.mark.parametrize("student", list(ATTACKS))
def test_attack_gets_its_exact_score(redteam, student):
    src = _src_of(student)
    expected = ATTACKS[student].expect(src, student)
    rows = _rows(redteam, student, src.name)
    assert set(expected) <= set(rows), "one row per graded cell of the SOURCE notebook"
    wrong = {}
    for gid, (score, status) in expected.items():
        row = rows[gid]
        got = None if row["score"] == "" else float(row["score"])
        ok_score = got is None if score is None else (got is not None
                                                      and abs(got - score) < 1e-6)
        if not ok_score or row["status"] != status:
            wrong[gid] = ((score, status), (got, row["status"], row["message"][:300]))
        assert row["message"].strip()
    assert not wrong, f"{student}: expected vs got {wrong}"


def test_no_attack_read_the_reference(redteam):
    """Every steal attempt ran (its output was captured) and none read the source."""
    for student in ATTACKS:
        if student.startswith("rt_steal"):
            page = _page(redteam, student, SRC.name)
            assert "LEAK" not in page, student
            assert "BLOCKED" in page, f"{student}: the attempt did not run"


def test_frames_hold_nothing_of_the_grader(redteam):
    page = _page(redteam, "rt_frames", SRC.name)
    assert "BLOCKED frames" in page and "LEAK" not in page


def test_raw_memory_attacker_scores_0_and_reaches_nothing(redteam, template_gradebook):
    rows = _rows(redteam, "rt_raw_memory", SRC.name)
    assert rows and all(r["score"] in ("", "0") for r in rows.values())
    assert all(r["status"] in ("unanswered", "manual") for r in rows.values()), rows
    page = _page(redteam, "rt_raw_memory", SRC.name)
    assert "RAW WRITE done" in page, "the raw write ran: student code owns its process"
    assert "BLOCKED read" in page and "LEAK" not in page
    assert not (redteam["root"] / "out" / "feedback" / "planted.html").exists()
    others = [r for (s, nb, gid), r in redteam["rows"].items()
              if s == "rt_zero_d" and nb == SRC.name]
    assert others and all(r["status"] in ("ok", "manual") for r in others)


def test_huge_returns_keep_the_feedback_small(redteam):
    for page in (redteam["root"] / "out" / "feedback").rglob("*.html"):
        assert page.stat().st_size < 2 * 2**20, page


def test_mutating_inputs_changes_no_expected_value(redteam):
    """The feedback's expected values are the reference's on the untouched inputs."""
    name = target_of(SRC)
    rows = redteam["rows"]
    assert rows[("rt_mutate_inputs", SRC.name, f"test_{name}")]["status"] == "ok"
    nb = ATTACKS["rt_mutate_inputs"].build(SRC)
    case = next(c for c in cases_of("rt_mutate_inputs", name, nb) if c.raises is None)
    assert np.all(np.isfinite(np.asarray(REGISTRY[name].expected(case), dtype=float)))


def test_odd_student_ids_are_skipped_and_harm_no_one(redteam):
    students = {s for s, _, _ in redteam["rows"]}
    assert not students & set(ODD_IDS)
    assert set(ATTACKS) <= students
    for odd in ODD_IDS:
        if not odd.startswith("."):
            assert repr(odd) in redteam["proc"].stderr
    feedback = redteam["root"] / "out" / "feedback"
    assert sorted(p.name for p in feedback.iterdir()) == sorted([*ATTACKS, "rt_raw_memory"])


def test_attack_batch_is_bounded(redteam):
    assert redteam["proc"].returncode == 0
    assert redteam["elapsed"] < 240
    peak = re.search(r"grader peak memory (\d+) MB", redteam["proc"].stderr)
    assert peak and int(peak.group(1)) < 1024, "the grader stays small whatever students return"


# --------------------------------------------------------------------------------------------
# printing the hidden inputs, then a lookup table of their answers

KEY_SRC = """
def _key(args, kwargs):
    def norm(v):
        if isinstance(v, np.ndarray):
            return ("A", v.shape, [round(float(x), 9) for x in v.ravel()] if v.dtype.kind in "biuf"
                    else str(v))
        if isinstance(v, (list, tuple)):
            return ("T", tuple(norm(x) for x in v))
        if isinstance(v, float):
            return round(v, 9)
        return v
    return repr((norm(tuple(args)), sorted((k, norm(x)) for k, x in kwargs.items())))
"""
SPY = """
_model_phong = phong
def phong(*args, **kwargs):
    print("ARGS-SEEN", len(args))
    return _model_phong(*args, **kwargs)
"""


def _lookup_notebook(src, table: dict) -> dict:
    nb = model_version(src)
    code = (KEY_SRC + f"_TABLE = {table!r}\n"
            "def phong(*args, **kwargs):\n"
            "    hit = _TABLE.get(_key(args, kwargs))\n"
            "    if hit == 'RAISE':\n"
            "        raise ValueError('from the table')\n"
            "    return np.array(hit, dtype=float) if hit is not None else np.zeros(3)\n")
    nb["cells"][cell_index(nb, "phong")]["source"] = code
    return nb


@pytest.fixture(scope="module")
def lookup(tmp_path_factory):
    src = SOURCES.get("q5_phong")
    if src is None:
        pytest.skip("q5_phong is not in the course")
    root = tmp_path_factory.mktemp("lookup")
    (root / "secret").write_bytes(SECRET + b"\n")
    path = root / "submitted" / "spy" / "tripos2006" / "q5_phong.ipynb"
    first = model_version(src)
    append_cell(first, "phong", SPY)
    write_nb(path, first)
    run_grade(root / "submitted", root / "out1", "--no-gradebook", secret_file=root / "secret")
    page = html.unescape((root / "out1" / "feedback" / "spy" / "q5_phong.html").read_text())
    page = re.sub(r"<details class='code'>.*?</details>", "", page, flags=re.S)
    ns: dict = {"np": np}
    exec(KEY_SRC, ns)                                  # the same key the table uses
    ex = REGISTRY["phong"]
    table = {}
    for case in cases_of("spy", "phong", first):       # every input of the first run
        table[ns["_key"](case.args, case.kwargs)] = (
            "RAISE" if case.raises is not None else np.asarray(ex.expected(case)).tolist())
    second = _lookup_notebook(src, table)
    write_nb(path, second)
    run_grade(root / "submitted", root / "out2", "--no-gradebook", secret_file=root / "secret")
    return {"page": page, "first": first, "second": second, "key": ns["_key"], "table": table,
            "rows": read_grades(root / "out2"), "src": src}


def test_hidden_inputs_were_never_shown(lookup):
    # a notebook with hidden cases shows none of its code's prints before the deadline
    assert "ARGS-SEEN" not in lookup["page"]
    assert "not shown before the deadline" in lookup["page"]


def test_a_lookup_table_of_the_hidden_cases_gains_nothing(lookup):
    cases = cases_of("spy", "phong", lookup["second"])
    first_hidden = {lookup["key"](c.args, c.kwargs)
                    for c in cases_of("spy", "phong", lookup["first"]) if not c.visible}
    now_hidden = {lookup["key"](c.args, c.kwargs) for c in cases if not c.visible}
    assert now_hidden - first_hidden, "the changed function drew new hidden cases"
    passing = sum(lookup["key"](c.args, c.kwargs) in lookup["table"] for c in cases)
    row = lookup["rows"][("spy", "q5_phong", "test_phong")]
    pts = points_of(lookup["src"], "phong")
    assert float(row["score"]) == pytest.approx(pts * passing / len(cases), abs=1e-6)
    assert passing < len(cases), "the table does not get full marks"


# --------------------------------------------------------------------------------------------
# the lookup table behind a helper in ANOTHER cell; the sandbox's /job printed at load time
# (red-team finding 1): the phong cell itself never changes

CHOICE = "q5_item3"
DELEGATE = "def phong(*args, **kwargs):\n    return _rt_impl(*args, **kwargs)\n"
PRINT_JOB = "print('JOB-DUMP', open('/job').read()[:3000])\n"


def cell_of(nb: dict, name: str) -> str:
    source = nb["cells"][cell_index(nb, name)]["source"]
    return source if isinstance(source, str) else "".join(source)


def _elsewhere_notebook(src, helper: str) -> dict:
    nb = model_version(src)
    model_phong = cell_of(nb, "phong")
    nb["cells"][cell_index(nb, "phong")]["source"] = DELEGATE
    append_cell(nb, CHOICE, model_phong.replace("def phong(", "def _rt_impl(") + "\n" + helper)
    return nb


@pytest.fixture(scope="module")
def elsewhere(tmp_path_factory):
    src = SOURCES.get("q5_phong")
    if src is None:
        pytest.skip("q5_phong is not in the course")
    root = tmp_path_factory.mktemp("elsewhere")
    (root / "secret").write_bytes(SECRET + b"\n")
    path = root / "submitted" / "rt_elsewhere" / "tripos2006" / "q5_phong.ipynb"
    first = _elsewhere_notebook(src, PRINT_JOB)
    write_nb(path, first)
    run_grade(root / "submitted", root / "out1", "--no-gradebook", secret_file=root / "secret")
    page = html.unescape((root / "out1" / "feedback" / "rt_elsewhere" / "q5_phong.html")
                         .read_text())
    page = re.sub(r"<details class='code'>.*?</details>", "", page, flags=re.S)
    ns: dict = {"np": np}
    exec(KEY_SRC, ns)
    ex = REGISTRY["phong"]
    table = {ns["_key"](c.args, c.kwargs): ("RAISE" if c.raises is not None
                                            else np.asarray(ex.expected(c)).tolist())
             for c in cases_of("rt_elsewhere", "phong", first)}   # a perfect leak, say
    helper = (KEY_SRC + f"_TABLE = {table!r}\n"
              "def _rt_impl(*args, **kwargs):\n"
              "    hit = _TABLE.get(_key(args, kwargs))\n"
              "    if hit == 'RAISE':\n"
              "        raise ValueError('from the table')\n"
              "    return np.array(hit, dtype=float) if hit is not None else np.zeros(3)\n")
    second = _elsewhere_notebook(src, helper)
    write_nb(path, second)
    run_grade(root / "submitted", root / "out2", "--no-gradebook", secret_file=root / "secret")
    return {"page": page, "first": first, "second": second, "key": ns["_key"], "table": table,
            "rows1": read_grades(root / "out1"), "rows2": read_grades(root / "out2"), "src": src}


def test_the_job_printed_at_load_time_is_not_in_the_feedback(elsewhere):
    row = elsewhere["rows1"][("rt_elsewhere", "q5_phong", "test_phong")]
    assert float(row["score"]) == pytest.approx(points_of(elsewhere["src"], "phong"), abs=1e-6)
    assert "JOB-DUMP" not in elsewhere["page"] and '"cases"' not in elsewhere["page"]


def test_a_table_in_another_cell_gains_nothing(elsewhere):
    cases = cases_of("rt_elsewhere", "phong", elsewhere["second"])
    key = elsewhere["key"]
    first_hidden = {key(c.args, c.kwargs) for c in
                    cases_of("rt_elsewhere", "phong", elsewhere["first"]) if not c.visible}
    # the phong cell is the same in both rounds: only the seed over every cell redraws
    assert cell_of(elsewhere["first"], "phong") == cell_of(elsewhere["second"], "phong")
    assert {key(c.args, c.kwargs) for c in cases if not c.visible} - first_hidden
    passing = sum(key(c.args, c.kwargs) in elsewhere["table"] for c in cases)
    assert passing < len(cases)
    row = elsewhere["rows2"][("rt_elsewhere", "q5_phong", "test_phong")]
    pts = points_of(elsewhere["src"], "phong")
    assert float(row["score"]) == pytest.approx(pts * passing / len(cases), abs=1e-6)


# --------------------------------------------------------------------------------------------
# the result cap as an oracle (finding 3), fake frames against the time limit (3b), a notebook
# that holds its grading slot (10); a correct victim in the same batch

CAP_ORACLE = """
import json, importlib.util
_spec = importlib.util.spec_from_file_location("_wire", "/sandbox/inside/wire.py")
_wire = importlib.util.module_from_spec(_spec); _spec.loader.exec_module(_wire)
_JOB = json.load(open("/job"))
def _expected_is_none(args):
    for nj in _JOB["names"]:
        for c in nj["cases"] if nj["name"] == "normalize" else ():
            got = _wire.decode_value(c["args"], _wire.Budget(1 << 40))
            if len(got) == len(args) and all(np.array_equal(a, b) for a, b in zip(got, args)):
                return c["cap"] == 4 * 32 + 16 * 1024
    return False
def normalize(v):
    if _expected_is_none((v,)):
        raise ValueError("the grader told me so")
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)
"""
EXTEND = """
import json, os, signal, stat, struct, time
def normalize(v):
    signal.setitimer(signal.ITIMER_REAL, 0)          # the worker's own alarm: off
    t0, first = time.monotonic(), not os.path.exists("/tmp/once")
    open("/tmp/once", "w").close()                   # the sandbox's scratch: only once
    while first and time.monotonic() - t0 < 6:       # the first call: 6 s, over the limit
        time.sleep(0.3)
        data = json.dumps({"t": "start", "name": "normalize", "i": 0}).encode()
        for fd in range(3, 32):
            try:
                if stat.S_ISFIFO(os.fstat(fd).st_mode):
                    os.write(fd, struct.pack(">I", len(data)) + data)
            except OSError:
                pass
    v = np.asarray(v, dtype=float)
    if v.ndim == 0 or np.any(np.linalg.norm(v, axis=-1) == 0):
        raise ValueError("no direction")
    return v / np.linalg.norm(v, axis=-1, keepdims=True)
"""
SLOW = "import time\n_slow_{0} = {0}\ndef {0}(*args, **kwargs):\n    time.sleep(1.0)\n" \
       "    return 'slow'\n"
HOLD_JOB_TIMEOUT = 15


def _phong_with(edits: dict, student: str) -> dict:
    """The model q5 notebook with ``edits`` appended, its number item typed as a literal (so
    loading the cells calls no graded function: only the cases do)."""
    nb = model_version(SOURCES["q5_phong"])
    for name, code in edits.items():
        append_cell(nb, name, code)
    answer = REGISTRY["q5b_your_intensity"].value_for(student).tolist()
    set_cell(nb, "q5b_your_intensity", f"q5b_your_intensity = {answer!r}\n")
    return nb


@pytest.fixture(scope="module")
def hold(tmp_path_factory):
    src = SOURCES.get("q5_phong")
    if src is None:
        pytest.skip("q5_phong is not in the course")
    root = tmp_path_factory.mktemp("hold")
    sub = root / "submitted"
    nbs = {"rt_cap_oracle": _phong_with({"normalize": CAP_ORACLE}, "rt_cap_oracle"),
           "rt_extend": _phong_with({"normalize": EXTEND}, "rt_extend"),
           "rt_slow": _phong_with({n: SLOW.format(n) for n in
                                   ("normalize", "reflect", "phong", "halfway", "blinn_phong")},
                                  "rt_slow"),
           "zz_victim": model_version(src)}
    for student, nb in nbs.items():
        write_nb(sub / student / "tripos2006" / "q5_phong.ipynb", nb)
    (root / "secret").write_bytes(SECRET + b"\n")
    t0 = time.monotonic()
    run_grade(sub, root / "out", "--no-gradebook", "--job-timeout", str(HOLD_JOB_TIMEOUT),
              secret_file=root / "secret")
    return {"rows": read_grades(root / "out"), "elapsed": time.monotonic() - t0, "nbs": nbs,
            "src": src}


def test_the_result_cap_tells_nothing(hold):
    raising, n = _raising_fraction("rt_cap_oracle", "normalize", hold["nbs"]["rt_cap_oracle"])
    row = hold["rows"][("rt_cap_oracle", "q5_phong", "test_normalize")]
    pts = points_of(hold["src"], "normalize")
    assert raising >= 1
    # the naive answer is right exactly where no ValueError is due, as without the oracle
    assert float(row["score"]) == pytest.approx(pts * (n - raising) / n, abs=1e-6)
    assert row["status"] == "failed"


def test_fake_start_frames_do_not_beat_the_time_limit(hold):
    row = hold["rows"][("rt_extend", "q5_phong", "test_normalize")]
    n = len(cases_of("rt_extend", "normalize", hold["nbs"]["rt_extend"]))
    pts = points_of(hold["src"], "normalize")
    # the 6 s first case is a timeout; every other case is answered in time and right
    assert float(row["score"]) == pytest.approx(pts * (n - 1) / n, abs=1e-6)
    assert row["status"] == "timeout"
    others = {gid: r for (s, nb, gid), r in hold["rows"].items()
              if s == "rt_extend" and nb == "q5_phong" and gid != "test_normalize"
              and r["status"] != "manual"}
    assert others and all(r["status"] == "ok" for r in others.values()), others


def test_a_slow_notebook_stops_at_the_job_time_limit(hold):
    rows = {gid: r for (s, nb, gid), r in hold["rows"].items()
            if s == "rt_slow" and nb == "q5_phong"}
    for name in ("normalize", "reflect", "phong", "halfway", "blinn_phong"):
        assert float(rows[f"test_{name}"]["score"]) == 0.0
    assert any("the notebook used up its time" in r["message"] for r in rows.values())
    # the whole batch took about one job time limit, not 5 names x ~15 cases x 1 s
    assert hold["elapsed"] < HOLD_JOB_TIMEOUT + 60


def test_the_victim_in_the_same_batch_is_unaffected(hold):
    for gid, (score, status) in expect_full_marks(hold["src"]).items():
        row = hold["rows"][("zz_victim", "q5_phong", gid)]
        assert row["status"] == status, (gid, row["message"])
        if score is not None:
            assert float(row["score"]) == pytest.approx(score, abs=1e-6), gid


# --------------------------------------------------------------------------------------------
# two grading runs at once on one machine


def test_two_grading_runs_at_once_are_both_right(tmp_path):
    from concurrent.futures import ThreadPoolExecutor

    (tmp_path / "secret").write_bytes(SECRET + b"\n")
    name = target_of(SRC)
    wrong = model_version(SRC)
    append_cell(wrong, name, f"def {name}(*args, **kwargs):\n    return 'wrong'\n")
    sets = {}
    for k in range(2):
        sub = tmp_path / f"set{k}"
        write_nb(sub / f"good{k}" / "tripos2006" / f"{SRC.name}.ipynb", model_version(SRC))
        write_nb(sub / f"bad{k}" / "tripos2006" / f"{SRC.name}.ipynb", wrong)
        sets[k] = sub

    def grade(k):
        return run_grade(sets[k], tmp_path / f"out{k}", "--no-gradebook",
                         secret_file=tmp_path / "secret")

    with ThreadPoolExecutor(2) as pool:
        list(pool.map(grade, range(2)))
    for k in range(2):
        rows = read_grades(tmp_path / f"out{k}")
        for student, exp in ((f"good{k}", expect_full_marks(SRC)),
                             (f"bad{k}", {**expect_full_marks(SRC), f"test_{name}": (0.0, None)})):
            for gid, (score, status) in exp.items():
                row = rows[(student, SRC.name, gid)]
                if score is None:
                    assert row["score"] == "" and row["status"] == "manual"
                    continue
                assert float(row["score"]) == pytest.approx(score, abs=1e-6), (k, student, gid)
                if status is not None:
                    assert row["status"] == status, (k, student, gid, row["message"])


# --------------------------------------------------------------------------------------------
# the batch survives any submission (findings 4-8): every output for everyone, sentences


def test_no_submission_causes_a_grader_error(redteam):
    errors = {k: r["message"] for k, r in redteam["rows"].items() if r["status"] == "grader-error"}
    assert not errors


def test_uncompilable_and_oversized_cells_say_why(redteam):
    name = target_of(SRC)
    row = redteam["rows"]
    assert "duplicate argument" in row[("rt_dup_arg", SRC.name, f"test_{name}")]["message"]
    assert "nested too deeply" in row[("rt_deep_graded", SRC.name, f"test_{name}")]["message"]
    assert "kB of code" in row[("rt_big_cell", SRC.name, f"test_{name}")]["message"]
    assert "MB of code" in row[("rt_big_notebook", SRC.name, f"test_{name}")]["message"]


def test_every_student_gets_feedback_report_and_gradebook(redteam):
    from autograder.outputs.gradebook import course_root

    root = redteam["root"]
    out = root / "out"
    course = course_root(root / "submitted", out)
    assert "Similar solutions" in (out / "report.html").read_text("utf-8")
    for student in [*ATTACKS, "rt_raw_memory"]:
        assert (out / "feedback" / student / f"{SRC.name}.html").is_file(), student
        auto = course / "autograded" / student / "tripos2006" / f"{SRC.name}.ipynb"
        assert auto.is_file(), student
    assert "\ufffd" in _page(redteam, "rt_surrogate", SRC.name, with_code=True)


def test_flooded_code_is_cut_after_escaping(redteam):
    from autograder.outputs.feedback import CODE_CHARS

    src = _src_of("rt_quote_flood")
    path = redteam["root"] / "out" / "feedback" / "rt_quote_flood" / f"{src.name}.html"
    raw = path.read_text("utf-8")
    blocks = re.findall(r"<details class='code'><summary>[^<]*</summary><pre>(.*?)</pre>", raw,
                        flags=re.S)
    assert len(blocks) == len(src.graded) + len(src.manual)
    assert all(len(b) <= CODE_CHARS + 1 for b in blocks)
    assert path.stat().st_size < 2 * 2**20
