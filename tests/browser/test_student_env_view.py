"""``make lab`` in the browser: the student view served from the students' own environment.

``python -m autograder lab --role student --student-env ENV`` (what ``make lab`` runs, with
``.venv-student``) starts JupyterLab from a virtual environment holding only the students'
wheel (here the tests' shared one, ``tests/studentenv.py``). In a release notebook a student
sees nbgrader's Validate button, the kernel imports ``course_lib`` from that environment, and
``perspective_matrix??`` (a shipped function of Q6) shows its docstring but no source.
"""

from __future__ import annotations

import re

import pytest
import studentenv

from autograder.course import nbgrader_env
from labtools import running_lab

pytestmark = [pytest.mark.browser, pytest.mark.slow, pytest.mark.xdist_group("student_env")]


@pytest.fixture
def student_env_lab(tmp_path, repo_root, free_port):
    """URL of ``autograder lab --role student`` run in the tests' student environment."""
    studentenv.python()  # build and install first (minutes on a cold cache), then time the start
    args = ["--role", "student", "--course-root", str(tmp_path / "course"),
            "--student-env", str(studentenv.ENV_DIR), "--build-cache", str(studentenv.BUILD_CACHE)]
    with running_lab(args, free_port, tmp_path / "lab.log", repo_root, nbgrader_env(),
                     "the student lab") as url:
        yield url


def test_student_env_shows_docstring_not_source(page, student_env_lab, artifacts):
    base, query = student_env_lab.split("/lab", 1)[0], student_env_lab.split("?", 1)[1]
    # a workspace of its own (``reset``): no tab restored from another test's session
    page.goto(f"{base}/lab/workspaces/student-env/tree/tripos2006/q6_clipping.ipynb?reset&{query}")
    panel = page.locator(".jp-NotebookPanel:visible").first
    panel.locator(".jp-Notebook .jp-Cell").first.wait_for()
    page.locator(".jp-NotebookPanel-toolbar:visible", has_text="Validate").first.wait_for(
        timeout=30_000)
    # the kernel (started from the student environment) is up before anything is typed
    page.get_by_text(re.compile(r"\|\s*Idle")).first.wait_for(timeout=180_000)
    # a new cell above the first: where is course_lib, and what does ?? show of a reference
    panel.locator(".jp-Notebook .jp-Cell").first.click()
    page.keyboard.press("Escape")
    page.keyboard.press("a")
    page.keyboard.press("Enter")
    first = panel.locator(".jp-Notebook .jp-Cell").first
    page.keyboard.type("import course_lib.clipping as reference\nprint(reference.__file__)\n"
                       "reference.perspective_matrix??")
    first.get_by_text("reference.perspective_matrix??").wait_for(timeout=30_000)
    page.keyboard.press("Shift+Enter")
    output = first.locator(".jp-OutputArea")
    try:
        output.get_by_text("from camera coordinates to homogeneous").first.wait_for(timeout=180_000)
    finally:
        page.screenshot(path=str(artifacts / "student-env-perspective-matrix-source.png"))
    text = output.inner_text()
    site = str(studentenv.site_packages())
    assert site in text and ".so" in text, f"course_lib not from the student env:\n{text[:1000]}"
    assert "def perspective_matrix" not in text and "Source:" not in text, text[:2000]
