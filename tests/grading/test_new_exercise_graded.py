"""A function added with ``new-exercise`` and filled in, graded by ``python -m autograder grade``
in the OS sandbox on the scratch copy: the honest answer earns the new cell's full points, and
the notebook's other cells keep theirs (``test_new_exercise.py`` plays the same flow in process
for ``make test-fast``).
"""

from __future__ import annotations

import csv
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from autograder.course import REPO_ROOT

GRADING_TESTS = Path(__file__).resolve().parent
sys.path.insert(0, str(GRADING_TESTS.parent / "notebooks"))

from test_new_exercise import NAME, _fill_in, _run  # noqa: E402

_SUBMIT = '''
import json, sys
sys.path.insert(0, sys.argv[2])
from gradingtools import SECRET, model_version, write_nb
from autograder.grade.sources import load_source
from pathlib import Path

src = load_source(Path("notebooks/q5_phong.ipynb"))
nb = model_version(src)
honest = open("tests/grading/honest/q5_phong.py").read()
body = honest[honest.index("def NAME("):]
for cell in nb["cells"]:
    if cell["metadata"].get("nbgrader", {}).get("grade_id") == "NAME":
        cell["source"] = body
root = Path(sys.argv[1])
write_nb(root / "submitted" / "honest" / "tripos2006" / "q5_phong.ipynb", nb)
(root / "secret").write_bytes(SECRET + b"\\n")
print(json.dumps({g: p for _, g, p in src.graded}))
'''.replace("NAME", NAME)


@pytest.mark.slow
def test_an_added_function_is_graded_in_the_sandbox(tmp_path, mode):
    """``mode``: skips where this machine cannot isolate students' code."""
    root = tmp_path / "repo"
    for part in ("autograder", "course_lib", "notebooks", "tests/grading/honest"):
        shutil.copytree(REPO_ROOT / part, root / part,
                        ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "_build*"))
    (root / "tests" / "course_lib").mkdir(parents=True)
    added = _run(root, "new-exercise", "q5_phong", NAME, "--part", "c", "--points", "0.5",
                 "--args", "n")
    assert added.returncode == 0, added.stderr
    _fill_in(root)
    made = _run(root, code=_SUBMIT.replace("sys.argv[1]", repr(str(tmp_path)))
                .replace("sys.argv[2]", repr(str(GRADING_TESTS))))
    assert made.returncode == 0, made.stderr
    points = json.loads(made.stdout.strip().splitlines()[-1])
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=os.pathsep.join(
        [str(root), os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.run(
        [sys.executable, "-m", "autograder", "grade", str(tmp_path / "submitted"), "--out",
         str(tmp_path / "out"), "--no-gradebook", "--jobs", "1", "--secret-file",
         str(tmp_path / "secret"), "--quiet"],
        cwd=root, env=env, capture_output=True, text=True, timeout=900, check=False)
    assert proc.returncode == 0, proc.stderr[-3000:]
    with open(tmp_path / "out" / "grades.csv", newline="", encoding="utf-8") as f:
        rows = {r["grade_id"]: r for r in csv.DictReader(f) if r["student"] == "honest"}
    assert points[f"test_{NAME}"] == 0.5
    for gid, pts in points.items():
        assert rows[gid]["status"] == "ok", (gid, rows[gid])
        assert float(rows[gid]["score"]) == pytest.approx(pts, abs=1e-9), (gid, rows[gid])
