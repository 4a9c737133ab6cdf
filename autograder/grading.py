"""``python -m autograder grade``: batch grading outside the students' kernels.

    python -m autograder grade SUBMITTED --out OUT [--jobs N] [--timeout S] [--db-url URL]
                                                   [--reveal-hidden] [--secret-file F]

``SUBMITTED`` has nbgrader's layout, ``SUBMITTED/<student>/tripos2006/<notebook>.ipynb``. For
every student, notebook and auto-graded test cell of the *source* notebooks the grader

1. reads the submission defensively (:func:`read_submission`): invalid JSON, an old nbformat, a
   missing or misnamed file, a huge file, duplicated or stripped cells each get a clear status;
2. runs the student's solution cells and the graded function in a sandbox
   (:mod:`autograder.sandbox`) on the exercise's cases (:mod:`autograder.exercises`): the visible
   ones and hidden ones drawn from a generator seeded by the course secret and the student id,
   so a re-grade gives the same cases and the same scores;
3. compares each plain-data answer with the reference *in this process* with the exercise's own
   rule; a test cell scores ``points × (cases passed / cases)``, the points taken from the
   source notebook (never from the submission);
4. writes ``OUT/grades.csv``, ``OUT/feedback/<student>/<notebook>.html``
   (:mod:`autograder.feedback`), ``OUT/report.html`` (:mod:`autograder.report`), and keeps
   nbgrader's gradebook and ``autograded/`` notebooks in step (:mod:`autograder.gradebook`).

The exit status is 0 whenever the batch was graded, whatever the submissions did; 2 for a usage
error (no such folder, no source notebooks, unreadable secret).

Statuses (the ``status`` column of ``grades.csv``) are listed in :data:`STATUSES`.
"""

from __future__ import annotations

import argparse
import ast
import csv
import difflib
import hashlib
import hmac
import json
import os
import queue
import re
import secrets
import shutil
import stat
import sys
import tempfile
import threading
import time
import traceback
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import sandbox
from course_lib.answers import ChoiceFormatError, choice_letters

from .exercises import REGISTRY, NotPlainData, to_plain

ASSIGNMENT = "tripos2006"

#: Every status a row of ``grades.csv`` can carry, with what it means for the student.
STATUSES = {
    "ok": "every case passed",
    "failed": "the function ran but some answers were wrong (value, shape or type), or it did "
              "not raise the error a bad input calls for",
    "error": "the function raised an exception or crashed the Python process on some cases, or "
             "it is not defined after running the solution cells",
    "unanswered": "no answer was given: the cell is as released (it still raises "
                  "NotImplementedError), emptied, or sets the answer to None",
    "timeout": "the function took longer than the time limit on some cases",
    "rejected-output": "the function returned something that is not plain numbers (an object of "
                       "its own class, an array subclass, a result too large to keep)",
    "reference-used": "the function called the course's reference implementation (score 0)",
    "missing": "the notebook was not submitted (or was renamed), or its solution cell is gone",
    "unreadable": "the notebook file could not be read: invalid JSON, an old notebook format, "
                  "not a notebook, or far too large",
    "manual": "a written answer, marked by hand in formgrader (no automatic score)",
    "grader-error": "the grader itself failed on this cell (not the student's doing): the "
                    "instructor must look into it",
}
#: When a test cell fails in several ways, the status names the most serious one.
_SEVERITY = ["reference-used", "rejected-output", "timeout", "error", "failed", "unanswered"]
CSV_COLUMNS = ["student", "notebook", "grade_id", "score", "max_score", "status", "message"]

DEFAULT_SECRET = Path("~/.config/4f9/secret").expanduser()
MAX_NOTEBOOK_MB = 25.0
_STUDENT_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._@+-]{0,127}$")


# ============================================================================================
# the course: source notebooks


@dataclass
class SourceCell:
    index: int
    cell_type: str
    source: str
    meta: dict          # the cell's nbgrader metadata


@dataclass
class SourceNotebook:
    """What the grader takes from the instructor's notebook (never from a submission)."""

    name: str
    path: Path
    nb: dict
    setup_source: str
    cells: list[SourceCell]
    solution_ids: list[str]          #: grade_ids of code solution cells, in order
    graded: list[tuple[str, str, float]]   #: (name, test grade_id, points) of auto-graded tests
    manual: list[tuple[str, float]]        #: (grade_id, points) of manually graded answers

    def cell(self, grade_id: str) -> SourceCell | None:
        for c in self.cells:
            if c.meta.get("grade_id") == grade_id:
                return c
        return None


