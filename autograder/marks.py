"""A notebook's marks as its cells' nbgrader ``points`` give them, and as its text states them.

A mark is stated in three places a reader sees: the intro table (one row per exam part), the
part's header (``## Part (a) — ... [40%, 8 marks]``) and the cell's nbgrader ``points``, which
is the one that counts. Only ``points`` is the fact; :func:`problems` says where the text
disagrees with it, so moving a mark is one edit of metadata and a test names the prose to
follow (``tests/notebooks/test_marks.py``; ``python -m autograder facts`` prints the marks).

Reads the notebook's JSON with the standard library only (no nbformat: it costs seconds of CPU
per process, see ``fast_start``).
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from pathlib import Path

from .cells import CellRole, cell_role, join_source

#: A part's label as the notebooks write it: "(a)", "(c)(ii)".
_LABEL = r"\([a-z]\)(?:\([ivx]+\))?"
#: A part's header: a level-2 or -3 heading naming the part and its marks, in any of the
#: notebooks' wordings ("## Part (a) — ... [40%, 8 marks]", "### (b)(i) ... *[20 % — 4 marks]*").
_HEADER = re.compile(rf"^#{{2,3}} (?:Part )?(?P<label>{_LABEL})\s.*?"
                     r"(?:(?P<pct>\d+) ?%[^\]\d]*)?(?P<marks>\d+) marks?\]\*?\s*$")
#: A heading that ends the part above it without starting one ("## Going further", "## Explore").
_OTHER_H2 = re.compile(r"^## ")
#: A row of the intro table: "| (a) | what it asks | ... | marks here |".
_ROW = re.compile(rf"^\|\s*(?P<label>{_LABEL})\s*\|(?P<rest>.*)\|\s*$")
#: An intro sentence "(a) 35 % = 7 marks" (q2, q6).
_SENTENCE = re.compile(rf"(?P<label>{_LABEL}) (?P<pct>\d+) ?% = (?P<marks>\d+) marks")
#: A number as the notebooks write marks: "1", "2½", "½", "1.5".
_NUMBER = re.compile(r"\d+(?:\.\d+)?½?|½")
#: A prompt's marks: "*[1 mark]*", "*[½ + 1½ marks]*", "*[5 marks, marked by hand]*",
#: "*[practice, no marks: ...]*" (a practice item's, which covers 0-point cells only).
_PROMPT = re.compile(r"\[(?P<terms>[^\]\[]*?)\bmarks?\b[^\]]*\]")


def number(text: str) -> float:
    """"2½" → 2.5, "½" → 0.5, "3" → 3.0."""
    whole, half = text.rstrip("½"), text.endswith("½")
    return (float(whole) if whole else 0.0) + (0.5 if half else 0.0)


def table_marks(cell_text: str) -> float:
    """The marks a table's last column states: its leading number ("8 (4 multiple choice × ½
    + 6 written)" → 8), or the sum of its terms ("1 choice + 1½ written + 1½ code (`f`); your
    own numbers: practice" → 4); what is in brackets or after ";" is detail, not a term."""
    outer = re.sub(r"\([^)]*\)", "", cell_text).split(";")[0]
    return sum(number(n) for n in _NUMBER.findall(outer))


@dataclass
class Part:
    """One exam part of a notebook: what its header states and what its cells carry."""

    label: str
    header_marks: float
    header_percent: float | None
    #: grade_id → points of every graded cell below the header, up to the next part
    cells: dict[str, float] = field(default_factory=dict)

    @property
    def points(self) -> float:
        return sum(self.cells.values())


@dataclass
class NotebookMarks:
    """What a notebook's text and metadata say about its marks."""

    name: str
    parts: list[Part]
    #: label → marks of the intro table's rows, and of an intro sentence "(a) 35 % = 7 marks"
    table: dict[str, float]
    sentence: dict[str, tuple[float, float]]
    #: graded cells above the first part header or below the last part ("Going further")
    outside: dict[str, float]
    #: every graded cell's points, in notebook order
    points: dict[str, float]
    #: the prompts' marks: (what the prompt says, its marks, {grade_id: points} it covers)
    prompts: list[Prompt] = field(default_factory=list)
    #: graded cells that earn points under no prompt stating them
    unprompted: dict[str, float] = field(default_factory=dict)


