"""Fixtures of the grading service's tests (builders in ``servicetools.py``).

- ``sources``: the course's parsed source notebooks that have registered exercises;
- ``mode``: the sandbox's mode on this machine (skips when it cannot isolate);
- ``service``: a factory of :class:`autograder.service.grading.Service` on a fresh course,
  exchange and gradebook under ``tmp_path`` (every submission folder counts as its student's:
  the tests run as one Unix user).
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
for extra in (HERE, HERE.parent / "grading"):
    if str(extra) not in sys.path:
        sys.path.insert(0, str(extra))

from gradingtools import course_sources  # noqa: E402

from autograder.isolation import IsolationUnavailable, probe  # noqa: E402


@pytest.fixture(scope="session")
def sources():
    found = course_sources()
    if not found:
        pytest.skip("no source notebooks with registered exercises yet")
    return found


@pytest.fixture(scope="session")
def q1(sources):
    return next(s for s in sources if s.name == "q1_imaging")


@pytest.fixture(scope="session")
def mode():
    try:
        return probe()
    except IsolationUnavailable as exc:
        pytest.skip(str(exc))


@pytest.fixture(scope="session")
def registered_gradebook(tmp_path_factory, sources):
    """A gradebook that knows every cell of the assignment, copied per service."""
    from autograder.outputs.gradebook import register_cells

    db = tmp_path_factory.mktemp("gradebook") / "gradebook.db"
    register_cells(f"sqlite:///{db}", sources)
    return db


@pytest.fixture
def service(tmp_path, sources, mode, registered_gradebook):
    from servicetools import make_service

    def factory(**policy):
        return make_service(tmp_path, sources, mode, registered_gradebook, **policy)
    return factory
