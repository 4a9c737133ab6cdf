"""``OUT/report.html``: what an instructor wants after a grading run, on one page.

The score distribution per question (inline SVG histograms), the most-failed tests (by how many
students lost points, and how), the item analysis (:mod:`.items_html`), the submissions that
could not be graded at all, similar solutions, answers that fit another student's own numbers
and the ``--graded-as`` decisions taken on them (:mod:`.variants`), and a count of every status
with its meaning. Unanswered cells count as lost points with their own status, never as grader
failures.
"""

from __future__ import annotations

import sys
import traceback
from collections import Counter, defaultdict
from collections.abc import Mapping
from pathlib import Path

from ..course import ASSIGNMENT
from ..model import STATUS_MEANING, CellKind, CellResult, SourceNotebook, Status
from .html import e, page, write_page
from .items_html import STYLE as ITEMS_STYLE
from .items_html import section_html as items_html
from .similarity import find_pasted_references, find_similar, render_section
from .variants import graded_as_html
from .variants import section_html as own_numbers_html

_STYLE = """
.grid{display:flex;flex-wrap:wrap;gap:1.2em}.card{border:1px solid #ddd;padding:.6em;
border-radius:.4em}
"""


def write_report(results: list[CellResult], sources: list[SourceNotebook], path: Path,
                 references: Mapping[str, str] | None = None, jobs: int = 1,
                 graded_as: list[dict] | None = None) -> Path:
    """Write the report of ``results`` to ``path``.

    ``references`` (``{graded name: course_lib reference source}``) lets the "Similar
    solutions" section also flag cells that paste a reference; ``jobs`` processes fingerprint;
    ``graded_as``: the ``--graded-as`` decisions of the output folder
    (:func:`autograder.grade.remedy.decisions`), shown after "Own numbers".
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_page(path, render(results, sources, references, jobs, graded_as))
    return path


def similar_solutions_html(results: list[CellResult], references: Mapping[str, str] | None = None,
                           jobs: int = 1) -> str:
    """The "Similar solutions" section over every student's graded function cells."""
    cells: dict[str, dict[str, str]] = defaultdict(dict)
    everywhere: dict[str, dict[str, str]] = defaultdict(dict)   # every graded cell, any kind
    for r in results:
        if r.kind is not CellKind.MANUAL and r.code.strip():
            everywhere[r.student][(r.notebook, r.name)] = r.code
            if r.kind is CellKind.FUNCTION:
                cells[r.student][r.name] = r.code
    jobs = max(1, jobs)
    found = find_similar(cells, references or {}, jobs=jobs)
    seen = {(m.left, m.name) for m in found if m.is_reference}
    code = {s: [c for _, c in sorted(per.items())] for s, per in everywhere.items()}
    found += [m for m in find_pasted_references(code, references or {}, jobs=jobs)
              if (m.left, m.name) not in seen]
    return render_section(found)


def notebook_totals(results: list[CellResult]) -> dict[str, dict[str, tuple[float, float]]]:
    """``{notebook: {student: (auto score, auto max)}}`` over the notebooks that were read
    (a notebook that is missing or unreadable as a whole is left out of its distribution)."""
    totals: dict[str, dict[str, list[float]]] = defaultdict(lambda: defaultdict(lambda: [0.0, 0.0]))
    for r in results:
        if r.kind is CellKind.MANUAL or r.whole_notebook:
            continue
        t = totals[r.notebook][r.student]
        t[0] += r.score or 0.0
        t[1] += r.max_score
    return {nb: {s: (v[0], v[1]) for s, v in d.items()} for nb, d in totals.items()}


def most_failed(results: list[CellResult]) -> list[dict]:
    """Auto-graded tests ordered by how many students lost points on them."""
    by_test: dict[tuple[str, str], list[CellResult]] = defaultdict(list)
    for r in results:
        if r.kind is not CellKind.MANUAL and not r.whole_notebook:
            by_test[(r.notebook, r.grade_id)].append(r)
    rows = []
    for (nb, gid), rs in by_test.items():
        lost = [r for r in rs if (r.score or 0.0) < r.max_score - 1e-9]
        mean = sum((r.score or 0.0) / r.max_score for r in rs if r.max_score) / max(len(rs), 1)
        rows.append({"notebook": nb, "grade_id": gid, "students": len(rs), "lost": len(lost),
                     "mean": mean, "how": Counter(r.status.value for r in lost)})
    rows.sort(key=lambda d: (-d["lost"], d["mean"], d["notebook"], d["grade_id"]))
    return rows


def ungradeable(results: list[CellResult]) -> list[tuple[str, str, str, str]]:
    """``(student, notebook, status, message)`` of notebooks that could not be graded."""
    seen = {}
    for r in results:
        if r.whole_notebook and (r.student, r.notebook) not in seen:
            seen[(r.student, r.notebook)] = (r.student, r.notebook, r.status.value, r.message)
    # unreadable files first (something to chase), then missing notebooks
    return sorted(seen.values(), key=lambda t: (t[2] != Status.UNREADABLE.value, t[0], t[1]))


