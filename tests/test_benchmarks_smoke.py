"""The benchmarks keep working: ``python -m benchmarks --smoke`` runs every section at tiny sizes.

Benchmarks never fail on time; this only checks that each section still runs end to end
(exit status 0) and contributes at least one row to the results table it writes.
"""

from __future__ import annotations

import importlib
import math
import subprocess
import sys

import pytest

pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("benchmarks-smoke")]


def _expected_sections() -> dict[str, str]:
    """``{module: section label}`` of every ``benchmarks/bench_*.py``."""
    from benchmarks.__main__ import sections

    out = {}
    for name in sections():
        mod = importlib.import_module(f"benchmarks.{name}")
        out[name] = getattr(mod, "SECTION", name[len("bench_"):].replace("_", " "))
    return out


def _table_rows(text: str) -> list[list[str]]:
    rows = []
    for line in text.splitlines():
        if line.startswith("| ") and not line.startswith("| section") and "---" not in line:
            rows.append([c.strip() for c in line.strip().strip("|").split("|")])
    return rows


def test_smoke_run_has_a_row_for_every_section(repo_root, tmp_path):
    from autograder.course import nbgrader_env

    out = tmp_path / "r.md"
    proc = subprocess.run(
        [sys.executable, "-m", "benchmarks", "--smoke", "--out", str(out)],
        cwd=repo_root, env=nbgrader_env(), capture_output=True, text=True, timeout=600, check=False)
    assert proc.returncode == 0, proc.stderr[-3000:]
    text = out.read_text(encoding="utf-8")
    assert text.startswith("# Benchmark results") and "(smoke sizes)" in text
    assert "cores" in text and "NumPy" in text          # the machine line

    rows = _table_rows(text)
    assert rows, text
    assert all(len(r) == 7 for r in rows), rows
    found = {r[0] for r in rows}
    expected = _expected_sections()
    missing = {mod: label for mod, label in expected.items() if label not in found}
    assert not missing, f"sections without a row: {missing}\n{text}"
    # the printed table is the written one
    assert all(f"| {r[0]} | {r[1]} |" in proc.stdout for r in rows)


def test_ratio_is_ours_over_peer():
    """The table's ratio column: below 1 means ours is faster (a quick check of the harness
    contract the sections rely on)."""
    from benchmarks.harness import Row

    assert Row("s", "c", "m", 2.0, 4.0).ratio == 0.5
    assert Row("s", "c", "m", 2.0).ratio is None
    assert Row("s", "c", "m", math.nan, 4.0).ratio is None  # not measured: no ratio


def test_a_run_of_one_section_keeps_the_other_sections_rows():
    """``--only bench_x`` replaces that section's rows in ``results.md`` and keeps the rest."""
    from benchmarks.__main__ import RESULTS_INTRO, results_file, table
    from benchmarks.harness import Row

    def row(section, case, ours):
        return Row(section=section, case=case, metric="time", ours=ours, peer=2.0, unit="s",
                   peer_name="peer", notes="")

    old = results_file([row("browser", "a", 1.0), row("grading", "b", 3.0)], "day one")
    new = results_file([row("browser", "a", 0.5)], "day two", old)
    rows = _table_rows(new)
    assert [(r[0], r[3]) for r in rows] == [("browser", "0.5 s"), ("grading", "3 s")]
    assert "Measured day two: the rows of browser." in new and "Measured day one." in new
    assert new.count(RESULTS_INTRO) == 1 and new.count(table([]).splitlines()[0]) == 1
