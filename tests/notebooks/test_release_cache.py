"""``autograder.release_cache``: a fresh course root served from the cache equals one that
nbgrader's ``generate_assignment`` makes itself, and a bad or missing entry is never used.

The oracle is nbgrader itself: a course prepared with the cache off, in another root. Runs on
the smallest source notebook, as ``test_course.py`` does.
"""

from __future__ import annotations

import json
import shutil

import pytest

import autograder.course as course_mod
from autograder import release_cache
from autograder.course import ASSIGNMENT, prepare_course, source_notebooks

NOTEBOOKS = source_notebooks()
pytestmark = [pytest.mark.skipif(not NOTEBOOKS, reason="no notebooks/q*.ipynb yet"),
              pytest.mark.timeout(300)]


SRC = min(NOTEBOOKS, key=lambda p: p.stat().st_size) if NOTEBOOKS else None


class WouldRunNbgrader(Exception):
    """Raised instead of running nbgrader where a test expects nbgrader to be asked."""


@pytest.fixture(scope="module")
def kept(tmp_path_factory):
    """A cache holding one entry (``SRC`` prepared once, by nbgrader) and that course."""
    root = tmp_path_factory.mktemp("kept")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv(release_cache.ENV, str(root / "cache"))
        course = prepare_course(root / "first", notebooks=[SRC])
    return root / "cache", course


@pytest.fixture
def cache(kept, tmp_path, monkeypatch):
    """This test's copy of the kept cache, turned on."""
    folder = tmp_path / "cache"
    shutil.copytree(kept[0], folder)
    monkeypatch.setenv(release_cache.ENV, str(folder))
    return folder


@pytest.fixture
def nbgrader_runs(monkeypatch):
    """The nbgrader commands ``prepare_course`` runs from now on (they still run)."""
    runs = []
    real = course_mod.run_nbgrader

    def counting(args, *rest, **kwargs):
        runs.append(list(args))
        return real(args, *rest, **kwargs)

    monkeypatch.setattr(course_mod, "run_nbgrader", counting)
    return runs


def _refuse_nbgrader(monkeypatch) -> None:
    def refuse(args, *rest, **kwargs):
        raise WouldRunNbgrader(args)

    monkeypatch.setattr(course_mod, "run_nbgrader", refuse)


@pytest.fixture
def no_nbgrader(monkeypatch):
    _refuse_nbgrader(monkeypatch)


def _cells(db_url: str) -> dict:
    """Every cell the gradebook registered, by notebook and name, with what nbgrader keeps."""
    from nbgrader.api import Gradebook

    with Gradebook(db_url) as gb:
        assignment = gb.find_assignment(ASSIGNMENT)
        return {
            (nb.name, kind, cell.name): (getattr(cell, "max_score", None),
                                         getattr(cell, "cell_type", None),
                                         getattr(cell, "checksum", None),
                                         getattr(cell, "source", None))
            for nb in assignment.notebooks
            for kind, cells in (("grade", nb.grade_cells), ("solution", nb.solution_cells),
                                ("source", nb.source_cells), ("task", nb.task_cells))
            for cell in cells
        }


def test_a_fresh_root_from_the_cache_equals_nbgrader_s_own(tmp_path, monkeypatch, kept):
    monkeypatch.delenv(release_cache.ENV, raising=False)
    oracle = prepare_course(tmp_path / "plain", notebooks=[SRC])     # nbgrader, no cache
    assert not (tmp_path / "cache").exists()

    monkeypatch.setenv(release_cache.ENV, str(kept[0]))
    _refuse_nbgrader(monkeypatch)
    served = prepare_course(tmp_path / "served", notebooks=[SRC])    # copied, nbgrader not run
    for course in (kept[1], served):
        assert (course.release_dir / SRC.name).read_bytes() == \
            (oracle.release_dir / SRC.name).read_bytes()
        assert _cells(course.db_url) == _cells(oracle.db_url)
    assert len(_cells(served.db_url)) > 10
    # the stamp makes the next preparation of the served root a no-op, as after nbgrader
    assert prepare_course(tmp_path / "served", notebooks=[SRC]) == served


def test_a_tampered_entry_is_replaced_not_used(tmp_path, cache, nbgrader_runs):
    (entry,) = [p for p in cache.iterdir() if not p.name.startswith(".")]
    kept_copy = entry / "release" / SRC.name
    kept_copy.write_text(kept_copy.read_text().replace("raise NotImplementedError()", "pass", 1))

    again = prepare_course(tmp_path / "again", notebooks=[SRC])
    assert nbgrader_runs == [["generate_assignment", ASSIGNMENT, "--force"]], \
        "a tampered entry was used"
    assert "raise NotImplementedError()" in (again.release_dir / SRC.name).read_text()
    # that run kept a whole entry again, which the next fresh root is served from
    third = prepare_course(tmp_path / "third", notebooks=[SRC])
    assert len(nbgrader_runs) == 1
    assert (third.release_dir / SRC.name).read_bytes() == \
        (again.release_dir / SRC.name).read_bytes()


def test_another_source_is_not_served_the_kept_release(tmp_path, cache, no_nbgrader):
    changed = tmp_path / SRC.name
    nb = json.loads(SRC.read_text())
    nb["cells"].append({"cell_type": "markdown", "metadata": {}, "source": "One more remark."})
    changed.write_text(json.dumps(nb, indent=1))
    with pytest.raises(WouldRunNbgrader):
        prepare_course(tmp_path / "other", notebooks=[changed])


def test_a_root_that_holds_a_gradebook_is_never_served(tmp_path, cache, no_nbgrader):
    """A course whose gradebook exists (students, marks) goes to nbgrader, never gets a copy."""
    from nbgrader.api import Gradebook

    root = tmp_path / "kept"
    root.mkdir()
    with Gradebook(f"sqlite:///{root / 'gradebook.db'}", course_id="4f9") as gb:
        gb.add_student("s1")
    with pytest.raises(WouldRunNbgrader):
        prepare_course(root, notebooks=[SRC])
    with Gradebook(f"sqlite:///{root / 'gradebook.db'}", course_id="4f9") as gb:
        assert [s.id for s in gb.students] == ["s1"]
    assert not (root / "release").exists()
