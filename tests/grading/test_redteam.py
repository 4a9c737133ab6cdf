"""Red-team attacks on the batch grader, beyond the bank of ``test_bank.py``.

Each attack is a submission built like the bank's (the model answers of one source notebook
with one edit), graded in ONE batch (``python -m autograder grade --jobs 2``) with an exact
expected score and status for every graded cell. The expected values are decided here: full
points from the source notebook, partial credit from the registry's cases drawn with the
grader's documented seed, and for the attacked function the cases its honest part still gets
right (the bad-input cases, where the model raises before the attack's code returns anything).

What the attacks try (and what the grader must do):

- answers that are not plain floats: complex or object arrays, an object whose ``__float__``
  and ``__array__`` tell the right answer, a generator (``rejected-output``); NaN answers
  (``failed``); a 0-d array where a float is expected (full marks: it *is* the number);
- mutating the input arrays in place after computing the answer (no effect: the expected
  value is computed in the grader's process on its own copy);
- stealing the ``course_lib`` reference past the sandbox's audit hook so that
  ``reference-used`` never fires: by patching ``builtins.isinstance`` or ``posixpath`` (which
  the hook used to call), with a path-like object or ``str`` subclass that answers differently
  when checked and when opened, through a ``dir_fd``, by editing the hook's configuration
  reached from a traceback or from ``gc``, or by reloading/reading the module through its
  loader. Each must fail to read the source (the attack then returns a wrong answer: 0);
- overriding ``builtins.type``/``isinstance`` to fool the child's encoder; forging the
  manifest (fake results and a ``done``, a ``.npz`` whose header claims a gigantic array);
- ignoring ``SIGALRM`` and cancelling the alarm in an endless loop (``timeout``); runaway
  recursion through C calls that overflows the C stack (``error``: the process crashes);
- defining the graded name in an untagged later cell through ``globals()``/``exec`` (ignored:
  the solution cell is graded), or only through ``exec`` after deleting the solution cell
  (``missing``); zero-width characters in grade_ids; a solution cell whose source is a list of
  numbers (ignored: ``missing``); ``cells`` that is not a list (``unreadable``); megabytes of
  notebook metadata (graded normally);
- a submission folder that is a symbolic link to another student's folder, a notebook that is
  a symbolic link to ``/etc/passwd`` (``unreadable``), and student folders with odd names
  (skipped with a warning, nobody else affected).
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
                          model_version, read_grades, run_grade, target_of, write_nb)

from autograder.exercises import REGISTRY

pytestmark = [pytest.mark.xdist_group("grading")]

_ALL = course_sources()
SRC = _ALL[0] if _ALL else None








def _raising_fraction(student: str, name: str) -> tuple[int, int]:
    """(cases where a ValueError is the right answer, all cases) for ``student``."""
    cases = cases_of(student, name)
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
            raising, n = _raising_fraction(student, name)
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

# --------------------------------------------------------------------------------------------
# stealing the reference past the audit hook (each returns a wrong answer if the read fails)

def _steal(opener: str, prelude: str = "", after: str = "") -> Callable:
    def code_of(src, name):
        ref = REGISTRY[name].reference
        path = Path(ref.__code__.co_filename).resolve()
        return f"""
def _steal_it():
    {prelude.strip() or 'pass'}
    try:
        text = ({opener.format(path=str(path))})
    except BaseException as exc:
        print("BLOCKED", type(exc).__name__)
        return None
    finally:
        {after.strip() or 'pass'}
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


STEAL_ISINSTANCE = _steal(
    "open({path!r}).read()",
    prelude="import builtins; real = builtins.isinstance; "
            "builtins.isinstance = lambda o, t: True",
    after="builtins.isinstance = real")
STEAL_POSIXPATH = _steal(
    "open({path!r}).read()",
    prelude="import posixpath, os; keep = posixpath._joinrealpath; "
            "posixpath._joinrealpath = lambda path, rest, strict, seen: (os.getcwd() + '/x', True)",
    after="posixpath._joinrealpath = keep")
STEAL_FSPATH = _steal(
    "open(P()).read()",
    prelude="""class P:
        n = 0
        def __fspath__(self):
            P.n += 1
            return {path!r} if P.n % 2 else 'harmless.txt'""".replace("{path!r}", "'%s'"),
)
STEAL_STRSUB = _steal(
    "open(S({path!r})).read()",
    prelude="""class S(str):
        def startswith(self, *a): return True""")
STEAL_DIRFD = _steal(
    "os.read(os.open(os.path.relpath({path!r}, site), os.O_RDONLY, dir_fd=os.open(site, "
    "os.O_RDONLY)), 10**6)",
    prelude="import os, sysconfig; site = sysconfig.get_paths()['purelib']")
