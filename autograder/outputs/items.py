"""Item analysis: which graded cells of the assignment measure anything (classical test theory).

Every automatically graded cell (and, in ``export``, every written answer once marked) is an
*item*. For each, over the students who answered it (``n``):

- **facility**: mean score / ``max_score`` (the share of the marks the class earned);
- **discrimination**: Pearson's r between the item's score and the student's *rest score* (the
  sum of their scores on every other item of the assignment): the corrected item-total
  correlation, so an item is not correlated with itself;
- **upper_lower**: facility among the ``ceil(0.27 n)`` students with the highest rest score minus
  facility among the ``ceil(0.27 n)`` with the lowest (Kelley's 27 % groups, T. L. Kelley,
  J. Educ. Psychol. 30 (1939) 17-24), ties broken by student id (the lower id first in each
  group);
- **flag**: ``review`` when facility > 0.95 or < 0.2 or discrimination < 0.1.

A row whose score is ``None`` is not an answer to its item: a notebook not handed in or
unreadable as a whole, a notebook handed in wholly blank (every automatic cell ``unanswered``),
a grader error, a written answer not yet marked. It is left out of that
item's statistics and counts 0 in the student's rest score (as in their total). Cronbach's alpha
(:func:`cronbach_alpha`) is here too; a choice item's options and the fairness of the variants
are in :mod:`.item_checks`. Everything is NumPy and the standard library, and never NaN: an
undefined number is ``None`` (an empty cell).
"""

from __future__ import annotations

import csv
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..model import CellKind, CellResult, Status, format_score

ITEM_COLUMNS = ("notebook", "grade_id", "kind", "max_score", "n", "facility", "discrimination",
                "upper_lower", "flag")
#: Kelley's share of the class in each of the upper and lower groups.
GROUP_SHARE = 0.27
#: An item is flagged for review outside these bounds.
FACILITY_HIGH, FACILITY_LOW, DISCRIMINATION_LOW = 0.95, 0.2, 0.1
#: Scores are kept to this many decimals (grades.csv keeps six), so equal totals tie exactly.
_PLACES = 9


class Response(NamedTuple):
    """One student's score on one item; ``score`` None: no answer to it (see the module)."""

    student: str
    notebook: str
    grade_id: str
    kind: str
    score: float | None
    max_score: float


@dataclass
class ItemStats:
    """One row of ``items.csv`` (``None`` for a number that is undefined: written empty)."""

    notebook: str
    grade_id: str
    kind: str
    max_score: float
    n: int
    facility: float | None
    discrimination: float | None
    upper_lower: float | None
    flag: str
    #: median attempts to first full marks, among those who got them (only with ``attempts``)
    attempts: float | None = None
    full_marks: int = 0         #: students who reached full marks (only with ``attempts``)


@dataclass
class ScoreMatrix:
    """Scores as a students x items array (NaN: no answer), rows sorted by student id."""

    students: list[str]
    items: list[tuple[str, str]]        #: (notebook, grade_id), in first-seen order
    kinds: list[str]
    max_scores: np.ndarray
    scores: np.ndarray

    @property
    def totals(self) -> np.ndarray:
        """Each student's total over every item (no answer counts 0)."""
        return np.round(np.nansum(self.scores, axis=1), _PLACES)

    def rest(self, j: int) -> np.ndarray:
        """Each student's total minus item ``j`` (NaN where item ``j`` has no answer)."""
        return np.round(self.totals - self.scores[:, j], _PLACES)


def responses(results: Iterable[CellResult]) -> list[Response]:
    """The automatically graded cells of a grading run as responses: a notebook not handed in
    or unreadable as a whole, one handed in wholly blank (every automatic cell ``unanswered``:
    the student did not attempt it, like one not handed in), and a grader error, are no answer
    to the item."""
    auto = [r for r in results if (_KIND_NAMES.get(r.kind) or str(r.kind)) != "manual"]
    attempted = {(r.student, r.notebook) for r in auto if r.status is not _UNANSWERED}
    out = []
    for r in auto:
        none = (r.whole_notebook or r.status is _GRADER_ERROR or r.score is None
                or (r.student, r.notebook) not in attempted)
        out.append(Response(r.student, r.notebook, r.grade_id,
                            _KIND_NAMES.get(r.kind) or str(r.kind),
                            None if none else float(r.score), float(r.max_score)))
    return out


