"""The building blocks of the exercise registry: cases, exercises and comparison rules.

A graded function is described once, by an :class:`Exercise`: its reference implementation in
``course_lib``, a generator of :class:`Case` objects (the visible cases that carry the exam's own
numbers first, then hidden random and edge cases drawn from a seeded generator) and a comparison
rule. Every hidden case that does not raise has an answer that depends on the draw (an edge case
draws its numbers, a True/False case draws which it is, an empty result is drawn among non-empty
ones): the grader shuffles the hidden cases, and a fixed answer could still be given by a function
that recognises its case without the maths (issue 33, finding 1;
``tests/grading/test_draw_dependence.py``). The in-notebook hidden tests (:mod:`autograder.incell`)
and the out-of-kernel grader both read the same objects, so a grading rule lives in one place.

Everything that crosses from student code to the grader is *plain data*: ``None``, ``bool``,
``int``, ``float``, ``str``, numeric NumPy arrays, and tuples/lists of those. :func:`to_plain`
enforces that; anything else is rejected.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np

from course_lib import variants
from course_lib.answers import ChoiceFormatError, choice_letters

from ..model import CellKind


@dataclass(frozen=True)
class Mismatch:
    """Why a received value does not match, as a comparison rule reports it.

    A rule returns ``None`` when the answer matches, otherwise a ``Mismatch`` built with
    :func:`wrong_shape` or :func:`wrong_value`: every rule of the registry speaks this one
    protocol. The grader classifies by ``kind``, never by the text (:func:`as_mismatch` reads a
    bare ``str`` from a rule written elsewhere as a wrong value, without parsing its words).
    """

    #: "wrong-value", "wrong-shape" (wrong shape, type or number of values) or, for a choice
    #: left blank, "unanswered"
    kind: str
    text: str

    def __str__(self) -> str:
        return self.text

    def __contains__(self, words: str) -> bool:
        """``"words" in mismatch`` reads its text."""
        return words in self.text


def wrong_shape(text: str) -> Mismatch:
    """A rule's answer for a value of the wrong shape, type or number of items."""
    return Mismatch("wrong-shape", text)


def wrong_value(text: str) -> Mismatch:
    """A rule's answer for a value of the right form but the wrong numbers."""
    return Mismatch("wrong-value", text)


def as_mismatch(why) -> Mismatch | None:
    """What a rule returned, as the one protocol: ``None`` (a match) or a :class:`Mismatch`;
    anything else is a wrong value described by its text (its words are never parsed)."""
    if why is None or isinstance(why, Mismatch):
        return why
    return wrong_value(str(why))


@dataclass(frozen=True)
class Case:
    """One call of a graded function.

    Parameters
    ----------
    args, kwargs
        Plain-data arguments (arrays, floats, strings, tuples).
    label
        A short description a student understands ("exam Q5(b) numbers", "batch of 7 vectors").
    visible
        True for the cases whose inputs and expected values the student may always see.
    raises
        The exception type the call must raise (``ValueError`` for bad input), or ``None``.
    """

    args: tuple = ()
    kwargs: dict = field(default_factory=dict)
    label: str = ""
    visible: bool = False
    raises: type[BaseException] | None = None


@dataclass(frozen=True)
class Exercise:
    """A graded function (``CellKind.FUNCTION``), a multiple-choice answer (``CellKind.CHOICE``)
    or a number item on the student's own numbers (``CellKind.VALUE``).

    ``name`` is the grade_id of the solution cell and the name the student defines; its test cell
    is ``test_<name>``. For a choice, ``answer`` is the correct option in the *canonical* order
    (a string such as ``"b"``, or a frozenset of options for "select all that apply") and
    ``options`` the allowed ones; each student sees the options in their own order
    (:func:`course_lib.variants.option_order`), so :meth:`key_for` gives their letters. For a
    value, ``solve`` computes the answer from the student's
    :class:`~course_lib.variants.Variant` with the course's references, on the grader's side.
    """

    name: str
    notebook: str
    kind: CellKind = CellKind.FUNCTION
    reference: Callable | None = None
    cases: Callable[[np.random.Generator], Iterable[Case]] | None = None
    compare: Callable[[Any, Any], Mismatch | None] | None = None
    answer: Any = None
    options: tuple = ()
    description: str = ""
    solve: Callable[[Any], Any] | None = None

    def __post_init__(self):
        try:
            kind = CellKind(self.kind)
        except ValueError:
            raise ValueError(f"Exercise.kind of {self.name!r} must be one of "
                             f"{[k.value for k in CellKind]}, got {self.kind!r}") from None
        object.__setattr__(self, "kind", kind)

    def key_for(self, student: str | None) -> str:
        """A choice's key as the letters ``student`` sees (``None``: the canonical letters)."""
        key = choice_key(self.answer)
        if student is None:
            return key
        return variants.displayed_letters(self.name, key, len(self.options), student)

    def value_for(self, student: str):
        """A value item's plain-data answer for ``student``'s numbers."""
        return to_plain(self.solve(variants.variant(self.notebook, student)))

    @property
    def compared_up_to(self) -> str | None:
        """What the comparison rule ignores, completing "compared up to ..." (see
        :func:`up_to`), or ``None`` for a rule that compares in order."""
        return getattr(self.compare, "compared_up_to", None)

    def draw_cases(self, rng: np.random.Generator) -> list[Case]:
        """The exercise's cases drawn from ``rng`` (``cases`` may return any iterable, e.g. be a
        generator function), visible ones first."""
        return list(self.cases(rng))

    def expected(self, case: Case):
        """The reference's plain-data answer for ``case`` (only for ``raises is None``)."""
        return to_plain(self.reference(*case.args, **case.kwargs))


