"""A term on the course's real JupyterHub (``deploy/``), end to end, in Chromium.

Two students log in (PAM), fetch ``tripos2006`` from the Assignments panel, answer in the
browser (Ana: the right multiple-choice letter and a written answer; Ben: a wrong letter),
validate and submit. The grader account collects (``nbgrader collect``), grades
(``python -m autograder grade``), the instructor marks Ana's written answer in the Formgrader
(the hub service ``/services/4f9/``, whose Generate Feedback the course's guard refuses), the
grader hands back (``python -m autograder feedback``) and each student fetches feedback in the
browser and reads their own marks. Ben can reach none of Ana's work: not through the
filesystem as his own Unix user, not through the hub's URLs.

Oracles: the score of a multiple-choice item is the source notebook's points when the letter
is the model answer's and 0 otherwise; the manual mark and comment are the ones typed here.
Screenshots of every step go to ``test-artifacts/deploy/``.
"""

from __future__ import annotations

import concurrent.futures
import html
import json
import re
import stat
from pathlib import Path

import pytest
from hubtools import ARTIFACTS, CHROMIUM, INSTRUCTOR, STUDENTS

import hub  # deploy/hub.py

pytestmark = [pytest.mark.xdist_group("hub"), pytest.mark.slow, pytest.mark.browser]

A, NB = "tripos2006", "q1_imaging"
ANA, BEN = STUDENTS
CHOICE, WRITTEN = "q1_item1", "q1a_answer"
ANA_TEXT = "Ana: a planar X-ray sums the attenuation along each ray from source to film."
MARK, COMMENT = 4.0, "Ana: the line integral is right; say what CT adds."
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]


def _source_cell(gid: str) -> dict:
    nb = json.loads((hub.REPO / "notebooks" / f"{NB}.ipynb").read_text(encoding="utf-8"))
    return next(c for c in nb["cells"] if c["metadata"].get("nbgrader", {}).get("grade_id") == gid)


def _right_letter(user: str) -> str:
    """The key of the item as ``user`` sees its options (each student has their own order:
    ``course_lib.variants``; on the hub the id is the login)."""
    from autograder.exercises import REGISTRY

    return REGISTRY[CHOICE].key_for(user)


def _points(gid: str) -> float:
    return float(_source_cell(gid)["metadata"]["nbgrader"]["points"])


def _shot(page, name: str) -> None:
    page.screenshot(path=str(ARTIFACTS / f"{name}.png"))


def _login(browser, url: str, user: str, password: str):
    """A browser context of its own, logged in through the hub's login form (PAM)."""
    page = browser.new_context(viewport={"width": 1400, "height": 1000}).new_page()
    page.set_default_timeout(60_000)
    page.goto(f"{url}/hub/login")
    page.fill("#username_input", user)
    page.fill("#password_input", password)
    page.click("#login_submit")
    page.wait_for_url(re.compile(rf"/user/{user}/lab"), timeout=240_000)
    page.locator("#jp-main-dock-panel").wait_for()
    return page


def _assignments(page):
    """The Assignments panel (nbgrader's assignment list), refreshed."""
    tab = page.locator(".lm-TabBar-tab", has_text="Assignments")
    if tab.count() == 0:
        page.locator(".lm-MenuBar-itemLabel", has_text="Nbgrader").first.click()
        page.locator('li[data-command="nbgrader:open-assignment-list"]').click()
    else:
        tab.first.click()
        page.locator("#refresh_assignments_list").click()
    page.locator("#released_assignments_list").wait_for()


def _rows(page, which: str):
    page.locator(f"#{which}_assignments_list_loading").wait_for(state="hidden")
    return page.locator(f"#{which}_assignments_list > .list_item", has_text=A)


def _fetch(page, user: str) -> None:
    _assignments(page)
    _rows(page, "released").first.locator(".item_status button").click()
    _rows(page, "fetched").first.wait_for()
    _shot(page, f"01-{user}-fetched")


def _fill(page, cell, text: str) -> None:
    cell.scroll_into_view_if_needed()
    cell.locator(".cm-content").click()
    page.keyboard.press("Control+a")
    page.keyboard.insert_text(text)


def _cell_index(path: Path, pick) -> int:
    cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    return next(i for i, c in enumerate(cells) if pick(c))


