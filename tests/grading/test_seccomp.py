"""The sandbox runs no native code that a job brings: the seccomp filter of every worker, the
``noexec`` scratch, the read-only ``/proc`` and the modules a solution may use.

Each attack is a solution cell that a determined student could write, run in the real sandbox
(:func:`autograder.isolation.run_notebook`); without the filter and the mounts, each of them
succeeds (it returns what the attack was after), so every test below fails on a grader without
them. The honest side: NumPy's compiled parts, threads and every allowed module still work, with
values checked against the grader's own NumPy.
"""

from __future__ import annotations

import errno
import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from autograder.isolation import (CaseInput, IsolationUnavailable, Limits, NameJob, NotebookJob,
                                  allowlist, probe, run_notebook, seccomp)
from autograder.isolation.inside import confine, failures
from autograder.model import OutcomeKind as K

pytestmark = pytest.mark.xdist_group("isolation")

REPO = Path(__file__).resolve().parents[2]
FAST = Limits(case_timeout=5.0, load_timeout=20.0)
SETUP = "import numpy as np\n"


def fn(name: str, source: str, cases=((),)) -> NameJob:
    return NameJob(name, "function", [(f"{name}-cell", textwrap.dedent(source))],
                   [CaseInput(tuple(a), {}, 1_000_000) for a in cases])


def run(mode, *names):
    return run_notebook(NotebookJob("seccomp", SETUP, list(names)), FAST, mode)


# ------------------------------------------------------------------------------------------
# the honest student is unaffected


def test_numpy_threads_and_every_allowed_module_still_work(mode):
    a = np.array([[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]])
    honest = fn("honest", f"""
        import importlib, threading
        import numpy as np
        MODULES = {list(allowlist.ALLOWED_MODULES)!r}
        for _m in MODULES:
            importlib.import_module(_m)
        import math, cmath, statistics, decimal, fractions, random, bisect, heapq, json

        def honest(a):
            out = {{}}
            def work(k):                      # threads start AND end (libgcc_s preloaded)
                out[k] = float(np.linalg.det(a) * k)
            ts = [threading.Thread(target=work, args=(k,)) for k in range(1, 4)]
            for t in ts:
                t.start()
            for t in ts:
                t.join()
            return (np.linalg.solve(a, np.ones(3)), np.linalg.eigvalsh(a),
                    np.abs(np.fft.rfft(np.arange(8.0))), np.random.default_rng(5).random(3),
                    [out[k] for k in (1, 2, 3)],
                    [math.gamma(4.5), cmath.sqrt(-4).imag, statistics.median([3, 1, 2]),
                     float(decimal.Decimal("2.5") * 2), float(fractions.Fraction(3, 4)),
                     bisect.bisect([1, 2, 4], 3), heapq.nsmallest(1, [5, 2, 9])[0],
                     json.loads("[1.5]")[0], random.Random(3).random()])
    """, cases=[(a,)])
    out = run(mode, honest)["honest"]
    assert out.load_notes == [] and out.outcomes[0].kind is K.RETURNED, out
    solve, eig, fft, rnd, threads, small = out.outcomes[0].value
    np.testing.assert_allclose(a @ solve, np.ones(3), rtol=1e-12, atol=1e-12)   # solves it
    assert np.prod(eig) == pytest.approx(np.linalg.det(a), rel=1e-12)          # det = prod(eig)
    assert sum(eig) == pytest.approx(np.trace(a), rel=1e-12)
    k = np.arange(5)   # |DFT of 0..7| at k > 0 is 4 / sin(pi k / 8); at 0 the sum, 28
    np.testing.assert_allclose(fft, np.r_[28.0, 4 / np.sin(np.pi * k[1:] / 8)], rtol=1e-12,
                               atol=1e-12)
    np.testing.assert_array_equal(rnd, np.random.default_rng(5).random(3))
    np.testing.assert_allclose(threads, [np.linalg.det(a) * k for k in (1, 2, 3)], rtol=1e-12,
                               atol=1e-12)
    import math
    import random
    assert small == pytest.approx([math.gamma(4.5), 2.0, 2, 5.0, 0.75, 2, 2, 1.5,
                                   random.Random(3).random()], rel=1e-12)


