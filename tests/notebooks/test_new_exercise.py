"""``python -m autograder new-exercise`` played as a teaching assistant would, on a scratch copy.

Add ``blinn_phong_specular_exponent`` (½ mark, Q5(c)), see the marks it prints and what the
facts check names, fill in the maths (reference, cases, model answer, honest answer), move half
a mark from the written answer (c) to it, and grade: the honest answer and the notebook's model
answer earn full marks on the registry's cases, judged as ``grade`` judges them
(``judging.judge_cell``). An existing name is refused with exit status 2 and nothing written.
The oracle of the maths is the exam's rule of thumb itself: Blinn-Phong needs about four times
Phong's exponent for the same highlight (n' = 4 n).
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from autograder.course import REPO_ROOT

#: a name no real exercise will take: a TA adding the docs' example (blinn_phong_specular_exponent)
#: to the course must not collide with this scratch run
NAME = "scratch_blinn_phong_exponent"
_IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc", "_build*")


@pytest.fixture
def scratch(tmp_path) -> Path:
    """What the command writes to, copied: the package, the library, notebooks, stubs' homes."""
    root = tmp_path / "repo"
    for part in ("autograder", "course_lib", "notebooks", "tests/grading/honest"):
        shutil.copytree(REPO_ROOT / part, root / part, ignore=_IGNORE)
    (root / "tests" / "course_lib").mkdir(parents=True)
    return root


def _run(root: Path, *args: str, code: str | None = None) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(root), os.environ.get("PYTHONPATH", "")]))
    argv = [sys.executable, "-c", code] if code else [sys.executable, "-m", "autograder", *args]
    return subprocess.run(argv, cwd=root, env=env, capture_output=True, text=True, timeout=300,
                          check=False)


def _digest(root: Path) -> str:
    h = hashlib.sha256()
    for path in sorted(p for p in root.rglob("*") if p.is_file() and "__pycache__" not in p.parts):
        h.update(str(path.relative_to(root)).encode() + path.read_bytes())
    return h.hexdigest()


def _replace(path: Path, pattern: str, new: str) -> None:
    text = path.read_text(encoding="utf-8")
    out, n = re.subn(pattern, lambda _: new, text, count=1, flags=re.S)
    assert n == 1, f"{pattern!r} not found in {path}"
    path.write_text(out, encoding="utf-8")


