"""Keep nbgrader's gradebook and ``autograded/`` notebooks in step with the hardened grader.

nbgrader stays the instructors' workflow: formgrader reads the gradebook for the scores and the
``autograded/<student>/tripos2006/<notebook>.ipynb`` notebooks for manual grading. After
``python -m autograder grade`` this module

- makes sure the gradebook knows the assignment and every grade cell (through
  :func:`autograder.course.prepare_course`, which runs ``nbgrader generate_assignment``, when it
  does not yet);
- registers each student and submission and sets the ``auto_score`` of every auto-graded test
  cell to the sandboxed score (manual answer cells stay "needs manual grade");
- writes the autograded notebooks: the student's cells with every *trusted* cell (setup, tests,
  locked text) restored from the source by ``grade_id`` (hidden tests removed, so even nbgrader's
  own ``generate_feedback`` cannot leak them), duplicates demoted to plain cells, cells whose
  metadata was stripped re-tagged, missing cells re-inserted, outputs cleared, and each test cell
  carrying the grader's verdict as its output; a student's raw cell (or one of a type nbformat
  does not know) becomes a markdown cell quoting it (the Formgrader would show a raw cell's HTML
  as is: see ``safe_markdown``), and grading metadata on a cell the course does not know is
  dropped.

The course root is the folder holding ``SUBMITTED`` when that is an nbgrader course
(``<root>/submitted`` next to ``<root>/source/tripos2006``), otherwise ``OUT``; the gradebook is
``sqlite:///<root>/gradebook.db`` unless ``--db-url`` names another (PostgreSQL for a shared
server: nbgrader's FAQ advises against SQLite with several writers; this module is the only
writer during a grading run).
"""

from __future__ import annotations

import copy
import json
import re
import shutil
import sys
import traceback
import warnings
from pathlib import Path

from ..cells import CellRole, cell_role, join_source
from ..course import ASSIGNMENT, COURSE_ID, default_db_url
from ..model import Batch, CellKind, CellResult, SourceNotebook, Status, Submission, printable
from .choices import choice_legend
from .safe_markdown import quoted_cell

#: Files of a submission folder the autograded folder keeps: nbgrader's ``release_feedback``
#: needs both (``timestamp.txt`` names the submission, ``submission_secret.txt`` its exchange key).
#: Metadata key of the marker's rubric cells in the autograded notebooks.
RUBRIC_KEY = "autograder_rubric"
CARRIED_FILES = ("timestamp.txt", "submission_secret.txt")
_HIDDEN = re.compile(r"^[ \t]*###\s*BEGIN HIDDEN TESTS.*?^[ \t]*###\s*END HIDDEN TESTS[^\n]*\n?",
                     re.S | re.M)
HIDDEN_NOTE = ("# hidden tests: run outside the notebook by `python -m autograder grade` "
               "(see the grader's verdict below)\n")


def course_root(submitted: Path, out: Path) -> Path:
    """The nbgrader course root for a grading run (see the module docstring)."""
    submitted = Path(submitted).resolve()
    if submitted.name == "submitted" and (submitted.parent / "source" / ASSIGNMENT).is_dir():
        return submitted.parent
    return Path(out).resolve()


def submission_count(db_url: str) -> int:
    """How many submissions of the assignment the gradebook at ``db_url`` holds; 0 when it
    does not exist (a SQLite file is never created here) or cannot be read."""
    if db_url.startswith("sqlite:///") and not Path(db_url[len("sqlite:///"):]).is_file():
        return 0
    try:
        import sqlalchemy as sa

        engine = sa.create_engine(db_url)
        try:
            with engine.connect() as conn:
                if not sa.inspect(conn).has_table("submitted_assignment"):
                    return 0
                return int(conn.execute(sa.text(
                    "SELECT COUNT(*) FROM submitted_assignment")).scalar() or 0)
        finally:
            engine.dispose()
    except Exception:  # noqa: BLE001 - unreadable: the grading run reports it later
        return 0


def strip_hidden(source: str) -> str:
    """A test cell's source without its hidden tests (replaced by a one-line note)."""
    return _HIDDEN.sub(HIDDEN_NOTE, source)


def gradebook_knows(db_url: str, sources: list[SourceNotebook]) -> bool:
    """Whether the gradebook already holds the assignment with every grade cell of ``sources``
    (a SQLite file that does not exist is not created to ask: ``prepare_course`` then knows
    the course root is fresh)."""
    from nbgrader.api import Gradebook, MissingEntry

    if db_url.startswith("sqlite:///") and not Path(db_url[len("sqlite:///"):]).is_file():
        return False
    try:
        with Gradebook(db_url, course_id=COURSE_ID) as gb:
            try:
                gb.find_assignment(ASSIGNMENT)
            except MissingEntry:
                return False
            for src in sources:
                for gid in [g.test_id for g in src.graded] + [m[0] for m in src.manual]:
                    try:
                        gb.find_grade_cell(gid, src.name, ASSIGNMENT)
                    except MissingEntry:
                        return False
    except Exception:  # noqa: BLE001 - an empty or foreign database: (re)create the course
        return False
    return True


