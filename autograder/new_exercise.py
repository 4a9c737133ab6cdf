"""``python -m autograder new-exercise NOTEBOOK NAME --part X --points P``: a new graded function.

Writes what CONTRIBUTING.md's "an exercise from the exam to the grade" lists, each in the form
its section there gives, so that what is left by hand is the maths, the cases and the prose:

- the notebook: a prompt (markdown, stating "*[P marks]*"), the solution cell (grade_id
  ``NAME``) and the test cell (grade_id ``test_NAME``, ``points`` P, the hidden ``check`` line),
  both tagged ``raises-exception``, after a chosen cell (default: the part's last graded cell);
- the registry: an ``Exercise`` appended to ``autograder/exercises/<notebook>.py`` with a cases
  function to write;
- the reference: a stub with the house docstring (NumPy style, Notes citing the exam part) in
  the ``course_lib`` module the notebook's other functions use (``--module`` to choose);
- the honest bank: a stub in ``tests/grading/honest/<notebook>.py``;
- a test file stub ``tests/course_lib/test_NAME.py``.

Every stub fails until it is written (``NotImplementedError`` or ``pytest.fail``), so
``make test-fast`` lists what is left. It refuses a name that exists anywhere a graded name
lives (exit 2), and prints the notebook's marks by part: the points added are taken from
somewhere, a decision the printed headers make visible (``python -m autograder facts --check``).
"""

from __future__ import annotations

import ast
import json
import keyword
import re
import secrets
import sys
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

from . import facts, marks
from .course import REPO_ROOT


@dataclass(frozen=True)
class Plan:
    """What to add: a graded function ``name(args)`` in ``notebook``'s part ``part``."""

    notebook: str
    name: str
    part: str
    points: float
    args: tuple[str, ...]
    module: str
    after: str | None = None

    @property
    def exam_part(self) -> str:
        """"Q5(c)" for notebook q5_phong, part "(c)"."""
        return f"Q{self.notebook[1:].split('_')[0]}{self.part}"

    @property
    def signature(self) -> str:
        return f"{self.name}({', '.join(self.args)})"


def _part_label(part: str) -> str:
    """"c" → "(c)", "b(ii)" → "(b)(ii)", "(b)(ii)" stays; anything else is refused."""
    part = part.strip()
    label = part if part.startswith("(") else f"({part[:1]}){part[1:]}"
    if not re.fullmatch(r"\([a-z]\)(?:\([ivx]+\))?", label):
        raise ValueError(f"--part {part!r}: give a part of the exam such as 'c' or '(b)(ii)'")
    return label


def _reference_module(notebook: str) -> str:
    """The ``course_lib`` module most of the notebook's graded functions come from."""
    from .exercises import for_notebook

    modules = Counter(ex.reference.__module__.split(".")[-1] for ex in for_notebook(notebook)
                      if ex.kind == "function" and ex.reference is not None)
    if not modules:
        raise ValueError(f"{notebook}: no graded function to take the course_lib module from; "
                         "give --module")
    return modules.most_common(1)[0][0]


def plan_from(notebook: str, name: str, part: str, points: float, args: str = "x",
              module: str | None = None, after: str | None = None) -> Plan:
    """Check the request (``ValueError`` saying what is wrong) and fill in the defaults."""
    from .exercises import NOTEBOOKS

    if notebook not in NOTEBOOKS:
        raise ValueError(f"no notebook {notebook!r}; the notebooks are {list(NOTEBOOKS)}")
    if not name.isidentifier() or keyword.iskeyword(name) or name != name.lower() \
            or name.startswith("_"):
        raise ValueError(f"{name!r} is not a lower-case Python name a student can define")
    try:
        points = float(points)
    except (TypeError, ValueError):
        raise ValueError(f"--points {points!r}: a number of marks, e.g. 1 or 0.5") from None
    if not (points > 0 and (2 * points).is_integer()):
        raise ValueError(f"--points {points:g}: a positive number of half marks")
    arg_names = tuple(a.strip() for a in args.split(",") if a.strip())
    if not arg_names or not all(a.isidentifier() for a in arg_names):
        raise ValueError(f"--args {args!r}: comma-separated argument names")
    plan = Plan(notebook, name, _part_label(part), float(points), arg_names,
                module or _reference_module(notebook), after)
    _refuse_existing(plan)
    return plan


