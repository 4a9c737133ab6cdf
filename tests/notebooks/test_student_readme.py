"""The students' README (inside their wheel) and the instructors' guide give the same commands.

Off the hub a student needs the course's exchange settings before nbgrader's fetch, submit and
fetch_feedback work; the instructors' guide (``docs/instructors.md``, step 3) gives the commands,
and the students' README (``autograder.student_bundle.student_readme``, the wheel's long
description) must give the same ones, with the file the course really writes.
"""

from __future__ import annotations

import re
from pathlib import Path

from autograder.course import DEFAULT_COURSE_ROOT, STUDENT_CONFIG
from autograder.student_bundle import student_readme

REPO = Path(__file__).resolve().parents[2]


def _commands(block: str) -> list[str]:
    """The command lines of a bash block (comments and blank lines dropped)."""
    return [line.split("#", 1)[0].strip() for line in block.splitlines()
            if line.split("#", 1)[0].strip()]


def _block_with(text: str, needle: str) -> str:
    blocks = [b for b in re.findall(r"```bash\n(.*?)```", text, re.S) if needle in b]
    assert len(blocks) == 1, (needle, blocks)
    return blocks[0]


def test_the_students_readme_gives_the_instructors_guides_off_hub_commands():
    main = _commands(_block_with((REPO / "docs" / "instructors.md").read_text(encoding="utf-8"),
                                 "for-students"))
    students = _commands(_block_with(student_readme(), "for-students"))
    assert main and all(line in students for line in main), (main, students)
    for verb in ("fetch_assignment", "submit", "fetch_feedback"):
        assert any(f"nbgrader {verb} tripos2006 --course 4f9" == line for line in students), verb
    # the file copied is the one the course writes for students
    copied = next(line for line in students if "for-students" in line).split()[-2]
    rel = DEFAULT_COURSE_ROOT.resolve().relative_to(REPO) / STUDENT_CONFIG
    assert copied == f"<repository>/{rel.as_posix()}", copied
    assert "Unwritable directory" in student_readme()   # the error it prevents, by its words
