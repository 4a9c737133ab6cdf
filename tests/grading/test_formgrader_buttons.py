"""No click in the course's Formgrader hands a marker's rubric to a student.

nbgrader's Manage Assignments and Manage Submissions pages put Generate, Release, Collect,
Autograde, Generate Feedback and Release Feedback one click away; nbgrader's generate_feedback
copies the autograded notebooks, rubric cells included, into the students' pages. The test
runs a one-student term on nbgrader's local exchange with the students' own commands, opens
the real Formgrader of ``python -m autograder lab --role instructor`` in Debian's Chromium and
clicks every button of both pages; then calls the refused URLs directly (a hidden button can
still be called by URL), and runs nbgrader's own ``generate_feedback`` by hand.

Oracle: the rubric text of the source notebook (what the marker sees under each written
answer) must appear in no page a student can receive: ``course/feedback/``, the exchange's
feedback folder, and what the student's ``nbgrader fetch_feedback`` brings home.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import urllib.request
from pathlib import Path

import pytest

from gradingtools import REPO, SECRET, model_version, run_grade, write_nb

pytestmark = [pytest.mark.xdist_group("term"), pytest.mark.slow]

A = "tripos2006"
STUDENT = "carol"


def _student_env(home: Path) -> dict:
    env = {k: v for k, v in os.environ.items() if not k.startswith("JUPYTER")}
    env.update(HOME=str(home),
               PATH=f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}")
    return env


def _run(cmd: list[str], cwd: Path, env: dict | None = None) -> subprocess.CompletedProcess:
    proc = subprocess.run(cmd, cwd=cwd, env=env or dict(os.environ, MPLBACKEND="Agg"),
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0 and "[ERROR]" not in proc.stderr, (cmd, proc.stderr[-3000:])
    return proc


def _nbgrader(args: list[str], cwd: Path, env: dict | None = None) -> subprocess.CompletedProcess:
    return _run([sys.executable, "-m", "nbgrader", *args], cwd, env)


def rubric_lines(src) -> list[str]:
    """Lines of the source notebook's written-answer cells (model answer and rubric) that a
    student's page must never show: long enough not to occur by chance."""
    out = []
    for gid, _ in src.manual:
        cell = next(c for c in src.nb["cells"]
                    if (c["metadata"].get("nbgrader") or {}).get("grade_id") == gid)
        text = "".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]
        out += [ln.strip() for ln in text.splitlines()
                if len(ln.strip()) > 40 and "BEGIN SOLUTION" not in ln and "END SOLUTION" not in ln]
    return out


def student_pages(base: Path) -> dict[Path, str]:
    """Every HTML page a student can receive, with its text."""
    import html

    roots = [base / "course" / "feedback", base / "course" / "exchange",
             base / "home" / STUDENT / A / "feedback"]
    return {p: html.unescape(p.read_text(encoding="utf-8", errors="replace"))
            for r in roots if r.exists() for p in r.rglob("*.html")}


def assert_no_rubric(base: Path, lines: list[str]) -> None:
    pages = student_pages(base)
    assert pages, "no page to check"
    leaks = [(str(p), ln) for p, text in pages.items() for ln in lines if ln in text]
    leaks += [(str(p), "For the marker of") for p, text in pages.items()
              if "For the marker of" in text]
    assert not leaks, leaks[:5]


@pytest.fixture(scope="module")
def term(tmp_path_factory, sources):
    """Release, one student's fetch and submit (the README's commands), collect, grade,
    the course's hand-back; the student fetches it."""
    src = next(s for s in sources if s.manual)
    base = tmp_path_factory.mktemp("buttons")
    course = base / "course"
    (base / "secret").write_bytes(SECRET + b"\n")
    _run([sys.executable, "-m", "autograder", "release", "--course-root", str(course)], REPO)
    _nbgrader(["release_assignment", A], course)
    home = base / "home" / STUDENT
    (home / ".jupyter").mkdir(parents=True)
    shutil.copyfile(course / "for-students" / "nbgrader_config.py",
                    home / ".jupyter" / "nbgrader_config.py")
    env = _student_env(home)
    _nbgrader(["fetch_assignment", A, "--course", "4f9"], home, env)
    nb = model_version(src)
    for cell in nb["cells"]:
        if (cell["metadata"].get("nbgrader") or {}).get("grade_id") in dict(src.manual):
            cell["source"] = "Carol's own words about the echo: $t = 2d/c$."
    write_nb(home / A / f"{src.name}.ipynb", nb)
    # each student is a login of their own on a real machine; one account runs them all here,
    # so --student says whose work it is (nbgrader takes the id from the Unix account)
    _nbgrader(["submit", A, "--course", "4f9", f"--student={STUDENT}"], home, env)
    _nbgrader(["collect", A], course)
    run_grade(course / "submitted", base / "grading", secret_file=base / "secret")
    _run([sys.executable, "-m", "autograder", "feedback", "--grading", str(base / "grading"),
          "--course", str(course)], REPO)
    _nbgrader(["fetch_feedback", A, "--course", "4f9", f"--student={STUDENT}"], home, env)
    lines = rubric_lines(src)
    assert lines, "the source notebook's written answers carry a model answer and rubric"
    autograded = (course / "autograded" / STUDENT / A / f"{src.name}.ipynb").read_text()
    assert any(json.dumps(ln)[1:-1] in autograded for ln in lines), \
        "the marker's copy shows the rubric (else this test checks nothing)"
    return {"base": base, "course": course, "src": src, "lines": lines, "env": env,
            "home": home}


