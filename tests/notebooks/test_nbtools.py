"""``nbtools.first_untagged_error`` finds the cell where nbclient's ``allow_errors=False`` stops.

The release notebooks run once with ``allow_errors=True`` (``execute_shared``) for two test
modules; the Run All test then asks ``first_untagged_error``. Here nbclient itself is the oracle.
"""

from __future__ import annotations

import nbformat
import pytest
from nbclient.exceptions import CellExecutionError
from nbtools import execute, execute_shared, first_untagged_error


def _notebook(path, untagged_fails: bool):
    nb = nbformat.v4.new_notebook()
    tagged = nbformat.v4.new_code_cell("raise NotImplementedError('a stub')")
    tagged.metadata["tags"] = ["raises-exception"]
    later = nbformat.v4.new_code_cell("x = 1 / 0" if untagged_fails else "x = 1")
    nb.cells = [nbformat.v4.new_code_cell("y = 2"), tagged, later, nbformat.v4.new_code_cell("x + y")]
    nbformat.write(nb, str(path))
    return path


@pytest.mark.parametrize("untagged_fails", [False, True])
def test_the_shared_run_tells_what_run_all_would(tmp_path, untagged_fails):
    path = _notebook(tmp_path / "n.ipynb", untagged_fails)
    stopped = first_untagged_error(execute_shared(path, cwd=tmp_path))
    if untagged_fails:
        with pytest.raises(CellExecutionError, match="ZeroDivisionError"):
            execute(path, cwd=tmp_path)
        assert stopped and stopped.startswith("cell 2: x = 1 / 0") and "ZeroDivisionError" in stopped
    else:
        execute(path, cwd=tmp_path)        # nbclient runs through: so must the shared run
        assert stopped is None
    # a second call is the same run, and a copy: changing it changes no later caller's
    again = execute_shared(path, cwd=tmp_path)
    again.cells.clear()
    assert len(execute_shared(path, cwd=tmp_path).cells) == 4
