"""What a student installs: a wheel of ``course_lib`` with no readable reference, and a README.

``python -m autograder release --out DIR`` calls :func:`write_bundle`, which writes
``DIR/student/4f9_course_student-<version>-<tags>.whl`` and ``DIR/student/README.md``.

The wheel holds the course library the release notebooks import (figures, explorers, tables)
without any way to read a graded function's reference: every module of ``course_lib`` except
the package ``__init__`` files and :data:`SHIPPED_AS_SOURCE` is compiled by Cython into an
extension module (docstrings kept for ``?``, no ``.py``, ``.pyc``, ``.c`` or debug information
in the wheel, so ``??`` and ``inspect.getsource`` find no source). The wheel holds no
``autograder`` (keys, hidden cases, the grader) and no notebook. :func:`wheel_problems` checks
every built wheel for exactly that before it is handed out.

A compiled wheel fits one Python version and platform (its tags say which): build the release
with the interpreter the students use (e.g. the course's JupyterHub image).

Compiling every module takes about 90 CPU seconds (minutes on two busy cores), so wheels
are cached in a build folder, keyed on a digest of everything that goes into them
(:func:`sources_digest`); the digest is also the wheel's local version label, so ``pip``
upgrades an environment whenever the sources change. Within a build, each module's binary is
cached too (``<build folder>/modules/``, keyed on that module's own staged source: see
``student_setup.py``), so a change to one module recompiles that module and those whose
students' copy it changes (a generated module, a routine's C-level copy), not all 42.
:func:`ensure_student_env` makes (or refreshes) a virtual environment holding the wheel alone,
which is what ``make lab`` opens (``.venv-student/``) and what the tests execute the release in.
"""

from __future__ import annotations

import ast
import hashlib
import importlib.metadata
import re
import json
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
import zipfile
from pathlib import Path

from packaging.requirements import Requirement

from .course import REPO_ROOT, file_lock
from .inlining import CFUNC, inline_into

LIBRARY = "course_lib"
LIBRARY_DIR = REPO_ROOT / LIBRARY
DIST_NAME = "4f9-course-student"
#: modules students may read: the multiple-choice *format* checker that visible test cells
#: call (it holds no key: the grader alone does), and each student's numbers and order of
#: options (a pure function of the id; no answers)
SHIPPED_AS_SOURCE = ("course_lib.answers", "course_lib.variants")
#: helpers the students' wheel leaves out with the graded functions: each computes a left-out
#: function's answer (or part of it) or calls one; ``{module: (function, ...)}``
LEFT_OUT_HELPERS = {
    "course_lib.marching_cubes": (                                                   # q3
        "_check_volume", "_active_cells", "_march", "_axis_vertices", "marching_cubes_loop",
        "_table_triangles", "_march_loop", "cell_triangles", "hole_demo", "probe_triangulation",
        "cube_symmetries", "_apply", "_orbit_labels", "_cycle_lengths"),   # Q3(b)'s orbits
    "course_lib.ultrasound": ("phantom_interfaces", "displayed_faces"),  # q1: displayed depths
    "course_lib.gamma_camera": ("pmt_cascade", "exam_cutoff_radius", "exact_cutoff_radius",  # q2
                                "transmission_profile", "compare_models"),
    "course_lib.splines": ("basis_matrix", "end_weights", "_apply_rule", "extend_with_phantoms",
                           "segment_geometries", "evaluate_curve"),                  # q4
    "course_lib.shading": ("_normalised", "_unit", "_shade", "phong_terms", "highlight_normal",
                           "highlight_pixel", "render_sphere", "sphere_normals", "view_basis"),
    "course_lib.clipping": ("clip_against_plane", "clip_steps", "clip_polygons", "_clip_array",
                            "_clip_plane_array", "_clip_batch", "_clip_rows", "shoelace_area"),
}
#: shipped routines that compute with left-out functions yet answer no graded question: each
#: returns only a whole figure, an 8-bit image, text, or numbers at display precision, and
#: stores nothing finer on an object. The students' copy of each calls C-level copies of the
#: left-out functions it calls, which nothing else can reach (:mod:`autograder.inlining`);
#: ``{module: (qualified name, ...)}``, methods as ``Class.method``
INLINE_INTO: dict[str, tuple[str, ...]] = {
    "course_lib.plots.ultrasound": ("bscan_summary", "displayed_outlines", "displayed_interfaces"),
    "course_lib.widgets.ultrasound": ("BScanExplorer._write_readout",),   # q1 readout, text
    "course_lib.plots.gamma_camera": ("cascade_labels", "shown_resolution", "hole_verdicts",
                                      "profile_curves", "model_curves"),      # q2 figures
    "course_lib.widgets.gamma_camera": ("collimator_model",),                # q2 explorer
    "course_lib.plots.splines": ("spline_scene", "plot_blending_functions"),   # q4 figures
    "course_lib.plots.shading": ("update_sphere_pair", "drawn_vectors"),      # q5 figures
    "course_lib.widgets.shading": ("PhongExplorer.refresh", "angles"),        # q5 explorer
    "course_lib.widgets.clipping": ("clip_display",),                        # q6 explorer
}
#: modules the students' wheel does not carry at all (nothing of the students' copy needs
#: them; no shipped module may import them)
INSTRUCTORS_ONLY = ("course_lib.mesh", "course_lib._polygons", "course_lib.spectral_render")
#: modules whose students' copy is generated when the wheel is built: the text their
#: ``students_copy()`` returns (e.g. the results of the references on a figure's fixed inputs)
GENERATED_MODULES = (
    "course_lib._mc_results_data", "course_lib._mc_tables", "course_lib._mc_case_data",  # q3
    "course_lib._collimator_results_data",                                          # q2
    "course_lib._spline_weights_data",                                              # q4
    "course_lib._spectral_spheres_data",                                            # q5
    "course_lib._clip_results_data",                                                # q6
)
#: the instructors' requirements a student's environment needs (versions come from our own
#: package metadata, so the two never disagree)
STUDENT_REQUIREMENTS = ("numpy", "matplotlib", "ipywidgets", "ipympl", "anywidget", "jupyterlab",
                        "nbgrader")
