"""Which of a student's cells run, and what each graded cell's source shows before it runs.

:func:`plan_cells` picks the solution cells (by grade_id; when the nbgrader metadata is gone, by
what a cell defines), in notebook order as "Run All" would; test, figure and explorer cells
never run. :func:`answer_hint` reads a graded cell's source (never running it) and says whether
it is still the released stub, empty, or binds the graded name to None, a constant, or a
function that cannot take the exercise's arguments.
"""

from __future__ import annotations

import ast
import inspect
import re
from dataclasses import dataclass, field

from ..isolation.allowlist import ALLOWED_COURSE_MODULES, ALLOWED_REFERENCE, ALLOWED_WHOLE_MODULES
from ..isolation.inside.wire import MAX_INT_BITS
from ..model import AnswerHint, AnswerShape, CellKind, SourceNotebook, Status, Submission
from .magics import PARSE_ERRORS, to_python

#: Characters of code in one cell the grader reads (parses, sends to the sandbox): an answer
#: needs far less, and parsing costs some 600 bytes of memory per character.
MAX_CELL_CODE = 100_000


def parse_code(code: str) -> ast.Module | None:
    """The syntax tree of ``code``, or None when it cannot be parsed (never raises)."""
    try:
        return ast.parse(code)
    except PARSE_ERRORS:
        return None


def compile_problem(code: str) -> str:
    """Why ``code`` does not compile (``""`` when it does), in a sentence for the student.

    ``def f(a, a)`` parses but does not compile; a sum of 100,000 terms is too deeply nested
    for Python's compiler.
    """
    try:
        compile(code, "<cell>", "exec", dont_inherit=True)
    except SyntaxError as exc:
        where = f" (line {exc.lineno})" if exc.lineno else ""
        return f"SyntaxError: {exc.msg}{where}"
    except (RecursionError, MemoryError, OverflowError):
        return "the code is nested too deeply for Python to compile it"
    except ValueError as exc:
        return f"ValueError: {exc}"
    return ""


def _bindings(code: str, name: str) -> list[ast.stmt] | None:
    """Top-level statements of ``code`` that bind ``name``; None when it does not parse."""
    tree = parse_code(code)
    if tree is None:
        return None
    found = []
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name == name:
            found.append(node)
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            if any(isinstance(t, ast.Name) and t.id == name for t in targets):
                found.append(node)
    return found


#: What :func:`typed_answer` returns when the cell does not type its answer as a literal.
NOT_TYPED = object()


def typed_answer(code: str, name: str):
    """The answer a choice or number item's cell *types*: the literal of its last top-level
    ``name = <literal>`` (a string, a number, ``True``/``False``, or lists and tuples of them;
    lists become tuples), else :data:`NOT_TYPED`.

    Items are judged on what the student typed, never on what code computes: a
    notebook whose cells compute the answer from ``mine`` would hand every friend who copies it
    their own right answers.
    """
    found = _bindings(code, name)
    if not found or not isinstance(found[-1], (ast.Assign, ast.AnnAssign)) \
            or found[-1].value is None:
        return NOT_TYPED
    try:
        value = ast.literal_eval(found[-1].value)
    except PARSE_ERRORS + (TypeError,):
        return NOT_TYPED
    return _plain_literal(value)


def _plain_literal(value, depth: int = 0):
    if type(value) is int and value.bit_length() > MAX_INT_BITS:
        return NOT_TYPED        # as from the sandbox: no page, CSV or report prints it
    if value is None or type(value) in (bool, int, float, str):
        return value
    if type(value) in (list, tuple) and depth < 3:
        items = tuple(_plain_literal(v, depth + 1) for v in value)
        return NOT_TYPED if any(v is NOT_TYPED for v in items) else items
    return NOT_TYPED


def top_level_names(code: str) -> frozenset[str] | None:
    """The names ``code`` binds at top level (``def name``, ``name = ...``, as
    :func:`_bindings` reads them); None when it does not parse."""
    tree = parse_code(code)
    if tree is None:
        return None
    names = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            names.add(node.name)
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            names.update(t.id for t in targets if isinstance(t, ast.Name))
    return frozenset(names)


def defines(code: str, name: str) -> bool:
    """Whether ``code`` defines ``name`` at top level (``def name`` or ``name = ...``)."""
    return _defines(code, name, top_level_names(code))


def _defines(code: str, name: str, names: frozenset[str] | None) -> bool:
    """:func:`defines`, given ``code``'s :func:`top_level_names` (None: by its text)."""
    if names is None:
        return bool(re.search(rf"^(def\s+{re.escape(name)}\b|{re.escape(name)}\s*=)", code, re.M))
    return name in names


