"""Item analysis: a class of 500 students on every automatically graded cell of the assignment.

The class is synthetic: each student has an ability, every graded cell of the six source
notebooks gets a score that rises with it, choice items get typed letters in the student's own
order of the options (a key for the strong, a popular distractor for the weak), and 2 % of the
notebooks are missing.

- **ours**: :func:`autograder.outputs.items.item_statistics` (``items.csv``'s numbers), and the
  whole "Items" section of the report (:func:`autograder.outputs.items_html.section_html`:
  the statistics, Cronbach's alpha, the distractor tables with every student's letters mapped
  back to the canonical options, the variant features and their tests);
- **peer**: the same statistics computed the plain way, per item from a dict of rows with
  ``scipy.stats.pearsonr`` for the discrimination and ``sorted`` for Kelley's groups.

The issue's target: a 500-student class analysed in under 5 s.
"""

from __future__ import annotations

import math
import random
import time

from .harness import Row

SECTION = "item analysis"
STUDENTS = 500
SMOKE_STUDENTS = 20


def make_class(n: int):
    """``CellResult``s of ``n`` students on every automatically graded cell."""
    from autograder.exercises import REGISTRY
    from autograder.grade.sources import default_sources, load_source
    from autograder.model import CellKind, CellResult, Status
    from course_lib import variants

    rng = random.Random(4)
    sources = [load_source(p) for p in default_sources()]
    results = []
    for i in range(n):
        student, theta = f"st{i:04d}", rng.gauss(0.0, 1.0)
        for src in sources:
            missing = rng.random() < 0.02
            for k, (name, test_id, points) in enumerate(src.graded):
                ex = REGISTRY[name]
                p = 1 / (1 + math.exp(-(1.5 * theta + 1.2 - 0.1 * k)))
                right = rng.random() < p
                score = 0.0 if missing else (points if right else points * rng.choice((0, .5)))
                answer = None
                if ex.kind == "choice" and not missing:
                    key = "".join(sorted(ex.answer))
                    pick = key if right else rng.choice(("a", "b", "c", "d"))
                    pick = "".join(c for c in pick if c in "abcdefgh"[:len(ex.options)])
                    answer = variants.displayed_letters(name, pick or "a", len(ex.options),
                                                        student)
                    score = points if (pick or "a") == key else 0.0
                status = Status.MISSING if missing else (
                    Status.OK if score == points else Status.FAILED)
                results.append(CellResult(student, src.name, test_id, name, score, points, status,
                                          "", kind=CellKind(ex.kind), answer=answer,
                                          whole_notebook=missing))
    return results


def peer_statistics(results) -> dict:
    """``{(notebook, grade_id): (n, facility, discrimination, upper_lower)}`` the plain way."""
    from scipy.stats import pearsonr

    total, by_item = {}, {}
    for r in results:
        total[r.student] = total.get(r.student, 0.0) + (r.score or 0.0)
        if not r.whole_notebook and r.max_score:   # practice items (0 marks) have no facility
            by_item.setdefault((r.notebook, r.grade_id), []).append(r)
    out = {}
    for key, rs in by_item.items():
        frac = [r.score / r.max_score for r in rs]
        rest = [total[r.student] - r.score for r in rs]
        disc = None
        if len(set(frac)) > 1 and len(set(rest)) > 1:
            disc = pearsonr(frac, rest)[0]
        k = math.ceil(0.27 * len(rs))
        rows = list(zip(rest, [r.student for r in rs], frac))
        upper = sorted(rows, key=lambda t: (-t[0], t[1]))[:k]
        lower = sorted(rows, key=lambda t: (t[0], t[1]))[:k]
        out[key] = (len(rs), sum(frac) / len(rs), disc,
                    sum(t[2] for t in upper) / k - sum(t[2] for t in lower) / k)
    return out


def _best(fn, repeat: int) -> tuple[float, object]:
    best, value = float("inf"), None
    for _ in range(repeat):
        t0 = time.perf_counter()
        value = fn()
        best = min(best, time.perf_counter() - t0)
    return best, value


def run(smoke: bool = False) -> list[Row]:
    import scipy.stats  # noqa: F401 - imported before the peer is timed, as ours is

    from autograder.outputs import items, items_html

    n = SMOKE_STUDENTS if smoke else STUDENTS
    results = make_class(n)
    repeat = 1 if smoke else 3
    ours, stats = _best(lambda: items.item_statistics(items.responses(results)), repeat)
    peer, oracle = _best(lambda: peer_statistics(results), repeat)
    worst = max(abs(s.facility - oracle[(s.notebook, s.grade_id)][1])
                for s in stats if s.facility is not None)
    section, html = _best(lambda: items_html.section_html(results), 1)
    case = f"{n} students x {len(stats)} items"
    return [
        Row(SECTION, case, "items.csv statistics", ours * 1e3, peer * 1e3,
            "plain Python + scipy.stats.pearsonr per item", "ms",
            f"facility, rest-score discrimination, Kelley groups; largest facility difference "
            f"from the peer {worst:.1e}"),
        Row(SECTION, case, "the report's Items section", section * 1e3, 5e3, "target", "ms",
            f"statistics, alpha, {html.count('(key ')} distractor tables, variant tests; "
            f"{len(html) / 1e3:.0f} kB of HTML; the issue's target is under 5 s"),
    ]