SETUP_SCRIPT = Path(__file__).with_name("student_setup.py")
INLINING_SCRIPT = Path(__file__).with_name("inlining.py")
#: nbgrader's instructor tools: off in ``make lab``'s student view and, through the wheel's
#: Jupyter config files (:func:`student_jupyter_config`), wherever the wheel is installed
STUDENT_DISABLED_PLUGINS = (
    "@jupyter/nbgrader:formgrader",
    "@jupyter/nbgrader:create-assignment",
    "@jupyter/nbgrader:course-list",
)
STUDENT_DISABLED_SERVER_EXTENSIONS = (
    "nbgrader.server_extensions.formgrader",
    "nbgrader.server_extensions.course_list",
)
#: where the wheel's Jupyter config files go, under the environment's ``etc/jupyter/``; the
#: server file sorts after nbgrader's own ``nbgrader.json`` so that it wins
JUPYTER_CONFIG_FILES = {
    "labconfig/page_config.d/4f9-student.json": "page",
    "jupyter_server_config.d/zz-4f9-student.json": "server",
}
#: wheel members that must never reach a student, by suffix
FORBIDDEN_SUFFIXES = (".pyc", ".pyo", ".c", ".cpp", ".h", ".pyx", ".pxd", ".ipynb")
BUILD_TIMEOUT = 1800
#: the build folder's sub-folder of compiled modules (one binary per module key)
MODULE_CACHE = "modules"
#: how many builds' worth of module binaries the module cache keeps (a few recent versions of
#: each module: switching between branches does not recompile everything)
MODULE_CACHE_BUILDS = 4


class WheelLeak(RuntimeError):
    """A built student wheel contains something a student must not see."""


def library_files() -> list[Path]:
    """Every Python file of ``course_lib`` (sorted, relative to the repository)."""
    return sorted(p.relative_to(REPO_ROOT) for p in LIBRARY_DIR.rglob("*.py")
                  if "__pycache__" not in p.parts)


def shipped_files() -> list[Path]:
    """The files of :func:`library_files` the students' wheel carries (not :data:`INSTRUCTORS_ONLY`)."""
    return [p for p in library_files() if module_name(p) not in INSTRUCTORS_ONLY]


