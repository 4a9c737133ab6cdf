"""``python -m autograder watch --help`` states each option's default."""

from __future__ import annotations

import argparse
import os
import subprocess
import sys


def test_every_option_of_watch_states_its_default():
    from autograder.course import DEFAULT_COURSE_ROOT
    from autograder.service.cli import add_arguments

    parser = argparse.ArgumentParser(prog="watch")
    add_arguments(parser)
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction):
            continue
        text = action.help % vars(action) if "%(" in action.help else action.help
        flag = action.option_strings[0]
        assert "default:" in text or text.endswith("required"), flag
        # a default the parser really holds is the one the help names
        if isinstance(action.default, (int, float)) and not isinstance(action.default, bool):
            assert f"{action.default:g}" in text, (flag, action.default, text)
    assert f"default: {DEFAULT_COURSE_ROOT}" in " ".join(parser.format_help().split())
    assert parser.parse_args(["--exchange", "x"]).jobs == max(1, min(8, os.cpu_count() or 1))


def test_watch_help_runs_and_names_the_defaults():
    out = subprocess.run([sys.executable, "-m", "autograder", "watch", "--help"],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    flat = " ".join(out.stdout.split())
    for expected in ("default: 2", "default: 10", "default: 2048", "required",
                     "default: sqlite:///COURSE/gradebook.db"):
        assert expected in flat, expected
