"""What students install, as ``python -m autograder release --out DIR`` writes it (issue 11).

- ``DIR/student/`` holds exactly one wheel and a README that says how to install it;
- the wheel holds ``course_lib``, its metadata and two Jupyter config files only: no
  ``autograder``, no notebook, and no Python source, bytecode or C of any compiled module (read
  from the zip itself, not from the builder's own check);
- no file of the wheel holds a solution cell's code, a model answer of a manually graded cell
  or a multiple-choice key (the byte search is shown to work on each module's docstring);
- installed alone in a fresh virtual environment, the wheel exposes none of the graded
  functions (``student_bundle.withheld_functions``: all of them), and the routines that draw
  with their C-level copies (``INLINE_INTO``) keep their docstrings and signatures, but neither
  ``inspect.getsource`` nor IPython's ``??`` finds their source (the same probe does find it in
  the instructors' copy);
- every release notebook runs in that environment (kernel included) with no error but a stub's;
- in that environment nbgrader's instructor tools are off (its own Jupyter config), Validate on.
"""

from __future__ import annotations

import ast
import json
import re
import shutil
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path

import pytest
import studentenv
from nbtools import CELL_TIMEOUT, errors, errors_beyond_stubs, graded_items, nbgrader_meta, read

from autograder import student_bundle
from autograder.course import ASSIGNMENT, nbgrader_env, source_notebooks

NOTEBOOKS = source_notebooks()
pytestmark = [
    pytest.mark.skipif(not NOTEBOOKS, reason="no notebooks/q*.ipynb yet"),
    pytest.mark.skipif(shutil.which("gcc") is None, reason="no C compiler (make wheel-deps)"),
    pytest.mark.slow,
    # one worker builds the wheel and the environment; the browser test waits on the same lock
    pytest.mark.xdist_group("student_env"),
]
#: modules students may read as source (package markers and the answer *format* checker)
READABLE = {"course_lib/__init__.py", "course_lib/plots/__init__.py",
            "course_lib/widgets/__init__.py", "course_lib/answers.py",
            "course_lib/variants.py"}


@pytest.fixture(scope="module")
def bundle(tmp_path_factory, course, repo_root):
    """``OUT`` of ``python -m autograder release --out OUT`` (the wheel from the test cache)."""
    out = tmp_path_factory.mktemp("student_release")
    proc = subprocess.run(
        [sys.executable, "-m", "autograder", "release", "--out", str(out),
         "--course-root", str(course.root), "--build-cache", str(studentenv.BUILD_CACHE)],
        cwd=repo_root, env=nbgrader_env(), capture_output=True, text=True, timeout=1800,
        check=False,
    )
    assert proc.returncode == 0, f"release failed:\n{proc.stdout}\n{proc.stderr[-4000:]}"
    return out


@pytest.fixture(scope="module")
def wheel(bundle) -> Path:
    wheels = sorted((bundle / "student").glob("*.whl"))
    assert len(wheels) == 1, wheels
    return wheels[0]


@pytest.fixture(scope="module")
def members(wheel) -> dict[str, bytes]:
    with zipfile.ZipFile(wheel) as zf:
        return {name: zf.read(name) for name in zf.namelist()}


@pytest.fixture(scope="module")
def student_python(wheel) -> Path:
    return studentenv.python(wheel)


def graded_references() -> dict[str, tuple[str, str]]:
    """``{exercise: (module, qualname)}`` of every graded function's reference (the wheel
    leaves every one out)."""
    from autograder.exercises import REGISTRY

    refs = {n: (ex.reference.__module__, ex.reference.__qualname__)
            for n, ex in REGISTRY.items() if ex.kind == "function"}
    assert refs and all(m.startswith("course_lib.") for m, _ in refs.values()), refs
    return refs


def inlined_routines() -> dict[str, tuple[str, str]]:
    """``{module.qualname: (module, qualname)}`` of the routines that draw with C-level copies
    of graded functions (``student_bundle.INLINE_INTO``): the compiled code that holds maths."""
    refs = {f"{m}.{q}": (m, q) for m, names in student_bundle.INLINE_INTO.items() for q in names}
    assert refs, "no routine draws with a left-out function"
    return refs


def test_release_writes_wheel_and_readme(bundle, wheel):
    assert sorted(p.name for p in bundle.iterdir()) == sorted([ASSIGNMENT, "student"])
    assert sorted(p.name for p in (bundle / "student").iterdir()) == sorted(["README.md", wheel.name])
    assert [p.name for p in sorted((bundle / ASSIGNMENT).iterdir())] == [p.name for p in NOTEBOOKS]
    readme = (bundle / "student" / "README.md").read_text()
    assert f"pip install {wheel.name}" in readme
    assert "Validate" in readme and "YOUR CODE HERE" in readme


