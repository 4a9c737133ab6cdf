"""The nbgrader course of 4F9: one assignment ``tripos2006`` holding the six exam notebooks.

Everything that drives nbgrader goes through this module, so the release command, the lab
launcher, the hardened grader and the tests all agree on one layout::

    <root>/nbgrader_config.py
    <root>/gradebook.db                      (default gradebook, ``sqlite:///<root>/gradebook.db``)
    <root>/source/tripos2006/qN_*.ipynb      (the instructor's notebooks, copied from notebooks/)
    <root>/release/tripos2006/qN_*.ipynb     (``nbgrader generate_assignment``: solutions stubbed,
                                              the grading service's policy in the first cell)
    <root>/grading_service.json              (the grading service's policy, optional)
    <root>/submitted/<student>/tripos2006/
    <root>/autograded/<student>/tripos2006/
    <root>/feedback/<student>/tripos2006/

nbgrader runs ``alembic`` as a subprocess, so every nbgrader call made here runs with the
virtual environment's ``bin/`` first on ``PATH`` (:func:`nbgrader_env`).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from course_lib.variants import ASSIGNMENT

from . import explanations, release_cache
from .service.policy import PARAGRAPH_MARK, load_policy, policy_paragraph

#: ``ASSIGNMENT``: the nbgrader assignment that holds all six question notebooks, named once in
#: ``course_lib.variants`` (each student's numbers are drawn from it, and that module ships to
#: students without ``autograder``).
#: The nbgrader course id.
COURSE_ID = "4f9"
#: The repository root (the folder holding ``notebooks/`` and ``autograder/``).
REPO_ROOT = Path(__file__).resolve().parent.parent
#: The instructor's (source) notebooks, as committed.
NOTEBOOKS_DIR = REPO_ROOT / "notebooks"
#: The default course root used by ``make lab`` / ``make instructor`` (git-ignored).
DEFAULT_COURSE_ROOT = REPO_ROOT / "course"

#: Per-cell execution timeout (s) for ``nbgrader autograde`` / ``validate``.
CELL_TIMEOUT = 120
#: What replaces a solution in the student version; the release tests rely on the exception type.
CODE_STUB = "# YOUR CODE HERE\nraise NotImplementedError()"
TEXT_STUB = "YOUR ANSWER HERE"
#: stderr lines that must not zero a test cell (nbgrader scores a cell with any stderr as 0).
IGNORE_STDERR = r"Matplotlib is building the font cache"

_STAMP = f".{ASSIGNMENT}-release.json"
#: The root the release cache's key is computed for: what nbgrader makes does not depend on it.
_ANY_ROOT = Path("/course-root")


def source_notebooks(notebooks_dir: Path | None = None) -> list[Path]:
    """The question notebooks ``q1_*.ipynb`` … ``q6_*.ipynb`` that exist, in question order."""
    folder = Path(notebooks_dir) if notebooks_dir is not None else NOTEBOOKS_DIR
    if not folder.is_dir():
        return []
    return sorted(p for p in folder.glob("q[0-9]*_*.ipynb") if p.is_file())


def nbgrader_env(base: dict | None = None) -> dict:
    """A copy of the environment with this interpreter's ``bin/`` first on ``PATH``.

    nbgrader shells out to ``alembic`` and Jupyter resolves the ``python3`` kernel through
    ``PATH``: both must come from the same virtual environment as this interpreter.
    """
    env = dict(os.environ if base is None else base)
    bindir = str(Path(sys.executable).parent)
    parts = [p for p in env.get("PATH", "").split(os.pathsep) if p and p != bindir]
    env["PATH"] = os.pathsep.join([bindir, *parts])
    env.setdefault("MPLBACKEND", "Agg")
    env.setdefault("PYTHONIOENCODING", "utf-8")
    return env


def use_this_environment() -> None:
    """Put this interpreter's ``bin/`` first on this process's ``PATH``.

    nbgrader's ``Gradebook`` runs ``alembic`` as a subprocess from *this* process (not only from
    the nbgrader commands started through :func:`nbgrader_env`), so ``python -m autograder``
    must work even when the venv was not activated (``.venv/bin/python -m autograder ...``).
    """
    os.environ["PATH"] = nbgrader_env({"PATH": os.environ.get("PATH", "")})["PATH"]


use_this_environment()


def default_db_url(root: Path) -> str:
    """nbgrader's default gradebook for a course root: ``sqlite:///<root>/gradebook.db``."""
    return f"sqlite:///{Path(root).resolve() / 'gradebook.db'}"


