"""``setup.py`` of the students' wheel (copied into a staging folder by ``student_bundle``).

Not imported by the package: :func:`autograder.student_bundle.build_wheel` copies this file as
``setup.py`` beside a copy of ``course_lib/`` and a ``bundle.json`` naming the modules to compile,
then runs ``pip wheel --no-build-isolation`` on that folder with the instructors' interpreter
(which has setuptools and Cython). Each listed module becomes a Cython extension; its ``.py``
is left out of the wheel (``build_py`` below skips it) and no ``.c`` is packaged.
"""

import json
import os
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext
from setuptools.command.build_py import build_py

#: what to build, written by ``student_bundle``: {"packages", "compiled", "data_files"}
BUNDLE_FILE = Path(__file__).resolve().parent / "bundle.json"

#: docstrings stay (students read them with ``?``); no debug info, no source comments in the .so
CYTHON_DIRECTIVES = {
    "language_level": 3,
    "binding": True,            # inspect.signature and ``?`` show the real signature
    "embedsignature": True,
    "annotation_typing": False,  # plain Python semantics: ``x: int`` must not become a C int
    "emit_code_comments": False,
}
CFLAGS = ["-O1", "-g0"]
LDFLAGS = ["-s"]


class SourceFreeBuildPy(build_py):
    """``build_py`` that copies no Python source of a compiled module."""

    def find_package_modules(self, package, package_dir):
        modules = super().find_package_modules(package, package_dir)
        compiled = set(read_bundle()["compiled"])
        return [m for m in modules if f"{m[0]}.{m[1]}" not in compiled]


class ParallelBuildExt(build_ext):
    """``build_ext`` on every core (two on the course's CI machine)."""

    def finalize_options(self):
        super().finalize_options()
        if not self.parallel:
            self.parallel = os.cpu_count() or 1


def read_bundle() -> dict:
    return json.loads(BUNDLE_FILE.read_text())


def extensions(compiled: list[str]) -> list[Extension]:
    """One Cython extension per dotted module name in ``compiled``."""
    from Cython.Build import cythonize

    exts = [
        Extension(name, [name.replace(".", "/") + ".py"], extra_compile_args=CFLAGS,
                  extra_link_args=LDFLAGS)
        for name in sorted(compiled)
    ]
    return cythonize(exts, compiler_directives=CYTHON_DIRECTIVES, nthreads=os.cpu_count() or 1,
                     build_dir="build/cython", quiet=True)


def main() -> None:
    bundle = read_bundle()
    setup(
        packages=bundle["packages"],
        data_files=[(target, files) for target, files in bundle["data_files"]],
        ext_modules=extensions(bundle["compiled"]),
        cmdclass={"build_py": SourceFreeBuildPy, "build_ext": ParallelBuildExt},
        zip_safe=False,
    )


if __name__ == "__main__":  # setuptools' build backend runs setup.py as __main__
    main()
