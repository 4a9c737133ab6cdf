"""The sandbox on its own: one graded name, hand-written cells, no notebook needed.

Each test runs a tiny "student" function through :func:`autograder.sandbox.run_job` and checks
what the grader observes against what the operating system and Python promise: the uid the
child runs as (when the tests run as root), the limits it carries, the files it can reach, and
that a crash or a hang keeps the cases before it.
"""

from __future__ import annotations

import os
import tempfile
import time

import numpy as np
import pytest

from autograder import sandbox

pytestmark = [pytest.mark.xdist_group("grading")]

CASES = [((np.arange(3.0),), {}), ((2.0,), {}), ((-1.5,), {}), ((np.eye(2),), {})]


@pytest.fixture(scope="module")
def workdir():
    d = tempfile.mkdtemp(prefix="4f9-sandbox-test-")
    os.chmod(d, 0o711)
    yield d
    import shutil

    shutil.rmtree(d, ignore_errors=True)


@pytest.fixture(scope="module", params=["fresh", "zygote"])
def launcher(request):
    if request.param == "fresh":
        yield None
    else:
        z = sandbox.Zygote(["textwrap"])
        yield z
        z.close()


def run(workdir, launcher, code, cases=CASES, timeout=1.0, **limits):
    job = sandbox.SandboxJob(
        name="f", kind="function", setup_source="import numpy as np\nimport textwrap\n",
        cells=[("f", code)], cases=cases, reference_targets=[("textwrap", "dedent")],
        graded_names=["dedent"], protected_prefixes=["textwrap"],
        deny_paths=sandbox.protected_dirs())
    lim = sandbox.Limits(case_timeout=timeout, load_timeout=20, **limits)
    return sandbox.run_job(job, lim, workdir, slot=3, zygote=launcher)


def test_plain_results_come_back_exactly(workdir, launcher):
    r = run(workdir, launcher, "def f(x):\n    return x * x\n")
    assert [o.kind for o in r.outcomes] == ["returned"] * 4
    np.testing.assert_array_equal(r.outcomes[0].value, [0.0, 1.0, 4.0])
    assert r.outcomes[1].value == 4.0 and type(r.outcomes[1].value) is float
    assert type(r.outcomes[3].value) is np.ndarray and r.outcomes[3].value.shape == (2, 2)


def test_objects_are_rejected_not_compared(workdir, launcher):
    code = ("class E:\n    def __eq__(self, other): return True\n"
            "def f(x):\n    return E()\n")
    r = run(workdir, launcher, code)
    assert {o.kind for o in r.outcomes} == {"rejected"}
    assert "object of type E" in r.outcomes[0].message


@pytest.mark.skipif(os.name != "posix" or os.geteuid() != 0, reason="uid drop needs root")
def test_runs_as_an_unprivileged_uid_with_limits(workdir, launcher):
    code = ("import os, resource\n"
            "def f(x):\n"
            "    return (os.getuid(), os.geteuid(), os.getgid(), len(os.getgroups()),\n"
            "            resource.getrlimit(resource.RLIMIT_AS)[0],\n"
            "            resource.getrlimit(resource.RLIMIT_FSIZE)[0],\n"
            "            resource.getrlimit(resource.RLIMIT_NPROC)[0],\n"
            "            os.environ.get('OPENBLAS_NUM_THREADS'), sorted(os.environ) == sorted(\n"
            "            ['PATH','HOME','TMPDIR','LANG','LC_ALL','MPLBACKEND','MPLCONFIGDIR',\n"
            "             'OPENBLAS_NUM_THREADS','OMP_NUM_THREADS','MKL_NUM_THREADS',\n"
            "             'NUMEXPR_NUM_THREADS','VECLIB_MAXIMUM_THREADS']))\n")
    r = run(workdir, launcher, code, cases=CASES[:1], memory_mb=1500, fsize_mb=7, nproc=33)
    uid, euid, gid, ngroups, mem, fsize, nproc, blas, scrubbed = r.outcomes[0].value
    assert uid == euid == sandbox.SANDBOX_UID_BASE + 3 and gid == sandbox.SANDBOX_GID
    assert ngroups <= 1
    assert mem == 1500 * 2**20 and fsize == 7 * 2**20 and nproc == 33
    assert blas == "1" and scrubbed


