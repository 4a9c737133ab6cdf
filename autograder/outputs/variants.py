"""The report's "Own numbers" section: answers that do not look like the student's own,
and the ``--graded-as`` decisions taken on that evidence.

Two signs, for the instructor only (the student's feedback never names other ids before the
deadline):

- a wrong choice or number item that fits the numbers or option letters of another student the
  notebook names (:attr:`CellResult.fits_other <autograder.model.CellResult.fits_other>`);
- a multiple-choice answer that is *computed* instead of typed: a student reads their options
  and types letters, so a cell that calls ``course_lib.variants`` (``mine.letters``,
  ``displayed_letters``, ``option_order``) to map canonical letters to their own is most likely
  a key sheet passed round the class (red-team finding F4). It still scores what it scores; the
  instructor decides.
"""

from __future__ import annotations

import re

from ..model import CellKind, CellResult
from .html import e, e_clipped

#: What a typed choice answer looks like: ``name = "b"`` (letters, spaces, commas), a comment.
_TYPED = re.compile(r"""^\s*(?:#[^\n]*\n\s*)*[A-Za-z_]\w*\s*=\s*(["'])[A-Za-z ,]*\1\s*(?:#[^\n]*)?\s*$""")
_VARIANT_CALLS = re.compile(r"\b(letters|displayed_letters|canonical_letters|option_order|"
                            r"options_text|variant|my_variant)\s*\(")
#: Rows listed in full per table.
LIMIT = 200


def computed_choices(results: list[CellResult]) -> list[CellResult]:
    """Choice cells whose answer is computed with ``course_lib.variants`` instead of typed."""
    return [r for r in results if r.kind is CellKind.CHOICE and r.code.strip()
            and not _TYPED.match(r.code) and _VARIANT_CALLS.search(r.code)]


def section_html(results: list[CellResult]) -> str:
    """``<section>`` with both tables (a short note when there is nothing to show)."""
    fits = [r for r in results if r.fits_other]
    computed = computed_choices(results)
    out = ["<section class='own-numbers'>",
           f"<h2>Own numbers ({len(fits)} answers fit another student's, {len(computed)} "
           "choices computed)</h2>",
           "<p class='note'>Every student answers the number items on their own numbers and sees "
           "the options of every multiple-choice item in their own order "
           "(<code>course_lib/variants.py</code>). Listed here: wrong answers that are right for "
           "another id the notebook names (typed <code>STUDENT_ID</code> or saved output), and "
           "choice answers computed from the canonical key with <code>course_lib.variants</code> "
           "rather than typed (a shared key sheet). Scores are not changed.</p>"]
    if fits:
        out.append("<table><tr><th>student</th><th>notebook</th><th>item</th>"
                   "<th>fits the answer of</th></tr>")
        out += [f"<tr><td>{e(r.student)}</td><td>{e(r.notebook)}</td><td>{e(r.name)}</td>"
                f"<td>{e(r.fits_other)}</td></tr>" for r in fits[:LIMIT]]
        out.append("</table>")
    if computed:
        out.append("<table><tr><th>student</th><th>notebook</th><th>item</th><th>cell</th></tr>")
        out += [f"<tr><td>{e(r.student)}</td><td>{e(r.notebook)}</td><td>{e(r.name)}</td>"
                f"<td><pre>{e_clipped(r.code, 400)}</pre></td></tr>" for r in computed[:LIMIT]]
        out.append("</table>")
    return "\n".join(out + ["</section>"])


def graded_as_html(decisions: list[dict]) -> str:
    """``<section>`` of the ``--graded-as`` decisions in ``OUT/graded-as.log``
    (:func:`autograder.grade.remedy.decisions`): who was graded on which id, why, by whom,
    when, on what evidence, and whether this run applied it. Empty when there are none."""
    if not decisions:
        return ""
    dropped = [d for d in decisions if not d["applied"]]
    out = ["<section class='graded-as'>",
           f"<h2>Graded on another id ({len(decisions) - len(dropped)} in this run, from "
           "<code>graded-as.log</code>)</h2>",
           "<p class='note'>The instructor's decisions to judge a student's items on the numbers "
           "and option letters of the id the notebook was worked for (<code>grade --graded-as "
           "STUDENT=ID --reason ...</code>), latest per student. A decision this run did not "
           "apply is marked: grading again into the same folder applies it only when "
           "<code>--graded-as</code> is given again.</p>",
           "<table><tr><th>student</th><th>graded on</th><th>reason</th><th>by</th>"
           "<th>when (UTC)</th><th>evidence</th><th>this run</th></tr>"]
    out += [f"<tr><td>{e(d['student'])}</td><td>{e(d['graded_as'])}</td><td>{e(d['reason'])}"
            f"</td><td>{e(d['by'])}</td><td>{e(d['when'])}</td><td>{e_clipped(d['evidence'], 400)}"
            f"</td><td>{'applied' if d['applied'] else 'NOT applied'}</td></tr>"
            for d in decisions[:LIMIT]]
    return "\n".join(out + ["</table>", "</section>"])
