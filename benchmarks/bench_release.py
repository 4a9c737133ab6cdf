"""Release and ``make lab`` times: cold, warm and one-module releases, lab to first notebook.

Each row runs this tree's code ("ours") and a git revision's ("peer", default ``main``: the code
before the per-module wheel cache), each from a fresh export of its tree (``git archive``: no
``course/``, no build cache, no students' environment, as after a clone), with the instructors'
environment this one runs in (``.venv`` is the same for both and not timed). Rows:

- **cold release**: ``python -m autograder release --out OUT`` on the fresh tree (nbgrader's
  release and every module of the students' wheel compiled);
- **warm release**: the same command again, nothing changed (the cached wheel is reused);
- **one-module release**: again after one line of one module's docstring changed
  (:data:`EDITED`), which changes that module's students' copy alone;
- **lab to first notebook**: ``python -m autograder lab --role student --student-env ENV`` on
  another fresh tree, until the first notebook can be opened (the server answers the contents
  API for it); ours opens before its wheel is built, so the time until that wheel is installed
  is noted too.

The machine's load average is noted with each row: these are minutes of two shared cores.
``AUTOGRADER_BENCH_PEER`` names another revision for the peer.
"""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

from .harness import REPO, Row

SECTION = "release"
#: the module a one-module release edits, and the docstring line it changes
EDITED = ("course_lib/plotting.py", '"""')
PEER = os.environ.get("AUTOGRADER_BENCH_PEER", "main")
TIMEOUT = 3600


def _export(rev: str, where: Path) -> Path:
    """The tree of ``rev`` (``HEAD``'s for ours, with this tree's uncommitted files on top)."""
    where.mkdir(parents=True)
    archive = subprocess.run(["git", "archive", rev], cwd=REPO, capture_output=True, check=True)
    subprocess.run(["tar", "-x", "-C", str(where)], input=archive.stdout, check=True)
    return where


def _env(tree: Path) -> dict:
    from autograder.course import nbgrader_env

    env = nbgrader_env()
    env["PYTHONPATH"] = str(tree)            # the tree's autograder and course_lib, not .venv's
    env.pop("AUTOGRADER_COURSE_CACHE", None)
    return env


def _load() -> str:
    return f"load {os.getloadavg()[0]:.1f}"


def _release(tree: Path) -> float:
    """Seconds of one ``release --out`` in ``tree``."""
    out = tree / "dist"
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "autograder", "release", "--out", str(out)],
                          cwd=tree, env=_env(tree), capture_output=True, text=True,
                          timeout=TIMEOUT, check=False)
    elapsed = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"release in {tree} failed: {proc.stderr[-2000:]}")
    return elapsed


def _edit_one_module(tree: Path) -> None:
    path = tree / EDITED[0]
    text = path.read_text(encoding="utf-8")
    path.write_text(text.replace(EDITED[1], EDITED[1] + "(Edited for the benchmark.) ", 1),
                    encoding="utf-8")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _lab(tree: Path) -> tuple[float, float | None]:
    """Seconds until ``make lab``'s command serves the first notebook, and (ours) until it says
    the wheel is installed (``None`` when it never said so: the peer installs it first)."""
    port, token = _free_port(), "bench"
    log = tree / "lab.log"
    url = (f"http://127.0.0.1:{port}/api/contents/tripos2006/q1_imaging.ipynb?content=0"
           f"&token={token}")
    t0 = time.perf_counter()
    with open(log, "w") as err:
        proc = subprocess.Popen(
            [sys.executable, "-m", "autograder", "lab", "--role", "student", "--student-env",
             str(tree / ".venv-student"), "--port", str(port), "--token", token, "--no-browser"],
            cwd=tree, env=_env(tree), stdout=subprocess.DEVNULL, stderr=err)
    try:
        shown = ready = None
        while time.perf_counter() - t0 < TIMEOUT and proc.poll() is None:
            if shown is None:
                try:
                    with urllib.request.urlopen(url, timeout=5) as answer:
                        if answer.status == 200:
                            shown = time.perf_counter() - t0
                except OSError:
                    pass
            said = log.read_text(errors="replace")
            if shown is not None and ("ready: the students' wheel" in said
                                      or "waiting for the students' wheel" not in said):
                ready = time.perf_counter() - t0 if "ready:" in said else None
                break
            time.sleep(1)
        if shown is None:
            raise RuntimeError(f"lab in {tree} showed no notebook: {log.read_text()[-2000:]}")
        return shown, ready
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=60)
        except subprocess.TimeoutExpired:
            proc.kill()


def run(smoke: bool = False) -> list[Row]:
    if smoke:   # the lookup a warm release starts with, on an empty build cache
        from autograder import student_bundle

        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            assert student_bundle.cached_wheel(Path(tmp)) is None
            took = time.perf_counter() - t0
        return [Row(SECTION, "smoke", "cached-wheel lookup", took, unit="s",
                    notes="smoke: nothing built")]
    rows = []
    with tempfile.TemporaryDirectory(prefix="4f9-bench-release-") as tmp:
        trees = {"ours": _export("HEAD", Path(tmp) / "ours"),
                 "peer": _export(PEER, Path(tmp) / "peer")}
        times: dict[str, dict[str, tuple[float, str]]] = {"ours": {}, "peer": {}}
        for who, tree in trees.items():
            print(f"  {who}: cold, warm, one-module release ({_load()})", file=sys.stderr,
                  flush=True)
            times[who]["cold"] = (_release(tree), _load())
            times[who]["warm"] = (_release(tree), _load())
            _edit_one_module(tree)
            times[who]["one module"] = (_release(tree), _load())
        for case in ("cold", "warm", "one module"):
            (ours, load_o), (peer, load_p) = times["ours"][case], times["peer"][case]
            rows.append(Row(SECTION, f"{case} release", "wall time", ours, peer, PEER, "s",
                            f"ours at {load_o}, {PEER} at {load_p}"))
        labs = {}
        for who, rev in (("ours", "HEAD"), ("peer", PEER)):
            print(f"  {who}: lab to first notebook ({_load()})", file=sys.stderr, flush=True)
            try:
                labs[who] = (*_lab(_export(rev, Path(tmp) / f"lab-{who}")), _load())
            except (OSError, RuntimeError, subprocess.SubprocessError) as exc:
                print(f"  {who}: lab failed: {exc}", file=sys.stderr, flush=True)
                labs[who] = (float("nan"), None, _load())
        (shown_o, ready_o, load_o), (shown_p, _, load_p) = labs["ours"], labs["peer"]
        wheel = f"; ours' wheel installed at {ready_o:.0f} s" if ready_o else ""
        rows.append(Row(SECTION, "make lab, fresh tree", "to first notebook", shown_o, shown_p,
                        PEER, "s", f"ours at {load_o}, {PEER} at {load_p}{wheel}"))
        shutil.rmtree(tmp, ignore_errors=True)
    return rows
