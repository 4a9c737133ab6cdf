"""Whose numbers a submitted notebook worked.

The grader always judges number items and option letters for the student of the submission's
folder. When the notebook shows it worked another id's numbers (a ``STUDENT_ID`` typed in a code
cell, or a saved output "Your numbers (student X)"), the grader checks whether each wrong item
fits one of those ids. That goes to the instructors' report at once, and into the student's
feedback only once hidden tests are revealed (after the deadline): before it, a note naming ids
of the student's own choosing would be an oracle for the option keys (red-team finding F1).

The scan is bounded (a few ids, the first outputs of each cell, the start of each text) and
runs once per submission, so a notebook full of made-up ids costs nothing (finding F2).
"""

from __future__ import annotations

import re

from ..model import Submission

_ID = r"([A-Za-z0-9][A-Za-z0-9._@+-]{0,127})"
_PRINTED = re.compile(r"Your numbers \(student " + _ID + r"\)")
_TYPED = re.compile(r"""^\s*STUDENT_ID\s*=\s*["']""" + _ID + """["']""", re.MULTILINE)
#: Characters of one cell's source or one saved output the search reads (a header is near the start).
SCAN_CHARS = 4000
#: Saved outputs read per code cell.
SCAN_OUTPUTS = 8
#: Ids other than the folder's own that are checked at most.
MAX_OTHERS = 3


def other_students(sub: Submission) -> list[str]:
    """Up to :data:`MAX_OTHERS` ids other than the folder's own that the notebook names, in
    notebook order (case as written)."""
    own = sub.student.lower()
    found: list[str] = []
    seen = {own}
    for cell in sub.cells:
        if cell.get("cell_type") != "code":
            continue
        for text in [cell.get("source", "")] + _output_texts(cell.get("raw") or {}):
            for rx in (_TYPED, _PRINTED):
                for match in rx.finditer(text[:SCAN_CHARS]):
                    sid = match.group(1)
                    if sid.lower() not in seen:
                        seen.add(sid.lower())
                        found.append(sid)
                        if len(found) >= MAX_OTHERS:
                            return found
    return found


def _output_texts(raw: dict) -> list[str]:
    texts = []
    outputs = raw.get("outputs") if isinstance(raw, dict) else None
    for out in (outputs if isinstance(outputs, list) else [])[:SCAN_OUTPUTS]:
        if not isinstance(out, dict):
            continue
        text = out.get("text")
        if text is None and isinstance(out.get("data"), dict):
            text = out["data"].get("text/plain")
        if isinstance(text, list):
            text = "".join(t for t in text[:200] if isinstance(t, str))
        if isinstance(text, str):
            texts.append(text[:SCAN_CHARS])
    return texts
