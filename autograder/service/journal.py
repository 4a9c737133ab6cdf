"""The service's durable journal: one row per submission, its state, and every attempt.

SQLite in write-ahead-log mode in the course folder (``<course>/service/journal.db``). Each
submission folder of the exchange's inbound gets one row (its name is unique: noticing it again
changes nothing) that moves ``queued -> grading -> done`` (or ``failed``: refused by the collect
rules, out of tries or out of time). A service killed while a row is ``grading`` finds it so on
restart and puts it back in the queue (:meth:`Journal.recover`): nothing is lost.

An attempt is charged before anything of it leaves: :meth:`Journal.charge` writes each notebook's
row (its digest, and ``graded`` 1 for a notebook to be graded) in one transaction before the
sandbox runs and before any page is written, keyed by (submission, notebook), so a retry of the
same submission finds its charge and never charges again, and an exception anywhere later
(a crash, a kill, a student's notebook that breaks the grader) leaves the attempt counted. The
items' scores follow in the transaction that marks the row ``done`` (:meth:`Journal.finish`).

Tables (documented for the class report, which reads ``attempts``):

- ``submissions(id, folder, student, ctime_ns, noticed, state, tries, retry_at, error,
  finished, started, spent, reserved)`` (``started``: when its last try began, epoch s;
  ``spent``: the seconds of grading its tries have used, against its time budget; ``reserved``:
  the part of ``spent`` the running try charged ahead, given back if the service is killed);
- ``notebooks(submission_id, student, notebook, time, digest, graded, score, max_score)``: one
  row per notebook a submission held; ``graded`` 0 when it was unchanged, over the day's
  attempts or over the size limit; ``score`` NULL while a charged attempt is being graded, 0 for
  one whose submission failed;
- ``attempts(submission_id, student, notebook, item, time, score, max_score, status)``: one
  row per graded item of a graded notebook (``time``: the submission's, seconds since the
  epoch, as the exchange's kernel recorded it).
"""

from __future__ import annotations

import sqlite3
import time
from dataclasses import dataclass
from pathlib import Path

SCHEMA = """
CREATE TABLE IF NOT EXISTS submissions (
    id INTEGER PRIMARY KEY, folder TEXT UNIQUE NOT NULL, student TEXT NOT NULL,
    ctime_ns INTEGER NOT NULL, noticed REAL NOT NULL, state TEXT NOT NULL DEFAULT 'queued',
    tries INTEGER NOT NULL DEFAULT 0, retry_at REAL NOT NULL DEFAULT 0, error TEXT DEFAULT '',
    finished REAL NOT NULL DEFAULT 0, started REAL NOT NULL DEFAULT 0,
    spent REAL NOT NULL DEFAULT 0, reserved REAL NOT NULL DEFAULT 0);
CREATE TABLE IF NOT EXISTS notebooks (
    submission_id INTEGER NOT NULL, student TEXT NOT NULL, notebook TEXT NOT NULL,
    time REAL NOT NULL, digest TEXT NOT NULL, graded INTEGER NOT NULL,
    score REAL, max_score REAL, PRIMARY KEY (submission_id, notebook));
CREATE TABLE IF NOT EXISTS attempts (
    submission_id INTEGER NOT NULL, student TEXT NOT NULL, notebook TEXT NOT NULL,
    item TEXT NOT NULL, time REAL NOT NULL, score REAL, max_score REAL, status TEXT,
    PRIMARY KEY (submission_id, notebook, item));
CREATE INDEX IF NOT EXISTS sub_state ON submissions (state, student);
"""
STATES = ("queued", "grading", "done", "failed")
#: columns added since the first journals: a journal written before them gets them on opening
_ADDED = {name: "REAL NOT NULL DEFAULT 0" for name in ("started", "spent", "reserved")}
_ROW = "id, folder, student, ctime_ns, state, tries, spent"


@dataclass(frozen=True)
class Row:
    """A submission as the journal holds it."""

    id: int
    folder: str
    student: str
    ctime_ns: int
    state: str
    tries: int          #: tries begun before this one (:meth:`Journal.start` counts the next)
    spent: float = 0.0  #: seconds of grading used by its earlier tries


@dataclass(frozen=True)
class NotebookOutcome:
    """What one notebook of a graded submission gave (written by :meth:`Journal.finish`)."""

    notebook: str
    digest: str
    graded: bool
    score: float | None = None
    max_score: float | None = None
    items: tuple = ()          #: (item, score, max_score, status) of a graded notebook