def module_name(path: Path) -> str:
    """``course_lib/plots/clipping.py`` -> ``course_lib.plots.clipping``."""
    return ".".join(Path(path).with_suffix("").parts)


def compiled_modules() -> list[str]:
    """Dotted names of the modules the wheel carries only as compiled extensions."""
    return [module_name(p) for p in shipped_files()
            if p.name != "__init__.py" and module_name(p) not in SHIPPED_AS_SOURCE]


def withheld_functions() -> dict[str, tuple[str, ...]]:
    """``{module: (function, ...)}``: the graded functions' references, every one of which the
    students' wheel leaves out (a new exercise's too: an explorer that needs its maths calls
    it from a routine listed in :data:`INLINE_INTO`)."""
    from .exercises import REGISTRY

    out: dict[str, set[str]] = {}
    for ex in REGISTRY.values():
        ref = ex.reference
        if ex.kind == "function":
            out.setdefault(ref.__module__, set()).add(ref.__qualname__)
    return {m: tuple(sorted(names)) for m, names in sorted(out.items())}


def without_functions(text: str, names) -> str:
    """A module's source ``text`` without its top-level functions ``names`` (decorators
    included) and without their entries in its ``__all__``.

    ``ValueError`` when one of them is not a top-level function of ``text``, or when what is
    left still names one (a caller would fail only when a student's explorer reached it).
    """
    names = set(names)
    tree = ast.parse(text)
    lines = text.splitlines(keepends=True)
    cut = {}
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name in names:
            cut[node.name] = (min([node.lineno] + [d.lineno for d in node.decorator_list]),
                              node.end_lineno)
        elif (isinstance(node, ast.Assign) and len(node.targets) == 1
              and getattr(node.targets[0], "id", None) == "__all__"):
            cut["__all__"] = (node.lineno, node.end_lineno)
    missing = names - set(cut)
    if missing:
        raise ValueError(f"no top-level function {sorted(missing)} to leave out")
    listing = cut.pop("__all__", None)
    if listing is not None:
        start, end = listing
        block = "".join(lines[start - 1:end])
        for name in names:
            block = re.sub(rf"\s*[\"']{re.escape(name)}[\"'],?", "", block)
        lines[start - 1:end] = [block]
    for start, end in sorted(cut.values(), reverse=True):
        if listing is not None and start > listing[0]:
            start, end = start - (listing[1] - listing[0]), end - (listing[1] - listing[0])
        del lines[start - 1:end]
    out = "".join(lines)
    still = sorted(names & names_used(out))
    if still:
        raise ValueError(f"{still} left out but still named in the module")
    return out


def left_out() -> dict[str, tuple[str, ...]]:
    """``{module: (function, ...)}``: what staging removes, the graded functions of
    :func:`withheld_functions` and their :data:`LEFT_OUT_HELPERS`."""
    out = {m: set(names) for m, names in withheld_functions().items()}
    for m, names in LEFT_OUT_HELPERS.items():
        if m in out:          # the helpers go with the module's graded functions
            out[m].update(names)
    return {m: tuple(sorted(names)) for m, names in sorted(out.items())}


def imported_modules(text: str, module: str) -> set[str]:
    """Dotted names of the modules (and of the names in them) that ``module``'s source imports,
    relative imports resolved."""
    package = module.rpartition(".")[0]
    out = set()
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.Import):
            out.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                parts = parts[:len(parts) - node.level + 1]
                base = ".".join(parts + ([node.module] if node.module else []))
            out.add(base)
            out.update(f"{base}.{alias.name}" for alias in node.names)
    return out


def names_used(text: str) -> set[str]:
    """Every name a module's source uses: names, attributes, imported names, and strings
    that can name an attribute (a call's argument, as in ``getattr(m, "f")``, or an entry of
    ``__all__``; a dictionary key "phong" names nothing)."""
    used = set()
    for node in _walk_outside_c_functions(ast.parse(text)):
        if isinstance(node, ast.Name):
            used.add(node.id)
        elif isinstance(node, ast.Attribute):
            used.add(node.attr)
        elif isinstance(node, ast.alias):
            used.add(node.name.rpartition(".")[2])
        elif isinstance(node, ast.Call):
            used.update(a.value for a in node.args
                        if isinstance(a, ast.Constant) and isinstance(a.value, str))
        elif (isinstance(node, ast.Assign) and len(node.targets) == 1
              and getattr(node.targets[0], "id", None) == "__all__"):
            used.update(n.value for n in ast.walk(node.value)
                        if isinstance(n, ast.Constant) and isinstance(n.value, str))
    return used


