"""Per-student feedback: ``OUT/feedback/<student>/<notebook>.html``.

What a student sees, per graded name: the score and a sentence saying why; every *visible* case
in full (its inputs, the expected and the received value, what was wrong); for *hidden* cases only
how many failed and how (wrong value, wrong shape, error, timeout...): no inputs, no exception
text, nothing they printed. With ``--reveal-hidden`` (after the deadline) the failing hidden cases
are shown in full too. Where an answer is geometric (a curve, a polygon, a mesh) a small inline
SVG draws the expected and the received answer on top of each other.

The page is built from the grader's results alone: it never reads a test cell, so the hidden
tests' code (which plain ``nbgrader generate_feedback`` shows, nbgrader #917 and #1363) cannot
leak. Choice keys are never printed; an item's explanation (the instructor's notebook's
explanation cells, :mod:`autograder.explanations`, which the release leaves out) is shown with
``--reveal-hidden``, after the due date, whatever the verdict.
"""

from __future__ import annotations

import dataclasses
import html
import re
import sys
import traceback
from pathlib import Path

import numpy as np

from .. import explanations as explanation_cells
from ..course import source_notebooks
from ..exercises import REGISTRY
from ..model import VERDICT_WORDS, CaseRecord, CellKind, CellResult, Status, Verdict
from .html import e, e_clipped, page, plot_data, svg_lines, value_text, write_page
from .safe_markdown import markdown2html

_STYLE = """
.total{font-size:1.1em;color:#444}.msg{margin:.3em 0 .6em}
.badge{display:inline-block;padding:.05em .5em;border-radius:.8em;font-size:.85em;color:#fff}
.ok{background:#2e7d32}.failed{background:#c62828}.error{background:#8e24aa}
.timeout{background:#ef6c00}.missing,.unreadable,.unanswered{background:#616161}
.reference-used,.rejected-output,.rejected-code{background:#b71c1c}.manual{background:#1565c0}
.grader-error{background:#000}.pass{color:#2e7d32}.fail{color:#c62828}
.whose{border-left:4px solid #ef6c00;padding:.3em .8em;background:#fff3e0}
details{margin:.4em 0}svg{background:#fafafa;border:1px solid #ddd}.legend span{margin-right:1.2em}
"""
#: Characters of the student's own code shown back (counted after HTML escaping).
CODE_CHARS = 20_000
#: Characters of printed output shown (counted after HTML escaping).
PRINTED_CHARS = 5_000
#: Characters of a page, at most (a page that would be longer drops the code shown back).
PAGE_CHARS = 1_500_000
#: Characters of each message on a page that had to be slimmed.
MESSAGE_CHARS = 2_000
#: Failing hidden cases listed when revealed.
REVEAL_ROWS = 20


def course_explanations(notebooks: list[Path] | None = None) -> dict[str, dict[str, list[str]]]:
    """``{notebook: {item: [markdown, ...]}}`` from the instructor's notebooks (by default the
    course's ``notebooks/q*.ipynb``); a notebook that cannot be read gives none."""
    found = {}
    for path in notebooks if notebooks is not None else source_notebooks():
        try:
            found[Path(path).stem] = explanation_cells.of_notebook(Path(path))
        except (OSError, ValueError) as exc:
            print(f"warning: no explanations from {Path(path).name}: {exc}", file=sys.stderr)
    return found


def write_all(results: list[CellResult], folder: Path, reveal_hidden: bool = False,
              ids: dict | None = None,
              explanations: dict[str, dict[str, list[str]]] | None = None) -> list[Path]:
    """Write one page per (student, notebook) that has results; returns the files written.

    ``ids``: per (student, notebook), ``{"named": [ids the notebook names besides its
    folder's], "graded_as": the id it was judged on by the instructor's decision, or ""}``
    (:func:`autograder.grade.remedy.ids_of`): the page says so at the top.
    ``explanations`` (default: :func:`course_explanations`, read only when ``reveal_hidden``)
    are shown under their items when ``reveal_hidden``.
    """
    if reveal_hidden and explanations is None:
        explanations = course_explanations()
    by_key: dict[tuple[str, str], list[CellResult]] = {}
    for r in results:
        by_key.setdefault((r.student, r.notebook), []).append(r)
    written = []
    for (student, notebook), rows in sorted(by_key.items()):
        path = Path(folder) / student / f"{notebook}.html"
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            write_page(path, render(student, notebook, rows, reveal_hidden,
                                    (explanations or {}).get(notebook, {}),
                                    whose=(ids or {}).get((student, notebook))))
        except Exception:  # noqa: BLE001 - one bad page never stops the others
            traceback.print_exc()
            print(f"error: the feedback of {student}/{notebook} could not be written",
                  file=sys.stderr)
            continue
        written.append(path)
    return written


