"""``autograder.release_cache``: a fresh course root served from the cache equals one that
nbgrader's ``generate_assignment`` makes itself, and a bad or missing entry is never used.

The oracle is nbgrader itself: a course prepared with the cache off, in another root. Runs on
the smallest source notebook, as ``test_course.py`` does.
"""

from __future__ import annotations

import json

import pytest

import autograder.course as course_mod
from autograder import release_cache
from autograder.course import ASSIGNMENT, prepare_course, source_notebooks

NOTEBOOKS = source_notebooks()
pytestmark = [pytest.mark.skipif(not NOTEBOOKS, reason="no notebooks/q*.ipynb yet"),
              pytest.mark.timeout(300)]


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


def test_a_fresh_root_from_the_cache_equals_nbgrader_s_own(tmp_path, monkeypatch, nbgrader_runs):
    src = min(NOTEBOOKS, key=lambda p: p.stat().st_size)
    monkeypatch.delenv(release_cache.ENV, raising=False)
    oracle = prepare_course(tmp_path / "plain", notebooks=[src])
    assert nbgrader_runs == [["generate_assignment", ASSIGNMENT, "--force"]]
    assert not list(tmp_path.glob("cache*"))

    monkeypatch.setenv(release_cache.ENV, str(tmp_path / "cache"))
    first = prepare_course(tmp_path / "first", notebooks=[src])      # runs nbgrader, keeps
    assert len(nbgrader_runs) == 2
    served = prepare_course(tmp_path / "served", notebooks=[src])    # copied from the cache
    assert len(nbgrader_runs) == 2, "a fresh root with the same sources ran nbgrader again"

    for course in (first, served):
        assert (course.release_dir / src.name).read_bytes() == \
            (oracle.release_dir / src.name).read_bytes()
        assert _cells(course.db_url) == _cells(oracle.db_url)
    assert len(_cells(served.db_url)) > 10
    # the stamp makes the next preparation of the served root a no-op, as after nbgrader
    assert prepare_course(tmp_path / "served", notebooks=[src]) == served
    assert len(nbgrader_runs) == 2


def test_a_tampered_entry_or_changed_source_is_not_used(tmp_path, monkeypatch, nbgrader_runs):
    src = min(NOTEBOOKS, key=lambda p: p.stat().st_size)
    monkeypatch.setenv(release_cache.ENV, str(tmp_path / "cache"))
    first = prepare_course(tmp_path / "first", notebooks=[src])
    (entry,) = [p for p in (tmp_path / "cache").iterdir() if not p.name.startswith(".")]
    kept = entry / "release" / src.name
    kept.write_text(kept.read_text().replace("raise NotImplementedError()", "pass", 1))

    again = prepare_course(tmp_path / "again", notebooks=[src])
    assert len(nbgrader_runs) == 2, "a tampered entry was used"
    assert (again.release_dir / src.name).read_bytes() == \
        (first.release_dir / src.name).read_bytes()
    # that run kept a whole entry again, which the next fresh root is served from
    third = prepare_course(tmp_path / "third", notebooks=[src])
    assert len(nbgrader_runs) == 2
    assert (third.release_dir / src.name).read_bytes() == \
        (first.release_dir / src.name).read_bytes()

    changed = tmp_path / src.name
    nb = json.loads(src.read_text())
    nb["cells"].append({"cell_type": "markdown", "metadata": {}, "source": "One more remark."})
    changed.write_text(json.dumps(nb, indent=1))
    other = prepare_course(tmp_path / "other", notebooks=[changed])
    assert len(nbgrader_runs) == 3, "another source was served the first one's release"
    assert "One more remark." in (other.release_dir / src.name).read_text()


def test_a_root_that_holds_a_gradebook_is_never_served(tmp_path, monkeypatch, nbgrader_runs):
    """A course whose gradebook exists (students, marks) is prepared by nbgrader, never
    overwritten by a copy."""
    from nbgrader.api import Gradebook

    src = min(NOTEBOOKS, key=lambda p: p.stat().st_size)
    monkeypatch.setenv(release_cache.ENV, str(tmp_path / "cache"))
    prepare_course(tmp_path / "first", notebooks=[src])
    root = tmp_path / "kept"
    root.mkdir()
    with Gradebook(f"sqlite:///{root / 'gradebook.db'}", course_id="4f9") as gb:
        gb.add_student("s1")
    course = prepare_course(root, notebooks=[src])
    assert len(nbgrader_runs) == 2
    with course.gradebook() as gb:
        assert [s.id for s in gb.students] == ["s1"]
        assert [nb.name for nb in gb.find_assignment(ASSIGNMENT).notebooks] == [src.stem]
