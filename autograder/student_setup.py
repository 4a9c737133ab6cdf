"""``setup.py`` of the students' wheel (copied into a staging folder by ``student_bundle``).

Not imported by the package: :func:`autograder.student_bundle.build_wheel` copies this file as
``setup.py`` beside a copy of ``course_lib/`` and a ``bundle.json`` naming the modules to compile,
then runs ``pip wheel --no-build-isolation`` on that folder with the instructors' interpreter
(which has setuptools and Cython). Each listed module becomes a Cython extension; its ``.py``
is left out of the wheel (``build_py`` below skips it) and no ``.c`` is packaged.

Compiling is most of a release's time (about 50 s of Cython and 95 s of gcc at ``-O1``, CPU
seconds, for 42 modules), so :class:`CachedBuildExt` keeps each compiled module in
``bundle.json``'s ``module_cache`` folder under :func:`module_key`, a digest of everything its
binary is made from (its staged source, its name, this script, Cython, the compiler and the
interpreter), and compiles only the modules it does not find there, on every core, the
slowest first. The generated data modules (``init_only``) only build constants, once, at
import, and gcc spent 16 s optimising the initialisation function of ``_mc_tables`` alone
against 2 s compiling it at ``-O0``: they are compiled at ``-O0``. The code students' explorers
run on every redraw stays at ``-O1`` (all at ``-O0`` would save about 45 more CPU seconds).
"""

import copy
import hashlib
import json
import os
import shutil
import subprocess
import sys
import sysconfig
import uuid
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext
from setuptools.command.build_py import build_py

#: what to build, written by ``student_bundle``: {"packages", "compiled", "init_only",
#: "data_files", "module_cache"}
BUNDLE_FILE = Path(__file__).resolve().parent / "bundle.json"
#: how many modules the build compiled and took from the module cache, for ``student_bundle``
REPORT_FILE = BUNDLE_FILE.with_name("compiled.txt")

#: docstrings stay (students read them with ``?``); no debug info, no source comments in the .so
CYTHON_DIRECTIVES = {
    "language_level": 3,
    "binding": True,            # inspect.signature and ``?`` show the real signature
    "embedsignature": True,
    "annotation_typing": False,  # plain Python semantics: ``x: int`` must not become a C int
    "emit_code_comments": False,
}
CFLAGS = ["-O1", "-g0"]
#: generated data modules: module-level constants only, run once at import
INIT_ONLY_CFLAGS = ["-O0", "-g0"]
LDFLAGS = ["-s"]


class SourceFreeBuildPy(build_py):
    """``build_py`` that copies no Python source of a compiled module."""

    def find_package_modules(self, package, package_dir):
        modules = super().find_package_modules(package, package_dir)
        compiled = set(read_bundle()["compiled"])
        return [m for m in modules if f"{m[0]}.{m[1]}" not in compiled]


def read_bundle() -> dict:
    return json.loads(BUNDLE_FILE.read_text())


#: environment variables through which setuptools changes how a module is compiled or linked
COMPILER_ENV = ("CC", "CXX", "CFLAGS", "CPPFLAGS", "LDFLAGS", "LDSHARED", "ARCHFLAGS")


def compiler_identity() -> str:
    """The C compiler's command, its version line (a new gcc makes new binaries) and the
    :data:`COMPILER_ENV` variables set (``CFLAGS=-g`` would put debug information in)."""
    cc = os.environ.get("CC") or sysconfig.get_config_var("CC") or "cc"
    try:
        version = subprocess.run(cc.split() + ["--version"], capture_output=True, text=True,
                                 timeout=60, check=False).stdout.partition("\n")[0]
    except OSError:
        version = "unknown"
    env = {var: os.environ[var] for var in COMPILER_ENV if var in os.environ}
    return f"{cc}\0{version}\0{json.dumps(env, sort_keys=True)}"