def render(student: str, notebook: str, rows: list[CellResult], reveal_hidden: bool,
           explanations: dict[str, list[str]] | None = None,
           whose: dict | None = None) -> str:
    """The feedback page of one student's notebook, under :data:`PAGE_CHARS` whatever the
    submission: a page that would be longer is drawn again without the code and output shown
    back, and with each message cut to :data:`MESSAGE_CHARS`. With ``reveal_hidden`` each item
    named in ``explanations`` is followed by its explanation."""
    shown = explanations if reveal_hidden else None
    text = _render(student, notebook, rows, reveal_hidden, explanations=shown, whose=whose)
    if len(text) <= PAGE_CHARS:
        return text
    slim = [dataclasses.replace(r, code="", printed="", message=r.message[:MESSAGE_CHARS])
            for r in rows]
    return _render(student, notebook, slim, reveal_hidden, note=(
        "This page would have been too long: your code and its printed output are not shown."),
        explanations=shown, whose=whose)


def _render(student: str, notebook: str, rows: list[CellResult], reveal_hidden: bool,
            note: str = "", explanations: dict[str, list[str]] | None = None,
            whose: dict | None = None) -> str:
    auto = [r for r in rows if r.kind is not CellKind.MANUAL]
    manual = [r for r in rows if r.kind is CellKind.MANUAL]
    got = sum(r.score or 0.0 for r in auto)
    total = (f"<p class='total'>{e(student)}: automatically graded <b>{round(got, 2):g} / "
             f"{sum(r.max_score for r in auto):g}</b>")
    if manual:
        total += (f"; written answers ({sum(r.max_score for r in manual):g} marks) are marked by "
                  "hand")
    body = [f"<h1>{e(notebook)}</h1>", total + "</p>"]
    if whose:
        body.append(f"<p class='whose'>{e(whose_text(student, whose))}</p>")
    if note:
        body.append(f"<p class='note'>{e(note)}</p>")
    if reveal_hidden:
        body.append("<p class='note'>The failing hidden cases are shown in full (released after "
                    "the deadline).</p>")
    body += [_cell_html(r, reveal_hidden) + _explanation_html(r, explanations) for r in rows]
    return page(f"{notebook}: feedback for {student}", body, _STYLE)


def _cell_html(r: CellResult, reveal: bool) -> str:
    if r.kind is CellKind.MANUAL:
        return "\n".join([_written_head(r)] + _outputs(r))
    score = "–" if r.score is None else f"{round(r.score, 2):g}"
    # a number item is practice: checked and explained, worth no marks
    mark = "practice, no marks" if r.max_score == 0 else f"{score} / {r.max_score:g}"
    parts = [f"<h2>{e(r.name)} <span class='badge {e(r.status.value)}'>{e(r.status.value)}"
             f"</span> <small>{mark}</small></h2>",
             f"<p class='msg'>{e(r.message)}</p>"]
    if r.kind is CellKind.FUNCTION and r.cases:
        parts += _visible_html([c for c in r.cases if c.visible], _up_to(r.name))
        parts += _hidden_html([c for c in r.cases if not c.visible], reveal)
    elif (r.kind in (CellKind.CHOICE, CellKind.VALUE) and reveal and r.cases
          and r.cases[0].verdict is not Verdict.PASS):
        parts.append("<p class='note'>Its explanation follows; see the model answer in the "
                     "released solutions.</p>")
    return "\n".join(parts + _outputs(r))


def whose_text(student: str, whose: dict) -> str:
    """What the page says when the notebook names another id than the one it was handed in
    under (only the ids the student typed: nothing about anyone's answers or keys)."""
    if whose.get("graded_as"):
        return (f"Graded on the numbers and option letters of {whose['graded_as']}, the id this "
                f"notebook was worked for, as your instructor decided (handed in as {student}).")
    named = ", ".join(whose.get("named") or [])
    return (f"Check your student id: this notebook names {named} (its STUDENT_ID cell or a "
            f"saved output), but it was handed in as {student}. It is graded on the numbers "
            f"and option letters of {student}, the id it was handed in under: set STUDENT_ID = "
            f"\"{student}\" in the id cell, run the notebook again, and check your answers to "
            "the 'your numbers' and multiple-choice items before you hand in again.")


