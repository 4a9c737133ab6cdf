"""Fixtures of the grading tests (builders live in ``gradingtools.py``).

- ``sources``: the parsed source notebooks that have registered exercises (skips when none);
- ``template_gradebook``: an nbgrader gradebook that knows every cell of the assignment,
  registered with nbgrader's own ``SaveCells``; tests copy it into their ``OUT``.
"""

from __future__ import annotations

import pytest

from gradingtools import course_sources

from autograder.isolation import IsolationUnavailable, probe


@pytest.fixture(scope="session")
def sources():
    found = course_sources()
    if not found:
        pytest.skip("no source notebooks with registered exercises yet")
    return found


@pytest.fixture(scope="session")
def template_gradebook(tmp_path_factory, sources):
    """A gradebook that already knows every cell (nbgrader's SaveCells), copied per test."""
    from autograder.outputs.gradebook import register_cells

    folder = tmp_path_factory.mktemp("gradebook-template")
    db = folder / "gradebook.db"
    register_cells(f"sqlite:///{db}", sources)
    return db


@pytest.fixture(scope="module")
def mode():
    """The sandbox's mode on this machine (as root: a uid of its own); skips when the operating
    system cannot isolate students' code here."""
    try:
        return probe()
    except IsolationUnavailable as exc:
        pytest.skip(str(exc))
