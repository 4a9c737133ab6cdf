"""The report's "Items" section: which automatically graded cells measure anything.

A sortable table of :mod:`.items` statistics (native buttons in the column headers: keyboard and
screen-reader operable, no script from elsewhere), a facility-against-discrimination plot
(inline SVG, flagged items drawn as triangles, not only in another colour), Cronbach's alpha per
notebook and for the assignment, a distractor table per choice item in the canonical options
(:mod:`.item_checks`), and the facility of each variant item across features of the students'
numbers, with a possibly unfair draw marked (:mod:`.item_variants`).
"""

from __future__ import annotations

import ast
from collections import defaultdict
from collections.abc import Mapping

from ..model import CellKind, CellResult, SourceNotebook, Status
from .html import e
from .item_checks import DrawTest, draw_test, option_table
from .item_variants import canonical_choice, choice_items, features
from .items import (DISCRIMINATION_LOW, FACILITY_HIGH, FACILITY_LOW, ItemStats, ScoreMatrix,
                    alphas, matrix_statistics, responses, score_matrix)

#: Family-wise error rate of the fairness tests (Bonferroni over every test in the report).
FAIRNESS_ALPHA = 0.05

STYLE = """
.items th button{font:inherit;font-weight:600;background:none;border:0;padding:0;cursor:pointer;
text-align:left;color:inherit}.items th button:focus-visible{outline:2px solid #1565c0;
outline-offset:2px}.items th[aria-sort=ascending] button::after{content:" \\25B2"}
.items th[aria-sort=descending] button::after{content:" \\25BC"}.items caption{text-align:left;
font-weight:600;padding:.3em 0}td.num{text-align:right;font-variant-numeric:tabular-nums}
.flag{font-weight:600;color:#8a3b00}.sr{position:absolute;left:-9999px}
.items tbody th{font-weight:normal}
"""

_SORT_JS = """
<script>
document.querySelectorAll('table.sortable').forEach(function (t) {
  var live = document.getElementById(t.id + '-status');
  t.querySelectorAll('thead th button').forEach(function (b, col) {
    b.addEventListener('click', function () {
      var th = b.parentNode, asc = th.getAttribute('aria-sort') !== 'ascending';
      t.querySelectorAll('thead th').forEach(function (h) { h.setAttribute('aria-sort', 'none'); });
      th.setAttribute('aria-sort', asc ? 'ascending' : 'descending');
      var body = t.tBodies[0], rows = Array.prototype.slice.call(body.rows);
      var num = b.getAttribute('data-type') === 'num';
      rows.sort(function (x, y) {
        var a = x.cells[col].getAttribute('data-v'), c = y.cells[col].getAttribute('data-v');
        if (num) {
          if (a === '' || c === '') { return (a === '') - (c === ''); }
          return asc ? a - c : c - a;
        }
        return asc ? a.localeCompare(c) : c.localeCompare(a);
      });
      rows.forEach(function (r) { body.appendChild(r); });
      if (live) { live.textContent = 'Sorted by ' + b.textContent + (asc ? ', ascending' : ', descending'); }
    });
  });
});
</script>
"""


def section_html(results: list[CellResult], sources: list[SourceNotebook] = (),
                 attempts: Mapping[tuple[str, str, str], int | None] | None = None) -> str:
    """The whole section; ``sources`` give the choice items' option texts, ``attempts`` see
    :func:`.items.item_statistics`."""
    rows = responses(results)
    out = ["<section class='items' id='items' aria-labelledby='items-h'>",
           "<h2 id='items-h'>Items</h2>"]
    if not rows:
        return "\n".join(out + ["<p>No automatically graded cells.</p></section>"])
    m = score_matrix(rows)
    stats = matrix_statistics(m, attempts)
    out.append(
        "<p class='note'>One row per automatically graded cell, over the students whose notebook "
        "was graded (<i>n</i>). <b>Facility</b>: mean score as a share of the marks. "
        "<b>Discrimination</b>: correlation of the item's score with the student's score on "
        "every other item (rest score); empty when either does not vary. <b>Upper − lower</b>: "
        "facility in the top 27 % by rest score minus the bottom 27 %. Items marked "
        f"<b>review</b> have a facility above {FACILITY_HIGH:g} or below {FACILITY_LOW:g}, or a "
        f"discrimination below {DISCRIMINATION_LOW:g}: check the wording, the key and the "
        "cases. The same numbers are in <code>items.csv</code>.</p>")
    out += [table_html(stats, attempts is not None), plot_svg(stats), alpha_html(m)]
    out += [distractors_html(results, m, option_texts(sources)), draws_html(results), _SORT_JS,
            "</section>"]
    return "\n".join(out)


