"""Builders for the grading bank: submissions made from the course's own notebooks.

A *submission* is an nbgrader notebook as a student would hand it in. The builders start from a
source notebook and produce

- :func:`release_version`: what ``nbgrader generate_assignment`` gives students (solution bodies
  replaced by ``raise NotImplementedError()``, written answers by "YOUR ANSWER HERE", hidden
  tests removed, outputs cleared);
- :func:`model_version`: the same notebook with the instructor's model answers filled in (the
  "student who copied the model answer"), which the bank uses as the honest baseline around each
  adversarial edit;
- edits on either (:func:`set_cell`, :func:`cell_index`...).

Everything the tests compare against is decided here, independently of the grader: the points
come from the source notebook, the case counts from the registry with the grader's documented
seed (:func:`autograder.grade.cases.case_seed` over the student, the name and the digest of ALL
the student's solution cells that run, :func:`autograder.grade.cases.job_digest`).
"""

from __future__ import annotations

import copy
import csv
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

from autograder.exercises import REGISTRY
from autograder.grade.cases import case_seed, job_digest, running_order
from autograder.grade.planning import to_python
from autograder.grade.sources import load_source

REPO = Path(__file__).resolve().parents[2]
#: Per-case time limit used by the grading tests (s): small, so hangs cost little.
CASE_TIMEOUT = 1.5
SECRET = b"grading-bank-secret-0001"

_SOLUTION = re.compile(r"^[ \t]*### BEGIN SOLUTION[^\n]*\n(.*?)^[ \t]*### END SOLUTION[^\n]*\n?",
                       re.S | re.M)
_HIDDEN = re.compile(r"^[ \t]*### BEGIN HIDDEN TESTS.*?### END HIDDEN TESTS[^\n]*\n?", re.S | re.M)


def course_sources():
    """The parsed source notebooks that have auto-graded exercises in the registry."""
    from autograder.course import source_notebooks

    out = []
    for path in source_notebooks():
        try:
            src = load_source(path)
        except (OSError, ValueError):
            continue
        if any(name in REGISTRY for name, _, _ in src.graded):
            out.append(src)
    return out


def _src_text(cell: dict) -> str:
    s = cell.get("source", "")
    return "".join(s) if isinstance(s, list) else s


def _meta(cell: dict) -> dict:
    return cell.get("metadata", {}).get("nbgrader", {}) or {}


def _clear(cell: dict) -> None:
    if cell["cell_type"] == "code":
        cell["outputs"] = []
        cell["execution_count"] = None


def release_version(src) -> dict:
    """The student version of a source notebook (what generate_assignment produces)."""
    nb = copy.deepcopy(src.nb)
    for cell in nb["cells"]:
        meta = _meta(cell)
        text = _src_text(cell)
        if meta.get("solution") and cell["cell_type"] == "code":
            text = _SOLUTION.sub(lambda m: _indent_of(m.group(0)) + "# YOUR CODE HERE\n"
                                 + _indent_of(m.group(0)) + "raise NotImplementedError()\n", text)
        elif meta.get("solution") and cell["cell_type"] == "markdown":
            text = "YOUR ANSWER HERE"
        elif meta.get("grade") and cell["cell_type"] == "code":
            text = _HIDDEN.sub("", text)
        cell["source"] = text
        _clear(cell)
    return nb


def model_version(src) -> dict:
    """The source notebook as a submission: model answers in, markers and hidden tests out."""
    nb = copy.deepcopy(src.nb)
    for cell in nb["cells"]:
        meta = _meta(cell)
        text = _src_text(cell)
        if meta.get("solution"):
            text = _SOLUTION.sub(lambda m: m.group(1), text)
        elif meta.get("grade") and cell["cell_type"] == "code":
            text = _HIDDEN.sub("", text)
        cell["source"] = text
        _clear(cell)
    return nb


def _indent_of(block: str) -> str:
    return block[: len(block) - len(block.lstrip(" \t"))]


def cell_index(nb: dict, grade_id: str) -> int:
    for i, cell in enumerate(nb["cells"]):
        if _meta(cell).get("grade_id") == grade_id:
            return i
    raise KeyError(grade_id)


def set_cell(nb: dict, grade_id: str, source: str) -> dict:
    nb["cells"][cell_index(nb, grade_id)]["source"] = source
    return nb


def append_cell(nb: dict, grade_id: str, extra: str) -> dict:
    i = cell_index(nb, grade_id)
    nb["cells"][i]["source"] = _src_text(nb["cells"][i]).rstrip("\n") + "\n\n" + extra
    return nb


def function_names(src) -> list[str]:
    return [name for name, _, _ in src.graded
            if name in REGISTRY and REGISTRY[name].kind == "function"]