STEAL_TRACEBACK = _steal(
    "open({path!r}).read()",
    prelude="""
    try:
        open({path!r})
    except PermissionError as e:
        tb = e.__traceback__
        while tb is not None:
            for v in list(tb.tb_frame.f_locals.values()):
                if callable(v) and getattr(v, "__name__", "") == "allowed":
                    for c in (v.__closure__ or ()):
                        c.cell_contents = ("/",)
                    try:
                        v.__defaults__ = tuple(("/",) if type(x) is tuple else x
                                               for x in (v.__defaults__ or ()))
                    except PermissionError:
                        pass
            tb = tb.tb_next""")
STEAL_GC = _steal(
    "open({path!r}).read()",
    prelude="""
    import gc
    try:
        for o in gc.get_objects():
            if type(o).__name__ == "function" and o.__name__ in ("allowed", "hook"):
                for c in (o.__closure__ or ()):
                    c.cell_contents = ("/",)
    except PermissionError:
        pass""")
STEAL_LOADER = _steal(
    "__import__('importlib').import_module(mod).__loader__.get_data({path!r})",
    prelude="import importlib, sys; mod = [m for m, v in sys.modules.items() if "
            "getattr(v, '__file__', None) == {path!r}][0]; "
            "importlib.reload(sys.modules[mod]) if False else None")


def _fix_fspath(code_of):
    def fixed(src, name):
        path = str(Path(REGISTRY[name].reference.__code__.co_filename).resolve())
        return code_of(src, name).replace("'%s'", repr(path))
    return fixed


def _fill_path(code_of):
    def fixed(src, name):
        path = str(Path(REGISTRY[name].reference.__code__.co_filename).resolve())
        return code_of(src, name).replace("{path!r}", repr(path))
    return fixed


# --------------------------------------------------------------------------------------------
# the child's machinery