def _walk_outside_c_functions(tree: ast.AST):
    """``ast.walk`` that skips the C-level copies :mod:`autograder.inlining` adds (their text
    is a left-out function's own, strings and all; only compiled code can call them)."""
    todo = [tree]
    while todo:
        node = todo.pop()
        if isinstance(node, ast.FunctionDef) and any(
                ast.unparse(d) == CFUNC for d in node.decorator_list):
            continue
        yield node
        todo.extend(ast.iter_child_nodes(node))


def library_packages() -> list[str]:
    """``course_lib`` and its sub-packages."""
    return sorted(module_name(p.parent) for p in library_files() if p.name == "__init__.py")


def student_requirements() -> list[str]:
    """Requirement strings of the students' wheel, taken from the instructors' package."""
    try:
        declared = importlib.metadata.requires("4f9-course") or []
    except importlib.metadata.PackageNotFoundError as exc:
        raise RuntimeError("the course package is not installed (run `make .venv/.installed`)") \
            from exc
    chosen = [Requirement(r) for r in declared]
    chosen = [r for r in chosen if r.marker is None and r.name in STUDENT_REQUIREMENTS]
    missing = set(STUDENT_REQUIREMENTS) - {r.name for r in chosen}
    if missing:
        raise RuntimeError(f"pyproject.toml no longer requires {sorted(missing)}")
    return [str(r) for r in chosen]


def course_version() -> str:
    return importlib.metadata.version("4f9-course")


def student_jupyter_config() -> dict[str, dict]:
    """``{path under etc/jupyter: JSON}``: nbgrader's instructor tools off for a student."""
    contents = {
        "page": {"disabledExtensions": {p: True for p in STUDENT_DISABLED_PLUGINS}},
        "server": {"ServerApp": {"jpserver_extensions": {
            ext: False for ext in STUDENT_DISABLED_SERVER_EXTENSIONS}}},
    }
    return {path: contents[kind] for path, kind in JUPYTER_CONFIG_FILES.items()}


def bundle_spec() -> dict:
    """What ``setup.py`` builds: the packages, the modules to compile (``init_only``: those
    that only hold data, compiled without optimisation), and the Jupyter config files as
    setuptools ``data_files`` (``[[target dir, [staged file]], ...]``)."""
    data_files = [[str(Path("etc/jupyter", path).parent), [str(Path("jupyter", path))]]
                  for path in JUPYTER_CONFIG_FILES]
    compiled = compiled_modules()
    return {"packages": library_packages(), "compiled": compiled,
            "init_only": [m for m in compiled if m in GENERATED_MODULES],
            "data_files": data_files}


def sources_digest() -> str:
    """A digest of everything that goes into the wheel: the library, the build script, the
    metadata and README, the module lists, the interpreter that compiles it."""
    h = hashlib.sha256()
    for rel in library_files():
        h.update(str(rel).encode() + b"\0" + (REPO_ROOT / rel).read_bytes() + b"\0")
    h.update(SETUP_SCRIPT.read_bytes())
    h.update(INLINING_SCRIPT.read_bytes())
    h.update(json.dumps([course_version(), bundle_spec(), left_out(), INLINE_INTO,
                         INSTRUCTORS_ONLY,
                         GENERATED_MODULES, np_version(),
                         student_jupyter_config(),
                         pyproject_text("0"), student_readme(),
                         sys.version, sysconfig.get_platform()]).encode())
    return h.hexdigest()


def np_version() -> str:
    """NumPy's version: the generated modules hold arrays it computed."""
    return importlib.metadata.version("numpy")


def wheel_version(digest: str) -> str:
    """The course version with the sources' digest as local label, e.g. ``0.1.0+g1a2b3c4d5e6f``."""
    return f"{course_version()}+g{digest[:12]}"


