"""``python -m autograder`` run by a Python that is not the course's environment says what to do
in one line (activate .venv, or run .venv/bin/python), not with a traceback."""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

from autograder import __main__ as entry

REPO = Path(__file__).resolve().parents[2]


def test_a_missing_package_is_one_line_with_the_remedy(monkeypatch, capsys):
    real = importlib.import_module

    def without_nbformat(name, *a, **k):
        if name == "autograder.release":
            raise ModuleNotFoundError("No module named 'nbformat'", name="nbformat")
        return real(name, *a, **k)
    monkeypatch.setattr(entry.importlib, "import_module", without_nbformat)
    monkeypatch.setattr(entry.sys, "prefix", "/usr")               # not the course's .venv
    assert entry.run(["export", "--out", "x"]) == 2
    err = capsys.readouterr().err
    assert "No module named 'nbformat'" in err and "Traceback" not in err
    assert "activate .venv (. .venv/bin/activate) or run .venv/bin/python -m autograder" in err


def test_an_error_of_the_course_itself_is_not_hidden(monkeypatch):
    def broken(name, *a, **k):
        raise ModuleNotFoundError("No module named 'autograder.nothing'", name="autograder.x")
    monkeypatch.setattr(entry.importlib, "import_module", broken)
    with pytest.raises(ModuleNotFoundError):
        entry.run(["export", "--out", "x"])


def test_the_systems_python_says_so():
    base = Path(sys.base_prefix) / "bin" / "python3"
    probe = subprocess.run([str(base), "-c", "import nbformat"], capture_output=True)
    if not base.is_file() or probe.returncode == 0:
        pytest.skip("no Python without the course's packages on this machine")
    env = {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "PYTHONPATH")}
    proc = subprocess.run([str(base), "-m", "autograder", "grade", "x", "--out", "y"],
                          cwd=REPO, env=env, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert ". .venv/bin/activate" in proc.stderr and ".venv/bin/python -m autograder" in proc.stderr
