"""The Formgrader API calls the course answers itself (see the package docstring).

Each handler is a subclass of nbgrader's own API handler (same login, same XSRF check) and
answers in nbgrader's JSON shape, ``{"success": bool, "log": str, "error": str}``, so the
Formgrader's page shows the course's message in its usual dialog.
"""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path

from jupyter_server.utils import url_path_join
from nbgrader.server_extensions.formgrader.base import (BaseApiHandler, check_notebook_dir,
                                                        check_xsrf)
from nbgrader.server_extensions.formgrader.handlers import (ManageAssignmentsHandler,
                                                            ManageSubmissionsHandler,
                                                            SubmissionHandler)
from tornado import web

#: What replaces each refused button, in the words the instructor needs.
REFUSED = {
    "assign": (
        "In 4F9 the student version is made by the course's release, which checks it for "
        "leaks first: run `python -m autograder release` (docs/instructors.md, step 1). "
        "Nothing was done."),
    "autograde": (
        "In 4F9 submissions are graded outside the students' kernels: run `python -m "
        "autograder grade course/submitted --out grading/` (docs/instructors.md, step 4). "
        "Nothing was done."),
    "generate_feedback": (
        "In 4F9 feedback is written by `python -m autograder feedback --grading grading/` "
        "(docs/instructors.md, step 6): nbgrader's generate_feedback knows nothing of the "
        "course's grader (its pages would lack the hidden cases' results and the explanations). "
        "Nothing was done."),
}


def refusal(action: str, detail: str = "") -> dict:
    """nbgrader's result shape for a call the course does not let through."""
    text = REFUSED.get(action, detail) if not detail else detail
    return {"success": False, "log": f"[ERROR] {text}", "error": text}


def course_root(handler) -> Path:
    return Path(handler.coursedir.root).resolve()


class Refused(BaseApiHandler):
    """A button the course replaces by one of its commands."""

    def initialize(self, action: str):
        self.action = action

    @web.authenticated
    @check_xsrf
    @check_notebook_dir
    def post(self, *args):
        self.log.warning("4F9: refused the Formgrader's %s %s", self.action, args)
        self.write(json.dumps(refusal(self.action)))


class GuardedRelease(BaseApiHandler):
    """Release: nbgrader's own, after the course's leak check of the release notebooks."""

    @web.authenticated
    @check_xsrf
    @check_notebook_dir
    def post(self, assignment_id):
        from ..release import ReleaseLeak, ReleaseNotRunnable, check_release

        folder = course_root(self) / "release" / assignment_id
        notebooks = sorted(folder.glob("*.ipynb"))
        try:
            if not notebooks:
                raise ReleaseLeak(f"no release notebooks in {folder}: run `python -m "
                                  "autograder release` first")
            check_release(notebooks)
        except (ReleaseLeak, ReleaseNotRunnable, ValueError, OSError) as exc:
            self.write(json.dumps(refusal("release", f"Not released: {exc}")))
            return
        self.write(json.dumps(self.api.release_assignment(assignment_id)))