def _cell(x: float | None, places: int = 2) -> str:
    if x is None:
        return ("<td class='num' data-v=''><span aria-hidden='true'>—</span>"
                "<span class='sr'>none</span></td>")
    return f"<td class='num' data-v='{x:.6f}'>{x:.{places}f}</td>"


def table_html(stats: list[ItemStats], with_attempts: bool = False) -> str:
    """The sortable item table."""
    cols = [("notebook", "text"), ("item", "text"), ("kind", "text"), ("marks", "num"),
            ("n", "num"), ("facility", "num"), ("discrimination", "num"),
            ("upper − lower", "num"), ("flag", "text")]
    if with_attempts:
        cols += [("median attempts to full marks", "num")]
    head = "".join(f"<th scope='col' aria-sort='none'><button type='button' data-type='{t}'>"
                   f"{e(c)}</button></th>" for c, t in cols)
    body = []
    for s in stats:
        flag = (f"<td data-v='{s.flag}'><span class='flag'>⚑ {s.flag}</span></td>" if s.flag
                else "<td data-v=''></td>")
        tail = _cell(s.attempts, 1) if with_attempts else ""
        body.append(f"<tr><td data-v='{e(s.notebook)}'>{e(s.notebook)}</td>"
                    f"<th scope='row' data-v='{e(s.grade_id)}'>{e(s.grade_id)}</th>"
                    f"<td data-v='{e(s.kind)}'>{e(s.kind)}</td>{_cell(s.max_score, 1)}"
                    f"<td class='num' data-v='{s.n}'>{s.n}</td>{_cell(s.facility)}"
                    f"{_cell(s.discrimination)}{_cell(s.upper_lower)}{flag}{tail}</tr>")
    flagged = sum(bool(s.flag) for s in stats)
    return ("<table class='sortable' id='item-table'><caption>Item statistics: "
            f"{len(stats)} items, {flagged} marked for review. Sort by a column with its "
            "header's button.</caption>"
            f"<thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"
            "<p id='item-table-status' class='sr' role='status' aria-live='polite'></p>")


def plot_svg(stats: list[ItemStats]) -> str:
    """Facility (x, 0..1) against discrimination (y) as an inline SVG figure."""
    pts = [s for s in stats if s.facility is not None and s.discrimination is not None]
    w, h, pad = 460, 300, 40
    lo = min([-0.2] + [s.discrimination for s in pts])
    sx = lambda f: pad + f * (w - 2 * pad)  # noqa: E731
    sy = lambda d: h - pad - (d - lo) / (1 - lo) * (h - 2 * pad)  # noqa: E731
    g = [f"<rect x='{sx(FACILITY_LOW):.1f}' y='{sy(1):.1f}' "
         f"width='{sx(FACILITY_HIGH) - sx(FACILITY_LOW):.1f}' "
         f"height='{sy(DISCRIMINATION_LOW) - sy(1):.1f}' fill='#eef5ee'/>"]
    g += [f"<line x1='{pad}' y1='{h - pad}' x2='{w - pad}' y2='{h - pad}' stroke='#444'/>",
          f"<line x1='{pad}' y1='{pad}' x2='{pad}' y2='{h - pad}' stroke='#444'/>"]
    for f in (0, 0.5, 1):
        g.append(f"<text x='{sx(f):.1f}' y='{h - pad + 14}' font-size='11' "
                 f"text-anchor='middle'>{f:g}</text>")
    for d in sorted({round(lo, 1), 0.0, 0.5, 1.0}):
        g.append(f"<text x='{pad - 4}' y='{sy(d) + 4:.1f}' font-size='11' "
                 f"text-anchor='end'>{d:g}</text>")
    g.append(f"<text x='{w / 2}' y='{h - 6}' font-size='12' text-anchor='middle'>facility</text>"
             f"<text x='12' y='{h / 2}' font-size='12' text-anchor='middle' "
             f"transform='rotate(-90 12 {h / 2})'>discrimination</text>")
    for s in pts:
        x, y = sx(s.facility), sy(s.discrimination)
        tip = (f"<title>{e(s.notebook)} {e(s.grade_id)}: facility {s.facility:.2f}, "
               f"discrimination {s.discrimination:.2f}{', review' if s.flag else ''}</title>")
        if s.flag:
            g.append(f"<polygon points='{x:.1f},{y - 6:.1f} {x - 5.5:.1f},{y + 4:.1f} "
                     f"{x + 5.5:.1f},{y + 4:.1f}' fill='#d84315' stroke='#5d1a00'>{tip}</polygon>")
        else:
            g.append(f"<circle cx='{x:.1f}' cy='{y:.1f}' r='4' fill='#1565c0' "
                     f"stroke='#0b2f5e'>{tip}</circle>")
    flagged = sum(bool(s.flag) for s in pts)
    label = (f"Scatter plot of {len(pts)} items: facility on the horizontal axis from 0 to 1, "
             f"discrimination on the vertical axis from {lo:.1f} to 1. The shaded band is the "
             f"range that needs no review (facility {FACILITY_LOW:g} to {FACILITY_HIGH:g}, "
             f"discrimination at least {DISCRIMINATION_LOW:g}); {flagged} items marked for "
             "review are drawn as triangles, the others as circles. The table lists the same "
             "numbers.")
    left_out = len(stats) - len(pts)
    return (f"<figure><svg width='{w}' height='{h}' viewBox='0 0 {w} {h}' role='img' "
            f"aria-label='{e(label)}'>{''.join(g)}</svg><figcaption class='note'>Facility "
            "against discrimination: circles need no review, triangles are marked for review; "
            "the shaded band is where good items lie."
            + (f" Not drawn, without a discrimination: {left_out} item"
               f"{'s' if left_out != 1 else ''}." if left_out else "")
            + "</figcaption></figure>")