def test_wheel_holds_no_source_key_or_grader(members):
    names = sorted(members)
    tops = {n.split("/", 1)[0] for n in names}
    assert {t for t in tops if not t.endswith((".dist-info", ".data"))} == {"course_lib"}, tops
    data = [n.split("/", 1)[1] for n in names if n.split("/", 1)[0].endswith(".data")]
    assert all(re.fullmatch(r"data/etc/jupyter/[\w./-]+\.d/[\w.-]+\.json", n) for n in data), data
    sources = {n for n in names if n.endswith(".py")}
    assert sources == READABLE, f"Python source beyond the readable modules: {sources - READABLE}"
    bad = [n for n in names if re.search(r"\.(pyc|pyo|c|cpp|h|pyx|pxd|ipynb)$", n)
           or "__pycache__" in n or "autograder" in n or "notebooks/" in n]
    assert not bad, bad
    # every module of the instructors' course_lib is there, compiled unless readable, but the
    # instructors-only ones, which are not there in any form
    repo = studentenv.REPO
    for path in (repo / "course_lib").rglob("*.py"):
        rel = path.relative_to(repo).as_posix()
        stem = rel[:-3]
        if stem.replace("/", ".") in student_bundle.INSTRUCTORS_ONLY:
            assert not any(n.startswith(stem + ".") for n in names), rel
            continue
        if rel in READABLE:
            continue
        assert any(n.startswith(stem + ".") and n.endswith(".so") for n in names), rel


def _solution_lines() -> set[str]:
    """Distinctive code lines of every solution region of the source notebooks."""
    lines = set()
    for path in NOTEBOOKS:
        for cell in read(path).cells:
            inside = False
            for line in cell.source.splitlines():
                text = line.strip()
                if text.startswith("### BEGIN SOLUTION"):
                    inside = True
                elif text.startswith("### END SOLUTION"):
                    inside = False
                elif inside and len(text) >= 25 and not text.startswith("#"):
                    lines.add(text)
    return lines


def _model_answer_sentences() -> set[str]:
    """Sentences (40 characters or more) of the manually graded cells' model answers."""
    sentences = set()
    for path in NOTEBOOKS:
        for cell in read(path).cells:
            meta = nbgrader_meta(cell)
            if cell.cell_type == "markdown" and meta.get("solution") and meta.get("grade"):
                for piece in re.split(r"(?<=[.!?])\s+|\n", cell.source):
                    if len(piece.strip()) >= 40:
                        sentences.add(piece.strip())
    return sentences


def _choice_keys() -> set[str]:
    """Each multiple-choice item's registry description, which says what its key is (the
    item's name alone is no needle: ``course_lib.item_options`` ships each item's options,
    without keys, under its name)."""
    from autograder.exercises import REGISTRY

    return {ex.description for ex in REGISTRY.values()
            if ex.kind == "choice" and len(ex.description) >= 20}


def test_no_file_holds_a_solution_a_model_answer_or_a_key(members):
    needles = _solution_lines() | _model_answer_sentences() | _choice_keys()
    assert len(needles) > 50, "too few needles: the notebooks changed shape?"
    found = [(name, needle[:60]) for name, data in members.items() for needle in needles
             if needle.encode() in data]
    assert not found, f"instructor material in the wheel: {found[:5]}"
    for marker in (b"BEGIN SOLUTION", b"HIDDEN TESTS", b"autograder.incell", b"answer="):
        assert not [n for n, d in members.items() if marker in d], marker


def test_byte_search_finds_docstrings_in_compiled_modules(members):
    """The search above can see into the extension modules: each one's docstrings are there."""
    import importlib

    for name, data in members.items():
        if not name.endswith(".so"):
            continue
        dotted = name.split(".", 1)[0].replace("/", ".")
        module = importlib.import_module(dotted)
        if dotted in student_bundle.GENERATED_MODULES:   # its students' text is generated
            doc = ast.get_docstring(ast.parse(module.students_copy()))
        else:
            doc = module.__doc__
        first = (doc or "").strip().splitlines()
        assert first, f"{name}: the instructors' module has no docstring"
        assert first[0].encode() in data, f"{name}: module docstring not found in the binary"


def _probe_sources(targets):
    """For each ``(module, qualname)``: what the usual tools find of the object's source.

    Runs in the student environment (sent there as source) and, as a control, here.
    """
    import importlib
    import inspect

    from IPython.core import oinspect

    report = {}
    for module_name, qualname in targets:
        module = importlib.import_module(module_name)
        obj = module
        for part in qualname.split("."):
            obj = getattr(obj, part)
        found = []
        for target in (obj, getattr(obj, "__code__", None), module):
            try:
                found.append(inspect.getsource(target)[:80])
            except (OSError, TypeError):
                pass
        ipython_source = oinspect.getsource(obj)  # what ``name??`` shows
        if ipython_source:
            found.append(ipython_source[:80])
        report[f"{module_name}.{qualname}"] = {
            "file": module.__file__, "doc": inspect.getdoc(obj) or "",
            "signature": str(inspect.signature(obj)), "found": found,
        }
    return report