def _refuse_existing(plan: Plan) -> None:
    """``ValueError`` when ``plan.name`` already lives where a graded name lives."""
    from .exercises import REGISTRY

    name = plan.name
    if name in REGISTRY:
        raise ValueError(f"{name!r} exists: registered in autograder/exercises/"
                         f"{REGISTRY[name].notebook}.py")
    for path in sorted((REPO_ROOT / "notebooks").glob("q*.ipynb")):
        for cell in marks.read_cells(path):
            gid = cell.get("metadata", {}).get("nbgrader", {}).get("grade_id")
            if gid in (name, f"test_{name}"):
                raise ValueError(f"{name!r} exists: a cell of {path.name} has grade_id {gid!r}")
    lib = REPO_ROOT / "course_lib" / f"{plan.module}.py"
    if not lib.exists():
        raise ValueError(f"--module {plan.module!r}: no course_lib/{plan.module}.py")
    if re.search(rf"^def {name}\(", lib.read_text(encoding="utf-8"), re.M):
        raise ValueError(f"{name!r} exists: course_lib/{plan.module}.py defines it")
    honest = REPO_ROOT / "tests" / "grading" / "honest" / f"{plan.notebook}.py"
    if honest.exists() and re.search(rf"^def {name}\(", honest.read_text(encoding="utf-8"),
                                     re.M):
        raise ValueError(f"{name!r} exists: {honest.relative_to(REPO_ROOT)} defines it")
    test = REPO_ROOT / "tests" / "course_lib" / f"test_{name}.py"
    if test.exists():
        raise ValueError(f"{name!r} exists: {test.relative_to(REPO_ROOT)}")


# --- the notebook -------------------------------------------------------------------------------

def _lines(text: str) -> list[str]:
    """A cell's source as nbformat writes it: lines that keep their newline, the last without."""
    return text.splitlines(keepends=True)


def _code_cell(grade_id: str, source: str, *, grade: bool, points: float | None) -> dict:
    meta = {"grade": grade, "grade_id": grade_id, "locked": grade}
    if points is not None:
        meta["points"] = points
    meta.update({"schema_version": 3, "solution": not grade, "task": False})
    return {"cell_type": "code", "execution_count": None, "id": secrets.token_hex(4),
            "metadata": {"nbgrader": meta, "tags": ["raises-exception"]}, "outputs": [],
            "source": _lines(source)}


def _marks_words(points: float) -> str:
    """1 → "1 mark", 0.5 → "½ mark", 2.5 → "2½ marks" (the notebooks' own wording)."""
    whole = int(points)
    text = ("" if whole == 0 and points != whole else str(whole)) + ("½" if points != whole else "")
    return f"{text} mark" + ("s" if points > 1 else "")


def notebook_cells(plan: Plan) -> list[dict]:
    """The prompt, solution and test cells of a new graded function (CONTRIBUTING.md,
    "A notebook")."""
    prompt = (f"**Exercise** *[{_marks_words(plan.points)}]*. Write `{plan.signature}`: "
              f"TODO what it returns, for one input and for a batch, and the `ValueError` it "
              f"raises for bad input ({plan.exam_part}).")
    solution = (f"def {plan.signature}:\n"
                f'    """TODO one line: what {plan.name} returns (the signature and this '
                f'docstring stay visible)."""\n'
                f"    ### BEGIN SOLUTION\n"
                f"    raise NotImplementedError(\"the model answer of {plan.name}: readable, "
                f"for students, NumPy only (not a call into course_lib)\")\n"
                f"    ### END SOLUTION")
    test = (f"# TODO visible asserts on the exam's own numbers, and a bad-input ValueError check\n"
            f"assert {plan.name} is not None\n"
            f"\n"
            f"### BEGIN HIDDEN TESTS\n"
            f"from autograder.incell import check\n"
            f"check(\"{plan.name}\", {plan.name})\n"
            f"### END HIDDEN TESTS")
    return [{"cell_type": "markdown", "id": secrets.token_hex(4), "metadata": {},
             "source": _lines(prompt)},
            _code_cell(plan.name, solution, grade=False, points=None),
            _code_cell(f"test_{plan.name}", test, grade=True, points=plan.points)]