# ------------------------------------------------------------------------------------------
# the attacks: each one succeeds without the filter and the mounts


#: What the ctypes attacks start with (indented like the attacks, for ``textwrap.dedent``).
LIBC = textwrap.indent("import ctypes, os\nlibc = ctypes.CDLL(None, use_errno=True)\n"
                       "libc.syscall.restype = ctypes.c_long\n", " " * 8)

ATTACKS = {
    # new executable memory, then a call into it (mov eax, 42; ret)
    "mmap_exec": LIBC + """
        def mmap_exec():
            libc.mmap.restype = ctypes.c_void_p
            libc.mmap.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_int, ctypes.c_int,
                                  ctypes.c_int, ctypes.c_long]
            addr = libc.mmap(None, 4096, 7, 0x22, -1, 0)       # RWX, MAP_PRIVATE|ANONYMOUS
            if addr in (None, ctypes.c_void_p(-1).value):
                raise OSError(ctypes.get_errno(), os.strerror(ctypes.get_errno()))
            ctypes.memmove(addr, b"\\xb8\\x2a\\x00\\x00\\x00\\xc3", 6)
            return ctypes.CFUNCTYPE(ctypes.c_int)(addr)()
    """,
    # code written into a writable page, then made executable
    "mprotect_exec": LIBC + """
        def mprotect_exec():
            libc.mmap.restype = ctypes.c_void_p
            libc.mmap.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_int, ctypes.c_int,
                                  ctypes.c_int, ctypes.c_long]
            addr = libc.mmap(None, 4096, 3, 0x22, -1, 0)       # RW
            ctypes.memmove(addr, b"\\xb8\\x2a\\x00\\x00\\x00\\xc3", 6)
            if libc.mprotect(ctypes.c_void_p(addr), 4096, 5) != 0:    # R-X
                raise OSError(ctypes.get_errno(), os.strerror(ctypes.get_errno()))
            return ctypes.CFUNCTYPE(ctypes.c_int)(addr)()
    """,
    # an extension module of the standard library that is not on the list
    "import_mmap": """
        import mmap
        def import_mmap():
            return mmap.PAGESIZE
    """,
    "memfd_create": """
        import os
        def memfd_create():
            return os.memfd_create("payload")
    """,
    # a key in the uid's keyring would outlive the job (keyrings are not namespaced)
    "add_key": LIBC + """
        def add_key():
            key = libc.syscall(248, b"user", b"sandbox-key", b"left behind", 11, -4)
            if key < 0:
                raise OSError(ctypes.get_errno(), os.strerror(ctypes.get_errno()))
            return key
    """,
    "unshare_user": LIBC + """
        def unshare_user():
            if libc.unshare(0x10000000) != 0:                  # CLONE_NEWUSER
                raise OSError(ctypes.get_errno(), os.strerror(ctypes.get_errno()))
            return open("/proc/self/uid_map").read()
    """,
    "execve_sh": """
        import os
        def execve_sh():
            os.execv("/bin/sh", ["sh", "-c", "exit 0"])
    """,
}

UNSHARE_COMMAND = {
    "unshare_command": """
        import os
        def unshare_command():
            pid = os.fork()
            if pid == 0:
                try:
                    os.execv("/usr/bin/unshare", ["unshare", "-U", "-r", "true"])
                finally:
                    os._exit(99)
            return os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1])
    """,
}


@pytest.mark.parametrize("name", sorted(ATTACKS))
def test_attack_is_rejected_code(mode, name):
    out = run(mode, fn(name, ATTACKS[name]))[name]
    outcome = out.outcomes[0]
    assert outcome.kind is K.REJECTED_CODE, (outcome, out.load_notes)
    assert outcome.value is None
    assert failures.REFUSED_CODE in outcome.message