def up_to(wording: str) -> Callable[[Callable], Callable]:
    """Mark a comparison rule that ignores an order: ``wording`` completes "compared up to
    ..." (e.g. "vertex and triangle order"). The feedback page prints it under the visible
    cases, whose passed answers may list the same items in another order than the expected."""
    def mark(rule: Callable) -> Callable:
        rule.compared_up_to = wording
        return rule
    return mark


#: The tolerance of every number item, stated in each notebook: three significant
#: figures are enough.
NUMBER_RTOL, NUMBER_ATOL = 5e-3, 1e-3


def number_item(name: str, notebook: str, solve: Callable[[Any], Any],
                description: str, compare: Callable | None = None) -> Exercise:
    """A number item worked on the student's own numbers: ``solve(variant)`` gives the answer
    with the course's references; by default (:func:`numbers_close`) answers within 0.5 % (or
    0.001) of it pass."""
    return Exercise(name=name, notebook=notebook, kind=CellKind.VALUE, solve=solve,
                    compare=compare or numbers_close, description=description)


def same_integer(expected, received) -> Mismatch | None:
    """A whole number, exactly (a case number 200 is not 201, however close): ``int``, a NumPy
    integer or a float/0-d array holding a whole number."""
    if isinstance(received, np.ndarray) and received.shape == ():
        received = received.item()
    if isinstance(received, bool) or not isinstance(received, (int, float)):
        return wrong_shape(f"wrong type (expected one whole number, got {describe(received)})")
    if isinstance(received, float) and not (math.isfinite(received) and received.is_integer()):
        return wrong_value("wrong value: not a whole number")
    return None if int(received) == int(expected) else wrong_value("wrong value")


def numbers_close(expected, received) -> Mismatch | None:
    """:func:`close` at the number items' tolerance; a list or tuple of numbers stands for an
    array (students type ``[1.5, 2.0]``), and ``True``/``False`` for 1 and 0. A wrong value is
    reported without its error, which would give a one-number answer away."""
    if isinstance(expected, np.ndarray) and isinstance(received, tuple):
        try:
            received = np.array(received, dtype=float)
        except (TypeError, ValueError):
            return wrong_shape(f"wrong type (expected numbers of shape {expected.shape}, got "
                               f"{describe(received)})")
    if isinstance(received, np.ndarray) and received.dtype == bool:
        received = received.astype(float)
    if isinstance(expected, np.ndarray) and expected.dtype == bool:
        expected = expected.astype(float)
    why = _close(expected, received, NUMBER_RTOL, NUMBER_ATOL)
    if why is not None and why.kind == "wrong-value":
        # never how far off: the size of the error would give a scalar answer away
        return wrong_value("wrong value: not within 0.5 % (or 0.001) of the answer for your "
                           "numbers")
    return why


# --------------------------------------------------------------------------------------------
# plain data


class NotPlainData(TypeError):
    """Raised by :func:`to_plain` for an object that is not plain data."""