def _insert_at(cells: list[dict], plan: Plan, notebook: marks.NotebookMarks) -> int:
    """The index after which the new cells go: ``plan.after`` (a cell id or a grade_id), or
    the last graded cell of the part."""
    def gid(cell):
        return cell.get("metadata", {}).get("nbgrader", {}).get("grade_id")

    if plan.after is not None:
        for i, cell in enumerate(cells):
            if plan.after in (cell.get("id"), gid(cell)):
                return i
        raise ValueError(f"--after {plan.after!r}: no cell of {plan.notebook} has that id or "
                         "grade_id")
    part = next((p for p in notebook.parts if p.label == plan.part), None)
    if part is None:
        raise ValueError(f"{plan.notebook} has no part {plan.part}; its parts are "
                         f"{[p.label for p in notebook.parts]}")
    if not part.cells:
        raise ValueError(f"part {plan.part} of {plan.notebook} has no graded cell: give --after")
    last = list(part.cells)[-1]
    return next(i for i, cell in enumerate(cells) if gid(cell) == last)


def add_cells(plan: Plan) -> Path:
    path = REPO_ROOT / "notebooks" / f"{plan.notebook}.ipynb"
    nb = json.loads(path.read_text(encoding="utf-8"))
    at = _insert_at(nb["cells"], plan, marks.notebook_marks(path))
    new = notebook_cells(plan)
    taken = {cell.get("id") for cell in nb["cells"]}
    for cell in new:        # nbformat 4.5 wants cell ids unique within the notebook
        while cell["id"] in taken:
            cell["id"] = secrets.token_hex(4)
        taken.add(cell["id"])
    nb["cells"][at + 1:at + 1] = new
    path.write_text(json.dumps(nb, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    return path


# --- the registry, the reference, the honest bank, the test -----------------------------------

def _imports(text: str) -> set[str]:
    names = set()
    for node in ast.parse(text).body:
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            names |= {a.asname or a.name for a in node.names}
    return names


def add_registry_entry(plan: Plan) -> Path:
    path = REPO_ROOT / "autograder" / "exercises" / f"{plan.notebook}.py"
    text = path.read_text(encoding="utf-8")
    have = _imports(text)
    head = [f"from course_lib import {plan.module}"] if plan.module not in have else []
    head += [f"from .base import {n}" for n in ("Case", "Exercise", "close") if n not in have]
    entry = f'''

def _{plan.name}_cases(rng):
    """{plan.exam_part}: the exam's numbers first (visible), then hidden random inputs,
    batches, edge cases and bad input (``raises=ValueError``), drawn from ``rng`` alone."""
    raise NotImplementedError(
        "write the cases of {plan.name}: yield Case(args=(...), label=..., visible=True)")
    yield Case()


EXERCISES.append(Exercise(
    name="{plan.name}", notebook="{plan.notebook}",
    reference={plan.module}.{plan.name},
    cases=_{plan.name}_cases, compare=close(rtol=1e-9, atol=1e-12),
    description="{plan.exam_part} TODO what it computes"))
'''
    if head:
        text = _after_imports(text, head)
    path.write_text(text.rstrip("\n") + "\n" + entry, encoding="utf-8")
    return path


def _after_imports(text: str, lines: list[str]) -> str:
    """``text`` with ``lines`` inserted after its last top-level import."""
    last = max(node.end_lineno for node in ast.parse(text).body
               if isinstance(node, (ast.Import, ast.ImportFrom)))
    rows = text.splitlines(keepends=True)
    return "".join(rows[:last] + [line + "\n" for line in lines] + rows[last:])


def add_reference_stub(plan: Plan) -> Path:
    path = REPO_ROOT / "course_lib" / f"{plan.module}.py"
    text = path.read_text(encoding="utf-8")
    params = "\n".join(f"    {a} : array_like\n        TODO." for a in plan.args)
    stub = f'''

def {plan.signature}:
    """TODO one line: what it returns.

    Parameters
    ----------
{params}

    Returns
    -------
    ndarray or float
        TODO.

    Raises
    ------
    ValueError
        TODO: each bad input, named (``course_lib/_validate.py``'s helpers).

    Notes
    -----
    {plan.exam_part} of the 2006 paper: TODO the equation of the worked solutions it follows.

    Examples
    --------
    TODO the exam's own numbers as doctest-style lines.
    """
    raise NotImplementedError(
        "{plan.name}: write the reference (CONTRIBUTING.md, 'A course_lib function')")
'''
    text = _into_all(text, plan.name)
    path.write_text(text.rstrip("\n") + "\n" + stub, encoding="utf-8")
    return path


def _into_all(text: str, name: str) -> str:
    """``text`` with ``name`` added, in order, to a one-name-per-line ``__all__`` list."""
    match = re.search(r"^__all__ = \[\n((?:    \"\w+\",\n)*)\]", text, re.M)
    if not match:
        return text
    names = sorted(re.findall(r'"(\w+)"', match[1]) + [name])
    body = "".join(f'    "{n}",\n' for n in names)
    return text[:match.start(1)] + body + text[match.end(1):]


def add_honest_stub(plan: Plan) -> Path:
    path = REPO_ROOT / "tests" / "grading" / "honest" / f"{plan.notebook}.py"
    text = path.read_text(encoding="utf-8") if path.exists() else \
        f'"""{plan.notebook} written from the exam\'s equations alone (not from course_lib)."""\n'
    stub = f'''

def {plan.signature}:
    raise NotImplementedError(
        "{plan.name}: a short honest answer written from the exam alone, not from course_lib")
'''
    path.write_text(text.rstrip("\n") + "\n" + stub, encoding="utf-8")
    return path


def add_test_stub(plan: Plan) -> Path:
    path = REPO_ROOT / "tests" / "course_lib" / f"test_{plan.name}.py"
    path.write_text(f'''"""``course_lib.{plan.module}.{plan.name}`` ({plan.exam_part}) against oracles
independent of it: the exam's own numbers, an analytic result, another library or Monte Carlo
(CONTRIBUTING.md, "Tests")."""

import pytest

from course_lib import {plan.module}


def test_{plan.name}_against_the_exam():
    assert callable({plan.module}.{plan.name})
    pytest.fail(
        "write this test: {plan.name} against the exam's numbers and an independent oracle")
''', encoding="utf-8")
    return path


# --- the command --------------------------------------------------------------------------------

def create(plan: Plan) -> list[Path]:
    """Write everything :class:`Plan` asks for; the files written, in the checklist's order."""
    return [add_cells(plan), add_registry_entry(plan), add_reference_stub(plan),
            add_honest_stub(plan), add_test_stub(plan)]


def add_arguments(parser) -> None:
    parser.add_argument("notebook", help="the notebook, e.g. q5_phong")
    parser.add_argument("name", help="the graded function's name (the grade_id)")
    parser.add_argument("--part", required=True, help="the exam part, e.g. c or (b)(ii)")
    parser.add_argument("--points", required=True, type=float, help="its marks, e.g. 1 or 0.5")
    parser.add_argument("--args", default="x", help="its arguments, e.g. 'L, V' (default x)")
    parser.add_argument("--module", default=None,
                        help="the course_lib module of its reference (default: the one the "
                             "notebook's other functions come from)")
    parser.add_argument("--after", default=None,
                        help="the cell id or grade_id after which its cells go (default: the "
                             "part's last graded cell)")


def main(args) -> int:
    try:
        plan = plan_from(args.notebook, args.name, args.part, args.points, args.args,
                         args.module, args.after)
        written = create(plan)
    except ValueError as exc:
        print(f"new-exercise: {exc}", file=sys.stderr)
        return 2
    print(f"added {plan.signature} to {plan.notebook} part {plan.part} ({plan.points:g} marks):")
    for path in written:
        print(f"  wrote {path.relative_to(REPO_ROOT)}")
    path = REPO_ROOT / "notebooks" / f"{plan.notebook}.ipynb"
    found = marks.notebook_marks(path)
    print(marks.summary(found))
    disagree = marks.problems(found, facts.MARKS_PER_NOTEBOOK)
    if disagree:
        print("to rebalance (take the marks from somewhere, then say so in the text):")
        print("\n".join(f"  {line}" for line in disagree))
    print("then: the contract (../shared/EXERCISES.md), the TODOs and NotImplementedErrors "
          "above, and `make test-fast` (CONTRIBUTING.md, 'Add a graded function')")
    return 0
