"""Fixtures of the grading service's tests (builders in ``servicetools.py``).

- ``q1``: the parsed ``q1_imaging`` source (``sources``, ``mode`` and ``template_gradebook``
  come from ``tests/conftest.py``);
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


@pytest.fixture(scope="session")
def q1(sources):
    return next(s for s in sources if s.name == "q1_imaging")


@pytest.fixture
def service(tmp_path, sources, mode, template_gradebook):
    from servicetools import make_service

    def factory(**policy):
        return make_service(tmp_path, sources, mode, template_gradebook, **policy)
    return factory
