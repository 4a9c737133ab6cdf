"""The shared multiple-choice answer format (course_lib.answers)."""

import doctest

import pytest

from course_lib import answers
from course_lib.answers import ChoiceFormatError, choice_letters


@pytest.mark.parametrize("given, want", [
    ("b", "b"), ("B", "b"), (" c, A ", "ac"), ("a c", "ac"), ("ca", "ac"), ("aa", "a"),
])
def test_case_spaces_commas_and_order_are_ignored(given, want):
    assert choice_letters(given, "abcd") == want


@pytest.mark.parametrize("given", [None, "", "  ", " , "])
def test_no_answer_says_so(given):
    with pytest.raises(ChoiceFormatError, match="no answer given") as info:
        choice_letters(given, "abcd", name="q5_x")
    assert info.value.unanswered


@pytest.mark.parametrize("given", [3, ["a"], 1.5, ("a",)])
def test_non_strings_are_refused_with_their_type(given):
    with pytest.raises(ValueError, match=type(given).__name__):
        choice_letters(given, "abcd")


def test_letters_outside_the_options_are_named():
    with pytest.raises(ChoiceFormatError, match="'e'") as info:
        choice_letters("ae", "abcd")
    assert not info.value.unanswered
    with pytest.raises(ValueError, match=r"'\('"):
        choice_letters("(a)", "abcd")


def test_single_answer_items_refuse_two_letters():
    assert choice_letters("c", "abcd", single=True) == "c"
    with pytest.raises(ValueError, match="exactly one"):
        choice_letters("a, b", "abcd", single=True)


def test_docstring_examples_hold():
    assert doctest.testmod(answers).failed == 0
