"""The hand-back page says one thing about each written answer (issue: the table showed
``q1a_answer 4.5 / 6`` with the marker's comment while the section below still said
``manual – / 6 marked by hand in formgrader``).

The page is read as a student reads it: its text, by Python's HTML parser. Oracle: the mark the
test gave (4.5 of 6), and the words a page must not use about a marked answer.
"""

from __future__ import annotations

import base64
import re
from html.parser import HTMLParser

from autograder.model import CellKind, CellResult, Status
from autograder.outputs import feedback, handback


class _Text(HTMLParser):
    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.parts: list[str] = []

    def handle_data(self, data):
        self.parts.append(data)


def text_of(page: str) -> str:
    parser = _Text()
    parser.feed(page)
    return re.sub(r"\s+", " ", " ".join(parser.parts))


def rows(written_status: Status = Status.MANUAL) -> list[CellResult]:
    return [
        CellResult("ann", "q1_imaging", "q1a_answer", "q1a_answer",
                   None if written_status is Status.MANUAL else 0.0, 6.0, written_status,
                   "marked by hand in formgrader" if written_status is Status.MANUAL
                   else "left blank: 0", kind=CellKind.MANUAL, code="Ann's answer."),
        CellResult("ann", "q1_imaging", "q1b_test", "axial_resolution", 2.0, 2.0, Status.OK,
                   "all cases passed"),
    ]


def marks(score: float, marked: bool, comment: str = "") -> handback.NotebookMarks:
    return handback.NotebookMarks("ann", "q1_imaging", [
        handback.Mark("q1a_answer", score, 6.0, True, marked, comment),
        handback.Mark("q1b_test", 2.0, 2.0, False, True, ""),
    ])


def test_a_marked_answer_shows_its_mark_everywhere():
    grader = feedback.render("ann", "q1_imaging", rows(), reveal_hidden=False)
    page = text_of(handback.render(marks(4.5, True, "Good on attenuation."), grader))
    assert page.count("4.5 / 6") == 2, page         # the table, and the answer's own heading
    assert "Good on attenuation." in page and "Ann's answer." in page
    for never in ("– / 6", "not marked", "marked by hand in formgrader", "A marker gives"):
        assert never not in page, (never, page)
    assert "Total 6.5 / 8" in page


def test_an_unmarked_answer_is_unmarked_everywhere():
    grader = feedback.render("ann", "q1_imaging", rows(), reveal_hidden=False)
    page = text_of(handback.render(marks(0.0, False), grader))
    assert "not marked yet" in page and "/ 6" not in page.replace("out of 6", ""), page
    assert "some written answers are not marked yet" in page


def test_the_graders_own_page_names_no_mark_for_a_written_answer():
    """Before marking (the page ``grade`` writes) a written answer shows who marks it."""
    page = text_of(feedback.render("ann", "q1_imaging", rows(), reveal_hidden=False))
    assert "q1a_answer (written answer) marked by hand out of 6" in page, page
    assert "– / 6" not in page


def test_a_blank_written_answer_keeps_its_zero_and_reason():
    grader = feedback.render("ann", "q1_imaging", rows(Status.UNANSWERED), reveal_hidden=False)
    page = text_of(handback.render(marks(0.0, True), grader))
    assert "left blank: 0" in page and page.count("0 / 6") == 2, page


def test_a_comment_is_prose_at_the_pages_size():
    """Not a <pre> in the table's smaller font; its line breaks kept; escaped."""
    grader = feedback.render("ann", "q1_imaging", rows(), reveal_hidden=False)
    page = handback.render(marks(4.5, True, "Line one <blink>\nline two."), grader)
    assert "<td class='comment'><p>Line one &lt;blink&gt;\nline two.</p></td>" in page
    assert re.search(r"td\.comment\{white-space:pre-wrap;[^}]*font-size:1\.1em", page)