def _edit_cells(path: Path, edit) -> None:
    nb = json.loads(path.read_text(encoding="utf-8"))
    for cell in nb["cells"]:
        edit(cell, cell["metadata"].get("nbgrader", {}).get("grade_id"))
    path.write_text(json.dumps(nb, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")


_BODY = '''    n = float(n)
    if not (n > 0 and n < float("inf")):
        raise ValueError(f"n must be a positive finite exponent, got {n}")
    return 4.0 * n
'''
_CASES = '''    yield Case(args=(10.0,), label="exam Q5 exponent n = 10", visible=True)
    for n in rng.uniform(0.5, 200.0, size=5):
        yield Case(args=(float(n),), label="a random exponent")
    yield Case(args=(0.0,), label="n = 0", raises=ValueError)
    yield Case(args=(-3.0,), label="a negative exponent", raises=ValueError)
'''


def _fill_in(root: Path) -> None:
    """The maths, the cases, the model and honest answers, and half a mark moved from the
    written answer (c) to the new function: what the command leaves to the TA."""
    stub = rf'    raise NotImplementedError\(\n        "{NAME}: write the reference.*?\)\n'
    _replace(root / "course_lib" / "shading.py", stub, _BODY)
    _replace(root / "autograder" / "exercises" / "q5_phong.py",
             r'    raise NotImplementedError\(\n        "write the cases of .*?yield Case\(\)\n',
             _CASES)
    _replace(root / "tests" / "grading" / "honest" / "q5_phong.py",
             rf'    raise NotImplementedError\(\n        "{NAME}: a short.*?\)\n',
             "    if not 0 < n < float('inf'):\n        raise ValueError('bad n')\n"
             "    return 4 * float(n)\n")

    from autograder.new_exercise import _marks_words

    nb = json.loads((root / "notebooks" / "q5_phong.ipynb").read_text(encoding="utf-8"))
    was = next(c["metadata"]["nbgrader"]["points"] for c in nb["cells"]
               if c["metadata"].get("nbgrader", {}).get("grade_id") == "q5c_answer")
    moved = {_marks_words(was): _marks_words(was - 0.5)}

    def edit(cell, gid):
        source = "".join(cell["source"])
        if gid == NAME:
            source = re.sub(r"    raise NotImplementedError\(.*?\)\n", _BODY, source, flags=re.S)
        elif gid == f"test_{NAME}":
            source = source.replace(f"assert {NAME} is not None",
                                    f"assert np.isclose({NAME}(10.0), 40.0)")
        elif gid == "q5c_answer":
            cell["metadata"]["nbgrader"]["points"] = was - 0.5
        for old, new in moved.items():          # the written answer's prompt, below its cell
            source = source.replace(f"*[{old}, marked by hand]*", f"*[{new}, marked by hand]*")
        cell["source"] = source.splitlines(keepends=True)

    _edit_cells(root / "notebooks" / "q5_phong.ipynb", edit)


_GRADE = '''
import json, sys
import numpy as np
from autograder.exercises import get
from autograder.judging import CellEvidence, call_in_process, judge_case, judge_cell
from autograder.model import CaseRecord, Status

def score(name, func, points, seed):
    ex = get(name)
    records = []
    for i, case in enumerate(ex.draw_cases(np.random.default_rng(seed))):
        expected = ex.expected(case) if case.raises is None else None
        verdict, why = judge_case(ex, case, expected, call_in_process(func, case, i))
        records.append(CaseRecord(i, case.label, bool(case.visible), verdict, why))
    cell = judge_cell(CellEvidence(ex, points, records))
    return cell.score, cell.status is Status.OK, len(records)

honest = {}
exec(open("tests/grading/honest/q5_phong.py").read(), honest)
nb = json.load(open("notebooks/q5_phong.ipynb"))
cells = {c["metadata"].get("nbgrader", {}).get("grade_id"): "".join(c["source"])
         for c in nb["cells"]}
kernel = {}
for gid in ("setup_q5_phong", "NAME", "test_NAME"):      # Run All's order, hidden tests too
    exec(cells[gid], kernel)
points = next(c["metadata"]["nbgrader"]["points"] for c in nb["cells"]
              if c["metadata"].get("nbgrader", {}).get("grade_id") == "test_NAME")
print(json.dumps({"points": points,
                  "honest": [score("NAME", honest["NAME"], points, s) for s in (1, 2, 3)],
                  "model": score("NAME", kernel["NAME"], points, 4)}))
'''.replace("NAME", NAME)


def test_add_fill_in_and_grade_an_honest_answer(scratch):
    done = _run(scratch, "new-exercise", "q5_phong", NAME, "--part", "c", "--points", "0.5",
                "--args", "n")
    assert done.returncode == 0, done.stderr
    assert re.search(r"part \(c\)\s+3\.5 marks\s+\(header says 3\)", done.stdout), done.stdout
    assert "the cells' points add up to 20.5, not 20" in done.stdout
    for written in ("notebooks/q5_phong.ipynb", "autograder/exercises/q5_phong.py",
                    "course_lib/shading.py", "tests/grading/honest/q5_phong.py",
                    f"tests/course_lib/test_{NAME}.py"):
        assert f"wrote {written}" in done.stdout
    import nbformat

    nbformat.validate(nbformat.read(str(scratch / "notebooks" / "q5_phong.ipynb"), as_version=4))
    before = _run(scratch, "facts", "--check")
    assert before.returncode == 1 and "part (c): the header says 3 marks" in before.stderr

    _fill_in(scratch)
    after = _run(scratch, "facts", "--check")
    assert "q5_phong" not in after.stderr, after.stderr   # the text follows the moved mark
    graded = _run(scratch, code=_GRADE)
    assert graded.returncode == 0, graded.stderr
    result = json.loads(graded.stdout.strip().splitlines()[-1])
    assert result["points"] == 0.5
    for got, ok, n_cases in result["honest"] + [result["model"]]:
        assert ok and got == pytest.approx(0.5, abs=1e-12) and n_cases == 8


def test_an_existing_name_is_refused_with_exit_status_2_and_nothing_written(scratch):
    before = _digest(scratch)
    done = _run(scratch, "new-exercise", "q5_phong", "phong", "--part", "c", "--points", "1")
    assert done.returncode == 2, done.stderr
    assert "'phong' exists: registered in autograder/exercises/q5_phong.py" in done.stderr
    assert _digest(scratch) == before


@pytest.mark.parametrize("args, why", [
    (("q5_phong", "normalize", "c", 1), "'normalize' exists: registered"),
    (("q5_phong", "q5c_answer", "c", 1), "a cell of q5_phong.ipynb has grade_id 'q5c_answer'"),
    (("q5_phong", "Phong", "c", 1), "not a lower-case Python name"),
    (("q9_none", "f", "a", 1), "no notebook 'q9_none'"),
    (("q5_phong", "f", "c", 0.3), "half marks"),
    (("q5_phong", "f", "c)(", 1), "give a part of the exam"),
])
def test_a_bad_request_is_a_clear_value_error(args, why):
    from autograder.new_exercise import plan_from

    with pytest.raises(ValueError, match=re.escape(why)):
        plan_from(*args)


@pytest.mark.parametrize("part, after, why", [("z", None, "has no part (z)"),
                                              ("c", "nowhere", "--after 'nowhere'")])
def test_a_place_that_is_not_there_is_refused_before_anything_is_written(scratch, monkeypatch,
                                                                          part, after, why):
    from autograder import new_exercise

    monkeypatch.setattr(new_exercise, "REPO_ROOT", scratch)
    before = _digest(scratch)
    plan = new_exercise.plan_from("q5_phong", "f", part, 1, after=after)
    with pytest.raises(ValueError, match=re.escape(why)):
        new_exercise.create(plan)
    assert _digest(scratch) == before


def test_the_new_cells_have_nbgrader_metadata_as_the_notebooks_do():
    """The cells the command writes against an existing graded function's (q5's halfway)."""
    from autograder.new_exercise import Plan, notebook_cells

    plan = Plan("q5_phong", "f", "(c)", 1.5, ("x",), "shading")
    prompt, solution, test = notebook_cells(plan)
    nb = json.loads((REPO_ROOT / "notebooks" / "q5_phong.ipynb").read_text(encoding="utf-8"))
    ref = {c["metadata"].get("nbgrader", {}).get("grade_id"): c for c in nb["cells"]}
    for new, old in ((solution, ref["halfway"]), (test, ref["test_halfway"])):
        want = dict(old["metadata"]["nbgrader"], grade_id=new["metadata"]["nbgrader"]["grade_id"])
        if "points" in want:
            want["points"] = 1.5
        assert new["metadata"] == dict(old["metadata"], nbgrader=want)
        assert set(new) == set(old)
    assert "*[1½ marks]*" in "".join(prompt["source"])
    assert "".join(test["source"]).endswith(
        '### BEGIN HIDDEN TESTS\nfrom autograder.incell import check\ncheck("f", f)\n'
        "### END HIDDEN TESTS")
