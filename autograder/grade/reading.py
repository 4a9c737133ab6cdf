"""Reading submissions without trusting them: every failure becomes a status and a sentence.

``SUBMITTED/<student>/tripos2006/<notebook>.ipynb``: a missing or misnamed file is ``missing``
(with the names that were found instead), invalid JSON, an old nbformat, a binary file, a
symbolic link or a huge file is ``unreadable``; malformed cells are skipped with a note.
"""

from __future__ import annotations

import difflib
import json
import os
import re
import stat
import sys
from pathlib import Path

from ..cells import join_source
from ..course import ASSIGNMENT
from ..model import Status, Submission

MAX_NOTEBOOK_MB = 25.0
#: Characters of code (all code cells together) a notebook may hold: an answer needs far less,
#: and the grader's parser costs some 600 bytes of memory per character it reads.
MAX_NOTEBOOK_CODE = 1_000_000
#: Cells a notebook may hold: a released notebook has under a hundred; a few hundred empty cells
#: cost nothing, but hundreds of thousands (still small on disk) would stall the whole batch
#: while the grader reads and plans them, before any sandbox starts.
MAX_CELLS = 2_000
_LONE_SURROGATE = re.compile("[\ud800-\udfff]")
_STUDENT_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._@+-]{0,127}$")


class _Unreadable(Exception):
    """Why a notebook file cannot be graded (internal to this module)."""


def discover_students(submitted: Path) -> list[str]:
    """Student ids: the folders of ``SUBMITTED`` (hidden and oddly named entries skipped)."""
    students = []
    for p in sorted(Path(submitted).iterdir()):
        if p.name.startswith(".") or not p.is_dir() or p.is_symlink():
            continue
        if not _STUDENT_RE.match(p.name):
            print(f"warning: skipping {p.name!r}: not a valid student id", file=sys.stderr)
            continue
        students.append(p.name)
    return students


def read_submission(folder: Path, student: str, notebook: str,
                    max_mb: float = MAX_NOTEBOOK_MB) -> Submission:
    """Read ``folder/<notebook>.ipynb`` without trusting it; never raises."""
    path = Path(folder) / f"{notebook}.ipynb"
    sub = Submission(student, notebook, path)
    try:
        data = _read_bytes(Path(folder), path, sub, max_mb)
        if data is None:
            return sub
        nb = _parse(data)
    except _Unreadable as why:
        sub.status = Status.UNREADABLE
        sub.message = f"{notebook}.ipynb could not be graded: {why}"
        return sub
    sub.nb, sub.cells = nb, _cells(nb, sub.notes)
    code = sum(len(c["source"]) for c in sub.cells if c["cell_type"] == "code")
    if code > MAX_NOTEBOOK_CODE:
        sub.status = Status.UNREADABLE
        sub.message = (f"{notebook}.ipynb could not be graded: its code cells hold "
                       f"{code / 1e6:.1f} MB of code, far more than the answers need (at most "
                       f"{MAX_NOTEBOOK_CODE / 1e6:g} MB); remove the generated code and resubmit")
    return sub


def _read_bytes(folder: Path, path: Path, sub: Submission, max_mb: float) -> bytes | None:
    """The file's bytes; None (with ``sub`` marked missing) when there is no such file."""
    if folder.is_symlink():  # e.g. a link to another student's folder: nothing of theirs
        raise _Unreadable(f"the {folder.name} folder of the submission is a symbolic link, not "
                          "a folder of files")
    if not folder.is_dir():
        sub.status, sub.message = Status.MISSING, (
            f"no {sub.notebook}.ipynb was submitted (there is no {ASSIGNMENT} folder in your "
            "submission)")
        return None
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        sub.status, sub.message = Status.MISSING, _missing_message(folder, sub.notebook)
        return None
    except OSError as exc:
        raise _Unreadable(f"it could not be opened ({exc.strerror})") from None
    if stat.S_ISLNK(st.st_mode):
        raise _Unreadable("it is a symbolic link, not a notebook file")
    if not stat.S_ISREG(st.st_mode):
        raise _Unreadable("it is not a regular file")
    if st.st_size > max_mb * 2**20:
        raise _Unreadable(f"the file is {st.st_size / 2**20:.0f} MB, far larger than a notebook "
                          "should be (huge outputs?): clear all outputs (Edit > Clear Outputs of "
                          "All Cells), save and resubmit")
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW)
        with os.fdopen(fd, "rb") as f:
            return f.read(int(max_mb * 2**20) + 1)
    except OSError as exc:
        raise _Unreadable(f"it could not be read ({exc.strerror})") from None