def test_private_files_cannot_be_read(workdir, launcher, tmp_path):
    secret = tmp_path / "secret"
    secret.write_text("s3cret")
    code = ("def f(x):\n"
            "    out = []\n"
            f"    for p in [{str(secret)!r}, '/etc/passwd', {sandbox.__file__!r}]:\n"
            "        try:\n"
            "            open(p).read(); out.append('read')\n"
            "        except PermissionError:\n"
            "            out.append('denied')\n"
            "    return ' '.join(out)\n")
    r = run(workdir, launcher, code, cases=CASES[:1])
    assert r.outcomes[0].value == "denied denied denied"


def test_reference_is_stubbed(workdir, launcher):
    code = "from textwrap import dedent\ndef f(x):\n    return dedent('  x')\n"
    r = run(workdir, launcher, code, cases=CASES[:2])
    assert [o.kind for o in r.outcomes] == ["reference-used"] * 2


def test_exit_and_kill_are_contained(workdir, launcher):
    code = "import os, sys\ndef f(x):\n    os._exit(3)\n"
    r = run(workdir, launcher, code, cases=CASES[:2])
    assert [o.kind for o in r.outcomes] == ["raised", "raised"]
    assert r.outcomes[0].error_type == "SystemExit" and r.launches == 1


def test_a_crash_keeps_the_earlier_cases(workdir, launcher):
    code = ("import signal\nn = 0\n"
            "def f(x):\n    global n\n    n += 1\n"
            "    if n == 2:\n        signal.raise_signal(signal.SIGKILL)\n    return x\n")
    r = run(workdir, launcher, code)
    kinds = [o.kind for o in r.outcomes]
    # process 1: case 0 ok, case 1 killed; process 2 restarts at case 2: ok, then case 3 killed
    assert kinds == ["returned", "crashed", "returned", "crashed"]
    assert "SIGKILL" in r.outcomes[1].message and r.launches == 2


def test_a_hang_costs_bounded_time(workdir, launcher):
    code = "def f(x):\n    while True:\n        pass\n"
    t0 = time.monotonic()
    r = run(workdir, launcher, code, cases=CASES * 2, timeout=0.5)
    assert {o.kind for o in r.outcomes} == {"timeout"}
    # three cases in a row time out, the rest are not run
    assert time.monotonic() - t0 < 3 * 0.5 + 10
    assert "not run" in r.outcomes[-1].message


def test_output_is_captured_and_capped(workdir, launcher):
    code = ("import sys, warnings\n"
            "def f(x):\n    for k in range(100000):\n        print('line', k)\n"
            "    warnings.warn('careful')\n    return 1.0\n")
    r = run(workdir, launcher, code, cases=CASES[:1], output_bytes=5000)
    assert r.outcomes[0].kind == "returned"
    assert len(r.stdout) < 5400
    assert "truncated" in r.stdout
    assert "careful" in r.stderr


def test_no_process_can_be_started(workdir, launcher):
    code = ("import os, subprocess, sys\n"
            "def f(x):\n"
            "    tried = []\n"
            "    for attempt in (lambda: subprocess.run(['true']), lambda: os.system('true'),\n"
            "                    lambda: os.fork(), lambda: os.execv('/bin/true', ['true']),\n"
            "                    lambda: sys.modules['_posixsubprocess'].fork_exec):\n"
            "        try:\n"
            "            attempt()\n"
            "            tried.append('started')\n"
            "        except (PermissionError, AttributeError):\n"
            "            tried.append('blocked')\n"
            "    return ' '.join(tried)\n")
    r = run(workdir, launcher, code, cases=CASES[:1])
    assert r.outcomes[0].value == "blocked blocked blocked blocked blocked"
