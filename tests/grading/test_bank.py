"""The adversarial bank of issue 4: every way a submission can try to game or break grading.

Each case is a submission built from the course's own notebooks (:mod:`conftest`): the model
answers everywhere except for one edit, and an exact expected score and status for *every* graded
cell of the notebook. All cases of all notebooks are graded in ONE batch (``python -m autograder
grade --jobs 2``, as an instructor runs it), which is also the "one broken submission of every
kind" batch of the issue: it must finish in bounded time with everyone else's scores right.

The expected values are decided here, not read from the grader: full points from the *source*
notebook's test cells, 0 where tampering was attempted (raising ValueError on every input
included: bad-input cases count in proportion to the hidden ordinary cases passed), and partial credit from
the registry's case list drawn with the grader's documented seed (``case_seed(secret, student,
name)``).
"""

from __future__ import annotations

import html
import json
import os
import re
import shutil
import sqlite3
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from gradingtools import (expect_all, expect_full_marks, points_of,
                          CASE_TIMEOUT, SECRET, append_cell, cases_of, cell_index, counted_cases,
                          course_sources, gradebook_grades, model_version, read_grades,
                          release_version, run_grade, set_cell, target_of, write_nb)

from autograder.exercises import REGISTRY

pytestmark = [pytest.mark.xdist_group("bank")]

#: ``GRADING_BANK_NOTEBOOKS=q1_imaging,q5_phong`` limits the bank while developing.
_ONLY = [n for n in os.environ.get("GRADING_BANK_NOTEBOOKS", "").split(",") if n]
SOURCES = {s.name: s for s in course_sources() if not _ONLY or s.name in _ONLY}
HONEST_DIR = Path(__file__).parent / "honest"


@dataclass
class Ctx:
    student: str
    submitted: Path
    out: Path
    db: Path
    secret: Path








def _with_target(status, score=0.0):
    def expect(src, ctx):
        exp = expect_full_marks(src)
        exp[f"test_{target_of(src)}"] = (score, status)
        return exp
    return expect


def _rebind(name: str, body: str, keep_model: bool = True) -> str:
    """Code appended to a solution cell that wraps (or replaces) the function ``name``."""
    lines = [f"_model_{name} = {name}" if keep_model else "",
             f"def {name}(*args, **kwargs):"]
    lines += ["    " + ln for ln in body.strip("\n").splitlines()]
    if keep_model:
        lines.append(f"    return _model_{name}(*args, **kwargs)")
    return "\n".join(lines) + "\n"


@dataclass
class Adversary:
    build: Callable          # (src, ctx) -> {file name: notebook dict | bytes | str}
    expect: Callable         # (src, ctx) -> {grade_id: (score or None, status)}
    all_notebooks: bool = True
    message: dict = field(default_factory=dict)   # grade_id template -> words the message has
    applies: Callable = lambda src: True           # (src) -> whether the notebook can have it


def _edit(fn):
    """An adversary that edits the model version of the notebook."""
    def build(src, ctx):
        nb = model_version(src)
        nb = fn(nb, src, ctx) or nb
        return {f"{src.name}.ipynb": nb}
    return build


def _target_code(body, keep_model=True):
    return _edit(lambda nb, src, ctx: append_cell(nb, target_of(src),
                                                  _rebind(target_of(src), body, keep_model)))


# --------------------------------------------------------------------------------------------
# the cases

EQ_ALWAYS_TRUE = """
class _Sneaky:
    def __eq__(self, other): return True
    def __ne__(self, other): return False
    def __lt__(self, other): return False
    def __float__(self): return 0.0
    __hash__ = object.__hash__
return _Sneaky()
"""

SUBCLASS = """
class _Arr(np.ndarray):
    def __eq__(self, other): return np.ones(np.shape(other), bool)
class _F(float):
    def __eq__(self, other): return True
    __hash__ = float.__hash__
return _F(0.0) if len(args) % 2 else np.zeros(3).view(_Arr)
"""

MONKEYPATCH = """
import builtins
np.allclose = lambda *a, **k: True
np.isclose = lambda *a, **k: True
np.array_equal = lambda *a, **k: True
np.testing.assert_allclose = lambda *a, **k: None
builtins.AssertionError = type("AssertionError", (Exception,), {})
builtins.abs = lambda x: 0
try:
    import autograder.incell as _incell
    _incell.check = lambda *a, **k: None
except BaseException:
    pass
return "cheat"
"""

