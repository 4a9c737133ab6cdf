"""Builders of the service's tests: an exchange, submissions as nbgrader's submit writes them,
a service on a fresh course."""

from __future__ import annotations

import copy
import json
import os
import secrets
import shutil
import time
from pathlib import Path

from gradingtools import CASE_TIMEOUT, SECRET, model_version, set_cell, typed_version

from autograder.course import COURSE_ID
from autograder.grade.batch import Options
from autograder.isolation import Limits
from autograder.course import ASSIGNMENT
from autograder.service.grading import Service
from autograder.service.journal import Journal
from autograder.service.policy import Policy


def own_uid(_student: str) -> int:
    """Every folder counts as its student's: the tests run as one Unix user."""
    return os.getuid()


def make_service(tmp: Path, sources, mode, gradebook_db: Path | None, **policy) -> Service:
    course, exchange = tmp / "course", tmp / "exchange"
    inbound = exchange / COURSE_ID / "inbound"
    inbound.mkdir(parents=True)
    (course / "service").mkdir(parents=True)
    db_url = None
    if gradebook_db is not None:
        shutil.copyfile(gradebook_db, course / "gradebook.db")
        db_url = f"sqlite:///{course / 'gradebook.db'}"
    limits = Limits(case_timeout=CASE_TIMEOUT, load_timeout=30.0)
    opts = Options(out=course / "service", jobs=2, limits=limits, secret=SECRET, mode=mode,
                   progress=False)
    return Service(course, inbound, exchange, Journal(course / "service" / "journal.db"),
                   Policy(**policy), sources, opts, {s.name: 60.0 for s in sources}, db_url,
                   uid_of=own_uid)


def honest(src, student: str) -> dict:
    """The model answer of ``src`` as ``student`` hands it in (items typed for them)."""
    return typed_version(model_version(src), student)


def with_cell(nb: dict, grade_id: str, source: str) -> dict:
    return set_cell(copy.deepcopy(nb), grade_id, source)


def submit(svc: Service, student: str, notebooks: dict[str, dict]) -> str:
    """A submission folder in the inbound as nbgrader's submit writes it (notebooks,
    ``timestamp.txt``, ``submission_secret.txt``); its name."""
    stamp = time.strftime("%Y-%m-%d %H:%M:%S.000000 UTC", time.gmtime())
    name = f"{student}+{ASSIGNMENT}+{stamp}+{secrets.token_hex(9)}"
    folder = svc.inbound / name
    folder.mkdir()
    for nb_name, nb in notebooks.items():
        (folder / f"{nb_name}.ipynb").write_text(json.dumps(nb), encoding="utf-8")
    (folder / "timestamp.txt").write_text(stamp)
    (folder / "submission_secret.txt").write_text(secrets.token_hex(16))
    return name


def later() -> float:
    """A clock past the inbound's settling time (no test waits for it)."""
    return time.time() + 3600


def exchange_page(svc: Service, folder: str, notebook: str) -> str:
    """The page nbgrader's fetch_feedback would fetch for ``folder``'s ``notebook``."""
    from nbgrader.utils import notebook_hash

    secret = (svc.inbound / folder / "submission_secret.txt").read_text()
    path = svc.exchange / COURSE_ID / "feedback" / \
        f"{notebook_hash(secret=secret, notebook_id=notebook)}.html"
    return path.read_text(encoding="utf-8")


def reopen_service(tmp: Path, mode) -> Service:
    """The service :func:`make_service` built under ``tmp``, opened again (a restart)."""
    from gradingtools import course_sources

    course, exchange = tmp / "course", tmp / "exchange"
    limits = Limits(case_timeout=CASE_TIMEOUT, load_timeout=30.0)
    opts = Options(out=course / "service", jobs=2, limits=limits, secret=SECRET, mode=mode,
                   progress=False)
    sources = course_sources()
    return Service(course, exchange / COURSE_ID / "inbound", exchange,
                   Journal(course / "service" / "journal.db"), Policy(), sources, opts,
                   {s.name: 60.0 for s in sources}, f"sqlite:///{course / 'gradebook.db'}",
                   uid_of=own_uid)


def auto_scores(svc, student, notebook) -> dict:
    """``{test id: automatic score}`` of ``student``'s ``notebook`` in the service's gradebook."""
    import warnings

    from nbgrader.api import Gradebook

    with warnings.catch_warnings(), Gradebook(svc.db_url, course_id="4f9") as gb:
        warnings.simplefilter("ignore")
        nb = gb.find_submission_notebook(notebook, ASSIGNMENT, student)
        return {g.name: g.auto_score for g in nb.grades}