def test_a_refused_import_blames_only_the_cases_that_need_it(mode):
    """One cell's import is refused; the next cell's function still raises its own ValueError
    for a bad input (judged as usual), and only the case that needs the module is
    ``rejected-code``."""
    mixed = NameJob("mixed", "function", [
        ("a", "import csv\n"),
        ("b", "def mixed(x):\n    if x < 0:\n        raise ValueError('negative')\n"
              "    return csv.excel.delimiter\n")], [CaseInput((-1,), {}), CaseInput((1,), {})])
    out = run(mode, mixed)["mixed"]
    assert [o.kind for o in out.outcomes] == [K.RAISED, K.REJECTED_CODE], out
    assert out.outcomes[0].error_type == "ValueError"
    assert "NameError" in out.outcomes[1].message


#: One name's worker posts its inputs (a hidden case's, say) to a System V message queue; a
#: later name's worker (a visible case, whose value and message reach the page) reads them.
IPC_POST = LIBC + """
        def ipc_post(secret):
            qid = libc.msgget(0x33, 0o1600)                      # a fixed key, IPC_CREAT | 0600
            if qid < 0:
                raise OSError(ctypes.get_errno(), os.strerror(ctypes.get_errno()))
            msg = ctypes.create_string_buffer(8 + 64)
            data = (1).to_bytes(8, "little") + secret.encode()
            ctypes.memmove(ctypes.addressof(msg), data, len(data))
            if libc.msgsnd(qid, msg, 64, 0) != 0:
                raise OSError(ctypes.get_errno(), os.strerror(ctypes.get_errno()))
            return "posted"
"""
IPC_READ = LIBC + """
        def ipc_read():
            qid = libc.msgget(0x33, 0o600)
            if qid < 0:
                raise OSError(ctypes.get_errno(), os.strerror(ctypes.get_errno()))
            msg = ctypes.create_string_buffer(8 + 64)
            n = libc.msgrcv(qid, msg, 64, 0, 0o4000)             # IPC_NOWAIT
            if n < 0:
                raise OSError(ctypes.get_errno(), os.strerror(ctypes.get_errno()))
            return msg.raw[8:8 + n].rstrip(b"\\0").decode()
"""


def test_workers_of_one_job_share_no_message_queue(mode):
    """Finding 5 of issue 33: the System V queue is refused, so nothing one name's worker saw
    reaches a later name's."""
    runs = run(mode, fn("ipc_post", IPC_POST, cases=[("HIDDEN-4.25",)]), fn("ipc_read", IPC_READ))
    post, read = runs["ipc_post"].outcomes[0], runs["ipc_read"].outcomes[0]
    assert post.kind is K.REJECTED_CODE and read.kind is K.REJECTED_CODE, (post, read)
    assert all("HIDDEN" not in repr([o.value, o.message, o.printed]) for o in (post, read))


def test_unshare_in_a_forked_child_is_refused_too(mode):
    """The filter is inherited: a child process gets exit code 99 (``execve`` refused), not
    ``unshare``'s 0."""
    out = run(mode, fn("fork_unshare", UNSHARE_COMMAND["unshare_command"].replace(
        "def unshare_command", "def fork_unshare")))["fork_unshare"]
    assert out.outcomes[0].kind is K.RETURNED and out.outcomes[0].value == 99, out


def test_a_library_written_to_tmp_cannot_be_loaded(mode):
    """NumPy's own FFT module, copied into the writable scratch and loaded from there (as a
    student's carried-in module would be): refused (``noexec`` and the filter)."""
    tmp_so = fn("tmp_so", """
        import glob, shutil, ctypes
        SRC = glob.glob("/sandbox/site/numpy/fft/_pocketfft_umath*.so")[0]
        shutil.copy(SRC, "/tmp/zz.so")
        LIB = ctypes.CDLL("/tmp/zz.so")
        def tmp_so():
            return 1
    """)
    out = run(mode, tmp_so)["tmp_so"]
    assert out.outcomes[0].kind is K.REJECTED_CODE, out
    assert any("/tmp/zz.so" in n and failures.REFUSED_CODE in n for n in out.load_notes), out