class _Tags(HTMLParser):
    """Every start tag with its attributes, as a browser would build them."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.tags: list[tuple[str, dict]] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))


def _comment_cell(page: str) -> str:
    return re.search(r"<td class='comment'>(.*?)</td>", page, re.DOTALL).group(1)


def test_a_comment_is_rendered_as_markdown_with_its_maths_typeset():
    """The Formgrader tells markers comments support Markdown and MathJax: the page shows
    them so (bold as bold, ``$\\mu$`` as a typeset picture whose alt text is the TeX)."""
    grader = feedback.render("ann", "q1_imaging", rows(), reveal_hidden=False)
    page = handback.render(marks(4.5, True, "**Good**: use $\\mu$ in\n\n$$I = I_0 e^{-\\mu x}$$"),
                           grader)
    cell = _comment_cell(page)
    assert "<strong>Good</strong>" in cell and "**" not in cell
    parser = _Tags()
    parser.feed(cell)
    pictures = [a for t, a in parser.tags if t == "img"]
    assert [p["alt"] for p in pictures] == ["$\\mu$", "$$I = I_0 e^{-\\mu x}$$"]
    for p in pictures:
        assert p["src"].startswith("data:image/png;base64,")
        png = base64.b64decode(p["src"].split(",", 1)[1])
        assert png[:8] == b"\x89PNG\r\n\x1a\n"         # a real picture, not text
    assert "use" in text_of(cell) and "$" not in text_of(cell)


def test_a_script_in_a_comment_stays_inert():
    payload = ('<script>alert(1)</script><img src=x onerror="alert(2)">'
               '[x](javascript:alert(3)) $\\" onerror="alert(4)$ <style>body{display:none}</style>')
    grader = feedback.render("ann", "q1_imaging", rows(), reveal_hidden=False)
    cell = _comment_cell(handback.render(marks(4.5, True, payload), grader))
    parser = _Tags()
    parser.feed(cell)
    for tag, attrs in parser.tags:
        assert tag not in ("script", "style"), cell
        assert not any(k.startswith("on") for k in attrs), (tag, attrs)
        assert not any("javascript:" in (v or "") for v in attrs.values()), (tag, attrs)
        if tag == "img":
            assert attrs.get("src", "").startswith("data:image/png;base64,") or "src" not in attrs
    assert "<script>alert(1)" in text_of(cell)                   # shown as text, not run


def test_the_check_your_id_note_comes_before_the_marks():
    """The first thing a student reads on a notebook that names another id is that note."""
    grader = feedback.render("ann", "q1_imaging", rows(), reveal_hidden=False,
                             whose={"named": ["xy987"], "graded_as": ""})
    page = handback.render(marks(4.5, True, "Good."), grader)
    note = page.index("Check your student id: this notebook names xy987")
    assert note < page.index("<table") and note < page.index("class='total'")
    assert page.count("Check your student id") == 1
    assert page.index("<h1>") < note


class _Grade:
    def __init__(self, name, cell_type):
        self.name, self.score, self.max_score = name, 1.0, 2.0
        self.auto_score = None if cell_type == "markdown" else 1.0
        self.needs_manual_grade = False
        self.cell = type("Cell", (), {"cell_type": cell_type})()


def test_marks_are_listed_in_the_notebooks_order(sources, monkeypatch):
    """The gradebook keeps no order (it was listed alphabetically): the oracle is the order of
    the graded cells in the source notebook's file, read here with nbformat."""
    import nbformat
    import nbgrader.api

    src = next(s for s in sources if s.manual and s.graded)
    nb = nbformat.read(src.path, as_version=4)
    graded = [(c.metadata["nbgrader"]["grade_id"], c.cell_type) for c in nb.cells
              if c.metadata.get("nbgrader", {}).get("grade")]
    assert [g for g, _ in graded] != sorted(g for g, _ in graded)   # the test can fail
    notebook = type("Nb", (), {"name": src.name, "comments": [], "late_submission_penalty": 0,
                               "grades": [_Grade(g, t) for g, t in sorted(graded)]})()
    submission = type("Sub", (), {"student_id": "ann", "notebooks": [notebook]})()

    class FakeGradebook:
        def __init__(self, *a, **k):
            pass

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def assignment_submissions(self, assignment):
            return [submission]

    monkeypatch.setattr(nbgrader.api, "Gradebook", FakeGradebook)
    got = handback.read_marks("sqlite:///unused.db", handback.cell_order(sources))
    assert [m.grade_id for m in got[0].marks] == [g for g, _ in graded]
    assert [m.written for m in got[0].marks] == [t == "markdown" for _, t in graded]


def test_missing_secrets_names_the_students_whose_folder_lacks_nbgraders_files(tmp_path):
    """A notebook placed in ``submitted/`` by hand has no ``timestamp.txt``: its student is named
    (so ``feedback`` releases the others and says who was left out), not the folder above."""
    from autograder.course import ASSIGNMENT

    for student, carried in (("ab123", True), ("ef789", False)):
        folder = tmp_path / "feedback" / student / ASSIGNMENT
        folder.mkdir(parents=True)
        for name in handback.CARRIED_FILES if carried else ():
            (folder / name).write_text("x")
    assert handback.missing_secrets(tmp_path) == ["ef789"]


def test_a_practice_item_is_not_shown_as_zero_of_zero():
    """A practice item (0 marks) reads "practice" in the hand-back table, not "0 / 0", which a
    student reads as a fail (a careful student's playtest)."""
    nb = handback.NotebookMarks("ann", "q3_marching_cubes", [
        handback.Mark("q3_item6", 0.0, 0.0, False, True, ""),
        handback.Mark("q3b_test", 1.5, 1.5, False, True, ""),
    ])
    page = text_of(handback.render(nb, None))
    assert "q3_item6 practice, no marks" in page, page
    assert "0 / 0" not in page and "1.5 / 1.5" in page
