"""The exchange's feedback folder the service makes: enterable, not listable, as nbgrader's
``release_feedback`` makes it (``S_IRWXU | S_IXGRP | S_IXOTH``), so on the hub a student fetches
their own page by its hashed name and cannot list (nor so read) a classmate's."""

from __future__ import annotations

import stat
from stat import S_IRWXU, S_IXGRP, S_IXOTH

from autograder.course import COURSE_ID
from autograder.service import handout


def test_the_feedback_folder_is_not_listable(tmp_path):
    collected = tmp_path / "collected"
    collected.mkdir()
    (collected / handout.SECRET_FILE).write_text("a-submission-secret")
    exchange = tmp_path / "exchange"
    page = handout.hand_out(tmp_path / "course", exchange, collected, "ab123", "q1_imaging",
                            "<html>page</html>")
    folder = exchange / COURSE_ID / "feedback"
    assert page is not None and page.parent == folder
    assert stat.S_IMODE(folder.stat().st_mode) == S_IRWXU | S_IXGRP | S_IXOTH
    assert stat.S_IMODE(page.stat().st_mode) & 0o444 == 0o444     # readable once named
    assert page.read_text() == "<html>page</html>"
