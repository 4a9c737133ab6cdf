"""The class summary: ``OUT/report.html``.

Three things an instructor wants after a grading run, on one self-contained page (inline SVG, no
scripts, no network): the distribution of each question's automatic score (a histogram per
notebook), the tests most students failed (with how they failed), and the submissions that could
not be graded at all (missing, misnamed, unreadable notebooks) with the reason.
"""

from __future__ import annotations

import html
from collections import Counter, defaultdict
from pathlib import Path

from .grading import STATUSES, CellResult, SourceNotebook

_STYLE = """
body{font-family:system-ui,-apple-system,Segoe UI,sans-serif;max-width:1080px;margin:2em auto;
padding:0 1em;color:#222;line-height:1.4}h1{font-size:1.6em}h2{font-size:1.25em;margin-top:2em}
table{border-collapse:collapse;width:100%;font-size:.9em;margin:.5em 0}
td,th{border:1px solid #ddd;padding:.3em .5em;text-align:left;vertical-align:top}
th{background:#f5f5f5}.grid{display:flex;flex-wrap:wrap;gap:1.2em}
.card{border:1px solid #ddd;padding:.6em;border-radius:.4em}.note{color:#555;font-size:.9em}
"""


def write_report(results: list[CellResult], sources: list[SourceNotebook], path: Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(render(results, sources), encoding="utf-8")
    return path


def notebook_totals(results: list[CellResult]) -> dict[str, dict[str, tuple[float, float]]]:
    """``{notebook: {student: (auto score, auto max)}}`` over the notebooks that were read
    (a notebook that is missing or unreadable as a whole is left out of its distribution)."""
    unread = {(student, nb) for student, nb, _, _ in ungradeable(results)}
    totals: dict[str, dict[str, list[float]]] = defaultdict(lambda: defaultdict(lambda: [0.0, 0.0]))
    for r in results:
        if r.kind == "manual" or (r.student, r.notebook) in unread:
            continue
        t = totals[r.notebook][r.student]
        t[0] += r.score or 0.0
        t[1] += r.max_score
    return {nb: {s: (v[0], v[1]) for s, v in d.items()} for nb, d in totals.items()}


def most_failed(results: list[CellResult]) -> list[dict]:
    """Auto-graded tests ordered by how many students lost points on them."""
    by_test: dict[tuple[str, str], list[CellResult]] = defaultdict(list)
    for r in results:
        if r.kind != "manual" and r.status not in ("missing", "unreadable"):
            by_test[(r.notebook, r.grade_id)].append(r)
    rows = []
    for (nb, gid), rs in by_test.items():
        lost = [r for r in rs if (r.score or 0.0) < r.max_score - 1e-9]
        mean = sum((r.score or 0.0) / r.max_score for r in rs if r.max_score) / max(len(rs), 1)
        how = Counter(r.status for r in lost)
        rows.append({"notebook": nb, "grade_id": gid, "students": len(rs), "lost": len(lost),
                     "mean": mean, "how": how})
    rows.sort(key=lambda d: (-d["lost"], d["mean"], d["notebook"], d["grade_id"]))
    return rows


def ungradeable(results: list[CellResult]) -> list[tuple[str, str, str, str]]:
    """``(student, notebook, status, message)`` of notebooks that could not be graded."""
    seen = {}
    for r in results:
        whole_notebook = "could not be graded" in r.message or "was submitted" in r.message
        if r.status in ("missing", "unreadable") and whole_notebook \
                and (r.student, r.notebook) not in seen:
            seen[(r.student, r.notebook)] = (r.student, r.notebook, r.status, r.message)
    # unreadable files first (something to chase), then missing notebooks
    return sorted(seen.values(), key=lambda t: (t[2] != "unreadable", t[0], t[1]))


def render(results: list[CellResult], sources: list[SourceNotebook]) -> str:
    students = sorted({r.student for r in results})
    totals = notebook_totals(results)
    out = ["<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
           "<title>tripos2006: grading report</title>", f"<style>{_STYLE}</style></head><body>",
           "<h1>tripos2006: grading report</h1>",
           f"<p>{len(students)} students, {len(sources)} notebooks, "
           f"{sum(r.kind != 'manual' for r in results)} automatically graded cells. Written "
           "answers are marked in formgrader and are not included here.</p>",
           "<h2>Score distribution per question</h2><div class='grid'>"]
    for src in sources:
        per = totals.get(src.name, {})
        scores = [v[0] for v in per.values()]
        top = max((v[1] for v in per.values()), default=sum(g[2] for g in src.graded))
        mean = sum(scores) / len(scores) if scores else 0.0
        out.append(f"<div class='card'><b>{_e(src.name)}</b> <span class='note'>({len(scores)} "
                   f"submitted; auto-graded out of {top:g}; mean {mean:.2f})</span><br>"
                   f"{histogram_svg(scores, top)}</div>")
    out.append("</div>")

    out.append("<h2>Most-failed tests</h2><table><tr><th>notebook</th><th>test</th>"
               "<th>students who lost points</th><th>mean score</th><th>how</th></tr>")
    for row in [r for r in most_failed(results) if r["lost"]][:15]:
        how = ", ".join(f"{n} {s}" for s, n in row["how"].most_common())
        out.append(f"<tr><td>{_e(row['notebook'])}</td><td>{_e(row['grade_id'])}</td>"
                   f"<td>{row['lost']} of {row['students']}</td><td>{row['mean']:.0%}</td>"
                   f"<td>{_e(how)}</td></tr>")
    out.append("</table>")

    broken = [r for r in results if r.status == "grader-error"]
    out.append(f"<h2>Grader errors ({len(broken)})</h2>")
    if broken:
        out.append("<p>The grader itself failed on these cells; the students are not to blame. "
                   "Its traceback is in the grading log: fix the cause and grade again.</p>"
                   "<table><tr><th>student</th><th>notebook</th><th>test</th></tr>")
        out += [f"<tr><td>{_e(r.student)}</td><td>{_e(r.notebook)}</td>"
                f"<td>{_e(r.grade_id)}</td></tr>" for r in broken]
        out.append("</table>")
    else:
        out.append("<p>None: every cell was graded.</p>")

    bad = ungradeable(results)
    kinds = Counter(status for _, _, status, _ in bad)
    out.append(f"<h2>Submissions that could not be graded ({kinds.get('unreadable', 0)} "
               f"unreadable, {kinds.get('missing', 0)} missing)</h2>")
    if bad:
        out.append("<table><tr><th>student</th><th>notebook</th><th>status</th><th>why</th></tr>")
        for student, nb, status, msg in bad:
            out.append(f"<tr><td>{_e(student)}</td><td>{_e(nb)}</td><td>{_e(status)}</td>"
                       f"<td>{_e(msg)}</td></tr>")
        out.append("</table>")
    else:
        out.append("<p>None: every notebook was read.</p>")

    counts = Counter(r.status for r in results)
    out.append("<h2>Statuses</h2><table><tr><th>status</th><th>cells</th><th>meaning</th></tr>")
    for status, meaning in STATUSES.items():
        out.append(f"<tr><td>{_e(status)}</td><td>{counts.get(status, 0)}</td>"
                   f"<td>{_e(meaning)}</td></tr>")
    out.append("</table></body></html>")
    return "\n".join(out)


def histogram_svg(scores: list[float], top: float, bins: int = 10) -> str:
    """A small inline SVG histogram of ``scores`` on ``[0, top]``."""
    w, h, pad = 300, 150, 22
    top = top if top > 0 else 1.0
    counts = [0] * bins
    for s in scores:
        k = min(bins - 1, max(0, int(s / top * bins)))
        counts[k] += 1
    peak = max(counts) or 1
    bw = (w - 2 * pad) / bins
    bars = []
    for k, c in enumerate(counts):
        bh = (h - 2 * pad) * c / peak
        x = pad + k * bw
        bars.append(f"<rect x='{x + 1:.1f}' y='{h - pad - bh:.1f}' width='{bw - 2:.1f}' "
                    f"height='{bh:.1f}' fill='#1565c0'><title>{c} students scored "
                    f"{k * top / bins:g}–{(k + 1) * top / bins:g}</title></rect>")
        if c:
            bars.append(f"<text x='{x + bw / 2:.1f}' y='{h - pad - bh - 3:.1f}' font-size='10' "
                        f"text-anchor='middle'>{c}</text>")
    axis = (f"<line x1='{pad}' y1='{h - pad}' x2='{w - pad}' y2='{h - pad}' stroke='#444'/>"
            f"<text x='{pad}' y='{h - 6}' font-size='10'>0</text>"
            f"<text x='{w - pad}' y='{h - 6}' font-size='10' text-anchor='end'>{top:g}</text>")
    return (f"<svg width='{w}' height='{h}' viewBox='0 0 {w} {h}' role='img' "
            f"aria-label='histogram of {len(scores)} scores'>{''.join(bars)}{axis}</svg>")


def _e(text) -> str:
    return html.escape(str(text), quote=True)