def load_source(path: Path) -> SourceNotebook:
    """Parse one source notebook: its setup cell, solution cells, tests and their points."""
    nb = json.loads(Path(path).read_text(encoding="utf-8"))
    name = Path(path).stem
    cells = []
    for i, c in enumerate(nb.get("cells", [])):
        meta = (c.get("metadata") or {}).get("nbgrader") or {}
        cells.append(SourceCell(i, c.get("cell_type", ""), _join(c.get("source", "")), meta))
    setup = next((c for c in cells if c.meta.get("grade_id") == f"setup_{name}"), None)
    if setup is None:
        setup = next((c for c in cells if c.cell_type == "code"
                      and str(c.meta.get("grade_id", "")).startswith("setup")), None)
    solution_ids, graded, manual = [], [], []
    for c in cells:
        gid = c.meta.get("grade_id")
        if not gid:
            continue
        if c.cell_type == "code" and c.meta.get("solution") and not c.meta.get("grade"):
            solution_ids.append(gid)
        elif c.cell_type == "code" and c.meta.get("grade") and not c.meta.get("solution"):
            target = gid[len("test_"):] if gid.startswith("test_") else gid
            graded.append((target, gid, float(c.meta.get("points", 0) or 0)))
        elif c.meta.get("grade") and c.meta.get("solution"):
            manual.append((gid, float(c.meta.get("points", 0) or 0)))
    return SourceNotebook(name, Path(path), nb, setup.source if setup else "", cells,
                          solution_ids, graded, manual)


def default_sources() -> list[Path]:
    try:
        from .course import source_notebooks
    except ImportError:  # pragma: no cover - course.py is part of the project
        root = Path(__file__).resolve().parent.parent / "notebooks"
        return sorted(root.glob("q[0-9]*_*.ipynb"))
    return source_notebooks()


def _join(source) -> str:
    if isinstance(source, list):
        return "".join(str(s) for s in source)
    return source if isinstance(source, str) else ""


# ============================================================================================
# reading a submission


@dataclass
class Submission:
    """One student's notebook as read by the grader."""

    student: str
    notebook: str
    path: Path
    status: str = "ok"              #: ok | missing | unreadable
    message: str = ""
    nb: dict | None = None
    cells: list[dict] = field(default_factory=list)   #: normalised cells (type, source, meta)
    notes: list[str] = field(default_factory=list)


def read_submission(folder: Path, student: str, notebook: str,
                    max_mb: float = MAX_NOTEBOOK_MB) -> Submission:
    """Read ``folder/<notebook>.ipynb`` without trusting it; never raises."""
    path = folder / f"{notebook}.ipynb"
    sub = Submission(student, notebook, path)
    if folder.is_symlink():  # e.g. a link to another student's folder: nothing of theirs
        return _unreadable(sub, f"the {folder.name} folder of the submission is a symbolic "
                                "link, not a folder of files")
    if not folder.is_dir():
        sub.status, sub.message = "missing", (
            f"no {notebook}.ipynb was submitted (there is no {ASSIGNMENT} folder in your "
            "submission)")
        return sub
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        sub.status = "missing"
        similar = _similar_files(folder, notebook)
        sub.message = f"no {notebook}.ipynb was submitted"
        if similar:
            sub.message += (f"; found {', '.join(repr(s) for s in similar)} instead: notebooks "
                            "must keep their original file name to be graded")
        return sub
    except OSError as exc:
        return _unreadable(sub, f"it could not be opened ({exc.strerror})")
    if stat.S_ISLNK(st.st_mode):
        return _unreadable(sub, "it is a symbolic link, not a notebook file")
    if not stat.S_ISREG(st.st_mode):
        return _unreadable(sub, "it is not a regular file")
    if st.st_size > max_mb * 2**20:
        return _unreadable(sub, f"the file is {st.st_size / 2**20:.0f} MB, far larger than a "
                                "notebook should be (huge outputs?): clear all outputs "
                                "(Edit > Clear Outputs of All Cells), save and resubmit")
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW)
        with os.fdopen(fd, "rb") as f:
            data = f.read(int(max_mb * 2**20) + 1)
    except OSError as exc:
        return _unreadable(sub, f"it could not be read ({exc.strerror})")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        return _unreadable(sub, "it is not a text file (not UTF-8)")
    try:
        nb = json.loads(text)
    except ValueError as exc:
        where = f" (line {exc.lineno}, column {exc.colno})" if hasattr(exc, "lineno") else ""
        return _unreadable(sub, f"it is not valid notebook JSON{where}: was it edited in a text "
                                "editor or cut short? Restore it from a checkpoint or the "
                                "released version and resubmit")
    if not isinstance(nb, dict):
        return _unreadable(sub, "it is JSON but not a notebook")
    major = nb.get("nbformat")
    if "worksheets" in nb or (type(major) is int and major < 4):
        return _unreadable(sub, f"it is saved in an old notebook format (nbformat {major}); "
                                "open it in JupyterLab, save it (nbformat 4) and resubmit")
    if type(major) is not int or major > 4 or not isinstance(nb.get("cells"), list):
        return _unreadable(sub, "it is not a Jupyter notebook in format 4 (no list of cells)")
    cells = []
    for i, c in enumerate(nb["cells"]):
        if not isinstance(c, dict) or not isinstance(c.get("cell_type"), str):
            sub.notes.append(f"cell {i} is malformed and was ignored")
            continue
        src = c.get("source", "")
        if not isinstance(src, (str, list)) or (isinstance(src, list)
                                                and not all(isinstance(s, str) for s in src)):
            sub.notes.append(f"cell {i} has no readable source and was ignored")
            continue
        meta = c.get("metadata") if isinstance(c.get("metadata"), dict) else {}
        nbg = meta.get("nbgrader") if isinstance(meta.get("nbgrader"), dict) else {}
        gid = nbg.get("grade_id") if isinstance(nbg.get("grade_id"), str) else None
        cells.append({"index": i, "cell_type": c["cell_type"], "source": _join(src),
                      "grade_id": gid, "raw": c})
    sub.nb, sub.cells = nb, cells
    return sub