def module_key(name: str, source: bytes, flags: list[str], compiler: str) -> str:
    """Digest of what module ``name``'s binary is made from: its staged ``source``, its C
    ``flags``, this build script (directives), Cython's version, the ``compiler`` and the
    interpreter."""
    import Cython

    h = hashlib.sha256()
    for part in (name.encode(), source, json.dumps(flags).encode(), Path(__file__).read_bytes(),
                 Cython.__version__.encode(),
                 compiler.encode(), sys.version.encode(), sysconfig.get_platform().encode(),
                 str(sysconfig.get_config_var("EXT_SUFFIX")).encode()):
        h.update(part + b"\0")
    return h.hexdigest()


class CachedBuildExt(build_ext):
    """``build_ext`` that takes each module from the module cache when it is there and compiles
    the rest on every core: Cython in a pool of processes (it holds the interpreter's lock),
    then gcc in a pool of threads (each waits on its compiler process)."""

    def build_extensions(self):
        self.check_extensions_list(self.extensions)
        cache = read_bundle().get("module_cache")
        cache = Path(cache) if cache else None
        compiler = compiler_identity()
        todo = []
        for ext in self.extensions:
            key = module_key(ext.name, Path(ext.sources[0]).read_bytes(),
                             ext.extra_compile_args + ext.extra_link_args, compiler)
            cached = cache / f"{key}.so" if cache else None
            target = Path(self.get_ext_fullpath(ext.name))
            if cached is not None and cached.is_file():
                target.parent.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(cached, target)
                os.utime(cached)            # recently used: kept by the cache's pruning
            else:
                todo.append((ext, cached))
        # the slowest first, so that the last one to start does not keep a core waiting alone
        todo.sort(key=lambda item: -Path(item[0].sources[0]).stat().st_size)
        report = (f"compiling {len(todo)} of {len(self.extensions)} modules "
                  f"({len(self.extensions) - len(todo)} from the module cache)")
        print(report, flush=True)
        REPORT_FILE.write_text(report)      # pip hides this output: the caller says it
        if not todo:
            return
        from Cython.Build import cythonize

        workers = os.cpu_count() or 1
        translated = cythonize([copy.copy(ext) for ext, _ in todo], quiet=True, force=True,
                               compiler_directives=CYTHON_DIRECTIVES, build_dir="build/cython",
                               nthreads=workers if len(todo) > 1 else 0)
        c_sources = {ext.name: ext.sources for ext in translated}
        for ext, _ in todo:     # setuptools' own extension objects: it has prepared them
            ext.sources = c_sources[ext.name]
        with ThreadPoolExecutor(workers) as pool:
            list(pool.map(self.build_extension, [ext for ext, _ in todo]))
        for ext, cached in todo:
            if cached is not None:
                store(Path(self.get_ext_fullpath(ext.name)), cached)


def store(binary: Path, cached: Path) -> None:
    """Copy ``binary`` to ``cached`` whole (a temporary file renamed into place)."""
    cached.parent.mkdir(parents=True, exist_ok=True)
    tmp = cached.with_name(f".{cached.name}.{uuid.uuid4().hex}.tmp")
    shutil.copyfile(binary, tmp)
    os.replace(tmp, cached)


def extensions(compiled: list[str], init_only: list[str]) -> list[Extension]:
    """One extension per dotted module name in ``compiled``, its staged ``.py`` as source
    (:class:`CachedBuildExt` runs Cython on the ones it compiles)."""
    return [
        Extension(name, [name.replace(".", "/") + ".py"],
                  extra_compile_args=INIT_ONLY_CFLAGS if name in init_only else CFLAGS,
                  extra_link_args=LDFLAGS)
        for name in sorted(compiled)
    ]


def main() -> None:
    bundle = read_bundle()
    setup(
        packages=bundle["packages"],
        data_files=[(target, files) for target, files in bundle["data_files"]],
        ext_modules=extensions(bundle["compiled"], bundle.get("init_only", [])),
        cmdclass={"build_py": SourceFreeBuildPy, "build_ext": CachedBuildExt},
        zip_safe=False,
    )


if __name__ == "__main__":  # setuptools' build backend runs setup.py as __main__
    main()