def run_nbgrader(
    args: list[str],
    root: Path,
    db_url: str | None = None,
    *,
    timeout: float | None = None,
    check: bool = True,
) -> subprocess.CompletedProcess:
    """Run ``python -m nbgrader <args>`` in the course ``root``.

    ``--CourseDirectory.root`` (and ``--CourseDirectory.db_url`` when given) are appended, so the
    command works whatever the caller's working directory. Raises ``RuntimeError`` with the tail
    of nbgrader's output when it fails (nbgrader logs its errors on stderr but sometimes still
    exits 0 for a notebook it could not process; those runs carry ``[ERROR]`` lines and are
    treated as failures too).
    """
    root = Path(root).resolve()
    cmd = [sys.executable, "-m", "nbgrader", *map(str, args), f"--CourseDirectory.root={root}"]
    if db_url:
        cmd.append(f"--CourseDirectory.db_url={db_url}")
    proc = subprocess.run(
        cmd, cwd=root, env=nbgrader_env(), capture_output=True, text=True, timeout=timeout,
        check=False,
    )
    if check and (proc.returncode != 0 or "[ERROR]" in proc.stderr):
        tail = "\n".join((proc.stderr or proc.stdout).strip().splitlines()[-40:])
        raise RuntimeError(
            f"nbgrader {' '.join(map(str, args))} failed (exit {proc.returncode}) "
            f"in {root}:\n{tail}"
        )
    return proc


def config_text(db_url: str, exchange_root: Path | None = None) -> str:
    """The ``nbgrader_config.py`` of the course."""
    lines = [
        '"""nbgrader configuration of 4F9 (written by autograder/course.py; edits are lost)."""',
        "c = get_config()  # noqa: F821",
        "",
        f"c.CourseDirectory.course_id = {COURSE_ID!r}",
        f"c.CourseDirectory.db_url = {db_url!r}",
        f"# the assignment, {ASSIGNMENT!r}, is named on each nbgrader command line (setting",
        "# CourseDirectory.assignment_id here would clash with it)",
        "",
        "# the student versions: every solution becomes a stub that raises NotImplementedError",
        f"c.ClearSolutions.code_stub = {{'python': {CODE_STUB!r}}}",
        f"c.ClearSolutions.text_stub = {TEXT_STUB!r}",
        "",
        "# autograde / validate: generous per-cell timeout (nbgrader's own default is 30 s)",
        f"c.ExecutePreprocessor.timeout = {CELL_TIMEOUT}",
        f"c.Execute.timeout = {CELL_TIMEOUT}",
        "c.Execute.interrupt_on_timeout = True",
        "c.Execute.startup_timeout = 120",
        "",
        "# a test cell with any stderr output scores 0: ignore known harmless noise only",
        f"c.IgnorePattern.pattern = {IGNORE_STDERR!r}",
        "",
        "# keep notebook checkpoints and caches out of the release",
        "c.CourseDirectory.ignore = "
        "['.ipynb_checkpoints', '*.pyc', '__pycache__', 'feedback', '.*']",
        "",
        "# the Formgrader shows students' written answers as text, never as live HTML",
        "# (autograder/outputs/safe_markdown.py): markdown sanitised, raw cells not rendered",
        "c.HTMLExporter.filters = "
        "{'markdown2html': 'autograder.outputs.safe_markdown.markdown2html'}",
        "c.HTMLExporter.raw_mimetypes = []",
        "",
        "# nbgrader's own generate_feedback (typed by hand, or a Formgrader without the course's",
        "# guard, autograder/formgrader/) never copies the marker's rubric cells into a page",
        "c.GenerateFeedback.preprocessors = ["
        "'autograder.formgrader.withhold.WithholdRubrics', "
        "'nbgrader.preprocessors.GetGrades', "
        "'nbconvert.preprocessors.CSSHTMLHeaderPreprocessor']",
    ]
    if exchange_root is not None:
        lines += ["", f"c.Exchange.root = {str(exchange_root)!r}"]
    return "\n".join(lines) + "\n"


#: The students' nbgrader configuration for this machine's exchange, relative to the course root.
STUDENT_CONFIG = Path("for-students") / "nbgrader_config.py"


def student_config_text(exchange_root: Path) -> str:
    """The ``nbgrader_config.py`` a student needs for the course's local exchange.

    nbgrader's ``fetch_assignment``, ``submit`` and ``fetch_feedback`` look for the exchange at
    ``/usr/local/share/nbgrader/exchange`` unless told otherwise; off the hub the course's is
    ``<root>/exchange``. A student puts this file in ``~/.jupyter/`` (or the folder they run
    nbgrader in); the Validate button's cell timeout is the course's.
    """
    return "\n".join([
        '"""nbgrader configuration for 4F9 students on this machine (copy to ~/.jupyter/)."""',
        "c = get_config()  # noqa: F821",
        f"c.CourseDirectory.course_id = {COURSE_ID!r}",
        f"c.Exchange.root = {str(Path(exchange_root).resolve())!r}",
        f"c.Execute.timeout = {CELL_TIMEOUT}  # the Validate button",
    ]) + "\n"