def _unreadable(sub: Submission, why: str) -> Submission:
    sub.status = "unreadable"
    sub.message = f"{sub.notebook}.ipynb could not be graded: {why}"
    return sub


def _similar_files(folder: Path, notebook: str) -> list[str]:
    try:
        names = sorted(p.name for p in folder.iterdir() if p.suffix.lower() == ".ipynb")
    except OSError:
        return []
    stems = {n: Path(n).stem for n in names}
    want = notebook.lower()
    hits = [n for n, s in stems.items()
            if want in s.lower() or s.lower().replace(" ", "_").replace("-", "_") == want]
    close = set(difflib.get_close_matches(notebook, list(stems.values()), n=3, cutoff=0.7))
    hits += [n for n, s in stems.items() if s in close and n not in hits]
    return hits[:3]


# --------------------------------------------------------------------------------------------
# which student cells to run


def to_python(source: str) -> tuple[str | None, str]:
    """Plain Python for a notebook cell: IPython magics and shell lines turned into no-ops.

    Returns ``(code, note)``; ``code`` is None when the whole cell is a non-Python cell magic
    (``%%bash``, ``%%html``...), which the grader skips.
    """
    lines = source.splitlines()
    note = ""
    if lines and lines[0].lstrip().startswith("%%"):
        magic = lines[0].lstrip()[2:].split()[0] if lines[0].strip() != "%%" else ""
        if magic in ("time", "timeit", "capture", "prun", "python", "python3", "debug"):
            lines = lines[1:]
            note = f"cell magic %%{magic} ignored"
        else:
            return None, f"cell magic %%{magic}: cell skipped"
    text = "\n".join(lines)
    try:
        from IPython.core.inputtransformer2 import TransformerManager

        return TransformerManager().transform_cell(text), note
    except Exception:  # noqa: BLE001 - fall back to dropping magic and shell lines
        kept = [ln for ln in text.splitlines() if not ln.lstrip().startswith(("%", "!"))]
        return "\n".join(kept) + "\n", note


def _defines(code: str, name: str) -> bool:
    try:
        tree = ast.parse(code)
    except (SyntaxError, ValueError):
        return bool(re.search(rf"^(def\s+{re.escape(name)}\b|{re.escape(name)}\s*=)", code, re.M))
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name == name:
            return True
        if isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for t in targets:
                if isinstance(t, ast.Name) and t.id == name:
                    return True
    return False


@dataclass
class CellPlan:
    """The student's cells the sandbox runs (shared by every graded name of a notebook)."""

    cells: list[tuple[str, str]]          #: (label, python) in notebook order
    found: dict[str, str]                 #: graded name -> "tagged" | "by-name" | "missing"
    notes: dict[str, list[str]]           #: graded name -> notes for the student
    chosen: dict[str, int]                #: graded name -> index (in sub.cells) of its cell
    skipped: list[str] = field(default_factory=list)


def plan_cells(src: SourceNotebook, sub: Submission) -> CellPlan:
    """Pick the solution cells to run: by grade_id, else (metadata stripped) by what they define.

    Every cell tagged with one of the source's solution grade_ids runs, in notebook order (as
    "Run All" would); a graded name whose tagged cell is gone is looked up among untagged code
    cells by its definition (``def name`` / ``name = ...``). Test cells, figure and explorer
    cells never run.
    """
    sol_ids = set(src.solution_ids)
    names = [g[0] for g in src.graded]
    chosen: dict[int, str] = {}
    found: dict[str, str] = {}
    notes: dict[str, list[str]] = {n: [] for n in names}
    by_id: dict[str, list[int]] = {}
    for k, c in enumerate(sub.cells):
        if c["cell_type"] == "code" and c["grade_id"] in sol_ids:
            by_id.setdefault(c["grade_id"], []).append(k)
            chosen[k] = c["grade_id"]
    for gid, ks in by_id.items():
        if len(ks) > 1 and gid in notes:
            notes[gid].append(f"the solution cell of {gid} appears {len(ks)} times (a copied "
                              "cell?); all copies ran in notebook order, so the last one counts")
    python: dict[int, str] = {}
    skipped = []
    for k, c in enumerate(sub.cells):
        if c["cell_type"] != "code":
            continue
        code, note = to_python(c["source"])
        if code is not None:
            python[k] = code
        if note and k in chosen:
            skipped.append(f"cell {chosen[k]}: {note}")
    chosen_for: dict[str, int] = {}
    for name in names:
        ks = by_id.get(name)
        if ks:
            found[name] = "tagged"
            chosen_for[name] = ks[-1]
            continue
        candidates = [k for k, c in enumerate(sub.cells)
                      if c["cell_type"] == "code" and k in python and k not in chosen
                      and not (c["grade_id"] or "").startswith("test_")
                      and _defines(python[k], name)]
        if candidates:
            k = candidates[-1]
            chosen[k] = name
            chosen_for[name] = k
            found[name] = "by-name"
            notes[name].append(f"the nbgrader metadata of the solution cell of {name} was "
                               "missing or changed; the cell that defines it was graded instead")
        else:
            found[name] = "missing"
    cells = [(f"{chosen[k]} (cell {sub.cells[k]['index'] + 1})", python[k])
             for k in sorted(chosen) if k in python]
    return CellPlan(cells, found, notes, chosen_for, skipped)