def foreign_pages(root: Path, assignment_id: str, student_id: str | None = None) -> list[str]:
    """Feedback pages that ``python -m autograder feedback`` did not write (or that changed
    since): ``student/notebook.html``, relative to ``root/feedback``."""
    from ..outputs.handback import MANIFEST

    feedback = root / "feedback"
    try:
        manifest = json.loads((feedback / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        manifest = {}
    pattern = f"{student_id or '*'}/{assignment_id}/*"
    out = []
    for path in sorted(feedback.glob(pattern)):
        if path.name in ("timestamp.txt", "submission_secret.txt") or path.is_dir():
            continue
        key = f"{path.parent.parent.name}/{path.stem}"
        digest = hashlib.sha256(path.read_bytes()).hexdigest() if path.is_file() else None
        if path.suffix != ".html" or manifest.get(key) != digest:
            out.append(f"{path.parent.parent.name}/{path.name}")
    return out


class GuardedReleaseFeedback(BaseApiHandler):
    """Release Feedback: nbgrader's own, for pages the course's hand-back wrote, only."""

    @web.authenticated
    @check_xsrf
    @check_notebook_dir
    def post(self, assignment_id, student_id=None):
        foreign = foreign_pages(course_root(self), assignment_id, student_id)
        if foreign:
            text = ("Not released: these feedback pages were not written by `python -m "
                    "autograder feedback` (nbgrader's generate_feedback, or edited since), and "
                    "may show a marker's rubric: " + ", ".join(foreign[:20])
                    + ". Run `python -m autograder feedback --grading grading/`, which "
                    "rewrites them and releases them.")
            self.write(json.dumps(refusal("release_feedback", text)))
            return
        self.write(json.dumps(self.api.release_feedback(assignment_id, student_id)))


#: The buttons the course refuses are hidden on nbgrader's pages, and a note says what to run.
PAGE_STYLE = ("<style>td.assign a, td.autograde a, td.generate-feedback a {display: none}"
              " .course-4f9 code {font-size: 1em}</style>")
PAGE_NOTE = (
    "<div class='alert alert-info course-4f9' role='note'><b>4F9:</b> the course's commands "
    "replace three of nbgrader's buttons (hidden here): the student version is made by "
    "<code>python -m autograder release</code>, submissions are graded by <code>python -m "
    "autograder grade course/submitted --out grading/</code>, and feedback is written and "
    "released by <code>python -m autograder feedback --grading grading/</code> (nbgrader's "
    "would hand the marker's rubric to students). Release, Collect and Release Feedback are "
    "nbgrader's, behind the course's checks.</div>")


def with_course_note(page: str) -> str:
    """nbgrader's page with the course's style in its head and its note above the content."""
    page = page.replace("</head>", PAGE_STYLE + "</head>", 1)
    found = [i for i in (page.find('<div class="panel-group"'), page.find("<table")) if i >= 0]
    at = min(found) if found else (page.find("<body>") + len("<body>") if "<body>" in page else 0)
    return page[:at] + PAGE_NOTE + page[at:]


class CourseManageAssignments(ManageAssignmentsHandler):
    """nbgrader's Manage Assignments page with the course's note, its refused buttons hidden."""

    def render(self, name, **ns):
        return with_course_note(super().render(name, **ns))


class CourseManageSubmissions(ManageSubmissionsHandler):
    """nbgrader's Manage Submissions page with the course's note, Autograde and Generate
    Feedback hidden."""

    def render(self, name, **ns):
        return with_course_note(super().render(name, **ns))


#: Debian's MathJax 2 (``libjs-mathjax``, ``make mathjax-deps``): the version nbconvert's
#: templates are written for, served by the Formgrader itself instead of from a CDN.
MATHJAX_DIR = Path("/usr/share/javascript/mathjax")
MATHJAX_URL = "/formgrader/course-mathjax/"
_CDN_MATHJAX = re.compile(r"https://cdnjs\.cloudflare\.com/ajax/libs/mathjax/[^/\"']+/"
                          r"(?:latest|MathJax)\.js")


def local_mathjax(page: str, base_url: str) -> str:
    """``page`` loading MathJax from this server when Debian's MathJax is installed (the
    marker's browser may have no network, and a CDN sees every page a marker opens)."""
    if not (MATHJAX_DIR / "MathJax.js").is_file():
        return page
    local = url_path_join(base_url or "/", MATHJAX_URL.lstrip("/"), "MathJax.js")
    return _CDN_MATHJAX.sub(local, page)


class CourseSubmission(SubmissionHandler):
    """nbgrader's submission page (the marker's), with MathJax served locally."""

    def write(self, chunk):
        if isinstance(chunk, str):
            chunk = local_mathjax(chunk, self.base_url)
        return super().write(chunk)


#: (URL under the server's base URL, handler, its arguments): nbgrader's own URLs.
ROUTES = [
    (r"/formgrader/manage_assignments/?", CourseManageAssignments, {}),
    (r"/formgrader/manage_submissions/([^/]+)/?", CourseManageSubmissions, {}),
    (r"/formgrader/submissions/([^/]+)/?", CourseSubmission, {}),
    (MATHJAX_URL + "(.*)", web.StaticFileHandler, {"path": str(MATHJAX_DIR)}),
    (r"/formgrader/api/assignment/([^/]+)/assign", Refused, {"action": "assign"}),
    (r"/formgrader/api/assignment/([^/]+)/release", GuardedRelease, {}),
    (r"/formgrader/api/assignment/([^/]+)/generate_feedback", Refused,
     {"action": "generate_feedback"}),
    (r"/formgrader/api/assignment/([^/]+)/([^/]+)/generate_feedback", Refused,
     {"action": "generate_feedback"}),
    (r"/formgrader/api/assignment/([^/]+)/release_feedback", GuardedReleaseFeedback, {}),
    (r"/formgrader/api/assignment/([^/]+)/([^/]+)/release_feedback", GuardedReleaseFeedback, {}),
    (r"/formgrader/api/submission/([^/]+)/([^/]+)/autograde", Refused, {"action": "autograde"}),
]


def install(webapp) -> None:
    """Put the course's handlers before every other rule of the server (nbgrader's included).

    Tornado tries its rules in order, and ``add_handlers`` inserts a new one just before the
    catch-all: the Formgrader's rule, added whenever its extension loads, would win over one
    added later. So the course's rule is moved to the very front.
    """
    base = webapp.settings.get("base_url", "/")
    rules = [(url_path_join(base, pattern.lstrip("/")), cls, kwargs)
             for pattern, cls, kwargs in ROUTES]
    webapp.add_handlers(".*$", rules)
    router = webapp.default_router
    ours = router.rules.pop(-2)          # add_handlers inserted it just before the catch-all
    router.rules.insert(0, ours)