def test_proc_self_mem_cannot_be_written(mode):
    """A write through ``/proc/self/mem`` ignores page protections (it could patch the
    interpreter's code): ``/proc`` is read-only, so the open fails with EROFS."""
    procmem = fn("procmem", LIBC + """
        def procmem():
            libc.prctl(4, 1, 0, 0, 0)                          # PR_SET_DUMPABLE: own /proc files
            buf = ctypes.create_string_buffer(b"before")
            with open("/proc/self/mem", "r+b", buffering=0) as f:
                f.seek(ctypes.addressof(buf))
                f.write(b"AFTER!")
            return buf.value.decode()
    """)
    outcome = run(mode, procmem)["procmem"].outcomes[0]
    assert outcome.kind is K.RAISED and outcome.error_type == "OSError", outcome
    assert "Read-only file system" in outcome.message


def test_writable_mounts_are_noexec_and_proc_read_only(mode):
    """Every folder the job can write to is on a ``noexec`` mount (``/tmp``); ``/proc`` is
    read-only."""
    mounts = fn("mounts", """
        import os
        def mounts():
            out = {}
            for line in open("/proc/self/mountinfo"):
                parts = line.split()
                out[parts[4]] = [parts[5].split(","),
                                 os.path.isdir(parts[4]) and os.access(parts[4], os.W_OK)]
            return out
    """)
    table = run(mode, mounts)["mounts"].outcomes[0].value
    writable = {point for point, (_, w) in table.items() if w}
    assert "/tmp" in writable
    for point in writable:
        assert {"noexec", "nosuid", "nodev"} <= set(table[point][0]), (point, table[point])
    assert "ro" in table["/proc"][0]


def test_a_worker_holds_no_writable_and_executable_memory(mode):
    """Nothing the worker inherits (ctypes' closures included) is both writable and executable,
    and no executable mapping is anonymous or comes from the writable scratch."""
    maps = fn("maps", """
        def maps():
            rows = [line.split() for line in open("/proc/self/maps")]
            return [" ".join(r) for r in rows if "x" in r[1] and ("w" in r[1] or len(r) < 6
                    or r[5].startswith(("/tmp", "/dev")))]
    """)
    outcome = run(mode, maps)["maps"].outcomes[0]
    assert outcome.kind is K.RETURNED and outcome.value == [], outcome


# ------------------------------------------------------------------------------------------
# the filter itself, installed in a plain subprocess (no sandbox needed)


FILTER_PROBE = r"""
import ctypes, errno, json, mmap, os, sys, threading
sys.path.insert(0, sys.argv[1])
import confine
libc = ctypes.CDLL(None, use_errno=True)
libc.syscall.restype = ctypes.c_long
libc.mmap.restype = ctypes.c_void_p
libc.mmap.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_int, ctypes.c_int, ctypes.c_int,
                      ctypes.c_long]
confine.preload([])
# prepared before the filter: i386 getpid through int 0x80 (mov eax, 20; int 0x80; ret)
page = libc.mmap(None, 4096, 7, 0x22, -1, 0)
ctypes.memmove(page, b"\xb8\x14\x00\x00\x00\xcd\x80\xc3", 8)
int80 = ctypes.CFUNCTYPE(ctypes.c_int)(page)
rw = libc.mmap(None, 4096, 3, 0x22, -1, 0)
confine.install_filter(bytes.fromhex(sys.argv[2]))

def call(nr, *args):
    r = libc.syscall(nr, *args)
    return [r, ctypes.get_errno() if r < 0 else 0]

out = {
    "x32_getpid": call(0x40000000 | 39),
    "clone3": call(435, 0, 0),
    "clone_newuser": call(56, 0x10000000 | 17, 0, 0, 0, 0),
    "clone_newnet": call(56, 0x40000000 | 17, 0, 0, 0, 0),
    "mprotect_exec": call(10, ctypes.c_void_p(rw), 4096, 5),
    "mprotect_rw": call(10, ctypes.c_void_p(rw), 4096, 3),
    "ptrace": call(101, 0, 0, 0, 0),
    "bpf": call(321, 0, 0, 0),
    "personality": call(135, 0x0400000),
    "io_uring_setup": call(425, 1, 0),
    "modify_ldt": call(154, 1, ctypes.c_void_p(rw), 16),
    "msgget": call(68, 0, 0o1600),                 # IPC_PRIVATE, IPC_CREAT | 0600
    "semget": call(64, 0, 1, 0o1600),
    "shmget": call(29, 0, 4096, 0o1600),
    "mq_open": call(240, b"q", 0o100 | 2, 0o600, 0),   # O_CREAT | O_RDWR
    "i386_getpid": int80(),
}
threads = [threading.Thread(target=lambda: None) for _ in range(3)]
[t.start() for t in threads]
[t.join() for t in threads]
pid = os.fork()
if pid == 0:
    os._exit(3)
out["fork"] = os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1])
print(json.dumps(out))
"""