# ============================================================================================
# grading one test cell


@dataclass
class CaseRecord:
    """One case as the feedback shows it."""

    index: int
    label: str
    visible: bool
    #: pass | wrong-value | wrong-shape | error | timeout | rejected | reference-used
    verdict: str
    reason: str = ""
    args: tuple = ()
    kwargs: dict = field(default_factory=dict)
    expected: Any = None
    received: Any = None
    raises: str = ""


@dataclass
class CellResult:
    """One row of ``grades.csv`` plus what the feedback needs."""

    student: str
    notebook: str
    grade_id: str
    name: str
    score: float | None
    max_score: float
    status: str
    message: str
    kind: str = "function"          #: function | choice | manual
    cases: list[CaseRecord] = field(default_factory=list)
    stdout: str = ""
    stderr: str = ""
    notes: list[str] = field(default_factory=list)
    seconds: float = 0.0
    code: str = ""                  #: the student's graded cell (or written answer), for feedback

    def row(self) -> dict:
        return {"student": self.student, "notebook": self.notebook, "grade_id": self.grade_id,
                "score": "" if self.score is None else _fmt(self.score),
                "max_score": _fmt(self.max_score), "status": self.status,
                "message": self.message}


def _fmt(x: float) -> str:
    """Scores as written to grades.csv: at most six decimals, no trailing zeros."""
    text = f"{float(x):.6f}".rstrip("0").rstrip(".")
    return text if text not in ("", "-0") else "0"


def case_seed(secret: bytes, student: str, name: str) -> int:
    """The seed of a student's hidden cases: HMAC-SHA256 of the secret over student and name."""
    digest = hmac.new(secret, f"{ASSIGNMENT}\0{student}\0{name}".encode(), hashlib.sha256)
    return int.from_bytes(digest.digest()[:16], "big")


def _verdict(ex, case, expected, outcome: sandbox.CaseOutcome) -> tuple[str, str]:
    """``(verdict, reason)`` for one case, decided here, never in the student's process."""
    kind = outcome.kind
    if ex.kind == "choice":
        return _choice_verdict(ex, outcome)
    if kind == "returned":
        if case.raises is not None:
            return "wrong-value", (f"should raise {case.raises.__name__} for this input, but "
                                   "returned a value")
        try:
            plain = to_plain(outcome.value)
        except NotPlainData as exc:
            return "rejected", f"returned {exc}, not plain numbers"
        try:
            why = ex.compare(expected, plain)
        except Exception as exc:  # noqa: BLE001 - a rule that cannot compare is a wrong answer
            why = f"wrong value (the answer could not be compared: {type(exc).__name__})"
        if why is None:
            return "pass", ""
        low = why.lower()
        if "wrong shape" in low or "wrong type" in low or "wrong number" in low:
            return "wrong-shape", why
        return "wrong-value", why
    if kind == "raised":
        if outcome.error_type == "NotImplementedError":
            return "unanswered", ("not attempted: the function still raises NotImplementedError "
                                  "(delete that line and write your code)")
        if case.raises is not None:
            want = f"{case.raises.__module__}.{case.raises.__qualname__}"
            if want in outcome.error_mro:
                return "pass", ""
            return "error", (f"raised {outcome.error_type} ({_clip(outcome.message, 200)}) "
                             f"instead of {case.raises.__name__}")
        return "error", f"raised {outcome.error_type}: {_clip(outcome.message, 300)}"
    if kind == "timeout":
        return "timeout", outcome.message or "took too long"
    if kind == "crashed":
        return "error", "crashed the Python process" + (f" ({outcome.message})"
                                                          if outcome.message else "")
    if kind == "rejected":
        return "rejected", outcome.message or "returned something that is not plain numbers"
    if kind == "reference-used":
        return "reference-used", outcome.message or "called the reference implementation"
    if kind == "not-run":
        return ("timeout" if "time" in outcome.message else "error"), outcome.message
    return "error", outcome.message or kind


def _choice_verdict(ex, outcome: sandbox.CaseOutcome) -> tuple[str, str]:
    """A multiple-choice answer: one shared format (:func:`course_lib.answers.choice_letters`)."""
    if outcome.kind != "returned":
        return "unanswered", _no_answer(ex.name)
    options = "".join(ex.options) if getattr(ex, "options", None) else "abcd"
    try:
        given = choice_letters(outcome.value, options, name=ex.name)
    except ChoiceFormatError as exc:
        return ("unanswered", _no_answer(ex.name)) if exc.unanswered else ("wrong-shape", str(exc))
    key = choice_letters("".join(ex.answer), options)
    return ("pass", "") if given == key else ("wrong-value", "wrong answer")


