"""The course's guard on nbgrader's Formgrader: no click in it can hand a rubric to a student.

nbgrader's Formgrader puts nbgrader's own commands one click away (Manage Assignments:
Generate, Release, Collect, Generate Feedback, Release Feedback; Manage Submissions:
Autograde, Generate Feedback, Release Feedback). Two of them would undo what the course's
commands guarantee: ``generate_feedback`` writes pages from the autograded notebooks, where
each written answer is followed by its marker's rubric (:func:`~autograder.outputs.gradebook.
rubric_cell`), and ``autograde`` grades inside the student's kernel. So this Jupyter server
extension (switched on by ``python -m autograder lab --role instructor``) answers those API
calls itself, before nbgrader's handlers see them (:mod:`.handlers`):

- Generate (``assign``): refused; ``python -m autograder release`` checks the release first.
- Release: nbgrader's own, once the release notebooks pass the course's leak check.
- Collect, Unrelease: nbgrader's own (nothing of the instructors' copy moves).
- Autograde: refused; ``python -m autograder grade`` grades outside the students' kernels.
- Generate Feedback: refused; ``python -m autograder feedback`` writes pages with no rubric.
- Release Feedback: nbgrader's own, only when every page to release is one that
  ``python -m autograder feedback`` wrote (its digest in ``feedback/.handback.json``).

A hidden button could still be called by URL, so the guard is on the server, not the page.
And where this extension is not loaded (the command line, another server), the course's
``nbgrader_config.py`` makes nbgrader's ``generate_feedback`` drop the rubric cells
(:class:`.withhold.WithholdRubrics`).
"""

from __future__ import annotations

#: The module name to switch on in ``ServerApp.jpserver_extensions``.
EXTENSION = "autograder.formgrader"


def _jupyter_server_extension_points():
    return [{"module": EXTENSION}]


def _load_jupyter_server_extension(serverapp) -> None:
    from .handlers import install

    install(serverapp.web_app)
    serverapp.log.info("4F9: the Formgrader's generate/autograde/feedback buttons run through "
                       "the course's guard")
