"""Whose numbers a submitted notebook worked (issue 11).

The grader always judges number items and option letters for the student of the submission's
folder. When the notebook shows it worked another id's numbers (its first cell typed another
``STUDENT_ID``, or its saved output of the setup cell says "Your numbers (student X)"), the
feedback says so, and says which of the wrong answers fit that other student's numbers.
"""

from __future__ import annotations

import re

from ..model import Submission

_PRINTED = re.compile(r"Your numbers \(student ([A-Za-z0-9._@+-]{1,100})\)")
_TYPED = re.compile(r"""^\s*STUDENT_ID\s*=\s*["']([A-Za-z0-9._@+-]{1,100})["']""", re.MULTILINE)
#: Characters of one saved output the search reads (a header is near the start).
SCAN_CHARS = 4000


def declared_students(sub: Submission) -> list[str]:
    """The ids a submitted notebook says it worked for, in notebook order, without repeats."""
    found: list[str] = []
    for cell in sub.cells:
        if cell.get("cell_type") != "code":
            continue
        texts = [cell.get("source", "")] + _output_texts(cell.get("raw") or {})
        for text in texts:
            for rx in (_TYPED, _PRINTED):
                for match in rx.finditer(text[:SCAN_CHARS]):
                    if match.group(1) not in found:
                        found.append(match.group(1))
    return found


def other_students(sub: Submission) -> list[str]:
    """The ids other than the submission's own that its notebook says it worked for."""
    return [s for s in declared_students(sub) if s != sub.student][:3]


def _output_texts(raw: dict) -> list[str]:
    texts = []
    outputs = raw.get("outputs") if isinstance(raw, dict) else None
    for out in outputs if isinstance(outputs, list) else []:
        if not isinstance(out, dict):
            continue
        text = out.get("text")
        if text is None and isinstance(out.get("data"), dict):
            text = out["data"].get("text/plain")
        if isinstance(text, list):
            text = "".join(t for t in text if isinstance(t, str))
        if isinstance(text, str):
            texts.append(text)
    return texts
