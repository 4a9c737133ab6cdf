"""Two checks of single items: the options of a choice item, and a variant's fairness.

- :func:`option_table`: a choice item's distractor analysis in the *canonical* options (each
  student's letters already mapped back): how many chose each option, their mean rest score,
  and each option's point-biserial (Pearson's r of "chose it" with the rest score; Canvas
  reports the same per answer). A distractor is marked when more students choose it than the
  key (single-answer items), when its point-biserial is at least 0.1 (stronger students choose
  it: check the key and the wording), or when fewer than 5 % choose it (a non-functioning
  distractor, Haladyna & Downing, Educ. Psychol. Meas. 53 (1993) 999-1010).
- :func:`draw_test`: does the facility of an item depend on a feature of the student's numbers
  (Q4's spline and end rule, Q5's specular share...)? Students are grouped by the feature,
  groups under :data:`MIN_GROUP` are left out, and full marks against not is tested with
  Pearson's chi-square test of independence when Cochran's rule holds (every expected count at
  least 1, at most a fifth under 5), else, for two groups, Fisher's exact test (two-sided, the
  tables at most as likely as the one observed); otherwise there are too few students to tell.

Pure NumPy and the standard library (the chi-square tail is the closed form for integer degrees
of freedom).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from .items import pearson

#: A distractor chosen by fewer than this share of the class does no work.
NON_FUNCTIONING = 0.05
#: A distractor whose point-biserial is at least this is chosen by the stronger students.
POSITIVE_DISTRACTOR = 0.1
#: Students a variant group needs to enter a test.
MIN_GROUP = 10


@dataclass
class OptionStats:
    """One row of a distractor table."""

    option: str                     #: a canonical letter, or "no answer"
    key: bool
    chosen: int
    share: float
    mean_rest: float | None
    point_biserial: float | None
    notes: list[str] = field(default_factory=list)


def option_table(chosen: Mapping[str, str | None], key: str, options: str,
                 rest: Mapping[str, float]) -> list[OptionStats]:
    """Per canonical option of a choice item: ``chosen`` maps each student who answered to the
    canonical letters they chose (``None``: no answer, or not a string of option letters),
    ``key`` is the canonical key (``"b"``, or ``"ac"`` for all that apply), ``rest`` each
    student's rest score. The last row counts the students with no usable answer."""
    students = sorted(chosen)
    if not set(key) <= set(options):
        raise ValueError(f"key {key!r} is not among the options {options!r}")
    missing = [s for s in students if s not in rest]
    if missing:
        raise ValueError(f"no rest score for {missing[:3]}")
    n = len(students)
    rest_v = np.array([rest[s] for s in students], float)
    rows = []
    for letter in options:
        picked = np.array([bool(chosen[s]) and letter in chosen[s] for s in students])
        rows.append(_option_row(letter, letter in key, picked, rest_v, n))
    none = np.array([not chosen[s] for s in students])
    rows.append(_option_row("no answer", False, none, rest_v, n))
    _mark(rows, single=len(key) == 1)
    return rows


def _option_row(option: str, is_key: bool, picked: np.ndarray, rest: np.ndarray,
                n: int) -> OptionStats:
    count = int(picked.sum())
    return OptionStats(option, is_key, count, count / n if n else 0.0,
                       float(rest[picked].mean()) if count else None,
                       pearson(picked.astype(float), rest) if n else None)


def _mark(rows: list[OptionStats], single: bool) -> None:
    key_count = max((r.chosen for r in rows if r.key), default=0)
    for r in rows[:-1]:
        if r.key:
            if r.point_biserial is not None and r.point_biserial < POSITIVE_DISTRACTOR:
                r.notes.append("key: weak or negative point-biserial")
            continue
        if single and r.chosen > key_count:
            r.notes.append("chosen more often than the key")
        if r.point_biserial is not None and r.point_biserial >= POSITIVE_DISTRACTOR:
            r.notes.append("stronger students choose it")
        if r.share < NON_FUNCTIONING:
            r.notes.append("non-functioning (under 5 %)")


@dataclass
class DrawTest:
    """The outcome of :func:`draw_test`."""

    groups: list[tuple[str, int, float]]    #: (feature value, students, facility), all groups
    test: str                               #: "chi-square", "Fisher", or why there is none
    statistic: float | None = None
    p: float | None = None


def draw_test(groups: Mapping[str, Sequence[float]], min_group: int = MIN_GROUP) -> DrawTest:
    """Test whether full marks on an item depend on a variant feature: ``groups`` maps each
    value of the feature to the scores (as fractions of the item's marks) of the students who
    drew it. See the module for the tests and their conditions."""
    shown = [(str(g), len(v), float(np.mean(v)) if len(v) else 0.0)
             for g, v in sorted(groups.items())]
    table = [[sum(x >= 1 - 1e-9 for x in v), sum(x < 1 - 1e-9 for x in v)]
             for _, v in sorted(groups.items()) if len(v) >= min_group]
    if len(table) < 2:
        return DrawTest(shown, f"no test: fewer than 2 groups of {min_group} students")
    t = np.array(table, float)
    if (t.sum(axis=0) == 0).any():
        return DrawTest(shown, "no test: every student in the same column", None, 1.0)
    expected = t.sum(axis=1, keepdims=True) * t.sum(axis=0, keepdims=True) / t.sum()
    if expected.min() >= 1 and (expected < 5).mean() <= 0.2:
        stat = float(((t - expected) ** 2 / expected).sum())
        return DrawTest(shown, "chi-square", stat, chi2_sf(stat, len(table) - 1))
    if len(table) == 2:
        return DrawTest(shown, "Fisher", None, fisher_exact(table))
    return DrawTest(shown, "no test: expected counts too small")


def chi2_sf(x: float, df: int) -> float:
    """P(X >= x) for X chi-square with ``df`` (a positive integer) degrees of freedom: the
    regularised upper gamma function Q(df/2, x/2) in closed form."""
    if df < 1 or int(df) != df:
        raise ValueError(f"df must be a positive integer, got {df!r}")
    if x <= 0:
        return 1.0
    h = x / 2.0
    if df % 2 == 0:     # Q(m, h) = exp(-h) sum_{i<m} h^i / i!
        term, total = 1.0, 1.0
        for i in range(1, df // 2):
            term *= h / i
            total += term
        return min(1.0, math.exp(-h) * total)
    # Q(m + 1/2, h) = erfc(sqrt h) + exp(-h) sum_{i=1..m} h^(i-1/2) / Gamma(i+1/2)
    total, term = math.erfc(math.sqrt(h)), math.sqrt(h) / math.gamma(1.5)
    for i in range(1, (df - 1) // 2 + 1):
        total += math.exp(-h) * term
        term *= h / (i + 0.5)
    return min(1.0, total)


def fisher_exact(table: Sequence[Sequence[int]]) -> float:
    """Two-sided p of Fisher's exact test of a 2 x 2 table: the probability, with the margins
    fixed, of every table at most as likely as the one observed."""
    (a, b), (c, d) = ((int(x) for x in row) for row in table)
    if min(a, b, c, d) < 0:
        raise ValueError(f"counts must be >= 0, got {table!r}")
    row1, col1, n = a + b, a + c, a + b + c + d
    lo, hi = max(0, col1 - (n - row1)), min(row1, col1)

    def prob(x: int) -> float:
        return math.comb(col1, x) * math.comb(n - col1, row1 - x) / math.comb(n, row1)

    seen = prob(a)
    return min(1.0, sum(p for p in map(prob, range(lo, hi + 1)) if p <= seen * (1 + 1e-7)))