def render(results: list[CellResult], sources: list[SourceNotebook],
           references: Mapping[str, str] | None = None, jobs: int = 1,
           graded_as: list[dict] | None = None) -> str:
    """The report page."""
    students = sorted({r.student for r in results})
    body = ["<h1>tripos2006: grading report</h1>",
            f"<p>{len(students)} students, {len(sources)} notebooks, "
            f"{sum(r.kind is not CellKind.MANUAL for r in results)} automatically graded cells. "
            "Written answers are marked in formgrader and are not included here.</p>"]
    body += _distributions(results, sources) + _most_failed_html(results)
    body += [_section("items", "Items", items_html, results, sources)]
    body += _grader_errors_html(results) + _ungradeable_html(results)
    body += [_section("similar", "Similar solutions", similar_solutions_html, results,
                      references, jobs),
             _section("own-numbers", "Own numbers", own_numbers_html, results)]
    body += [_section("graded-as", "Graded as", graded_as_html, graded_as or [])]
    body += _statuses_html(results)
    return page(f"{ASSIGNMENT}: grading report", body, _STYLE + ITEMS_STYLE)


def _section(anchor: str, title: str, build, *args) -> str:
    """One section of the report, built by ``build(*args)``; should it fail (it reads what
    students typed and returned), the rest of the report is still written and this section
    says so."""
    try:
        return build(*args)
    except Exception as exc:  # noqa: BLE001 - one section never costs the whole page
        traceback.print_exc(limit=3)
        print(f"warning: the report's section {title!r} failed ({type(exc).__name__})",
              file=sys.stderr)
        return (f"<section id='{e(anchor)}'><h2>{e(title)}</h2><p>This section could not be "
                f"built ({e(type(exc).__name__)}); the traceback is in the grading log.</p>"
                "</section>")


def _distributions(results, sources) -> list[str]:
    totals = notebook_totals(results)
    out = ["<h2>Score distribution per question</h2><div class='grid'>"]
    for src in sources:
        per = totals.get(src.name, {})
        scores = [v[0] for v in per.values()]
        top = max((v[1] for v in per.values()), default=sum(g.points for g in src.graded))
        mean = sum(scores) / len(scores) if scores else 0.0
        out.append(f"<div class='card'><b>{e(src.name)}</b> <span class='note'>({len(scores)} "
                   f"submitted; auto-graded out of {top:g}; mean {mean:.2f})</span><br>"
                   f"{histogram_svg(scores, top)}</div>")
    return out + ["</div>"]


def _most_failed_html(results) -> list[str]:
    out = ["<h2>Most-failed tests</h2><table><tr><th>notebook</th><th>test</th>"
           "<th>students who lost points</th><th>mean score</th><th>how</th></tr>"]
    for row in [r for r in most_failed(results) if r["lost"]][:15]:
        how = ", ".join(f"{n} {s}" for s, n in row["how"].most_common())
        out.append(f"<tr><td>{e(row['notebook'])}</td><td>{e(row['grade_id'])}</td>"
                   f"<td>{row['lost']} of {row['students']}</td><td>{row['mean']:.0%}</td>"
                   f"<td>{e(how)}</td></tr>")
    return out + ["</table>"]


def _grader_errors_html(results) -> list[str]:
    broken = [r for r in results if r.status is Status.GRADER_ERROR]
    out = [f"<h2>Grader errors ({len(broken)})</h2>"]
    if not broken:
        return out + ["<p>None: every cell was graded.</p>"]
    out.append("<p>The grader itself failed on these cells; the students are not to blame. Its "
               "traceback is in the grading log: fix the cause and grade again.</p><table><tr>"
               "<th>student</th><th>notebook</th><th>test</th><th>message</th></tr>")
    out += [f"<tr><td>{e(r.student)}</td><td>{e(r.notebook)}</td><td>{e(r.grade_id)}</td>"
            f"<td>{e(r.message)}</td></tr>" for r in broken]
    return out + ["</table>"]


def _ungradeable_html(results) -> list[str]:
    bad = ungradeable(results)
    kinds = Counter(status for _, _, status, _ in bad)
    out = [f"<h2>Submissions that could not be graded ({kinds.get('unreadable', 0)} unreadable, "
           f"{kinds.get('missing', 0)} missing)</h2>"]
    if not bad:
        return out + ["<p>None: every notebook was read.</p>"]
    out.append("<table><tr><th>student</th><th>notebook</th><th>status</th><th>why</th></tr>")
    out += [f"<tr><td>{e(s)}</td><td>{e(nb)}</td><td>{e(st)}</td><td>{e(msg)}</td></tr>"
            for s, nb, st, msg in bad]
    return out + ["</table>"]


def _statuses_html(results) -> list[str]:
    counts = Counter(r.status for r in results)
    out = ["<h2>Statuses</h2><table><tr><th>status</th><th>cells</th><th>meaning</th></tr>"]
    out += [f"<tr><td>{e(status.value)}</td><td>{counts.get(status, 0)}</td>"
            f"<td>{e(meaning)}</td></tr>" for status, meaning in STATUS_MEANING.items()]
    return out + ["</table>"]


def histogram_svg(scores: list[float], top: float, bins: int = 10) -> str:
    """A small inline SVG histogram of ``scores`` on ``[0, top]``."""
    w, h, pad = 300, 150, 22
    top = top if top > 0 else 1.0
    counts = [0] * bins
    for s in scores:
        counts[min(bins - 1, max(0, int(s / top * bins)))] += 1
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