@dataclass
class Prompt:
    """A prompt's "[N marks]" and the graded cells below it, up to the next prompt or part."""

    text: str
    marks: float
    practice: bool
    cells: dict[str, float] = field(default_factory=dict)


def read_cells(path: Path) -> list[dict]:
    """The cells of a notebook file; ``ValueError`` naming the file when it is not one."""
    try:
        cells = json.loads(Path(path).read_text(encoding="utf-8"))["cells"]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise ValueError(f"{path}: not a readable notebook ({exc})") from None
    if not isinstance(cells, list):
        raise ValueError(f"{path}: 'cells' is not a list")
    return cells


def graded_points(cell: dict) -> tuple[str, float] | None:
    """``(grade_id, points)`` of a cell that earns points (tests or manual), else ``None``."""
    meta = cell.get("metadata", {}).get("nbgrader")
    if cell_role(meta) not in (CellRole.TESTS, CellRole.MANUAL):
        return None
    return str(meta.get("grade_id")), float(meta.get("points", 0) or 0)


def _intro(cells: list[dict]) -> tuple[dict[str, float], dict[str, tuple[float, float]]]:
    """The intro table's marks and the intro sentence's ``(percent, marks)``, by part label,
    from the markdown cells above the first code cell."""
    table, sentence = {}, {}
    for cell in cells:
        if cell.get("cell_type") == "code":
            break
        text = join_source(cell.get("source"))
        for line in text.splitlines():
            row = _ROW.match(line.strip())
            if row:
                table[row["label"]] = table_marks(row["rest"].split("|")[-1])
        for m in _SENTENCE.finditer(" ".join(text.split())):
            sentence[m["label"]] = (float(m["pct"]), float(m["marks"]))
    return table, sentence


def notebook_marks(path: Path) -> NotebookMarks:
    """Read one notebook's parts, intro table and graded cells (see :class:`NotebookMarks`)."""
    cells = read_cells(path)
    parts: list[Part] = []
    current: Part | None = None
    outside, points = {}, {}
    for cell in cells:
        if cell.get("cell_type") == "markdown":
            for line in join_source(cell.get("source")).splitlines():
                header = _HEADER.match(line)
                if header:
                    pct = header["pct"]
                    current = Part(header["label"], float(header["marks"]),
                                   float(pct) if pct else None)
                    parts.append(current)
                elif _OTHER_H2.match(line):
                    current = None
        graded = graded_points(cell)
        if graded:
            gid, pts = graded
            points[gid] = pts
            (current.cells if current else outside)[gid] = pts
    table, sentence = _intro(cells)
    found, unprompted = _prompts(cells)
    return NotebookMarks(Path(path).stem, parts, table, sentence, outside, points, found,
                         unprompted)


def _prompt_in(text: str) -> Prompt | None:
    """The first "[N marks]" of a markdown cell that is not a part header, as a prompt."""
    for line in text.splitlines():
        m = None if _HEADER.match(line) else _PROMPT.search(line)
        if m:
            terms = m["terms"]
            practice = "practice" in terms or re.search(r"\bno\b", terms) is not None
            marks = 0.0 if practice else sum(number(n) for n in _NUMBER.findall(terms))
            return Prompt(m[0], marks, practice)
    return None


def _prompts(cells: list[dict]) -> tuple[list[Prompt], dict[str, float]]:
    """Each prompt with the graded cells it covers, and the cells no prompt covers.

    A prompt covers the graded cells below it up to the next prompt or part header; a practice
    prompt ("no marks") only the 0-point cells right below it, so that a function's cells
    after a practice item still count under the prompt above (q1's "Your three functions")."""
    found, unprompted = [], {}
    current: Prompt | None = None
    before_practice: Prompt | None = None
    for cell in cells:
        graded = graded_points(cell)
        if graded:
            gid, pts = graded
            if current is not None and current.practice and pts > 0:
                current = before_practice
            (current.cells if current else unprompted)[gid] = pts
            continue
        if cell.get("cell_type") != "markdown":
            continue
        text = join_source(cell.get("source"))
        if any(_HEADER.match(line) or _OTHER_H2.match(line) for line in text.splitlines()):
            current = None
        prompt = _prompt_in(text)
        if prompt:
            before_practice = current if prompt.practice else None
            current = prompt
            found.append(prompt)
    return found, {g: p for g, p in unprompted.items() if p > 0}


