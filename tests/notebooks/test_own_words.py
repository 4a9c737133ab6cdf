"""The course is written in its own words: no long run of words is copied from the exam's
worked solutions (``../shared/seed/4F9-2006-solutions.txt``) into the notebooks, the library's
docstrings or the registry's messages. Short technical phrases ("the view volume is defined
by") are fine; a run of ``RUN`` or more consecutive words is not."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SEED = REPO.parent / "shared" / "seed" / "4F9-2006-solutions.txt"
RUN = 10


def words(text: str) -> list[str]:
    """The prose words of ``text``: maths ($...$, LaTeX commands, numbers, symbols) dropped."""
    text = re.sub(r"\$\$.*?\$\$|\$[^$]*\$|\\[a-zA-Z]+", " ", text, flags=re.S)
    return [w for w in re.findall(r"[a-z]+", text.lower()) if len(w) > 1]


def shingles(text: str, n: int = RUN) -> set[tuple[str, ...]]:
    w = words(text)
    return {tuple(w[i:i + n]) for i in range(len(w) - n + 1)}


def course_texts():
    for nb in sorted((REPO / "notebooks").glob("*.ipynb")):
        cells = json.loads(nb.read_text())["cells"]
        yield nb.name, "\n".join("".join(c["source"]) for c in cells)
    for py in sorted((REPO / "course_lib").rglob("*.py")) + sorted((REPO / "autograder").rglob("*.py")):
        yield str(py.relative_to(REPO)), py.read_text()


@pytest.mark.skipif(not SEED.exists(), reason="../shared/seed is not beside this checkout")
@pytest.mark.parametrize("name,text", list(course_texts()),
                         ids=lambda v: v if isinstance(v, str) and len(v) < 60 else "")
def test_no_long_run_copied_from_the_solutions(name, text):
    copied = shingles(text) & shingles(SEED.read_text())
    examples = sorted(" ".join(s) for s in copied)[:3]
    assert not copied, f"{name} repeats {len(copied)} {RUN}-word runs of the solutions, e.g. {examples}"


def test_the_check_can_fail():
    seed_like = "the quick brown fox " * 5
    assert shingles(seed_like) & shingles("and then " + seed_like)
