"""Names and places shared by the hub test's fixture and its test module."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
if str(REPO / "deploy") not in sys.path:
    sys.path.insert(0, str(REPO / "deploy"))  # deploy/hub.py, imported as ``hub``

ARTIFACTS = REPO / "test-artifacts" / "deploy"
#: the two environments, cached between runs (HUB_TEST_ENVS: elsewhere, e.g. while debugging)
ENVS = Path(os.environ.get("HUB_TEST_ENVS", str(ARTIFACTS / "envs")))
CHROMIUM = Path("/usr/bin/chromium")
#: test accounts: a prefix no real account has
PREFIX = "t4f9"
STUDENTS = (f"{PREFIX}ana", f"{PREFIX}ben")
INSTRUCTOR = f"{PREFIX}prof"
GRADER = f"{PREFIX}grader"
#: the grading service's hub (test_hub_grading.py): a prefix of its own, so it never removes
#: the term test's accounts; three students alone, then a class of 30 in a burst
GRADING_PREFIX = "t4g"
LONE = tuple(f"{GRADING_PREFIX}{n}" for n in ("ana", "ben", "cat"))
BURST = tuple(f"{GRADING_PREFIX}b{i:02d}" for i in range(1, 31))


def missing_for_accounts(what: str, tools: tuple[tuple[str, str], ...]) -> str | None:
    """Why a test that makes Unix users cannot run here (``what`` it does, the ``(tool path,
    Debian package)`` it needs), or ``None``."""
    import hub  # deploy/hub.py

    if sys.platform != "linux" or os.geteuid() != 0:
        return f"{what}: run it as root"
    for tool, package in tools:
        if not Path(tool).exists():
            return f"{tool} is missing (Debian package {package}; `make hub-deps` installs it)"
    if subprocess.run([hub.SYSTEM_PYTHON, "-c", "import ensurepip, venv"],
                      capture_output=True).returncode != 0:
        return "Debian's python3-venv is missing (`make hub-deps` installs it)"
    return None
