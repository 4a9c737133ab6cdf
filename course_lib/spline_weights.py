"""The weights of ``a, b, c, d`` in ``p, p', p''`` at a spline's end, as the page shows them.

Q4(b) asks for the rows ``[1 1 1 1] M``, ``[3 2 1 0] M`` and ``[6 2 0 0] M`` of the two
splines, and Q4(c)(i) for the same rows once the phantom point ``d`` follows an end rule. The
end-condition explorer's formulas panel and the notebook's tables show them for both splines
and every rule. The students' copy of the library holds these eight small tables, computed by
the references when it was built (:mod:`course_lib._spline_weights_data`), and not the
functions that compute them (writing those is the question). Weights are exact fractions,
given as text (``"1/6"``, ``"-1/2"``); none of these functions takes a basis matrix or a point.
"""

from __future__ import annotations

from fractions import Fraction

__all__ = ["KINDS", "ROWS", "RULES", "end_weights_text", "row_sums"]

#: the splines, and the end rules with "free" for the general rows (``d`` placed freely)
KINDS = ("catmull-rom", "b-spline")
RULES = ("free", "d=b", "d=2c-b", "d=c")
#: what each row of a table weighs
ROWS = ("p", "p'", "p''")


def end_weights_text(kind: str, rule: str) -> tuple[tuple[str, ...], ...]:
    """The weights of ``a, b, c, d`` (columns) in ``p(1), p'(1), p''(1)`` (rows) for the
    spline ``kind`` terminated by ``rule``, each an exact fraction as text.

    With ``rule="free"`` the rows are the general ones of Q4(b) (e.g. Catmull-Rom
    ``p'' = -a + 4b - 5c + 2d``); with a rule of Q4(c)(i) the phantom point is substituted and
    the ``d`` column is ``"0"`` (Catmull-Rom with ``d = b``: ``p'' = -a + 6b - 5c``).

    Raises
    ------
    ValueError
        For an unknown ``kind`` or ``rule``.

    Examples
    --------
    >>> end_weights_text("b-spline", "d=2c-b")[0]
    ('0', '0', '1', '0')
    """
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    if rule not in RULES:
        raise ValueError(f"rule must be one of {RULES}, got {rule!r}")
    from ._spline_weights_data import load

    return load()[(kind, rule)]


def row_sums(kind: str, rule: str) -> tuple[str, str, str]:
    """The sum of each row's weights, as text: ``"1"`` for ``p`` (the weights of a point form
    an affine combination), ``"0"`` for ``p'`` and ``p''`` (a derivative does not move when
    every point moves by the same vector)."""
    return tuple(str(sum(Fraction(w) for w in row)) for row in end_weights_text(kind, rule))