def ensure_course(root: Path, db_url: str, sources: list[SourceNotebook]) -> None:
    """Register the assignment and its cells in the gradebook (``nbgrader generate_assignment``)."""
    if gradebook_knows(db_url, sources):
        return
    try:
        from ..course import prepare_course

        prepare_course(root, db_url=db_url, notebooks=[s.path for s in sources])
    except Exception as exc:  # noqa: BLE001 - e.g. a source notebook nbgrader cannot release
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        print(f"warning: nbgrader generate_assignment failed ({first}); registering the "
              "grade cells in the gradebook directly", file=sys.stderr)
        register_cells(db_url, sources)
    if not gradebook_knows(db_url, sources):
        raise RuntimeError("nbgrader generate_assignment ran but the gradebook still lacks "
                           "some grade cells")


def register_cells(db_url: str, sources: list[SourceNotebook]) -> None:
    """Record the assignment's cells in the gradebook the way ``generate_assignment`` does
    (nbgrader's own ``ComputeChecksums`` and ``SaveCells`` preprocessors), without releasing."""
    import nbformat
    from nbgrader.api import Gradebook
    from nbgrader.preprocessors import ComputeChecksums, SaveCells

    with Gradebook(db_url, course_id=COURSE_ID) as gb:
        gb.update_or_create_assignment(ASSIGNMENT)
    for src in sources:
        nb = nbformat.read(str(src.path), as_version=4)
        resources = {"nbgrader": {"db_url": db_url, "assignment": ASSIGNMENT,
                                  "notebook": src.name}}
        nb, resources = ComputeChecksums().preprocess(nb, resources)
        SaveCells().preprocess(nb, resources)


def sync(batch: Batch, sources: list[SourceNotebook], submitted: Path, out: Path,
         db_url: str | None = None) -> Path:
    """Write every score of ``batch`` to the gradebook and the autograded notebooks.

    Returns the course root used. Idempotent: re-running with the same batch changes nothing.
    """
    from nbgrader.api import Gradebook, MissingEntry

    root = course_root(submitted, out)
    db_url = db_url or default_db_url(root)
    ensure_course(root, db_url, sources)
    by_student: dict[str, list[CellResult]] = {}
    for r in batch.results:
        by_student.setdefault(r.student, []).append(r)
    with warnings.catch_warnings(), Gradebook(db_url, course_id=COURSE_ID) as gb:
        # nbgrader's own add_submission triggers harmless SQLAlchemy autoflush warnings
        warnings.simplefilter("ignore")
        known = {s.id for s in gb.students}
        for student in batch.students:
            if student not in known:
                gb.add_student(student)
            timestamp = _timestamp(Path(submitted) / student / ASSIGNMENT)
            if timestamp is None:
                _warn_no_time(student, Path(submitted) / student / ASSIGNMENT)
            try:
                sub = gb.find_submission(ASSIGNMENT, student)
                if timestamp is not None:
                    sub.timestamp = timestamp
            except MissingEntry:
                kwargs = {"timestamp": timestamp} if timestamp is not None else {}
                sub = gb.add_submission(ASSIGNMENT, student, **kwargs)
            grades = {(nb.name, g.name): g for nb in sub.notebooks for g in nb.grades}
            for r in by_student.get(student, []):
                grade = grades.get((r.notebook, r.grade_id))
                if grade is None:
                    continue
                set_automatic_score(grade, r)
        gb.db.commit()
    for student in batch.students:
        _write_autograded(batch, sources, student, by_student.get(student, []),
                          root / "autograded" / student / ASSIGNMENT, Path(submitted))
    return root


def _write_autograded(batch: Batch, sources: list[SourceNotebook], student: str,
                      rows: list[CellResult], folder: Path, submitted: Path) -> None:
    """One student's autograded notebooks; a notebook that cannot be written is reported on
    stderr and never stops the others (nor the other students')."""
    folder.mkdir(parents=True, exist_ok=True)
    for name in CARRIED_FILES:
        kept = submitted / student / ASSIGNMENT / name
        if kept.is_file() and not kept.is_symlink():
            shutil.copyfile(kept, folder / name)
    results: dict[str, dict[str, CellResult]] = {}
    for r in rows:
        results.setdefault(r.notebook, {})[r.grade_id] = r
    for src in sources:
        sub = batch.submissions.get((student, src.name))
        if sub is None:
            continue
        try:
            nb = autograded_notebook(src, sub, results.get(src.name, {}))
            with open(folder / f"{src.name}.ipynb", "w", encoding="utf-8",
                      errors="replace") as f:
                json.dump(nb, f, indent=1, ensure_ascii=False)
                f.write("\n")
        except Exception:  # noqa: BLE001 - one bad notebook never stops the others
            traceback.print_exc()
            print(f"error: the autograded notebook {student}/{src.name} could not be written",
                  file=sys.stderr)


