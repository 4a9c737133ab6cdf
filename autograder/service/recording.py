"""What a graded submission leaves in the course: the counting notebooks and the gradebook.

The counting notebooks go into ``submitted/`` and their automatic scores into nbgrader's
gradebook (markers' scores and comments untouched), one worker process at a time; a gradebook
server that cannot be reached is told apart from anything about the submission, so the
submission waits for it rather than spending its tries (:func:`.tries.wait_for_gradebook`).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from ..course import file_lock
from ..model import Batch, CellResult
from ..outputs import gradebook
from . import handout

if TYPE_CHECKING:
    from .grading import Service


def gradebook_unreachable(exc: BaseException) -> bool:
    """Whether ``exc`` says the gradebook's database could not be reached or dropped the
    connection (a PostgreSQL server stopped or restarting, a locked SQLite file), rather than
    anything about the submission."""
    try:
        from sqlalchemy.exc import DBAPIError, OperationalError
    except ImportError:
        return False
    return isinstance(exc, OperationalError) or (
        isinstance(exc, DBAPIError) and bool(exc.connection_invalidated))


def ping_gradebook(db_url: str | None) -> None:
    """Open and close one connection to a gradebook server (SQLite files and no gradebook
    are skipped): raises SQLAlchemy's ``OperationalError`` when it cannot be reached, before
    nbgrader's ``Gradebook`` would take the failure for an empty database and try to create
    the course again."""
    if db_url is None or db_url.startswith("sqlite"):
        return
    from sqlalchemy import create_engine, text

    engine = create_engine(db_url)
    try:
        with engine.connect() as con:
            con.execute(text("SELECT 1"))
    finally:
        engine.dispose()


def record(svc: Service, student: str, collected: Path, counting: list[str],
           results: list[CellResult], subs: dict) -> None:
    """The counting notebooks into ``submitted/`` and their automatic scores into the gradebook
    (markers' scores and comments untouched: :func:`autograder.outputs.gradebook.sync`)."""
    if not counting:
        return
    ping_gradebook(svc.db_url)      # submitted/ and the gradebook change together or not at all
    handout.keep_counting(svc.course, collected, student, counting)
    if svc.db_url is None:
        return
    rows = [r for r in results if r.notebook in counting]
    kept = {k: v for k, v in subs.items() if k[1] in counting}
    with _gradebook_turn(svc):
        gradebook.sync(Batch(rows, kept, [student]), svc.sources,
                       submitted=Path(svc.course) / "submitted", out=Path(svc.course),
                       db_url=svc.db_url)


def _gradebook_turn(svc: Service):
    """One worker process at a time writes the gradebook: two writers of a SQLite gradebook
    would meet its lock (nbgrader's engine waits only seconds) and retry the whole submission."""
    return file_lock(Path(svc.course) / "service" / "gradebook.lock")
