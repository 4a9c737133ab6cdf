"""Per-student feedback: ``OUT/feedback/<student>/<notebook>.html``.

What a student sees, per graded name: the score and a sentence saying why; every *visible* case
in full (its inputs, the expected and the received value, what was wrong); for *hidden* cases only
how many failed and how (wrong value, wrong shape, error, timeout...). With ``--reveal-hidden``
(after the deadline) the failing hidden cases are shown in full too. Where an answer is
geometric (a curve, a polygon, a mesh) a small inline SVG draws the expected and the received
answer on top of each other (a mesh as its slice through the middle plane).

The page is built from the grader's results alone: it never reads a test cell, so the hidden
tests' code (which plain ``nbgrader generate_feedback`` shows, nbgrader #917 and #1363) cannot
leak. Choice answers are never revealed unless ``--reveal-hidden`` is given.
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

from .grading import CaseRecord, CellResult, SourceNotebook

_STYLE = """
body{font-family:system-ui,-apple-system,Segoe UI,sans-serif;max-width:980px;margin:2em auto;
padding:0 1em;color:#222;line-height:1.45}
h1{font-size:1.5em;margin-bottom:.2em}h2{font-size:1.15em;margin:1.6em 0 .3em}
.total{font-size:1.1em;color:#444}.msg{margin:.3em 0 .6em}
.badge{display:inline-block;padding:.05em .5em;border-radius:.8em;font-size:.85em;color:#fff}
.ok{background:#2e7d32}.failed{background:#c62828}.error{background:#8e24aa}
.timeout{background:#ef6c00}.missing,.unreadable{background:#616161}
.reference-used,.rejected-output{background:#b71c1c}.manual{background:#1565c0}
table{border-collapse:collapse;width:100%;margin:.4em 0;font-size:.9em}
td,th{border:1px solid #ddd;padding:.3em .5em;vertical-align:top;text-align:left}
th{background:#f5f5f5}pre{margin:0;white-space:pre-wrap;word-break:break-word;
font-size:.9em}.pass{color:#2e7d32}.fail{color:#c62828}
details{margin:.4em 0}svg{background:#fafafa;border:1px solid #ddd}
.legend span{margin-right:1.2em}.note{color:#555;font-size:.9em}
"""

_VERDICT = {
    "pass": "passed", "wrong-value": "wrong value", "wrong-shape": "wrong shape or type",
    "error": "error", "timeout": "timed out", "rejected": "not plain numbers",
    "reference-used": "called the reference", "unanswered": "not attempted",
}


def write_all(results: list[CellResult], sources: list[SourceNotebook], folder: Path,
              reveal_hidden: bool = False) -> list[Path]:
    """Write one page per (student, notebook) that has results; returns the files written."""
    folder = Path(folder)
    by_key: dict[tuple[str, str], list[CellResult]] = {}
    for r in results:
        by_key.setdefault((r.student, r.notebook), []).append(r)
    written = []
    for (student, notebook), rows in sorted(by_key.items()):
        path = folder / student / f"{notebook}.html"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(render(student, notebook, rows, reveal_hidden), encoding="utf-8")
        written.append(path)
    return written


def render(student: str, notebook: str, rows: list[CellResult], reveal_hidden: bool) -> str:
    """The feedback page of one student's notebook."""
    auto = [r for r in rows if r.kind != "manual"]
    manual = [r for r in rows if r.kind == "manual"]
    got = sum(r.score or 0.0 for r in auto)
    out = ["<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
           f"<title>{_e(notebook)}: feedback for {_e(student)}</title>",
           f"<style>{_STYLE}</style></head><body>",
           f"<h1>{_e(notebook)}</h1>",
           f"<p class='total'>{_e(student)}: automatically graded "
           f"<b>{round(got, 2):g} / {sum(r.max_score for r in auto):g}</b>"]
    if manual:
        out.append(f"; written answers ({sum(r.max_score for r in manual):g} marks) are marked "
                   "by hand")
    out.append("</p>")
    if reveal_hidden:
        out.append("<p class='note'>The failing hidden cases are shown in full (released after "
                   "the deadline).</p>")
    for r in rows:
        out.append(_cell_html(r, reveal_hidden))
    out.append("</body></html>")
    return "\n".join(out)


def _cell_html(r: CellResult, reveal: bool) -> str:
    score = "–" if r.score is None else f"{round(r.score, 2):g}"
    title = r.name if r.kind != "manual" else f"{r.name} (written answer)"
    parts = [f"<h2>{_e(title)} <span class='badge {_e(r.status)}'>{_e(r.status)}</span> "
             f"<small>{score} / {r.max_score:g}</small></h2>",
             f"<p class='msg'>{_e(r.message)}</p>"]
    if r.kind == "choice":
        if r.cases and reveal and r.cases[0].verdict != "pass":
            parts.append("<p class='note'>See the model answer in the released solutions.</p>")
        return "\n".join(parts + _outputs(r))
    if r.kind == "manual" or not r.cases:
        return "\n".join(parts + _outputs(r))
    visible = [c for c in r.cases if c.visible]
    hidden = [c for c in r.cases if not c.visible]
    if visible:
        parts.append("<table><tr><th>visible case</th><th>input</th><th>expected</th>"
                     "<th>your answer</th><th>result</th></tr>")
        for c in visible:
            parts.append(_case_row(c))
        parts.append("</table>")
        parts += [_plot(c) for c in visible if c.verdict != "pass" and _plottable(c)]
    if hidden:
        failed = [c for c in hidden if c.verdict != "pass"]
        how: dict[str, int] = {}
        for c in failed:
            how[_VERDICT[c.verdict]] = how.get(_VERDICT[c.verdict], 0) + 1
        line = f"Hidden cases: {len(hidden) - len(failed)} of {len(hidden)} passed"
        if how:
            line += " (" + ", ".join(f"{n} {k}" for k, n in sorted(how.items(),
                                                                   key=lambda x: -x[1])) + ")"
        parts.append(f"<p>{_e(line)}.</p>")
        if reveal and failed:
            parts.append("<table><tr><th>failing hidden case</th><th>input</th><th>expected</th>"
                         "<th>your answer</th><th>result</th></tr>")
            for c in failed[:20]:
                parts.append(_case_row(c))
            parts.append("</table>")
            if len(failed) > 20:
                parts.append(f"<p class='note'>… and {len(failed) - 20} more.</p>")
            parts += [_plot(c) for c in failed[:3] if _plottable(c)]
    return "\n".join(parts + _outputs(r))


def _outputs(r: CellResult) -> list[str]:
    parts = []
    if r.code.strip():
        what = "your answer" if r.kind == "manual" else "your code, as graded"
        parts.append(f"<details class='code'><summary>{what}</summary>"
                     f"<pre>{_e(r.code[:20000])}</pre></details>")
    for label, text in (("printed output", r.stdout), ("warnings and errors printed", r.stderr)):
        if text.strip():
            parts.append(f"<details><summary>{label} (not graded)</summary>"
                         f"<pre>{_e(text[:5000])}</pre></details>")
    return parts


def _case_row(c: CaseRecord) -> str:
    args = ", ".join([_value(a) for a in c.args] + [f"{k}={_value(v)}"
                                                     for k, v in c.kwargs.items()])
    if c.raises:
        expected = f"raises {c.raises}"
    else:
        expected = _value(c.expected)
    if c.raises and c.verdict == "pass":
        received = f"raised {c.raises}"
    elif c.verdict in ("pass", "wrong-value", "wrong-shape"):
        received = _value(c.received)
    else:
        received = "–"
    res = ("<span class='pass'>passed</span>" if c.verdict == "pass" else
           f"<span class='fail'>{_e(c.reason or _VERDICT[c.verdict])}</span>")
    return (f"<tr><td>{_e(c.label or f'case {c.index + 1}')}</td><td><pre>{_e(args)}</pre></td>"
            f"<td><pre>{_e(expected)}</pre></td><td><pre>{_e(received)}</pre></td>"
            f"<td>{res}</td></tr>")


def _value(v) -> str:
    if isinstance(v, np.ndarray):
        text = np.array2string(v, precision=6, threshold=60, edgeitems=4, max_line_width=70)
        return text if v.ndim <= 1 or v.size <= 60 else f"{text}\n(shape {v.shape})"
    if isinstance(v, float):
        return f"{v:.8g}"
    if isinstance(v, tuple):
        inner = ", ".join(_value(x) for x in v)
        return f"({inner}{',' if len(v) == 1 else ''})"
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    text = repr(v)
    return text if len(text) <= 2000 else text[:2000] + "…"


def _e(text) -> str:
    return html.escape(str(text), quote=True)


# --------------------------------------------------------------------------------------------
# geometric answers: two curves, two polygons, two meshes' slices


def _as_points(v) -> np.ndarray | None:
    """An ``(m, 2..4)`` float array of points (homogeneous points divided by ``w``)."""
    if not isinstance(v, np.ndarray) or v.ndim != 2 or v.dtype.kind != "f" or len(v) < 2:
        return None
    if v.shape[1] == 4:
        w = v[:, 3:4]
        if np.any(np.abs(w) < 1e-12):
            return None
        return v[:, :2] / w
    if v.shape[1] in (2, 3):
        return v[:, :2]
    return None


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
        pts = []
        for i, j in ((0, 1), (1, 2), (2, 0)):
            if (d[i] < 0) != (d[j] < 0):
                t = d[i] / (d[i] - d[j])
                pts.append(tri[i, :2] + t * (tri[j, :2] - tri[i, :2]))
        if len(pts) == 2:
            segs.append(np.array(pts))
    return segs


def _plottable(c: CaseRecord) -> bool:
    if c.raises or c.expected is None:
        return False
    return (_as_points(c.expected) is not None and len(c.expected) >= 3) or \
        _mesh_slice(c.expected) is not None


def _plot(c: CaseRecord) -> str:
    """An inline SVG of the expected (blue) and received (red, dashed) answers."""
    e_pts, r_pts = _as_points(c.expected), _as_points(c.received)
    closed = isinstance(c.expected, np.ndarray) and c.expected.shape[-1] == 4
    if e_pts is not None:
        e_lines, r_lines = [e_pts], ([r_pts] if r_pts is not None else [])
        what = "polygon (x/w, y/w)" if closed else "curve (first two coordinates)"
    else:
        e_lines = _mesh_slice(c.expected) or []
        r_lines = _mesh_slice(c.received) or []
        closed = False
        what = "mesh, sliced through the middle plane z = const"
    allpts = [p for p in e_lines + r_lines if len(p)]
    if not allpts:
        return ""
    xy = np.vstack(allpts)
    if not np.all(np.isfinite(xy)):
        xy = xy[np.all(np.isfinite(xy), axis=1)]
        if not len(xy):
            return ""
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    span = max(float(np.max(hi - lo)), 1e-9)
    size, pad = 320.0, 14.0

    def tx(p):
        q = (p - lo) / span * (size - 2 * pad) + pad
        return q[:, 0], size - q[:, 1]

    def path(pts, style):
        pts = pts[np.all(np.isfinite(pts), axis=1)]
        if len(pts) < 2:
            return ""
        x, y = tx(pts)
        d = " ".join(f"{a:.1f},{b:.1f}" for a, b in zip(x, y, strict=True))
        tag = "polygon" if closed else "polyline"
        return f"<{tag} points='{d}' fill='none' {style}/>"

    blue = "stroke='#1565c0' stroke-width='2.2'"
    red = "stroke='#c62828' stroke-width='1.6' stroke-dasharray='5,3'"
    body = "".join(path(p, blue) for p in e_lines) + "".join(path(p, red) for p in r_lines)
    return (f"<div><svg width='{size:.0f}' height='{size:.0f}' viewBox='0 0 {size:.0f} "
            f"{size:.0f}' role='img' aria-label='expected and received {what}'>{body}</svg>"
            f"<div class='legend note'><span style='color:#1565c0'>━ expected</span>"
            f"<span style='color:#c62828'>╍ your answer</span> {_e(c.label)}: {what}</div></div>")
