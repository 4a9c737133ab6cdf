"""The OS-level grading sandbox (``autograder.isolation``) against the attacks that defeated
the Python-level one: each attack with the exact outcome kinds it must get, and the grader's
side checked (files unchanged, no process left, memory bounded, other jobs unaffected)."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import tempfile
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from autograder.isolation import (CaseInput, IsolationError, IsolationUnavailable, Limits, Mode,
                                  NameJob, NotebookJob, run_notebook)
from autograder.isolation import bwrap, cgroup, identity
from autograder.isolation.inside import wire
from autograder.model import OutcomeKind as K

pytestmark = pytest.mark.xdist_group("isolation")

REPO = Path(__file__).resolve().parents[2]
FAST = Limits(case_timeout=2.0, load_timeout=10.0)
SETUP = "import numpy as np\n"


def fn(name: str, source: str, cases=((),), cap: int = 1_000_000, kind: str = "function"):
    """A NameJob whose one cell is ``source``; ``cases`` are tuples of positional args."""
    return NameJob(name, kind, [(f"{name}-cell", textwrap.dedent(source))],
                   [CaseInput(tuple(a), {}, cap) for a in cases])


def run(mode, *names, limits=FAST, setup=SETUP, job_id="t"):
    return run_notebook(NotebookJob(job_id, setup, list(names)), limits, mode)


def kinds(name_run):
    return [o.kind for o in name_run.outcomes]


def processes_left(uid: int) -> list[int]:
    """Live processes of a finished job's ``uid``, checked while holding its lock (so another
    grading run on this machine cannot be using that uid meanwhile)."""
    if not bwrap.privileged():
        return []
    import fcntl

    fd = os.open(os.path.join(identity.LOCK_DIR, f"{uid}.lock"), os.O_RDWR)
    try:
        for _ in range(600):
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                return identity.uid_processes(uid)
            except BlockingIOError:   # reused already by another job: wait for its end
                time.sleep(0.1)
        raise AssertionError(f"uid {uid} stayed busy")
    finally:
        os.close(fd)


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
                    {1: 2}, [[[[[[[[[[1]]]]]]]]]], {1, 2}, 10 ** 5000][k]
        """, cases=[(k,) for k in range(8)])
    runs = run(mode, odd)["odd"]
    assert kinds(runs) == [K.REJECTED] * 8
    messages = [o.message for o in runs.outcomes]
    assert messages[0] == "returned a Foo, not plain numbers"
    assert messages[1] == "returned a matrix, not plain numbers"
    assert "dtype <U1" in messages[2] and "dtype object" in messages[3]
    assert "keys" in messages[4] and "deep" in messages[5] and "a set" in messages[6]
    assert "bits" in messages[7]


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
                             "/sandbox/site/course_lib/marching_cubes.py",
                             "/sandbox/site/course_lib/variants.py"]   # no answers: numbers only
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
            try:   # the supervisor (PID 1) holds the channel: its descriptors are out of reach
                reach = os.listdir("/proc/1/fd")
            except OSError as exc:
                reach = type(exc).__name__
            return (os.getuid(), os.getgid(), os.getgroups(), status["NoNewPrivs"].strip(),
                    int(status["CapEff"], 16), int(status["CapBnd"], 16), int(status["CapPrm"], 16),
                    reach)
        """
    results = {}

    def one(tag):
        results[tag] = run(mode, fn("ident", probe_src), job_id=tag)["ident"].outcomes[0]

    threads = [threading.Thread(target=one, args=(t,)) for t in ("a", "b")]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    (uid_a, gid_a, groups, nnp, cap_eff, cap_bnd, cap_prm, reach), other = (
        results["a"].value, results["b"].value)
    assert reach == "PermissionError"
    assert uid_a != 0 and gid_a != 0 and uid_a != other[0] and groups == []
    if bwrap.privileged():
        assert identity.UID_BASE <= uid_a < identity.UID_BASE + identity.UID_COUNT
    assert nnp == "1" and cap_eff == 0 and cap_prm == 0 and cap_bnd == 0


# ------------------------------------------------------------------------------------------
# processes, network


def test_processes_cannot_outlive_the_job_or_reach_another_job(mode):
    evil = fn("evil", """
        import os, signal, time
        def evil(k):
            if k == 0:
                if os.fork() == 0:
                    os.setsid()
                    if os.fork() == 0:
                        while True:
                            try:
                                os.kill(-1, signal.SIGKILL)
                            except OSError:
                                pass
                            time.sleep(0.05)
                    os._exit(0)
                time.sleep(1.0)
            return (k, os.getuid())
        """, cases=[(0,), (1,), (2,)])
    calm = fn("calm", """
        import time, os
        def calm(x):
            time.sleep(0.3)
            return x * 2.0, os.getuid()
        """, cases=[(float(k),) for k in range(8)])
    results = {}
    thread = threading.Thread(target=lambda: results.update(run(mode, calm, job_id="calm")))
    thread.start()
    runs = run(mode, evil, job_id="evil")
    thread.join()

    # the grandchild kills the worker (and holds its pipe open): the supervisor sees it die
    assert kinds(runs["evil"])[0] is K.CRASHED
    assert "SIGKILL" in runs["evil"].outcomes[0].message
    assert kinds(runs["evil"])[1:] == [K.RETURNED, K.RETURNED]
    evil_uid = runs["evil"].outcomes[1].value[1]
    assert kinds(results["calm"]) == [K.RETURNED] * 8
    assert [o.value[0] for o in results["calm"].outcomes] == [2.0 * k for k in range(8)]
    assert results["calm"].outcomes[0].value[1] != evil_uid
    assert processes_left(evil_uid) == []


def test_fork_bomb_is_contained_and_cleared(mode):
    bomb = fn("bomb", """
        import os
        def bomb(k):
            if k == 0:
                while True:
                    try:
                        os.fork()
                    except OSError:
                        pass
            return os.getuid()
        """, cases=[(0,), (1,)])
    t0 = time.monotonic()
    runs = run(mode, bomb, limits=Limits(case_timeout=2.0, pids=32))["bomb"]
    assert kinds(runs) == [K.TIMEOUT, K.RETURNED]
    assert time.monotonic() - t0 < 30
    assert processes_left(runs.outcomes[1].value) == []


def test_the_job_budget_kills_the_whole_sandbox(mode, monkeypatch):
    from autograder.isolation import runner

    monkeypatch.setattr(runner, "job_budget", lambda job, limits: 6.0)
    sleeper = fn("sleeper", """
        import os, time
        def sleeper(k):
            if os.fork() == 0:
                os.setsid()
                time.sleep(60)
            time.sleep(60)
        """, cases=[(0,), (1,)])
    who = fn("who", "import os\ndef who():\n    return os.getuid()\n")
    t0 = time.monotonic()
    runs = run(mode, who, sleeper, limits=Limits(case_timeout=120.0))
    assert time.monotonic() - t0 < 20
    assert kinds(runs["sleeper"]) == [K.NOT_RUN, K.NOT_RUN]
    assert runs["sleeper"].outcomes[0].message == "not run: the notebook used up its time"
    assert processes_left(runs["who"].outcomes[0].value) == []


def test_two_grading_processes_get_distinct_uids(mode):
    script = textwrap.dedent("""
        from autograder.isolation import CaseInput, Limits, NameJob, NotebookJob, probe, run_notebook
        src = "import os, time\\ndef u():\\n    time.sleep(1.5)\\n    return os.getuid()\\n"
        job = NotebookJob("p", "", [NameJob("u", "function", [("a", src)], [CaseInput((), {})])])
        print(run_notebook(job, Limits(), probe())["u"].outcomes[0].value)
        """)
    procs = [subprocess.Popen([sys.executable, "-c", script], cwd=REPO, text=True,
                              stdout=subprocess.PIPE) for _ in range(2)]
    uids = [int(p.communicate(timeout=120)[0].strip()) for p in procs]
    assert len(set(uids)) == 2 and 0 not in uids


def test_no_network_even_from_c(mode):
    server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    server.bind(("127.0.0.1", 0))
    server.listen(5)
    server.settimeout(0.2)
    port = server.getsockname()[1]
    net = fn("net", """
        import ctypes, struct
        AF_INET, SOCK_STREAM, SOL_SOCKET, SO_SNDTIMEO = 2, 1, 1, 21
        def sockaddr(port):
            return struct.pack("=H", AF_INET) + struct.pack(">H", port) + bytes([127, 0, 0, 1]) \\
                + bytes(8)
        def net(port):
            libc = ctypes.CDLL(None, use_errno=True)
            fd = libc.socket(AF_INET, SOCK_STREAM, 0)
            timeout = struct.pack("ll", 1, 0)   # a SYN into a downed loopback waits: 1 s
            libc.setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, timeout, len(timeout))
            addr = sockaddr(port)
            rc = libc.connect(fd, ctypes.c_char_p(addr), len(addr))
            raw = (rc, ctypes.get_errno())
            try:   # the socket module is not among the modules a solution may use
                import socket  # noqa: F401
                py = "loaded"
            except ImportError:
                py = "refused"
            with open("/proc/net/dev") as f:
                interfaces = sorted(line.split(":")[0].strip() for line in f.readlines()[2:])
            # even its own loopback is down: a listening socket of its own cannot be reached
            own = libc.socket(AF_INET, SOCK_STREAM, 0)
            here = sockaddr(0)
            libc.bind(own, ctypes.c_char_p(here), len(here))
            libc.listen(own, 1)
            name, size = ctypes.create_string_buffer(16), ctypes.c_uint(16)
            libc.getsockname(own, name, ctypes.byref(size))
            there = sockaddr(struct.unpack(">H", name.raw[2:4])[0])
            other = libc.socket(AF_INET, SOCK_STREAM, 0)
            libc.setsockopt(other, SOL_SOCKET, SO_SNDTIMEO, timeout, len(timeout))
            loop = "connected" if libc.connect(other, ctypes.c_char_p(there), len(there)) == 0 \\
                else "refused"
            return raw, py, interfaces, loop
        """, cases=[(port,)])
    try:
        out = run(mode, net, limits=Limits(case_timeout=10.0))["net"].outcomes[0]
        with pytest.raises(socket.timeout):
            server.accept()
    finally:
        server.close()
    (rc, err), py, interfaces, loop = out.value
    assert rc == -1 and err != 0 and py == "refused"
    assert interfaces == ["lo"]
    if bwrap.privileged():
        assert loop != "connected"


# ------------------------------------------------------------------------------------------
# the course's references are absent; its data tables are there


def test_references_absent_tables_present(mode):
    import course_lib.marching_cubes as real

    uses = fn("uses", """
        def uses(k):
            if k == 0:
                from course_lib.shading import phong
            if k == 1:
                from course_lib.marching_cubes import _march
            if k == 2:
                import skimage
            if k == 3:
                import shapely
            if k == 4:
                import autograder
            return CORNERS, EDGES, N_TRIANGLES, TRI_TABLE
        """, cases=[(k,) for k in range(6)])
    importer = NameJob("imp", "function", [("i1", "import course_lib.clipping\n"),
                                           ("i2", "def imp():\n    return 1\n")],
                       [CaseInput((), {})])
    setup = SETUP + "from course_lib.marching_cubes import CORNERS, EDGES, N_TRIANGLES, TRI_TABLE\n"
    runs = run(mode, uses, importer, setup=setup)
    assert kinds(runs["uses"]) == [K.REFERENCE_USED, K.REFERENCE_USED, K.RAISED, K.RAISED,
                                   K.RAISED, K.RETURNED]
    assert [o.error_type for o in runs["uses"].outcomes[2:5]] == ["ModuleNotFoundError"] * 3
    tables = runs["uses"].outcomes[5].value
    for got, want in zip(tables, (real.CORNERS, real.EDGES, real.N_TRIANGLES, real.TRI_TABLE)):
        assert got.dtype == want.dtype
        np.testing.assert_array_equal(got, want)
    assert "course_lib.clipping" in runs["imp"].load_notes[0]
    assert kinds(runs["imp"]) == [K.RETURNED]


def test_every_source_notebooks_setup_cell_runs_in_the_sandbox(mode):
    import nbformat

    checked = 0
    for path in sorted((REPO / "notebooks").glob("q*.ipynb")):
        cells = nbformat.read(path, as_version=4).cells
        setup = next((c.source for c in cells if c.cell_type == "code" and str(
            c.metadata.get("nbgrader", {}).get("grade_id", "")).startswith("setup")), None)
        if setup is None:
            continue
        runs = run(mode, fn("probe_np", "def probe_np():\n    return float(np.pi)\n"),
                   setup=setup, job_id=path.stem)
        assert runs["probe_np"].load_notes == [], (path.name, runs["probe_np"].load_notes)
        assert runs["probe_np"].outcomes[0].value == pytest.approx(np.pi)
        checked += 1
    assert checked >= 1


def test_callers_frames_hold_no_expected_value(mode):
    spy = fn("spy", """
        import sys
        def spy(x):
            seen, frame = [], sys._getframe(1)
            while frame is not None:
                seen.append(repr(frame.f_locals)[:100000])
                frame = frame.f_back
            return "\\n".join(seen)
        """, cases=[(0.5,)])
    text = run(mode, spy)["spy"].outcomes[0].value
    assert "0.5" in text
    assert "expected" not in text and "123.456" not in text


# ------------------------------------------------------------------------------------------
# resources: memory, scratch, time, crashes, huge results


def test_memory_limit_holds_for_the_whole_job(mode):
    hog = fn("hog", """
        import os
        def hog(k):
            if k == 0:
                return np.ones(3 * 2**30 // 8).sum()
            if k == 1:
                pids = []
                for _ in range(3):
                    pid = os.fork()
                    if pid == 0:
                        block = np.ones(500 * 2**20 // 8)
                        os._exit(0 if block.sum() else 1)
                    pids.append(pid)
                return [os.waitstatus_to_exitcode(os.waitpid(p, 0)[1]) for p in pids]
            return 42
        """, cases=[(0,), (1,), (2,)])
    runs = run(mode, hog, limits=Limits(case_timeout=20.0, memory_mb=1024))["hog"]
    assert kinds(runs)[0] in (K.RAISED, K.CRASHED)
    if bwrap.privileged():
        first, second = runs.outcomes[0], runs.outcomes[1]
        assert first.kind is K.CRASHED or first.error_type == "MemoryError"
        assert second.kind is K.CRASHED or -9 in second.value
    assert runs.outcomes[2].kind is K.RETURNED and runs.outcomes[2].value == 42


def test_scratch_is_small_and_private(mode):
    fill = fn("fill", """
        import errno, os
        def fill(k):
            if k == 1:
                return os.getcwd(), os.environ.get("HOME")
            try:
                with open("/tmp/big", "wb") as f:
                    for _ in range(1024):
                        f.write(b"\\0" * 2**20)
                return "written"
            except OSError as exc:
                return errno.errorcode.get(exc.errno, "?")
        """, cases=[(0,), (1,)])
    runs = run(mode, fill)["fill"]
    assert [o.value for o in runs.outcomes] == ["ENOSPC", ("/tmp", "/tmp")]


KEEPER = """
import os
def keep(x):
    top = f"/tmp/k{x}"
    os.makedirs(top + "/deep")
    for folder in (top + "/deep", top):
        with open(folder + "/" + str(x), "w") as f:
            f.write(str(x))
    os.chmod(top + "/deep", 0o555)
    os.chmod(top, 0o555)           # a plain rmtree as this uid can no longer empty it
    return x
"""

FINDER = """
import os
def find(x):
    return sorted(os.path.join(top, f) for top, _, files in os.walk("/tmp") for f in files)
"""


def test_a_folder_made_read_only_keeps_nothing_for_a_later_name(mode):
    """The scratch is emptied before each name (a red team kept one name's hidden inputs in a
    folder it made read-only, and read them in a later name's visible case)."""
    if mode is not Mode.ISOLATED:
        pytest.skip("the scratch folder is emptied between names only in the sandbox")
    runs = run(mode, fn("keep", KEEPER, cases=[(11,), (22,)]), fn("find", FINDER, cases=[(0,)]))
    assert [o.value for o in runs["keep"].outcomes] == [11, 22]
    assert runs["find"].outcomes[0].value == [], runs["find"].outcomes[0]


def test_time_limits_and_crashes(mode):
    slow = fn("slow", """
        import os, time
        def slow(k):
            if k == 0:
                while True:
                    pass
            if k == 1:
                while True:
                    try:
                        time.sleep(10)
                    except BaseException:
                        pass
            if k == 2:
                os._exit(3)
            print("case", k)
            return k
        """, cases=[(k,) for k in range(5)])
    hang = fn("hang", """
        def hang(k):
            while True:
                pass
        """, cases=[(k,) for k in range(5)])
    top = NameJob("top", "function", [("t1", "while True:\n    pass\n"),
                                      ("t2", "def top():\n    return 'ok'\n")],
                  [CaseInput((), {})])
    runs = run(mode, slow, hang, top, limits=Limits(case_timeout=1.0, load_timeout=3.0))
    assert kinds(runs["slow"]) == [K.TIMEOUT, K.TIMEOUT, K.CRASHED, K.RETURNED, K.RETURNED]
    assert [o.value for o in runs["slow"].outcomes[3:]] == [3, 4]
    assert runs["slow"].outcomes[4].printed == "case 4\n"
    assert runs["slow"].launches == 3
    assert kinds(runs["hang"]) == [K.TIMEOUT] * 3 + [K.NOT_RUN] * 2
    # ONE load budget for all of a name's cells: t1 uses it up, so t2 never runs
    assert "t1" in runs["top"].load_notes[0] and "t2 was not run" in runs["top"].load_notes[1]
    assert kinds(runs["top"]) == [K.NOT_RUN]


FORGER = """
import sys
def _forged(value, cap):
    return FORGED
for _module in list(sys.modules.values()):      # the worker's own encoder, in this process
    if "_encode_result" in getattr(_module, "__dict__", {}):
        _module._encode_result = _forged
def NAME(k):
    if k == 1:                                  # the supervisor's own timeout
        import signal
        signal.signal(signal.SIGALRM, signal.SIG_IGN)   # the worker's wall-clock backstop
        signal.signal(signal.SIGPROF, signal.SIG_IGN)   # and its CPU-time alarm
        while True:
            pass
    return k
"""


def test_only_the_supervisors_records_are_marked_as_its_words(mode):
    """A worker's record (which student code may rewrite) is ``said_by_student``, whatever kind
    it claims; a record that claims to be the supervisor's is refused by the supervisor."""
    plain = FORGER.replace("FORGED", "{'kind': 'timeout', 'message': 'FORGED'}")
    claims = FORGER.replace("FORGED", "{'kind': 'timeout', 'message': 'FORGED', "
                                      "'by': 'supervisor'}")
    runs = run(mode, fn("plain", plain.replace("NAME", "plain"), cases=[(0,), (1,)]),
               fn("claims", claims.replace("NAME", "claims"), cases=[(0,)]),
               limits=Limits(case_timeout=1.0, load_timeout=10.0))
    forged, real = runs["plain"].outcomes
    assert (forged.kind, forged.message, forged.said_by_student) == (K.TIMEOUT, "FORGED", True)
    assert real.kind is K.TIMEOUT and not real.said_by_student
    assert "stopped by the supervisor" in real.message
    refused = runs["claims"].outcomes[0]
    assert refused.kind is K.REJECTED and not refused.said_by_student
    assert "FORGED" not in refused.message


GRADER_RSS = """
import json, resource, sys
import numpy as np
from autograder.isolation import CaseInput, Limits, NameJob, NotebookJob, probe, run_notebook
source = '''
import os
def big(k):
    if k == 0:
        return np.zeros(200 * 2**20 // 8)
    if k == 1:
        return ["x" * 2**20] * 200
    if k == 2:   # forge a record on every descriptor it can reach: only its own pipe
        blocked = []
        record = b'{"t":"case","name":"big","i":2,"kind":"returned","value":"' + b"A" * 2**20
        for fd in list(range(3, 64)) + [f"/proc/1/fd/{n}" for n in range(64)]:
            try:
                target = os.open(fd, os.O_WRONLY) if isinstance(fd, str) else fd
                os.write(target, (2**31).to_bytes(4, "big") + record)
                blocked.append("written")
            except OSError:
                pass
        return blocked
    if k == 3:   # switch off the worker's own size check: the supervisor still refuses it
        import sys
        worker = sys.modules["inside.worker"]      # the worker's own code: the student owns it
        worker.record_cap = lambda *args: 1 << 40
        worker.encode_value = lambda v, budget, depth=0: {"t": "list", "v": ["y" * 2**20] * 300}
        return 0
    return k
'''
job = NotebookJob("rss", "import numpy as np\\n", [NameJob("big", "function", [("c", source)],
                  [CaseInput((k,), {}, 1024) for k in range(5)])])
runs = run_notebook(job, Limits(case_timeout=20.0), probe())
out = [(o.kind.value, o.value if o.kind.value == "returned" else o.message)
       for o in runs["big"].outcomes]
print(json.dumps({"out": out, "maxrss_kb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}))
"""


def test_huge_results_and_forged_records_leave_the_grader_small(mode):
    done = subprocess.run([sys.executable, "-c", GRADER_RSS], capture_output=True, text=True,
                          cwd=REPO, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert report["out"] == [["rejected", "result too large (more than 1024 bytes)"],
                             ["rejected", "result too large (more than 1024 bytes)"],
                             ["rejected", "result too large"],
                             ["rejected", "result too large"], ["returned", 4]]
    assert report["maxrss_kb"] < 2**20


# ------------------------------------------------------------------------------------------
# the grader's side of the channel, on forged streams


def _stream(*chunks: bytes):
    rfd, wfd = os.pipe()
    writer = threading.Thread(target=lambda: ([os.write(wfd, c) for c in chunks],
                                              os.close(wfd)))
    writer.start()
    return rfd, writer


def test_reader_refuses_oversized_frames_before_reading_them():
    rfd, writer = _stream(wire.FRAME.pack(2**32 - 1) + b"{")
    reader = wire.FrameReader(rfd, frame_cap=4096, total_cap=10**9)
    assert reader.next(time.monotonic() + 5) == ("too-large", None)
    assert len(reader.buf) <= wire.FRAME.size + 4096
    writer.join()
    os.close(rfd)

    many = wire.frame({"t": "note", "name": None, "text": "x" * 900}) * 50
    rfd, writer = _stream(many)
    reader = wire.FrameReader(rfd, frame_cap=4096, total_cap=10_000)
    events = []
    while not events or events[-1] == "record":
        events.append(reader.next(time.monotonic() + 5)[0])
    assert events[-1] == "too-large" and reader.total <= 10_000 + 2**20
    assert events.count("record") <= 10_000 // 900
    writer.join()
    os.close(rfd)


def test_decoder_checks_sizes_before_decoding():
    huge = {"t": "array", "dtype": "<f8", "shape": [10**6, 10**6], "v": "AAAA"}
    with pytest.raises(wire.BadValue, match="too large"):
        wire.decode_value(huge, wire.Budget(1024))
    lying = {"t": "array", "dtype": "<f8", "shape": [4], "v": "AAAA"}
    with pytest.raises(wire.BadValue, match="does not match"):
        wire.decode_value(lying, wire.Budget(1024))
    for bad in ({"t": "array", "dtype": "|O", "shape": [1], "v": "AAAA"}, {"t": "pickle"},
                {"t": "list", "v": "abc"}, [1, 2]):
        with pytest.raises(wire.BadValue):
            wire.decode_value(bad, wire.Budget(1024))
    deep = 1
    for _ in range(12):
        deep = {"t": "list", "v": [deep]}
    with pytest.raises(wire.BadValue, match="deeply"):
        wire.decode_value(deep, wire.Budget(1024))
    value = np.arange(6, dtype=">i4").reshape(2, 3)
    back = wire.decode_value(wire.encode_value(value, wire.Budget(1024)), wire.Budget(1024))
    assert back.dtype == np.dtype("<i4") and back.tolist() == [[0, 1, 2], [3, 4, 5]]


# ------------------------------------------------------------------------------------------
# modes, and what a job costs


def test_probe_says_what_to_install(monkeypatch):
    monkeypatch.setattr(bwrap, "BWRAP", "/nonexistent/bwrap")
    bwrap.probe.cache_clear()
    try:
        with pytest.raises(IsolationUnavailable, match="apt-get install bubblewrap"):
            bwrap.probe()
    finally:
        bwrap.probe.cache_clear()


def test_no_job_runs_without_root(monkeypatch):
    """Without root a job could get neither a uid nor a cgroup of its own (an unprivileged user
    namespace maps every job to the grader's uid; no cgroup caps memory, processes or CPU):
    the probe refuses, saying what to do, and no sandboxed job runs."""
    monkeypatch.setattr(bwrap, "privileged", lambda: False)
    bwrap.probe.cache_clear()
    try:
        with pytest.raises(IsolationUnavailable, match="must run as root"):
            bwrap.probe()
        with pytest.raises(IsolationUnavailable, match="must run as root"):
            run(Mode.ISOLATED, fn("u", "def u():\n    return 1\n"))
    finally:
        bwrap.probe.cache_clear()


def test_no_job_runs_without_its_cgroup(monkeypatch, tmp_path):
    """No cgroup hierarchy (here: an empty folder in its place): the probe refuses, and a job
    is not run without its cgroup (the grader's problem, never an unconfined run)."""
    if not bwrap.privileged():
        pytest.skip("needs root (without root the probe refuses first)")
    monkeypatch.setattr(cgroup, "V1_ROOT", str(tmp_path))
    monkeypatch.setattr(cgroup, "V2_ROOT", str(tmp_path))
    bwrap.probe.cache_clear()
    try:
        with pytest.raises(IsolationUnavailable, match="cgroup"):
            bwrap.probe()
        with pytest.raises(IsolationError, match="cgroup"):
            run(Mode.ISOLATED, fn("u", "def u():\n    return 1\n"))
    finally:
        bwrap.probe.cache_clear()
    assert os.listdir(tmp_path) == []


def test_the_supervisor_reads_a_process_cpu_clock():
    """The clock the supervisor holds a case to (``/proc/<pid>/stat``), against this process's
    own CPU clock; a process that is gone has used nothing more."""
    from autograder.isolation.inside.confine import process_cpu_seconds

    before = process_cpu_seconds(os.getpid())
    t0 = time.process_time()
    while time.process_time() - t0 < 0.3:
        pass
    used = process_cpu_seconds(os.getpid()) - before
    assert used == pytest.approx(time.process_time() - t0, abs=0.05)
    assert process_cpu_seconds(2**22 + 1) == 0.0       # above any pid_max: no such process


def test_case_time_is_cpu_time_with_a_wall_backstop(mode):
    """A case's limit is its CPU time: 3 s asleep under a 2 s limit is not a timeout (a busy
    machine or a neighbour slows the wall clock, not the case's CPU clock); 2 s of CPU is, and
    so is sleeping past the backstop (``confine.WALL_FACTOR`` times the limit)."""
    limit = 2.0
    clock = fn("clock", f"""
        import time
        def clock(k):
            if k == 0:
                time.sleep({1.5 * limit})
            elif k == 1:
                while True:
                    pass
            else:
                time.sleep(1000)
            return k
        """, cases=[(0,), (1,), (2,)])
    runs = run(mode, clock, limits=Limits(case_timeout=limit, load_timeout=10.0))["clock"]
    assert kinds(runs) == [K.RETURNED, K.TIMEOUT, K.TIMEOUT]
    assert runs.outcomes[0].value == 0


def test_unsafe_mode_runs_the_same_child(tmp_path):
    assert "WITHOUT" in bwrap.UNSAFE_WARNING
    job = fn("double", "def double(x):\n    return 2 * x\n", cases=[(np.arange(3),)])
    runs = run(Mode.UNSAFE, job)
    np.testing.assert_array_equal(runs["double"].outcomes[0].value, [0, 2, 4])


def test_cost_of_a_job(mode):
    """Measured, not asserted: the cost of an empty job and of a typical one."""
    empty = NotebookJob("empty", "", [])
    typical = NotebookJob("typical", SETUP, [
        fn(f"f{k}", f"def f{k}(a):\n    return np.linalg.solve(a, np.ones(len(a)))\n",
           cases=[(np.eye(5) * (i + 1),) for i in range(10)]) for k in range(6)])
    for job in (empty, typical):
        t0 = time.perf_counter()
        runs = run_notebook(job, FAST, mode)
        print(f"{job.job_id}: {time.perf_counter() - t0:.3f} s")
    assert all(kinds(r) == [K.RETURNED] * 10 for r in runs.values())


# ------------------------------------------------------------------------------------------
# deadlines the worker cannot move

KEEPALIVE = """
import json, os, signal, stat, struct, time
def _fake(record):
    # student code writes the supervisor's own frames to its result pipe
    data = json.dumps(record).encode()
    for fd in range(3, 32):
        try:
            if stat.S_ISFIFO(os.fstat(fd).st_mode):
                os.write(fd, struct.pack(">I", len(data)) + data)
        except OSError:
            pass
"""


def test_fake_start_frames_do_not_extend_a_case(mode):
    extend = fn("extend", KEEPALIVE + """
def extend(i):
    signal.setitimer(signal.ITIMER_REAL, 0)          # the worker's own alarm: off
    t0 = time.monotonic()
    while time.monotonic() - t0 < 8:
        time.sleep(0.2)
        _fake({"t": "start", "name": "extend", "i": i})
    return "late"
""", cases=[(0,)])
    t0 = time.monotonic()
    runs = run(mode, extend, limits=Limits(case_timeout=1.0, load_timeout=5.0))
    assert kinds(runs["extend"]) == [K.TIMEOUT]
    assert time.monotonic() - t0 < 8


def test_fake_cell_frames_do_not_extend_the_load(mode):
    body = KEEPALIVE + """
signal.setitimer(signal.ITIMER_REAL, 0)
_t0 = time.monotonic()
while time.monotonic() - _t0 < 10:
    time.sleep(0.2)
    _fake({"t": "cell", "name": "slowload", "label": "x"})
def slowload():
    return 1
"""
    job = NameJob("slowload", "function", [("a", body), ("b", "pass\n")], [CaseInput((), {})])
    t0 = time.monotonic()
    runs = run(mode, job, limits=Limits(case_timeout=1.0, load_timeout=2.0))
    assert kinds(runs["slowload"]) == [K.TIMEOUT]
    assert time.monotonic() - t0 < 10


def test_the_notebook_has_one_hard_time_limit(mode):
    slow = "import time\ndef {0}(k):\n    time.sleep(0.5)\n    return k\n"
    first = fn("first", slow.format("first"), cases=[(k,) for k in range(30)])
    second = fn("second", slow.format("second"), cases=[(k,) for k in range(30)])
    t0 = time.monotonic()
    runs = run(mode, first, second,
               limits=Limits(case_timeout=2.0, load_timeout=5.0, job_timeout=4.0))
    assert time.monotonic() - t0 < 4.0 + 15.0          # far below 60 cases x 0.5 s
    done = [o.value for o in runs["first"].outcomes if o.kind is K.RETURNED]
    assert 1 <= len(done) < 30 and done == list(range(len(done)))
    assert kinds(runs["second"]) == [K.NOT_RUN] * 30
    assert "the notebook used up its time" in runs["second"].outcomes[0].message
    assert "the notebook used up its time" in runs["first"].outcomes[-1].message


# ------------------------------------------------------------------------------------------
# a worker holds only the case it is running

#: Looks for case markers where student code can: every object the interpreter tracks (the
#: frames' locals included), the job file and the scratch folder (``reachable``), and raw memory
#: (every writable mapping of the process, read through ``__array_interface__``).
SPY = r"""
import gc, os, re, sys
PATTERN = re.compile(rb"MARK[-][a-z][-][0-9]")

class _Raw:
    def __init__(self, address, n):
        self.__array_interface__ = {"shape": (n,), "typestr": "|u1", "data": (address, True),
                                    "version": 3}

def _markers(data):
    return {m.group().decode() for m in PATTERN.finditer(data)}

def _reachable():
    found = set()
    for obj in gc.get_objects():
        items = obj.values() if type(obj) is dict else obj if type(obj) in (list, tuple) else ()
        for v in items:
            if type(v) is str:
                found |= _markers(v.encode())
    with open(sys.argv[sys.argv.index("--job") + 1], "rb") as f:
        found |= _markers(f.read())
    for entry in os.listdir("."):
        found |= _markers(entry.encode())
        if os.path.isfile(entry):
            with open(entry, "rb") as f:
                found |= _markers(f.read())
    return found

def _raw():
    found = set()
    with open("/proc/self/maps") as f:
        maps = f.read().splitlines()
    for line in maps:
        parts = line.split()
        if not parts[1].startswith("rw") or (len(parts) > 5 and parts[5] == "[vvar]"):
            continue
        lo, hi = (int(x, 16) for x in parts[0].split("-"))
        found |= _markers(bytes(np.asarray(_Raw(lo, hi - lo))))
    return found

def NAME(marker):
    with open("stash-" + marker, "w") as f:     # for a later worker to find
        f.write(marker)
    seen, raw = _reachable(), _raw()
    return [len({m for m in seen | raw if m[5] != marker[5]}),
            len({m for m in seen | raw if m[5] == marker[5] and m > marker}),
            int(marker in seen and marker in raw)]
"""


def test_a_worker_holds_no_other_case_than_its_own(mode):
    """Each case's inputs reach the worker only when it is due: nothing of a later case of the
    same name, and nothing of another name, in objects, frames, the job file, the scratch
    folder (names and contents) or raw memory."""
    if mode is not Mode.ISOLATED:
        pytest.skip("the scratch folder is emptied between workers only in the sandbox")
    names = [fn(n, SPY.replace("NAME", n), cases=[(f"MARK-{n}-{k}",) for k in range(4)])
             for n in ("f", "g")]
    runs = run(mode, *names, limits=Limits(case_timeout=20.0, load_timeout=10.0))
    for n in ("f", "g"):
        assert kinds(runs[n]) == [K.RETURNED] * 4, [o.message for o in runs[n].outcomes]
        # no marker of the other name, none of a later case of its own; its own is found
        assert [o.value for o in runs[n].outcomes] == [[0, 0, 1]] * 4, n


def test_the_job_document_holds_no_case_inputs():
    """The file bound into the sandbox holds no case's inputs: they are the frames of the cases
    file, one after another, which only the supervisor's descriptor reaches."""
    from autograder.isolation import runner

    job = NotebookJob("j", SETUP, [fn("f", "def f(x):\n    return x\n",
                                      cases=[(0.123456789,), (np.array([9.87654321]),)]),
                                   fn("g", "def g(x):\n    return x\n", cases=[(7.5,)])])
    doc, cases = runner._job_contents(job, Limits(), False)
    assert "0.123456789" not in json.dumps(doc) and "args" not in json.dumps(doc)
    with tempfile.TemporaryFile() as f:
        f.write(cases)
        f.flush()
        stream = wire.CaseStream(f.fileno())
        # the g's case is frame 2; a name's cases never read are passed over
        got = [stream.read(0), stream.read(2), stream.read(1), stream.read(3)]
    rec = [json.loads(bytes(b[wire.FRAME.size:])) for b in got[:2]]
    assert wire.decode_value(rec[0]["args"], wire.Budget(1 << 20)) == (0.123456789,)
    assert wire.decode_value(rec[1]["args"], wire.Budget(1 << 20)) == (7.5,)
    assert got[2] == got[3] == bytearray(), "read already, or no such case"


JOB_READER = "def NAME(x):\n    with open('/job') as f:\n        return f.read()\n"


def test_the_job_file_the_sandbox_sees_does_not_tell_cases_apart(mode):
    """Student code reads ``/job``: it must not tell a hidden case from another (no offsets or
    byte lengths, which would tell how large each hidden input is). Two jobs whose cases differ
    only in their inputs' sizes show the sandbox the same job file."""
    seen = []
    for size in (1, 600):
        cases = [(np.zeros(1),), (np.zeros(size),), (np.zeros(3),)]
        runs = run(mode, fn("early", JOB_READER.replace("NAME", "early"), cases=cases),
                   fn("late", JOB_READER.replace("NAME", "late"), cases=cases))
        docs = [o.value for name in ("early", "late") for o in runs[name].outcomes]
        assert all(type(d) is str for d in docs), docs
        seen.append(json.loads(docs[0]))
    assert [len(n["cases"]) for n in seen[0]["names"]] == [3, 3]
    assert seen[0] == seen[1]


# ------------------------------------------------------------------------------------------
# the job's cgroup on a pure cgroup v2 machine (this one may be v1): files in a folder laid out
# as /sys/fs/cgroup is there


def _fake_v2(root: Path, offered: str) -> None:
    (root / "cgroup.controllers").write_text(offered + "\n")
    (root / "cgroup.subtree_control").write_text("")
    (root / cgroup.GROUP).mkdir()
    (root / cgroup.GROUP / "cgroup.controllers").write_text(offered + "\n")
    (root / cgroup.GROUP / "cgroup.subtree_control").write_text("")


def test_a_v2_job_cgroup_gets_memory_pids_and_one_cpu(monkeypatch, tmp_path):
    monkeypatch.setattr(cgroup, "V2_ROOT", str(tmp_path))
    _fake_v2(tmp_path, "cpuset cpu io memory pids")
    job = cgroup.JobCgroup("u1", 300, 17)
    path = tmp_path / cgroup.GROUP / "u1"
    assert job.dirs == [str(path)]
    assert (path / "memory.max").read_text() == str(300 * 2**20)
    assert (path / "pids.max").read_text() == "17"
    quota, period = (path / "cpu.max").read_text().split()
    assert quota == period                                   # one CPU at most
    assert (path / "cpu.weight").read_text() == "100"       # the default weight, for every job
    for parent in (tmp_path, tmp_path / cgroup.GROUP):      # switched on from the top down
        assert set((parent / "cgroup.subtree_control").read_text().split()) == \
            {"+cpu", "+memory", "+pids"}


def test_a_v2_machine_without_the_cpu_controller_is_refused(monkeypatch, tmp_path):
    monkeypatch.setattr(cgroup, "V2_ROOT", str(tmp_path))
    _fake_v2(tmp_path, "memory pids")
    with pytest.raises(cgroup.CgroupError, match="controllers cpu are not available"):
        cgroup.JobCgroup("u1", 300, 17)
    assert not (tmp_path / cgroup.GROUP / "u1").exists()
