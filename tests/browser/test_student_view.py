"""What a student sees in the browser after ``make lab`` (``python -m autograder lab --role
student``): the released notebooks, nbgrader's Validate button and Assignments panel, and none of
the instructor's tools (Create Assignment, Formgrader)."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
import time
import urllib.request

import pytest

from autograder.course import nbgrader_env

pytestmark = [pytest.mark.browser, pytest.mark.slow, pytest.mark.xdist_group("browser")]


@pytest.fixture
def student_lab(tmp_path, repo_root, free_port):
    port = free_port
    log = open(tmp_path / "lab.log", "w+")
    proc = subprocess.Popen(
        [sys.executable, "-m", "autograder", "lab", "--role", "student", "--port", str(port),
         "--no-browser", "--course-root", str(tmp_path / "course")],
        cwd=repo_root, env=nbgrader_env(), stdout=log, stderr=subprocess.STDOUT, text=True)
    try:
        deadline, url = time.monotonic() + 180, None
        while time.monotonic() < deadline and proc.poll() is None:
            log.seek(0)
            m = re.search(rf"(http://localhost:{port}/\S*\?token=\w+)", log.read())
            if m:
                try:
                    with urllib.request.urlopen(m.group(1), timeout=5) as r:
                        if r.status == 200:
                            url = m.group(1)
                            break
                except OSError:
                    pass
            time.sleep(0.5)
        if url is None:
            log.seek(0)
            pytest.fail(f"the student lab did not come up:\n{log.read()[-3000:]}")
        yield url
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
        log.close()


def test_student_sees_release_notebooks_and_validate_only(page, student_lab, artifacts):
    base, query = student_lab.split("/lab", 1)[0], student_lab.split("?", 1)[1]
    page.goto(f"{base}/lab/tree/tripos2006/q5_phong.ipynb?{query}")
    page.wait_for_selector(".jp-NotebookPanel .jp-Notebook .jp-Cell")
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