def default_build_cache(course_root: Path) -> Path:
    """Where compiled wheels are kept between releases of a course (one build per digest)."""
    return Path(course_root) / ".student-build"


def pyproject_text(version: str) -> str:
    """The staging folder's ``pyproject.toml`` (static metadata; setup.py adds the modules)."""
    deps = ", ".join(json.dumps(r) for r in student_requirements())
    return (
        '[build-system]\nrequires = ["setuptools>=68", "wheel", "cython>=3.0"]\n'
        'build-backend = "setuptools.build_meta"\n\n'
        f'[project]\nname = "{DIST_NAME}"\nversion = "{version}"\n'
        'description = "4F9 Medical Imaging & 3D Computer Graphics: the course library for '
        'students (figures, explorers, tables)"\n'
        'readme = "README.md"\n'
        f'requires-python = "=={sys.version_info.major}.{sys.version_info.minor}.*"\n'
        f"dependencies = [{deps}]\n"
    )


def staged_text(rel: Path, withheld: dict, gone: set) -> str:
    """The students' copy of the library file ``rel``: generated (:data:`GENERATED_MODULES`),
    without its left-out functions, or as it is; ``ValueError`` when it would still name a
    function left out elsewhere or import an :data:`INSTRUCTORS_ONLY` module."""
    import importlib

    name = module_name(rel)
    if name in GENERATED_MODULES:
        text = importlib.import_module(name).students_copy()
    else:
        text = (REPO_ROOT / rel).read_text(encoding="utf-8")
    if name in INLINE_INTO:
        text = inline_into(text, name, INLINE_INTO[name], withheld, _library_source,
                           _is_library_module)
    if name in withheld:
        text = without_functions(text, withheld[name])
    # a left-out function that shares its name with a module of the library (marching_cubes)
    # cannot be told from an import of that module by name: the wheel probe checks those
    modules = {module_name(p).rpartition(".")[2] for p in library_files()}
    named = (gone - modules) & names_used(text)
    if named:   # e.g. a re-export of a function left out elsewhere
        raise ValueError(f"{rel} names {sorted(named)}, which the students' wheel leaves out")
    imported = sorted(m for m in imported_modules(text, name)
                      if any(m == o or m.startswith(o + ".") for o in INSTRUCTORS_ONLY))
    if imported:
        raise ValueError(f"{rel} imports {imported}, which the students' wheel leaves out")
    return text


def _library_source(module: str) -> str:
    """The instructors' source of library module ``module`` (what left-out functions are
    copied from)."""
    return (REPO_ROOT / (module.replace(".", "/") + ".py")).read_text(encoding="utf-8")


def _is_library_module(dotted: str) -> bool:
    return dotted in {module_name(p) for p in library_files()}


def stage_sources(stage: Path, digest: str, module_cache: Path | None = None) -> Path:
    """Fill ``stage`` with what ``pip wheel`` builds from: the library, setup, metadata; the
    build keeps each compiled module in ``module_cache`` (none: every module is compiled)."""
    withheld = left_out()
    gone = {name for names in withheld.values() for name in names}
    for rel in shipped_files():
        (stage / rel).parent.mkdir(parents=True, exist_ok=True)
        text = staged_text(rel, withheld, gone)
        (stage / rel).write_text(text, encoding="utf-8")
    shutil.copyfile(SETUP_SCRIPT, stage / "setup.py")
    spec = bundle_spec()
    spec["module_cache"] = str(module_cache) if module_cache is not None else None
    (stage / "bundle.json").write_text(json.dumps(spec, indent=1))
    for path, content in student_jupyter_config().items():
        (stage / "jupyter" / path).parent.mkdir(parents=True, exist_ok=True)
        (stage / "jupyter" / path).write_text(json.dumps(content, indent=1))
    (stage / "pyproject.toml").write_text(pyproject_text(wheel_version(digest)))
    (stage / "README.md").write_text(student_readme())
    return stage


