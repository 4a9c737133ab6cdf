"""What the instructor's commands say: ``make instructor`` prints its URL only once the server
accepts connections; the students' exchange configuration names the course's exchange."""

from __future__ import annotations

import socket
import subprocess
import sys
import textwrap
import time

from autograder.course import STUDENT_CONFIG, student_config_text
from autograder.lab import wait_until_listening

SLOW_SERVER = textwrap.dedent("""
    import socket, sys, time
    time.sleep(float(sys.argv[2]))
    s = socket.socket(); s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    s.bind(("127.0.0.1", int(sys.argv[1]))); s.listen(5)
    while True:
        c, _ = s.accept(); c.close()
""")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_the_url_waits_for_the_server_to_listen():
    port = _free_port()
    proc = subprocess.Popen([sys.executable, "-c", SLOW_SERVER, str(port), "1.5"])
    try:
        t0 = time.monotonic()
        assert wait_until_listening(proc, "127.0.0.1", port, timeout=60, poll=0.05)
        waited = time.monotonic() - t0
        with socket.create_connection(("127.0.0.1", port), timeout=5):
            pass                                   # the server answers when the URL is shown
        assert waited >= 1.0, "returned before the server listened"
    finally:
        proc.kill()
        proc.wait()


def test_a_server_that_exits_is_not_waited_for():
    port = _free_port()
    proc = subprocess.Popen([sys.executable, "-c", "raise SystemExit(3)"])
    assert not wait_until_listening(proc, "127.0.0.1", port, timeout=60, poll=0.05)
    assert proc.wait() == 3


def test_the_students_config_names_the_courses_exchange(tmp_path):
    """Read by traitlets as nbgrader reads it: the exchange root and the course id."""
    from traitlets.config.loader import PyFileConfigLoader

    path = tmp_path / STUDENT_CONFIG
    path.parent.mkdir(parents=True)
    path.write_text(student_config_text(tmp_path / "exchange"))
    config = PyFileConfigLoader(path.name, str(path.parent)).load_config()
    assert config.Exchange.root == str((tmp_path / "exchange").resolve())
    assert config.CourseDirectory.course_id == "4f9"


def test_a_choice_answer_is_shown_in_the_markers_letters():
    """The student's right answer, in their letters, maps to the canonical key (the
    instructors' order); every one of their letters maps to a different option."""
    import re

    from autograder.exercises import REGISTRY
    from autograder.outputs.choices import choice_legend

    choices = [ex for ex in REGISTRY.values() if ex.kind == "choice"]
    assert choices
    for ex in choices:
        for student in ("ab123", "xy987", "cd456"):
            legend = choice_legend(ex.name, student, ex.key_for(student).upper())
            mapped = re.findall(r"their \((\w)\) is \((\w)\) here", legend)
            assert [a for a, _ in mapped] == list("abcdefgh"[:len(ex.options)])
            assert sorted(b for _, b in mapped) == sorted(ex.options)
            answer = re.search(r"their answer '[^']*' is (.*) here$", legend).group(1)
            assert "".join(re.findall(r"\((\w)\)", answer)) == ex.key_for(None), legend
    assert choice_legend("no_such_item", "ab123") == ""
