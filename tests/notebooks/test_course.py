"""``autograder.course.prepare_course``: layout, idempotence, and a student's work kept safe.

Runs on one real source notebook (the smallest) in its own course root.
"""

from __future__ import annotations

import json
import os

import pytest
from nbtools import read

from autograder.course import ASSIGNMENT, CODE_STUB, COURSE_ID, prepare_course, source_notebooks

NOTEBOOKS = source_notebooks()
pytestmark = [pytest.mark.skipif(not NOTEBOOKS, reason="no notebooks/q*.ipynb yet"),
              pytest.mark.timeout(300)]


def test_prepare_course_layout_idempotence_and_backup(tmp_path):
    src = min(NOTEBOOKS, key=lambda p: p.stat().st_size)
    course = prepare_course(tmp_path / "c", notebooks=[src])

    # layout: nbgrader's own folders, config and gradebook
    assert course.root == (tmp_path / "c").resolve()
    assert (course.source_dir / src.name).read_bytes() == src.read_bytes()
    released = course.release_dir / src.name
    assert released.exists() and course.db_url == f"sqlite:///{course.root / 'gradebook.db'}"
    config = (course.root / "nbgrader_config.py").read_text()
    assert f"c.CourseDirectory.course_id = {COURSE_ID!r}" in config
    stub = CODE_STUB.splitlines()[-1]  # "raise NotImplementedError()", indented in a function
    assert any(stub in c.source for c in read(released).cells), "no solution was stubbed"
    assert course.submitted_dir("s1") == course.root / "submitted" / "s1" / ASSIGNMENT
    assert course.feedback_dir("s1") == course.root / "feedback" / "s1" / ASSIGNMENT
    with course.gradebook() as gb:
        assignment = gb.find_assignment(ASSIGNMENT)
        assert [nb.name for nb in assignment.notebooks] == [src.stem]
        assert assignment.max_score == pytest.approx(20)  # every notebook is worth 20 marks

    # idempotent: unchanged sources do not regenerate (the release file is not rewritten)
    os.utime(released, (1_000_000_000, 1_000_000_000))
    again = prepare_course(tmp_path / "c", notebooks=[src])
    assert again == course and released.stat().st_mtime == 1_000_000_000

    # a student edits the release, then the sources change: the edit is moved aside, not lost
    released.write_text(released.read_text().replace("YOUR ANSWER HERE", "my own answer", 1))
    changed = tmp_path / src.name
    nb = json.loads(src.read_text())
    nb["cells"].append({"cell_type": "markdown", "metadata": {}, "source": "One more remark."})
    changed.write_text(json.dumps(nb, indent=1))
    prepare_course(tmp_path / "c", notebooks=[changed])
    backups = list((course.root / "backup").glob(f"{ASSIGNMENT}-*/{src.name}"))
    assert len(backups) == 1 and "my own answer" in backups[0].read_text()
    assert "One more remark." in released.read_text()
    assert "my own answer" not in released.read_text()
