"""The OS-level grading sandbox (``autograder.isolation``) against the attacks that defeated
the Python-level one: each attack with the exact outcome kinds it must get, and the grader's
side checked (files unchanged, no process left, memory bounded, other jobs unaffected)."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from autograder.isolation import (CaseInput, IsolationUnavailable, Limits, Mode, NameJob,
                                  NotebookJob, probe, run_notebook)
from autograder.isolation import bwrap, child, identity
from autograder.model import OutcomeKind as K

pytestmark = pytest.mark.xdist_group("isolation")

REPO = Path(__file__).resolve().parents[2]
FAST = Limits(case_timeout=2.0, load_timeout=10.0)
SETUP = "import numpy as np\n"


@pytest.fixture(scope="module")
def mode():
    try:
        return probe()
    except IsolationUnavailable as exc:
        pytest.skip(str(exc))


def fn(name: str, source: str, cases=((),), cap: int = 1_000_000, kind: str = "function"):
    """A NameJob whose one cell is ``source``; ``cases`` are tuples of positional args."""
    return NameJob(name, kind, [(f"{name}-cell", textwrap.dedent(source))],
                   [CaseInput(tuple(a), {}, cap) for a in cases])


def run(mode, *names, limits=FAST, setup=SETUP, job_id="t"):
    return run_notebook(NotebookJob(job_id, setup, list(names)), limits, mode)


def kinds(name_run):
    return [o.kind for o in name_run.outcomes]


def sandbox_uids_alive() -> list[int]:
    """Pids of live processes with a sandbox uid (the range identity hands out)."""
    return [pid for uid in range(identity.UID_BASE, identity.UID_BASE + 16)
            for pid in identity.uid_processes(uid)]


# ------------------------------------------------------------------------------------------
# plain behaviour


def test_values_prints_notes_and_undefined_names(mode):
    values = fn("values", """
        def values(k):
            print("case", k)
            return [np.arange(3, dtype=np.int16), np.array([[1.5, -2.0]], dtype=">f8"),
                    np.array([True, False]), np.array([1 + 2j], dtype=np.complex64),
                    (None, True, 7, 2.5, 3 - 4j, "text"), {"k": np.uint8(200)}][k]
        """, cases=[(k,) for k in range(6)])
    choice = NameJob("answer", "choice", [("c1", "answer = None\n")], [CaseInput((), {})])
    broken = NameJob("later", "function",
                     [("b1", "undefined_name\n"), ("b2", "import sys\nsys.exit(3)\n"),
                      ("b3", "def later():\n    return 1\n")], [CaseInput((), {})])
    missing = fn("missing", "x = 1\n")
    runs = run(mode, values, choice, broken, missing)

    got = [o.value for o in runs["values"].outcomes]
    assert kinds(runs["values"]) == [K.RETURNED] * 6
    assert got[0].dtype == np.int16 and got[0].tolist() == [0, 1, 2]
    np.testing.assert_array_equal(got[1], [[1.5, -2.0]])
    assert got[2].dtype == np.bool_ and got[3].dtype == np.complex64
    assert got[3][0] == 1 + 2j
    assert got[4] == (None, True, 7, 2.5, 3 - 4j, "text")
    assert got[5] == {"k": 200}
    assert [o.printed for o in runs["values"].outcomes] == [f"case {k}\n" for k in range(6)]

    assert kinds(runs["answer"]) == [K.RETURNED] and runs["answer"].outcomes[0].value is None
    notes = runs["later"].load_notes
    assert notes[0].startswith("cell b1 raised NameError") and "sys.exit" in notes[1]
    assert kinds(runs["later"]) == [K.RETURNED] and runs["later"].outcomes[0].value == 1
    assert runs["missing"].defined is False and kinds(runs["missing"]) == [K.NOT_RUN]


def test_objects_that_are_not_plain_data_are_rejected(mode):
    odd = fn("odd", """
        class Foo:
            def __eq__(self, other):
                return True
        def odd(k):
            return [Foo(), np.matrix([[1.0]]), np.array(["a"]), np.array([1], dtype=object),
                    {1: 2}, [[[[[[[[[[1]]]]]]]]]], {1, 2}][k]
        """, cases=[(k,) for k in range(7)])
    runs = run(mode, odd)["odd"]
    assert kinds(runs) == [K.REJECTED] * 7
    messages = [o.message for o in runs.outcomes]
    assert messages[0] == "returned a Foo, not plain numbers"
    assert messages[1] == "returned a matrix, not plain numbers"
    assert "dtype <U1" in messages[2] and "dtype object" in messages[3]
    assert "keys" in messages[4] and "deep" in messages[5] and "a set" in messages[6]


# ------------------------------------------------------------------------------------------
# files: nothing of the course, the grader or other students is there


ATTACK_FILES = """
import ctypes, glob, os

