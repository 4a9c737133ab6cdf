"""``grade`` run as root hands what it wrote back to the course folder's owner
(:mod:`autograder.grade.ownership`): an instructor who marks in the Formgrader as themselves
must be able to write the gradebook and the ``autograded/`` notebooks."""

from __future__ import annotations

import os

import pytest

from autograder.grade import ownership

pytestmark = pytest.mark.skipif(os.geteuid() != 0, reason="only root can chown")

INSTRUCTOR = 4242          # an account that is not root (no need for it to exist)


def _course(tmp_path, owner: int):
    course = tmp_path / "course"
    (course / "autograded" / "ab123").mkdir(parents=True)
    (course / "autograded" / "ab123" / "q1.ipynb").write_text("{}")
    (course / "gradebook.db").write_text("")
    (course / "autograded" / "outside").symlink_to("/etc/hostname")
    os.chown(course, owner, owner)
    return course


def test_root_written_files_go_to_the_course_owner_and_links_are_not_followed(tmp_path):
    course = _course(tmp_path, INSTRUCTOR)
    before = os.stat("/etc/hostname").st_uid
    changed = ownership.give_back(course, [course / "autograded", course / "gradebook.db",
                                           course / "not-there"])
    assert changed == 5      # autograded, ab123, q1.ipynb, the link itself, gradebook.db
    for path in (course / "autograded", course / "autograded" / "ab123" / "q1.ipynb",
                 course / "gradebook.db"):
        st = os.stat(path)
        assert (st.st_uid, st.st_gid) == (INSTRUCTOR, INSTRUCTOR), path
    assert os.lstat(course / "autograded" / "outside").st_uid == INSTRUCTOR
    assert os.stat("/etc/hostname").st_uid == before == 0


def test_a_course_root_owns_is_left_as_it_is(tmp_path):
    course = _course(tmp_path, 0)
    assert ownership.give_back(course, [course / "autograded"]) == 0
    assert os.stat(course / "autograded" / "ab123" / "q1.ipynb").st_uid == 0


def test_files_another_account_owns_keep_their_owner(tmp_path):
    course = _course(tmp_path, INSTRUCTOR)
    other = course / "autograded" / "ab123" / "q1.ipynb"
    os.chown(other, 5151, 5151)
    ownership.give_back(course, [course / "autograded"])
    assert os.stat(other).st_uid == 5151