def test_student_env_has_no_left_out_reference(student_python, tmp_path):
    refs = graded_references()
    code = ("import importlib, json, sys\n"
            "refs = json.loads(sys.argv[1])\n"
            "found, absent = [], set()\n"
            "for m, q in refs:\n"
            "    try:\n"
            "        if hasattr(importlib.import_module(m), q):\n"
            "            found.append(m + '.' + q)\n"
            "    except ModuleNotFoundError:\n"
            "        absent.add(m)\n"
            "print(json.dumps([found, sorted(absent)]))\n")
    proc = studentenv.run(code, json.dumps(sorted(set(refs.values()))), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    found, absent = json.loads(proc.stdout.strip().splitlines()[-1])
    assert found == []
    # only the instructors-only modules are missing (course_lib.mesh, all of Q3(d))
    assert set(absent) == {m for m, _ in refs.values()} & set(student_bundle.INSTRUCTORS_ONLY)


def test_student_env_hides_the_source_of_every_inlined_routine(student_python, tmp_path):
    refs = inlined_routines()
    code = textwrap.dedent(__import__("inspect").getsource(_probe_sources)) + (
        "\nimport json, sys\n"
        "print(json.dumps(_probe_sources(json.loads(sys.argv[1]))))\n")
    proc = studentenv.run(code, json.dumps(sorted(set(refs.values()))), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    student = json.loads(proc.stdout.strip().splitlines()[-1])
    here = _probe_sources(sorted(set(refs.values())))  # the instructors' copy: sources found
    site = studentenv.site_packages()
    for name, (module, qualname) in refs.items():
        key = f"{module}.{qualname}"
        got = student[key]
        assert Path(got["file"]).resolve().is_relative_to(site), got["file"]
        assert got["file"].endswith(".so"), f"{name}: {got['file']} is not compiled"
        assert got["found"] == [], f"{name}: source readable in the student env: {got['found']}"
        assert here[key]["found"], f"{name}: the probe finds no source even in the repository"
        assert got["doc"] and got["doc"].endswith(here[key]["doc"][-200:]), \
            f"{name}: docstring lost"
        assert got["signature"] == here[key]["signature"], name


@pytest.mark.timeout(1800)
def test_release_notebooks_run_in_student_env(bundle, student_python, tmp_path):
    work = tmp_path / ASSIGNMENT
    shutil.copytree(bundle / ASSIGNMENT, work)
    code = textwrap.dedent(f"""
        import sys, nbformat
        from nbclient import NotebookClient
        work, paths = sys.argv[1], sys.argv[2:]
        for path in paths:
            nb = nbformat.read(path, as_version=4)
            nb.cells.append(nbformat.v4.new_code_cell(
                "import sys, course_lib; print(sys.executable); print(course_lib.__file__)"))
            NotebookClient(nb, timeout={CELL_TIMEOUT}, kernel_name="python3", allow_errors=True,
                           resources={{"metadata": {{"path": work}}}}).execute()
            nbformat.write(nb, path + ".out")
        """)
    paths = [str(work / p.name) for p in NOTEBOOKS]
    proc = studentenv.run(code, str(work), *paths, cwd=work, timeout=1800)
    assert proc.returncode == 0, proc.stderr[-4000:]
    site = studentenv.site_packages()
    problems = []
    for source in NOTEBOOKS:
        nb = read(Path(str(work / source.name) + ".out"))
        where = "".join(o.get("text", "") for o in nb.cells[-1].outputs).split()
        assert len(where) == 2, where
        assert Path(where[0]).parent.parent.resolve() == studentenv.ENV_DIR.resolve(), where
        assert Path(where[1]).resolve().is_relative_to(site), where
        found = errors(nb)
        problems += [f"{source.stem}: {e}" for e in errors_beyond_stubs(found)]
        failed = {e.grade_id for e in found}
        passing = [n for n in graded_items(read(source)) if f"test_{n}" not in failed]
        problems += [f"{source.stem}: test_{n} passes on the stub" for n in passing]
    assert not problems, "\n".join(problems)


def test_student_env_switches_off_instructor_tools(student_python, tmp_path):
    """Installing the wheel is enough to get the student view of nbgrader: the Formgrader, Create
    Assignment and Course List are off in the environment's own Jupyter config (read back with
    Jupyter's config readers); Validate and the Assignments list stay on."""
    code = textwrap.dedent("""
        import json, sys
        from jupyter_server.extension.config import ExtensionConfigManager
        from jupyterlab_server.config import get_static_page_config
        etc = sys.prefix + "/etc/jupyter"
        server = ExtensionConfigManager(read_config_path=[etc]).get_jpserver_extensions()
        page = get_static_page_config(level="sys_prefix")
        print(json.dumps({"server": server, "disabled": page.get("disabledExtensions", {})}))
        """)
    proc = studentenv.run(code, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    got = json.loads(proc.stdout.strip().splitlines()[-1])
    server, disabled = got["server"], got["disabled"]
    for ext in ("formgrader", "course_list"):
        assert server.get(f"nbgrader.server_extensions.{ext}") is False, server
    for ext in ("validate_assignment", "assignment_list"):
        assert server.get(f"nbgrader.server_extensions.{ext}") is True, server
    for plugin in ("formgrader", "create-assignment", "course-list"):
        assert disabled.get(f"@jupyter/nbgrader:{plugin}") is True, disabled
    for plugin in ("validate-assignment", "assignment-list"):
        assert not disabled.get(f"@jupyter/nbgrader:{plugin}"), disabled
