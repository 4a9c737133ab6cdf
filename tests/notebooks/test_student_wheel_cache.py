"""The students' wheel recompiles only what changed (issue 36: releases in a minute).

``autograder/student_setup.py`` keeps each compiled module under a digest of what its binary is
made from (``module_key``): its staged source, its name, its C flags, the build script, Cython,
the compiler and the interpreter. A build compiles only the modules it does not find in the
module cache; the generated data modules are compiled without optimisation. The build script is
played here on a two-module package: what it reports compiling is checked against which module
was edited, and each binary against what its source returns.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from autograder import student_bundle, student_setup

COMPILER = "cc\0gcc 12"


def test_a_module_key_changes_with_each_of_its_inputs_and_nothing_else():
    base = dict(name="course_lib.a", source=b"X = 1\n", flags=["-O1", "-g0"], compiler=COMPILER)
    key = student_setup.module_key(**base)
    assert student_setup.module_key(**base) == key
    for field, other in [("name", "course_lib.b"), ("source", b"X = 2\n"),
                         ("flags", ["-O0", "-g0"]), ("compiler", "cc\0gcc 13")]:
        assert student_setup.module_key(**{**base, field: other}) != key, field


def test_the_generated_data_modules_alone_are_compiled_without_optimisation():
    spec = student_bundle.bundle_spec()
    assert set(spec["init_only"]) == set(student_bundle.GENERATED_MODULES)
    assert set(spec["init_only"]) <= set(spec["compiled"])
    exts = {e.name: e for e in student_setup.extensions(spec["compiled"], spec["init_only"])}
    assert set(exts) == set(spec["compiled"])
    for name, ext in exts.items():
        level = "-O0" if name in student_bundle.GENERATED_MODULES else "-O1"
        assert level in ext.extra_compile_args and "-g0" in ext.extra_compile_args, name


def test_pruning_keeps_the_most_recently_used_binaries(tmp_path):
    import os

    for i in range(5):
        (tmp_path / f"{i}.so").write_bytes(b"x")
        os.utime(tmp_path / f"{i}.so", (1000 + i, 1000 + i))
    (tmp_path / ".torn.so.tmp").write_bytes(b"x")
    os.utime(tmp_path / ".torn.so.tmp", (1000, 1000))
    student_bundle.prune_module_cache(tmp_path, keep=2)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["3.so", "4.so"]


def _stage(root: Path, sources: dict[str, str], cache: Path) -> Path:
    """A staging folder as ``student_bundle.stage_sources`` writes one, for package ``pkg``."""
    shutil.rmtree(root, ignore_errors=True)
    (root / "pkg").mkdir(parents=True)
    (root / "pkg" / "__init__.py").write_text("")
    for name, text in sources.items():
        (root / "pkg" / f"{name}.py").write_text(text)
    shutil.copyfile(student_bundle.SETUP_SCRIPT, root / "setup.py")
    (root / "bundle.json").write_text(json.dumps({
        "packages": ["pkg"], "compiled": [f"pkg.{n}" for n in sources], "init_only": ["pkg.data"],
        "data_files": [], "module_cache": str(cache)}))
    return root


def _build(stage: Path) -> tuple[str, dict[str, object]]:
    """The build's report of what it compiled, and what each built module's ``value()`` gives."""
    proc = subprocess.run([sys.executable, "setup.py", "build_ext", "--inplace"], cwd=stage,
                          capture_output=True, text=True, timeout=900, check=False)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    report = [line for line in proc.stdout.splitlines() if line.startswith("compiling ")]
    assert report and (stage / "compiled.txt").read_text() == report[-1]
    for source in (stage / "pkg").glob("[!_]*.py"):
        source.unlink()      # the values below come from the binaries
    probe = subprocess.run(
        [sys.executable, "-c", "import json, pkg.code, pkg.data\n"
         "print(json.dumps([pkg.code.__file__, pkg.code.value(), pkg.data.value()]))"],
        cwd=stage, capture_output=True, text=True, timeout=120, check=False)
    assert probe.returncode == 0, probe.stderr[-2000:]
    where, code, data = json.loads(probe.stdout.strip().splitlines()[-1])
    assert where.endswith(".so"), where
    return report[-1], {"code": code, "data": data}


@pytest.mark.slow
def test_a_build_compiles_only_the_modules_whose_source_changed(tmp_path):
    cache = tmp_path / "modules"
    sources = {"code": "def value():\n    return 1\n", "data": "TABLE = [7] * 3\n\n"
               "def value():\n    return sum(TABLE)\n"}
    report, got = _build(_stage(tmp_path / "one", sources, cache))
    assert report.startswith("compiling 2 of 2 modules"), report
    assert got == {"code": 1, "data": 21}
    assert len(list(cache.glob("*.so"))) == 2

    report, got = _build(_stage(tmp_path / "two", sources, cache))
    assert report.startswith("compiling 0 of 2 modules"), report
    assert got == {"code": 1, "data": 21}

    sources["code"] = "def value():\n    return 2\n"
    report, got = _build(_stage(tmp_path / "three", sources, cache))
    assert report.startswith("compiling 1 of 2 modules"), report
    assert got == {"code": 2, "data": 21}       # the new code; the data module from the cache
    assert len(list(cache.glob("*.so"))) == 3


def test_compiler_flags_from_the_environment_change_the_compiler_identity(monkeypatch):
    monkeypatch.delenv("CFLAGS", raising=False)
    plain = student_setup.compiler_identity()
    monkeypatch.setenv("CFLAGS", "-g")      # debug information would reach the binaries
    assert student_setup.compiler_identity() != plain