def attack(paths, out_dir):
    # raw memory writes: full Python power is assumed, nothing inside the process is a guard
    a = np.zeros(4)
    ctypes.memmove(a.__array_interface__["data"][0], ctypes.c_char_p(b"\\x01" * 32), 32)
    found = {"raw-write": bool(a.any())}
    for key, path in paths.items():
        try:
            with open(path, "rb") as f:
                found[key] = f.read(64).decode("latin-1")
        except OSError as exc:
            found[key] = type(exc).__name__
    try:
        os.symlink(paths["secret"], "/tmp/link")
        open("/tmp/link").read()
        found["symlink"] = "read"
    except OSError as exc:
        found["symlink"] = type(exc).__name__
    try:
        root = os.open("/", os.O_RDONLY)
        fd = os.open(paths["secret"].lstrip("/"), os.O_RDONLY, dir_fd=root)
        found["dir_fd"] = os.read(fd, 64).decode("latin-1")
    except OSError as exc:
        found["dir_fd"] = type(exc).__name__
    try:
        with open(os.path.join(out_dir, "planted.txt"), "w") as f:
            f.write("x")
        found["write"] = "written"
    except OSError as exc:
        found["write"] = type(exc).__name__
    found["glob"] = sorted(p for top in ("/sandbox", "/root", "/tmp", "/job")
                           for p in glob.glob(top + "/**/*", recursive=True)
                           if p.endswith((".ipynb", ".db")) or "autograder" in p
                           or ("course_lib" in p and p.endswith(".py")))
    found["root"] = sorted(os.listdir("/"))
    found["site"] = sorted(os.listdir("/sandbox/site"))
    return found
"""


def test_files_of_the_course_and_other_students_are_absent(mode, tmp_path):
    secret = tmp_path / "secret.txt"
    secret.write_text("the course secret")
    other = tmp_path / "students" / "bob" / "q1_imaging.ipynb"
    other.parent.mkdir(parents=True)
    other.write_text("bob's answers")
    out_dir = tmp_path / "outputs"
    out_dir.mkdir()
    notebook = sorted((REPO / "notebooks").glob("q*.ipynb"))[0]
    paths = {"notebook": str(notebook), "course_lib": str(REPO / "course_lib" / "shading.py"),
             "secret": str(secret), "other": str(other),
             "autograder": str(REPO / "autograder" / "isolation" / "runner.py"),
             "passwd": "/etc/shadow", "venv": str(Path(sys.prefix) / "pyvenv.cfg")}
    before = {p: Path(p).read_bytes() for p in (secret, other, notebook)}
    job = fn("attack", ATTACK_FILES, cases=[(paths, str(out_dir))])
    outcome = run(mode, job, limits=Limits(case_timeout=30.0))["attack"].outcomes[0]
    assert outcome.kind is K.RETURNED, outcome
    found = outcome.value

    assert found["raw-write"] is True
    for key in (*paths, "symlink", "dir_fd"):
        assert found[key] in ("FileNotFoundError", "PermissionError"), (key, found[key])
    assert found["write"] in ("FileNotFoundError", "PermissionError", "OSError")
    assert found["glob"] == ["/sandbox/site/course_lib/__init__.py",
                             "/sandbox/site/course_lib/marching_cubes.py"]
    assert set(found["root"]) <= {"bin", "dev", "job", "lib", "lib64", "proc", "root",
                                  "sandbox", "sbin", "tmp", "usr"}
    assert set(found["site"]) <= {"course_lib", "numpy", "numpy.libs"}
    assert {p: Path(p).read_bytes() for p in before} == before
    assert list(out_dir.iterdir()) == []


def test_identity_no_capabilities_and_distinct_uids(mode):
    probe_src = """
        import os, time
        def ident():
            time.sleep(1.0)
            status = dict(l.split(":\\t", 1) for l in open("/proc/self/status").read().splitlines())
            return (os.getuid(), os.getgid(), os.getgroups(), status["NoNewPrivs"].strip(),
                    int(status["CapEff"], 16), int(status["CapBnd"], 16), int(status["CapPrm"], 16))
        """
    results = {}

    def one(tag):
        results[tag] = run(mode, fn("ident", probe_src), job_id=tag)["ident"].outcomes[0]

    threads = [threading.Thread(target=one, args=(t,)) for t in ("a", "b")]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    (uid_a, gid_a, groups, nnp, cap_eff, cap_bnd, cap_prm), other = (
        results["a"].value, results["b"].value)
    assert uid_a != 0 and gid_a != 0 and uid_a != other[0] and groups == []
    if bwrap.privileged():
        assert identity.UID_BASE <= uid_a < identity.UID_BASE + identity.UID_COUNT
    assert nnp == "1" and cap_eff == 0 and cap_prm == 0 and cap_bnd == 0
