"""A written answer is shown to the marker as text, never run (red team 7, §1).

Before: ``<script>``, ``<img onerror>``, ``<style>`` or a raw cell in a submission ran in the
marker's Formgrader with the marker's session (the red team gave itself full marks on unread
answers and zeroed classmates' grades). Now :mod:`autograder.outputs.safe_markdown` sanitises
the Formgrader's ``markdown2html`` and the grader quotes raw cells.

Oracle: Python's own HTML parser reads the page as a browser would. A payload carries the
marker ``PWN7``; it must appear on the page (the marker sees the attempt as text) and in no
place where a browser would run or apply it: a script element, an ``on*`` attribute, a style
element or attribute, a ``javascript:`` or ``data:`` URL other than a raster picture.
The end-to-end test asks the real Formgrader (``python -m autograder lab --role instructor``,
the course's own ``nbgrader_config.py``) for the submission's page over HTTP.
"""

from __future__ import annotations

import base64
import copy
import json
import re
import subprocess
import sys
import urllib.request
from html.parser import HTMLParser

import pytest
from jinja2 import Environment

from autograder.outputs.safe_markdown import (_PICTURE_STYLE, clean_html, markdown2html,
                                             quoted_cell)

MARK = "PWN7"
PNG = base64.b64encode(b"\x89PNG\r\n\x1a\n" + b"\0" * 16).decode()
SVG = base64.b64encode(f"<svg xmlns='http://www.w3.org/2000/svg' onload='{MARK}()'/>".encode()).decode()

#: written answers an attacker might hand in; each carries MARK where it would run
PAYLOADS = [
    f"<script>window.{MARK} = 1</script>",
    f"<img src=x onerror=\"{MARK}()\">",
    f"<svg><animate onbegin=\"{MARK}()\" attributeName=x /></svg>",
    f"<style>.output_area pre {{ display: none }} /* {MARK} */</style>",
    f"<p style=\"position: fixed; top: 0\">{MARK} over the form</p>",
    f"[read me](javascript:{MARK}())",
    f"<a href=\"javascript:{MARK}()\">read me</a>",
    f"<a href=\"data:text/html,<script>{MARK}()</script>\">read me</a>",
    f"<iframe src=\"/api/contents?{MARK}\"></iframe>",
    f"<object data=\"/api/terminals?{MARK}\"></object>",
    f"<form action=\"/formgrader/api/grade/1?{MARK}\"><button>go</button></form>",
    f"<meta http-equiv=\"refresh\" content=\"0; url=/logout?{MARK}\">",
    f"<div class=\"navbar-fixed-top\" title=\"{MARK}\">over the form</div>",
    f"<!-- {MARK} --><scr<script>ipt>{MARK}()</script>",
    f"![pic](attachment:v.svg) {MARK}",
    f"<img src=\"/logout?{MARK}\"> and ![x](https://example.org/{MARK}.png)",
    # the filter styles every "<img" after cleaning: one inside an attribute must stay text
    f"<a title=\"<img x onmouseover={MARK}() y\">t</a> ![x](y \"<img onload={MARK}()\")",
]

#: payloads whose first tag is not allowed at all: the marker reads them whole, as text
SHOWN_AS_TEXT = ("<script", "<svg", "<style", "<iframe", "<object", "<form", "<meta")


