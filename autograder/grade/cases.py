"""The cases each student's graded names are run on, and what the sandbox may send back.

Hidden cases come from a generator seeded with HMAC-SHA256 of the course secret over the
assignment, the student, the graded name and a digest of ALL the student's solution code that
runs for that notebook (:func:`job_digest`: every planned cell's label and exact text, comments
and spacing included, since student code can read its own cells' text in the sandbox and a comment
could carry a table). Re-grading the same submission draws the same cases (same CSV,
feedback, report); a change to ANY solution cell of the notebook (the graded function's, a
helper's, a choice's) draws new hidden cases for every name, so a table of hidden inputs
printed on one run, wherever it lives, gains nothing on the next (red-team finding 1).

Every case of a name has the same result cap (:func:`name_cap`), so the cap says nothing about
any one case's answer (finding 3).
"""

from __future__ import annotations

import hashlib
import hmac
import sys
from dataclasses import dataclass

import numpy as np

from ..exercises.base import Case, Exercise
from ..course import ASSIGNMENT

#: Bytes every case may return beyond four times its expected answer's size.
RESULT_SLACK = 16 * 2**10
#: The smallest result cap of a graded name (a power of two).
CAP_FLOOR = 64 * 2**10


def solution_digest(code: str) -> str:
    """SHA-256 of a solution cell's exact text.

    Not of its syntax tree: the sandbox's code can read every cell's text, so a table hidden in
    a comment, in spacing, or behind an expression too deep to parse must change the seed too
    (red-team findings 1 and N1).
    """
    return hashlib.sha256(code.encode("utf-8", "surrogatepass")).hexdigest()


def notebook_digest(sources) -> str:
    """SHA-256 over :func:`solution_digest` of every solution cell that runs, in order."""
    joined = "\n".join(solution_digest(code) for code in sources)
    return hashlib.sha256(joined.encode("ascii")).hexdigest()


def job_digest(cells) -> str:
    """:func:`notebook_digest` over everything of the student's that the sandbox receives:
    each planned cell's label (its graded name and its place in the notebook) and its code.

    A label reaches the student's code (in the job and as the code's file name), so a label
    left out of the seed would let a resubmission with the same code but cells moved about
    (empty cells in between) carry answers to hidden cases drawn the same as before.
    """
    return notebook_digest(part for label, code in cells for part in (label, code))


def case_seed(secret: bytes, student: str, name: str, digest: str = "") -> int:
    """The seed of a student's hidden cases for ``name`` (see the module docstring)."""
    message = f"{ASSIGNMENT}\0{student}\0{name}\0{digest}".encode()
    return int.from_bytes(hmac.new(secret, message, hashlib.sha256).digest()[:16], "big")


@dataclass
class DrawnCase:
    """One case with the reference's answer (None where the case must raise) and its name's
    result cap (the same for every case of the name)."""

    case: Case
    expected: object
    result_cap: int


def draw(ex: Exercise, seed: int) -> list[DrawnCase]:
    """The exercise's cases from ``seed`` with their expected answers, in the order the sandbox
    runs them (:func:`running_order`); a case whose reference fails (a registry problem) is
    skipped with a warning."""
    drawn = []
    rng = np.random.default_rng(seed)
    for case in running_order(ex.draw_cases(rng), rng):
        expected = None
        if case.raises is None:
            try:
                expected = ex.expected(case)
            except Exception as exc:  # noqa: BLE001 - a registry problem: skip the case
                print(f"warning: reference of {ex.name} failed on case {case.label!r}: {exc}; "
                      "case skipped", file=sys.stderr)
                continue
        drawn.append(DrawnCase(case, expected, result_cap(expected)))
    cap = name_cap(d.result_cap for d in drawn)
    for d in drawn:
        d.result_cap = cap
    return drawn


def running_order(cases, rng: np.random.Generator) -> list[Case]:
    """The visible cases in the generator's order, then the hidden ones (bad-input cases among
    them) shuffled by ``rng``.

    Visible first, so a function has seen no hidden input while its returned values are still
    shown. Hidden shuffled per draw, so the k-th call is no particular kind of case: a function
    that counts its calls and answers by position (the visible answers, ``ValueError`` where the
    generator puts its bad inputs, the constants of fixed cases) earns nothing by it
    (issue 33, finding 1).
    """
    cases = list(cases)
    visible = [c for c in cases if c.visible]
    hidden = [c for c in cases if not c.visible]
    return visible + [hidden[i] for i in rng.permutation(len(hidden))]


def name_cap(caps) -> int:
    """ONE result cap for all of a name's cases: the largest case's, rounded up to a power of
    two, never below :data:`CAP_FLOOR` (so it reveals no single case's answer)."""
    largest = max(caps, default=0)
    return max(CAP_FLOOR, 1 << max(0, int(largest) - 1).bit_length())


def result_cap(expected) -> int:
    """Bytes the encoded result of a case may take: 4 × the expected answer's size + 16 KiB."""
    return 4 * encoded_size(expected) + RESULT_SLACK


def encoded_size(value) -> int:
    """An estimate of the bytes ``value`` takes once encoded (arrays by their data)."""
    if isinstance(value, np.ndarray):
        return int(value.nbytes) + 128
    if isinstance(value, (tuple, list)):
        return 16 + sum(encoded_size(v) for v in value)
    if isinstance(value, str):
        return len(value.encode("utf-8", "surrogatepass")) + 8
    return 32