def test_filter_refuses_other_abis_namespaces_and_exec_memory():
    try:
        bpf = seccomp.filter_bytes()
    except seccomp.SeccompUnavailable as exc:
        pytest.skip(str(exc))
    isolation = Path(confine.__file__).parent
    done = subprocess.run([sys.executable, "-I", "-c", FILTER_PROBE, str(isolation), bpf.hex()],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout)
    eperm = [-1, errno.EPERM]
    for name in ("x32_getpid", "clone_newuser", "clone_newnet", "mprotect_exec", "ptrace", "bpf",
                 "personality", "io_uring_setup", "modify_ldt", "msgget", "semget", "shmget",
                 "mq_open"):
        assert out[name] == eperm, (name, out[name])
    assert out["clone3"] == [-1, errno.ENOSYS]        # glibc falls back to clone
    assert out["mprotect_rw"] == [0, 0]
    assert out["i386_getpid"] == -errno.EPERM          # refused, not the pid
    assert out["fork"] == 3                            # plain fork (clone) and threads work


# ------------------------------------------------------------------------------------------
# one list of allowed modules, stated in every notebook


def test_every_notebook_states_the_allowed_modules():
    import nbformat

    sentence = " ".join(allowlist.notebook_sentence().split())
    paths = sorted((REPO / "notebooks").glob("q*.ipynb"))
    assert len(paths) == 6
    for path in paths:
        first = nbformat.read(path, as_version=4).cells[0]
        assert first.cell_type == "markdown"
        assert sentence in " ".join(first.source.split()), path.name
    named = set(re_names(sentence))
    assert named == set(allowlist.ALLOWED_MODULES)


def re_names(text: str) -> list[str]:
    import re

    return [m for m in re.findall(r"`([a-z_.]+)`", text) if m != "rejected-code"]


def test_the_job_carries_the_list_the_policy_and_the_filter():
    from autograder.isolation import runner

    job = NotebookJob("j", "", [])
    doc = runner._job_document(job, Limits(), True, b"\0" * 16)
    assert doc["modules"] == list(allowlist.ALLOWED_MODULES)
    assert doc["filter"] == "AAAAAAAAAAAAAAAAAAAAAA=="
    # the grading policy travels in the job: the sandbox program holds none of its own
    assert doc["policy"]["course_modules"] == ["course_lib", "course_lib.marching_cubes",
                                               "course_lib.variants"]
    assert doc["policy"]["off_limits"] == allowlist.OFF_LIMITS


# ------------------------------------------------------------------------------------------
# the attack of the students' wheel, through the whole grader


def _wheel_members(names: tuple[str, ...]) -> dict[str, bytes]:
    """The compiled ``course_lib`` modules ``names`` from the real students' wheel."""
    import zipfile

    studentenv = pytest.importorskip("studentenv")
    with zipfile.ZipFile(studentenv.wheel()) as z:
        found = {Path(m).name.split(".")[0]: (m, z.read(m)) for m in z.namelist()
                 if m.startswith("course_lib/") and m.count("/") == 1 and m.endswith(".so")}
    return {found[n][0].split("/")[1]: found[n][1] for n in names}