def wheel_problems(wheel: Path) -> list[str]:
    """Every member of ``wheel`` a student must not get (empty when the wheel is fit to give)."""
    compiled = set(compiled_modules())
    problems = []
    with zipfile.ZipFile(wheel) as zf:
        names = zf.namelist()
    config_files = {f"data/etc/jupyter/{path}" for path in JUPYTER_CONFIG_FILES}
    for name in names:
        top, _, rest = name.partition("/")
        allowed = (top == LIBRARY or top.endswith(".dist-info")
                   or (top.endswith(".data") and rest in config_files))
        if not allowed:
            problems.append(f"{name}: not part of {LIBRARY}")
        if name.endswith(".py") and module_name(Path(name)) in compiled:
            problems.append(f"{name}: source of a compiled module")
        if name.endswith(FORBIDDEN_SUFFIXES) or "__pycache__" in name:
            problems.append(f"{name}: source, bytecode or notebook")
        if any(name.startswith(m.replace(".", "/") + ".") for m in INSTRUCTORS_ONLY):
            problems.append(f"{name}: a module the students' wheel leaves out")
    missing = [m for m in compiled
               if not any(n.startswith(m.replace(".", "/") + ".") and n.endswith(".so")
                          for n in names)]
    problems += [f"{m}: no compiled extension in the wheel" for m in missing]
    return problems


def _run_build(stage: Path, out: Path) -> Path:
    cmd = [sys.executable, "-m", "pip", "wheel", "--no-build-isolation", "--no-deps",
           "--no-cache-dir", "--quiet", "--wheel-dir", str(out), str(stage)]
    proc = subprocess.run(cmd, cwd=stage, capture_output=True, text=True, timeout=BUILD_TIMEOUT,
                          check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"building the student wheel failed:\n{proc.stdout[-3000:]}\n"
                           f"{proc.stderr[-3000:]}")
    wheels = sorted(out.glob("*.whl"))
    if len(wheels) != 1:
        raise RuntimeError(f"pip wheel wrote {[w.name for w in wheels]}, expected one wheel")
    return wheels[0]


def cached_wheel(cache_dir: Path, digest: str | None = None) -> Path | None:
    """The student wheel of the current sources (``digest``: :func:`sources_digest`) when
    ``cache_dir`` holds it, else ``None`` (nothing is built)."""
    digest = digest or sources_digest()
    built = sorted((Path(cache_dir).resolve() / digest[:16]).glob("*.whl"))
    return built[0] if len(built) == 1 else None


def build_wheel(cache_dir: Path) -> Path:
    """The student wheel of the current sources, built into ``cache_dir/<digest>/`` if missing.

    Raises :class:`WheelLeak` when the built wheel holds anything :func:`wheel_problems` names.
    """
    digest = sources_digest()
    target = Path(cache_dir).resolve() / digest[:16]
    target.parent.mkdir(parents=True, exist_ok=True)
    with file_lock(target.parent / ".build.lock"):
        built = cached_wheel(cache_dir, digest)
        if built is not None:
            return built
        modules = target.parent / MODULE_CACHE
        for old in target.parent.iterdir():  # one cached wheel at a time
            if old.is_dir() and old != modules:
                shutil.rmtree(old)
        print(f"compiling the students' wheel into {target} (the modules that changed since "
              "the last build; every one on a fresh clone, a few minutes on two cores) ...",
              file=sys.stderr, flush=True)
        started = time.monotonic()
        with tempfile.TemporaryDirectory(prefix="4f9-student-wheel-") as tmp:
            stage = stage_sources(Path(tmp) / "src", digest, modules)
            wheel = _run_build(stage, Path(tmp) / "dist")
            report = stage / "compiled.txt"
            said = report.read_text().replace("compiling", "compiled") if report.exists() \
                else "compiled"
            print(f"{said} in {time.monotonic() - started:.0f} s", file=sys.stderr, flush=True)
            problems = wheel_problems(wheel)
            if problems:
                raise WheelLeak("the student wheel would leak instructor material:\n  "
                                + "\n  ".join(problems))
            target.mkdir()
            prune_module_cache(modules)
            return Path(shutil.copy2(wheel, target / wheel.name))