#: One written answer's heading, as :func:`with_marks` finds it again in a written page.
_WRITTEN = re.compile(r"<div class='written' data-grade-id='([^']*)'>.*?</div><!--/written-->",
                      re.S)


def _written_head(r: CellResult) -> str:
    """A written answer's heading: waiting for its marker, or 0 when left blank.

    The grader gives a written answer no mark of its own, so the page says who does; the
    hand-back (:func:`with_marks`) puts the marker's mark in its place, so one page never
    shows a mark in its table and "not marked" below it.
    """
    if r.status is Status.MANUAL:
        badge, mark, msg = "marked by hand", f"out of {r.max_score:g}", r.message
    else:
        badge, mark = r.status.value, f"{round(r.score or 0.0, 2):g} / {r.max_score:g}"
        msg = r.message
    return _written_div(r.name, badge, r.status.value, mark, msg)


def _written_div(grade_id: str, badge: str, css: str, mark: str, msg: str) -> str:
    return (f"<div class='written' data-grade-id='{e(grade_id)}'><h2>{e(grade_id)} (written "
            f"answer) <span class='badge {e(css)}'>{e(badge)}</span> <small>{e(mark)}</small>"
            f"</h2><p class='msg'>{e(msg)}</p></div><!--/written-->")


def with_marks(page_html: str, marks: dict[str, tuple[float, float, bool]]) -> str:
    """A grader's page with each written answer's heading showing the gradebook's mark.

    ``marks``: ``{grade_id: (score, max_score, marked)}``. An answer still waiting for its
    marker says so; one marked shows its mark (the comment is in the hand-back's table).
    """
    def head(match: re.Match) -> str:
        gid = html.unescape(match.group(1))
        if gid not in marks:
            return match.group(0)
        score, max_score, marked = marks[gid]
        if "<span class='badge unanswered'>" in match.group(0) and marked and score == 0:
            return match.group(0)                 # left blank: 0, with the grader's reason
        if not marked:
            return _written_div(gid, "not marked yet", "manual", f"out of {max_score:g}",
                                "A marker has not marked this answer yet.")
        return _written_div(gid, "marked", "ok", f"{round(score, 2):g} / {max_score:g}",
                            "Marked by hand: the marker's comment is in the table above.")

    return _WRITTEN.sub(head, page_html)


def _explanation_html(r: CellResult, explanations: dict[str, list[str]] | None) -> str:
    """Item ``r``'s explanation (the instructor's markdown, rendered and sanitised)."""
    if not explanations or not explanations.get(r.name):
        return ""
    text = "\n\n".join(explanations[r.name])
    return ("\n<details class='explanation' open><summary>explanation of this item</summary>"
            f"{markdown2html({}, text)}</details>")


def _up_to(name: str) -> str | None:
    """What the graded name's comparison rule ignores (its registry entry's own wording)."""
    exercise = REGISTRY.get(name)
    return exercise.compared_up_to if exercise is not None else None


def _visible_html(visible: list[CaseRecord], up_to: str | None = None) -> list[str]:
    """The visible cases' table; under it, for a rule that ignores an order, what it ignores
    (a passed answer may list the expected items in another order)."""
    if not visible:
        return []
    parts = ["<table><tr><th>visible case</th><th>input</th><th>expected</th>"
             "<th>your answer</th><th>result</th></tr>"]
    parts += [_case_row(c) for c in visible] + ["</table>"]
    if up_to:
        parts.append(f"<p class='note'>Your answer is compared with the expected one up to "
                     f"{e(up_to)}.</p>")
    return parts + [_plot(c) for c in visible if c.verdict is not Verdict.PASS and _plottable(c)]


def _hidden_html(hidden: list[CaseRecord], reveal: bool) -> list[str]:
    if not hidden:
        return []
    failed = [c for c in hidden if c.verdict is not Verdict.PASS]
    how: dict[str, int] = {}
    for c in failed:
        how[VERDICT_WORDS[c.verdict]] = how.get(VERDICT_WORDS[c.verdict], 0) + 1
    line = f"Hidden cases: {len(hidden) - len(failed)} of {len(hidden)} passed"
    if how:
        line += " (" + ", ".join(f"{n} {k}" for k, n in sorted(how.items(),
                                                               key=lambda x: -x[1])) + ")"
    parts = [f"<p>{e(line)}.</p>"]
    if reveal and failed:
        parts.append("<table><tr><th>failing hidden case</th><th>input</th><th>expected</th>"
                     "<th>your answer</th><th>result</th></tr>")
        parts += [_case_row(c) for c in failed[:REVEAL_ROWS]] + ["</table>"]
        if len(failed) > REVEAL_ROWS:
            parts.append(f"<p class='note'>… and {len(failed) - REVEAL_ROWS} more.</p>")
        parts += [_plot(c) for c in failed[:3] if _plottable(c)]
    return parts