def alpha_html(m: ScoreMatrix) -> str:
    """Cronbach's alpha per notebook and for the assignment."""
    rows = "".join(
        f"<tr><th scope='row'>{e(nb)}</th><td class='num'>{k}</td><td class='num'>{n}</td>"
        f"<td class='num'>{'—' if a is None else f'{a:.2f}'}</td></tr>"
        for nb, k, n, a in alphas(m))
    return ("<table><caption>Cronbach's alpha of the automatically graded items (internal "
            "consistency; over the students who answered every item of the notebook, or of "
            "the assignment)</caption><thead><tr><th scope='col'>notebook</th><th scope='col'>"
            "items</th><th scope='col'>students</th><th scope='col'>alpha</th></tr></thead>"
            f"<tbody>{rows}</tbody></table>")


def _answered(results: list[CellResult], kind: CellKind) -> dict[tuple[str, str, str],
                                                                   list[CellResult]]:
    by_item = defaultdict(list)
    for r in results:
        if r.kind is kind and not r.whole_notebook and r.status is not Status.GRADER_ERROR:
            by_item[(r.notebook, r.grade_id, r.name)].append(r)
    return by_item


def option_texts(sources: list[SourceNotebook]) -> dict[str, list[str]]:
    """``{choice item: its options' texts in the canonical order}``, read from the source
    notebooks' ``mine.options("name", [...])`` cells (literals only; others are skipped)."""
    found = {}
    for src in sources:
        for cell in src.cells:
            if cell.cell_type != "code" or ".options(" not in cell.source:
                continue
            try:
                tree = ast.parse(cell.source)
            except SyntaxError:
                continue
            for node in ast.walk(tree):
                if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) \
                        and node.func.attr == "options" and len(node.args) == 2:
                    try:
                        name, texts = ast.literal_eval(node.args[0]), ast.literal_eval(node.args[1])
                    except ValueError:
                        continue
                    if isinstance(name, str) and isinstance(texts, (list, tuple)):
                        found[name] = [str(t) for t in texts]
    return found