def prune_module_cache(folder: Path, keep: int | None = None) -> None:
    """Keep the ``keep`` most recently used binaries of the module cache ``folder`` (default:
    :data:`MODULE_CACHE_BUILDS` builds' worth); drop temporary files a day old (left by a build
    that died while storing)."""
    keep = MODULE_CACHE_BUILDS * len(compiled_modules()) if keep is None else keep
    try:
        found = [(p, p.stat().st_mtime) for p in Path(folder).iterdir() if p.is_file()]
    except OSError:
        return
    binaries = sorted((f for f in found if not f[0].name.startswith(".")),
                      key=lambda f: f[1], reverse=True)
    stale = [p for p, mtime in found if p.name.startswith(".") and mtime < time.time() - 86400]
    for old in [p for p, _ in binaries[keep:]] + stale:
        old.unlink(missing_ok=True)


def write_bundle(out_dir: Path, cache_dir: Path) -> list[Path]:
    """Write ``out_dir/student/`` (the wheel and a README for students); return the files."""
    wheel = build_wheel(cache_dir)
    dest = Path(out_dir) / "student"
    dest.mkdir(parents=True, exist_ok=True)
    for old in dest.glob("*.whl"):
        old.unlink()
    written = [Path(shutil.copy2(wheel, dest / wheel.name)), dest / "README.md"]
    written[1].write_text(student_readme(wheel.name))
    return written


def env_python(env_dir: Path) -> Path:
    """The interpreter of the virtual environment ``env_dir``."""
    return Path(env_dir) / ("Scripts/python.exe" if os.name == "nt" else "bin/python")


def ensure_student_env(env_dir: Path, wheel: Path, base_python: str | None = None) -> Path:
    """A virtual environment at ``env_dir`` holding ``wheel`` and its requirements alone.

    Created with ``base_python`` (default: the Python this one was created from, never with
    this environment's packages) when missing; the wheel is (re)installed when the environment
    holds another build. Returns the environment's interpreter.
    """
    env_dir = Path(env_dir).resolve()
    env_dir.mkdir(parents=True, exist_ok=True)  # ``venv`` fills an existing folder
    with file_lock(env_dir / ".student-env.lock"):
        python = _make_env(env_dir, base_python)
        stamp = env_dir / WHEEL_STAMP
        if not stamp.exists() or stamp.read_text() != Path(wheel).name:
            print(f"installing {Path(wheel).name} into {env_dir} ...", file=sys.stderr, flush=True)
            _pip(env_dir, "install", str(wheel))
            stamp.write_text(Path(wheel).name)
    return python


def ensure_student_requirements(env_dir: Path, base_python: str | None = None) -> Path:
    """A virtual environment at ``env_dir`` holding the students' wheel's requirements
    (JupyterLab, nbgrader, NumPy...) and no ``course_lib``: what ``make lab`` opens while the
    wheel of the current sources is being built (a wheel of other sources installed there
    is removed first: it may hold a function that is graded now). Returns its interpreter."""
    env_dir = Path(env_dir).resolve()
    env_dir.mkdir(parents=True, exist_ok=True)
    with file_lock(env_dir / ".student-env.lock"):
        python = _make_env(env_dir, base_python)
        stamp = env_dir / WHEEL_STAMP
        if stamp.exists():
            _pip(env_dir, "uninstall", "--yes", DIST_NAME)
            stamp.unlink()
        wanted = "\n".join(student_requirements())
        stamp = env_dir / ".student-requirements"
        if not stamp.exists() or stamp.read_text() != wanted:
            print(f"installing JupyterLab, nbgrader and the course's other requirements into "
                  f"{env_dir} ...", file=sys.stderr, flush=True)
            # no byte-compiling of every file of JupyterLab and its dependencies: what the
            # server and kernels import is compiled on first use
            _pip(env_dir, "install", "--no-compile", *student_requirements())
            stamp.write_text(wanted)
    return python


#: the file in a students' environment naming the wheel installed there
WHEEL_STAMP = ".student-wheel"


def _make_env(env_dir: Path, base_python: str | None) -> Path:
    python = env_python(env_dir)
    if not python.exists():
        base = base_python or getattr(sys, "_base_executable", sys.executable)
        subprocess.run([base, "-m", "venv", str(env_dir)], check=True, timeout=300,
                       capture_output=True)
    return python