@dataclass
class CellPlan:
    """The student's cells the sandbox runs (shared by every graded name of a notebook)."""

    cells: list[tuple[str, str]]          #: (label, python) in notebook order
    missing: set[str]                     #: graded names with no cell at all
    notes: dict[str, list[str]]           #: graded name -> notes for the student
    chosen: dict[str, int]                #: graded name -> index (in sub.cells) of its cell
    by_name: dict[str, int] = field(default_factory=dict)  #: found by definition, not grade_id
    python: dict[int, str] = field(default_factory=dict)   #: index -> the cell as Python
    #: graded name -> (status, message) when its cell cannot run (too big, does not compile)
    blocked: dict[str, tuple[Status, str]] = field(default_factory=dict)


def plan_cells(src: SourceNotebook, sub: Submission) -> CellPlan:
    """Pick the solution cells to run: by grade_id, else (metadata stripped) by definition."""
    sol_ids = set(src.solution_ids)
    names = [g.name for g in src.graded]
    notes: dict[str, list[str]] = {n: [] for n in names}
    by_id: dict[str, list[int]] = {}
    for k, c in enumerate(sub.cells):
        if c["cell_type"] == "code" and c["grade_id"] in sol_ids:
            by_id.setdefault(c["grade_id"], []).append(k)
    for gid, ks in by_id.items():
        if len(ks) > 1 and gid in notes:
            notes[gid].append(f"the solution cell of {gid} appears {len(ks)} times (a copied "
                              "cell?); all copies ran in notebook order, so the last one counts")
    python = {k: code for k, c in enumerate(sub.cells)
              if c["cell_type"] == "code" and len(c["source"]) <= MAX_CELL_CODE
              for code in [to_python(c["source"])[0]] if code is not None}
    run = {k: gid for gid, ks in by_id.items() for k in ks}
    plan = CellPlan([], set(), notes, {}, python=python)
    bound: dict[int, frozenset[str] | None] = {}     # each cell parsed once, whatever is missing
    for name in names:
        if by_id.get(name):
            plan.chosen[name] = by_id[name][-1]
            continue
        k = _cell_defining(sub, python, run, name, bound)
        if k is None:
            plan.missing.add(name)
            continue
        plan.chosen[name] = plan.by_name[name] = k
        run[k] = name
        notes[name].append(f"the nbgrader metadata of the solution cell of {name} was missing "
                           "or changed; the cell that defines it was graded instead")
    _block_unrunnable(sub, plan)
    plan.cells = [(f"{run[k]} (cell {sub.cells[k]['index'] + 1})", python[k])
                  for k in sorted(run) if k in python]
    return plan


def _block_unrunnable(sub: Submission, plan: CellPlan) -> None:
    """Graded cells far too big to read, or that do not compile, are not run: their names get
    a status and a sentence in ``plan.blocked`` (and the cell leaves ``plan.python``)."""
    for name, k in plan.chosen.items():
        cell = sub.cells[k]
        size = len(cell["source"])
        if size > MAX_CELL_CODE:
            plan.blocked[name] = (Status.UNREADABLE, (
                f"cell {cell['index'] + 1} (the solution of {name}) holds {_size_text(size)} of "
                f"code, far more than an answer needs (at most {_size_text(MAX_CELL_CODE)}): it "
                "was not run"))
        elif k in plan.python:
            problem = compile_problem(plan.python[k])
            if problem:
                plan.blocked[name] = (Status.ERROR, (
                    f"cell {cell['index'] + 1} (the solution of {name}) does not compile: "
                    f"{problem}; so {name} is not defined"))
    for name, k in plan.chosen.items():
        if name in plan.blocked:
            plan.python.pop(k, None)


def _size_text(chars: int) -> str:
    return f"{chars / 1e6:.1f} MB" if chars >= 1e6 else f"{chars / 1e3:.0f} kB"


def _cell_defining(sub: Submission, python: dict[int, str], taken: dict, name: str,
                   bound: dict[int, frozenset[str] | None]) -> int | None:
    """The last untaken cell (no test cell) that defines ``name``; ``bound`` caches each
    cell's :func:`top_level_names`, so a notebook stripped of its metadata is parsed once, not
    once per graded name (ten 96 kB cells cost 21 s of the grader's CPU that way)."""
    candidates = []
    for k, c in enumerate(sub.cells):
        if k not in python or k in taken or (c["grade_id"] or "").startswith("test_"):
            continue
        if k not in bound:
            bound[k] = top_level_names(python[k])
        if _defines(python[k], name, bound[k]):
            candidates.append(k)
    return candidates[-1] if candidates else None


# --------------------------------------------------------------------------------------------
# what a graded cell's source shows