FORGE = """
import sys, os, numpy as np
frame = sys._getframe(1)
emit = frame.f_locals["emit"]
n = len(frame.f_locals["cases"])
# a case file whose header claims a 2**40-element array
header = "{'descr': '<f8', 'fortran_order': False, 'shape': (1099511627776,), }"
header = header + " " * (118 - len(header)) + "\\n"
import zipfile
with zipfile.ZipFile("case_0.npz", "w") as zf:
    zf.writestr("a0.npy", b"\\x93NUMPY\\x01\\x00" + len(header).to_bytes(2, "little")
                + header.encode() + b"\\x00" * 64)
emit({"ev": "case", "i": 0, "kind": "returned", "value": {"__array__": "a0"}, "arrays": True})
for i in range(1, n):
    emit({"ev": "case", "i": i, "kind": "returned", "value": "forged"})
emit({"ev": "done"})
return _model(*args, **kwargs)
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


@dataclass
class Attack:
    build: Callable            # (src) -> notebook dict, or None for a special layout
    expect: Callable           # (src, student) -> {grade_id: (score, status)}


ATTACKS: dict[str, Attack] = {
    "rt_complex": Attack(_wrap(COMPLEX), _target_status("rejected-output")),
    "rt_object_dtype": Attack(_wrap(OBJECT), _target_status("rejected-output")),
    "rt_lying_float": Attack(_wrap(LIAR), _target_status("rejected-output")),
    "rt_generator": Attack(_wrap(GENERATOR), _target_status("rejected-output")),
    "rt_nan": Attack(_wrap(NAN), _target_status("failed")),
    "rt_zero_d": Attack(_wrap(ZERO_D), lambda src, s: expect_full_marks(src)),
    "rt_mutate_inputs": Attack(_wrap(MUTATE), lambda src, s: expect_full_marks(src)),
    "rt_type_override": Attack(_wrap(TYPE_OVERRIDE), _target_status("rejected-output")),
    "rt_steal_isinstance": Attack(_append(_fill_path(STEAL_ISINSTANCE)),
                                  _target_status("failed", _zero)),
    "rt_steal_posixpath": Attack(_append(STEAL_POSIXPATH), _target_status("failed", _zero)),
    "rt_steal_fspath": Attack(_append(_fix_fspath(STEAL_FSPATH)),
                              _target_status("failed", _zero)),
    "rt_steal_strsub": Attack(_append(STEAL_STRSUB), _target_status("failed", _zero)),
    "rt_steal_dirfd": Attack(_append(STEAL_DIRFD), _target_status("failed", _zero)),
    "rt_steal_traceback": Attack(_append(_fill_path(STEAL_TRACEBACK)),
                                 _target_status("failed", _zero)),
    "rt_steal_gc": Attack(_append(STEAL_GC), _target_status("failed", _zero)),
    "rt_steal_loader": Attack(_append(_fill_path(STEAL_LOADER)),
                              _target_status("failed", _zero)),
    "rt_forge_manifest": Attack(_wrap(FORGE), _target_status("rejected-output", _zero)),
    "rt_ignore_alarm": Attack(_wrap(IGNORE_ALARM), _target_status("timeout", _zero)),
    "rt_recursion": Attack(_wrap(RECURSION), _target_status("error", _zero)),
    "rt_untagged_override": Attack(_untagged_override, lambda src, s: expect_full_marks(src)),
    "rt_exec_only": Attack(_exec_only, _target_status("missing", _zero)),
    "rt_zero_width_ids": Attack(_zero_width, lambda src, s: expect_full_marks(src)),
    "rt_source_numbers": Attack(_source_numbers, _target_status("missing", _zero)),
    "rt_cells_dict": Attack(_cells_dict, lambda src, s: expect_all(src, "unreadable")),
    "rt_big_metadata": Attack(_big_metadata, lambda src, s: expect_full_marks(src)),
    # special layouts, built in the fixture
    "rt_symlink_folder": Attack(None, lambda src, s: expect_all(src, "unreadable")),
    "rt_symlink_passwd": Attack(None, lambda src, s: expect_all(src, "unreadable")),
}
ODD_IDS = ["bad id;rm -rf", "-rf", "\u00fcn\u00efc\u00f6de", ".hidden"]


@pytest.fixture(scope="module")
def redteam(tmp_path_factory):
    if SRC is None:
        pytest.skip("no source notebooks with registered exercises yet")
    root = tmp_path_factory.mktemp("redteam")
    sub = root / "submitted"
    for student, attack in ATTACKS.items():
        if attack.build is not None:
            write_nb(sub / student / "tripos2006" / f"{SRC.name}.ipynb", attack.build(SRC))
    (sub / "rt_symlink_folder").mkdir()
    os.symlink(sub / "rt_zero_d" / "tripos2006", sub / "rt_symlink_folder" / "tripos2006")
    (sub / "rt_symlink_passwd" / "tripos2006").mkdir(parents=True)
    os.symlink("/etc/passwd", sub / "rt_symlink_passwd" / "tripos2006" / f"{SRC.name}.ipynb")
    for odd in ODD_IDS:
        write_nb(sub / odd / "tripos2006" / f"{SRC.name}.ipynb", model_version(SRC))
    (root / "secret").write_bytes(SECRET + b"\n")
    t0 = time.monotonic()
    proc = run_grade(sub, root / "out", "--no-gradebook", "--source", str(SRC.path.parent),
                     secret_file=root / "secret")
    return {"root": root, "rows": read_grades(root / "out"), "proc": proc,
            "elapsed": time.monotonic() - t0}


@pytest.mark.parametrize("student", list(ATTACKS))
def test_attack_gets_its_exact_score(redteam, student):
    expected = ATTACKS[student].expect(SRC, student)
    rows = {gid: r for (s, nb, gid), r in redteam["rows"].items()
            if s == student and nb == SRC.name}
    assert set(rows) == set(expected), "one row per graded cell of the SOURCE notebook"
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
    feedback = redteam["root"] / "out" / "feedback"
    for student in ATTACKS:
        if not student.startswith("rt_steal"):
            continue
        page = html.unescape((feedback / student / f"{SRC.name}.html").read_text("utf-8"))
        page = re.sub(r"<details class='code'>.*?</details>", "", page, flags=re.S)
        assert "LEAK" not in page, student
        assert "BLOCKED" in page, f"{student}: the attempt did not run"


def test_mutating_inputs_changes_no_expected_value(redteam):
    """The feedback's expected values are the reference's on the untouched inputs."""
    name = target_of(SRC)
    rows = redteam["rows"]
    assert rows[("rt_mutate_inputs", SRC.name, f"test_{name}")]["status"] == "ok"
    case = next(c for c in cases_of("rt_mutate_inputs", name) if c.raises is None)
    assert np.all(np.isfinite(np.asarray(REGISTRY[name].expected(case), dtype=float)))


def test_odd_student_ids_are_skipped_and_harm_no_one(redteam):
    students = {s for s, _, _ in redteam["rows"]}
    assert not students & set(ODD_IDS)
    assert set(ATTACKS) <= students
    for odd in ODD_IDS:
        if not odd.startswith("."):
            assert repr(odd) in redteam["proc"].stderr
    feedback = redteam["root"] / "out" / "feedback"
    assert sorted(p.name for p in feedback.iterdir()) == sorted(ATTACKS)


def test_redteam_batch_is_bounded(redteam):
    assert redteam["proc"].returncode == 0
    assert redteam["elapsed"] < 60
