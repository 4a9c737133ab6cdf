"""Names and places shared by the hub test's fixture and its test module."""

from __future__ import annotations

import os
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