@dataclass(frozen=True)
class CourseDir:
    """A prepared nbgrader course root (see the module docstring for its layout)."""

    root: Path
    source_dir: Path
    release_dir: Path
    db_url: str

    def submitted_dir(self, student: str) -> Path:
        return self.root / "submitted" / student / ASSIGNMENT

    def autograded_dir(self, student: str) -> Path:
        return self.root / "autograded" / student / ASSIGNMENT

    def feedback_dir(self, student: str) -> Path:
        return self.root / "feedback" / student / ASSIGNMENT

    def release_notebooks(self) -> list[Path]:
        return sorted(self.release_dir.glob("*.ipynb"))

    def nbgrader(self, args: list[str], **kwargs) -> subprocess.CompletedProcess:
        """:func:`run_nbgrader` in this course."""
        return run_nbgrader(args, self.root, self.db_url, **kwargs)

    def gradebook(self):
        """An ``nbgrader.api.Gradebook`` on this course's database (use as a context manager)."""
        from nbgrader.api import Gradebook

        return Gradebook(self.db_url, course_id=COURSE_ID)


def _digest(paths: list[Path], extra: str) -> str:
    h = hashlib.sha256(extra.encode())
    for p in paths:
        h.update(p.name.encode())
        h.update(p.read_bytes())
    return h.hexdigest()


def prepare_course(
    root: Path,
    db_url: str | None = None,
    notebooks: list[Path] | None = None,
) -> CourseDir:
    """Create (or refresh) an nbgrader course in ``root`` with the assignment released.

    Copies the source notebooks into ``root/source/tripos2006/``, writes
    ``root/nbgrader_config.py``, registers the assignment in the gradebook and runs
    ``nbgrader generate_assignment tripos2006 --force``, then states the grading service's
    policy (``root/grading_service.json``, or the defaults) in each release notebook's first
    cell (:func:`state_policy`). Re-running with unchanged sources, configuration and policy
    skips nbgrader altogether (a stamp file records what was released). ``ValueError`` naming
    the policy file when it is bad.
    """
    root = Path(root).resolve()
    notebooks = [Path(p) for p in (notebooks if notebooks is not None else source_notebooks())]
    if not notebooks:
        raise FileNotFoundError(f"no source notebooks to release (looked in {NOTEBOOKS_DIR})")
    names = [p.name for p in notebooks]
    if len(set(names)) != len(names):
        raise ValueError(f"two source notebooks share a file name: {names}")
    db_url = db_url or default_db_url(root)
    course = CourseDir(
        root=root,
        source_dir=root / "source" / ASSIGNMENT,
        release_dir=root / "release" / ASSIGNMENT,
        db_url=db_url,
    )
    root.mkdir(parents=True, exist_ok=True)
    with file_lock(root / ".prepare.lock"):
        return _prepare(course, notebooks, names)


@contextlib.contextmanager
def file_lock(path: Path):
    """An exclusive lock on the file ``path``, held for the ``with`` block (two commands
    preparing one course, two builds of the students' wheel, two service workers writing one
    gradebook: each waits for the other)."""
    try:
        import fcntl
    except ImportError:  # not POSIX: no lock
        yield
        return
    with open(path, "w") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


def _sqlite_file(db_url: str) -> Path | None:
    return Path(db_url[len("sqlite:///"):]) if db_url.startswith("sqlite:///") else None


