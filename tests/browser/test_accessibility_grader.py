"""The pages of the people who grade and are graded: axe-core (WCAG 2.0/2.1 A and AA) finds no
serious or critical violation on the class report, the students' feedback pages, and the
Formgrader pages a marker goes through (assignments, one notebook's submissions, one
submission to mark), served by the course's own instructor JupyterLab.

One release notebook is handed in by two students (the model answers, and untouched), graded
by ``python -m autograder grade`` as an instructor runs it.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

from a11y import describe, run_axe, save, severe

pytestmark = [pytest.mark.browser, pytest.mark.slow, pytest.mark.xdist_group("browser")]

REPO = Path(__file__).resolve().parents[2]
NOTEBOOK = "q5_phong"
#: what axe finds on nbgrader's own Formgrader pages (nbgrader 0.9's templates, Bootstrap 3 and
#: Pygments' default style), which the course does not render: ``(rule, the element's HTML,
#: why)``. Anything else on those pages (a student's answer as shown to the marker, a picture
#: without a text alternative, a new kind of violation) still fails.
_PYGMENTS = "Pygments' default colours in nbgrader's code cells (#777 comments on #f8f8f8: 4.2:1)"
_BOOTSTRAP = "Bootstrap 3's greys in nbgrader's navigation (#777 on #f5f5f5 or white)"
FORMGRADER_EXCEPTIONS = (
    ("html-has-lang", "<html", "nbgrader's Formgrader templates give <html> no lang"),
    ("color-contrast", '<span class="c1"', _PYGMENTS),
    ("color-contrast", '<span class="ne"', _PYGMENTS),
    ("color-contrast", '<span class="ow"', _PYGMENTS),
    ("color-contrast", "data-placement=", _BOOTSTRAP),
    ("color-contrast", '<a href="/formgrader/gradebook', _BOOTSTRAP),
    ("color-contrast", '<li class="active">', _BOOTSTRAP),
    ("color-contrast", "label label-info", _BOOTSTRAP),
    ("label", 'class="score tabbable', "nbgrader's manual-grading score boxes have no <label>"),
    ("link-name", "glyphicon", "nbgrader's icon-only links (edit, assign, release, preview)"),
    ("list", 'class="nav', "nbgrader's navigation nests a <ul> directly in a <ul>"),
    ("nested-interactive", 'role="tab"', "Bootstrap 3's collapsible panel headings (role=tab)"),
    ("scrollable-region-focusable", "<pre>",
     "nbconvert's code cells in the Formgrader scroll in a <pre> that takes no focus"),
)


def _grading_module(name: str):
    """A helper module of ``tests/grading`` (the grading tests' own builders)."""
    spec = importlib.util.spec_from_file_location(f"a11y_{name}",
                                                  REPO / "tests" / "grading" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    """``(course, grading_out)`` after two students' hand-ins of ``NOTEBOOK`` were graded."""
    if not Path("/usr/bin/bwrap").exists():
        pytest.skip("bubblewrap is not installed (make test installs it): nothing is graded")
    tools = _grading_module("gradingtools")
    src = next((s for s in tools.course_sources() if s.name == NOTEBOOK), None)
    if src is None:
        pytest.skip(f"no source notebook {NOTEBOOK}")
    tmp = tmp_path_factory.mktemp("a11y-grading")
    course = tmp / "course"
    subprocess.run([sys.executable, "-m", "autograder", "release", "--course-root", str(course)],
                   cwd=REPO, check=True, capture_output=True, timeout=900)
    for student, nb in (("ada", tools.model_version(src)), ("bob", tools.release_version(src))):
        path = course / "submitted" / student / "tripos2006" / f"{NOTEBOOK}.ipynb"
        tools.write_nb(path, nb)
        (path.parent / "timestamp.txt").write_text("2026-12-01 12:00:00.000000 UTC")
    tools.run_grade(course / "submitted", tmp / "grading", jobs=1)
    return course, tmp / "grading"


def test_report_and_feedback_pages(page, graded, artifacts):
    _course, out = graded
    pages = [out / "report.html", *sorted((out / "feedback").rglob("*.html"))]
    assert len(pages) >= 3, pages            # the report and both students' feedback
    problems = []
    for path in pages:
        page.goto(path.as_uri())
        found = run_axe(page, "html")
        save(artifacts / f"axe-grading-{path.stem}.json", found)
        bad = severe(found)
        if bad:
            problems.append(f"{path.relative_to(out)}:\n{describe(bad)}")
    assert not problems, "\n".join(problems)


def test_formgrader_pages_a_marker_uses(page, graded, artifacts):
    from nbgrader.api import Gradebook

    course, _out = graded
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id="4f9") as gb:
        sub_id = gb.find_submission_notebook(NOTEBOOK, "tripos2006", "ada").id
    ui = _grading_module("formgrader_ui")
    problems = []
    with ui.instructor_lab(course, artifacts / "a11y-formgrader-lab.log") as (base, token):
        for name, path in (("assignments", "/formgrader/manage_assignments"),
                           ("submissions", f"/formgrader/gradebook/tripos2006/{NOTEBOOK}"),
                           ("submission", f"/formgrader/submissions/{sub_id}/")):
            page.goto(f"{base}{path}?token={token}")
            page.wait_for_load_state("networkidle")
            found = run_axe(page, "html")
            save(artifacts / f"axe-formgrader-{name}.json", found)
            bad = severe(found, FORMGRADER_EXCEPTIONS)
            if bad:
                problems.append(f"{name} ({path}):\n{describe(bad)}")
    assert not problems, "\n".join(problems)
