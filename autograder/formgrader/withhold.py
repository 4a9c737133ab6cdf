"""nbgrader's ``generate_feedback`` without the marker's rubric cells.

The autograded notebooks carry, after each written answer, a cell for the marker with the
model answer and the rubric, tagged in its metadata (``RUBRIC_KEY``). The course's
``nbgrader_config.py`` puts :class:`WithholdRubrics` first in
``GenerateFeedback.preprocessors``, so a page written by nbgrader's own ``generate_feedback``
(a command typed by hand, or a Formgrader without the course's guard) never shows them.
"""

from __future__ import annotations

from nbconvert.preprocessors import Preprocessor
from traitlets import Bool

from ..outputs.gradebook import RUBRIC_KEY

#: Text that starts every rubric cell (a second way to know one, should its tag be lost).
RUBRIC_HEADING = "**For the marker of `"


def is_rubric(cell) -> bool:
    """A marker's cell: tagged ``RUBRIC_KEY``, or starting with the rubric cell's heading."""
    meta = cell.get("metadata") or {}
    return bool(meta.get(RUBRIC_KEY)) or str(cell.get("source", "")).startswith(RUBRIC_HEADING)


class WithholdRubrics(Preprocessor):
    """Drop every marker's cell (model answer and rubric) from a notebook."""

    #: nbconvert registers a preprocessor named in configuration switched off unless it says
    enabled = Bool(True).tag(config=True)

    def preprocess(self, nb, resources):
        nb.cells = [c for c in nb.cells if not is_rubric(c)]
        return nb, resources