def set_automatic_score(grade, r: CellResult) -> None:
    """Set what the grader decides of one nbgrader ``Grade`` and nothing a marker decided.

    Only ``auto_score`` changes. ``manual_score``, comments and extra credit are never touched,
    and a cell is flagged "needs manual grade" only when it is a written answer that nobody has
    marked yet: an answer a marker scored stays marked through any number of re-grades, and a
    blank or missing answer scores 0 with no marker (as nbgrader scores an unchanged answer).
    """
    if r.kind is CellKind.MANUAL:
        grade.auto_score = None if r.status is Status.MANUAL else 0.0
        grade.needs_manual_grade = r.status is Status.MANUAL and grade.manual_score is None
    else:
        grade.auto_score = float(r.score or 0.0)
        grade.needs_manual_grade = False


def _warn_no_time(student: str, folder: Path) -> None:
    """Say, naming the student, that a submission has no hand-in time the late rules can use
    (a folder put in ``submitted/`` by hand rather than by ``nbgrader collect`` or the service:
    ``export`` then never counts it late)."""
    ts = folder / "timestamp.txt"
    why = ("has an unreadable timestamp.txt" if ts.is_file() and not ts.is_symlink()
           else "has no timestamp.txt")
    print(f"warning: {student}'s submission ({folder}) {why}: the gradebook records no hand-in "
          "time for it (an earlier one, if any, is kept), so `export` never counts it late; "
          f"write its time, e.g. `{_EXAMPLE_STAMP}`, to {ts} and grade again to apply the late "
          "rules", file=sys.stderr)


#: a hand-in time as nbgrader writes it in ``timestamp.txt``
_EXAMPLE_STAMP = "2026-03-13 15:59:00.000000 UTC"


def _timestamp(folder: Path):
    ts = folder / "timestamp.txt"
    if not ts.is_file() or ts.is_symlink():
        return None
    try:
        from nbgrader.utils import parse_utc

        return parse_utc(ts.read_text(encoding="utf-8")[:100].strip())
    except Exception:  # noqa: BLE001 - a garbled timestamp is simply not recorded
        return None


# --------------------------------------------------------------------------------------------
# the autograded notebook


def _source_cell_json(src: SourceNotebook, index: int) -> dict:
    return copy.deepcopy(src.nb["cells"][index])


def _is_trusted(meta: dict) -> bool:
    """Cells the student may not change: locked cells and auto-graded test cells."""
    return bool(meta.get("locked")) or cell_role(meta) is CellRole.TESTS


def _clean(cell: dict) -> dict:
    cell = copy.deepcopy(cell)
    cell.setdefault("metadata", {})
    if not isinstance(cell["metadata"], dict):
        cell["metadata"] = {}
    if cell.get("cell_type") == "code":
        cell["outputs"] = []
        cell["execution_count"] = None
    else:
        cell.pop("outputs", None)
        cell.pop("execution_count", None)
    if isinstance(cell.get("source"), list):
        cell["source"] = join_source(cell["source"])
    cell.pop("id", None)
    return cell


def _verdict_output(r: CellResult) -> dict:
    score = "-" if r.score is None else f"{r.score:g}"
    text = f"autograder: {score} / {r.max_score:g} [{r.status.value}] {printable(r.message)}\n"
    if r.kind is CellKind.CHOICE:
        answer = r.cases[0].received if r.cases else None
        legend = choice_legend(r.name, r.student, answer)
        text += f"{printable(legend)}\n" if legend else ""
    return {"output_type": "stream", "name": "stdout", "text": text}


def autograded_notebook(src: SourceNotebook, sub: Submission,
                        results: dict[str, CellResult]) -> dict:
    """The notebook formgrader shows for one submission (see the module docstring)."""
    if sub.status is not Status.OK or sub.nb is None:
        cells = [{"cell_type": "markdown", "metadata": {},
                  "source": f"**Not graded automatically:** {sub.message}"}]
        for c in src.nb["cells"]:
            c = _clean(c)
            role = cell_role(c["metadata"].get("nbgrader", {}))
            if role.by_student:
                c["source"] = ("*(not submitted)*" if c["cell_type"] == "markdown"
                               else "# (not submitted)\n")
            elif role is CellRole.TESTS and c["cell_type"] == "code":
                c["source"] = strip_hidden(c["source"])
            cells.append(c)
    else:
        cells = _merge(src, sub)
    cells = with_rubrics(cells, src)
    seen_ids: set[str] = set()
    for k, c in enumerate(cells):
        gid = (c.get("metadata", {}).get("nbgrader") or {}).get("grade_id")
        if gid in results and c.get("cell_type") == "code" and results[gid].kind is not CellKind.MANUAL:
            c["outputs"] = [_verdict_output(results[gid])]
        # nbformat 4.5 wants a unique id per cell: the grade_id where there is one
        cid = re.sub(r"[^A-Za-z0-9_-]", "-", gid)[:64] if gid else f"cell-{k}"
        while cid in seen_ids:
            cid = f"{cid[:56]}-{k}"
        seen_ids.add(cid)
        c["id"] = cid
    return {"cells": cells, "metadata": copy.deepcopy(src.nb.get("metadata", {})),
            "nbformat": 4, "nbformat_minor": 5}


