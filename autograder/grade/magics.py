"""A notebook cell as plain Python: IPython's ``%``, ``!`` and ``?`` lines turned into no-ops.

The grader reads every code cell of every submission before any sandbox starts, in its own
process, so this must cost time in proportion to the cell's length whatever it holds. IPython's
own transformer (``TransformerManager.transform_cell``) re-tokenises the cell once per special
line it rewrites: a 96 kB cell of ``x = !ls`` lines cost 159 s of the grader's CPU (issue 33,
finding 8). Here each line is looked at once, by patterns anchored at its start.

What a rewritten line becomes is what it did in the sandbox anyway, where ``get_ipython()``
answers every call with None (:func:`autograder.isolation.inside.main._notebook_helpers`):
``%magic ...`` and ``!cmd`` become ``pass`` (at their indentation, so a block stays a block),
and ``x = !cmd`` or ``x = %magic ...`` become ``x = None``. Line numbers are kept (a
continued magic's further lines become empty), so Python's messages point at the student's
lines. A cell that parses as it stands is left alone: a line starting with ``!`` or ``%`` can
then only be inside a bracket or a string (``ok = (a\\n    != b)``), never a magic. In a cell
that does need rewriting, a line of a multi-line string or bracket that starts with ``%`` or ``!``
is rewritten too (the cell then usually fails to compile, and the student is told so): telling
them apart is what IPython's tokenising costs.
"""

from __future__ import annotations

import ast
import re

#: The cell magics whose body is Python: the body runs, the magic line is dropped.
PYTHON_CELL_MAGICS = ("time", "timeit", "capture", "prun", "python", "python3", "debug")
#: A line that may be IPython's: a magic or a shell escape (at its start, or assigned from), a
#: help request.
_SPECIAL = re.compile(r"^[ \t]*[%!?]|=[ \t]*[%!]|\?[ \t]*$", re.M)
#: A help request: ``name?``, ``name??``, ``?name``, ``??name`` (dotted names, ``*`` wildcards).
_HELP = re.compile(r"[ \t]*(\?\??[\w.*]+|[\w.*]+\?\??)[ \t]*")
#: The target of an assignment from a magic (``x = !ls``, ``a, b = %sx ls``, ``x: list = !ls``).
_TARGET = re.compile(r"[\w.:\[\]'\", \t]+")
#: What parsing or compiling a student's code may raise: all mean "it cannot be parsed".
PARSE_ERRORS = (SyntaxError, ValueError, RecursionError, MemoryError, OverflowError)


def to_python(source: str) -> tuple[str | None, str]:
    """Plain Python for a notebook cell: ``(code, note)``, in time linear in ``len(source)``.

    ``code`` is None when the whole cell is a non-Python cell magic (``%%bash``, ``%%html``...),
    which the grader skips; ``note`` says what was ignored.
    """
    lines = source.splitlines()
    note = ""
    if lines and lines[0].lstrip().startswith("%%"):
        words = lines[0].lstrip()[2:].split()
        magic = words[0] if words else ""
        if magic not in PYTHON_CELL_MAGICS:
            return None, f"cell magic %%{magic}: cell skipped"
        lines = lines[1:]
        note = f"cell magic %%{magic} ignored"
    text = _ended("\n".join(lines))
    if not _SPECIAL.search(text) or _parses(text):
        return text, note
    return _ended("\n".join(_rewritten(lines))), note


def _ended(text: str) -> str:
    """``text`` ending with one newline at least (as IPython's transformer ends a cell)."""
    return text if text.endswith("\n") else text + "\n"


def _parses(text: str) -> bool:
    try:
        ast.parse(text)
    except PARSE_ERRORS:
        return False
    return True


def _rewritten(lines: list[str]) -> list[str]:
    """``lines`` with every IPython line made a no-op, and the lines a trailing backslash
    continues it onto emptied (one pass over the lines)."""
    out, continued = [], False
    for line in lines:
        if continued:
            out.append("")
            continued = line.endswith("\\")
            continue
        plain = _as_python(line)
        continued = plain != line and line.endswith("\\")
        out.append(plain)
    return out


def _as_python(line: str) -> str:
    """``line`` itself, or its no-op when it is IPython's (see the module's docstring)."""
    body = line.lstrip(" \t")
    indent = line[: len(line) - len(body)]
    if body[:1] in ("%", "!", "?") or (body.rstrip().endswith("?") and _HELP.fullmatch(line)):
        return indent + "pass"
    target, equals, value = body.partition("=")
    if equals and value.lstrip(" \t")[:1] in ("%", "!") and _TARGET.fullmatch(target):
        return f"{indent}{target.rstrip()} = None"
    return line
