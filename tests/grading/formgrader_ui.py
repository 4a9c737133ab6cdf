"""Mark one written answer in nbgrader's Formgrader, in Debian's Chromium, as the README says.

``make instructor`` (here ``python -m autograder lab --role instructor`` on the test's course)
→ the Nbgrader menu → Formgrader → Manual Grading → tripos2006 → the notebook → Show All Names →
the student → type the score and the comment. Chromium and its flags are the browser tests' own
(``tests/browser/conftest.py``).
"""

from __future__ import annotations

import importlib.util
import re
import secrets
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from contextlib import contextmanager
from pathlib import Path

from autograder.course import nbgrader_env

REPO = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location("browser_conftest",
                                               REPO / "tests" / "browser" / "conftest.py")
browser_conftest = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(browser_conftest)
CHROMIUM = browser_conftest.CHROMIUM


@contextmanager
def instructor_lab(course: Path, log_path: Path):
    """The instructor's JupyterLab on ``course``; yields ``(base_url, token)``."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    token = secrets.token_hex(12)
    log = open(log_path, "w")
    proc = subprocess.Popen(
        [sys.executable, "-m", "autograder", "lab", "--role", "instructor", "--port", str(port),
         "--token", token, "--no-browser", "--course-root", str(course)],
        cwd=REPO, env=nbgrader_env(), stdout=log, stderr=subprocess.STDOUT)
    base = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 180
        while True:
            try:
                with urllib.request.urlopen(f"{base}/api/status?token={token}", timeout=2):
                    break
            except OSError:
                if proc.poll() is not None or time.monotonic() > deadline:
                    raise RuntimeError(f"the instructor lab did not start:\n"
                                       f"{log_path.read_text()[-3000:]}") from None
                time.sleep(0.5)
        yield base, token
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
        log.close()


def mark(course: Path, student: str, notebook: str, grade_id: str, score: float, comment: str,
         artifacts: Path) -> str:
    """Score and comment one answer through the Formgrader; returns the grading page's text."""
    from playwright.sync_api import sync_playwright

    with instructor_lab(course, artifacts / "formgrader-lab.log") as (base, token), \
            sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=str(CHROMIUM),
                                     args=browser_conftest.CHROMIUM_ARGS)
        try:
            page = browser.new_context(viewport={"width": 1400, "height": 1000}).new_page()
            page.set_default_timeout(60_000)
            page.goto(f"{base}/lab?reset&token={token}")
            page.locator(".lm-MenuBar-itemLabel", has_text="Nbgrader").first.click()
            page.locator(".lm-Menu .lm-Menu-itemLabel").filter(
                has_text=re.compile("^Formgrader$")).click()
            grader = page.frame_locator("iframe").first
            # one page after the other: a link of the page being left (the assignments page has
            # a "tripos2006" link too, to its source folder) must not be the one clicked
            for link, path in (("Manual Grading", "/formgrader/gradebook"),
                               ("tripos2006", "/formgrader/gradebook/tripos2006"),
                               (notebook, f"/formgrader/gradebook/tripos2006/{notebook}")):
                grader.get_by_role("link", name=link).click()
                page.wait_for_function(
                    "path => [...document.querySelectorAll('iframe')].some(f => f.contentWindow "
                    "&& ('/' + f.contentWindow.location.pathname.split('/').filter(Boolean)"
                    ".join('/')).endsWith(path) && f.contentDocument.readyState === 'complete')",
                    arg=path)
            grader.get_by_role("link", name=re.compile(r"^Submission #1$")).wait_for()
            grader.get_by_text("Show All Names").click()
            grader.get_by_role("link", name=student).first.click()
            grader.locator("textarea.comment").first.wait_for()
            submission = next(f for f in page.frames if "/formgrader/submissions/" in f.url)
            submission.wait_for_function("() => window.formgrader && formgrader.grades.loaded "
                                         "&& formgrader.comments.loaded")
            # the Formgrader saves each field on change (when it loses focus): one at a time
            for field, value, api in ((f"#{grade_id}-comment", comment, "/api/comment/"),
                                      (f"input.score#{grade_id}", f"{score:g}", "/api/grade/")):
                with page.expect_response(lambda r, api=api: api in r.url
                                          and r.request.method == "PUT" and r.ok):
                    grader.locator(field).fill(value)
                    grader.locator(field).press("Tab")
            page.screenshot(path=str(artifacts / "formgrader-marking.png"))
            return grader.locator("body").inner_text()
        finally:
            browser.close()


def mark_in_subprocess(course: Path, student: str, notebook: str, grade_id: str, score: float,
                       comment: str, artifacts: Path, timeout: float = 600) -> str:
    """:func:`mark` in a Python of its own.

    Playwright's sync API refuses to start inside a process where another sync Playwright (the
    browser tests' session-wide browser, on the same xdist worker) already runs an event loop.
    """
    import json

    args = json.dumps([str(course), student, notebook, grade_id, score, comment, str(artifacts)])
    out = subprocess.run([sys.executable, str(Path(__file__).resolve()), args], cwd=REPO,
                         env=nbgrader_env(), capture_output=True, text=True, timeout=timeout)
    if out.returncode != 0:
        raise RuntimeError(f"marking in the Formgrader failed:\n{out.stderr[-4000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


if __name__ == "__main__":
    import json

    course_, student_, notebook_, grade_id_, score_, comment_, artifacts_ = json.loads(sys.argv[1])
    text = mark(Path(course_), student_, notebook_, grade_id_, float(score_), comment_,
                Path(artifacts_))
    print(json.dumps(text))