SYS_EXIT = """
import sys
sys.exit(0)
"""

OS_EXIT = """
import os
os._exit(0)
"""

INFINITE_LOOP = """
while True:
    pass
"""

SWALLOWING_LOOP = """
while True:
    try:
        while True:
            pass
    except BaseException:
        pass
"""

MEMORY_BOMB = """
hoard = [np.empty(2**27) for _ in range(1000)]     # 1000 GB, a GB at a time
"""

PRINT_FLOOD = """
import sys
for k in range(20000):
    print("flood", k, "x" * 60)
    sys.stderr.write("flood on stderr\\n")
"""

WARNINGS = """
import sys, warnings
warnings.warn("this is only a warning", RuntimeWarning)
warnings.warn("deprecated!", DeprecationWarning)
print("a note on stderr", file=sys.stderr)
"""

CRASH_EVERY_THIRD = """
global _calls
_calls = globals().get("_calls", 0) + 1
if _calls % 3 == 0:
    import signal
    signal.raise_signal(signal.SIGKILL)
"""

ALWAYS_VALUEERROR = """
raise ValueError("I refuse every input")
"""


def _reference_call(nb, src, ctx):
    name = target_of(src)
    ref = REGISTRY[name].reference
    code = (f"import course_lib\nimport importlib\n"
            f"def {name}(*args, **kwargs):\n"
            f"    module = importlib.import_module({ref.__module__!r})\n"
            f"    return getattr(module, {ref.__name__!r})(*args, **kwargs)\n")
    append_cell(nb, name, code)


def _reference_from_import(nb, src, ctx):
    name = target_of(src)
    ref = REGISTRY[name].reference
    code = (f"from {ref.__module__} import {ref.__name__} as _theirs\n"
            f"def {name}(*args, **kwargs):\n"
            f"    try:\n"
            f"        return _theirs(*args, **kwargs)\n"
            f"    except Exception:\n"
            f"        return None\n")
    append_cell(nb, name, code)


def _snoop(nb, src, ctx):
    """Read what must stay private, write to the gradebook; report success on stdout."""
    name = target_of(src)
    paths = [str(src.path), str(ctx.secret), str(ctx.db), str(ctx.out / "grades.csv"),
             str(ctx.submitted / f"adv_eq-{src.name}" / "tripos2006" / f"{src.name}.ipynb"),
             str(Path(REGISTRY[name].reference.__code__.co_filename)),
             str(Path(__file__).resolve().parents[2] / "autograder" / "exercises" / "__init__.py"),
             "/etc/shadow", "/etc/passwd", "/root/.config/4f9/secret"]
    body = f"""
import os
for p in {paths!r}:
    try:
        with open(p, "rb") as fh:
            fh.read(10)
        print("LEAK read", p)
    except BaseException as exc:
        print("BLOCKED read", type(exc).__name__)
for d in {[str(ctx.submitted), str(ctx.out)]!r}:
    try:
        os.listdir(d)
        print("LEAK listdir", d)
    except BaseException as exc:
        print("BLOCKED listdir", type(exc).__name__)
for p in {paths!r}:          # the sandbox's own / and /tmp may be listed: none of these is there
    if os.path.lexists(p) and not p.startswith("/etc/"):
        print("LEAK exists", p)
try:
    with open({str(ctx.db)!r}, "ab") as fh:
        fh.write(b"garbage")
    print("LEAK write gradebook")
except BaseException as exc:
    print("BLOCKED write", type(exc).__name__)
try:                        # (sqlite3 is not among the modules a solution may use)
    import sqlite3
    con = sqlite3.connect({str(ctx.db)!r})
    con.execute("UPDATE grade SET auto_score = 1000")
    con.commit()
    print("LEAK sqlite")
except BaseException as exc:
    print("BLOCKED sqlite", type(exc).__name__)
try:                        # a process may start inside the sandbox, but sees nothing more
    import subprocess
    got = subprocess.run(["cat", {str(ctx.secret)!r}], capture_output=True).stdout
    print("LEAK subprocess" if got.strip() else "BLOCKED subprocess (nothing read)")
except BaseException as exc:
    print("BLOCKED subprocess", type(exc).__name__)
try:                        # only the data tables of course_lib exist there: no code
    import inspect, course_lib, course_lib.marching_cubes as tables
    text = inspect.getsource(course_lib) + inspect.getsource(tables)
    print("LEAK source" if "def " in text else "BLOCKED source (tables only)")
except BaseException as exc:
    print("BLOCKED source", type(exc).__name__)
"""
    append_cell(nb, name, _rebind(name, body))