def _prepare(course: CourseDir, notebooks: list[Path], names: list[str]) -> CourseDir:
    root, db_url = course.root, course.db_url
    exchange = root / "exchange"
    config = config_text(db_url, exchange_root=exchange)
    # the policy in force is part of what is released: a changed policy file releases again
    policy = policy_paragraph(load_policy(root))
    digest = _digest(notebooks, config + policy)
    stamp = root / _STAMP
    expected = sorted(names)
    db_file = _sqlite_file(db_url)
    if (
        stamp.exists()
        and (root / "nbgrader_config.py").exists()
        and (root / STUDENT_CONFIG).exists()
        and (db_file is None or db_file.exists())
        and sorted(p.name for p in course.release_dir.glob("*.ipynb")) == expected
        and sorted(p.name for p in course.source_dir.glob("*.ipynb")) == expected
    ):
        try:
            if json.loads(stamp.read_text()).get("digest") == digest:
                return course
        except ValueError:
            pass

    exchange.mkdir(exist_ok=True)
    (root / "nbgrader_config.py").write_text(config)
    (root / STUDENT_CONFIG).parent.mkdir(exist_ok=True)
    (root / STUDENT_CONFIG).write_text(student_config_text(exchange))
    course.source_dir.mkdir(parents=True, exist_ok=True)
    for old in course.source_dir.glob("*.ipynb"):
        if old.name not in names:
            old.unlink()
    for nb in notebooks:
        shutil.copyfile(nb, course.source_dir / nb.name)

    # a fresh root (no gradebook, no release yet) may be served from the release cache
    fresh = (db_url == default_db_url(root) and not db_file.exists()
             and not course.release_dir.exists())
    cache_key = None
    if fresh and release_cache.cache_dir() is not None:
        cache_key = release_cache.key(notebooks, config_text(
            default_db_url(_ANY_ROOT), exchange_root=_ANY_ROOT / "exchange"))
    if not (cache_key and release_cache.restore(cache_key, course.release_dir, db_file,
                                                expected)):
        _generate(course, stamp)
        if cache_key:
            release_cache.store(cache_key, course.release_dir, db_file)
    for released_nb in course.release_dir.glob("*.ipynb"):
        state_policy(released_nb, policy)  # after the cache: each course states its own policy
    released = sorted(p.name for p in course.release_dir.glob("*.ipynb"))
    if released != expected:
        raise RuntimeError(f"generate_assignment released {released}, expected {expected}")
    released_hashes = {p.name: _sha(p) for p in course.release_dir.glob("*.ipynb")}
    stamp.write_text(
        json.dumps({"digest": digest, "notebooks": names, "release": released_hashes}, indent=1)
        + "\n"
    )
    return course


def state_policy(path: Path, paragraph: str) -> None:
    """End the first markdown cell of notebook ``path`` with ``paragraph``, the grading
    service's policy in words (:func:`autograder.service.policy.policy_paragraph`: attempts per
    day, what a page shows before the due date, which attempt counts), replacing an earlier
    statement rather than adding a second. That cell carries no nbgrader metadata, so no
    checksum changes; ``ValueError`` when the notebook has no markdown cell."""
    import nbformat

    nb = nbformat.read(str(path), as_version=4)
    cell = next((c for c in nb.cells if c.cell_type == "markdown"), None)
    if cell is None:
        raise ValueError(f"{Path(path).name}: no markdown cell to state the grading policy in")
    kept = cell.source.split(PARAGRAPH_MARK, 1)[0].rstrip()
    source = f"{kept}\n\n{paragraph}" if kept else paragraph
    if source != cell.source:
        cell.source = source
        nbformat.write(nb, str(path))


def _generate(course: CourseDir, stamp: Path) -> None:
    """Register the assignment and release it with ``nbgrader generate_assignment`` (a release
    folder a student edited is moved aside first), explanations stripped from the release."""
    from nbgrader.api import Gradebook

    with Gradebook(course.db_url, course_id=COURSE_ID) as gb:
        gb.update_or_create_assignment(ASSIGNMENT)
    if course.release_dir.exists():
        _backup_student_work(course, stamp)
        shutil.rmtree(course.release_dir, ignore_errors=True)
    run_nbgrader(["generate_assignment", ASSIGNMENT, "--force"], course.root, course.db_url)
    for released_nb in course.release_dir.glob("*.ipynb"):
        explanations.strip(released_nb)      # an item's explanation comes with the feedback


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _backup_student_work(course: CourseDir, stamp: Path) -> Path | None:
    """Move an edited release folder aside before regenerating it.

    ``make lab`` lets a student work in ``course/release/tripos2006``; when the sources change,
    the next release would overwrite that work, so a release folder whose notebooks differ from
    what was released last time is first moved to ``<root>/backup/tripos2006-<UTC time>/``.
    """
    try:
        released = json.loads(stamp.read_text()).get("release", {})
    except (OSError, ValueError):
        released = {}
    current = {p.name: _sha(p) for p in course.release_dir.glob("*.ipynb")}
    edited = [name for name, h in current.items() if released.get(name) != h]
    if not edited:
        return None
    dest = course.root / "backup" / f"{ASSIGNMENT}-{time.strftime('%Y%m%dT%H%M%SZ', time.gmtime())}"
    dest.parent.mkdir(parents=True, exist_ok=True)
    shutil.move(str(course.release_dir), str(dest))
    print(f"note: edited notebooks in {course.release_dir} ({', '.join(sorted(edited))}) "
          f"were moved to {dest} before releasing again", file=sys.stderr)
    return dest


__all__ = [
    "ASSIGNMENT", "COURSE_ID", "REPO_ROOT", "NOTEBOOKS_DIR", "DEFAULT_COURSE_ROOT", "CELL_TIMEOUT",
    "CODE_STUB", "TEXT_STUB", "CourseDir", "source_notebooks", "nbgrader_env", "default_db_url",
    "run_nbgrader", "config_text", "prepare_course", "STUDENT_CONFIG", "student_config_text",
]