def _parse(data: bytes) -> dict:
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise _Unreadable("it is not a text file (not UTF-8)") from None
    try:
        nb = json.loads(text)
    except RecursionError:
        raise _Unreadable("its JSON is nested too deeply to be a notebook") from None
    except ValueError as exc:
        where = f" (line {exc.lineno}, column {exc.colno})" if hasattr(exc, "lineno") else ""
        raise _Unreadable(f"it is not valid notebook JSON{where}: was it edited in a text editor "
                          "or cut short? Restore it from a checkpoint or the released version "
                          "and resubmit") from None
    if not isinstance(nb, dict):
        raise _Unreadable("it is JSON but not a notebook")
    major = nb.get("nbformat")
    if "worksheets" in nb or (type(major) is int and major < 4):
        raise _Unreadable(f"it is saved in an old notebook format (nbformat {major}); open it in "
                          "JupyterLab, save it (nbformat 4) and resubmit")
    if type(major) is not int or major > 4 or not isinstance(nb.get("cells"), list):
        raise _Unreadable("it is not a Jupyter notebook in format 4 (no list of cells)")
    if len(nb["cells"]) > MAX_CELLS:
        raise _Unreadable(f"it holds {len(nb['cells']):,} cells, far more than an answered notebook "
                          f"needs (at most {MAX_CELLS:,}); delete the added cells and resubmit")
    return sanitise(nb) if re.search(r"\\u[dD][89a-fA-F]", text) else nb


def sanitise(data):
    """``data`` (parsed JSON) with every lone surrogate in its strings replaced by U+FFFD.

    JSON may spell a lone surrogate (``"\\udcff"``), which no UTF-8 file can hold: left in, it
    would stop every page and notebook the grader writes. Walks without recursion.
    """
    def clean(v):
        return _LONE_SURROGATE.sub("\ufffd", v) if isinstance(v, str) else v

    data = clean(data)
    stack = [data] if isinstance(data, (dict, list)) else []
    while stack:
        node = stack.pop()
        if isinstance(node, dict):
            for k in list(node):
                v = node.pop(k)
                node[clean(k)] = clean(v)
        else:
            node[:] = [clean(v) for v in node]
        stack += [v for v in (node.values() if isinstance(node, dict) else node)
                  if isinstance(v, (dict, list))]
    return data


def _cells(nb: dict, notes: list[str]) -> list[dict]:
    """The notebook's cells as ``{index, cell_type, source, grade_id, raw}``; bad ones noted."""
    cells = []
    for i, c in enumerate(nb["cells"]):
        if not isinstance(c, dict) or not isinstance(c.get("cell_type"), str):
            notes.append(f"cell {i} is malformed and was ignored")
            continue
        src = c.get("source", "")
        if not isinstance(src, (str, list)) or (isinstance(src, list)
                                                and not all(isinstance(s, str) for s in src)):
            notes.append(f"cell {i} has no readable source and was ignored")
            continue
        meta = c.get("metadata") if isinstance(c.get("metadata"), dict) else {}
        nbg = meta.get("nbgrader") if isinstance(meta.get("nbgrader"), dict) else {}
        gid = nbg.get("grade_id") if isinstance(nbg.get("grade_id"), str) else None
        cells.append({"index": i, "cell_type": c["cell_type"], "source": join_source(src),
                      "grade_id": gid, "raw": c})
    return cells


def _missing_message(folder: Path, notebook: str) -> str:
    similar = _similar_files(folder, notebook)
    message = f"no {notebook}.ipynb was submitted"
    if similar:
        message += (f"; found {', '.join(repr(s) for s in similar)} instead: notebooks must "
                    "keep their original file name to be graded")
    return message


def _similar_files(folder: Path, notebook: str) -> list[str]:
    try:
        names = sorted(p.name for p in folder.iterdir() if p.suffix.lower() == ".ipynb")
    except OSError:
        return []
    stems = {n: Path(n).stem for n in names}
    want = notebook.lower()
    hits = [n for n, s in stems.items()
            if want in s.lower() or s.lower().replace(" ", "_").replace("-", "_") == want]
    close = set(difflib.get_close_matches(notebook, list(stems.values()), n=3, cutoff=0.7))
    hits += [n for n, s in stems.items() if s in close and n not in hits]
    return hits[:3]