class _Live(HTMLParser):
    """Where, in parsed HTML, a browser would run or apply something: the texts of those places."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.live: list[str] = []
        self.text: list[str] = []
        self._inside: str | None = None

    def handle_starttag(self, tag, attrs):
        if tag in ("script", "style"):
            self._inside = tag
        if tag in ("iframe", "object", "embed", "form", "meta", "link", "base", "svg"):
            self.live.append(f"<{tag} {attrs}>")
        for name, value in attrs:
            value = value or ""
            url = value.strip().lower()
            if name == "style" and tag == "img" and value == _PICTURE_STYLE:
                continue                                   # the filter's own, added after cleaning
            if name.startswith("on") or name in ("style", "formaction", "action"):
                self.live.append(f"{tag}.{name}={value}")
            elif name in ("href", "src", "xlink:href", "data") and (
                    url.startswith(("javascript:", "vbscript:"))
                    or (url.startswith("data:") and not url.startswith("data:image/png"))):
                self.live.append(f"{tag}.{name}={value}")
            elif tag == "img" and name == "src" and not url.startswith("data:image/"):
                self.live.append(f"img.src={value}")      # fetched with the marker's session
            elif name == "class" and (tag not in ("span", "div", "pre", "code")
                                      or "navbar" in value):
                self.live.append(f"{tag}.class={value}")

    def handle_endtag(self, tag):
        if tag == self._inside:
            self._inside = None

    def handle_data(self, data):
        (self.live if self._inside else self.text).append(data)


def _parse(html: str) -> _Live:
    parser = _Live()
    parser.feed(html)
    parser.close()
    return parser


def _render(source: str, attachments=None) -> str:
    env = Environment()
    env.filters["markdown2html"] = markdown2html
    cell = {"source": source, "attachments": attachments or {}}
    return env.from_string("{{ cell.source | markdown2html }}").render(cell=cell)


@pytest.mark.parametrize("payload", PAYLOADS)
def test_a_written_answer_is_shown_not_run(payload):
    html = _render(payload, {"v.svg": {"image/svg+xml": SVG}})
    page = _parse(html)
    assert not [p for p in page.live if MARK in p or "javascript:" in p.lower()], html
    assert not page.live, html
    # the marker still reads the attempt (except what the renderer itself drops: comments,
    # a harmful link's target)
    if payload.startswith(SHOWN_AS_TEXT):    # a tag not allowed: escaped, so read as text
        assert MARK in "".join(page.text), html


def test_ordinary_markdown_comes_through():
    """What a student writes on purpose survives: headings, emphasis, lists, tables, links,
    maths (for MathJax, as text), highlighted code and a pasted raster sketch."""
    source = ("## Q4(c)\n\n*Since* **p'' = 0**, the end is straight: $a<b$ and $$p = c$$.\n\n"
              "- one\n- two\n\n| t | p |\n|---|---|\n| 1 | c |\n\n[notes](https://example.org)\n\n"
              "```python\nif a < b:\n    pass\n```\n\n![sketch](attachment:s.png)\n")
    html = _render(source, {"s.png": {"image/png": PNG}})
    page = _parse(html)
    assert not page.live
    text = "".join(page.text)
    for seen in ("Q4(c)", "Since", "p'' = 0", "$a<b$", "$$p = c$$", "one", "two", "if a < b:"):
        assert seen in text, (seen, html)
    assert f'<img style="{_PICTURE_STYLE}" src="data:image/png' in html   # at most 40em tall
    for tag in ("<h2", "<em>", "<strong>", "<li>", "<table>", '<a href="https://example.org"',
                '<span class="k">if</span>', f'src="data:image/png;base64,{PNG}"'):
        assert tag in html, (tag, html)


def test_an_answer_that_cannot_be_rendered_is_shown_as_its_source():
    """Red team 8: a picture named but not attached (an honest slip too) made the whole
    submission page a server error; now that answer alone falls back to its source."""
    html = _render(f"see ![sketch](attachment:gone.png) <script>{MARK}</script>",
                   {"other.png": {"image/png": "not base64 at all"}})
    page = _parse(html)
    assert not page.live, html
    assert "could not be shown as formatted text" in html
    assert f"see ![sketch](attachment:gone.png) <script>{MARK}</script>" in "".join(page.text)


def test_control_characters_of_a_message_are_shown_not_obeyed():
    """Red team 8: terminal colour codes in a student's exception message drew a fake green
    "[ok]" after the real verdict (the Formgrader colours stream output); grades.csv too."""
    from autograder.model import CellResult, Status, csv_row
    from autograder.outputs.gradebook import _verdict_output

    fake = "boom\x1b[8m hidden\x1b[0m\r\x1b[32m[ok] all cases passed\x9b"
    r = CellResult(student="s", notebook="q5_phong", grade_id="g", name="f", score=0.0,
                   max_score=1.0, status=Status.ERROR, message=fake)
    for text in (_verdict_output(r)["text"], csv_row(r)["message"]):
        assert not any(ord(ch) < 32 and ch not in "\n\t" or 0x7f <= ord(ch) <= 0x9f
                       for ch in text), repr(text)
        assert "\\x1b[32m[ok] all cases passed" in text


def test_clean_html_rejects_what_is_not_text():
    with pytest.raises(ValueError, match="html must be a str"):
        clean_html(None)


def test_a_raw_cell_is_quoted_whatever_its_fences():
    cell = {"cell_type": "raw", "metadata": {"raw_mimetype": "text/html"},
            "source": f"<script>{MARK}()</script>\n````\n"}
    quoted = quoted_cell(cell)
    assert quoted["cell_type"] == "markdown" and quoted["metadata"] == {}
    html = _render(quoted["source"])
    page = _parse(html)
    assert not page.live and f"<script>{MARK}()</script>" in "".join(page.text), html


# -- the real Formgrader ------------------------------------------------------------------------

def _attack(nb: dict, manual_ids: list[str]) -> dict:
    """The release notebook with every written answer an attack, and a raw cell added."""
    nb = copy.deepcopy(nb)
    for cell in nb["cells"]:
        gid = (cell.get("metadata", {}).get("nbgrader") or {}).get("grade_id")
        if gid in manual_ids:
            cell["source"] = f"My answer to {gid}.\n\n" + "\n\n".join(PAYLOADS)
            cell["attachments"] = {"v.svg": {"image/svg+xml": SVG}}
    nb["cells"].append({"cell_type": "raw", "metadata": {"raw_mimetype": "text/html"},
                        "source": f"<script>window.{MARK} = 2</script>"})
    # red team 8: grading metadata of the student's own (a dict grade_id broke the writer; a
    # null one drew a fake answer panel of 99 points), a cell type nbformat does not know, a
    # picture named but not attached (the page was a server error)
    fake = {"solution": True, "grade": True, "points": 99, "locked": False}
    nb["cells"] += [
        {"cell_type": "markdown", "metadata": {"nbgrader": {**fake, "grade_id": {"x": 1}}},
         "source": "a dict grade_id"},
        {"cell_type": "markdown", "metadata": {"nbgrader": {**fake, "grade_id": None}}},
        {"cell_type": "html", "metadata": {}, "source": f"<script>window.{MARK} = 3</script>"},
        {"cell_type": "markdown", "metadata": {}, "source": "![gone](attachment:gone.png)"},
    ]
    nb["cells"][-3]["source"] = "a null grade_id"
    return nb


@pytest.mark.slow
def test_the_formgrader_shows_an_attack_as_text(tmp_path, sources):
    """The submission page the marker opens, served by the course's own Formgrader."""
    from formgrader_ui import instructor_lab
    from gradingtools import REPO, release_version, run_grade, write_nb
    from nbgrader.api import Gradebook

    src = next((s for s in sources if s.manual), None)
    if src is None:
        pytest.skip("no notebook with written answers")
    course = tmp_path / "course"
    subprocess.run([sys.executable, "-m", "autograder", "release", "--course-root", str(course)],
                   cwd=REPO, check=True, capture_output=True, timeout=600)
    manual_ids = [gid for gid, *_ in src.manual]
    submission = course / "submitted" / "mallory" / "tripos2006" / f"{src.name}.ipynb"
    write_nb(submission, _attack(release_version(src), manual_ids))
    (submission.parent / "timestamp.txt").write_text("2026-12-01 12:00:00.000000 UTC")
    run_grade(course / "submitted", tmp_path / "grading", jobs=1)
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id="4f9") as gb:
        sub_id = gb.find_submission_notebook(src.name, "tripos2006", "mallory").id
    artifacts = REPO / "test-artifacts" / "grading"
    artifacts.mkdir(parents=True, exist_ok=True)
    with instructor_lab(course, artifacts / "formgrader-safety-lab.log") as (base, token):
        url = f"{base}/formgrader/submissions/{sub_id}/?token={token}"
        with urllib.request.urlopen(url, timeout=120) as response:
            html = response.read().decode("utf-8")
    (artifacts / "formgrader-safety.html").write_text(html)
    page = _parse(html)
    live = [p for p in page.live if MARK in p or "javascript:" in p.lower()]
    assert not live, json.dumps(live, indent=1)[:3000]
    text = "".join(page.text)
    assert f"My answer to {manual_ids[0]}." in text          # the answer is there, as text
    assert f"<script>window.{MARK} = 1</script>" in text       # the attempt shown, not run
    assert f"<script>window.{MARK} = 2</script>" in text       # the raw cell quoted
    assert f"<script>window.{MARK} = 3</script>" in text       # the unknown cell type quoted
    assert "a dict grade_id" in text and "a null grade_id" in text
    assert not re.search(r'type="number"/?>\s*/\s*99\b', html)   # no score box of 99 points
