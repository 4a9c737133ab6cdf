"""The release's own guard on the students' wheel (``student_bundle.wheel_problems``), on forged
wheels: it passes one that holds only what students may get and names every kind of leak in one
that does not. Also: the wheel asks for the same versions as the instructors' ``pyproject.toml``.
(The real build is tested in ``test_student_bundle.py``.)"""

from __future__ import annotations

import sys
import zipfile
from pathlib import Path

import pytest

from autograder import student_bundle

REPO = Path(__file__).resolve().parents[2]
SO = ".cpython-311-x86_64-linux-gnu.so"
DIST_INFO = "4f9_course_student-0.1.0.dist-info"


def _library_modules() -> list[str]:
    """``course_lib`` module paths without ``.py``, read from the repository here."""
    return sorted(p.relative_to(REPO).with_suffix("").as_posix()
                  for p in (REPO / "course_lib").rglob("*.py") if "__pycache__" not in p.parts)


def _forge(path: Path, members: list[str]) -> Path:
    with zipfile.ZipFile(path, "w") as zf:
        for name in members:
            zf.writestr(name, b"x")
    return path


DATA = "4f9_course_student-0.1.0.data/data/etc/jupyter"


def _fit_members() -> list[str]:
    members = [f"{DIST_INFO}/METADATA", f"{DIST_INFO}/RECORD",
               f"{DATA}/labconfig/page_config.d/4f9-student.json",
               f"{DATA}/jupyter_server_config.d/zz-4f9-student.json"]
    for module in _library_modules():
        if module.replace("/", ".") in student_bundle.INSTRUCTORS_ONLY:
            continue
        readable = module.endswith("__init__") or module == "course_lib/answers"
        members.append(module + (".py" if readable else SO))
    return members


def test_guard_passes_a_wheel_with_compiled_modules_only(tmp_path):
    assert student_bundle.wheel_problems(_forge(tmp_path / "fit.whl", _fit_members())) == []


@pytest.mark.parametrize("extra, complaint", [
    ("course_lib/clipping.py", "source of a compiled module"),
    ("course_lib/widgets/clipping.py", "source of a compiled module"),
    ("course_lib/__pycache__/clipping.cpython-311.pyc", "bytecode"),
    ("course_lib/clipping.c", "source, bytecode"),
    ("course_lib/clipping.pyx", "source, bytecode"),
    ("autograder/exercises/q6_clipping.py", "not part of course_lib"),
    ("notebooks/q6_clipping.ipynb", "not part of course_lib"),
    ("course_lib/q6_clipping.ipynb", "notebook"),
    (f"{DATA}/jupyter_server_config.d/keys.json", "not part of course_lib"),
    ("4f9_course_student-0.1.0.data/scripts/clipping.py", "not part of course_lib"),
])
def test_guard_names_each_leak(tmp_path, extra, complaint):
    problems = student_bundle.wheel_problems(_forge(tmp_path / "leak.whl", _fit_members() + [extra]))
    assert any(extra in p and complaint in p for p in problems), problems


def test_guard_names_a_module_left_uncompiled(tmp_path):
    members = [m for m in _fit_members() if not m.startswith("course_lib/clipping.")]
    problems = student_bundle.wheel_problems(_forge(tmp_path / "short.whl", members))
    assert problems == ["course_lib.clipping: no compiled extension in the wheel"]


def test_guard_names_a_module_the_wheel_leaves_out(tmp_path):
    """``course_lib.mesh`` (the volume of Q3(d)) is instructors-only: in any form, it is a leak."""
    assert "course_lib.mesh" in student_bundle.INSTRUCTORS_ONLY
    for member in ("course_lib/mesh" + SO, "course_lib/mesh.py"):
        problems = student_bundle.wheel_problems(_forge(tmp_path / "extra.whl",
                                                        _fit_members() + [member]))
        assert f"{member}: a module the students' wheel leaves out" in problems, problems


@pytest.mark.skipif(sys.version_info < (3, 11), reason="tomllib")
def test_wheel_requirements_match_pyproject():
    import tomllib

    declared = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["dependencies"]
    wanted = {"numpy", "matplotlib", "ipywidgets", "ipympl", "anywidget", "jupyterlab", "nbgrader"}
    from packaging.requirements import Requirement

    expected = {Requirement(r).name: Requirement(r).specifier for r in declared
                if Requirement(r).name in wanted}
    got = {Requirement(r).name: Requirement(r).specifier
           for r in student_bundle.student_requirements()}
    assert got == expected and set(got) == wanted