def to_plain(value, _depth: int = 0):
    """Convert ``value`` to plain data or raise :class:`NotPlainData`.

    NumPy scalars become Python numbers; numeric arrays are copied as ``np.ndarray`` (never a
    subclass); lists and tuples become tuples. Object arrays, custom classes (including ones that
    subclass ``float`` or ``ndarray``) and dicts are rejected: a student's object could otherwise
    decide its own comparison.
    """
    if _depth > 4:
        raise NotPlainData("nested too deeply")
    if value is None or type(value) in (bool, int, float, str):
        return value
    if type(value) in (np.bool_,):
        return bool(value)
    if type(value) in (np.float16, np.float32, np.float64, np.longdouble):
        return float(value)
    if isinstance(value, np.integer) and type(value).__module__ == "numpy":
        return int(value)
    if type(value) is np.ndarray:
        if value.dtype.kind not in "biuf":
            raise NotPlainData(f"an array of dtype {value.dtype} (expected numbers)")
        return np.array(value, copy=True)
    if type(value) in (tuple, list):
        return tuple(to_plain(v, _depth + 1) for v in value)
    raise NotPlainData(f"an object of type {type(value).__name__}")


def describe(value) -> str:
    """A short human description of a plain value: its type and shape."""
    if isinstance(value, np.ndarray):
        return f"array of shape {value.shape}"
    if isinstance(value, tuple):
        return f"tuple of {len(value)}"
    return type(value).__name__


# --------------------------------------------------------------------------------------------
# comparison rules: each returns None when `received` matches `expected`, else a reason


def close(rtol: float = 1e-6, atol: float = 1e-9) -> Callable[[Any, Any], Mismatch | None]:
    """Element-wise ``np.allclose`` on arrays/floats, recursively through tuples.

    Shapes must match exactly (a ``(1, 3)`` answer for a ``(3,)`` question is a wrong shape), a
    Python float and a 0-d array are interchangeable, and bools must match exactly.
    """

    def rule(expected, received):
        return _close(expected, received, rtol, atol)

    rule.__doc__ = f"all values within rtol={rtol}, atol={atol}"
    return rule


def _close(expected, received, rtol, atol) -> Mismatch | None:
    if expected is None or isinstance(expected, (bool, str)):
        if type(received) is not type(expected):
            return wrong_shape(f"wrong type (expected {expected!r}, got {_short(received)})")
        if received != expected:
            return wrong_value(f"wrong value (expected {expected!r}, got {_short(received)})")
        return None
    if isinstance(expected, tuple):
        if not isinstance(received, tuple) or len(received) != len(expected):
            return wrong_shape(f"wrong type (expected a tuple of {len(expected)}, got "
                               f"{describe(received)})")
        for i, (e, r) in enumerate(zip(expected, received, strict=True)):
            why = _close(e, r, rtol, atol)
            if why is not None:
                return Mismatch(why.kind, f"item {i}: {why.text}")
        return None
    if isinstance(received, (bool, str, tuple)) or received is None:
        return wrong_shape(f"wrong type (expected numbers, got {describe(received)})")
    e = np.asarray(expected, dtype=float)
    r = np.asarray(received, dtype=float)
    if e.shape != r.shape:
        return wrong_shape(f"wrong shape (expected {e.shape}, got {r.shape})")
    if not np.all(np.isfinite(r) | ~np.isfinite(e)):
        return wrong_value("wrong value (NaN or inf in the answer)")
    if not np.allclose(r, e, rtol=rtol, atol=atol, equal_nan=True):
        err = np.max(np.abs(r - e)) if e.size else 0.0
        return wrong_value(f"wrong value (largest error {err:.3g})")
    return None


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else describe(value)


def choice_key(answer) -> str:
    """A choice exercise's key as option letters (``"b"``, or ``"ac"`` for all that apply)."""
    return answer if isinstance(answer, str) else "".join(sorted(answer))


def same_choice(expected, received, options="abcd", name: str = "the answer",
                single: bool | None = None) -> Mismatch | None:
    """Multiple choice: ``received`` normalised by :func:`course_lib.answers.choice_letters`
    (case, spaces and commas ignored) against the key. No answer at all is an ``unanswered``
    mismatch, an answer of the wrong form a wrong shape, other letters a wrong value.
    ``single`` (default: a one-letter ``str`` key) says the item wants exactly one letter."""
    key = choice_key(expected)
    if single is None:
        single = isinstance(expected, str) and len(key) == 1
    try:
        got = choice_letters(received, "".join(options) or "abcd", name=name, single=single)
    except ChoiceFormatError as exc:
        return Mismatch("unanswered" if exc.unanswered else "wrong-shape", str(exc))
    return None if got == key else wrong_value("wrong answer")


def isclose_scalar(a: float, b: float, rtol=1e-6, atol=1e-9) -> bool:
    """Scalar tolerance test used by custom rules."""
    return math.isclose(a, b, rel_tol=rtol, abs_tol=atol)
