"""A student submits in JupyterLab and reads the grading service's feedback page, in Chromium.

An nbgrader course in a temporary folder with ``tripos2006`` released to its own exchange; the
grading service (``python -m autograder watch``) on that exchange, as a subprocess; JupyterLab
in the student's view (``autograder.lab``'s per-launch configuration: the Assignments panel,
no Formgrader) serving a home folder of its own. In the browser the student fetches the
assignment in the Assignments panel, answers one graded function (``normalize`` of Q5(a),
taken from ``tests/grading/honest/``) in the notebook, saves, submits, presses Fetch Feedback
until the page has come back, and opens it. The page must show that function's full points
(from the source notebook's metadata), an unanswered function's zero, and "4 of 5 graded
attempts left today" (the default policy's five, one used). No hub: the Unix user running the
tests is the student (the service's owner check then holds). Screenshots in
``test-artifacts/browser/``.
"""

from __future__ import annotations

import ast
import json
import os
import pwd
import re
import secrets
import subprocess
import sys
import time
import urllib.parse
import urllib.request
from pathlib import Path

import pytest

from autograder.course import ASSIGNMENT, COURSE_ID, nbgrader_env, prepare_course
from labtools import open_notebook

pytestmark = [pytest.mark.browser, pytest.mark.slow, pytest.mark.xdist_group("service_browser"),
              pytest.mark.timeout(1500)]

HONEST = Path(__file__).resolve().parents[1] / "grading" / "honest" / "q5_phong.py"
NOTEBOOK = "q5_phong"
ANSWERED, UNANSWERED = "normalize", "reflect"


def honest_function(name: str) -> str:
    """The source of ``name`` in the honest student's Q5 answers."""
    text = HONEST.read_text(encoding="utf-8")
    node = next(n for n in ast.parse(text).body
                if isinstance(n, ast.FunctionDef) and n.name == name)
    return ast.get_source_segment(text, node) + "\n"


def points(name: str) -> float:
    """The points of ``name``'s test cell in the source notebook (the oracle of the score)."""
    from autograder.course import NOTEBOOKS_DIR

    nb = json.loads((NOTEBOOKS_DIR / f"{NOTEBOOK}.ipynb").read_text(encoding="utf-8"))
    return next(c["metadata"]["nbgrader"]["points"] for c in nb["cells"]
                if c["metadata"].get("nbgrader", {}).get("grade_id") == f"test_{name}")


@pytest.fixture
def course(tmp_path):
    """A course with ``tripos2006`` released to its own exchange (``ROOT/exchange``)."""
    course = prepare_course(tmp_path / "course")
    course.nbgrader(["release_assignment", ASSIGNMENT, "--force"])
    for folder in ("inbound", "feedback"):
        (course.root / "exchange" / COURSE_ID / folder).mkdir(parents=True, exist_ok=True)
    return course


@pytest.fixture
def service(course, tmp_path):
    """``python -m autograder watch`` on the course's exchange (stopped afterwards)."""
    from autograder.isolation import IsolationUnavailable, probe

    try:
        probe()
    except IsolationUnavailable as exc:
        pytest.skip(str(exc))
    (tmp_path / "secret").write_bytes(secrets.token_bytes(32).hex().encode() + b"\n")
    log = open(tmp_path / "watch.log", "w+")
    proc = subprocess.Popen(
        [sys.executable, "-m", "autograder", "watch", "--exchange", str(course.root / "exchange"),
         "--course", str(course.root), "--secret-file", str(tmp_path / "secret"), "--poll", "0.5",
         "--jobs", "2", "--reference-seconds", "3"],
        env=nbgrader_env(), stdout=log, stderr=subprocess.STDOUT, text=True)
    try:
        yield proc, log
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
        log.close()


@pytest.fixture
def student_lab(course, tmp_path, free_port):
    """``(base, query, home)`` of JupyterLab in the student's view on a home folder of its own
    (its own ``HOME`` too: nbgrader's cache of submissions and JupyterLab's settings are not
    shared with anything else running as this user)."""
    from autograder.lab import lab_command, write_launch_config

    home = tmp_path / "home"
    home.mkdir()
    config = write_launch_config(tmp_path / "jupyter-config", "student", course.root)
    user = pwd.getpwuid(os.getuid()).pw_name
    env = dict(nbgrader_env(), HOME=str(home), USER=user, LOGNAME=user,
               JUPYTER_CONFIG_PATH=str(config))
    env.pop("MPLBACKEND", None)
    env.pop("JUPYTER_DATA_DIR", None)
    token = secrets.token_hex(16)
    cmd = lab_command("student", home, free_port, "127.0.0.1", token, False, "/lab")
    log = open(tmp_path / "lab.log", "w")
    proc = subprocess.Popen(cmd, cwd=home, env=env, stdout=log, stderr=subprocess.STDOUT)
    base = f"http://127.0.0.1:{free_port}"
    try:
        deadline = time.monotonic() + 180
        while True:
            try:
                with urllib.request.urlopen(f"{base}/api/status?token={token}", timeout=2):
                    break
            except OSError:
                if proc.poll() is not None or time.monotonic() > deadline:
                    log.flush()
                    pytest.fail("the student's lab did not start:\n"
                                + (tmp_path / "lab.log").read_text()[-3000:])
                time.sleep(0.5)
        yield base, f"token={token}", home
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
        log.close()


