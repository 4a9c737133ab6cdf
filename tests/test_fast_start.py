"""``autograder.fast_start``: ``python -m autograder`` no longer builds the RFC 3987 parser at
start, and IRIs are judged exactly as before.

Oracle: the same checks in a process that builds the parser the ordinary way. Both processes
run without ``PYTHONPATH``, so the tests' own ``sitecustomize`` (which defers it too) is out.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]

IRIS = ["http://example.com/a?b=c#d", "https://例え.jp/パス", "urn:isbn:0451450523",
        "http://exa mple.com", "no scheme", "http://[::1]:80/", "mailto:kim@cam.ac.uk", ""]
CHECK = f"""
import json, sys
if sys.argv[1] == "deferred":
    from autograder.fast_start import defer_iri_grammar
    defer_iri_grammar()
import nbformat  # noqa: F401 - the import that would build the parser
from jsonschema import FormatChecker
built_at_import = "rfc3987_syntax.syntax_helpers" in sys.modules
checker = FormatChecker()
print(json.dumps([built_at_import] + [[checker.conforms(s, f) for f in ("iri", "iri-reference")]
                                      for s in {IRIS!r}]))
"""


def _run(args: list[str]) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    return subprocess.run([sys.executable, *args], cwd=REPO_ROOT, env=env, capture_output=True,
                          text=True, timeout=300)


def test_the_cli_does_not_build_the_iri_parser_at_start():
    proc = _run(["-X", "importtime", "-m", "autograder", "grade", "--help"])
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "--out" in proc.stdout
    imported = proc.stderr
    assert "nbformat" in imported                      # the import that would have built it
    assert "rfc3987_syntax.syntax_helpers" not in imported


def test_iris_are_judged_as_without_the_deferral():
    ordinary = json.loads(_run(["-c", CHECK, "ordinary"]).stdout)
    deferred = json.loads(_run(["-c", CHECK, "deferred"]).stdout)
    assert ordinary[0] is True and deferred[0] is False
    assert deferred[1:] == ordinary[1:]
    assert [True, True] in ordinary[1:] and [False, False] in ordinary[1:]
