"""autograder.outputs.similarity (issue 11, part 3): near copies between students and pasted references.

The oracles are independent of the module: copies are made here by rewriting a cell's syntax
tree (every name the author chose renamed, helpers re-ordered, layout from ``ast.unparse``,
comments added), honest code comes from ``tests/grading/honest`` (written from the exam, not
from course_lib) and the model answers of the source notebooks, and the inverted index is
checked against a brute-force comparison of every pair.
"""

from __future__ import annotations

import ast
import builtins
import inspect
import json
import random
import re
from itertools import combinations
from pathlib import Path

import numpy as np
import pytest

from autograder.outputs import similarity as sim
from autograder.exercises import REGISTRY

REPO = Path(__file__).resolve().parents[2]
HONEST = Path(__file__).parent / "honest"
_MARKER = re.compile(r"^[ \t]*### (BEGIN|END) SOLUTION[^\n]*\n?", re.M)
_KEEP = set(dir(builtins)) | {"np", "math", "itertools"}   # imports of the setup cells


# --------------------------------------------------------------------------------------------
# the course's own code


def _functions() -> list[str]:
    return sorted(n for n, ex in REGISTRY.items() if ex.kind == "function")


def model_answers() -> dict[str, str]:
    """``{name: solution cell}`` of the source notebooks, solution markers removed."""
    out = {}
    for path in sorted((REPO / "notebooks").glob("q[0-9]*_*.ipynb")):
        for cell in json.loads(path.read_text(encoding="utf-8"))["cells"]:
            meta = cell.get("metadata", {}).get("nbgrader", {})
            if meta.get("solution") and cell["cell_type"] == "code" \
                    and meta.get("grade_id") in _functions():
                out[meta["grade_id"]] = _MARKER.sub("", "".join(cell["source"]))
    return out


def honest_answers() -> dict[str, str]:
    """``{name: the def of that name}`` from tests/grading/honest/*.py."""
    out = {}
    for path in sorted(HONEST.glob("q*.py")):
        text = path.read_text(encoding="utf-8")
        for node in ast.parse(text).body:
            if isinstance(node, ast.FunctionDef) and node.name in _functions():
                out[node.name] = ast.get_source_segment(text, node)
    return out


def long_enough(source: str) -> bool:
    return len(sim.normalise(source)) >= sim.MIN_TOKENS


# --------------------------------------------------------------------------------------------
# a copier


class _Rename(ast.NodeTransformer):
    """Renames every identifier the author chose, consistently, to a name of the copier's."""

    def __init__(self, seed: int):
        self.names: dict[str, str] = {}
        self.rng = random.Random(seed)

    def new(self, name: str) -> str:
        if name in _KEEP:
            return name
        if name not in self.names:
            self.names[name] = f"{self.rng.choice(['my', 'tmp', 'val', 'q'])}_{len(self.names)}"
        return self.names[name]

    def visit_Name(self, node):
        node.id = self.new(node.id)
        return node

    def visit_arg(self, node):
        node.arg = self.new(node.arg)
        return node

    def visit_FunctionDef(self, node):
        node.name = self.new(node.name)
        self.generic_visit(node)
        return node


def disguise(source: str, seed: int = 0) -> str:
    """A copy as a student hides it: names changed, top-level definitions in reverse order,
    docstrings dropped, the layout of ``ast.unparse`` and a comment after every other line."""
    tree = _Rename(seed).visit(ast.parse(source))
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr) \
                and isinstance(body[0].value, ast.Constant) and len(body) > 1:
            del body[0]
    tree.body.reverse()
    lines = ast.unparse(tree).splitlines()
    return "\n".join(f"{line}  # step {i}" if i % 2 and line.strip() else line
                     for i, line in enumerate(lines)) + "\n"


HAND_WRITTEN = '''
def _unit(v):
    v = np.asarray(v, dtype=float)
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    if np.any(n == 0):
        raise ValueError("zero-length vector")
    return v / n


def ring_hole_positions(pitch, n_rings):
    if pitch <= 0 or n_rings < 0 or int(n_rings) != n_rings:
        raise ValueError("pitch must be positive and n_rings a non-negative integer")
    centres = [np.zeros(2)]
    for k in range(1, int(n_rings) + 1):
        angles = 2 * np.pi * np.arange(8 * k) / (8 * k)
        centres.append(k * pitch * np.stack([np.cos(angles), np.sin(angles)], axis=1))
    return np.vstack(centres)
'''