def problems(marks: NotebookMarks, total: float) -> list[str]:
    """Every place the notebook's text disagrees with its cells' points (empty: all agree).

    ``total`` is the notebook's worth (the course's 20 marks); a part's percentage is of it."""
    out, name = [], marks.name
    if not marks.parts:
        out.append(f"{name}: no part header of the form '## Part (a) — ... [N marks]'")
    if marks.outside:
        out.append(f"{name}: graded cells outside every part: {sorted(marks.outside)}")
    if abs(sum(marks.points.values()) - total) > 1e-9:
        out.append(f"{name}: the cells' points add up to {sum(marks.points.values()):g}, "
                   f"not {total:g}")
    for part in marks.parts:
        where = f"{name} part {part.label}"
        if abs(part.points - part.header_marks) > 1e-9:
            out.append(f"{where}: the header says {part.header_marks:g} marks, its cells carry "
                       f"{part.points:g} ({_listed(part.cells)})")
        if part.header_percent is not None and \
                abs(part.header_percent / 100 * total - part.header_marks) > 1e-9:
            out.append(f"{where}: the header's {part.header_percent:g}% of {total:g} is not "
                       f"{part.header_marks:g} marks")
        out += _stated_elsewhere(marks, part, where)
    for prompt in marks.prompts:
        if abs(prompt.marks - sum(prompt.cells.values())) > 1e-9 and \
                (prompt.cells or not prompt.practice):
            out.append(f"{name}: the prompt's {prompt.text!r} covers cells carrying "
                       f"{sum(prompt.cells.values()):g} ({_listed(prompt.cells) or 'none'})")
    if marks.unprompted:
        out.append(f"{name}: graded cells under no prompt stating their marks (e.g. "
                   f"'*[1 mark]*'): {_listed(marks.unprompted)}")
    labels = [p.label for p in marks.parts]
    if sorted(marks.table) and sorted(marks.table) != sorted(labels):
        out.append(f"{name}: the intro table's parts {sorted(marks.table)} are not the "
                   f"headers' {sorted(labels)}")
    if not marks.table and not marks.sentence:
        out.append(f"{name}: no intro table of the parts' marks")
    return out


def _stated_elsewhere(marks: NotebookMarks, part: Part, where: str) -> list[str]:
    """The intro table's and the intro sentence's marks for ``part`` against its cells."""
    out = []
    if part.label in marks.table and abs(marks.table[part.label] - part.points) > 1e-9:
        out.append(f"{where}: the intro table says {marks.table[part.label]:g} marks, its "
                   f"cells carry {part.points:g}")
    if part.label in marks.sentence:
        pct, stated = marks.sentence[part.label]
        if abs(stated - part.points) > 1e-9 or pct != part.header_percent:
            out.append(f"{where}: the intro says {pct:g} % = {stated:g} marks, the cells "
                       f"carry {part.points:g} (header: {part.header_percent}%)")
    return out


def _listed(cells: dict[str, float]) -> str:
    return ", ".join(f"{gid} {pts:g}" for gid, pts in cells.items())


def summary(marks: NotebookMarks) -> str:
    """The notebook's marks by part, one line each, as ``new-exercise`` and ``facts`` print
    them (the cells' points: the one fact)."""
    lines = [f"{marks.name}: {sum(marks.points.values()):g} marks"]
    for part in marks.parts:
        lines.append(f"  part {part.label:<8} {part.points:>5g} marks  (header says "
                     f"{part.header_marks:g})  {_listed(part.cells)}")
    if marks.outside:
        lines.append(f"  outside every part: {_listed(marks.outside)}")
    return "\n".join(lines)