def _answer(page, url: str, user: str, letter: str, written: str | None) -> None:
    """Open the notebook, type the answers into their cells, save.

    The answer cells are reached from the first stub with the keyboard (command mode, ``j``
    per cell, ``Enter`` to edit), counting cells in the fetched notebook: a rendered markdown
    cell is not reliably put in edit mode by a click."""
    saved = Path(hub.home_of(user)) / A / f"{NB}.ipynb"
    stub_at = _cell_index(saved, lambda c: "NotImplementedError" in "".join(c["source"]))
    answer_at = _cell_index(saved, lambda c: c["metadata"].get("nbgrader", {}).get("grade_id")
                            == WRITTEN)
    page.goto(f"{url}/user/{user}/lab/tree/{A}/{NB}.ipynb")
    nb = page.locator(".jp-NotebookPanel:visible .jp-Notebook")
    stub = nb.locator(".jp-CodeCell", has_text="NotImplementedError").first
    stub.wait_for()
    _fill(page, stub, f'{CHOICE} = "{letter}"')
    if written:
        page.keyboard.press("Escape")
        for _ in range(answer_at - stub_at):
            page.keyboard.press("j")
        page.keyboard.press("Enter")
        page.keyboard.press("Control+a")
        page.keyboard.insert_text(written)
        page.keyboard.press("Shift+Enter")
    page.keyboard.press("Control+s")
    for _ in range(120):
        text = saved.read_text(encoding="utf-8")
        if f'{CHOICE} = \\"{letter}\\"' in text and (not written or written in text):
            break
        page.wait_for_timeout(500)
    else:
        pytest.fail(f"{user}'s answers never reached {saved}")
    _shot(page, f"02-{user}-answered")


def _validate(page, user: str) -> str:
    """The notebook toolbar's Validate: the dialog's text."""
    page.locator(".jp-NotebookPanel:visible .jp-Toolbar").get_by_text("Validate").click()
    dialog = page.locator(".jp-Dialog")
    dialog.wait_for(timeout=300_000)
    page.locator(".jp-Dialog .jp-Dialog-body").wait_for()
    page.wait_for_function("() => !document.querySelector('.jp-Dialog-body')"
                           ".innerText.includes('Validating')", timeout=300_000)
    _shot(page, f"03-{user}-validated")
    text = dialog.inner_text()
    page.keyboard.press("Escape")
    dialog.wait_for(state="hidden")
    return text


def _submit(page, user: str) -> None:
    _assignments(page)
    _rows(page, "fetched").first.locator('.item_status button:text("Submit")').click()
    _rows(page, "submitted").first.wait_for()
    _shot(page, f"04-{user}-submitted")


def _student_turn(browser, course_hub, user, letter, written):
    page = _login(browser, course_hub["url"], user, course_hub["passwords"][user])
    _fetch(page, user)
    _answer(page, course_hub["url"], user, letter, written)
    # Validate ran the notebook in the student's server: the cells left unanswered fail, the
    # visible check of the one answered passes (a letter of the right form, right or wrong)
    text = _validate(page, user)
    assert "NameError" in text and f"choice_letters({CHOICE}," not in text, text[:2000]
    _submit(page, user)
    return page


def _inbound(settings) -> Path:
    return Path(settings.paths["exchange"]) / settings.course_id / "inbound"


def _check_privacy_on_disk(settings) -> None:
    """Ben, as his own Unix user, can neither list the inbound nor open Ana's submission."""
    inbound = _inbound(settings)
    theirs = [p for p in inbound.iterdir() if p.name.startswith(f"{ANA}+{A}+")]
    assert len(theirs) == 1, list(inbound.iterdir())
    ana_nb = theirs[0] / f"{NB}.ipynb"
    assert ANA_TEXT in ana_nb.read_text(encoding="utf-8")
    for path in (ana_nb, *ana_nb.parent.iterdir(), ana_nb.parent):
        assert stat.S_IMODE(path.stat().st_mode) & 0o007 == 0, (path, oct(path.stat().st_mode))
    for cmd in (["ls", inbound], ["ls", theirs[0]], ["cat", ana_nb],
                ["cat", Path(hub.home_of(ANA)) / A / f"{NB}.ipynb"]):
        proc = hub.as_user(BEN, cmd)
        assert proc.returncode != 0 and "Permission denied" in proc.stderr, (cmd, proc.stdout[:300])
        assert ANA_TEXT not in proc.stdout