HAND_COPIED = '''
# ring k has 8k holes on radius k * pitch
def ring_hole_positions(p, rings):
    """Hole centres of the collimator, Q2."""
    if p <= 0 or rings < 0 or int(rings) != rings:
        raise ValueError("bad pitch or number of rings")   # the contract's error
    pts = [np.zeros(2)]
    for ring in range(1, int(rings) + 1):
        theta = 2 * np.pi * np.arange(8 * ring) / (8 * ring)   # evenly spaced, first at 0
        pts.append(ring * p * np.stack([np.cos(theta),
                                        np.sin(theta)], axis=1))
    return np.vstack(pts)

def _direction(vec):
    vec = np.asarray(vec, dtype=float)
    length = np.linalg.norm(vec, axis=-1, keepdims=True)
    if np.any(length == 0): raise ValueError("no direction")
    return vec / length
'''


# --------------------------------------------------------------------------------------------
# the three cases


def test_a_hand_copied_pair_is_flagged_and_its_lines_marked():
    cells = {"alice": {"ring_hole_positions": HAND_WRITTEN},
             "bob": {"ring_hole_positions": HAND_COPIED}}
    found = sim.find_similar(cells)
    assert [(m.left, m.right, m.name) for m in found] == [("alice", "bob", "ring_hole_positions")]
    assert found[0].score >= sim.THRESHOLD
    # the loop and the re-ordered helper are marked on both sides, the added docstring is not
    def line_of(source, text):
        return next(n for n, line in enumerate(source.splitlines(), 1) if text in line)

    m = found[0]
    assert {line_of(HAND_WRITTEN, "np.arange(8 * k)"), line_of(HAND_WRITTEN, "return v / n")} \
        <= m.left_lines
    assert {line_of(HAND_COPIED, "np.arange(8 * ring)"), line_of(HAND_COPIED, "return vec / ")} \
        <= m.right_lines
    assert line_of(HAND_COPIED, "Hole centres") not in m.right_lines


@pytest.mark.parametrize("seed", [0, 1])
def test_a_disguised_copy_of_every_long_model_answer_is_flagged(seed):
    models = {n: s for n, s in model_answers().items() if long_enough(s)}
    assert len(models) >= 20
    cells = {"author": models, "copier": {n: disguise(s, seed) for n, s in models.items()}}
    found = {m.name: m for m in sim.find_similar(cells)}
    assert set(found) == set(models)
    assert all((m.left, m.right) == ("author", "copier") for m in found.values())
    # a rename, a re-order and comments change nothing the normaliser keeps
    assert min(m.score for m in found.values()) == pytest.approx(1.0)


def test_a_pasted_reference_is_flagged_even_with_extra_code_around_it():
    refs = {n: sim.reference_source(REGISTRY[n].reference) for n in _functions()}
    pasted = {n: "import math\n\n" + disguise(s, 3) + "\n\ndef _extra(x):\n    return x * 2\n"
              for n, s in refs.items() if long_enough(s)}
    assert len(pasted) >= 15
    found = sim.find_similar({"paster": pasted}, refs)
    assert {m.name for m in found} == set(pasted)
    assert all(m.is_reference and m.left == "paster" for m in found)
    assert min(m.score for m in found) >= 0.9, sorted((round(m.score, 2), m.name) for m in found)


def test_honest_solutions_and_model_answers_are_not_flagged_against_each_other():
    """Written independently (tests/grading/honest from the exam alone): no pair, and neither
    looks like a pasted course_lib reference."""
    honest, model = honest_answers(), model_answers()
    assert set(honest) == set(model) == set(_functions())
    refs = {n: sim.reference_source(REGISTRY[n].reference) for n in _functions()}
    found = sim.find_similar({"honest": honest, "model": model}, refs)
    assert found == [], [(m.name, m.left, m.right, round(m.score, 2)) for m in found]


def test_cells_too_short_to_tell_are_never_flagged():
    short = "def normalize(v):\n    v = np.asarray(v, dtype=float)\n" \
            "    return v / np.linalg.norm(v, axis=-1, keepdims=True)\n"
    basis = ("def bspline_basis():\n    return np.array([[-1, 3, -3, 1], [3, -6, 3, 0], "
             "[-3, 0, 3, 0], [1, 4, 1, 0]]) / 6.0\n")
    cells = {s: {"normalize": short, "bspline_basis": basis} for s in ("a", "b", "c")}
    assert sim.find_similar(cells, {"normalize": short}) == []
    # the same cells are flagged once the minimum length allows them
    assert len(sim.find_similar(cells, min_tokens=10)) == 6