WHEEL_LOADER = '''
import base64, os, sys
os.makedirs("/tmp/zz", exist_ok=True)
open("/tmp/zz/__init__.py", "w").close()
for _file, _text in zip(FILES, "".join(CHUNKS).split(",")):
    with open("/tmp/zz/" + _file, "wb") as _f:
        _f.write(base64.b85decode(_text))
sys.path.insert(0, "/tmp")
import zz, zz._validate
_cl = "course" + "_lib"            # the compiled module imports its helpers by their real name
_saved = {k: sys.modules.get(k) for k in (_cl, _cl + "._validate")}
sys.modules[_cl], sys.modules[_cl + "._validate"] = zz, zz._validate
try:
    import zz.shading as _shading
finally:
    for _k, _v in _saved.items():
        if _v is None:
            sys.modules.pop(_k, None)
        else:
            sys.modules[_k] = _v


def blinn_phong(colour, Ia, ka, Ip, kd, ks, n, L, N, V):
    return _shading.blinn_phong(colour, Ia, ka, Ip, kd, ks, n, L, N, V)
'''


def wheel_attack_notebook(src, members: dict[str, bytes]) -> dict:
    """Q5's release notebook whose ``blinn_phong`` runs the wheel's compiled ``shading``
    module: the modules as base85 text split across the earlier solution cells (each under the
    grader's 100 kB cap), written into ``/tmp/zz`` and imported (never as ``course_lib``)."""
    import base64

    from gradingtools import release_version

    nb = release_version(src)
    files = list(members)
    text = ",".join(base64.b85encode(members[f]).decode("ascii") for f in files)
    carriers = ["normalize", "reflect", "phong", "halfway"]
    size = -(-len(text) // len(carriers))
    chunks = [text[k * size:(k + 1) * size] for k in range(len(carriers))]
    cells = {c["metadata"].get("nbgrader", {}).get("grade_id"): c for c in nb["cells"]}
    for k, name in enumerate(carriers):
        cells[name]["source"] = f"_zz{k} = {chunks[k]!r}\n\n" + cells[name]["source"]
        assert len(cells[name]["source"].encode()) < 100_000
    cells["blinn_phong"]["source"] = (f"FILES = {files!r}\nCHUNKS = ["
                                      + ", ".join(f"_zz{k}" for k in range(len(carriers)))
                                      + "]\n" + WHEEL_LOADER)
    return nb


def test_the_wheels_compiled_module_carried_in_as_text_scores_zero(tmp_path):
    """Attack 1 of the threat model: without the filter and ``noexec`` this submission's
    ``blinn_phong`` passes every case (the wheel's own compiled reference answers it)."""
    from gradingtools import course_sources, read_grades, run_grade, write_nb

    src = next((s for s in course_sources() if s.name == "q5_phong"), None)
    if src is None:
        pytest.skip("no q5_phong source notebook")
    try:
        probe()
    except IsolationUnavailable as exc:
        pytest.skip(str(exc))
    nb = wheel_attack_notebook(src, _wheel_members(("_validate", "shading")))
    write_nb(tmp_path / "submitted" / "rt_wheel" / "tripos2006" / f"{src.name}.ipynb", nb,
             type_answers=False)
    run_grade(tmp_path / "submitted", tmp_path / "out", "--no-gradebook", "--reveal-hidden")
    row = read_grades(tmp_path / "out")[("rt_wheel", src.name, "test_blinn_phong")]
    assert (float(row["score"]), row["status"]) == (0.0, "rejected-code"), row
    assert "NumPy and the standard library modules listed in the notebook" in row["message"]
    page = (tmp_path / "out" / "feedback" / "rt_wheel" / f"{src.name}.html").read_text("utf-8")
    assert "rejected-code" in page and "/tmp/zz/" in page
