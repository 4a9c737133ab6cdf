"""What a student sees in the browser after ``make lab`` (``python -m autograder lab --role
student --student-env``, the students' own venv with only their compiled wheel): the released
notebooks, nbgrader's Validate button and Assignments panel, and none of
the instructor's tools (Create Assignment, Formgrader)."""

from __future__ import annotations

import time

import pytest

from autograder.course import nbgrader_env
from labtools import open_notebook, run_all_cells, running_lab, wait_idle

pytestmark = [pytest.mark.browser, pytest.mark.slow, pytest.mark.xdist_group("browser")]


@pytest.fixture
def student_lab(tmp_path, repo_root, free_port):
    import studentenv

    studentenv.python()   # build the wheel and the students' venv before the start-up clock
    args = ["--role", "student", "--course-root", str(tmp_path / "course"),
            "--student-env", str(studentenv.ENV_DIR), "--build-cache", str(studentenv.BUILD_CACHE)]
    with running_lab(args, free_port, tmp_path / "lab.log", repo_root, nbgrader_env(),
                     "the student lab") as url:
        yield url


def test_student_sees_release_notebooks_and_validate_only(page, student_lab, artifacts):
    base, query = student_lab.split("/lab", 1)[0], student_lab.split("?", 1)[1]
    open_notebook(page, base, query, "tripos2006/q5_phong.ipynb")
    # the notebook served to the student is the release: stubs, no model solution
    resp = page.request.get(f"{base}/api/contents/tripos2006/q5_phong.ipynb?{query}")
    assert resp.ok
    source = "\n".join("".join(c["source"]) for c in resp.json()["content"]["cells"])
    assert "raise NotImplementedError" in source and "YOUR ANSWER HERE" in source
    assert "BEGIN SOLUTION" not in source and "HIDDEN TESTS" not in source
    # nbgrader's promise to students: Validate in the notebook toolbar, the Assignments panel
    page.locator(".jp-NotebookPanel-toolbar", has_text="Validate").first.wait_for(timeout=30_000)
    page.locator(".lm-MenuBar-itemLabel", has_text="Nbgrader").first.click()
    menu = page.locator(".lm-Menu").last
    menu.wait_for()
    items = menu.inner_text()
    page.screenshot(path=str(artifacts / "student-view-nbgrader-menu.png"))
    page.keyboard.press("Escape")
    assert "Assignment List" in items
    assert "Formgrader" not in items and "Course List" not in items
    # no "Create Assignment" side panel for students
    assert page.locator(".lm-TabBar-tab", has_text="Create Assignment").count() == 0


def test_student_run_all_on_untouched_notebook_renders_explorers(page, student_lab, artifacts):
    """A student opens an untouched release notebook and chooses Run All: the stubs and the
    failing tests show their errors (their cells carry the ``raises-exception`` tag), and every
    cell below them still runs, so the figures and the explorer render."""
    from test_explorers_in_lab import FIGURE_CANVAS, canvas_pixels

    base, query = student_lab.split("/lab", 1)[0], student_lab.split("?", 1)[1]
    open_notebook(page, base, query, "tripos2006/q5_phong.ipynb")
    run_all_cells(page, 90, 300)
    # the explorer (the last code cell) rendered: its figure canvas is not blank
    out = page.locator(".jp-OutputArea-output").filter(has=page.locator(FIGURE_CANVAS)).first
    out.wait_for(timeout=120_000)
    wait_idle(page, 120)
    page.screenshot(path=str(artifacts / "student-run-all.png"))
    canvas = out.locator(FIGURE_CANVAS).first
    pixels = canvas_pixels(canvas)
    out.screenshot(path=str(artifacts / "student-run-all-explorer.png"))
    assert pixels.size and float(pixels.std()) > 5.0, "the explorer's canvas is blank"
    # JupyterLab renders only the cells near the view, so read what Run All did from the saved
    # notebook (saved again until the last cell's run is in it): the stubs failed visibly ...
    cells = []
    for _ in range(30):
        page.keyboard.press("Control+s")
        time.sleep(1.0)
        resp = page.request.get(f"{base}/api/contents/tripos2006/q5_phong.ipynb?{query}")
        cells = [c for c in resp.json()["content"]["cells"] if c["cell_type"] == "code"]
        if cells and cells[-1].get("execution_count"):
            break
    errors = [o for c in cells for o in c.get("outputs", []) if o.get("output_type") == "error"]
    assert any(o.get("ename") == "NotImplementedError" for o in errors), \
        "Run All showed no stub error: did it run the solution cells at all?"
    # ... and Run All went on past them to the last code cell
    assert cells[-1].get("execution_count"), "the last code cell did not run"
    # and the static figures above it are images
    assert page.locator(".jp-OutputArea-output img").count() >= 1, "no static figure rendered"