def _check_privacy_through_the_hub(page, url: str) -> None:
    """Ben, logged in, asks the hub for Ana's notebook and for the Formgrader: refused."""
    for what, path in (("anas-notebook", f"/user/{ANA}/files/{A}/{NB}.ipynb"),
                       ("anas-contents-api", f"/user/{ANA}/api/contents/{A}/{NB}.ipynb"),
                       ("the-formgrader", "/services/4f9/formgrader")):
        resp = page.goto(f"{url}{path}")
        assert resp is not None and resp.status in (403, 404), (path, resp and resp.status)
        assert ANA_TEXT not in page.content()
        _shot(page, f"05-ben-refused-{what}")


def _grade(settings) -> None:
    """The grader account collects, root grades (each sandbox job a uid and a cgroup of its
    own), as the README's instructor section says."""
    python = Path(settings.paths["instructor_env"]) / "bin" / "python"
    hub.as_grader(settings, [python, "-m", "nbgrader", "collect", A])
    assert hub.run_grading(settings, ["grade", "submitted", "--out", "grading", "--jobs", "2"],
                           timeout=600) == 0


def _mark_in_the_formgrader(browser, course_hub) -> str:
    """The instructor opens the Formgrader service and marks Ana's written answer."""
    url = course_hub["url"]
    page = _login(browser, url, INSTRUCTOR, course_hub["passwords"][INSTRUCTOR])
    page.goto(f"{url}/services/4f9/lab")
    page.locator(".lm-MenuBar-itemLabel", has_text="Nbgrader").first.click()
    page.locator(".lm-Menu .lm-Menu-itemLabel").filter(has_text=re.compile("^Formgrader$")).click()
    grader = page.frame_locator("iframe").first
    for link in ("Manual Grading", A, NB):
        grader.get_by_role("link", name=link).click()
    grader.get_by_role("link", name=re.compile(r"^Submission #1$")).wait_for()
    grader.get_by_text("Show All Names").click()
    grader.get_by_role("link", name=ANA).first.click()
    grader.locator("textarea.comment").first.wait_for()
    submission = next(f for f in page.frames if "/formgrader/submissions/" in f.url)
    # the page defines formgrader before its grades and comments: a predicate that throws
    # fails the wait at once instead of retrying
    submission.wait_for_function("() => window.formgrader && formgrader.grades "
                                 "&& formgrader.grades.loaded && formgrader.comments "
                                 "&& formgrader.comments.loaded")
    for field, value, api in ((f"#{WRITTEN}-comment", COMMENT, "/api/comment/"),
                              (f"input.score#{WRITTEN}", f"{MARK:g}", "/api/grade/")):
        with page.expect_response(lambda r, api=api: api in r.url
                                  and r.request.method == "PUT" and r.ok):
            grader.locator(field).fill(value)
            grader.locator(field).press("Tab")
    _shot(page, "06-instructor-marked")
    text = grader.locator("body").inner_text()
    _check_the_guard(page, url, course_hub["log"])
    return text


def _check_the_guard(page, url: str, log: Path) -> None:
    """The service loaded the course's guard: Manage Assignments' Generate Feedback (hidden by
    the guard, clicked by script as a marker's script could) names the course's command and
    does nothing."""
    page.goto(f"{url}/services/4f9/formgrader/manage_assignments")
    row = page.locator("tr", has=page.locator("td.name a", has_text=A))
    row.wait_for()
    button = row.locator("td.generate-feedback a").first
    button.wait_for(state="attached")
    assert button.is_hidden(), "the Generate Feedback button is shown"
    button.dispatch_event("click")
    modal = page.locator(".modal.in, .modal.show").last
    modal.wait_for(state="visible", timeout=120_000)
    said = modal.inner_text()
    _shot(page, "06-instructor-generate-feedback-refused")
    assert "python -m autograder feedback" in said and "Nothing was done" in said, said
    assert "through the course's guard" in log.read_text(errors="replace")