def _edit_tests(nb, src, ctx):
    name = target_of(src)
    i = cell_index(nb, f"test_{name}")
    nb["cells"][i]["source"] = "assert True\n"
    nb["cells"][i]["metadata"]["nbgrader"]["points"] = 1000
    others = [tid for n, tid, _ in src.graded if n != name]
    if others:
        del nb["cells"][cell_index(nb, others[-1])]
    append_cell(nb, name, _rebind(name, 'return "cheat"', keep_model=False))


def _tamper_metadata(nb, src, ctx):
    name = target_of(src)
    nb["cells"][cell_index(nb, name)]["metadata"]["nbgrader"]["grade_id"] = "my_own_cell"
    for _, tid, _ in src.graded:
        nb["cells"][cell_index(nb, tid)]["metadata"]["nbgrader"]["points"] = 99
    # a cell claiming to be a new graded test worth 50 points
    nb["cells"].append({"cell_type": "code", "execution_count": None, "outputs": [],
                        "source": "assert True\n",
                        "metadata": {"nbgrader": {"grade": True, "grade_id": "test_bonus",
                                                  "locked": True, "points": 50,
                                                  "schema_version": 3, "solution": False,
                                                  "task": False}}})


def _strip_metadata(nb, src, ctx):
    for cell in nb["cells"]:
        cell["metadata"].pop("nbgrader", None)


def _duplicate(nb, src, ctx):
    name = target_of(src)
    i = cell_index(nb, name)
    broken = json.loads(json.dumps(nb["cells"][i]))
    broken["source"] = f"def {name}(*args, **kwargs):\n    return 'an early draft'\n"
    nb["cells"].insert(i, broken)                        # the draft first, the answer after
    t = cell_index(nb, f"test_{name}")
    nb["cells"].insert(t, json.loads(json.dumps(nb["cells"][t])))   # and a copied test cell


def _delete_solution(nb, src, ctx):
    del nb["cells"][cell_index(nb, target_of(src))]


def _huge_output(nb, src, ctx):
    i = cell_index(nb, target_of(src))
    nb["cells"][i]["outputs"] = [{"output_type": "stream", "name": "stdout",
                                  "text": "y" * (3 * 2**20)}]
    nb["cells"][i]["execution_count"] = 7


def _widgets(nb, src, ctx):
    name = target_of(src)
    append_cell(nb, name, """
import ipywidgets as widgets
slider = widgets.FloatSlider(value=1.0, min=0.0, max=2.0)
slider.observe(lambda change: print(change["new"]), names="value")
display(widgets.VBox([slider]))
from ipywidgets import interact
interact(lambda x: x, x=(0, 10))
""")
    explorer = {"cell_type": "code", "execution_count": None, "metadata": {}, "outputs": [],
                "source": "%matplotlib widget\nfrom course_lib import widgets as w\n"
                          "explorer = [getattr(w, n) for n in dir(w) if n.startswith('explore')]\n"
                          "import time\nwhile True:\n    time.sleep(1)\n"}
    nb["cells"].insert(cell_index(nb, name) + 1, explorer)


def _old_format(src, ctx):
    v3 = {"metadata": {"name": src.name}, "nbformat": 3, "nbformat_minor": 0,
          "worksheets": [{"cells": [{"cell_type": "code", "input": "x = 1", "language": "python",
                                     "outputs": []}], "metadata": {}}]}
    return {f"{src.name}.ipynb": v3}


def _partial_expect(src, ctx):
    """Raising ValueError on every input passes exactly the bad-input cases, and those count
    in proportion to the hidden ordinary cases passed: 0."""
    name = target_of(src)
    cases = cases_of(ctx.student, name, _submitted_nb(ctx, src))
    raising = sum(c.raises is not None and issubclass(ValueError, c.raises) for c in cases)
    ordinary = sum(c.raises is None for c in cases)
    assert raising and ordinary, f"{name}: the bank needs both kinds of case"
    exp = expect_full_marks(src)
    exp[f"test_{name}"] = (0.0, "error")
    return exp


