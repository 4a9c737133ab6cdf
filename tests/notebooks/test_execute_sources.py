"""Every source (instructor) notebook runs top to bottom without an error.

The source notebooks carry the model solutions and the hidden tests
(``autograder.incell.check`` against the ``course_lib`` references on the registry's cases), so
this also checks that every model solution agrees with its reference on every case.
Each notebook runs in its own ``python3`` kernel with ``notebooks/`` as working directory and a
per-cell timeout; two notebooks may run at once under ``pytest -n 2`` (separate kernels).
"""

from __future__ import annotations

import pytest
from nbtools import CELL_TIMEOUT, execute, nbgrader_meta

from autograder.course import NOTEBOOKS_DIR, source_notebooks

NOTEBOOKS = source_notebooks()


@pytest.mark.slow
@pytest.mark.timeout(900)
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_source_notebook_executes(path):
    nb = execute(path, cwd=NOTEBOOKS_DIR, allow_errors=False, timeout=CELL_TIMEOUT)
    # nbgrader scores a test cell that writes to stderr as 0 (a warning is enough): the model
    # solutions must pass their own test cells silently
    noisy = [
        f"{nbgrader_meta(c)['grade_id']}: {out.get('text', '')[:200]!r}"
        for c in nb.cells
        if c.cell_type == "code" and nbgrader_meta(c).get("grade")
        for out in c.get("outputs", [])
        if out.get("output_type") == "stream" and out.get("name") == "stderr"
    ]
    assert not noisy, "graded test cells wrote to stderr (nbgrader would score them 0):\n" + \
        "\n".join(noisy)
