"""No graded function can be answered by position (issue 33, finding 1).

A function that counts its calls knows nothing about the case in front of it but its place in
the run. So, over thousands of draws, for every graded function of the registry:

- every hidden case that does not raise has an answer that depends on the draw: no single
  answer, judged by the exercise's own rule, passes that case in more than
  :data:`MOST_FIXED` of the draws (a fair True/False case is 1/2);
- the hidden cases run in an order shuffled per draw, bad-input cases among them: every hidden
  position holds a bad-input case in some draws and an ordinary case in others, near the
  share a uniform shuffle gives;
- the visible cases still run first, in the generator's order.

The oracle is the generator's own list (``Exercise.draw_cases``) and the exercise's rule, not
values from a run of the grader.
"""

from __future__ import annotations

import dataclasses
import pickle

import numpy as np
import pytest

from autograder.exercises import REGISTRY
from autograder.grade.cases import draw
from autograder.model import CellKind

FUNCTIONS = sorted(n for n, ex in REGISTRY.items() if ex.kind is CellKind.FUNCTION)
#: Draws for the order of the cases (cheap: no reference is called).
ORDER_DRAWS = 2000
#: Draws whose answers are computed per hidden case, and how many of the first draws' answers
#: are tried as the fixed answer a positional function would return.
ANSWER_DRAWS, CANDIDATES = 1000, 6
#: The largest share of draws that one fixed answer may pass on a hidden ordinary case.
MOST_FIXED = 0.6


def _hidden_ordinary(cases):
    return [i for i, c in enumerate(cases) if not c.visible and c.raises is None]


@pytest.mark.slow
@pytest.mark.parametrize("name", FUNCTIONS)
def test_every_hidden_ordinary_answer_depends_on_the_draw(name):
    ex = REGISTRY[name]
    reference = _memoised(ex)
    per_case: list[list] = []                   # per hidden ordinary case, its answer per draw
    labels = None
    for seed in range(ANSWER_DRAWS):
        cases = ex.draw_cases(np.random.default_rng(seed))
        hidden = [cases[i] for i in _hidden_ordinary(cases)]
        labels = labels or [c.label for c in hidden]
        assert len(hidden) == len(labels), f"{name}: the number of hidden cases varies"
        for k, case in enumerate(hidden):
            if seed == 0:
                per_case.append([])
            per_case[k].append(reference(case))
    fixed = [f"{labels[k]!r}: one answer passes {share:.0%} of {ANSWER_DRAWS} draws"
             for k, answers in enumerate(per_case)
             if (share := _best_fixed_share(ex, answers)) > MOST_FIXED]
    assert not fixed, f"{name}: hidden cases answerable without the maths: {fixed}"


def _memoised(ex):
    """``ex.expected`` with one object per distinct input (the answers of equal inputs are then
    the same object, judged once)."""
    memo: dict[bytes, object] = {}

    def expected(case):
        key = pickle.dumps((case.args, case.kwargs))
        if key not in memo:
            memo[key] = ex.expected(case)
        return memo[key]
    return expected


def _best_fixed_share(ex, answers) -> float:
    """The largest share of ``answers`` that one of the first :data:`CANDIDATES` of them passes
    by the exercise's own rule (what a function returning it at that call would earn), counted
    only as far as needed to tell whether it exceeds :data:`MOST_FIXED`."""
    distinct: dict[int, list] = {}
    for a in answers:
        distinct.setdefault(id(a), [a, 0])[1] += 1
    enough = (1.0 - MOST_FIXED) * len(answers)
    best = 0
    for candidate in {id(a): a for a in answers[:CANDIDATES]}.values():
        passed = failed = 0
        for a, n in distinct.values():
            if ex.compare(a, candidate) is None:
                passed += n
            else:
                failed += n
            if failed > enough:                 # it cannot pass more than MOST_FIXED
                break
        best = max(best, passed)
    return best / len(answers)


@pytest.mark.parametrize("name", FUNCTIONS)
def test_hidden_cases_run_shuffled_with_the_bad_input_among_them(name):
    ex = REGISTRY[name]
    generated = ex.draw_cases(np.random.default_rng(0))
    visible = [c.label for c in generated if c.visible]
    n_hidden = len(generated) - len(visible)
    n_bad = sum(c.raises is not None for c in generated if not c.visible)
    bad_at = np.zeros(n_hidden)
    orders = set()
    draws = ORDER_DRAWS if n_hidden > 1 else 1
    for seed in range(draws):
        cases = [d.case for d in _order_only(ex, seed)]
        assert [c.label for c in cases[:len(visible)]] == visible, "visible cases run first"
        hidden = cases[len(visible):]
        assert not any(c.visible for c in hidden)
        bad_at += [c.raises is not None for c in hidden]
        orders.add(tuple((c.label, c.raises) for c in hidden))
    if len({(c.label, c.raises) for c in generated if not c.visible}) > 1:
        assert len(orders) > 1, f"{name}: the hidden cases always run in one order"
    if n_bad:
        # a uniform shuffle puts a bad-input case at each position n_bad / n_hidden of the time;
        # 5 standard deviations either side, at 2000 draws
        p = n_bad / n_hidden
        spread = 5 * np.sqrt(p * (1 - p) / draws) + 1e-12
        share = bad_at / draws
        assert np.all(np.abs(share - p) <= spread), (
            f"{name}: bad-input cases are not spread over the hidden positions: {share}, "
            f"expected {p:.3f}")


def _order_only(ex, seed):
    """``draw``'s list for ``ex`` with a reference that computes nothing (only the order of the
    cases is looked at)."""
    return draw(dataclasses.replace(ex, reference=lambda *args, **kwargs: 0.0), seed)
