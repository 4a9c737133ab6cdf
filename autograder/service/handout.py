"""Placing a page where nbgrader's Fetch Feedback finds it, and keeping the counting copy.

A page goes to ``<course>/feedback/<student>/tripos2006/<notebook>.html`` beside the
submission's ``timestamp.txt`` and ``submission_secret.txt`` (the layout ``python -m autograder
feedback`` writes), then to ``<exchange>/<course id>/feedback/<hash>.html`` exactly as nbgrader's
``release_feedback`` names it (``nbgrader.utils.notebook_hash`` of the submission's secret and
the notebook), written to a temporary name and renamed, so a student fetching meanwhile gets the
old page or the new one, never half of one. Every submission has its own secret, so each
submission's pages are its own.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from ..course import COURSE_ID
from ..course import ASSIGNMENT
from ..outputs.gradebook import CARRIED_FILES

SECRET_FILE = "submission_secret.txt"
#: the exchange's feedback folder: rwx--x--x, nbgrader's ``ExchangeReleaseFeedback`` mode
OUTBOUND_MODE = 0o711


def write_atomic(path: Path, text: str, mode: int = 0o644) -> None:
    """Write ``text`` to ``path`` through a temporary file and a rename."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp")
    with open(tmp, "w", encoding="utf-8") as fh:
        fh.write(text)
        fh.flush()
        os.fsync(fh.fileno())
    os.chmod(tmp, mode)
    os.replace(tmp, path)


def hand_out(course: Path, exchange: Path | None, collected: Path, student: str,
             notebook: str, html: str) -> Path | None:
    """Write the page and release it; the exchange's file (None without an exchange or
    without the submission's secret, which only nbgrader's submit writes)."""
    from nbgrader.utils import notebook_hash

    folder = Path(course) / "feedback" / student / ASSIGNMENT
    folder.mkdir(parents=True, exist_ok=True)
    for name in CARRIED_FILES:
        kept = Path(collected) / name
        if kept.is_file() and not kept.is_symlink():
            shutil.copyfile(kept, folder / name)
    write_atomic(folder / f"{notebook}.html", html)
    secret = Path(collected) / SECRET_FILE
    if exchange is None or not secret.is_file():
        return None
    outbound = Path(exchange) / COURSE_ID / "feedback"
    if not outbound.is_dir():
        outbound.mkdir(parents=True, exist_ok=True)
        # as nbgrader's release_feedback makes it: students may enter it (to fetch their own
        # page by its hashed name) but not list it (nor so read a classmate's)
        os.chmod(outbound, OUTBOUND_MODE)
    target = outbound / f"{notebook_hash(secret=secret.read_text(), notebook_id=notebook)}.html"
    write_atomic(target, html)
    return target


def keep_counting(course: Path, collected: Path, student: str, notebooks: list[str]) -> Path:
    """Copy the counting ``notebooks`` of the collected submission, with its timestamp and
    secret, into ``<course>/submitted/<student>/tripos2006/`` (what ``grade`` and the
    gradebook read); returns that folder."""
    target = Path(course) / "submitted" / student / ASSIGNMENT
    target.mkdir(parents=True, exist_ok=True)
    for name in [f"{n}.ipynb" for n in notebooks] + list(CARRIED_FILES):
        kept = Path(collected) / name
        if kept.is_file() and not kept.is_symlink():
            tmp = target / f".{name}.tmp"
            shutil.copyfile(kept, tmp)
            os.replace(tmp, target / name)
    return target