def _no_answer(name: str) -> str:
    return f"no answer given: set {name} to a string of option letters, such as \"a\" or \"bd\""


def _clip(text: str, n: int) -> str:
    text = " ".join(str(text).split())
    return text if len(text) <= n else text[: n - 3] + "..."


_VERDICT_WORDS = {
    "unanswered": "not attempted", "wrong-value": "wrong value",
    "wrong-shape": "wrong shape or type", "error": "raised an error",
    "timeout": "timed out", "rejected": "returned something that is not plain numbers",
    "reference-used": "called the reference",
}
_VERDICT_STATUS = {"unanswered": "unanswered", "wrong-value": "failed", "wrong-shape": "failed",
                   "error": "error",
                   "timeout": "timeout", "rejected": "rejected-output",
                   "reference-used": "reference-used"}


def summarise(records: list[CaseRecord], points: float) -> tuple[float, str, str]:
    """``(score, status, message)`` of a test cell from its case verdicts."""
    n = len(records)
    if n == 0:
        return 0.0, "error", "no cases could be run"
    passed = sum(r.verdict == "pass" for r in records)
    counts: dict[str, int] = {}
    for r in records:
        if r.verdict != "pass":
            counts[r.verdict] = counts.get(r.verdict, 0) + 1
    if counts.get("unanswered") == n:
        return 0.0, "unanswered", _clip(records[0].reason, 300)
    if "reference-used" in counts:
        ref = next(r for r in records if r.verdict == "reference-used")
        return 0.0, "reference-used", (
            f"{_clip(ref.reason, 160)}: a graded function must be your own work, so this test "
            "scores 0")
    score = round(points * passed / n, 6)
    if passed == n:
        return score, "ok", ("correct" if n == 1 and records[0].label == "your answer"
                             else f"all {n} cases passed")
    statuses = {_VERDICT_STATUS[v] for v in counts}
    status = next(s for s in _SEVERITY if s in statuses)
    if n == 1 and records[0].label == "your answer":   # a multiple-choice item
        return score, status, _clip(records[0].reason, 300)
    parts = [f"{c} {_VERDICT_WORDS[v]}" for v, c in sorted(counts.items(), key=lambda x: -x[1])]
    msg = f"{passed} of {n} cases passed ({', '.join(parts)})"
    first = next((r for r in records if r.verdict != "pass" and r.visible), None)
    if first is not None:
        msg += f"; e.g. {first.label or 'a visible case'}: {_clip(first.reason, 200)}"
    else:
        first = next(r for r in records if r.verdict != "pass")
        msg += f"; e.g. a hidden case: {_VERDICT_WORDS[first.verdict]}"
    return score, status, msg


# ============================================================================================
# the batch


@dataclass
class Options:
    out: Path
    jobs: int = 1
    limits: sandbox.Limits = field(default_factory=sandbox.Limits)
    secret: bytes = b""
    reveal_hidden: bool = False
    db_url: str | None = None
    max_notebook_mb: float = MAX_NOTEBOOK_MB
    progress: bool = True
    gradebook: bool = True
    use_zygote: bool = True     #: fork runs from a warm interpreter (else one Python per run)


@dataclass
class Task:
    student: str
    src: SourceNotebook
    sub: Submission
    plan: CellPlan
    name: str
    test_id: str
    points: float


def discover_students(submitted: Path) -> list[str]:
    """Student ids: the folders of ``SUBMITTED`` (hidden and oddly named entries skipped)."""
    students = []
    for p in sorted(submitted.iterdir()):
        if p.name.startswith(".") or not p.is_dir() or p.is_symlink():
            continue
        if not _STUDENT_RE.match(p.name):
            print(f"warning: skipping {p.name!r}: not a valid student id", file=sys.stderr)
            continue
        students.append(p.name)
    return students


@dataclass
class Batch:
    """The outcome of :func:`grade_batch`."""

    results: list[CellResult]                       #: one per (student, notebook, graded cell)
    submissions: dict[tuple[str, str], Submission]  #: (student, notebook) -> what was read
    students: list[str]


