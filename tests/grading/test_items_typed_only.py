"""Choice and number items are judged on the literal typed in their own cell, and on nothing
the student's code computes (issue 33, finding 2).

The attack, rebuilt from the release: every item cell left exactly as released, and ONE later
solution cell (``attacks/items_elsewhere.txt``) that computes the reader's own letters from the
canonical key and the public option-order code, for whoever is graded. On main two students with
different letter orders scored 21 of 21 choice points with the same notebook text; the per-student
shuffle was worth nothing. Graded by the real ``grade``; an honest student who types the letters
shown to them in the item cells scores them, in the same batch.
"""

from __future__ import annotations

import ast
import re

import numpy as np
import pytest
from attacks.builders import payload
from gradingtools import (course_sources, read_grades, release_version, run_grade, set_cell,
                          write_nb)

from autograder.exercises import REGISTRY
from autograder.grade.planning import NOT_TYPED, typed_answer
from autograder.model import CellKind
from course_lib import variants

ATTACKERS = ("rt_items_a", "rt_items_b")
HONEST = "rt_items_typed"


def _items(src, kind: CellKind) -> list[tuple[str, str, float]]:
    return [(name, test_id, points) for name, test_id, points in src.graded
            if name in REGISTRY and REGISTRY[name].kind is kind]


def _keys(src) -> dict[str, tuple[str, int]]:
    """Each choice item's key in the canonical order and its number of options: what the
    attacker knows (a friend's notebook or the instructors' copy says it)."""
    return {name: (REGISTRY[name].key_for(None), len(REGISTRY[name].options))
            for name, _, _ in _items(src, CellKind.CHOICE)}


def _attack(src) -> str:
    return payload("items_elsewhere.txt", keys=repr(_keys(src)))


def _last_function(src, nb) -> str:
    """The graded function whose solution cell comes last in the notebook."""
    functions = {name for name, _, _ in _items(src, CellKind.FUNCTION)}
    cells = [(c.get("metadata", {}).get("nbgrader") or {}).get("grade_id") for c in nb["cells"]]
    return [gid for gid in cells if gid in functions][-1]


def attacked(src) -> dict:
    """The release notebook, items untouched, the attack appended to its last function's cell
    (after the released stub, which defines the function without raising)."""
    nb = release_version(src)
    name = _last_function(src, nb)
    cell = next(c for c in nb["cells"]
                if (c.get("metadata", {}).get("nbgrader") or {}).get("grade_id") == name)
    cell["source"] = "".join(cell["source"]).rstrip("\n") + "\n" + _attack(src)
    return nb


def typed(src, student: str) -> dict:
    """The release notebook with every item typed right, in its own cell, for ``student``."""
    nb = release_version(src)
    for name, _, _ in _items(src, CellKind.CHOICE) + _items(src, CellKind.VALUE):
        ex = REGISTRY[name]
        answer = ex.key_for(student) if ex.kind is CellKind.CHOICE else ex.value_for(student)
        answer = answer.tolist() if isinstance(answer, np.ndarray) else answer
        set_cell(nb, name, f"{name} = {answer!r}\n")
    return nb


SOURCES = [s for s in course_sources() if _items(s, CellKind.CHOICE)]


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    if not SOURCES:
        pytest.skip("no source notebooks with choice items")
    root = tmp_path_factory.mktemp("items-elsewhere")
    sub = root / "submitted"
    for src in SOURCES:
        for student in ATTACKERS:
            write_nb(sub / student / "tripos2006" / f"{src.name}.ipynb", attacked(src),
                     type_answers=False)
        write_nb(sub / HONEST / "tripos2006" / f"{src.name}.ipynb", typed(src, HONEST),
                 type_answers=False)
    run_grade(sub, root / "out", "--no-gradebook")
    return read_grades(root / "out")


def test_the_attack_computes_each_readers_own_letters(monkeypatch):
    """The payload is the option-order code: run here, it gives ``variants.displayed_letters``,
    and the two attackers' letters differ (the shuffle is what the attack defeats)."""
    differ = False
    for src in SOURCES:
        seen = {}
        for student in ATTACKERS:
            monkeypatch.setenv("JUPYTERHUB_USER", student)
            ns: dict = {}
            exec(_attack(src), ns)
            for name, (key, n) in _keys(src).items():
                assert ns[name] == variants.displayed_letters(name, key, n, student)
            seen[student] = {name: ns[name] for name in _keys(src)}
        differ |= seen[ATTACKERS[0]] != seen[ATTACKERS[1]]
    assert differ