def target_of(src) -> str:
    """The function the adversarial edits target: one that no other solution cell calls (so
    breaking it costs exactly its own test), with at least three cases."""
    model = model_version(src)
    sol = {(_meta(c).get("grade_id")): _src_text(c) for c in model["cells"]
           if _meta(c).get("solution") and c["cell_type"] == "code"}
    for name in function_names(src):
        others = [text for gid, text in sol.items() if gid != name]
        if any(re.search(rf"\b{re.escape(name)}\s*\(", t) for t in others):
            continue
        if len(REGISTRY[name].draw_cases(np.random.default_rng(0))) >= 3:
            return name
    return function_names(src)[0]


def solution_code(nb: dict, name: str) -> str:
    """The solution cell of ``name`` in notebook ``nb`` (the last one tagged with it), as the
    grader runs it (magics turned into Python)."""
    cells = [c for c in nb["cells"] if _meta(c).get("grade_id") == name and c["cell_type"] == "code"]
    if not cells:
        return ""
    return to_python(_src_text(cells[-1]))[0] or ""


def planned_cells(nb: dict) -> list[tuple[str, str]]:
    """``(label, code)`` of every solution code cell of ``nb`` (by its nbgrader metadata), in
    notebook order, labelled as the grader labels them: what the sandbox receives and what
    seeds the hidden cases (:func:`autograder.grade.cases.job_digest`)."""
    cells = []
    for i, c in enumerate(nb["cells"]):
        meta = _meta(c)
        if c["cell_type"] == "code" and meta.get("solution") and not meta.get("grade"):
            code = to_python(_src_text(c))[0]
            if code is not None:
                cells.append((f"{meta.get('grade_id')} (cell {i + 1})", code))
    return cells


def cases_of(student: str, name: str, nb, secret: bytes = SECRET):
    """The cases the grader draws for ``student`` whose notebook is ``nb`` (a dict, or the path
    of the submitted file) with the grader's documented seeding, in the order it runs them."""
    ex = REGISTRY[name]
    if ex.kind == "choice":
        return [None]
    if not isinstance(nb, dict):
        nb = json.loads(Path(nb).read_text(encoding="utf-8"))
    rng = np.random.default_rng(case_seed(secret, student, name, job_digest(planned_cells(nb))))
    return running_order(ex.draw_cases(rng), rng)


def counted_cases(cases, passes) -> float:
    """How many of ``cases`` count when those flagged in ``passes`` pass, by the rule each
    notebook's first cell states (not read from the grader): visible and bad-input cases count
    in proportion to the share of hidden ordinary cases passed (with no hidden ordinary case,
    the visible ones give the share and only the bad-input cases are scaled)."""
    ordinary = [p for c, p in zip(cases, passes) if c.raises is None]
    hidden = [p for c, p in zip(cases, passes) if c.raises is None and not c.visible]
    share = sum(hidden or ordinary) / len(hidden or ordinary) if ordinary else 1.0
    earned = sum(p for c, p in zip(cases, passes) if c.raises is None and not c.visible)
    scaled = sum(p for c, p in zip(cases, passes) if c.raises is not None or c.visible)
    if not hidden:
        earned = sum(ordinary)
        scaled = sum(p for c, p in zip(cases, passes) if c.raises is not None)
    return earned + scaled * share


def typed_version(nb: dict, student: str) -> dict:
    """``nb`` with every choice and number item that the model answer *computes* from ``mine``
    typed out as a literal for ``student``: what a student hands in (the grader reads typed
    answers only, issue 11). Cells of any other form are left as they are."""
    cells = nb.get("cells") if isinstance(nb, dict) else None
    for cell in cells if isinstance(cells, list) else []:     # adversaries send odd notebooks
        try:
            text = _src_text(cell)
            named = [n for n in re.findall(r"^(\w+)\s*=", text, re.M)    # metadata stripped
                     if n in REGISTRY and REGISTRY[n].kind in ("choice", "value")]
            ex = REGISTRY.get(_meta(cell).get("grade_id", "") or (named[-1] if named else ""))
            computed = ex is not None and ex.kind in ("choice", "value") \
                and "mine." in text and not _types(text, ex.name)
        except (AttributeError, TypeError):
            continue
        if not computed:
            continue
        try:
            answer = ex.key_for(student) if ex.kind == "choice" else ex.value_for(student)
        except ValueError:          # not a student id (the grader skips such folders)
            return nb
        answer = answer.tolist() if isinstance(answer, np.ndarray) else answer
        cell["source"] = _retyped(text, ex.name, f"{ex.name} = {answer!r}")
    return nb


def _types(text: str, name: str) -> bool:
    """Whether the last top-level assignment to ``name`` in ``text`` is a literal already."""
    import ast

    try:
        found = [n for n in ast.parse(text).body if isinstance(n, ast.Assign)
                 and any(isinstance(t, ast.Name) and t.id == name for t in n.targets)]
        return bool(found) and ast.literal_eval(found[-1].value) is not None
    except (SyntaxError, ValueError, TypeError):
        return False