def test_the_wheel_leaves_out_every_graded_function():
    from nbtools import graded_items, read

    from autograder.course import source_notebooks
    from autograder.exercises import REGISTRY

    graded = {(ex.reference.__module__, ex.reference.__qualname__)
              for ex in REGISTRY.values() if ex.kind == "function"}
    withheld = {(m, n) for m, names in student_bundle.withheld_functions().items() for n in names}
    # the count of functions the notebooks grade, not a number typed here (autograder/facts.py)
    in_notebooks = [name for path in source_notebooks()
                    for name, kind in graded_items(read(path)).items() if kind == "function"]
    assert len(graded) == len(in_notebooks) > 0 and withheld == graded


def test_left_out_functions_go_with_their_decorators_and_all_entries():
    text = ('"""Doc: see :func:`gone`."""\nimport functools\n__all__ = [\n    "kept",\n'
            '    "gone",\n]\n\n\n@functools.lru_cache\ndef gone(x):\n    return x + 1\n\n\n'
            'def kept(x):\n    return 2 * x\n')
    out = student_bundle.without_functions(text, {"gone"})
    namespace = {}
    exec(compile(out, "m", "exec"), namespace)
    assert namespace["__all__"] == ["kept"] and namespace["kept"](2) == 4
    assert "gone" not in namespace and "see :func:`gone`" in out
    with pytest.raises(ValueError, match="still named"):
        student_bundle.without_functions(text + "\nalias = gone\n", {"gone"})
    with pytest.raises(ValueError, match="no top-level function"):
        student_bundle.without_functions(text, {"absent"})


def test_staged_library_imports_without_the_left_out_functions(tmp_path):
    """The staged sources (what Cython compiles) import, as pure Python, with every module,
    and none of them defines a left-out function."""
    import subprocess

    stage = student_bundle.stage_sources(tmp_path, "0" * 64)
    withheld = student_bundle.left_out()          # graded functions and their helpers
    assert "marching_cubes_loop" in withheld["course_lib.marching_cubes"]
    assert not (stage / "course_lib" / "mesh.py").exists()
    code = ("import importlib, json, pkgutil, sys, course_lib\n"
            "assert course_lib.__file__.startswith(sys.argv[1]), course_lib.__file__\n"
            "mods = [m.name for m in pkgutil.walk_packages(course_lib.__path__, 'course_lib.')]\n"
            "found = {m: sorted(n for n in json.loads(sys.argv[2]).get(m, [])\n"
            "                   if hasattr(importlib.import_module(m), n)) for m in mods}\n"
            "print(json.dumps({m: f for m, f in found.items() if f}))\n")
    proc = subprocess.run([sys.executable, "-c", code, str(stage), __import__("json").dumps(withheld)],
                          cwd=stage, capture_output=True, text=True, timeout=300,
                          env={"MPLBACKEND": "Agg", "PATH": "/usr/bin:/bin"}, check=False)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert proc.stdout.strip().splitlines()[-1] == "{}"


def test_staging_refuses_a_module_that_uses_a_function_left_out_elsewhere(tmp_path, monkeypatch):
    """``collimator_resolution`` is drawn by the q2 figures and explorer, in other modules: left
    out without their routines in ``INLINE_INTO``, the build stops with their name instead of
    shipping an explorer that fails to load."""
    monkeypatch.setattr(student_bundle, "withheld_functions",
                        lambda: {"course_lib.gamma_camera": ("collimator_resolution",)})
    monkeypatch.setattr(student_bundle, "LEFT_OUT_HELPERS", {})
    monkeypatch.setattr(student_bundle, "INLINE_INTO", {})
    with pytest.raises(ValueError, match=r"gamma_camera\.py names \['collimator_resolution'\]"):
        student_bundle.stage_sources(tmp_path, "0" * 64)


def test_staging_refuses_a_module_that_imports_an_instructors_only_module(tmp_path, monkeypatch):
    """Were the tables instructors-only, the march's module (which imports them) could not ship:
    the build names it instead of shipping a module that fails to import."""
    monkeypatch.setattr(student_bundle, "INSTRUCTORS_ONLY",
                        (*student_bundle.INSTRUCTORS_ONLY, "course_lib._mc_tables"))
    with pytest.raises(ValueError, match=r"marching_cubes\.py imports \['course_lib\._mc_tables"):
        student_bundle.stage_sources(tmp_path, "0" * 64)
