"""A multiple-choice answer as the marker reads it: the student's letters mapped to the
instructors' order.

Each student sees a choice item's options in an order of their own
(:func:`course_lib.variants.option_order`), while the autograded notebook the Formgrader shows
lists them in the canonical order of the source notebook. The verdict under a choice cell
therefore says which canonical option each of the student's letters stood for, and what the
student's answer was in canonical letters (Q1–Q6 multiple-choice items).
"""

from __future__ import annotations

from course_lib import variants
from course_lib.answers import choice_letters

from ..exercises import REGISTRY
from ..model import CellKind


def choice_legend(name: str, student: str, answer=None) -> str:
    """``ab123 saw the options in an order of their own: their (a) is (c) here, ...; their
    answer 'b' is (a) here``; ``""``
    for a name that is not a choice item (or an id the variants refuse)."""
    ex = REGISTRY.get(name)
    if ex is None or ex.kind is not CellKind.CHOICE or not ex.options:
        return ""
    n = len(ex.options)
    try:
        order = variants.option_order(name, n, student)
    except ValueError:
        return ""
    pairs = ", ".join(f"their ({variants.LETTERS[k]}) is ({variants.LETTERS[i]}) here"
                      for k, i in enumerate(order))
    text = f"{student} saw the options in an order of their own: {pairs}"
    if isinstance(answer, str):
        try:
            shown = choice_letters(answer, variants.LETTERS[:n])
        except ValueError:
            return text
        canonical = variants.canonical_letters(name, shown, n, student)
        text += (f"; their answer {answer.strip()!r} is "
                 f"{', '.join(f'({c})' for c in canonical) or 'nothing'} here")
    return text