def _crash_expect(src, ctx):
    """Every third call in a process is killed; the grader restarts the child (three processes
    at most) from the case after the crash, so with cases 0..n-1 the passes are 0,1 | 3,4 | 6,7."""
    name = target_of(src)
    cases = cases_of(ctx.student, name, _submitted_nb(ctx, src))
    n = len(cases)
    passes = [i < 9 and i % 3 != 2 for i in range(n)]
    exp = expect_full_marks(src)
    exp[f"test_{name}"] = (points_of(src, name) * counted_cases(cases, passes) / n,
                           "error" if sum(passes) < n else "ok")
    return exp



def _tamper_expect(src, ctx):
    return expect_full_marks(src)


def _strip_expect(src, ctx):
    exp = expect_full_marks(src)
    exp.update({gid: (0.0, "missing") for gid, _ in src.manual})
    return exp


# --------------------------------------------------------------------------------------------
# issue 9: no answer, or an answer of the wrong form, is the student's status, never the grader's


def _choice_of(src) -> str | None:
    return next((n for n, _, _ in src.graded
                 if n in REGISTRY and REGISTRY[n].kind == "choice"), None)


def _set_answer(which, source):
    """An edit setting the solution cell of the target function (``which="function"``) or of
    the notebook's first choice item to ``source`` (None deletes the cell; "RELEASE" restores
    the released stub); ``{name}`` in ``source`` is the item's name."""
    def edit(nb, src, ctx):
        name = target_of(src) if which == "function" else _choice_of(src)
        if source is None:
            del nb["cells"][cell_index(nb, name)]
        elif source == "RELEASE":
            stub = release_version(src)
            set_cell(nb, name, stub["cells"][cell_index(stub, name)]["source"])
        else:
            set_cell(nb, name, source.format(name=name))
    return _edit(edit)


def _answer_expect(which, status):
    def expect(src, ctx):
        exp = expect_full_marks(src)
        name = target_of(src) if which == "function" else _choice_of(src)
        exp[f"test_{name}"] = (0.0, status)
        return exp
    return expect


def _no_answer(which, source, status, words=None):
    return Adversary(_set_answer(which, source), _answer_expect(which, status),
                     message={"answer": words} if words else {},
                     applies=(lambda src: True) if which == "function"
                     else (lambda src: _choice_of(src) is not None))


def _release_expect(src, ctx):
    exp = {tid: (0.0, "unanswered") for _, tid, _ in src.graded}
    # written answers left as "YOUR ANSWER HERE" score 0 with no marker, as in nbgrader
    exp.update({gid: (0.0, "unanswered") for gid, _ in src.manual})
    return exp


ISSUE_9: dict[str, Adversary] = {
    "adv_fn_untouched": _no_answer("function", "RELEASE", "unanswered", "stub"),
    "adv_fn_emptied": _no_answer("function", "", "unanswered", "no code"),
    "adv_fn_comments": _no_answer("function", "# I will do this later\n", "unanswered",
                                  "no code"),
    "adv_fn_none": _no_answer("function", "{name} = None\n", "unanswered", "None"),
    "adv_fn_number": _no_answer("function", "{name} = 3.5\n", "failed", "must be a function"),
    "adv_fn_list": _no_answer("function", "{name} = [1, 2, 3]\n", "failed", "a list"),
    "adv_fn_arity": _no_answer("function", "def {name}(a, b, c, d, e, f, g, h, i, j, k, l, m, "
                               "n):\n    return 0.0\n", "failed", "signature"),
    "adv_choice_untouched": _no_answer("choice", "RELEASE", "unanswered", "stub"),
    "adv_choice_emptied": _no_answer("choice", "", "unanswered", "no code"),
    "adv_choice_deleted": _no_answer("choice", None, "missing", "deleted"),
    "adv_choice_none": _no_answer("choice", "{name} = None\n", "unanswered", "None"),
    "adv_choice_blank": _no_answer("choice", "{name} = ' '\n", "unanswered", "no answer"),
    "adv_choice_spaces": _no_answer("choice", "{name} = ' , '\n", "unanswered", "no answer"),
    "adv_choice_bad_letters": _no_answer("choice", "{name} = '(b)'\n", "failed",
                                         "may hold only the letters"),
    "adv_choice_number": _no_answer("choice", "{name} = 2\n", "failed", "string of option"),
    "adv_choice_list": _no_answer("choice", "{name} = ['a']\n", "failed", "string of option"),
    "adv_release": Adversary(lambda src, ctx: {f"{src.name}.ipynb": release_version(src)},
                             _release_expect),
}