def distractors_html(results: list[CellResult], m: ScoreMatrix,
                     texts: Mapping[str, list[str]] | None = None) -> str:
    """One distractor table per choice item, in the canonical options (with their texts)."""
    keys = choice_items()
    out = ["<h3>Choice items: the options</h3><p class='note'>Students see the options in "
           "orders of their own; each answer is mapped back to the canonical options (as in "
           "the source notebook). <b>Point-biserial</b>: correlation of choosing the option "
           "with the rest score; the key should have a clearly positive one, a distractor a "
           "negative one.</p>"]
    for (nb, gid, name), rs in _answered(results, CellKind.CHOICE).items():
        if name not in keys:
            continue
        key, options = keys[name]
        j = m.items.index((nb, gid))
        rest = dict(zip(m.students, m.rest(j)))
        chosen = {r.student: canonical_choice(name, r.answer, r.student) for r in rs}
        body = []
        for o in option_table(chosen, key, options, rest):
            label = f"({o.option})" if len(o.option) == 1 else o.option
            k = "abcdefgh".find(o.option) if len(o.option) == 1 else -1
            if 0 <= k < len((texts or {}).get(name, ())):
                label += " " + _short(texts[name][k])
            mark = "<td>✓ key</td>" if o.key else "<td><span class='sr'>not the key</span></td>"
            pb = "—" if o.point_biserial is None else f"{o.point_biserial:+.2f}"
            mean = "—" if o.mean_rest is None else f"{o.mean_rest:.1f}"
            note = "; ".join(o.notes)
            body.append(f"<tr><th scope='row'>{e(label)}</th>{mark}<td class='num'>{o.chosen}"
                        f"</td><td class='num'>{o.share:.0%}</td><td class='num'>{mean}</td>"
                        f"<td class='num'>{pb}</td><td>{'⚑ ' if note else ''}{e(note)}</td></tr>")
        out.append(f"<table><caption>{e(nb)}: {e(name)} (key {e(', '.join(key))}; "
                   f"{len(chosen)} students)</caption><thead><tr><th scope='col'>option</th>"
                   "<th scope='col'>key</th><th scope='col'>chosen by</th><th scope='col'>share"
                   "</th><th scope='col'>mean rest score</th><th scope='col'>point-biserial</th>"
                   f"<th scope='col'>note</th></tr></thead><tbody>{''.join(body)}</tbody></table>")
    return "\n".join(out)


def _short(text: str, limit: int = 110) -> str:
    text = " ".join(text.replace("$", "").split())     # the notebooks' LaTeX, read as text
    return text if len(text) <= limit else text[:limit - 1] + "…"


def _credit(r: CellResult) -> float:
    """The share of an item a student earned; a practice item (0 points: the number items)
    counts as 1 when right, so that its draw is still tested for fairness."""
    return (r.score or 0.0) / r.max_score if r.max_score > 0 else float(r.status == Status.OK)


def draw_tests(results: list[CellResult]) -> list[tuple[str, str, str, DrawTest, bool]]:
    """``(notebook, item, feature, test, possibly unfair)`` for every variant item and feature;
    unfair: p below :data:`FAIRNESS_ALPHA` divided by the number of tests (Bonferroni)."""
    found = []
    for kind in (CellKind.VALUE, CellKind.CHOICE):
        for (nb, _gid, name), rs in _answered(results, kind).items():
            groups: dict[str, dict[str, list[float]]] = defaultdict(lambda: defaultdict(list))
            for r in rs:
                for feature, value in features(name, nb, r.student).items():
                    groups[feature][value].append(_credit(r))
            found += [(nb, name, f, draw_test(g)) for f, g in groups.items()]
    tests = sum(t.p is not None for *_, t in found)
    cut = FAIRNESS_ALPHA / max(tests, 1)
    return [(nb, name, f, t, t.p is not None and t.p < cut) for nb, name, f, t in found]


def draws_html(results: list[CellResult]) -> str:
    """Facility by variant feature, a possibly unfair draw marked."""
    rows = draw_tests(results)
    out = ["<h3>Variants: facility by the student's numbers</h3><p class='note'>Number items "
           "are worked on each student's own numbers, and each choice item shows its key under "
           "a letter of the student's own. For every feature, full marks against not is tested "
           "across its groups (groups under 10 students left out) with Pearson's chi-square "
           "test, or Fisher's exact test for two small groups; a p-value below "
           f"{FAIRNESS_ALPHA:g} divided by the number of tests (Bonferroni) is marked "
           "<b>possibly unfair draw</b>.</p>"]
    if not rows:
        return "\n".join(out + ["<p>No variant items were graded.</p>"])
    body = []
    for nb, name, feature, t, unfair in rows:
        groups = "; ".join(f"{g}: {c} at {f:.0%}" for g, c, f in t.groups)
        p = "—" if t.p is None else (f"{t.p:.2g}" if t.p < 0.001 else f"{t.p:.3f}")
        flag = "<span class='flag'>⚑ possibly unfair draw</span>" if unfair else ""
        body.append(f"<tr><td>{e(nb)}</td><th scope='row'>{e(name)}</th><td>{e(feature)}</td>"
                    f"<td>{e(groups)}</td><td>{e(t.test)}</td><td class='num'>{p}</td>"
                    f"<td>{flag}</td></tr>")
    return "\n".join(out + [
        "<table><caption>Facility by variant feature (group: students at facility)</caption>"
        "<thead><tr><th scope='col'>notebook</th><th scope='col'>item</th><th scope='col'>"
        "feature</th><th scope='col'>groups</th><th scope='col'>test</th><th scope='col'>p</th>"
        f"<th scope='col'>flag</th></tr></thead><tbody>{''.join(body)}</tbody></table>"])

