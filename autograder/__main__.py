"""``python -m autograder <command>``: the instructors' command line.

Each command lives in its own module with a ``add_arguments(parser)`` and a ``main(args)``:

- ``release``  student versions through ``nbgrader generate_assignment`` (autograder/release.py)
- ``grade``    sandboxed batch grading, CSV, feedback, report, gradebook (autograder/grade/)
- ``feedback`` the hand-back through nbgrader's exchange (autograder/cli_feedback.py)
- ``export``   Canvas, Moodle and long-format grades (autograder/cli_export.py)
- ``watch``    grade each submission as it arrives, feedback at once (autograder/service/)
- ``lab``      JupyterLab on the student or the instructor view (autograder/lab.py)
- ``facts``    the course's counts and marks, and where the prose disagrees (autograder/facts.py)
- ``new-exercise`` a graded function's cells, registry entry and stubs (autograder/new_exercise.py)
"""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path

from .fast_start import defer_iri_grammar

# before any command imports nbformat (2 s of CPU per run otherwise: see fast_start)
defer_iri_grammar()

COMMANDS = {
    "release": ("autograder.release", "write the student versions of the assignment"),
    "grade": ("autograder.grade.cli", "grade a folder of submissions outside the students' kernels"),
    "feedback": ("autograder.cli_feedback", "hand back marks, comments and test results "
                 "through nbgrader's exchange"),
    "export": ("autograder.cli_export", "final grades for Canvas, Moodle and the archive"),
    "watch": ("autograder.service.cli", "grade each submission as it arrives and hand its "
              "feedback back at once (the grading service)"),
    "lab": ("autograder.lab", "open JupyterLab on the course (student or instructor view)"),
    "facts": ("autograder.facts", "print the course's counts and each notebook's marks by part "
              "(--check: where the docs or the notebooks' text disagree)"),
    "new-exercise": ("autograder.new_exercise", "add a graded function: its cells, registry "
                     "entry, reference, honest answer and test stubs"),
}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m autograder", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    for name, (module_name, help_text) in COMMANDS.items():
        p = sub.add_parser(name, help=help_text, description=help_text[0].upper() + help_text[1:] + ".")
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            if exc.name != module_name:
                raise
            p.set_defaults(_missing=module_name)
            continue
        module.add_arguments(p)
        p.set_defaults(_main=module.main)
    args = parser.parse_args(argv)
    if getattr(args, "_missing", None):
        parser.error(f"command {args.command!r} is not available ({args._missing} is missing)")
    return int(args._main(args) or 0)


def missing_package(exc: ModuleNotFoundError) -> str:
    """What to do when a package the course installs is not importable: almost always this
    Python is not the course's environment (``.venv``)."""
    here = Path(__file__).resolve().parents[1]
    venv = here / ".venv"
    if Path(sys.prefix).resolve() == venv.resolve():
        return (f"error: {exc}: the course's environment {venv} is incomplete; reinstall it "
                "with `make setup`")
    return (f"error: {exc}: this Python ({sys.executable}) is not the course's environment: "
            f"activate .venv (. .venv/bin/activate) or run .venv/bin/python -m autograder ... "
            f"from {here} (`make setup` creates .venv)")


def run(argv: list[str] | None = None) -> int:
    """:func:`main`, with a missing third-party package said in one line (exit status 2)."""
    try:
        return main(argv)
    except ModuleNotFoundError as exc:
        if (exc.name or "").split(".")[0] == "autograder":
            raise
        print(missing_package(exc), file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(run())