def rubric_cell(src: SourceNotebook, grade_id: str) -> dict:
    """A markdown cell with the model answer and rubric of a written answer, for the marker.

    It carries no nbgrader metadata (nothing to grade) and is tagged ``RUBRIC_KEY`` in its
    metadata so that the hand-back (:mod:`.handback`) can drop it: students never see it.
    """
    scell = src.cell(grade_id)
    text = scell.source if scell is not None else ""
    return {"cell_type": "markdown", "metadata": {RUBRIC_KEY: {"for": grade_id}},
            "source": (f"**For the marker of `{grade_id}` (never handed back): model answer "
                       f"and rubric, from the source notebook**\n\n{text}")}


def with_rubrics(cells: list[dict], src: SourceNotebook) -> list[dict]:
    """``cells`` with a :func:`rubric_cell` right after each written answer cell."""
    manual = {gid for gid, _ in src.manual}
    out = []
    for cell in cells:
        if (cell.get("metadata") or {}).get(RUBRIC_KEY):
            continue
        out.append(cell)
        gid = ((cell.get("metadata") or {}).get("nbgrader") or {}).get("grade_id")
        if gid in manual:
            out.append(rubric_cell(src, gid))
    return out


def _merge(src: SourceNotebook, sub: Submission) -> list[dict]:
    by_name = {k: name for name, k in sub.found_by_name.items()}
    last: dict[str, int] = {}
    for k, c in enumerate(sub.cells):
        if c["grade_id"]:
            last[c["grade_id"]] = k
    cells: list[dict] = []
    present: set[str] = set()
    for k, c in enumerate(sub.cells):
        cell = _clean(c["raw"])
        # the student's grading metadata is never kept: a cell matched to the course's gets the
        # source's below (a dict grade_id broke the writer; a null one drew a fake answer panel)
        cell["metadata"].pop("nbgrader", None)
        gid = c["grade_id"]
        scell = src.cell(gid) if gid else None
        if gid and last[gid] != k:
            pass                                         # an earlier duplicate: a plain cell
        elif scell is not None and _is_trusted(scell.meta):
            cell = _clean(_source_cell_json(src, scell.index))
            if cell["cell_type"] == "code":
                cell["source"] = strip_hidden(cell["source"])
            present.add(gid)
        elif scell is not None:
            cell["metadata"]["nbgrader"] = copy.deepcopy(scell.meta)
            cell["cell_type"] = scell.cell_type if scell.cell_type in ("code", "markdown") \
                else cell["cell_type"]
            if cell["cell_type"] == "markdown":
                cell.pop("outputs", None)
                cell.pop("execution_count", None)
            present.add(gid)
        elif k in by_name and not gid:
            meta = src.cell(by_name[k])
            if meta is not None:
                cell["metadata"]["nbgrader"] = copy.deepcopy(meta.meta)
                present.add(by_name[k])
        if cell.get("cell_type") not in ("code", "markdown"):  # the course has none: never HTML
            cell = quoted_cell(cell)
        cells.append(cell)
    # re-insert the graded and trusted cells that are gone, after their source predecessor
    for scell in src.cells:
        gid = scell.meta.get("grade_id")
        if not gid or gid in present:
            continue
        new = _clean(_source_cell_json(src, scell.index))
        if cell_role(scell.meta).by_student:
            new["source"] = ("*(missing from the submission)*" if new["cell_type"] == "markdown"
                             else "# (missing from the submission)\n")
        elif new["cell_type"] == "code":
            new["source"] = strip_hidden(new["source"])
        pos = len(cells)
        prev_ids = [c.meta.get("grade_id") for c in src.cells[: scell.index]
                    if c.meta.get("grade_id")]
        for pid in reversed(prev_ids):
            idx = next((i for i, c in enumerate(cells)
                        if (c["metadata"].get("nbgrader") or {}).get("grade_id") == pid), None)
            if idx is not None:
                pos = idx + 1
                break
        else:
            pos = 0 if prev_ids == [] else len(cells)
        cells.insert(pos, new)
        present.add(gid)
    return cells
