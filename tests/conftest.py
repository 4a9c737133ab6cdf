"""Fixtures shared by every test area (areas add their own ``tests/<area>/conftest.py``).

- ``MPLBACKEND=Agg`` for this process and every kernel or subprocess it starts;
- ``JUPYTERHUB_USER=ci-student`` likewise (unless set): the student whose own numbers
  (``course_lib.variants``) the notebooks work when the tests run them, as on the hub;
- ``repo_root``: the repository root;
- ``source_notebooks``: the committed ``notebooks/q*.ipynb`` (skips when none exist yet);
- ``sources``: the parsed source notebooks that have registered exercises (skips when none);
- ``mode``: the grading sandbox's mode on this machine (skips when it cannot isolate);
- ``template_gradebook``: the gradebook of a fresh course (every cell registered, no student),
  which tests copy into their ``OUT``;
- ``course``: a session-scoped nbgrader course (``autograder.course.prepare_course``) in a
  temporary directory, assignment ``tripos2006`` released and registered in its gradebook.
  Each xdist worker gets its own; tests that write into it (autograde) use one xdist group.
- ``postgres_url``: a throw-away PostgreSQL server for this session (``tests/postgres.py``),
  as the SQLAlchemy URL of its ``postgres`` database; ``postgres.fresh_database`` makes an
  empty one. Skips only when the server binaries are not installed.

Every Python process the tests start, and this one, first runs ``tests/startup/sitecustomize.py``
(``PYTHONPATH``): it puts off building a parser that importing ``nbformat`` would otherwise
build, about 2 s of CPU per process. ``make test`` also leaves out the unused ``nbmake``
plugin, which would import ``nbformat`` before this file runs.
"""

from __future__ import annotations

import importlib.util
import os
import sys
from pathlib import Path

import pytest


#: run at the start of every Python process the tests launch, and of this one (see its docstring)
STARTUP = Path(__file__).resolve().parent / "startup"
REPO_ROOT = Path(__file__).resolve().parents[1]
os.environ["PYTHONPATH"] = os.pathsep.join(
    p for p in (str(STARTUP), os.environ.get("PYTHONPATH", "")) if p)
_spec = importlib.util.spec_from_file_location("_tests_startup", STARTUP / "sitecustomize.py")
_spec.loader.exec_module(importlib.util.module_from_spec(_spec))

os.environ["MPLBACKEND"] = "Agg"

# Property tests judge values, never speed: hypothesis's default 200 ms deadline per example
# fails on a loaded 2-core machine (benchmarks/ holds the speed targets).
try:
    from hypothesis import settings as _hypothesis_settings
except ImportError:  # pragma: no cover - hypothesis is a test dependency
    pass
else:
    _hypothesis_settings.register_profile("course", deadline=None)
    _hypothesis_settings.load_profile("course")
#: a fresh course root's release and gradebook (nbgrader's generate_assignment, about 400 SQLite
#: commits) are copied from here after the first (autograder/release_cache.py)
os.environ.setdefault("AUTOGRADER_COURSE_CACHE", str(REPO_ROOT / ".cache" / "course-release"))
os.environ.setdefault("JUPYTERHUB_USER", "ci-student")
#: the student id every notebook run by the tests works as (see course_lib.variants)
CI_STUDENT = os.environ["JUPYTERHUB_USER"]


@pytest.fixture(scope="session")
def repo_root() -> Path:
    return REPO_ROOT


@pytest.fixture(scope="session")
def source_notebooks() -> list[Path]:
    from autograder.course import source_notebooks as find

    notebooks = find()
    if not notebooks:
        pytest.skip("no notebooks/q*.ipynb yet")
    return notebooks


@pytest.fixture(scope="session")
def course(tmp_path_factory, source_notebooks):
    """A prepared nbgrader course root (``autograder.course.CourseDir``) for this session."""
    from autograder.course import prepare_course

    return prepare_course(tmp_path_factory.mktemp("course"), notebooks=source_notebooks)


@pytest.fixture(scope="session")
def sources():
    """The parsed source notebooks that have registered exercises (skips when none)."""
    grading = str(REPO_ROOT / "tests" / "grading")
    if grading not in sys.path:
        sys.path.insert(0, grading)
    from gradingtools import course_sources

    found = course_sources()
    if not found:
        pytest.skip("no source notebooks with registered exercises yet")
    return found


@pytest.fixture(scope="session")
def mode():
    """The sandbox's mode on this machine (as root: a uid of its own); skips when the operating
    system cannot isolate students' code here."""
    from autograder.isolation import IsolationUnavailable, probe

    try:
        return probe()
    except IsolationUnavailable as exc:
        pytest.skip(str(exc))


@pytest.fixture(scope="session")
def template_gradebook(tmp_path_factory, sources):
    """The gradebook of a fresh course (``prepare_course``: every cell of the assignment
    registered, no student yet), for tests to copy into their ``OUT``; never written to."""
    from autograder.course import prepare_course

    root = tmp_path_factory.mktemp("gradebook-template")
    return prepare_course(root, notebooks=[s.path for s in sources]).root / "gradebook.db"


@pytest.fixture(scope="session")
def postgres_url():
    """A PostgreSQL server started for this session (and each xdist worker), removed after."""
    from postgres import PostgresUnavailable, start_server

    try:
        server = start_server()
    except PostgresUnavailable as exc:
        pytest.skip(str(exc))
    yield server.url()
    server.stop()


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(config, items):
    """Keep ``@pytest.mark.xdist_group`` working under ``pytest -n 2 --dist loadgroup``.

    pytest-xdist groups tests by appending ``@<group>`` to each item's node id (it assigns
    ``item._nodeid``); pytest 9 keeps node ids in a structured ``item._id`` instead, so that
    assignment is lost and grouped tests are scattered over workers (tests sharing a server or
    a course folder would then each build their own). Re-apply the suffix where it is missing.
    """
    if not getattr(config.option, "loadgroup", False):
        return
    try:
        from _pytest.nodeid import NodeId
    except ImportError:  # pytest < 9: xdist's own suffix works
        return
    for item in items:
        names = sorted({str(m.args[0] if m.args else m.kwargs.get("name", "default"))
                        for m in item.iter_markers("xdist_group")})
        if names and "@" not in item.nodeid and hasattr(item, "_id"):
            item._id = NodeId.parse(f"{item.nodeid}@{'_'.join(names)}")

