"""Every ``>>>`` example in ``course_lib``'s docstrings runs, and shows what it says.

The examples are what a student sees with ``?`` on a function of the library; they are checked
here with :mod:`doctest`, one test per module, against the module's own namespace. A module's
examples must all be found by doctest (an example doctest cannot see, in a comment or in a
string that is not a docstring, would never run), so the count of ``>>>`` lines in its source
is checked too.
"""

import doctest
import importlib
import pkgutil
import re

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import course_lib  # noqa: E402

MODULES = sorted(m.name for m in pkgutil.walk_packages(course_lib.__path__, "course_lib."))
PROMPT = re.compile(r"^\s*>>> ", re.MULTILINE)


def _examples_in_source(module) -> int:
    with open(module.__file__, encoding="utf-8") as f:
        return len(PROMPT.findall(f.read()))


def test_the_library_has_examples_to_run():
    modules = [importlib.import_module(name) for name in MODULES]
    assert sum(_examples_in_source(m) for m in modules) >= 80


@pytest.mark.parametrize("name", MODULES)
def test_the_examples_of_a_module_run_as_shown(name):
    module = importlib.import_module(name)
    tests = [t for t in doctest.DocTestFinder().find(module) if t.examples]
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    report = []
    with np.printoptions(legacy=False):
        for test in sorted(tests, key=lambda t: t.name):
            runner.run(test, out=report.append)
    results = runner.summarize(verbose=False)
    assert results.failed == 0, "".join(report)
    assert results.attempted == _examples_in_source(module), (
        f"{name}: {_examples_in_source(module)} '>>>' lines in the source, but doctest ran "
        f"{results.attempted}: an example outside a docstring never runs")