def _retyped(text: str, name: str, typed: str) -> str:
    """``text`` with its last top-level assignment to ``name`` replaced by ``typed`` (the rest
    of the cell, e.g. an attack's helper code, stays); the whole cell when it does not parse."""
    import ast

    try:
        tree = ast.parse(text)
    except SyntaxError:
        return typed + "\n"
    found = [n for n in tree.body if isinstance(n, ast.Assign)
             and any(isinstance(t, ast.Name) and t.id == name for t in n.targets)]
    if not found:
        return typed + "\n"
    lines = text.splitlines()
    node = found[-1]
    return "\n".join(lines[:node.lineno - 1] + [typed] + lines[node.end_lineno:]) + "\n"


def write_nb(path: Path, nb, type_answers: bool = True) -> None:
    """Write a submission; a notebook (dict) under ``<student>/tripos2006/`` gets its computed
    item answers typed for that student (:func:`typed_version`) unless ``type_answers`` is
    False."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if isinstance(nb, dict) and type_answers and path.parent.name == "tripos2006":
        nb = typed_version(copy.deepcopy(nb), path.parent.parent.name)
    if isinstance(nb, bytes):
        path.write_bytes(nb)
    elif isinstance(nb, str):
        path.write_text(nb, encoding="utf-8")
    else:
        path.write_text(json.dumps(nb, indent=1), encoding="utf-8")


def run_grade(submitted: Path, out: Path, *extra: str, jobs: int = 2,
              timeout: float = CASE_TIMEOUT, secret_file: Path | None = None,
              check: bool = True) -> subprocess.CompletedProcess:
    """``python -m autograder grade`` exactly as an instructor runs it."""
    if secret_file is None:
        secret_file = out.parent / "secret"
        secret_file.write_bytes(SECRET + b"\n")
    env = dict(os.environ, MPLBACKEND="Agg",
               PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}")
    cmd = [sys.executable, "-m", "autograder", "grade", str(submitted), "--out", str(out),
           "--jobs", str(jobs), "--timeout", str(timeout), "--load-timeout", "20",
           "--secret-file", str(secret_file), "--quiet", *extra]
    proc = subprocess.run(cmd, cwd=REPO, env=env, capture_output=True, text=True, timeout=900)
    if check and proc.returncode != 0:
        raise AssertionError(f"grade exited {proc.returncode}:\n{proc.stderr[-4000:]}")
    _snapshot(out)
    return proc


def _snapshot(out: Path) -> None:
    """With ``GRADES_SNAPSHOT=<dir>``, keep a copy of this run's grades and feedback there, named
    by the test that ran it, for ``tests/tools/compare_grades.py`` (grades byte-identical before
    and after a refactor; run pytest with a fixed ``--basetemp`` so paths agree)."""
    target = os.environ.get("GRADES_SNAPSHOT")
    if not target or not (out / "grades.csv").is_file():
        return
    import shutil

    test = os.environ.get("PYTEST_CURRENT_TEST", "no-test").split(" ")[0]
    stem = re.sub(r"[^A-Za-z0-9_.-]+", "_", test)
    n = 0
    while (Path(target) / f"{stem}--{n}").exists():
        n += 1
    dest = Path(target) / f"{stem}--{n}"
    dest.mkdir(parents=True)
    shutil.copyfile(out / "grades.csv", dest / "grades.csv")
    if (out / "feedback").is_dir():
        shutil.copytree(out / "feedback", dest / "feedback")


def gradebook_grades(db_url: str) -> dict[tuple[str, str, str], tuple]:
    """``{(student, notebook, grade id): (auto_score, needs_manual_grade)}`` of every grade in
    nbgrader's gradebook, read through nbgrader's own API one submitted notebook at a time
    (``Gradebook.find_grade`` per cell costs about a millisecond of CPU each: 33 s for a bank)."""
    from nbgrader.api import Gradebook

    found = {}
    with Gradebook(db_url) as gb:
        for sub in gb.find_assignment("tripos2006").submissions:
            for nb in sub.notebooks:
                for grade in nb.grades:
                    found[(sub.student_id, nb.name, grade.name)] = (grade.auto_score,
                                                                    grade.needs_manual_grade)
    return found


def read_grades(out: Path) -> dict[tuple[str, str, str], dict]:
    with open(out / "grades.csv", newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    return {(r["student"], r["notebook"], r["grade_id"]): r for r in rows}


def expect_full_marks(src) -> dict[str, tuple]:
    """Full marks everywhere: (score, status) per grade_id; manual cells wait for a human."""
    exp = {tid: (pts, "ok") for _, tid, pts in src.graded}
    exp.update({gid: (None, "manual") for gid, _ in src.manual})
    return exp


def expect_all(src, status) -> dict[str, tuple]:
    """0 with ``status`` for every graded and manual cell (a notebook that cannot be graded)."""
    exp = {tid: (0.0, status) for _, tid, _ in src.graded}
    exp.update({gid: (0.0, status) for gid, _ in src.manual})
    return exp


def points_of(src, name) -> float:
    """The points of graded name ``name``'s test cell in the source notebook."""
    return next(p for n, _, p in src.graded if n == name)