class Journal:
    """The journal at ``path`` (created with its folder on first use)."""

    def __init__(self, path: Path):
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.db = sqlite3.connect(str(self.path), timeout=30, isolation_level=None)
        self.db.execute("PRAGMA journal_mode=WAL")
        self.db.execute("PRAGMA synchronous=FULL")
        self.db.executescript(SCHEMA)
        columns = {c[1] for c in self.db.execute("PRAGMA table_info(submissions)")}
        for column, kind in _ADDED.items():
            if column not in columns:
                self.db.execute(f"ALTER TABLE submissions ADD COLUMN {column} {kind}")

    def close(self) -> None:
        self.db.close()

    def notice(self, folder: str, student: str, ctime_ns: int) -> bool:
        """Queue the inbound ``folder`` unless known; whether it was new."""
        cur = self.db.execute(
            "INSERT OR IGNORE INTO submissions (folder, student, ctime_ns, noticed) "
            "VALUES (?, ?, ?, ?)", (folder, student, int(ctime_ns), time.time()))
        return cur.rowcount == 1

    def row_of(self, folder: str) -> Row | None:
        """The journal's row of the inbound ``folder``."""
        found = self.db.execute(f"SELECT {_ROW} FROM submissions WHERE folder=?",
                                (folder,)).fetchone()
        return Row(*found) if found else None

    def recover(self) -> int:
        """Put back in the queue what a killed service left ``grading``; how many. The time
        their tries charged ahead is given back: the service's stop is no student's doing."""
        return self.db.execute("UPDATE submissions SET state='queued', "
                               "spent=MAX(0, spent - reserved), reserved=0 "
                               "WHERE state='grading'").rowcount

    def next_ready(self, now: float | None = None) -> Row | None:
        """The next submission to grade: students ranked by when a try of theirs last
        started (never first, then the longest ago), each student's own submissions in the order
        the exchange saw them. Ranking by the last start, not the last finish, puts a student
        whose submission was just tried (and is queued again for a retry, or followed by another
        of theirs) behind everyone who was not: a retry never jumps the queue.

        A student's later submissions wait behind their own, never the class's: none is handed
        out while another of the same student is being graded, nor while an earlier one of
        theirs is postponed for a retry (a gradebook or a disk that failed it), or the later
        would be graded first and the earlier would then replace it as the last."""
        now = time.time() if now is None else now
        columns = ", ".join(f"s.{c.strip()}" for c in _ROW.split(","))
        cur = self.db.execute(
            f"SELECT {columns} FROM submissions s "
            "LEFT JOIN (SELECT student, MAX(started) AS last FROM submissions "
            "           GROUP BY student) d "
            "ON d.student = s.student "
            "WHERE s.state='queued' AND s.retry_at <= ? AND NOT EXISTS (SELECT 1 FROM "
            "submissions e WHERE e.student = s.student AND (e.state = 'grading' OR "
            "(e.state = 'queued' AND (e.ctime_ns < s.ctime_ns OR "
            "(e.ctime_ns = s.ctime_ns AND e.id < s.id))))) "
            "ORDER BY COALESCE(d.last, 0), s.ctime_ns, s.id LIMIT 1", (now,))
        found = cur.fetchone()
        return Row(*found) if found else None

    def start(self, row: Row) -> None:
        self.db.execute("UPDATE submissions SET state='grading', tries=tries+1, started=?, "
                        "reserved=0 WHERE id=?", (time.time(), row.id))

    def postpone(self, row: Row, why: str, delay: float, count_try: bool = True) -> None:
        """Back to the queue, not before ``delay`` seconds (e.g. a full disk). With
        ``count_try`` False this try is not counted against the submission (the fault was the
        course's, such as a gradebook server down, however long it stays down)."""
        self.db.execute("UPDATE submissions SET state='queued', retry_at=?, error=?, "
                        "tries=tries - ? WHERE id=?",
                        (time.time() + delay, why, 0 if count_try else 1, row.id))

    def retime(self, row: Row, ctime_ns: int) -> None:
        """The submission changed after it was noticed: its time is the newer one."""
        self.db.execute("UPDATE submissions SET ctime_ns=? WHERE id=?", (int(ctime_ns), row.id))

    def reserve(self, row: Row, seconds: float) -> None:
        """Charge ``row`` ``seconds`` its running try may use, before it uses them: a worker
        that dies meanwhile leaves them charged (its next :meth:`start` keeps them), a
        service killed meanwhile gives them back (:meth:`recover`)."""
        self.db.execute("UPDATE submissions SET spent=spent + ?, reserved=reserved + ? "
                        "WHERE id=?", (float(seconds), float(seconds), row.id))

    def spend(self, row: Row, seconds: float) -> None:
        """Add ``seconds`` (negative: give back) to the grading time ``row`` has used; what was
        reserved is settled."""
        self.db.execute("UPDATE submissions SET spent=MAX(0, spent + ?), reserved=0 WHERE id=?",
                        (float(seconds), row.id))

    def spent(self, row: Row) -> float:
        """The seconds of grading ``row``'s tries have used so far."""
        found = self.db.execute("SELECT spent FROM submissions WHERE id=?", (row.id,)).fetchone()
        return found[0] if found else 0.0

    def fail(self, row: Row, why: str) -> None:
        """``row`` is ``failed`` (``why`` kept for the instructor); the attempts it was charged
        stay charged and score 0."""
        with self._transaction():
            self.db.execute("UPDATE submissions SET state='failed', error=?, finished=? "
                            "WHERE id=?", (why, time.time(), row.id))
            self.db.execute("UPDATE notebooks SET score=0 WHERE submission_id=? AND graded=1 "
                            "AND score IS NULL", (row.id,))

    def charge(self, row: Row, notebooks: list[tuple[str, str, bool]]) -> None:
        """Record ``row``'s notebooks, ``(notebook, digest, graded)`` each, in one transaction:
        a graded one is a charged attempt from now on, whatever happens to the grading."""
        when = row.ctime_ns / 1e9
        with self._transaction():
            for notebook, digest, graded in notebooks:
                self.db.execute(
                    "INSERT OR REPLACE INTO notebooks VALUES (?, ?, ?, ?, ?, ?, NULL, NULL)",
                    (row.id, row.student, notebook, when, digest, int(graded)))

    def charged(self, row: Row) -> set[str]:
        """The notebooks an earlier try of ``row`` charged as graded attempts."""
        return {n for (n,) in self.db.execute(
            "SELECT notebook FROM notebooks WHERE submission_id=? AND graded=1", (row.id,))}

    def finish(self, row: Row, outcomes: list[NotebookOutcome]) -> None:
        """Mark ``row`` done and record its notebooks and items, in one transaction."""
        when = row.ctime_ns / 1e9
        with self._transaction():
            for o in outcomes:
                self.db.execute(
                    "INSERT OR REPLACE INTO notebooks VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                    (row.id, row.student, o.notebook, when, o.digest, int(o.graded),
                     o.score, o.max_score))
                for item, score, max_score, status in o.items:
                    self.db.execute(
                        "INSERT OR REPLACE INTO attempts VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                        (row.id, row.student, o.notebook, item, when, score, max_score, status))
            # a charged notebook the last try no longer held: the attempt stands, scored 0
            self.db.execute("UPDATE notebooks SET score=0 WHERE submission_id=? AND graded=1 "
                            "AND score IS NULL", (row.id,))
            self.db.execute("UPDATE submissions SET state='done', error='', finished=? "
                            "WHERE id=?", (time.time(), row.id))

    def _transaction(self):
        db = self.db

        class _Tx:
            def __enter__(self):
                db.execute("BEGIN IMMEDIATE")

            def __exit__(self, kind, exc, tb):
                db.execute("ROLLBACK" if kind else "COMMIT")
                return False
        return _Tx()

    def graded_since(self, student: str, notebook: str, since: float,
                     other_than: int | None = None) -> int:
        """Graded (charged) attempts of ``notebook`` by ``student`` at or after ``since``
        (epoch s), leaving out submission ``other_than``'s."""
        return self.db.execute(
            "SELECT COUNT(*) FROM notebooks WHERE student=? AND notebook=? AND graded=1 "
            "AND time >= ? AND submission_id IS NOT ?",
            (student, notebook, since, other_than)).fetchone()[0]

    def last_digest(self, student: str, notebook: str,
                    other_than: int | None = None) -> str | None:
        """The digest of ``student``'s last graded (charged) version of ``notebook``, leaving
        out submission ``other_than``'s."""
        found = self.db.execute(
            "SELECT digest FROM notebooks WHERE student=? AND notebook=? AND graded=1 "
            "AND submission_id IS NOT ? ORDER BY time DESC, submission_id DESC LIMIT 1",
            (student, notebook, other_than)).fetchone()
        return found[0] if found else None

    def best_score(self, student: str, notebook: str, before: int,
                   names: tuple[str, ...]) -> float | None:
        """The best score of the graded cells ``names`` of ``notebook`` summed per attempt, over
        ``student``'s graded attempts in submissions other than ``before`` (None when none)."""
        marks = ",".join("?" * len(names)) or "NULL"
        found = self.db.execute(
            "SELECT MAX(total) FROM (SELECT a.submission_id, SUM(COALESCE(a.score, 0)) AS total "
            "FROM attempts a JOIN notebooks n ON n.submission_id = a.submission_id "
            "AND n.notebook = a.notebook WHERE a.student=? AND a.notebook=? AND n.graded=1 "
            f"AND a.submission_id != ? AND a.item IN ({marks}) GROUP BY a.submission_id)",
            (student, notebook, before, *names)).fetchone()
        return found[0]

    def states(self) -> dict[str, int]:
        """How many submissions are in each state."""
        got = dict(self.db.execute("SELECT state, COUNT(*) FROM submissions GROUP BY state"))
        return {s: got.get(s, 0) for s in STATES}

    def attempts_rows(self) -> list[tuple]:
        """Every recorded item attempt (student, notebook, item, time, score, max_score)."""
        return list(self.db.execute(
            "SELECT student, notebook, item, time, score, max_score FROM attempts "
            "ORDER BY time, submission_id, notebook, item"))