def grade_batch(submitted: Path, sources: list[SourceNotebook], opts: Options,
                students: list[str] | None = None) -> Batch:
    """Grade every student's notebooks: one :class:`CellResult` per graded cell."""
    submitted = Path(submitted)
    students = discover_students(submitted) if students is None else students
    results: list[CellResult] = []
    tasks: list[Task] = []
    subs: dict[tuple[str, str], Submission] = {}
    for student in students:
        folder = submitted / student / ASSIGNMENT
        for src in sources:
            sub = read_submission(folder, student, src.name, opts.max_notebook_mb)
            subs[(student, src.name)] = sub
            if sub.status != "ok":
                for name, test_id, points in src.graded:
                    kind = REGISTRY[name].kind if name in REGISTRY else "function"
                    results.append(CellResult(student, src.name, test_id, name, 0.0, points,
                                              sub.status, sub.message, kind=kind))
                for gid, points in src.manual:
                    results.append(CellResult(student, src.name, gid, gid, 0.0, points,
                                              sub.status, sub.message, kind="manual"))
                continue
            plan = plan_cells(src, sub)
            for name, test_id, points in src.graded:
                if name not in REGISTRY:
                    results.append(CellResult(
                        student, src.name, test_id, name, 0.0, points, "error",
                        f"the autograder has no rule for {test_id} (instructor: register "
                        f"{name!r} in autograder/exercises)"))
                    continue
                if plan.found.get(name) == "missing":
                    results.append(CellResult(
                        student, src.name, test_id, name, 0.0, points, "missing",
                        f"no solution cell for {name}: the cell (grade_id {name!r}) was deleted "
                        "and no other cell defines it", kind=REGISTRY[name].kind))
                    continue
                tasks.append(Task(student, src, sub, plan, name, test_id, points))
            for gid, points in src.manual:
                answer = [c["source"] for c in sub.cells if c["grade_id"] == gid]
                present = bool(answer)
                results.append(CellResult(
                    student, src.name, gid, gid, None if present else 0.0, points,
                    "manual" if present else "missing",
                    "marked by hand in formgrader" if present else
                    f"the answer cell {gid} is missing from the notebook", kind="manual",
                    code=answer[-1] if answer else ""))
    results.extend(_run_tasks(tasks, opts))
    order = {s.name: i for i, s in enumerate(sources)}
    cell_order = {(s.name, gid): i for s in sources for i, gid in
                  enumerate([c.meta.get("grade_id") for c in s.cells])}
    results.sort(key=lambda r: (r.student, order.get(r.notebook, 99),
                                cell_order.get((r.notebook, r.grade_id), 999)))
    return Batch(results, subs, list(students))


def _run_tasks(tasks: list[Task], opts: Options) -> list[CellResult]:
    if not tasks:
        return []
    workdir = tempfile.mkdtemp(prefix="4f9-grading-")
    os.chmod(workdir, 0o711)  # sandbox uids may enter their own scratch dirs, nothing else
    slots: queue.Queue[int] = queue.Queue()
    for k in range(max(1, opts.jobs)):
        slots.put(k)
    deny = sandbox.protected_dirs() + [str(opts.out.resolve())]
    deny += sorted({str(t.src.path.resolve().parent) for t in tasks})
    deny += sorted({str(t.sub.path.resolve().parent.parent.parent) for t in tasks})
    # only course_lib is ever loaded into a sandbox (never the registry itself)
    reference_targets = sorted({(ex.reference.__module__, ex.reference.__name__)
                                for ex in REGISTRY.values()
                                if ex.kind == "function" and ex.reference is not None
                                and hasattr(ex.reference, "__name__")
                                and str(ex.reference.__module__).startswith("course_lib.")})
    graded_names = sorted(n for n, ex in REGISTRY.items() if ex.kind == "function")
    progress = _Progress(len(tasks), enabled=opts.progress)
    results: list[CellResult] = []

    zygotes: dict[int, sandbox.Zygote | None] = {}
    preload = sorted({m for m, _ in reference_targets})

    def zygote_for(slot: int) -> sandbox.Zygote | None:
        z = zygotes.get(slot)
        if z is not None and not z.alive():
            z.close()
            z = zygotes[slot] = None
        if slot not in zygotes or (z is None and opts.use_zygote):
            try:
                z = sandbox.Zygote(preload) if opts.use_zygote else None
            except Exception as exc:  # noqa: BLE001 - fall back to a fresh interpreter per run
                print(f"warning: no warm sandbox ({exc}); starting one Python per test",
                      file=sys.stderr)
                opts.use_zygote = False
                z = None
            zygotes[slot] = z
        return z

    def work(task: Task) -> CellResult:
        slot = slots.get()
        try:
            return grade_task(task, opts, workdir, slot, deny, reference_targets, graded_names,
                              zygote_for(slot))
        except Exception as exc:  # noqa: BLE001 - one broken task never stops the batch
            traceback.print_exc()
            return CellResult(task.student, task.src.name, task.test_id, task.name, 0.0,
                              task.points, "grader-error",
                              f"the grader failed on this test ({type(exc).__name__}); "
                              "please report it to the instructor")
        finally:
            slots.put(slot)

    try:
        with ThreadPoolExecutor(max_workers=max(1, opts.jobs)) as pool:
            futures = [pool.submit(work, t) for t in tasks]
            for fut in as_completed(futures):
                r = fut.result()
                results.append(r)
                progress.update(f"{r.student} {r.grade_id}")
    finally:
        progress.close()
        for z in zygotes.values():
            if z is not None:
                z.close()
        shutil.rmtree(workdir, ignore_errors=True)
    return results


