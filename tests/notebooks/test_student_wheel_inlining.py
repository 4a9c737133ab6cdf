"""The students' copy of a routine that computes with a left-out function
(:mod:`autograder.inlining`): it gives the routine's own results, and the left-out function is
a C function nothing else can reach once Cython compiles the module; any other use of a
left-out function stops the build with its place named."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import pytest

from autograder import student_bundle
from autograder.inlining import c_name, inline_into

MATHS = textwrap.dedent('''
    """A module with a graded function ``secret`` and a figure routine ``shown``."""
    from __future__ import annotations
    import numpy as np
    SCALE = 10.0
    __all__ = ["secret", "shown"]


    def _helper(v):
        return np.asarray(v, float) * SCALE


    def secret(x, k=2, *, bias=0.0):
        """The graded answer."""
        return float(sum(t for t in _helper([x, k]))) + bias


    def shown(x):
        return round(secret(x, k=3), 1)
''')
VIEW = textwrap.dedent('''
    from __future__ import annotations
    from pkg import maths
    from pkg.maths import secret
    SCALE = -1          # the copies must read maths's SCALE, not this one


    class View:
        def draw(self, x):
            self.value = round(maths.secret(x, bias=0.5) + secret(x, 1), 2)
            return self.value
''')
SOURCES = {"pkg.maths": MATHS, "pkg.view": VIEW}
LEFT = {"pkg.maths": ("_helper", "secret")}


def _students_copy(module: str, text: str, routines) -> str:
    out = inline_into(text, module, routines, LEFT, SOURCES.__getitem__, SOURCES.__contains__)
    if module in LEFT:
        out = student_bundle.without_functions(out, LEFT[module])
    return out


def _write_package(root, texts: dict[str, str]):
    (root / "pkg").mkdir()
    (root / "pkg" / "__init__.py").write_text("")
    for module, text in texts.items():
        (root / (module.replace(".", "/") + ".py")).write_text(text)


def _expected(x):
    secret = lambda x, k=2, bias=0.0: 10.0 * (x + k) + bias  # noqa: E731  the maths, by hand
    return round(secret(x, 3), 1), round(secret(x, bias=0.5) + secret(x, 1), 2)


def test_routines_give_their_own_results_in_pure_python(tmp_path):
    texts = {"pkg.maths": _students_copy("pkg.maths", MATHS, ("shown",)),
             "pkg.view": _students_copy("pkg.view", VIEW, ("View.draw",))}
    assert "def secret" not in texts["pkg.maths"] and "secret'" not in texts["pkg.maths"]
    assert "from pkg.maths import secret" not in texts["pkg.view"]
    _write_package(tmp_path, texts)
    sys.path.insert(0, str(tmp_path))
    try:
        import pkg.maths
        import pkg.view
        got = pkg.maths.shown(1.234), pkg.view.View().draw(1.234)
        assert not hasattr(pkg.maths, "secret")
    finally:
        sys.path.remove(str(tmp_path))
        for name in ("pkg.view", "pkg.maths", "pkg"):
            sys.modules.pop(name, None)
    assert got == pytest.approx(_expected(1.234), abs=1e-9)


COMPILED_CHECK = r'''
import gc, json
import pkg.maths, pkg.view
assert pkg.maths.__file__.endswith(".so") and pkg.view.__file__.endswith(".so")
found = [n for m in (pkg.maths, pkg.view) for n in dir(m) if "secret" in n or "helper" in n]
alive = [o for o in gc.get_objects() if "secret" in str(getattr(o, "__name__", ""))]
print(json.dumps([pkg.maths.shown(1.234), pkg.view.View().draw(1.234), found, alive]))
'''


@pytest.mark.slow
def test_compiled_copies_are_unreachable_from_python(tmp_path):
    """Compiled, the routines still give the maths' results, while no module attribute, no
    object on the collector's lists and no stripped symbol names the left-out function."""
    texts = {"pkg.maths": _students_copy("pkg.maths", MATHS, ("shown",)),
             "pkg.view": _students_copy("pkg.view", VIEW, ("View.draw",))}
    _write_package(tmp_path, texts)
    setup = ("from Cython.Build import cythonize\nfrom setuptools import setup\n"
             "setup(ext_modules=cythonize(['pkg/maths.py', 'pkg/view.py'], compiler_directives="
             "{'language_level': 3, 'binding': True, 'annotation_typing': False}))\n")
    (tmp_path / "setup.py").write_text(setup)
    build = subprocess.run([sys.executable, "setup.py", "build_ext", "--inplace"], cwd=tmp_path,
                           capture_output=True, text=True, timeout=600, check=False)
    assert build.returncode == 0, build.stdout[-2000:] + build.stderr[-2000:]
    for module in texts:
        (tmp_path / (module.replace(".", "/") + ".py")).unlink()
    run = subprocess.run([sys.executable, "-c", COMPILED_CHECK], cwd=tmp_path,
                         capture_output=True, text=True, timeout=120, check=False)
    assert run.returncode == 0, run.stderr[-2000:]
    shown, drawn, found, alive = json.loads(run.stdout.strip().splitlines()[-1])
    assert (shown, drawn) == pytest.approx(_expected(1.234), abs=1e-9)
    assert found == [] and alive == [], run.stdout


@pytest.mark.parametrize("routine, complaint", [
    ("    return [secret][0](x)", "other than by calling it"),
    ("    return secret(*[x])", r"\*args or \*\*kwargs"),
    ("    f = getattr\n    return secret", "other than by calling it"),
])
def test_a_left_out_function_used_other_than_by_a_call_is_refused(routine, complaint):
    text = MATHS + "\n\ndef other(x):\n" + routine + "\n"
    with pytest.raises(ValueError, match=complaint):
        inline_into(text, "pkg.maths", ("other",), LEFT, SOURCES.__getitem__,
                    SOURCES.__contains__)


def test_a_left_out_function_a_c_function_cannot_be_is_refused():
    text = MATHS.replace("def secret(x, k=2, *, bias=0.0):", "def secret(x, *more):")
    with pytest.raises(ValueError, match="cannot be a C function"):
        inline_into(text, "pkg.maths", ("shown",), LEFT, {"pkg.maths": text}.__getitem__,
                    SOURCES.__contains__)


def test_a_routine_that_calls_nothing_left_out_is_refused():
    with pytest.raises(ValueError, match="call no left-out function"):
        inline_into(MATHS, "pkg.maths", ("_helper",), {"pkg.maths": ("secret",)},
                    SOURCES.__getitem__, SOURCES.__contains__)


def test_code_outside_the_listed_routines_still_may_not_name_it():
    """Only the listed routine gets the copy: another function of the module calling the
    left-out function stops the build (``without_functions`` finds the name)."""
    text = MATHS + "\n\ndef unlisted(x):\n    return secret(x)\n"
    inlined = inline_into(text, "pkg.maths", ("shown",), LEFT, {"pkg.maths": text}.__getitem__,
                          SOURCES.__contains__)
    with pytest.raises(ValueError, match="still named"):
        student_bundle.without_functions(inlined, LEFT["pkg.maths"])
    assert c_name("pkg.maths", "secret") in inlined


def test_a_dictionary_key_equal_to_a_left_out_name_is_not_a_use():
    text = "values = {'secret': 1}\nlabel = getattr(object, 'secret', None)\n"
    used = student_bundle.names_used(text)
    assert "secret" in used          # the getattr argument names it
    assert "secret" not in student_bundle.names_used("values = {'secret': 1}\n")

