"""Run at the start of every Python process the tests launch (``tests/conftest.py`` puts this
folder first on ``PYTHONPATH``; the pytest process runs it itself).

Importing ``nbformat`` imports ``jsonschema``'s format checkers and, with them,
``rfc3987_syntax``, which builds a Lark Earley parser of RFC 3987 at import: about 2 s of CPU
in every ``nbgrader``, ``python -m autograder`` and Jupyter process, several hundred of them in
a full run, for a check (IRI strings) that no test's notebook exercises. Here the parser is
built on the first IRI checked instead; what is valid stays exactly as before. The grading
sandbox and the students' environment start with environments of their own, without
``PYTHONPATH``, so they are untouched. The ``sitecustomize`` this file hides (Debian's Python
has one) still runs.
"""

import importlib.machinery
import importlib.util
import os
import sys
import types


def defer_iri_grammar() -> None:
    """Stand in for ``rfc3987_syntax`` a package whose ``is_valid_syntax`` (the one name
    ``jsonschema`` takes from it) imports the real one on its first call."""
    if "rfc3987_syntax" in sys.modules:
        return
    spec = importlib.util.find_spec("rfc3987_syntax")
    if spec is None or not spec.submodule_search_locations:
        return
    package = types.ModuleType("rfc3987_syntax")
    package.__spec__, package.__file__ = spec, spec.origin
    package.__path__ = list(spec.submodule_search_locations)

    def is_valid_syntax(term: str, value: str) -> bool:
        from rfc3987_syntax.syntax_helpers import is_valid_syntax as real

        return real(term, value)

    package.is_valid_syntax = is_valid_syntax
    sys.modules["rfc3987_syntax"] = package


def _run_the_hidden_sitecustomize() -> None:
    here = os.path.dirname(os.path.abspath(__file__))
    rest = [p for p in sys.path if os.path.abspath(p or os.curdir) != here]
    spec = importlib.machinery.PathFinder.find_spec("sitecustomize", rest)
    if spec is not None and spec.origin and os.path.abspath(spec.origin) != os.path.abspath(__file__):
        spec.loader.exec_module(importlib.util.module_from_spec(spec))


defer_iri_grammar()
if __name__ == "sitecustomize":
    _run_the_hidden_sitecustomize()