ADVERSARIES: dict[str, Adversary] = {
    # the grade is decided outside the student's process
    "adv_eq": Adversary(_target_code(EQ_ALWAYS_TRUE, keep_model=False),
                        _with_target("rejected-output")),
    "adv_subclass": Adversary(_target_code(SUBCLASS, keep_model=False),
                              _with_target("rejected-output")),
    # (np.testing imports subprocess, socket, lzma...: not among the modules a solution may
    # use, so the sandbox refuses it before the patches could matter)
    "adv_monkeypatch": Adversary(_target_code(MONKEYPATCH, keep_model=False),
                                 _with_target("rejected-code")),
    "adv_reference": Adversary(_edit(_reference_call), _with_target("reference-used")),
    "adv_reference_import": Adversary(_edit(_reference_from_import),
                                      _with_target("reference-used")),
    "adv_snoop": Adversary(_edit(_snoop), lambda src, ctx: expect_full_marks(src)),
    # tampering with the notebook itself
    "adv_edit_tests": Adversary(_edit(_edit_tests), _with_target("failed")),
    "adv_metadata": Adversary(_edit(_tamper_metadata), _tamper_expect,
                              message={"target": "metadata"}),
    "adv_stripped": Adversary(_edit(_strip_metadata), _strip_expect),
    "adv_duplicated": Adversary(_edit(_duplicate), lambda src, ctx: expect_full_marks(src),
                                message={"target": "appears 2 times"}),
    "adv_deleted_cell": Adversary(_edit(_delete_solution), _with_target("missing")),
    # processes that misbehave
    "adv_sys_exit": Adversary(_target_code(SYS_EXIT, keep_model=False), _with_target("error")),
    "adv_os_exit": Adversary(_target_code(OS_EXIT, keep_model=False), _with_target("error")),
    "adv_loop": Adversary(_target_code(INFINITE_LOOP, keep_model=False),
                          _with_target("timeout")),
    "adv_swallow_loop": Adversary(_target_code(SWALLOWING_LOOP, keep_model=False),
                                  _with_target("timeout"), all_notebooks=False),
    "adv_memory": Adversary(_target_code(MEMORY_BOMB, keep_model=False), _with_target("error")),
    "adv_crash": Adversary(_target_code(CRASH_EVERY_THIRD), _crash_expect),
    "adv_partial": Adversary(_target_code(ALWAYS_VALUEERROR, keep_model=False),
                             _partial_expect),
    # noise that must not cost anything
    "adv_flood": Adversary(_target_code(PRINT_FLOOD), lambda src, ctx: expect_full_marks(src)),
    "adv_warnings": Adversary(_target_code(WARNINGS), lambda src, ctx: expect_full_marks(src)),
    "adv_widgets": Adversary(_edit(_widgets), lambda src, ctx: expect_full_marks(src)),
    "adv_huge_output": Adversary(_edit(_huge_output), lambda src, ctx: expect_full_marks(src)),
    # files that cannot be graded
    "adv_invalid_json": Adversary(
        lambda src, ctx: {f"{src.name}.ipynb": json.dumps(model_version(src))[:-200]},
        lambda src, ctx: expect_all(src, "unreadable")),
    "adv_old_nbformat": Adversary(_old_format, lambda src, ctx: expect_all(src, "unreadable")),
    "adv_not_a_notebook": Adversary(lambda src, ctx: {f"{src.name}.ipynb": b"\x89PNG\r\n\x00"},
                                    lambda src, ctx: expect_all(src, "unreadable")),
    "adv_missing": Adversary(lambda src, ctx: {}, lambda src, ctx: expect_all(src, "missing")),
    "adv_misnamed": Adversary(
        lambda src, ctx: {f"{src.name}-Copy1.ipynb": model_version(src)},
        lambda src, ctx: expect_all(src, "missing"), message={"all": "-Copy1.ipynb"}),
    "adv_oversize": Adversary(
        lambda src, ctx: {f"{src.name}.ipynb": b"{" + b" " * (26 * 2**20) + b"}"},
        lambda src, ctx: expect_all(src, "unreadable"), all_notebooks=False),
    **ISSUE_9,
}

PAIRS = [(adv, nb) for adv, a in ADVERSARIES.items()
         for k, nb in enumerate(SOURCES) if (a.all_notebooks or k == 0) and a.applies(SOURCES[nb])]


def _submitted_nb(ctx: Ctx, src) -> Path:
    return ctx.submitted / ctx.student / "tripos2006" / f"{src.name}.ipynb"