@pytest.mark.parametrize("student", ATTACKERS)
def test_items_set_by_a_later_cell_score_nothing(graded, student):
    rows = {(src.name, name): graded[(student, src.name, test_id)] for src in SOURCES
            for kind in (CellKind.CHOICE, CellKind.VALUE) for name, test_id, _ in _items(src, kind)}
    scored = {item: float(r["score"]) for item, r in rows.items() if float(r["score"]) != 0.0}
    assert not scored, f"{sum(scored.values()):g} points for items no cell of theirs typed"
    for item, row in rows.items():
        assert row["status"] == "unanswered", (item, row["message"])
        assert "still the released stub" in row["message"], (item, row["message"])


def test_items_typed_in_their_own_cells_score(graded):
    """The control, in the same batch: the letters and numbers shown to the student, typed in
    the item cells, earn every item's points (so the 0 above is the attack's, not the batch's)."""
    full = 0.0
    for src in SOURCES:
        for name, test_id, points in _items(src, CellKind.CHOICE) + _items(src, CellKind.VALUE):
            row = graded[(HONEST, src.name, test_id)]
            assert row["status"] == "ok", (name, row["message"])
            assert float(row["score"]) == pytest.approx(points, abs=1e-9), name
            full += points
    assert full > 0


def test_items_never_reach_the_sandbox(tmp_path):
    """Every item's row is decided when the notebook is read; its job holds functions only."""
    from autograder.grade.batch import Options, _read_and_prepare

    src = SOURCES[0]
    write_nb(tmp_path / ATTACKERS[0] / "tripos2006" / f"{src.name}.ipynb", attacked(src),
             type_answers=False)
    read = _read_and_prepare(tmp_path, ATTACKERS[0], src, Options(out=tmp_path / "out"))
    items = {t for _, t, _ in _items(src, CellKind.CHOICE) + _items(src, CellKind.VALUE)}
    assert items <= {row.grade_id for row in read.rows}
    assert read.work is not None and {t.test_id for t in read.work.names}.isdisjoint(items)
    assert {t.test_id for t in read.work.names} == {t for _, t, _ in
                                                    _items(src, CellKind.FUNCTION)}


def _tupled(value):
    return tuple(_tupled(v) for v in value) if isinstance(value, list) else value


def test_every_form_the_notebooks_show_is_read_as_typed():
    """The forms each item's prompt tells students to type (``q2c_your_length = 123.4``,
    ``q6bi_your_inside = [True, False, True]``, a choice's ``"a, b"``), typed in the item's
    cell, are read as those literals; the forms come from the notebooks' own text."""
    items = {name for src in course_sources() for kind in (CellKind.CHOICE, CellKind.VALUE)
             for name, _, _ in _items(src, kind)}
    shown = set()
    for src in course_sources():
        for cell in src.nb["cells"]:
            text = "".join(cell["source"]) if cell["cell_type"] == "markdown" else ""
            forms = re.findall(r"`(\w+) = ([^`]+)`", text)
            forms += re.findall(r"Set `(\w+)` to[^`]*`(\"[^`]*\")`", text)
            for name, example in forms:
                if name in items:
                    typed = typed_answer(f"# my answer\n{name} = {example}\n", name)
                    assert typed is not NOT_TYPED and typed == _tupled(ast.literal_eval(example))
                    shown.add(name)
    value_items = {n for n in items if REGISTRY[n].kind is CellKind.VALUE}
    assert value_items <= shown and len(shown - value_items) >= 10


def test_a_number_no_page_can_print_is_not_a_typed_answer():
    """A 3,700-digit literal typed as a number item (a red team's) is read as nothing typed, as
    the sandbox refuses such an int: ``str()`` of it raises, and the report printed it."""
    from autograder.grade.planning import NOT_TYPED, typed_answer
    from autograder.isolation.inside.wire import MAX_INT_BITS

    huge = "0x" + "f" * 3700
    assert typed_answer(f"q5b_your_intensity = [{huge}, 1.0, 1.0]", "q5b_your_intensity") \
        is NOT_TYPED
    assert typed_answer(f"x = {2 ** MAX_INT_BITS - 1}", "x") == 2 ** MAX_INT_BITS - 1
    assert typed_answer(f"x = {2 ** MAX_INT_BITS}", "x") is NOT_TYPED
