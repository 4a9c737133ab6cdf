"""Marks by position (issue 33, finding 1), graded by the real ``python -m autograder grade``.

A determined student who reads the registry's source (it is public) writes every graded
function of the six blank release notebooks as a counter of its calls: call k returns what
the k-th case most often wants over the student's own draws of the public generators (through
the grader's own :func:`autograder.grade.cases.draw`, with seeds of the student's choosing):
the visible cases' public answers, ``ValueError`` where bad inputs usually run, and the
answers of hidden cases that do not depend on the draw. No maths, no import of the course.

Against the generators and order of the release before issue 33 this scored 12.6 of the 64
automatic points (9.9 from the visible cases alone). Now the hidden cases run shuffled, every
hidden ordinary answer depends on the draw, and the visible and bad-input cases count only in
proportion to the hidden ordinary cases passed (``judging.withheld_passes``): what is left is
what a guess of a True/False or an empty result earns. The bound below is that guess's
expected score plus its spread (:func:`test_the_bound_holds_over_draws` measures it with the
attacker's own table against many seeds, judged by each exercise's rule).

An honest student (the model answers) graded in the same batch keeps full marks.
"""

from __future__ import annotations

import collections
import pickle

import numpy as np
import pytest
from gradingtools import (SECRET, course_sources, model_version, points_of, read_grades,
                          release_version, run_grade, set_cell, write_nb)

from autograder.exercises import REGISTRY
from autograder.grade.cases import draw
from autograder.model import CellKind

pytestmark = [pytest.mark.xdist_group("attacks")]

SOURCES = course_sources()
#: The student's own draws of the public generators, from which the positional table is read.
OWN_DRAWS = 40
#: Answers whose literal is longer than this are left out (a solution cell holds 100 kB).
LONGEST_LITERAL = 20_000
#: At most this many of the 64 automatic points (see :func:`test_the_bound_holds_over_draws`).
BOUND = 3.0


def _functions(src):
    return [n for n, _, _ in src.graded if n in REGISTRY and REGISTRY[n].kind is CellKind.FUNCTION]


def _key(value):
    return pickle.dumps(value)


def positional_table(name: str) -> list:
    """Per call k, what the k-th case most often wants over :data:`OWN_DRAWS` draws:
    ``("raise",)`` or ``("return", answer)``."""
    ex = REGISTRY[name]
    per_call: dict[int, collections.Counter] = collections.defaultdict(collections.Counter)
    answers = {}
    for seed in range(10**6, 10**6 + OWN_DRAWS):
        for k, d in enumerate(draw(ex, seed)):
            key = ("raise",) if d.case.raises is not None else _key(d.expected)
            answers[key] = d.expected
            per_call[k][key] += 1
    table = []
    for k in range(len(per_call)):
        key, _ = per_call[k].most_common(1)[0]
        table.append(("raise",) if key == ("raise",) else ("return", answers[key]))
    return table


def literal(value) -> str:
    """Python source that rebuilds the plain value ``value`` with NumPy only."""
    if isinstance(value, np.ndarray):
        return (f"np.array({value.tolist()!r}, dtype={str(value.dtype)!r})"
                f".reshape({tuple(value.shape)!r})")
    if isinstance(value, tuple):
        return "(" + "".join(literal(v) + ", " for v in value) + ")"
    if isinstance(value, float) and not np.isfinite(value):
        return f"float({str(value)!r})"
    return repr(value)


def positional_cell(name: str) -> str:
    """The solution cell of ``name`` that answers by counting its calls."""
    rows = []
    for entry in positional_table(name):
        text = "None" if entry[0] == "raise" else literal(entry[1])
        rows.append("    'raise',\n" if entry[0] == "raise" else
                    f"    {text if len(text) <= LONGEST_LITERAL else 'None'},\n")
    return (f"import numpy as np\n\n_TABLE_{name} = [\n{''.join(rows)}]\n_CALLS_{name} = [0]\n\n\n"
            f"def {name}(*args, **kwargs):\n"
            f"    k = _CALLS_{name}[0]\n"
            f"    _CALLS_{name}[0] += 1\n"
            f"    answer = _TABLE_{name}[k] if k < len(_TABLE_{name}) else 'raise'\n"
            f"    if isinstance(answer, str) and answer == 'raise':\n"
            f"        raise ValueError('by position')\n"
            f"    return answer\n")