def _ctx(root: Path, student: str) -> Ctx:
    return Ctx(student, root / "submitted", root / "out", root / "out" / "gradebook.db",
               root / "secret")


def honest_notebook(src) -> dict | None:
    """The release notebook filled in with tests/grading/honest/<notebook>.py (None if absent).

    Each top-level function named after a graded name goes into that name's solution cell; the
    other top-level statements (imports, helpers) go into the first solution cell; choice
    answers are the registry's key in the honest student's own order of the options (the
    letters they would read off their notebook), and number items are typed as the values for
    the honest student's own numbers (what they would get by hand).
    """
    import ast

    path = HONEST_DIR / f"{src.name}.py"
    if not path.exists():
        return None
    text = path.read_text(encoding="utf-8")
    tree = ast.parse(text)
    graded = {name for name, _, _ in src.graded}
    defs, shared = {}, []
    for node in tree.body:
        segment = ast.get_source_segment(text, node, padded=True)
        if isinstance(node, ast.FunctionDef) and node.name in graded:
            defs[node.name] = segment
        elif not (isinstance(node, ast.Expr) and isinstance(getattr(node, "value", None),
                                                           ast.Constant)):
            shared.append(segment)
    nb = release_version(src)
    first = True
    for cell in nb["cells"]:
        meta = cell.get("metadata", {}).get("nbgrader", {})
        gid = meta.get("grade_id")
        if cell["cell_type"] != "code" or not meta.get("solution"):
            continue
        parts = ["\n".join(shared)] if first and shared else []
        first = False
        ex = REGISTRY.get(gid)
        if gid in defs:
            parts.append(defs[gid])
        elif ex is not None and ex.kind == "choice":
            parts.append(f"{gid} = {ex.key_for('honest')!r}")
        elif ex is not None and ex.kind == "value":
            parts.append(f"{gid} = {ex.value_for('honest').tolist()!r}"
                         if hasattr(ex.value_for("honest"), "tolist")
                         else f"{gid} = {ex.value_for('honest')!r}")
        else:
            continue
        cell["source"] = "\n\n".join(parts) + "\n"
    return nb


@pytest.fixture(scope="session")
def bank(tmp_path_factory, sources, template_gradebook):
    """All adversarial submissions (plus the honest student) graded in one batch."""
    root = tmp_path_factory.mktemp("bank")
    (root / "secret").write_bytes(SECRET + b"\n")
    (root / "out").mkdir()
    shutil.copyfile(template_gradebook, root / "out" / "gradebook.db")
    students = {}
    for adv, nb_name in PAIRS:
        src = SOURCES[nb_name]
        student = f"{adv}-{nb_name}"
        ctx = _ctx(root, student)
        folder = ctx.submitted / student / "tripos2006"
        folder.mkdir(parents=True)
        for fname, content in ADVERSARIES[adv].build(src, ctx).items():
            write_nb(folder / fname, content)
        students[student] = (adv, nb_name)
    honest = {}
    for name, src in SOURCES.items():
        nb = honest_notebook(src)
        if nb is not None:
            write_nb(root / "submitted" / "honest" / "tripos2006" / f"{name}.ipynb", nb)
            honest[name] = True
    t0 = time.monotonic()
    proc = run_grade(root / "submitted", root / "out", "--db-url",
                     f"sqlite:///{root / 'out' / 'gradebook.db'}",
                     secret_file=root / "secret")
    elapsed = time.monotonic() - t0
    return {"root": root, "rows": read_grades(root / "out"), "students": students,
            "honest": honest, "elapsed": elapsed, "proc": proc}


