"""The grader's vocabulary: plain dataclasses and enums, shared by every stage.

Data flows one way through the autograder::

    grade/ (read submissions, plan cells)  ->  isolation/ (run jobs)  ->  judging (verdicts,
    scores)  ->  outputs/ (csv, feedback, report, gradebook)

Every stage speaks in the types below. This module imports nothing of the package (and nothing
but the standard library), so any stage, and any test, can use it.
"""

from __future__ import annotations

import enum
import re
from dataclasses import dataclass, field
from typing import Any


class CellKind(str, enum.Enum):
    """What kind of graded cell an exercise (``Exercise.kind``) and a row of the gradebook are.

    The one spelling of kinds in Python; their values are the strings of the wire (the sandbox's
    jobs, the CSV files, the gradebook), converted at those edges only.
    """

    FUNCTION = "function"   #: a graded function, run on visible and hidden cases
    CHOICE = "choice"       #: a multiple-choice variable (a string of option letters)
    VALUE = "value"         #: a number item worked on the student's own numbers
    MANUAL = "manual"       #: a written answer, marked by hand

    @property
    def is_item(self) -> bool:
        """A choice or number item: judged on the literal its cell types, not on code run."""
        return self in (CellKind.CHOICE, CellKind.VALUE)


class OutcomeKind(str, enum.Enum):
    """What happened when the sandbox ran one case (observed, not yet judged)."""

    RETURNED = "returned"               #: returned plain data (``CaseOutcome.value``)
    RAISED = "raised"                   #: raised an exception
    TIMEOUT = "timeout"                 #: took longer than the case's time limit
    CRASHED = "crashed"                 #: the process died (signal, memory limit, os._exit)
    REJECTED = "rejected"               #: returned something that is not plain data, or too big
    REFERENCE_USED = "reference-used"   #: imported or called a course reference (absent)
    REJECTED_CODE = "rejected-code"     #: failed because the sandbox refused compiled code
    NOT_RUN = "not-run"                 #: never reached (the job's time ran out, too many crashes)


class Verdict(str, enum.Enum):
    """The judgement of one case."""

    PASS = "pass"
    WRONG_VALUE = "wrong-value"
    WRONG_SHAPE = "wrong-shape"         #: wrong shape, type or number of values
    UNANSWERED = "unanswered"           #: no answer given (a choice left empty or None)
    ERROR = "error"
    TIMEOUT = "timeout"
    REJECTED = "rejected"
    REFERENCE_USED = "reference-used"
    REJECTED_CODE = "rejected-code"     #: failed because the sandbox refused compiled code
    NOT_RUN = "not-run"                 #: never run (the time was used up; see its reason)


class Status(str, enum.Enum):
    """The status of one graded cell: the ``status`` column of ``grades.csv``."""

    OK = "ok"
    FAILED = "failed"
    UNANSWERED = "unanswered"
    ERROR = "error"
    TIMEOUT = "timeout"
    REJECTED_OUTPUT = "rejected-output"
    REFERENCE_USED = "reference-used"
    REJECTED_CODE = "rejected-code"
    MISSING = "missing"
    UNREADABLE = "unreadable"
    MANUAL = "manual"
    GRADER_ERROR = "grader-error"       #: an internal error of the grader: never the student's


#: What each status means for the student (the report's legend, the README's table).
STATUS_MEANING = {
    Status.OK: "every case passed",
    Status.FAILED: "the function ran but some answers were wrong (value, shape or type), or it "
                   "did not raise the error a bad input calls for",
    Status.UNANSWERED: "no answer was given: the cell was left as released, emptied, or sets the "
                       "answer to None",
    Status.ERROR: "the function raised an exception or crashed its process on some cases, or "
                  "the name is not defined after running the solution cells (e.g. its cell "
                  "does not compile)",
    Status.TIMEOUT: "the function took longer than the time limit on some cases",
    Status.REJECTED_OUTPUT: "the function returned something that is not plain numbers (an "
                            "object of its own class, an array subclass, a result too large)",
    Status.REFERENCE_USED: "the code imported or called course_lib, the course's reference "
                           "library, which graded code may not use (score 0)",
    Status.REJECTED_CODE: "graded code may use only NumPy and the standard library modules "
                          "listed in the notebook: the code tried to load compiled code or make "
                          "a system call that the grading sandbox refuses (the cases it broke "
                          "score 0)",
    Status.MISSING: "the notebook was not submitted (or was renamed), or its solution cell is "
                    "gone",
    Status.UNREADABLE: "the notebook file could not be read: invalid JSON, an old notebook "
                       "format, not a notebook, or far too large (more than 1 MB of code, or "
                       "a solution cell of more than 100 kB: not run)",
    Status.MANUAL: "a written answer, marked by hand in the Formgrader (no automatic score)",
    Status.GRADER_ERROR: "the grader itself failed on this cell: the instructor must look into "
                         "it (the student is not to blame)",
}