def _close_modal(page) -> str:
    modal = page.locator(".modal.in, .modal.show").last
    modal.wait_for(state="visible", timeout=120_000)
    text = modal.inner_text()
    page.evaluate("() => { $('.modal').modal('hide'); $('.modal, .modal-backdrop').remove(); "
                  "$('body').removeClass('modal-open'); }")
    return text


#: the buttons the course hides (and refuses): clicked all the same, as a script would
HIDDEN = ("assign", "generate-feedback", "autograde")


def _click(page, link, column: str, said: dict, key: str) -> None:
    link.wait_for(state="attached")
    if column in HIDDEN:
        assert link.is_hidden(), f"the {column} button is shown"
        link.dispatch_event("click")
    else:
        link.click()
    said[key] = said.get(key, "") + "\n" + _close_modal(page)


def click_every_button(course: Path, artifacts: Path) -> dict[str, str]:
    """Every button of Manage Assignments and Manage Submissions, in Chromium; the dialog
    each one opened (the hidden ones clicked by script); the pages' own text under "page"."""
    from formgrader_ui import CHROMIUM, browser_conftest, instructor_lab
    from playwright.sync_api import sync_playwright

    said = {}
    with instructor_lab(course, artifacts / "formgrader-buttons-lab.log") as (base, token), \
            sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=str(CHROMIUM),
                                     args=browser_conftest.CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport={"width": 1400, "height": 1000})
            page.set_default_timeout(60_000)
            page.goto(f"{base}/formgrader/manage_assignments?token={token}")
            row = page.locator("tr", has=page.locator("td.name a", has_text=A))
            row.wait_for()
            said["page"] = page.locator("body").inner_text()
            page.screenshot(path=str(artifacts / "formgrader-buttons-assignments.png"))
            # released by the term: Release shows Unrelease; clicking it makes it Release again
            for column in ("generate-feedback", "release-feedback", "collect", "release",
                           "release", "assign"):
                _click(page, row.locator(f"td.{column} a").first, column, said, column)
            page.goto(f"{base}/formgrader/manage_submissions/{A}?token={token}")
            for column in ("autograde", "generate-feedback", "release-feedback"):
                _click(page, page.locator(f"td.{column} a").first, column, said,
                       "submission " + column)
        finally:
            browser.close()
    return said


def post(base: str, token: str, path: str) -> dict:
    req = urllib.request.Request(f"{base}{path}", data=b"", method="POST",
                                 headers={"Authorization": f"token {token}"})
    with urllib.request.urlopen(req, timeout=300) as r:
        return json.loads(r.read().decode())


def test_no_formgrader_button_hands_a_rubric_to_a_student(term):
    import formgrader_ui

    if not formgrader_ui.CHROMIUM.exists():
        pytest.skip("Debian's chromium is not installed (make browser-deps)")
    course, base = term["course"], term["base"]
    assert_no_rubric(base, term["lines"])                  # the course's own hand-back
    ours = {p: p.read_bytes() for p in (course / "feedback").rglob("*.html")}
    artifacts = REPO / "test-artifacts" / "grading"
    artifacts.mkdir(parents=True, exist_ok=True)
    said = click_every_button(course, artifacts)
    (artifacts / "formgrader-buttons.json").write_text(json.dumps(said, indent=1))
    assert "python -m autograder feedback --grading grading/" in said["page"]   # the note
    assert "python -m autograder feedback" in said["generate-feedback"]
    assert "python -m autograder feedback" in said["submission generate-feedback"]
    assert "python -m autograder grade" in said["submission autograde"]
    assert "python -m autograder release" in said["assign"]
    assert "Successfully released" in said["release-feedback"]   # the course's own pages
    assert "Successfully released" in said["release"]            # after the leak check
    assert {p: p.read_bytes() for p in (course / "feedback").rglob("*.html")} == ours, \
        "a button rewrote the course's feedback pages"
    _nbgrader(["fetch_feedback", A, "--course", "4f9", f"--student={STUDENT}"], term["home"],
              term["env"])
    assert_no_rubric(base, term["lines"])


