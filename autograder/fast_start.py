"""Put off building a parser that importing ``nbformat`` would build, at a process's start.

Importing ``nbformat`` imports ``jsonschema``'s format checkers and, with them,
``rfc3987_syntax``, which builds a Lark Earley parser of RFC 3987 at import: about 2 s of CPU
in every ``python -m autograder`` process (and every ``nbgrader`` or Jupyter one), for a check
of IRI strings that no course notebook exercises. :func:`defer_iri_grammar` builds it on the
first IRI checked instead; what is valid stays exactly as before.

Standard library only, and loadable by file path: ``autograder/__main__.py`` calls it before
any command is imported, and the tests' ``tests/startup/sitecustomize.py`` loads this file in
every Python process they start (nbgrader, Jupyter), which may not import ``autograder``.
"""

from __future__ import annotations

import importlib.util
import sys
import types


def defer_iri_grammar() -> None:
    """Stand in for ``rfc3987_syntax`` a package whose ``is_valid_syntax`` (the one name
    ``jsonschema`` takes from it) imports the real one on its first call. Does nothing when
    the package is already imported or not installed."""
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


__all__ = ["defer_iri_grammar"]
