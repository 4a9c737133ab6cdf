"""The feedback page's table of visible cases: large array inputs (a marching-cubes volume) are
summarised by shape and a few values, and a rule that ignores an order says so under the table,
so a passed answer listed in another order than the expected one does not look wrong.

Oracles: the registry's own visible cases and reference answers, and the mesh re-listed here in
another vertex and triangle order (the same surface, by construction)."""

from __future__ import annotations

import html
import re

import numpy as np

from autograder.exercises import REGISTRY
from autograder.model import CaseRecord, CellKind, CellResult, Status, Verdict
from autograder.outputs import feedback
from autograder.outputs.html import value_text


def _relisted(mesh, rng):
    """The same mesh with its vertices and triangles listed in another order, and each
    triangle started at another vertex (winding kept)."""
    verts, faces = mesh
    perm = rng.permutation(len(verts))
    new_index = np.empty_like(perm)
    new_index[perm] = np.arange(len(perm))
    faces = new_index[faces][rng.permutation(len(faces))]
    return verts[perm], np.roll(faces, 1, axis=1)


def _page(name, cases, received_of):
    ex = REGISTRY[name]
    rows = [CaseRecord(index=k, label=c.label, visible=True, verdict=Verdict.PASS,
                       args=c.args, kwargs=c.kwargs, expected=ex.expected(c),
                       received=received_of(ex.expected(c)))
            for k, c in enumerate(cases)]
    result = CellResult(student="s001", notebook=ex.notebook, grade_id=name, name=name,
                        score=1.0, max_score=1.0, status=Status.OK, message="all cases passed",
                        kind=CellKind.FUNCTION, cases=rows)
    return html.unescape(feedback.render("s001", ex.notebook, [result], reveal_hidden=False))


def test_a_volume_input_is_summarised_and_the_mesh_order_note_is_shown():
    ex = REGISTRY["marching_cubes"]
    visible = [c for c in ex.draw_cases(np.random.default_rng(0)) if c.visible and not c.raises]
    volume = next(c for c in visible if c.args[0].shape == (7, 7, 7))
    rng = np.random.default_rng(1)
    received = _relisted(ex.expected(volume), rng)
    assert ex.compare(ex.expected(volume), received) is None      # the rule ignores the order
    assert not np.array_equal(received[1], ex.expected(volume)[1])
    page = _page("marching_cubes", [volume], lambda expected: received)
    row = re.search(r"<td><pre>(.*?)</pre></td>", page, re.S).group(1)
    assert "array of shape (7, 7, 7)" in row and "float64" in row
    assert row.count("\n") == 0 and len(row) < 300, row            # one line, not 343 numbers
    lo, hi = float(volume.args[0].min()), float(volume.args[0].max())
    assert f"from {lo:.6g} to {hi:.6g}" in row
    assert "compared with the expected one up to vertex order, triangle order" in page


def test_a_rule_that_compares_in_order_adds_no_note_and_small_arrays_print_in_full():
    ex = REGISTRY["end_rows"]
    visible = [c for c in ex.draw_cases(np.random.default_rng(0)) if c.visible and not c.raises]
    page = _page("end_rows", visible[:1], lambda expected: expected)
    assert "up to" not in page.split("<table>", 1)[1]
    small = np.arange(12.0).reshape(4, 3)
    assert "11." in value_text(small) and "array of shape" not in value_text(small)


def test_every_order_free_rule_says_what_it_ignores():
    """The registry's rules that accept another order name it (the wording the page shows)."""
    order_free = {"marching_cubes", "alternative_triangulation", "ring_hole_positions",
                  "clip_polygon"}
    for name in order_free:
        assert REGISTRY[name].compared_up_to, name
    rng = np.random.default_rng(2)
    pts = REGISTRY["ring_hole_positions"]
    case = next(c for c in pts.draw_cases(rng) if c.visible and not c.raises)
    expected = pts.expected(case)
    assert pts.compare(expected, expected[::-1].copy()) is None    # another order passes