#: When a test cell fails in several ways, its status names the most serious one.
SEVERITY = (Status.REFERENCE_USED, Status.REJECTED_CODE, Status.REJECTED_OUTPUT, Status.TIMEOUT, Status.ERROR,
            Status.FAILED, Status.UNANSWERED)

#: The cell status a failing verdict maps to.
VERDICT_STATUS = {
    Verdict.WRONG_VALUE: Status.FAILED, Verdict.WRONG_SHAPE: Status.FAILED,
    Verdict.UNANSWERED: Status.UNANSWERED, Verdict.ERROR: Status.ERROR,
    Verdict.TIMEOUT: Status.TIMEOUT, Verdict.REJECTED: Status.REJECTED_OUTPUT,
    Verdict.REFERENCE_USED: Status.REFERENCE_USED, Verdict.NOT_RUN: Status.ERROR,
    Verdict.REJECTED_CODE: Status.REJECTED_CODE,
}

#: How a failing verdict reads in a summary ("3 wrong value, 1 timed out").
VERDICT_WORDS = {
    Verdict.PASS: "passed",
    Verdict.WRONG_VALUE: "wrong value", Verdict.WRONG_SHAPE: "wrong shape or type",
    Verdict.UNANSWERED: "no answer", Verdict.ERROR: "raised an error",
    Verdict.TIMEOUT: "timed out", Verdict.REJECTED: "returned something that is not plain numbers",
    Verdict.REFERENCE_USED: "used the reference", Verdict.NOT_RUN: "not run",
    Verdict.REJECTED_CODE: "refused by the sandbox (compiled code)",
}


@dataclass
class ValueSummary:
    """A large array as the grader keeps it after judging: its shape, dtype and first rows."""

    shape: tuple
    dtype: str
    head: Any                       #: a small ``np.ndarray`` (the first rows)


@dataclass
class CaseOutcome:
    """What the sandbox observed for one case (no verdict yet)."""

    index: int
    kind: OutcomeKind
    value: Any = None               #: the decoded plain data, for ``RETURNED``
    error_type: str = ""            #: the exception's class name, for ``RAISED``
    error_mro: tuple[str, ...] = ()  #: ``module.qualname`` of each class in its MRO
    message: str = ""               #: capped exception text, or why the case did not run
    seconds: float = 0.0
    printed: str = ""               #: stdout/stderr written while the case ran (capped)
    #: the message and error type came from the student's process (a worker's record, which
    #: student code may rewrite), not from the grader or the sandbox's supervisor
    said_by_student: bool = False


@dataclass
class NameRun:
    """Everything the sandbox reports for one graded name of one notebook."""

    name: str
    outcomes: list[CaseOutcome]     #: one per case, in the order of the job's cases
    defined: bool = True            #: the name existed after the solution cells ran
    load_notes: list[str] = field(default_factory=list)  #: cells that failed, with why
    printed: str = ""               #: output of the solution cells themselves (capped)
    launches: int = 1               #: processes started for this name (restarts after crashes)
    seconds: float = 0.0


@dataclass
class CaseRecord:
    """One judged case, as the feedback shows it."""

    index: int
    label: str
    visible: bool
    verdict: Verdict
    reason: str = ""
    args: tuple = ()
    kwargs: dict = field(default_factory=dict)
    expected: Any = None
    received: Any = None
    raises: str = ""                #: the exception a bad input must raise, by name
    printed: str = ""
    #: the returned value is kept (False: it was not of the expected answer's type and shape,
    #: so nothing of it is shown)
    shown: bool = True


@dataclass(frozen=True)
class CellVerdict:
    """The judgement of one graded cell (``judging.judge_cell``): its score, status and message
    (with its notes), the notes themselves, and whose answer a wrong item fits."""

    score: float
    status: Status
    message: str
    notes: tuple[str, ...] = ()
    fits_other: str = ""            #: another student whose numbers or letters a wrong item fits


@dataclass
class CellResult:
    """One graded cell of one student's notebook: a row of ``grades.csv`` and its feedback.

    Built by keyword (every field after ``student`` and ``notebook`` names what it holds)."""

    student: str
    notebook: str
    grade_id: str
    name: str
    score: float | None             #: None while a written answer waits for a marker
    max_score: float
    status: Status
    message: str
    kind: CellKind = CellKind.FUNCTION
    cases: list[CaseRecord] = field(default_factory=list)
    printed: str = ""               #: output of the solution cells (visible to the student)
    notes: list[str] = field(default_factory=list)
    seconds: float = 0.0
    code: str = ""                  #: the student's graded cell (or written answer)
    whole_notebook: bool = False    #: the status concerns the whole notebook (missing, unreadable)
    #: another student whose numbers or option letters this wrong answer fits (instructors' report;
    #: the student's feedback says so only once hidden tests are revealed)
    fits_other: str = ""
    #: what a choice or number item's cell typed (the literal it was judged on), else None: the
    #: report's distractor tables map it back to the canonical options
    answer: Any = None


