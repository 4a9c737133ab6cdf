"""Run at the start of every Python process the tests launch (``tests/conftest.py`` puts this
folder first on ``PYTHONPATH``; the pytest process runs it itself).

It runs ``autograder/fast_start.py`` (loaded by its path: nbgrader and Jupyter processes need
not import ``autograder``), which puts off building the RFC 3987 parser that importing
``nbformat`` would build: about 2 s of CPU in every ``nbgrader``, ``python -m autograder`` and
Jupyter process, several hundred of them in a full run. ``python -m autograder`` does the same
itself; here every other process the tests start gains it too. The grading sandbox and the
students' environment start with environments of their own, without ``PYTHONPATH``, so they
are untouched. The ``sitecustomize`` this file hides (Debian's Python has one) still runs.
"""

import importlib.machinery
import importlib.util
import os
import sys

_FAST_START = os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir, os.pardir,
                           "autograder", "fast_start.py")


def _defer_iri_grammar() -> None:
    spec = importlib.util.spec_from_file_location("_autograder_fast_start", _FAST_START)
    if spec is None or not os.path.isfile(_FAST_START):
        return
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    module.defer_iri_grammar()


def _run_the_hidden_sitecustomize() -> None:
    here = os.path.dirname(os.path.abspath(__file__))
    rest = [p for p in sys.path if os.path.abspath(p or os.curdir) != here]
    spec = importlib.machinery.PathFinder.find_spec("sitecustomize", rest)
    if spec is not None and spec.origin and os.path.abspath(spec.origin) != os.path.abspath(__file__):
        spec.loader.exec_module(importlib.util.module_from_spec(spec))


_defer_iri_grammar()
if __name__ == "sitecustomize":
    _run_the_hidden_sitecustomize()