def positional_notebook(src) -> dict:
    nb = release_version(src)
    for name in _functions(src):
        set_cell(nb, name, positional_cell(name))
    return nb


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    if not SOURCES:
        pytest.skip("no source notebooks with registered exercises yet")
    root = tmp_path_factory.mktemp("positional")
    for src in SOURCES:
        write_nb(root / "submitted" / "rt_positional" / "tripos2006" / f"{src.name}.ipynb",
                 positional_notebook(src))
        write_nb(root / "submitted" / "honest" / "tripos2006" / f"{src.name}.ipynb",
                 model_version(src))
    (root / "secret").write_bytes(SECRET + b"\n")
    run_grade(root / "submitted", root / "out", "--no-gradebook", secret_file=root / "secret")
    return read_grades(root / "out")


def _function_scores(rows, student):
    out = {}
    for src in SOURCES:
        for name in _functions(src):
            row = rows[(student, src.name, f"test_{name}")]
            out[name] = (float(row["score"]), points_of(src, name), row["status"])
    return out


def test_answering_by_position_earns_next_to_nothing(graded):
    scores = _function_scores(graded, "rt_positional")
    total = sum(s for s, _, _ in scores.values())
    available = sum(p for _, p, _ in scores.values())
    earned = {n: s for n, (s, _, _) in scores.items() if s > 0}
    assert total <= BOUND, (f"answering by position scored {total:.2f} of {available:g} "
                            f"automatic points: {earned}")


def test_the_honest_student_beside_it_keeps_full_marks(graded):
    scores = _function_scores(graded, "honest")
    lost = {n: (s, p, st) for n, (s, p, st) in scores.items() if s != pytest.approx(p, abs=1e-6)}
    assert not lost, f"model answers lost marks: {lost}"


@pytest.mark.slow
def test_the_bound_holds_over_draws():
    """:data:`BOUND` against the attacker's expected score: its table against 200 draws of each
    function, each case judged by the exercise's rule and the cell scored by the rule the
    notebooks state (visible and bad-input cases in proportion to the hidden ordinary ones)."""
    expected_total = 0.0
    spread = 0.0
    for src in SOURCES:
        for name in _functions(src):
            ex, points = REGISTRY[name], points_of(src, name)
            table = positional_table(name)
            scores = []
            for seed in range(200):
                drawn = draw(ex, seed)
                passes = [_passes(ex, d, table[k] if k < len(table) else ("raise",))
                          for k, d in enumerate(drawn)]
                scores.append(points * _counted(drawn, passes) / len(drawn))
            expected_total += float(np.mean(scores))
            spread += float(np.var(scores))
    bound = expected_total + 4 * np.sqrt(spread)
    assert bound <= BOUND, (f"the positional attacker's expected score is {expected_total:.2f}, "
                            f"its 4-sigma bound {bound:.2f} > {BOUND}")


def _passes(ex, d, entry) -> bool:
    if d.case.raises is not None:
        return entry[0] == "raise"
    return entry[0] == "return" and ex.compare(d.expected, entry[1]) is None


def _counted(drawn, passes) -> float:
    """Cases that count: hidden ordinary passes, plus the visible and bad-input passes times
    the share of hidden ordinary cases passed (the visible ones give the share if none is
    hidden, and then only the bad-input cases are scaled)."""
    hidden = [p for d, p in zip(drawn, passes) if d.case.raises is None and not d.case.visible]
    ordinary = [p for d, p in zip(drawn, passes) if d.case.raises is None]
    if hidden:
        share = sum(hidden) / len(hidden)
        scaled = [p for d, p in zip(drawn, passes) if d.case.raises is not None or d.case.visible]
        return sum(hidden) + sum(scaled) * share
    share = sum(ordinary) / len(ordinary) if ordinary else 1.0
    return sum(ordinary) + sum(p for d, p in zip(drawn, passes) if d.case.raises) * share