class AnswerShape(str, enum.Enum):
    """What a student's graded cell is, read from its source before anything runs."""

    WRITTEN = "written"             #: an answer of the student's own
    UNTOUCHED = "untouched"         #: still the released stub (``raise NotImplementedError()``)
    EMPTY = "empty"                 #: no code at all (emptied, or only comments)
    NONE = "none"                   #: sets the name to None
    NOT_A_FUNCTION = "not-a-function"  #: binds a function's name to a number, a list, a string
    WRONG_ARITY = "wrong-arity"     #: a function that cannot take the exercise's arguments


@dataclass
class AnswerHint:
    """What the source of a graded cell says about its answer (see ``grade.planning``)."""

    shape: AnswerShape = AnswerShape.WRITTEN
    detail: str = ""                #: e.g. "a list", "takes 2 arguments"
    reference: str = ""             #: what of the course's reference the cell imports, if any


@dataclass
class SourceCell:
    """One cell of an instructor's source notebook."""

    index: int
    cell_type: str
    source: str
    meta: dict                      #: the cell's nbgrader metadata


@dataclass(frozen=True)
class GradedTest:
    """An automatically graded exercise of a source notebook: the name the student defines, the
    grade_id of its test cell and its points. Unpacks as ``name, test_id, points``."""

    name: str
    test_id: str
    points: float

    def __iter__(self):
        return iter((self.name, self.test_id, self.points))


@dataclass
class SourceNotebook:
    """What the grader takes from the instructor's notebook (never from a submission)."""

    name: str
    path: Any                       #: a ``pathlib.Path``
    nb: dict
    setup_source: str
    cells: list[SourceCell]
    solution_ids: list[str]         #: grade_ids of code solution cells, in order
    graded: list[GradedTest]        #: the auto-graded tests, in order (tuples are converted)
    manual: list[tuple[str, float]]        #: (grade_id, points) of manually graded answers

    def __post_init__(self):
        self.graded = [g if isinstance(g, GradedTest) else GradedTest(*g) for g in self.graded]

    def cell(self, grade_id: str) -> SourceCell | None:
        """The source cell whose grade_id is ``grade_id``, or None."""
        return next((c for c in self.cells if c.meta.get("grade_id") == grade_id), None)


@dataclass
class Submission:
    """One student's notebook as read by the grader, and which of its cells were graded."""

    student: str
    notebook: str
    path: Any                       #: a ``pathlib.Path``
    status: Status = Status.OK      #: OK, MISSING or UNREADABLE
    message: str = ""
    nb: dict | None = None
    cells: list[dict] = field(default_factory=list)  #: index, cell_type, source, grade_id, raw
    notes: list[str] = field(default_factory=list)
    #: graded name -> index (in ``cells``) of the cell that was graded for it, when found by its
    #: definition because its nbgrader metadata was gone
    found_by_name: dict[str, int] = field(default_factory=dict)


@dataclass
class Batch:
    """The outcome of a grading run: what every output is written from."""

    results: list[CellResult]                       #: one per (student, notebook, graded cell)
    submissions: dict[tuple[str, str], Submission]  #: (student, notebook) -> what was read
    students: list[str]


CSV_COLUMNS = ("student", "notebook", "grade_id", "score", "max_score", "status", "message")


def format_score(x: float) -> str:
    """A score as written to ``grades.csv``: at most six decimals, no trailing zeros."""
    text = f"{float(x):.6f}".rstrip("0").rstrip(".")
    return text if text not in ("", "-0") else "0"


#: control characters (C0 but tab and newline, DEL, C1): a student's exception message with
#: terminal colour codes drew a fake green "[ok] all cases passed" after the real verdict
_CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f-\x9f]")


def printable(text: str) -> str:
    """``text`` with every control character shown as its ``\\x..`` escape."""
    return _CONTROL.sub(lambda m: f"\\x{ord(m.group()):02x}", text)


def csv_row(r: CellResult) -> dict[str, str]:
    """The ``grades.csv`` row of a result."""
    return {"student": r.student, "notebook": r.notebook, "grade_id": r.grade_id,
            "score": "" if r.score is None else format_score(r.score),
            "max_score": format_score(r.max_score), "status": Status(r.status).value,
            "message": printable(r.message)}