def answer_hint(code: str, name: str, kind: CellKind, calls=()) -> AnswerHint:
    """Read ``code`` (the graded cell, as Python) for the shape of its answer to ``name``.

    ``calls`` are ``(args, kwargs)`` of the exercise's cases, used to check that a ``def`` can
    take them. Returns :attr:`AnswerShape.WRITTEN` whenever the source does not say more.
    """
    tree = parse_code(code)
    if tree is None:
        return AnswerHint()
    body = [s for s in tree.body if not _is_constant_expr(s)]
    if not body or all(isinstance(s, ast.Pass) for s in body):
        return AnswerHint(AnswerShape.EMPTY)
    if len(body) == 1 and _is_stub_raise(body[0]):
        return AnswerHint(AnswerShape.UNTOUCHED)
    found = _bindings(code, name) or []
    hint = _hint_of_binding(found[-1], kind, calls) if found else AnswerHint()
    hint.reference = reference_import(tree)
    return hint


def reference_import(tree: ast.AST) -> str:
    """The first import of the course's reference in ``tree`` (anywhere in it), else ``""``.

    Everything under ``course_lib`` is the reference except the data tables the sandbox
    provides (:data:`autograder.isolation.allowlist.ALLOWED_REFERENCE`).
    """
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if _is_course(alias.name) and alias.name not in ALLOWED_COURSE_MODULES:
                    return alias.name
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and _is_course(node.module):
            if node.module in ALLOWED_WHOLE_MODULES:
                continue
            allowed = ALLOWED_REFERENCE.get(node.module, ())
            for alias in node.names:
                full = f"{node.module}.{alias.name}"
                if alias.name not in allowed and full not in ALLOWED_REFERENCE:
                    return full
    return ""


def _is_course(module: str | None) -> bool:
    return bool(module) and (module == "course_lib" or module.startswith("course_lib."))


def _hint_of_binding(node: ast.stmt, kind: CellKind, calls) -> AnswerHint:
    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
        inner = [s for s in node.body if not _is_constant_expr(s)]
        if len(inner) == 1 and _is_stub_raise(inner[0]):
            return AnswerHint(AnswerShape.UNTOUCHED)
        return _arity_hint(node.name, node.args, calls)
    value = node.value
    if isinstance(value, ast.Constant) and value.value is None:
        return AnswerHint(AnswerShape.NONE)
    if kind is not CellKind.FUNCTION:
        return AnswerHint()
    if isinstance(value, ast.Lambda):
        return _arity_hint("the lambda", value.args, calls)
    what = _literal_kind(value)
    return AnswerHint(AnswerShape.NOT_A_FUNCTION, what) if what else AnswerHint()


def _literal_kind(value: ast.expr) -> str:
    if isinstance(value, ast.Constant):
        return {bool: "True or False", str: "a string", bytes: "bytes"}.get(
            type(value.value), "a number")
    kinds = {ast.List: "a list", ast.Tuple: "a tuple", ast.Dict: "a dict", ast.Set: "a set",
             ast.ListComp: "a list", ast.DictComp: "a dict", ast.SetComp: "a set"}
    return kinds.get(type(value), "")


def _arity_hint(label: str, args: ast.arguments, calls) -> AnswerHint:
    try:
        sig = _signature(args)
    except ValueError:  # e.g. a repeated argument name: the cell does not compile
        return AnswerHint()
    for a, kw in calls:
        try:
            sig.bind(*a, **kw)
        except TypeError as exc:
            return AnswerHint(AnswerShape.WRONG_ARITY, f"{label}{sig} {exc}")
    return AnswerHint()


def _signature(args: ast.arguments) -> inspect.Signature:
    """The call signature of a ``def`` or ``lambda`` from its AST (defaults as placeholders)."""
    P = inspect.Parameter
    params = []
    positional = [(a, P.POSITIONAL_ONLY) for a in args.posonlyargs]
    positional += [(a, P.POSITIONAL_OR_KEYWORD) for a in args.args]
    first_default = len(positional) - len(args.defaults)
    for i, (a, kind) in enumerate(positional):
        params.append(P(a.arg, kind, default=... if i >= first_default else P.empty))
    if args.vararg:
        params.append(P(args.vararg.arg, P.VAR_POSITIONAL))
    for a, d in zip(args.kwonlyargs, args.kw_defaults, strict=True):
        params.append(P(a.arg, P.KEYWORD_ONLY, default=... if d is not None else P.empty))
    if args.kwarg:
        params.append(P(args.kwarg.arg, P.VAR_KEYWORD))
    return inspect.Signature(params)


def _is_constant_expr(node: ast.stmt) -> bool:
    return isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant)


def _is_stub_raise(node: ast.stmt) -> bool:
    """``raise NotImplementedError`` or ``raise NotImplementedError(...)``: the released stub."""
    if not isinstance(node, ast.Raise) or node.exc is None:
        return False
    exc = node.exc.func if isinstance(node.exc, ast.Call) else node.exc
    return isinstance(exc, ast.Name) and exc.id == "NotImplementedError"