@pytest.mark.parametrize("adv,notebook", PAIRS, ids=[f"{a}-{n}" for a, n in PAIRS])
def test_bank_case(bank, adv, notebook):
    src = SOURCES[notebook]
    student = f"{adv}-{notebook}"
    ctx = _ctx(bank["root"], student)
    expected = ADVERSARIES[adv].expect(src, ctx)
    rows = {gid: r for (s, nb, gid), r in bank["rows"].items() if s == student and nb == notebook}
    assert set(rows) == set(expected), "one row per graded cell of the SOURCE notebook"
    wrong = {}
    for gid, (score, status) in expected.items():
        row = rows[gid]
        got_score = None if row["score"] == "" else float(row["score"])
        ok_score = (got_score is None) if score is None else (
            got_score is not None and abs(got_score - score) < 1e-3)
        if not ok_score or row["status"] != status:
            wrong[gid] = ((score, status), (got_score, row["status"], row["message"][:300]))
        assert row["message"].strip(), f"{gid}: every row says why"
        max_points = dict([(t, p) for _, t, p in src.graded] + list(src.manual))[gid]
        assert float(row["max_score"]) == max_points, "max_score comes from the source notebook"
    assert not wrong, f"{student}: expected vs got {wrong}"
    words = ADVERSARIES[adv].message
    if "target" in words:
        assert words["target"] in rows[f"test_{target_of(src)}"]["message"]
    if "all" in words:
        assert all(words["all"] in r["message"] for r in rows.values())
    if "answer" in words:
        name = target_of(src) if adv.startswith("adv_fn") else _choice_of(src)
        assert words["answer"] in rows[f"test_{name}"]["message"]
    assert not [gid for gid, r in rows.items() if r["status"] == "grader-error"
                or "grader failed" in r["message"]], "never blame the grader for a submission"


def test_no_bank_submission_is_a_grader_error(bank):
    """Whatever a submission does, it gets a student-facing status (issue 9)."""
    bad = {k: (r["status"], r["message"][:200]) for k, r in bank["rows"].items()
           if r["status"] == "grader-error" or "grader failed" in r["message"]}
    assert not bad


def test_unanswered_items_are_not_grader_failures_in_the_report(bank):
    page = (bank["root"] / "out" / "report.html").read_text(encoding="utf-8")
    table = page.split("Most-failed tests", 1)[1].split("</table>", 1)[0]
    assert "grader-error" not in table
    assert "unanswered" in table
    assert "Grader errors (0)" in page


def test_blank_release_is_unanswered_not_failed(bank):
    """The untouched release: every auto-graded item 'unanswered', with what to do about it."""
    for nb_name, src in SOURCES.items():
        rows = {gid: r for (s, nb, gid), r in bank["rows"].items()
                if s == f"adv_release-{nb_name}" and nb == nb_name}
        for _name, tid, _ in src.graded:
            assert rows[tid]["status"] == "unanswered"
            assert "released stub" in rows[tid]["message"], rows[tid]["message"]


def test_other_notebooks_of_a_student_are_missing(bank):
    """A student who handed in one notebook gets 'missing' for the others, nothing worse."""
    for student, (_adv, nb) in list(bank["students"].items())[:5]:
        for (s, other, _gid), row in bank["rows"].items():
            if s == student and other != nb:
                assert row["status"] == "missing" and float(row["score"]) == 0.0


def test_honest_solution_scores_full_marks(bank):
    """tests/grading/honest/: short implementations written for these tests, not course_lib's."""
    if not bank["honest"]:
        pytest.skip("no honest solutions yet")
    bad = {}
    for name in bank["honest"]:
        src = SOURCES[name]
        for _, tid, pts in src.graded:
            row = bank["rows"][("honest", name, tid)]
            if row["status"] != "ok" or abs(float(row["score"]) - pts) > 1e-9:
                bad[(name, tid)] = (row["score"], row["status"], row["message"][:300])
    assert not bad


def _feedback(bank, student, notebook, with_code: bool = False) -> str:
    """A feedback page; without the student's own code unless ``with_code``."""
    path = bank["root"] / "out" / "feedback" / student / f"{notebook}.html"
    text = path.read_text(encoding="utf-8")
    if not with_code:
        text = re.sub(r"<details class='code'>.*?</details>", "", text, flags=re.S)
    return text


def test_feedback_never_shows_hidden_test_code(bank, sources):
    """Plain nbgrader feedback shows hidden tests (nbgrader #917, #1363); ours never does."""
    hidden_lines = set()
    for src in sources:
        for cell in src.cells:
            text = cell.source
            if "BEGIN HIDDEN TESTS" in text:
                block = text.split("### BEGIN HIDDEN TESTS", 1)[1].split("### END HIDDEN TESTS")[0]
                hidden_lines |= {ln.strip() for ln in block.splitlines() if len(ln.strip()) > 8}
    assert hidden_lines, "the source notebooks have hidden tests"
    pages = list((bank["root"] / "out" / "feedback").rglob("*.html"))
    assert len(pages) >= len(bank["students"])
    for page in pages:
        text = html.unescape(page.read_text(encoding="utf-8"))
        assert "BEGIN HIDDEN TESTS" not in text, page
        leaked = [ln for ln in hidden_lines if ln in text]
        assert not leaked, f"{page}: {leaked}"