def grade_task(task: Task, opts: Options, workdir: str, slot: int, deny: list[str],
               reference_targets, graded_names, zygote=None) -> CellResult:
    """Run one graded name of one submission in the sandbox and judge every case."""
    ex = REGISTRY[task.name]
    rng = np.random.default_rng(case_seed(opts.secret, task.student, task.name))
    if ex.kind == "choice":
        cases = [None]
        expected = [None]
        inputs = [((), {})]
    else:
        all_cases = ex.draw_cases(rng)
        cases, expected, inputs = [], [], []
        for case in all_cases:
            exp = None
            if case.raises is None:
                try:
                    exp = ex.expected(case)
                except Exception as exc:  # noqa: BLE001 - a registry problem: skip the case
                    print(f"warning: reference of {task.name} failed on case {case.label!r}: "
                          f"{exc}; case skipped", file=sys.stderr)
                    continue
            cases.append(case)
            expected.append(exp)
            inputs.append((tuple(case.args), dict(case.kwargs)))
    job = sandbox.SandboxJob(
        name=task.name, kind=ex.kind, setup_source=task.src.setup_source,
        cells=task.plan.cells, cases=inputs, reference_targets=list(reference_targets),
        graded_names=list(graded_names), deny_paths=deny)
    run = sandbox.run_job(job, opts.limits, workdir, slot, zygote)
    records = []
    for i, (case, exp, outcome) in enumerate(zip(cases, expected, run.outcomes, strict=True)):
        verdict, reason = _verdict(ex, case, exp, outcome)
        if case is None:  # a multiple-choice answer: one visible "case", never revealed
            rec = CaseRecord(i, "your answer", True, verdict, reason)
        else:
            rec = CaseRecord(i, case.label, bool(case.visible), verdict, reason,
                             args=tuple(case.args), kwargs=dict(case.kwargs), expected=exp,
                             received=outcome.value if outcome.kind == "returned" else None,
                             raises=case.raises.__name__ if case.raises else "")
        records.append(rec)
    notes = list(task.plan.notes.get(task.name, []))
    k = task.plan.chosen.get(task.name)
    code = task.sub.cells[k]["source"] if k is not None else ""
    load_notes = [n for n in run.load_notes if not n.startswith("the setup cell")]
    if not run.defined:
        why = "; ".join(_clip(n, 200) for n in load_notes[-3:])
        what = "function" if ex.kind == "function" else "answer variable"
        status, message = "error", (f"the {what} {task.name} is not defined after running your "
                                    "solution cells" + (f" ({why})" if why else ""))
        if _unattempted(code, ex.kind):
            status = "unanswered"
            message = (_no_answer(task.name) if ex.kind == "choice" else
                       f"not attempted: write the function {task.name} in its cell")
        res = CellResult(task.student, task.src.name, task.test_id, task.name, 0.0, task.points,
                         status, message, kind=ex.kind,
                         cases=records, stdout=run.stdout, stderr=run.stderr, notes=notes,
                         seconds=run.seconds, code=code)
        return res
    score, status, message = summarise(records, task.points)
    if notes:
        message += ". Note: " + "; ".join(notes)
    setup_notes = [n for n in run.load_notes if n.startswith("the setup cell")]
    if setup_notes:  # the instructor's setup failed in the sandbox: say so loudly
        print(f"warning: {task.src.name}: {setup_notes[0]}", file=sys.stderr)
    return CellResult(task.student, task.src.name, task.test_id, task.name, score, task.points,
                      status, message, kind=ex.kind, cases=records, stdout=run.stdout,
                      stderr=run.stderr, notes=notes + load_notes, seconds=run.seconds, code=code)


def _unattempted(code: str, kind: str) -> bool:
    """True for a solution cell left as released (only the stub) or emptied."""
    body = [ln.strip() for ln in code.splitlines()
            if ln.strip() and not ln.strip().startswith("#")]
    stub = {"raise NotImplementedError()", "raise NotImplementedError"}
    if kind == "choice":
        return all(ln in stub for ln in body)
    # a function cell: its signature and docstring stay; unattempted when nothing else runs
    return not body or all(ln in stub for ln in body)


class _Progress:
    """tqdm when it is installed, else a plain counter on stderr."""

    def __init__(self, total: int, enabled: bool = True):
        self.total, self.n, self.enabled = total, 0, enabled
        self.bar = None
        self.t0 = time.monotonic()
        self.lock = threading.Lock()
        if not enabled:
            return
        try:
            from tqdm import tqdm

            self.bar = tqdm(total=total, unit="test", desc="grading", file=sys.stderr)
        except ImportError:
            self.tty = sys.stderr.isatty()
            self.step = max(1, total // 20)

    def update(self, what: str = "") -> None:
        with self.lock:
            self.n += 1
            if not self.enabled:
                return
            if self.bar is not None:
                self.bar.update(1)
                return
            if self.tty:
                print(f"\rgrading {self.n}/{self.total} {what[:50]:<50}", end="",
                      file=sys.stderr, flush=True)
            elif self.n % self.step == 0 or self.n == self.total:
                print(f"grading {self.n}/{self.total} ({time.monotonic() - self.t0:.0f} s)",
                      file=sys.stderr, flush=True)

    def close(self) -> None:
        if not self.enabled:
            return
        if self.bar is not None:
            self.bar.close()
        elif self.tty:
            print(file=sys.stderr)


# ============================================================================================
# outputs


def write_csv(results: list[CellResult], path: Path) -> None:
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, fieldnames=CSV_COLUMNS)
        w.writeheader()
        for r in results:
            w.writerow(r.row())