# looked up once: an enum member's ``.value`` costs a descriptor call per row
_KIND_NAMES = {k: k.value for k in CellKind}
_GRADER_ERROR, _UNANSWERED = Status.GRADER_ERROR, Status.UNANSWERED


def score_matrix(rows: Iterable[Response]) -> ScoreMatrix:
    """The students x items matrix of ``rows``; ``ValueError`` for a student with two rows for
    one item, a negative ``max_score`` or a score outside ``[0, max_score]``."""
    rows = list(rows)
    items: dict[tuple[str, str], int] = {}
    kinds, maxima = [], []
    for r in rows:
        key = (r.notebook, r.grade_id)
        if key not in items:
            items[key] = len(items)
            kinds.append(r.kind)
            maxima.append(float(r.max_score))
    students = sorted({r.student for r in rows})
    where = {s: i for i, s in enumerate(students)}
    at = np.array([(where[r.student], items[(r.notebook, r.grade_id)]) for r in rows],
                  dtype=np.intp).reshape(-1, 2)
    flat = at[:, 0] * max(len(items), 1) + at[:, 1]
    if len(np.unique(flat)) != len(flat):
        k = int(np.flatnonzero(np.bincount(flat) > 1)[0])
        (nb, gid), = [key for key, j in items.items() if j == k % len(items)]
        raise ValueError(f"{students[k // len(items)]} has two rows for {nb}/{gid}")
    bad = [r for r in rows if not (math.isfinite(r.max_score) and r.max_score >= 0)]
    if bad:
        raise ValueError(f"{bad[0].notebook}/{bad[0].grade_id}: max_score must be >= 0, got "
                         f"{bad[0].max_score!r}")
    score = np.array([np.nan if r.score is None else r.score for r in rows], float)
    top = np.array(maxima)[at[:, 1]] if len(rows) else np.zeros(0)
    wrong = ~np.isnan(score) & ~((score >= -1e-9) & (score <= top + 1e-9))
    if wrong.any():
        r = rows[int(np.flatnonzero(wrong)[0])]
        raise ValueError(f"{r.student}, {r.notebook}/{r.grade_id}: score {r.score!r} is not "
                         f"within [0, {float(r.max_score):g}]")
    scores = np.full((len(students), len(items)), np.nan)
    scores[at[:, 0], at[:, 1]] = np.round(score, _PLACES)
    return ScoreMatrix(students, list(items), kinds, np.array(maxima), scores)