def _pip(env_dir: Path, *args: str) -> None:
    """``pip ARGS`` in the students' environment ``env_dir``; ``RuntimeError`` when it fails."""
    proc = subprocess.run([str(env_python(env_dir)), "-m", "pip", *args[:1], "--quiet",
                           "--disable-pip-version-check", *args[1:]],
                          capture_output=True, text=True, timeout=BUILD_TIMEOUT,
                          env=student_env_vars(env_dir), check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"pip {' '.join(args)} in {env_dir} failed:\n"
                           f"{proc.stdout[-2000:]}\n{proc.stderr[-3000:]}")


def student_env_vars(env_dir: Path, base: dict | None = None) -> dict:
    """Environment variables for a process of the student environment ``env_dir``.

    Its ``bin/`` first on ``PATH`` (Jupyter finds kernels and ``nbgrader`` there) and nothing
    that would put the instructors' packages in reach (``PYTHONPATH``, another venv).
    """
    env = dict(os.environ if base is None else base)
    for var in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV", "PYTHONSTARTUP"):
        env.pop(var, None)
    bindir = str(env_python(env_dir).parent)
    instructors = str(Path(sys.executable).parent)
    parts = [p for p in env.get("PATH", "").split(os.pathsep) if p and p not in (bindir, instructors)]
    env["PATH"] = os.pathsep.join([bindir, *parts])
    env["VIRTUAL_ENV"] = str(Path(env_dir).resolve())
    return env


def student_readme(wheel_name: str = "4f9_course_student-*.whl") -> str:
    """The students' README (``DIR/student/README.md`` and the wheel's long description)."""
    return f"""# 4F9 Medical Imaging & 3D Computer Graphics: the 2006 paper

This folder holds the course library the six question notebooks (`tripos2006/q1_imaging.ipynb`
to `q6_clipping.ipynb`) import: the figures, the interactive explorers and the tables they
give you. It also brings JupyterLab, ipywidgets, ipympl, anywidget (the explorers' figures)
and nbgrader's Validate button.

## Install (once)

Use the Python version named in the wheel's file name (`cp311` is Python 3.11):

```bash
python3 -m venv ~/4f9-env
~/4f9-env/bin/python -m pip install {wheel_name}
```

## Fetch, submit, get feedback

On the course's JupyterHub: the **Assignments** panel (Nbgrader → Assignment List) fetches
`tripos2006`, submits it (as often as you like; the last submission before collection counts)
and fetches your feedback. Off the hub, on the machine the course runs on, first copy the
course's exchange settings (without them nbgrader stops with "Unwritable directory"); then the
panel works, or the commands (`<repository>` is the course's folder your instructor names):

```bash
source ~/4f9-env/bin/activate
mkdir -p ~/.jupyter && cp <repository>/course/for-students/nbgrader_config.py ~/.jupyter/
nbgrader fetch_assignment tripos2006 --course 4f9    # -> ./tripos2006/
nbgrader submit tripos2006 --course 4f9              # from the folder holding tripos2006/
nbgrader fetch_feedback tripos2006 --course 4f9      # once your instructor hands feedback back
```

## Work

```bash
cd tripos2006          # the folder of notebooks you fetched or were given
~/4f9-env/bin/jupyter lab
```

Open a notebook, run its setup cell, then type your student id once in the `STUDENT_ID` cell
just below it (`STUDENT_ID = "ab123"`) and run that: it prints **your numbers**, the ones the
items headed *Your numbers* ask about, and every multiple-choice item then shows its options in
an order of your own. (On the course's JupyterHub your login is used and the cell changes
nothing.) Fill in every cell marked `YOUR CODE HERE` (remove the `raise NotImplementedError()`),
run the test cell under it, and write your explanations where it says `YOUR ANSWER HERE`. The
**Validate** button in the notebook toolbar runs the notebook's visible tests and tells you which
still fail; they check the form of each answer, and the hidden tests of the grader check more.

- Each graded function must work on its own: the grader runs the notebook's setup cell and your
  answer cells, nothing else (not the `STUDENT_ID` cell: it knows who you are).
- Type the answers to items (letters, numbers, lists of numbers): the grader reads what an item's
  answer cell types, not what code computes.
- Do not call `course_lib` from a graded function: the library is there for the figures and
  explorers, and an answer that calls it scores nothing. Its help (`?` after a name) describes
  what each function does; its code is not part of the package.
- Multiple-choice answers are strings of option letters, e.g. `"b"` or `"ac"`.
"""