def test_hidden_cases_show_only_counts_without_reveal(bank):
    for nb_name, src in SOURCES.items():
        name = target_of(src)
        page = _feedback(bank, f"adv_edit_tests-{nb_name}", nb_name)
        student = f"adv_edit_tests-{nb_name}"
        cases = cases_of(student, name, _submitted_nb(_ctx(bank["root"], student), src))
        hidden = [c for c in cases if not c.visible]
        if not hidden:
            continue
        assert f"Hidden cases: 0 of {len(hidden)} passed" in page
        assert "failing hidden case" not in page
        for case in hidden:   # no hidden label appears unless a visible case shares it
            visible_labels = {c.label for c in cases if c.visible}
            if case.label not in visible_labels and len(case.label) > 12:
                assert html.escape(case.label) not in page


def test_snooping_reads_and_writes_nothing(bank):
    for nb_name in SOURCES:
        page = html.unescape(_feedback(bank, f"adv_snoop-{nb_name}", nb_name))
        # before the deadline a notebook with hidden cases shows none of its prints (they could
        # hold the sandbox's inputs): only that there were some; test_attacks.py reads them
        # after the deadline (--reveal-hidden)
        assert "BLOCKED read" in page or "printed is not shown before the deadline" in page, \
            "the attempts ran and their output was captured"
        assert "LEAK" not in page


def test_gradebook_agrees_with_csv(bank):
    """Every auto-graded cell's score is in nbgrader's gradebook, untouched by the snoopers."""
    db = bank["root"] / "out" / "gradebook.db"
    con = sqlite3.connect(db)
    try:
        assert con.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    finally:
        con.close()
    grades = gradebook_grades(f"sqlite:///{db}")
    checked = 0
    for key, row in bank["rows"].items():
        auto_score, needs_manual_grade = grades[key]
        if row["status"] == "manual":
            assert auto_score is None and needs_manual_grade
        else:
            assert auto_score == pytest.approx(float(row["score"]), abs=1e-6)
        checked += 1
    assert checked == len(bank["rows"])


def test_autograded_notebooks_restore_trusted_cells(bank):
    """formgrader's notebooks: test cells from the source (no hidden tests), one cell per id."""
    out = bank["root"] / "out" / "autograded"
    for nb_name, src in SOURCES.items():
        path = out / f"adv_edit_tests-{nb_name}" / "tripos2006" / f"{nb_name}.ipynb"
        nb = json.loads(path.read_text())
        ids = [c["metadata"].get("nbgrader", {}).get("grade_id") for c in nb["cells"]]
        ids = [i for i in ids if i]
        assert len(ids) == len(set(ids))
        by_id = {c["metadata"]["nbgrader"]["grade_id"]: c for c in nb["cells"]
                 if c["metadata"].get("nbgrader", {}).get("grade_id")}
        for _, tid, pts in src.graded:
            cell = by_id[tid]
            assert cell["metadata"]["nbgrader"]["points"] == pts
            assert "HIDDEN" not in cell["source"] and "autograder.incell" not in cell["source"]
            assert "autograder:" in cell["outputs"][0]["text"]
        dup = out / f"adv_duplicated-{nb_name}" / "tripos2006" / f"{nb_name}.ipynb"
        ids = [c["metadata"].get("nbgrader", {}).get("grade_id")
               for c in json.loads(dup.read_text())["cells"]]
        ids = [i for i in ids if i]
        assert len(ids) == len(set(ids)), "duplicated grade_ids are demoted to plain cells"


def test_report_lists_what_could_not_be_graded(bank):
    page = (bank["root"] / "out" / "report.html").read_text(encoding="utf-8")
    assert page.count("<svg") >= len(SOURCES), "one histogram per question"
    for nb_name in SOURCES:
        assert f"adv_invalid_json-{nb_name}" in page
        assert f"adv_old_nbformat-{nb_name}" in page
    assert "Most-failed tests" in page


def test_batch_of_broken_submissions_finishes_in_bounded_time(bank):
    """Every kind of broken submission at once: the batch ends, exit status 0, bounded time."""
    assert bank["proc"].returncode == 0
    n_runs = sum(len(SOURCES[nb].graded) for _, nb in PAIRS)
    # generous: a few hundred sandboxed runs, most in well under a second, the hangs bounded
    # by three case time limits each
    assert bank["elapsed"] < 60 + 0.5 * n_runs + 20 * CASE_TIMEOUT * len(SOURCES)