# --------------------------------------------------------------------------------------------
# normalising and fingerprints


def test_names_comments_docstrings_and_layout_do_not_change_the_token_stream():
    a = "def f(x, y):\n    '''Doc.'''\n    z = np.sum(x * y, axis=-1)  # dot\n    return z + 1\n"
    b = "def g(p,q):\n    # dot product\n    r = np.sum(\n        p*q,\n        axis=-1)\n    return r+1\n"
    assert [t for t, _ in sim.normalise(a)] == [t for t, _ in sim.normalise(b)]
    # an attribute, a keyword, a number or a builtin is kept
    for changed in (b.replace("np.sum", "np.prod"), b.replace("axis=-1", "axis=0"),
                    b.replace("r+1", "r+2"), b.replace("r = np.sum", "r = sum")):
        assert [t for t, _ in sim.normalise(changed)] != [t for t, _ in sim.normalise(b)]


def test_reordered_top_level_definitions_give_the_same_stream():
    one = "def _h(x):\n    return x + 1\n\ndef f(x):\n    return _h(x) * 2\n"
    two = "def f(y):\n    return _g(y) * 2\n\ndef _g(y):\n    return y + 1\n"
    assert [t for t, _ in sim.normalise(one)] == [t for t, _ in sim.normalise(two)]


def test_unparsable_cells_and_magics():
    assert sim.normalise("def f(:\n") == []
    assert sim.fingerprint("def f(:\n") is None
    with_magic = "%matplotlib widget\nx = 1\n"
    assert [t for t, _ in sim.normalise(with_magic)] == [t for t, _ in sim.normalise("\nx = 1\n")]
    continued = "ok = (a\n      != b)\n"          # a line starting with "!" that is no magic
    assert [t for t, _ in sim.normalise(continued)] == [t for t, _ in sim.normalise("ok = a != b")]
    with pytest.raises(ValueError, match="source"):
        sim.normalise(None)


def test_deeply_nested_or_huge_cells_do_not_break_the_report():
    deep = "x = " + "(" * 3000 + "1" + ")" * 3000 + "\n"     # beyond the parser's nesting
    chain = "x = 1" + " + 1" * 50000 + "\n"                    # beyond the compiler's recursion
    assert sim.normalise(deep) == [] and sim.normalise(chain) == []
    long_sum = "x = 1" + " + y" * 900 + "\n"      # parses: 900 nested BinOps, no recursion here
    assert len(sim.normalise(long_sum)) > 900 * 4
    found = sim.find_similar({"a": {"f": deep}, "b": {"f": long_sum}, "c": {"f": long_sum}})
    assert [(m.left, m.right) for m in found] == [("b", "c")]


def test_fingerprints_in_two_processes_are_those_of_one():
    cells = _class_of(120, seed=4)
    sources = [c["clip_polygon"] for c in cells.values()]
    both = sim.fingerprint_all(sources, jobs=2)
    assert len(both) == len(set(sources)) >= 100
    for src in sources[:10]:
        alone = sim.fingerprint(src)
        assert np.array_equal(both[src].prints, alone.prints)
        assert np.array_equal(both[src].token_lines, alone.token_lines)


def test_winnowing_guarantee_a_shared_run_of_k_plus_window_minus_one_tokens():
    """Schleimer et al.'s guarantee: any shared run of k + w - 1 tokens gives a shared
    fingerprint, whatever code surrounds it (checked on random surroundings)."""
    rng = random.Random(5)
    core = model_answers()["scanline_span"]
    for _ in range(20):
        pre = "\n".join(f"a{i} = {rng.randint(0, 99)} * b{i}" for i in range(rng.randint(1, 6)))
        post = "\n".join(f"c{i} = d{i} - {rng.random():.3f}" for i in range(rng.randint(1, 6)))
        a = sim.fingerprint(pre + "\n" + core)
        b = sim.fingerprint(core + "\n" + post)
        assert np.intersect1d(a.prints, b.prints).size > 0