def test_refused_calls_are_refused_by_url_and_nbgrader_by_hand_withholds_rubrics(term):
    """The server refuses what a hidden button would call; nbgrader's own generate_feedback
    (typed in a shell) writes pages without the rubric, and the Formgrader will not release
    them in place of the course's."""
    from formgrader_ui import instructor_lab

    course, base = term["course"], term["base"]
    _nbgrader(["generate_feedback", A, "--force"], course)
    nbgrader_pages = list((course / "feedback").rglob("*.html"))
    assert nbgrader_pages, "nbgrader wrote its pages"
    assert_no_rubric(base, term["lines"])
    artifacts = REPO / "test-artifacts" / "grading"
    artifacts.mkdir(parents=True, exist_ok=True)
    exchange_before = {p: p.read_bytes() for p in (course / "exchange").rglob("*.html")}
    with instructor_lab(course, artifacts / "formgrader-urls-lab.log") as (url, token):
        for path in (f"/formgrader/api/assignment/{A}/generate_feedback",
                     f"/formgrader/api/assignment/{A}/{STUDENT}/generate_feedback",
                     f"/formgrader/api/submission/{A}/{STUDENT}/autograde",
                     f"/formgrader/api/assignment/{A}/assign"):
            answer = post(url, token, path)
            assert answer["success"] is False and "Nothing was done" in answer["error"], path
        for path in (f"/formgrader/api/assignment/{A}/release_feedback",
                     f"/formgrader/api/assignment/{A}/{STUDENT}/release_feedback"):
            answer = post(url, token, path)
            assert answer["success"] is False, (path, answer)
            assert f"{STUDENT}/" in answer["error"] and "not written by" in answer["error"]
    assert {p: p.read_bytes() for p in (course / "exchange").rglob("*.html")} == exchange_before


def test_withhold_rubrics_drops_the_markers_cells_only():
    """nbconvert, as nbgrader's generate_feedback registers it: by its configured name."""
    import nbformat
    from nbconvert.exporters import HTMLExporter

    from autograder.outputs.gradebook import RUBRIC_KEY

    nb = nbformat.v4.new_notebook(cells=[
        nbformat.v4.new_markdown_cell("The student's answer, about the echo."),
        nbformat.v4.new_markdown_cell("**For the marker of `q1a`** SECRET-RUBRIC-1",
                                      metadata={RUBRIC_KEY: {"for": "q1a"}}),
        nbformat.v4.new_markdown_cell("**For the marker of `q1b` (never handed back)** "
                                      "SECRET-RUBRIC-2"),
    ])
    exporter = HTMLExporter()
    exporter.register_preprocessor("autograder.formgrader.withhold.WithholdRubrics")
    html, _ = exporter.from_notebook_node(nb)
    assert "SECRET-RUBRIC" not in html and "about the echo" in html


def test_the_markers_page_renders_latex_with_a_local_mathjax(term):
    """The submission page typesets a written answer's LaTeX with the MathJax this server
    serves (Debian's libjs-mathjax), asking no other host for anything."""
    import formgrader_ui
    from nbgrader.api import Gradebook
    from playwright.sync_api import sync_playwright

    from autograder.formgrader.handlers import MATHJAX_DIR

    if not formgrader_ui.CHROMIUM.exists() or not (MATHJAX_DIR / "MathJax.js").exists():
        pytest.skip("needs Debian's chromium and libjs-mathjax (make browser-deps mathjax-deps)")
    course, src = term["course"], term["src"]
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id="4f9") as gb:
        sub_id = gb.find_submission_notebook(src.name, A, STUDENT).id
    artifacts = REPO / "test-artifacts" / "grading"
    artifacts.mkdir(parents=True, exist_ok=True)
    with formgrader_ui.instructor_lab(course, artifacts / "formgrader-mathjax-lab.log") as (
            base, token), sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=str(formgrader_ui.CHROMIUM),
                                     args=formgrader_ui.browser_conftest.CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport={"width": 1400, "height": 1000})
            hosts = []
            page.on("request", lambda r: hosts.append(r.url.split("/")[2]))
            page.goto(f"{base}/formgrader/submissions/{sub_id}/?token={token}")
            page.wait_for_selector(".MathJax_CHTML", timeout=120_000)
            typeset = page.locator(".MathJax_CHTML").count()
            page.screenshot(path=str(artifacts / "formgrader-mathjax.png"))
        finally:
            browser.close()
    assert typeset >= 1, "no formula typeset"
    assert set(hosts) == {base.split("/")[2]}, set(hosts)
