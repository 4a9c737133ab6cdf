"""The one answer format of every multiple-choice item: a string of option letters.

Students answer a multiple-choice item by setting a variable to a string of option letters,
``"b"`` for one answer or ``"ac"`` for "all that apply". Case, spaces and commas are ignored, so
``"A, C"``, ``"ca"`` and ``"a c"`` are the same answer. The visible test cell of every item calls
:func:`choice_letters` to check the *form* of the answer (never whether it is right); the grader
normalises the answer with the same function before comparing it with the key, which it alone
holds.

Examples
--------
>>> choice_letters("B", "abcd")
'b'
>>> choice_letters(" c, A ", "abcd")
'ac'
>>> try:
...     choice_letters("ab", "abcd", single=True)
... except ValueError as exc:
...     print(exc)
choose exactly one option: got 'ab'
"""

from __future__ import annotations

__all__ = ["choice_letters", "ChoiceFormatError"]

_IGNORED = " ,\t\n"


class ChoiceFormatError(ValueError):
    """A multiple-choice answer that is not a string of option letters (or none was given).

    ``unanswered`` is True when no answer was given at all (None, an empty string, only spaces
    and commas), so a grader can tell "skipped" from "answered in the wrong form".
    """

    def __init__(self, message: str, *, unanswered: bool = False):
        super().__init__(message)
        self.unanswered = unanswered


def choice_letters(answer, options: str = "abcd", *, name: str = "the answer",
                   single: bool = False) -> str:
    """Normalise a multiple-choice answer to its sorted, lower-case option letters.

    Parameters
    ----------
    answer : str
        The student's answer: option letters; case, spaces and commas are ignored.
    options : str
        The item's option letters, e.g. ``"abcd"``.
    name : str
        The variable's name, used in the error messages.
    single : bool
        True for an item with exactly one correct option.

    Returns
    -------
    str
        The distinct letters, lower case and sorted (``" c, A "`` gives ``"ac"``).

    Raises
    ------
    ChoiceFormatError
        (a ``ValueError``) when no answer was given (``None``, an empty string), when the answer
        is not a string, holds anything but option letters, spaces and commas, or names more than
        one option where ``single`` is set. The message says how to write the answer.
    """
    letters = "".join(sorted(set(str(options).lower())))
    example = f'a string of option letters such as "{letters[-1]}"'
    if answer is None or answer is Ellipsis:
        raise ChoiceFormatError(f"no answer given: set {name} to {example}", unanswered=True)
    if not isinstance(answer, str):
        raise ChoiceFormatError(f"{name} must be {example}, not {type(answer).__name__}")
    text = answer.lower()
    bad = sorted({ch for ch in text if ch not in _IGNORED and ch not in letters})
    if bad:
        shown = ", ".join(repr(ch) for ch in bad[:5])
        raise ChoiceFormatError(f"{name} may hold only the letters {', '.join(letters)} "
                                f"(spaces and commas are ignored); it holds {shown}")
    chosen = "".join(sorted({ch for ch in text if ch in letters}))
    if not chosen:
        raise ChoiceFormatError(f"no answer given: set {name} to {example}", unanswered=True)
    if single and len(chosen) != 1:
        raise ChoiceFormatError(f"choose exactly one option: got {answer.strip()!r}")
    return chosen
