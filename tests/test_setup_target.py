"""``make setup`` installs and starts nothing; ``pyproject.toml`` uses the licence form setuptools
keeps supporting (the table form stops working after 2027-02-18)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    tomllib = pytest.importorskip("tomli")

REPO = Path(__file__).resolve().parents[1]


def test_the_licence_is_an_spdx_string_with_a_setuptools_that_reads_it():
    meta = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))
    assert meta["project"]["license"] == "MIT"          # a string, not {text = ...}
    backend = [r for r in meta["build-system"]["requires"] if r.startswith("setuptools")]
    low = re.match(r"setuptools>=(\d+)", backend[0])
    assert low and int(low.group(1)) >= 77, backend   # PEP 639 strings: setuptools 77+


def test_make_setup_installs_and_starts_no_server(tmp_path):
    """What ``make -n setup`` would run (nothing is run): the install, no lab, hub or server."""
    plan = subprocess.run(["make", "-n", "-B", "setup"], cwd=REPO, capture_output=True,
                          text=True, timeout=60)
    assert plan.returncode == 0, plan.stderr
    assert "pip install" in plan.stdout and "-m venv" in plan.stdout
    for server in ("autograder lab", "jupyterhub", "jupyter lab", "autograder hub"):
        assert server not in plan.stdout, server
