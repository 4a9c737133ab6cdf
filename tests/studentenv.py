"""The students' environment of the tests: their wheel installed alone in a venv of its own.

Building the wheel (Cython, every ``course_lib`` module but the package ``__init__`` files and
``answers``) takes a minute or more on two cores, and installing it with JupyterLab and nbgrader
another, so both are shared: the wheel is cached under ``test-artifacts/student/build/`` keyed
on a digest of its sources (``autograder.student_bundle.sources_digest``), the environment is
``test-artifacts/student/venv/`` (created on first use; the wheel is reinstalled whenever its
digest changes). File locks make test modules on different xdist workers wait for one another
instead of building twice. A fresh checkout (CI) builds and installs from nothing.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

from autograder import student_bundle

REPO = Path(__file__).resolve().parents[1]
ROOT = REPO / "test-artifacts" / "student"
BUILD_CACHE = ROOT / "build"
ENV_DIR = ROOT / "venv"


def wheel() -> Path:
    """The student wheel of the current sources (built on first use)."""
    return student_bundle.build_wheel(BUILD_CACHE)


def python(wheel_path: Path | None = None) -> Path:
    """The student environment's interpreter, with ``wheel_path`` (default :func:`wheel`) in it."""
    return student_bundle.ensure_student_env(ENV_DIR, wheel_path or wheel())


def env_vars() -> dict:
    """Environment of a student-environment process: its ``bin/`` first, headless figures."""
    env = student_bundle.student_env_vars(ENV_DIR)
    env["MPLBACKEND"] = "Agg"
    return env


def run(code: str, *args: str, cwd: Path, timeout: int = 900) -> subprocess.CompletedProcess:
    """Run ``code`` with the student interpreter in isolated mode (``-I``: neither the working
    directory nor ``PYTHON*`` variables reach ``sys.path``), from ``cwd`` (keep it outside the
    repository)."""
    assert not Path(cwd).resolve().is_relative_to(REPO), f"{cwd} is inside the repository"
    return subprocess.run([str(python()), "-I", "-c", code, *args], cwd=cwd, env=env_vars(),
                          capture_output=True, text=True, timeout=timeout, check=False)


def site_packages() -> Path:
    """The student environment's ``site-packages`` folder."""
    found = sorted(ENV_DIR.glob("lib/python*/site-packages")) if os.name != "nt" else \
        [ENV_DIR / "Lib" / "site-packages"]
    assert len(found) == 1, found
    return found[0].resolve()
