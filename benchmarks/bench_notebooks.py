"""Notebooks: wall time to execute each source notebook top to bottom (nbclient)."""

from __future__ import annotations

import time

import nbformat
from nbclient import NotebookClient

from .harness import REPO, Row


def run(smoke: bool = False) -> list[Row]:
    rows = []
    notebooks = sorted((REPO / "notebooks").glob("q*.ipynb"))
    for path in notebooks[:1] if smoke else notebooks:
        nb = nbformat.read(path, as_version=4)
        client = NotebookClient(nb, timeout=600, kernel_name="python3",
                                resources={"metadata": {"path": str(path.parent)}})
        t0 = time.perf_counter()
        client.execute()
        rows.append(Row("notebooks", path.stem, "execute top to bottom",
                        (time.perf_counter() - t0), unit="s",
                        notes=f"{len(nb.cells)} cells, kernel start included"))
    return rows