def open_assignments(page, base: str, query: str):
    """The Assignments panel (Nbgrader → Assignment List), its lists loaded."""
    page.goto(f"{base}/lab?reset&{query}")
    page.locator(".lm-MenuBar-itemLabel", has_text="Nbgrader").first.click()
    page.locator(".lm-Menu-itemLabel", has_text="Assignment List").first.click()
    panel = page.locator("#nbgrader-assignment-list")
    panel.wait_for()
    return panel


def refresh(panel) -> None:
    panel.locator("#refresh_assignments_list").click()
    time.sleep(1.0)


def answer_in_notebook(page, base: str, query: str, name: str, code: str) -> None:
    """Open the notebook, walk to ``name``'s solution cell (JupyterLab renders only the cells
    near the view), replace its text with ``code`` and save."""
    open_notebook(page, base, query, f"{ASSIGNMENT}/{NOTEBOOK}.ipynb")
    panel = page.locator(".jp-NotebookPanel:visible").first
    panel.locator(".jp-Notebook .jp-Cell").first.click()
    page.keyboard.press("Escape")
    active = panel.locator(".jp-Cell.jp-mod-active")
    for _ in range(400):
        if f"def {name}(" in active.inner_text():
            break
        page.keyboard.press("j")
    else:
        raise AssertionError(f"no cell defining {name} in {NOTEBOOK}")
    page.keyboard.press("Enter")                         # edit the cell
    page.keyboard.press("Control+a")                     # its whole text, in its editor
    page.keyboard.insert_text(code)                      # as pasted: no auto-indent
    page.keyboard.press("Escape")
    page.keyboard.press("Control+s")


def test_a_student_submits_and_reads_the_feedback_page(page, course, service, student_lab,
                                                       artifacts):
    base, query, home = student_lab
    code = honest_function(ANSWERED)

    panel = open_assignments(page, base, query)
    released = panel.locator("#released_assignments_list")
    released.get_by_text(ASSIGNMENT).wait_for(timeout=60_000)
    page.screenshot(path=str(artifacts / "service-1-released.png"))
    released.locator("button", has_text="Fetch").click()
    fetched = panel.locator("#fetched_assignments_list")
    fetched.locator("button", has_text="Submit").wait_for(timeout=60_000)
    assert (home / ASSIGNMENT / f"{NOTEBOOK}.ipynb").is_file()

    answer_in_notebook(page, base, query, ANSWERED, code)
    saved = (home / ASSIGNMENT / f"{NOTEBOOK}.ipynb").read_text(encoding="utf-8")
    for _ in range(40):                                  # the save lands on disk
        if "NaN or inf" in saved:                        # a line of the honest answer only
            break
        time.sleep(0.5)
        saved = (home / ASSIGNMENT / f"{NOTEBOOK}.ipynb").read_text(encoding="utf-8")
    assert "NaN or inf" in saved, "the answer did not reach the saved notebook"
    page.screenshot(path=str(artifacts / "service-2-answered.png"))

    panel = open_assignments(page, base, query)
    panel.locator("#fetched_assignments_list button", has_text="Submit").click()
    submitted = panel.locator("#submitted_assignments_list")
    submitted.locator("button", has_text="Fetch Feedback").wait_for(timeout=120_000)
    page.screenshot(path=str(artifacts / "service-3-submitted.png"))

    # the service grades it; Refresh until the panel says the feedback can be fetched
    proc, log = service
    deadline = time.monotonic() + 600
    while "feedback available to fetch" not in submitted.inner_text():
        if proc.poll() is not None or time.monotonic() > deadline:
            log.seek(0)
            pytest.fail(f"no feedback came back:\n{log.read()[-4000:]}")
        time.sleep(2.0)
        refresh(panel)
    submitted.locator("button", has_text="Fetch Feedback").click()
    submitted.get_by_text("view feedback").wait_for(timeout=120_000)
    page.screenshot(path=str(artifacts / "service-4-feedback-fetched.png"))

    pages = sorted((home / ASSIGNMENT / "feedback").glob(f"*/{NOTEBOOK}.html"))
    assert len(pages) == 1, pages
    rel = urllib.parse.quote(str(pages[0].relative_to(home)))
    page.goto(f"{base}/files/{rel}?{query}")
    body = page.locator("body")
    body.get_by_text("graded attempts left today").wait_for()
    page.screenshot(path=str(artifacts / "service-5-feedback-page.png"), full_page=True)
    text = body.inner_text()
    assert "4 of 5 graded attempts left today" in text
    full = points(ANSWERED)
    answered = page.locator("h2", has_text=re.compile(rf"^{ANSWERED}\b")).first.inner_text()
    assert f"{full:g} / {full:g}" in answered, answered
    unanswered = page.locator("h2", has_text=re.compile(rf"^{UNANSWERED}\b")).first.inner_text()
    assert f"0 / {points(UNANSWERED):g}" in unanswered, unanswered
    # the statement of the policy the student read in the notebook's first cell
    first = next(c for c in json.loads(saved)["cells"] if c["cell_type"] == "markdown")
    assert "**5 graded attempts per notebook per day**" in "".join(first["source"])