def test_scores_against_python_sets():
    models = model_answers()
    fa, fb = sim.fingerprint(models["phong"]), sim.fingerprint(models["blinn_phong"])
    sa, sb = set(fa.prints.tolist()), set(fb.prints.tolist())
    assert sim.jaccard(fa, fb) == pytest.approx(len(sa & sb) / len(sa | sb))
    assert sim.containment(fa, fb) == pytest.approx(len(sa & sb) / len(sa))
    assert sim.jaccard(fa, fa) == pytest.approx(1.0)


def test_reference_source_brings_the_private_helpers_it_calls():
    src = sim.reference_source(REGISTRY["phong"].reference)
    defined = {n.name for n in ast.parse(src).body if isinstance(n, ast.FunctionDef)}
    called = {n.func.id for n in ast.walk(ast.parse(src))
              if isinstance(n, ast.Call) and isinstance(n.func, ast.Name)}
    module = inspect.getmodule(REGISTRY["phong"].reference)
    private_here = {c for c in called if c.startswith("_") and inspect.isfunction(
        getattr(module, c, None)) and inspect.getmodule(getattr(module, c)) is module}
    assert "phong" in defined and private_here and private_here <= defined
    with pytest.raises(ValueError, match="function"):
        sim.reference_source(42)


# --------------------------------------------------------------------------------------------
# the inverted index against all pairs


def _class_of(n_students: int, seed: int) -> dict[str, dict[str, str]]:
    """Students writing the same function differently (random statements mixed into the model
    answer), one pair of whom copied."""
    rng = random.Random(seed)
    base = model_answers()["clip_polygon"]
    lines = base.splitlines()
    starts = sorted({(n.lineno - 1, n.col_offset) for n in ast.walk(ast.parse(base))
                     if isinstance(n, ast.stmt) and n.col_offset > 0})   # statements in bodies
    cells = {}
    for s in range(n_students):
        mine = list(lines)
        for at, col in sorted(rng.sample(starts, rng.randint(3, 12)), reverse=True):
            mine.insert(at, f"{' ' * col}w{s} = {rng.randint(0, 999)} * {rng.random():.4f}")
        cells[f"s{s:03d}"] = {"clip_polygon": "\n".join(mine) + "\n"}
    cells["s999"] = {"clip_polygon": disguise(cells["s005"]["clip_polygon"], 9)}
    return cells


def test_the_inverted_index_finds_what_all_pairs_find():
    cells = _class_of(60, seed=2)
    for threshold in (0.5, sim.THRESHOLD):
        found = {(m.left, m.right) for m in sim.find_similar(cells, threshold=threshold)}
        prints = {s: sim.fingerprint(c["clip_polygon"]) for s, c in cells.items()}
        brute = {(a, b) for a, b in combinations(sorted(prints), 2)
                 if sim.jaccard(prints[a], prints[b]) >= threshold}
        assert found == brute
    assert ("s005", "s999") in found


def test_shared_counts_against_python_set_intersections():
    rng = np.random.default_rng(0)
    sets = [np.unique(rng.integers(0, 300, size=rng.integers(5, 40)).astype(np.uint64))
            for _ in range(30)] + [np.array([], dtype=np.uint64)]
    for limit in (2, 5, 100):      # mostly common, mixed, all enumerated pair by pair
        counts = sim.shared_counts(sets, limit)
        for i, j in combinations(range(len(sets)), 2):
            assert counts[i, j] == len(set(sets[i].tolist()) & set(sets[j].tolist()))
        assert not np.tril(counts).any()
    assert sim.common_limit(20) == 10 and sim.common_limit(500) == 50


# --------------------------------------------------------------------------------------------
# the report's section and validation


def test_render_section_escapes_and_marks_the_evidence_side_by_side():
    evil = HAND_COPIED.replace("bad pitch", "</pre><script>alert(1)</script>")
    found = sim.find_similar({"alice<b>": {"ring_hole_positions": HAND_WRITTEN},
                              "bob": {"ring_hole_positions": evil}})
    page = sim.render_section(found)
    assert "<script>" not in page and "&lt;script&gt;" in page and "alice&lt;b&gt;" in page
    assert page.count("<pre>") == 2 and "<mark>" in page
    assert f"{sim.THRESHOLD:.0%}" in page and str(sim.MIN_TOKENS) in page
    assert "None above the threshold" in sim.render_section([])