def _feedback_page(page, url: str, user: str) -> str:
    """The student fetches feedback in the Assignments panel and opens their page."""
    page.goto(f"{url}/user/{user}/lab")
    page.locator("#jp-main-dock-panel").wait_for()
    _assignments(page)
    _rows(page, "submitted").first.locator('.item_status button:text("Fetch Feedback")').click()
    fetched = Path(hub.home_of(user)) / A / "feedback"
    for _ in range(120):
        pages = sorted(fetched.glob(f"*/{NB}.html"))
        if pages:
            break
        page.wait_for_timeout(500)
    else:
        pytest.fail(f"no feedback reached {fetched}")
    _shot(page, f"07-{user}-fetched-feedback")
    rel = pages[-1].relative_to(hub.home_of(user))
    page.goto(f"{url}/user/{user}/files/{rel}")
    _shot(page, f"08-{user}-feedback")
    return html.unescape(page.locator("body").inner_text())


def _shoot_everything(browser) -> None:
    """A screenshot of every open page, for the failure's report."""
    for i, context in enumerate(browser.contexts):
        for j, page in enumerate(context.pages):
            try:
                page.screenshot(path=str(ARTIFACTS / f"failure-{i}-{j}.png"))
            except Exception:  # noqa: BLE001  (the page may be gone; the failure matters)
                pass


def _term(course_hub) -> None:
    from playwright.sync_api import sync_playwright

    settings, url = course_hub["settings"], course_hub["url"]
    letter = _right_letter(ANA)
    wrong = next(x for x in "abcd" if x != _right_letter(BEN))
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
        try:
            pages = {ANA: _student_turn(browser, course_hub, ANA, letter, ANA_TEXT),
                     BEN: _student_turn(browser, course_hub, BEN, wrong, None)}
            _check_privacy_on_disk(settings)
            _check_privacy_through_the_hub(pages[BEN], url)
            _grade(settings)
            marked = _mark_in_the_formgrader(browser, course_hub)
            assert ANA_TEXT in marked
            python = Path(settings.paths["instructor_env"]) / "bin" / "python"
            hub.as_grader(settings, [python, "-m", "autograder", "feedback", "--grading", "grading",
                                     "--course", settings.paths["course_dir"]])
            ana, ben = (_feedback_page(pages[u], url, u) for u in (ANA, BEN))
        except Exception:
            _shoot_everything(browser)
            raise
        finally:
            browser.close()
    # each page: the student's own marks, the marker's comment for Ana only
    choice, written = _points(f"test_{CHOICE}"), _points(WRITTEN)
    assert re.search(rf"{WRITTEN} \(written answer\)\s+{MARK:g} / {written:g}\s+"
                     rf"{re.escape(COMMENT)}", ana), ana[:3000]
    assert re.search(rf"test_{CHOICE}\s+{choice:g} / {choice:g}", ana), ana[:3000]
    assert re.search(rf"test_{CHOICE}\s+0 / {choice:g}", ben), ben[:3000]
    assert re.search(rf"{WRITTEN} \(written answer\)\s+0 / {written:g}", ben), ben[:3000]
    assert f"feedback for {ANA}" in ana and f"feedback for {BEN}" in ben
    assert COMMENT not in ben and ANA not in ben and ANA_TEXT not in ben
    _check_scores(settings, letter)


def _check_scores(settings, letter) -> None:
    """The gradebook: Ana's letter earns the item's points, Ben's none; Ana's mark is stored."""
    python = Path(settings.paths["instructor_env"]) / "bin" / "python"
    code = ("import json,sys; from nbgrader.api import Gradebook\n"
            "with Gradebook('sqlite:///gradebook.db', course_id='4f9') as gb:\n"
            f"  print(json.dumps({{s: [gb.find_grade(g, '{NB}', '{A}', s).score for g in "
            f"('test_{CHOICE}', '{WRITTEN}')] for s in sys.argv[1:]}}))")
    out = hub.as_grader(settings, [python, "-c", code, ANA, BEN]).stdout
    scores = json.loads(out.strip().splitlines()[-1])
    assert scores[ANA] == pytest.approx([_points(f"test_{CHOICE}"), MARK], abs=1e-9)
    assert scores[BEN][0] == pytest.approx(0.0, abs=1e-9)


def test_a_term_on_the_hub(course_hub):
    # Playwright's sync API refuses to start on a thread where another one runs (the browser
    # tests' session-wide Chromium may live on this xdist worker): drive it from a thread of its own
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        pool.submit(_term, course_hub).result()