def read_secret(path: Path | None) -> bytes:
    """The course secret (created at the default location on first use)."""
    if path is None:
        path = DEFAULT_SECRET
        if not path.exists():
            path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
            with os.fdopen(fd, "w") as f:
                f.write(secrets.token_hex(32) + "\n")
            print(f"note: created the course secret {path} (keep it: hidden cases and "
                  "re-grades depend on it)", file=sys.stderr)
    data = Path(path).read_bytes().strip()
    if not data:
        raise ValueError(f"the secret file {path} is empty")
    return data


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("submitted", type=Path,
                        help="nbgrader's submitted folder: SUBMITTED/<student>/tripos2006/*.ipynb")
    parser.add_argument("--out", type=Path, required=True,
                        help="output folder: grades.csv, feedback/, report.html, autograded/")
    parser.add_argument("--jobs", type=int, default=max(1, min(8, os.cpu_count() or 1)),
                        help="sandboxes run in parallel (default: the number of CPUs, at most 8)")
    parser.add_argument("--timeout", type=float, default=10.0,
                        help="time limit per case, in seconds (default 10)")
    parser.add_argument("--db-url", default=None,
                        help="nbgrader gradebook URL (default sqlite:///<course root>/gradebook.db;"
                             " postgresql://... for a shared server)")
    parser.add_argument("--reveal-hidden", action="store_true",
                        help="after the deadline: show the failing hidden cases' inputs, "
                             "expected and received values in the feedback")
    parser.add_argument("--secret-file", type=Path, default=None,
                        help="the course secret that seeds the hidden cases (default "
                             "~/.config/4f9/secret, created on first use)")
    parser.add_argument("--source", type=Path, default=None,
                        help="folder of the source notebooks (default: the course's notebooks/)")
    parser.add_argument("--load-timeout", type=float, default=None,
                        help="seconds allowed for the setup and solution cells (default 30 + "
                             "the per-case time limit)")
    parser.add_argument("--memory-mb", type=int, default=2048,
                        help="address-space limit of each sandbox, in MB (default 2048)")
    parser.add_argument("--max-notebook-mb", type=float, default=MAX_NOTEBOOK_MB,
                        help=f"larger notebook files are rejected (default {MAX_NOTEBOOK_MB:g})")
    parser.add_argument("--no-gradebook", action="store_true",
                        help="do not touch nbgrader's gradebook or write autograded notebooks")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def main(args: argparse.Namespace) -> int:
    submitted: Path = args.submitted
    if not submitted.is_dir():
        print(f"error: {submitted} is not a folder", file=sys.stderr)
        return 2
    paths = (sorted(Path(args.source).glob("q[0-9]*_*.ipynb")) if args.source
             else default_sources())
    if not paths:
        print("error: no source notebooks found", file=sys.stderr)
        return 2
    try:
        secret = read_secret(args.secret_file)
    except (OSError, ValueError) as exc:
        print(f"error: cannot read the course secret: {exc}", file=sys.stderr)
        return 2
    sources = [load_source(p) for p in paths]
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    os.chmod(out, 0o700)
    if sandbox.sandbox_identity() is not None:
        mode = stat.S_IMODE(submitted.stat().st_mode)
        if mode & 0o077:
            os.chmod(submitted, 0o700)
            print(f"note: {submitted} was readable by other users; it is now 0700 so that "
                  "sandboxed code cannot read other students' files", file=sys.stderr)
    limits = sandbox.Limits(
        case_timeout=args.timeout,
        load_timeout=args.load_timeout if args.load_timeout else 30.0 + args.timeout,
        memory_mb=args.memory_mb)
    opts = Options(out=out, jobs=max(1, args.jobs), limits=limits, secret=secret,
                   reveal_hidden=args.reveal_hidden, db_url=args.db_url,
                   max_notebook_mb=args.max_notebook_mb, progress=not args.quiet,
                   gradebook=not args.no_gradebook)
    t0 = time.monotonic()
    batch = grade_batch(submitted, sources, opts)
    results = batch.results
    write_csv(results, out / "grades.csv")
    from . import feedback, report

    feedback.write_all(results, sources, out / "feedback", reveal_hidden=opts.reveal_hidden)
    report.write_report(results, sources, out / "report.html")
    if opts.gradebook:
        from . import gradebook

        try:
            gradebook.sync(batch, sources, submitted=submitted, out=out, db_url=opts.db_url)
        except Exception as exc:  # noqa: BLE001 - grades.csv is written; say what failed
            traceback.print_exc(limit=3)
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
            print(f"warning: the gradebook could not be updated ({type(exc).__name__}: "
                  f"{first}); grades.csv, the "
                  "feedback and the report are complete", file=sys.stderr)
    n_students = len({r.student for r in results})
    print(f"graded {n_students} students, {len(results)} cells in "
          f"{time.monotonic() - t0:.0f} s: {out / 'grades.csv'}", file=sys.stderr)
    return 0
