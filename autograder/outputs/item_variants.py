"""What the report knows of each item's variants: choice keys, and features of the numbers.

Every student answers the number items on numbers of their own and sees every choice item's
options in an order of their own (:mod:`course_lib.variants`). An examiner wants to know whether
the draw was fair: whether an item was harder for some numbers than for others. Each notebook's
numbers are summarised by a few *features* an examiner can reason about (Q4's spline kind and
end rule, Q5's specular share, Q6's vertices on a clipping plane...), and a choice item's by the
letter its key is shown under. :func:`features` gives a student's value of each;
:mod:`.item_checks` tests the facility across them.

The keys come from the exercise registry (:mod:`autograder.exercises`), the only place that
holds them.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable

from course_lib import variants

from ..exercises import REGISTRY
from ..exercises.base import choice_key
from ..model import CellKind


@functools.cache
def choice_items() -> dict[str, tuple[str, str]]:
    """``{graded name: (canonical key, option letters)}`` of every choice item."""
    return {name: (choice_key(ex.answer), variants.LETTERS[:len(ex.options)])
            for name, ex in REGISTRY.items() if ex.kind is CellKind.CHOICE}


def item_kind(name: str) -> str:
    """The registry's kind of graded name ``name`` (``function``, ``choice``, ``value``), or ``""``."""
    ex = REGISTRY.get(name)
    return ex.kind.value if ex is not None else ""


def canonical_choice(name: str, typed, student: str) -> str | None:
    """The canonical letters behind what ``student`` typed for choice item ``name``, or None
    when it is no string of option letters (or the item is not a choice)."""
    from course_lib.answers import ChoiceFormatError, choice_letters

    known = choice_items().get(name)
    if known is None or not isinstance(typed, str):
        return None
    options = known[1]
    try:
        shown = choice_letters(typed, options, name=name)
        order = _order(name, len(options), student)
    except (ChoiceFormatError, ValueError):
        return None
    return "".join(sorted(variants.LETTERS[order[variants.LETTERS.index(c)]] for c in shown))


@functools.lru_cache(maxsize=65536)
def _order(name: str, n_options: int, student: str) -> tuple[int, ...]:
    """:func:`course_lib.variants.option_order` (``order[k]``: the canonical index of the
    option shown as letter ``k``), kept: a report maps each student's letters and key once."""
    return variants.option_order(name, n_options, student)


@functools.lru_cache(maxsize=8192)
def _numbers(notebook: str, student: str):
    return variants.variant(notebook, student)


def _q1(v) -> dict[str, str]:
    slow = sum(c < 1540.0 for c in v.speeds)
    return {"layers slower than 1540 m/s": "2 or 3" if slow >= 2 else str(slow)}


def _q2(v) -> dict[str, str]:
    return {"hole diameter d (mm)": f"{v.d:g}"}


def _q3(v) -> dict[str, str]:
    above = sum(c > v.iso for c in v.corner_values)
    band = "1-2" if above <= 2 else ("3-5" if above <= 5 else "6-7")
    return {"cell corners above the iso-level": band,
            "crossed edge runs": "upwards" if v.v0 < v.v1 else "downwards"}


def _q4(v) -> dict[str, str]:
    return {"spline and end rule": f"{v.kind}, {v.rule}"}


def specular_share(v) -> float:
    """Q5(b): the specular term's share of a white surface's Phong intensity,
    ``Ip ks (R.V)^n / (Ia ka + Ip kd (L.N) + Ip ks (R.V)^n)`` with unit vectors."""
    unit = lambda w: [x / math.sqrt(sum(y * y for y in w)) for x in w]  # noqa: E731
    dot = lambda a, b: sum(x * y for x, y in zip(a, b))  # noqa: E731
    N, L, V = unit(v.N), unit(v.L), unit(v.V)
    ln = max(0.0, dot(L, N))
    R = [2 * ln * n - l for n, l in zip(N, L)]
    spec = v.Ip * v.ks * max(0.0, dot(R, V)) ** v.n
    total = v.Ia * v.ka + v.Ip * v.kd * ln + spec
    return spec / total if total > 0 else 0.0


def _q5(v) -> dict[str, str]:
    share = specular_share(v)
    band = "under 10 %" if share < 0.1 else ("10-30 %" if share < 0.3 else "30 % or more")
    return {"specular share of the intensity": band}


def _on_plane(row) -> bool:
    X, Y, Z, w = row
    return abs(X) == w or abs(Y) == w or Z == 0 or Z == w


def _q6(v) -> dict[str, str]:
    on = sum(_on_plane(r) for r in v.vertices)
    return {"vertices on a clipping plane": "none" if on == 0 else "1 or more"}


FEATURES: dict[str, Callable] = {"q1_imaging": _q1, "q2_nuclear": _q2,
                                 "q3_marching_cubes": _q3, "q4_splines": _q4, "q5_phong": _q5,
                                 "q6_clipping": _q6}


def features(name: str, notebook: str, student: str) -> dict[str, str]:
    """``{feature: value}`` of ``student``'s variant for graded name ``name``: the notebook's
    number features for a number item, the letter the key is shown under for a single-answer
    choice item, ``{}`` for anything else (or an id that is no valid id)."""
    kind = item_kind(name)
    try:
        if kind == "value" and notebook in FEATURES:
            return FEATURES[notebook](_numbers(notebook, student))
        key = choice_items().get(name)
        if kind == "choice" and key is not None and len(key[0]) == 1:
            order = _order(name, len(key[1]), student)
            shown = variants.LETTERS[order.index(variants.LETTERS.index(key[0]))]
            return {"key shown as": f"({shown})"}
    except ValueError:
        return {}
    return {}
