"""A notebook cell as the grader runs it (``autograder.grade.magics.to_python``): IPython's lines
turned into no-ops in one pass, never by IPython's transformer in the grader's process.

Issue 33, finding 8: IPython's transformer re-tokenises a cell once per line it rewrites, so one
96 kB cell of ``x = !ls`` lines (a cell that never runs) held the grader's CPU for 159 s before any
sandbox started, and ten such cells fit in a notebook. The oracle for plain Python is IPython's
own transformer, called here in the test's process on the course's cells.
"""

from __future__ import annotations

import ast
import json

import pytest
from gradingtools import _src_text, course_sources, model_version, release_version


from autograder.grade.planning import plan_cells, to_python
from autograder.grade.reading import MAX_NOTEBOOK_CODE, read_submission

SHELL_LINE = "x = !ls\n"
#: Characters of one attacking cell: just under the grader's cap on one cell's code.
BIG_CELL = 96_000


@pytest.fixture
def no_tokenising(monkeypatch):
    """Count every use of IPython's transformer and of Python's tokenizer (what made the
    transformer's work grow with the square of the cell); each call fails at once, so a
    grader that falls back on another path still shows up in the count."""
    import tokenize

    from IPython.core import inputtransformer2

    calls = []

    class Counted:
        def __init__(self, *args, **kwargs):
            calls.append("TransformerManager")
            raise RuntimeError("IPython's transformer called in the grader's process")

    def counted_tokens(*args, **kwargs):
        calls.append("tokenize")
        raise RuntimeError("tokenize called in the grader's process")

    monkeypatch.setattr(inputtransformer2, "TransformerManager", Counted)
    monkeypatch.setattr(tokenize, "generate_tokens", counted_tokens)
    return calls


def test_a_notebook_of_big_shell_cells_is_planned_without_tokenising(tmp_path, no_tokenising):
    src = next(s for s in course_sources() if s.name == "q1_imaging")
    nb = release_version(src)
    big = SHELL_LINE * (BIG_CELL // len(SHELL_LINE))
    cells = (MAX_NOTEBOOK_CODE - 20_000) // len(big)         # as many as the notebook may hold
    nb["cells"] += [{"cell_type": "code", "metadata": {}, "source": big, "outputs": [],
                     "execution_count": None} for _ in range(cells)]
    (tmp_path / f"{src.name}.ipynb").write_text(json.dumps(nb), encoding="utf-8")
    sub = read_submission(tmp_path, "kim", src.name)
    assert sub.status.value == "ok", sub.message
    plan = plan_cells(src, sub)
    assert no_tokenising == []
    planned = [plan.python[k] for k, c in enumerate(sub.cells) if c["source"] == big]
    assert len(planned) == cells >= 9
    # what the sandbox made of it before: get_ipython() answers None, so x is None
    assert all(code == "x = None\n" * big.count("\n") for code in planned)


@pytest.mark.parametrize("source, expected", [
    ("x = !ls\nprint(x)\n", "x = None\nprint(x)\n"),
    ("files: list = !ls", "files: list = None\n"),
    ("a, b = %sx ls -1\n", "a, b = None\n"),
    ("%matplotlib inline\nimport numpy as np\n", "pass\nimport numpy as np\n"),
    ("def f(x):\n    %time g(x)\n    return 1\n", "def f(x):\n    pass\n    return 1\n"),
    ("!pip install \\\n    shapely\ny = 2\n", "pass\n\ny = 2\n"),     # a continued magic
    ("np.linspace?\nz = 1\n", "pass\nz = 1\n"),
    ("??np.linspace\n", "pass\n"),
    ("ok = (a\n      != b)\n", "ok = (a\n      != b)\n"),      # "!" continuing a bracket
    ('s = """\n%d items\n"""\n', 's = """\n%d items\n"""\n'),    # "%" inside a string
    ("y = 1", "y = 1\n"),
])
def test_ipython_lines_become_no_ops_line_for_line(source, expected):
    code, _ = to_python(source)
    assert code == expected
    assert code.count("\n") == max(1, source.count("\n") + (not source.endswith("\n")))


def test_cell_magics():
    assert to_python("%%bash\nls\n") == (None, "cell magic %%bash: cell skipped")
    assert to_python("%%\nls\n") == (None, "cell magic %%: cell skipped")
    code, note = to_python("%%time\nx = 1\n")
    assert (code, note) == ("x = 1\n", "cell magic %%time ignored")


def test_plain_python_is_what_ipython_makes_of_it():
    """Every code cell of the course's notebooks (source, model answers, release) without an
    IPython line comes out exactly as IPython's transformer gives it, so the sandbox runs, and
    the hidden cases are seeded by, the same text as before; a cell with one compiles."""
    from IPython.core.inputtransformer2 import TransformerManager

    seen = special = 0
    for src in course_sources():
        for nb in (src.nb, model_version(src), release_version(src)):
            for cell in nb["cells"]:
                text = _src_text(cell)
                if cell["cell_type"] != "code" or text.lstrip().startswith("%%"):
                    continue
                code, _ = to_python(text)
                # what the grader ran before: IPython's transformer on the cell's lines
                ipython = TransformerManager().transform_cell("\n".join(text.splitlines()))
                if "get_ipython()" in ipython:
                    special += 1
                    ast.parse(code)
                    assert code.count("\n") == ipython.count("\n")
                else:
                    seen += 1
                    assert code == ipython
    assert seen > 500 and special > 0


def test_a_notebook_stripped_of_its_metadata_is_parsed_once_per_cell(tmp_path, monkeypatch):
    """With no grade_id left, every graded name is looked for by what the cells define: each
    cell is parsed once, not once per graded name (ten 96 kB cells of plain Python cost the
    grader 24 s of CPU that way, before any sandbox)."""
    from autograder.grade import planning

    src = next(s for s in course_sources() if s.name == "q1_imaging")
    nb = release_version(src)
    for cell in nb["cells"]:
        cell["metadata"] = {}
    (tmp_path / f"{src.name}.ipynb").write_text(json.dumps(nb), encoding="utf-8")
    sub = read_submission(tmp_path, "kim", src.name)
    parsed = []
    real = planning.parse_code
    monkeypatch.setattr(planning, "parse_code", lambda code: parsed.append(code) or real(code))
    plan = plan_cells(src, sub)
    assert plan.by_name, "names were found by definition"
    code_cells = sum(c["cell_type"] == "code" for c in sub.cells)
    assert len(parsed) <= code_cells < len(src.graded) * code_cells