def _outputs(r: CellResult) -> list[str]:
    parts = []
    if r.code.strip():
        what = "your answer" if r.kind is CellKind.MANUAL else "your code, as graded"
        parts.append(f"<details class='code'><summary>{what}</summary>"
                     f"<pre>{e_clipped(r.code, CODE_CHARS)}</pre></details>")
    if r.printed.strip():
        parts.append("<details><summary>printed output (not graded)</summary>"
                     f"<pre>{e_clipped(r.printed, PRINTED_CHARS)}</pre></details>")
    return parts


def _case_row(c: CaseRecord) -> str:
    args = ", ".join([value_text(a) for a in c.args]
                     + [f"{k}={value_text(v)}" for k, v in c.kwargs.items()])
    expected = f"raises {c.raises}" if c.raises else value_text(c.expected)
    if c.raises and c.verdict is Verdict.PASS:
        received = f"raised {c.raises}"
    elif not c.shown:
        received = "– (not of the expected type and shape)"
    elif c.verdict in (Verdict.PASS, Verdict.WRONG_VALUE, Verdict.WRONG_SHAPE):
        received = value_text(c.received)
    else:
        received = "–"
    res = ("<span class='pass'>passed</span>" if c.verdict is Verdict.PASS else
           f"<span class='fail'>{e(c.reason or VERDICT_WORDS[c.verdict])}</span>")
    return (f"<tr><td>{e(c.label or f'case {c.index + 1}')}</td><td><pre>{e(args)}</pre></td>"
            f"<td><pre>{e(expected)}</pre></td><td><pre>{e(received)}</pre></td>"
            f"<td>{res}</td></tr>")


# --------------------------------------------------------------------------------------------
# geometric answers: two curves, two polygons, two meshes' slices


def _as_points(v) -> np.ndarray | None:
    """An ``(m, 2)`` float array of points (homogeneous points divided by ``w``)."""
    v = plot_data(v)
    if not isinstance(v, np.ndarray) or v.ndim != 2 or v.dtype.kind != "f" or len(v) < 2:
        return None
    if v.shape[1] == 4:
        w = v[:, 3:4]
        return None if np.any(np.abs(w) < 1e-12) else v[:, :2] / w
    return v[:, :2] if v.shape[1] in (2, 3) else None


def _mesh_slice(v) -> list[np.ndarray] | None:
    """Segments where a mesh ``(verts, faces)`` meets the plane through its middle (z)."""
    if not (isinstance(v, tuple) and len(v) == 2 and isinstance(v[0], np.ndarray)
            and isinstance(v[1], np.ndarray)):
        return None
    verts, faces = v
    if verts.ndim != 2 or verts.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3 \
            or len(verts) == 0 or len(faces) == 0 or faces.dtype.kind not in "iuf":
        return None
    faces = faces.astype(int)
    if faces.min() < 0 or faces.max() >= len(verts):
        return None
    z0 = 0.5 * (verts[:, 2].min() + verts[:, 2].max()) + 1e-9
    segs = []
    for tri in verts[faces[:2000]]:
        d = tri[:, 2] - z0
        pts = [tri[i, :2] + d[i] / (d[i] - d[j]) * (tri[j, :2] - tri[i, :2])
               for i, j in ((0, 1), (1, 2), (2, 0)) if (d[i] < 0) != (d[j] < 0)]
        if len(pts) == 2:
            segs.append(np.array(pts))
    return segs


def _plottable(c: CaseRecord) -> bool:
    if c.raises or c.expected is None:
        return False
    pts = _as_points(c.expected)
    return (pts is not None and len(pts) >= 3) or _mesh_slice(c.expected) is not None


def _plot(c: CaseRecord) -> str:
    """An inline SVG of the expected (blue) and received (red, dashed) answers."""
    e_pts, r_pts = _as_points(c.expected), _as_points(c.received)
    if e_pts is not None:
        closed = plot_data(c.expected).shape[-1] == 4
        what = "polygon (x/w, y/w)" if closed else "curve (first two coordinates)"
        return svg_lines([e_pts], [r_pts] if r_pts is not None else [], closed, c.label, what)
    return svg_lines(_mesh_slice(c.expected) or [], _mesh_slice(c.received) or [], False,
                     c.label, "mesh, sliced through the middle plane z = const")