def test_render_section_puts_pasted_references_first():
    ref = sim.reference_source(REGISTRY["clip_polygon"].reference)
    found = sim.find_similar({"a": {"clip_polygon": HAND_WRITTEN + "\n" + ref},
                              "b": {"ring_hole_positions": HAND_WRITTEN},
                              "c": {"ring_hole_positions": HAND_COPIED}},
                             {"clip_polygon": ref})
    assert [(m.left, m.right) for m in found] == [("a", sim.REFERENCE), ("b", "c")]
    page = sim.render_section(found)
    assert page.index("Like the course_lib reference") < page.index("Pairs of students")
    assert "(1 like the reference, 1 pair)" in page


def test_render_section_lists_matches_beyond_the_limit_by_name():
    cells = {"a": {"ring_hole_positions": HAND_WRITTEN}, "b": {"ring_hole_positions": HAND_COPIED},
             "c": {"ring_hole_positions": disguise(HAND_WRITTEN, 4)}}
    found = sim.find_similar(cells)
    assert len(found) == 3
    page = sim.render_section(found, limit=1)
    assert page.count("<details") == 1 and page.count("Also above the threshold") == 1


@pytest.mark.parametrize("kwargs, word", [
    ({"threshold": 0.0}, "threshold"), ({"threshold": 1.5}, "threshold"),
    ({"min_tokens": 0}, "min_tokens"), ({"k": 0}, "k"), ({"window": 2.5}, "window"),
    ({"jobs": 0}, "jobs"), ({"threshold": "high"}, "threshold"),
])
def test_bad_arguments_raise_value_error_naming_them(kwargs, word):
    with pytest.raises(ValueError, match=word):
        sim.find_similar({"a": {"f": "x = 1\n"}}, **kwargs)


def test_bad_cells_raise_value_error():
    with pytest.raises(ValueError, match="cells"):
        sim.find_similar([("a", "x = 1")])
    with pytest.raises(ValueError, match="cells"):
        sim.find_similar({"a": "x = 1"})


def test_the_grading_report_carries_the_section(tmp_path):
    """grade writes report.html through outputs.report: the copied pair and the pasted
    reference appear there with their evidence, the honest student does not."""
    from autograder.model import CellKind, CellResult, Status
    from autograder.outputs import report

    ref = sim.reference_source(REGISTRY["ring_hole_positions"].reference)

    def row(student, code):
        return CellResult(student, "q2_nuclear", "test_ring_hole_positions", "ring_hole_positions",
                          1.0, 1.0, Status.OK, "all cases passed", kind=CellKind.FUNCTION,
                          code=code)

    results = [row("alice", HAND_WRITTEN), row("bob", HAND_COPIED), row("carol", ""),
               row("dave", "import math\n\n" + disguise(ref, 5))]
    path = report.write_report(results, [], tmp_path / "report.html",
                               references={"ring_hole_positions": ref})
    page = path.read_text(encoding="utf-8")
    section = page.split("Similar solutions", 1)[1]
    assert "alice" in section and "bob" in section and "dave" in section
    assert "carol" not in section


def test_a_reference_pasted_into_another_cell_is_flagged(tmp_path):
    """Red team: the graded cell stays the released stub and calls a helper; the reference is
    pasted into a multiple-choice cell of the same notebook. The report still finds it."""
    from autograder.model import CellKind, CellResult, Status
    from autograder.outputs import report

    ref = sim.reference_source(REGISTRY["ring_hole_positions"].reference)
    stub = "def ring_hole_positions(pitch, n_rings):\n    return _helper(pitch, n_rings)\n"
    elsewhere = "q2_item3 = 'b'\n\n" + disguise(ref, 7).replace(
        "def ring_hole_positions", "def _helper")

    def row(student, name, code, kind=CellKind.FUNCTION):
        return CellResult(student, "q2_nuclear", f"test_{name}", name, 1.0, 1.0, Status.OK, "",
                          kind=kind, code=code)

    results = [row("erin", "ring_hole_positions", stub),
               row("erin", "q2_item3", elsewhere, CellKind.CHOICE),
               row("frank", "ring_hole_positions", HAND_WRITTEN)]
    found = sim.find_pasted_references({"erin": [stub, elsewhere], "frank": [HAND_WRITTEN]},
                                       {"ring_hole_positions": ref})
    assert [(m.left, m.name) for m in found] == [("erin", "ring_hole_positions")]
    assert found[0].is_reference and found[0].score >= sim.THRESHOLD
    page = report.write_report(results, [], tmp_path / "r.html",
                               references={"ring_hole_positions": ref}).read_text()
    section = page.split("Similar solutions", 1)[1]
    assert "erin" in section and "frank" not in section