def pearson(x, y) -> float | None:
    """Pearson's r of ``x`` and ``y``; None when either has zero variance (or fewer than 2)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    if x.size < 2 or np.ptp(x) == 0 or np.ptp(y) == 0:
        return None
    dx, dy = x - x.mean(), y - y.mean()
    r = float(np.dot(dx, dy) / math.sqrt(float(np.dot(dx, dx)) * float(np.dot(dy, dy))))
    return min(1.0, max(-1.0, r))


def group_size(n: int) -> int:
    """Students in each of Kelley's upper and lower groups: ``ceil(0.27 n)``."""
    # 0.27 n computed in integers: 27 n / 100 rounded up (float 0.27 * 100 is 27.000000000000004)
    return -(-27 * n // 100)


def upper_lower(fraction, rest, students, k: int | None = None) -> float | None:
    """Facility of the upper group minus that of the lower (``k`` students each, by default
    ``ceil(0.27 n)``, by rest score; ties by student id, the lower id first); None for fewer
    than 2 students."""
    n = len(students)
    if n < 2:
        return None
    k = group_size(n) if k is None else int(k)
    if not 1 <= k <= n:
        raise ValueError(f"a group of {k} students out of {n}")
    fraction, rest = np.asarray(fraction, float), np.asarray(rest, float)
    ids = np.asarray(students, dtype=object)
    by_id = np.argsort(ids, kind="stable")
    up = by_id[np.argsort(-rest[by_id], kind="stable")][:k]
    low = by_id[np.argsort(rest[by_id], kind="stable")][:k]
    return float(fraction[up].mean() - fraction[low].mean())


def review_flag(facility: float | None, discrimination: float | None) -> str:
    """``review`` when the facility is above 0.95 or below 0.2 or the discrimination below 0.1."""
    if facility is not None and (facility > FACILITY_HIGH or facility < FACILITY_LOW):
        return "review"
    if discrimination is not None and discrimination < DISCRIMINATION_LOW:
        return "review"
    return ""


def item_statistics(rows: Iterable[Response],
                    attempts: Mapping[tuple[str, str, str], int | None] | None = None
                    ) -> list[ItemStats]:
    """One :class:`ItemStats` per item of ``rows``, in first-seen order.

    ``attempts`` (``{(student, notebook, grade_id): attempts to first full marks, None if
    never}``) is for a grading service that records each submission: no such service exists
    yet, so ``grade`` passes none; when given, each item also gets the median attempts to first
    full marks among the students who reached them.
    """
    return matrix_statistics(score_matrix(rows), attempts)


def matrix_statistics(m: ScoreMatrix, attempts: Mapping | None = None) -> list[ItemStats]:
    """:func:`item_statistics` of a matrix already built."""
    out = []
    totals = m.totals
    tries = _attempts_by_item(attempts) if attempts is not None else None
    for j, (notebook, grade_id) in enumerate(m.items):
        answered = ~np.isnan(m.scores[:, j])
        top = float(m.max_scores[j])
        n = int(answered.sum())
        stats = ItemStats(notebook, grade_id, m.kinds[j], top, n, None, None, None, "")
        if n and top > 0:
            frac = m.scores[answered, j] / top
            rest = np.round(totals - m.scores[:, j], _PLACES)[answered]
            ids = [s for s, a in zip(m.students, answered) if a]
            stats.facility = float(frac.mean())
            stats.discrimination = pearson(frac, rest)
            stats.upper_lower = upper_lower(frac, rest, ids)
            stats.flag = review_flag(stats.facility, stats.discrimination)
        if tries is not None:
            reached = tries.get((notebook, grade_id), [])
            stats.full_marks = len(reached)
            stats.attempts = float(np.median(reached)) if reached else None
        out.append(stats)
    return out


def _attempts_by_item(attempts: Mapping) -> dict[tuple[str, str], list[int]]:
    """``{(notebook, grade_id): [attempts to first full marks of each student who got them]}``;
    ``ValueError`` for a count below 1."""
    out: dict[tuple[str, str], list[int]] = {}
    for (student, nb, gid), a in attempts.items():
        if a is None:
            continue
        if int(a) != a or a < 1:
            raise ValueError(f"{student}, {nb}/{gid}: attempts must be a whole number >= 1, "
                             f"got {a!r}")
        out.setdefault((nb, gid), []).append(int(a))
    return out


def cronbach_alpha(scores) -> float | None:
    """Cronbach's alpha of a students x items array (raw points), over the students who
    answered every item (rows without NaN): ``k/(k-1) (1 - sum of item variances / variance of
    the totals)``. None with fewer than 2 items or 2 such students, or totals all equal."""
    a = np.asarray(scores, float)
    if a.ndim != 2:
        raise ValueError(f"scores must be a students x items array, got shape {a.shape}")
    a = a[~np.isnan(a).any(axis=1)]
    n, k = a.shape
    if k < 2 or n < 2:
        return None
    total_var = float(np.var(a.sum(axis=1), ddof=1))
    if total_var <= 1e-12 * max(1.0, float(np.abs(a).max())) ** 2:
        return None
    return k / (k - 1) * (1.0 - float(np.var(a, axis=0, ddof=1).sum()) / total_var)


def alphas(m: ScoreMatrix) -> list[tuple[str, int, int, float | None]]:
    """``(notebook or "assignment", items, students with every item answered, alpha)`` for each
    notebook and for the whole assignment last."""
    notebooks = list(dict.fromkeys(nb for nb, _ in m.items))
    out = []
    for nb in [*notebooks, None]:
        cols = [j for j, (b, _) in enumerate(m.items) if nb is None or b == nb]
        sub = m.scores[:, cols]
        complete = int((~np.isnan(sub).any(axis=1)).sum())
        out.append((nb or "assignment", len(cols), complete, cronbach_alpha(sub)))
    return out


def _number(x: float | None) -> str:
    return "" if x is None or not math.isfinite(x) else f"{x:.4f}"


def csv_rows(stats: Iterable[ItemStats]) -> list[list[str]]:
    """``items.csv`` rows (columns :data:`ITEM_COLUMNS`): numbers to 4 decimals, empty when
    undefined."""
    return [[s.notebook, s.grade_id, s.kind, format_score(s.max_score), str(s.n),
             _number(s.facility), _number(s.discrimination), _number(s.upper_lower), s.flag]
            for s in stats]


def write_items_csv(stats: Iterable[ItemStats], path: Path) -> Path:
    """Write ``items.csv`` to ``path``."""
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(ITEM_COLUMNS)
        w.writerows(csv_rows(stats))
    return Path(path)
