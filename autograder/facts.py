"""The course's counts and totals, computed from the registry and the notebooks' ``points``.

``python -m autograder facts`` prints them (and each notebook's marks by part);
``python -m autograder facts --check`` exits 1 naming every sentence of the docs, the notebooks'
intros and the registry's docstrings that states a different number. A count typed into prose
("all 36 graded functions", "the 64 automatic marks") is a copy of a fact: the registry
(:mod:`autograder.exercises`) and the cells' nbgrader ``points`` are the fact, and this check
(run by ``tests/notebooks/test_facts.py`` in ``make test-fast``) names the copies to follow when
an exercise is added, retired or moves a mark.
"""

from __future__ import annotations

import re
import sys
from dataclasses import dataclass
from pathlib import Path

from . import marks as marks_mod
from .course import NOTEBOOKS_DIR, REPO_ROOT

#: Every question notebook is worth this many marks (automatic and by hand), split between the
#: exam's parts by the exam's percentages (CONTRIBUTING.md, "Marks").
MARKS_PER_NOTEBOOK = 20

_WORDS = {w: n for n, w in enumerate(
    "zero one two three four five six seven eight nine ten eleven twelve".split())}
_COUNT = r"(\d+|" + "|".join(_WORDS) + r")"

#: The docs' sentences that state a course-wide count: (pattern with one count, fact's key).
DOC_CLAIMS = (
    (rf"\b{_COUNT} graded functions", "graded functions"),
    (rf"\ball {_COUNT} references", "graded functions"),
    (rf"\b{_COUNT} automatic marks", "automatic marks"),
    (rf"\b{_COUNT} automatically graded cells", "automatically graded cells"),
    (rf"\bworth \*\*{_COUNT} marks\*\*", "marks per notebook"),
)
#: The files whose prose :data:`DOC_CLAIMS` reads, relative to the repository.
DOC_FILES = ("README.md", "CONTRIBUTING.md", "docs/*.md")
#: A notebook's intro (its first cell) and its registry module's docstring state counts of
#: that notebook's items in words ("Nine short functions", "five multiple-choice items").
NOTEBOOK_CLAIMS = (
    (rf"\b{_COUNT} (?:short |graded )?functions\b", "function"),
    (rf"\b{_COUNT} multiple-choice items\b", "choice"),
    (rf"\b{_COUNT} practice items\b", "value"),
)


def count(text: str) -> int:
    """"36" → 36, "Nine" → 9."""
    return int(text) if text.isdigit() else _WORDS[text.lower()]


def course_facts(notebooks_dir: Path = NOTEBOOKS_DIR) -> dict[str, float]:
    """The course-wide counts and totals, from the registry and the cells' ``points``."""
    from .exercises import REGISTRY

    kinds = [ex.kind.value for ex in REGISTRY.values()]
    automatic = 0.0
    for path in sorted(Path(notebooks_dir).glob("q*.ipynb")):
        points = marks_mod.notebook_marks(path).points
        automatic += sum(points.get(f"test_{ex.name}", 0.0) for ex in REGISTRY.values()
                         if ex.notebook == path.stem)
    return {
        "graded functions": kinds.count("function"),
        "multiple-choice items": kinds.count("choice"),
        "number items": kinds.count("value"),
        "automatically graded cells": len(kinds),
        "automatic marks": automatic,
        "marks per notebook": MARKS_PER_NOTEBOOK,
    }


@dataclass(frozen=True)
class Claim:
    """A sentence that states a count, and what the count should be."""

    where: str
    text: str
    stated: float
    fact: str
    actual: float

    def __str__(self) -> str:
        return (f"{self.where}: {self.text!r} says {self.stated:g}; the count of "
                f"{self.fact} is {self.actual:g}")


def _claims_in(text: str, where: str, patterns, facts: dict) -> list[Claim]:
    found = []
    flat = " ".join(text.split())
    for pattern, fact in patterns:
        for m in re.finditer(pattern, flat, re.IGNORECASE):
            found.append(Claim(where, m[0], count(m[1]), fact, facts[fact]))
    return found


def doc_claims(root: Path = REPO_ROOT) -> list[Claim]:
    """Every count the docs state (see :data:`DOC_CLAIMS`), with the fact it should equal."""
    facts = course_facts(Path(root) / "notebooks")
    found = []
    for pattern in DOC_FILES:
        for path in sorted(Path(root).glob(pattern)):
            found += _claims_in(path.read_text(encoding="utf-8"),
                                str(path.relative_to(root)), DOC_CLAIMS, facts)
    return found


def notebook_claims(root: Path = REPO_ROOT) -> list[Claim]:
    """Every count of a notebook's items its intro prose (not its table) and its registry
    module's docstring state in words, with the notebook's count."""
    from .exercises import NOTEBOOKS, for_notebook

    found = []
    for name in NOTEBOOKS:
        path = Path(root) / "notebooks" / f"{name}.ipynb"
        if not path.exists():
            continue
        kinds = [ex.kind.value for ex in for_notebook(name)]
        facts = {k: kinds.count(k) for k in ("function", "choice", "value")}
        intro = marks_mod.join_source(marks_mod.read_cells(path)[0].get("source"))
        prose = "\n".join(line for line in intro.splitlines() if not line.startswith("|"))
        found += _claims_in(prose, f"notebooks/{name}.ipynb (intro)", NOTEBOOK_CLAIMS, facts)
        module = Path(root) / "autograder" / "exercises" / f"{name}.py"
        if module.exists():
            doc = module.read_text(encoding="utf-8").split('"""')
            if len(doc) > 2:
                found += _claims_in(doc[1], str(module.relative_to(root)), NOTEBOOK_CLAIMS,
                                    facts)
    return found


def problems(root: Path = REPO_ROOT) -> list[str]:
    """Every stated count or mark that differs from the registry's and the cells' (empty:
    all agree)."""
    out = [str(c) for c in doc_claims(root) + notebook_claims(root)
           if abs(c.stated - c.actual) > 1e-9]
    for path in sorted((Path(root) / "notebooks").glob("q*.ipynb")):
        out += marks_mod.problems(marks_mod.notebook_marks(path), MARKS_PER_NOTEBOOK)
    return out


def add_arguments(parser) -> None:
    parser.add_argument("--check", action="store_true",
                        help="exit 1 naming every sentence or mark that disagrees with the "
                             "registry and the cells' points")


def main(args) -> int:
    for fact, value in course_facts().items():
        print(f"{fact}: {value:g}")
    for path in sorted(NOTEBOOKS_DIR.glob("q*.ipynb")):
        print(marks_mod.summary(marks_mod.notebook_marks(path)))
    if not args.check:
        return 0
    found = problems()
    for line in found:
        print(line, file=sys.stderr)
    print(f"facts: {len(found)} disagreement(s)", file=sys.stderr)
    return 1 if found else 0
