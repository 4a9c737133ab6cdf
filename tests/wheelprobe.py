"""Does anything a copy of ``course_lib`` lets one call answer a graded function's hidden cases?

A determined student does not need a function's name: any callable of the students' copy that
returns the reference's answer can be wrapped by a one-line graded function (or its compiled
module carried into the sandbox). So the probe tries *every* callable reachable from the copy's
modules (public or private, plain Python or compiled, module-level or a class's static and
class methods) on the hidden cases of *every* graded function, and reports each callable that
gives the reference's answer on all of them, judged by that exercise's own comparison rule.
Data answer too: every module-level array, list, tuple or dict is tried as a constant and as a
table indexed by an exercise's integer argument (``T[i]``, and ``T[i, :N[i]]`` for every 1-D
integer count table ``N`` of the same length, the layout of a triangle table and its counts);
and the objects that the copy's zero-argument constructors and ``*_explorer()`` factories
return (figures headless) are walked, one level of attributes and the lists and dicts within:
their methods are tried as callables, their arrays, tables and floats as data.

:func:`find_answers` runs the probe with any interpreter (the instructors' venv, where it must
find every reference: the probe's own oracle; or the students' environment, where it must find
nothing) in a subprocess of its own, from a scratch folder, figures headless. The student side
(:data:`STUDENT_SIDE`) uses only NumPy and the standard library: it screens each callable's
outputs loosely (same size, same sorted values within 1e-3) and sends back the screened outputs;
the exercise's own rule, here, decides.
"""

from __future__ import annotations

import json
import os
import pickle
import subprocess
from pathlib import Path

import numpy as np

#: hidden cases tried per exercise (those that must not raise)
CASES_PER_EXERCISE = 6

#: the probe's address space (bytes): a callable handed another exercise's arguments may ask
#: for an enormous array (a photon count as an array size): it gets a MemoryError, which the
#: probe counts as "no answer", instead of the machine's OOM killer (seen: 20 GB, SIGKILL)
MEMORY_LIMIT = 8 << 30

#: CPU seconds one call may take (``ITIMER_PROF``: the process's own CPU time, so a busy
#: machine never stops a reference early; each of them answers in milliseconds)
CPU_BUDGET = 1.0
#: CPU seconds a zero-argument constructor or explorer factory may take (an explorer builds a
#: figure and its widgets)
FACTORY_BUDGET = 20.0
#: wall seconds one call may take, a backstop only for a callable that blocks without using
#: CPU (a sleep, a read); far beyond any reference's time however busy the machine
WALL_BACKSTOP = 30.0

STUDENT_SIDE = r'''
import importlib, inspect, io, os, pickle, pkgutil, resource, signal, sys, warnings
resource.setrlimit(resource.RLIMIT_AS, (int(os.environ["PROBE_MEMORY_LIMIT"]),) * 2)
import numpy as np
warnings.simplefilter("ignore")
os.environ.setdefault("MPLBACKEND", "Agg")
cases_path, out_path, package = sys.argv[1:4]
sys.path[:0] = sys.argv[4:]             # a forged copy's folder (the probe's own tests)
with open(cases_path, "rb") as f:
    cases = pickle.load(f)              # {exercise: [(args, kwargs, expected plain data)]}

class _Slow(BaseException):
    pass

def _alarm(*_):
    raise _Slow()

signal.signal(signal.SIGPROF, _alarm)
signal.signal(signal.SIGALRM, _alarm)
cpu_budget = float(os.environ["PROBE_CPU_BUDGET"])
wall_backstop = float(os.environ["PROBE_WALL_BACKSTOP"])

def _floats(x):
    try:
        a = np.asarray(x, dtype=float)
    except Exception:
        try:
            a = np.concatenate([np.ravel(np.asarray(p, dtype=float)) for p in x])
        except Exception:
            return None
    return np.sort(np.ravel(a))

def _screen(expected, got):
    if expected is None:
        return got is None
    e, g = _floats(expected), _floats(got)
    return (e is not None and g is not None and e.shape == g.shape
            and bool(np.allclose(g, e, rtol=1e-3, atol=1e-6, equal_nan=True)))

root = importlib.import_module(package)
modules, broken = [], {}
for info in pkgutil.walk_packages(root.__path__, package + "."):
    try:
        modules.append(importlib.import_module(info.name))
    except BaseException as exc:
        broken[info.name] = repr(exc)[:200]
modules.insert(0, root)

def _callables(module):
    for name, obj in sorted(vars(module).items()):
        owner = getattr(obj, "__module__", "") or ""
        if not (owner == package or owner.startswith(package + ".")):
            continue
        if inspect.isclass(obj):
            for attr, raw in sorted(vars(obj).items()):
                if isinstance(raw, (staticmethod, classmethod)):
                    yield f"{module.__name__}.{name}.{attr}", getattr(obj, attr)
        elif callable(obj):
            yield f"{module.__name__}.{name}", obj

try:
    import matplotlib.pyplot as plt
except Exception:
    plt = None

def _call(fn, args=(), kwargs=None, budget=None):
    """``fn(*args, **kwargs)`` within its CPU budget, printing nothing; ``_Slow`` on any error."""
    stdout, sys.stdout = sys.stdout, io.StringIO()
    signal.setitimer(signal.ITIMER_PROF, budget or cpu_budget)
    signal.setitimer(signal.ITIMER_REAL, wall_backstop)
    try:
        return fn(*args, **(kwargs or {}))
    except BaseException:
        return _Slow
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.setitimer(signal.ITIMER_REAL, 0)
        sys.stdout = stdout

import time
seen, found, tried, seconds = set(), {}, 0, {}
started = time.monotonic()

def _try(qual, fn):
    """Try callable ``fn`` on every exercise's cases; record it where it answers all of them."""
    global tried
    try:
        signature = inspect.signature(fn)
    except (TypeError, ValueError):
        signature = None
    for exercise, rows in cases.items():
        outputs = []
        if signature is not None:
            try:
                signature.bind(*pickle.loads(rows[0][0]), **pickle.loads(rows[0][1]))
            except TypeError:
                continue
        for args, kwargs, expected in rows:
            tried += 1
            got = _call(fn, pickle.loads(args), pickle.loads(kwargs))
            if got is _Slow or not _screen(expected, got):
                break
            outputs.append(got)
        else:
            found.setdefault(exercise, {})[qual] = pickle.dumps(outputs)
        if plt is not None:
            plt.close("all")

for module in modules:
    for qual, fn in _callables(module):
        if id(fn) in seen:
            continue
        seen.add(id(fn))
        _try(qual, fn)

seconds["callables"] = time.monotonic() - started

# -- data: tables indexed by an exercise's integer argument, and constants --------------------

def _is_int(a):
    return isinstance(a, (int, np.integer)) and not isinstance(a, (bool, np.bool_))

def _index_position(rows):
    """The first positional argument that is an integer in every case (a table's index)."""
    decoded = [pickle.loads(r[0]) for r in rows]
    for p in range(len(decoded[0])):
        if all(len(a) > p and _is_int(a[p]) for a in decoded):
            return p, [int(a[p]) for a in decoded]
    return None

INDEXED = {ex: pos for ex, rows in cases.items() if (pos := _index_position(rows)) is not None}

def _is_data(v):
    return isinstance(v, (np.ndarray, list, tuple, dict)) and not callable(v)

def _counts(v):
    """``v`` as a 1-D integer count table, or None."""
    if isinstance(v, dict) or not isinstance(v, (np.ndarray, list, tuple)) or len(v) == 0:
        return None
    try:
        a = np.asarray(v)
    except Exception:
        return None
    return a if a.ndim == 1 and a.dtype.kind in "iu" else None

def _lookup(table, i, counts=None):
    row = table[i]
    if counts is not None:
        row = np.asarray(row)[:int(counts[i])]
    return row

EXPECTED = {ex: [_floats(expected) for _, _, expected in rows] for ex, rows in cases.items()}

def _constant_answers(exercise, floats):
    """Does a value whose sorted floats are ``floats`` answer every case of ``exercise``?"""
    return all(e is not None and e.shape == floats.shape
               and bool(np.allclose(floats, e, rtol=1e-3, atol=1e-6, equal_nan=True))
               for e in EXPECTED[exercise])

def _screen_data(label, value, counts):
    """Record ``value`` where, as a constant or as a table ``T[i]`` / ``T[i, :N[i]]`` (N among
    ``counts``) indexed by an exercise's integer argument, it answers every case."""
    floats = _floats(value)             # sorted once: a table may hold a million samples
    for exercise, rows in cases.items():
        if floats is not None and _constant_answers(exercise, floats):
            found.setdefault(exercise, {})[label] = pickle.dumps([value] * len(rows))
        if exercise not in INDEXED or isinstance(value, (str, bytes)):
            continue
        _, indices = INDEXED[exercise]
        try:
            size = None if isinstance(value, dict) else len(value)
        except TypeError:               # a float, a 0-d array: a constant only
            continue
        for n_label, n in [(None, None)] + counts:
            if n is not None and (n is value or size is None or len(n) != size):
                continue
            outputs = []
            for i, (_, _, expected) in zip(indices, rows):
                try:
                    got = _lookup(value, i, n)
                except Exception:
                    break
                if not _screen(expected, got):
                    break
                outputs.append(got)
            else:
                name = f"{label}[i]" if n is None else f"{label}[i, :{n_label}[i]]"
                found.setdefault(exercise, {})[name] = pickle.dumps(outputs)

def _module_data(module):
    for name, v in sorted(vars(module).items()):
        if _is_data(v):
            yield f"{module.__name__}.{name}", v

data, counts, seen_data = [], [], set()
for module in modules:
    for label, v in _module_data(module):
        if id(v) not in seen_data:
            seen_data.add(id(v))
            data.append((label, v))
            if _counts(v) is not None:
                counts.append((label, _counts(v)))

# -- objects: what zero-argument constructors and explorer factories return ---------------------

def _within(label, v):
    """``v``'s items when it is a list, tuple or dict (one level)."""
    if isinstance(v, (list, tuple)):
        return [(f"{label}[{j}]", x) for j, x in enumerate(v[:64])]
    if isinstance(v, dict):
        return [(f"{label}[{k!r}]", x) for k, x in list(v.items())[:64]]
    return []

def _walk(label, obj):
    """``obj``, its attributes (one level) and the items of its lists and dicts."""
    out = [(label, obj)] + _within(label, obj)
    attrs = getattr(obj, "__dict__", None)
    for name, v in sorted(attrs.items()) if isinstance(attrs, dict) else ():
        out += [(f"{label}.{name}", v)] + _within(f"{label}.{name}", v)
    for name in dir(type(obj)) if not isinstance(obj, (list, tuple, dict, np.ndarray)) else ():
        if not name.startswith("__"):
            v = getattr(type(obj), name, None)
            if inspect.isfunction(v):
                out.append((f"{label}.{name}", getattr(obj, name, None)))
    return out

def _factories(module):
    for name, obj in sorted(vars(module).items()):
        owner = getattr(obj, "__module__", "") or ""
        if not (owner == package or owner.startswith(package + ".")) or not callable(obj):
            continue
        if not (inspect.isclass(obj) or name.lower().endswith("explorer")):
            continue
        try:
            inspect.signature(obj).bind()
        except (TypeError, ValueError):
            continue
        yield f"{module.__name__}.{name}()", obj

objects, made, alive = 0, set(), []
started = time.monotonic()
for module in modules:
    for label, factory in _factories(module):
        if id(factory) in made:
            continue
        made.add(id(factory))
        obj = _call(factory, budget=float(os.environ["PROBE_FACTORY_BUDGET"]))
        if obj is _Slow:
            continue
        objects += 1
        for qual, v in _walk(label, obj):
            if (_is_data(v) or isinstance(v, (float, np.floating))) and id(v) not in seen_data:
                seen_data.add(id(v))
                data.append((qual, v))
            elif callable(v) and not inspect.isclass(v) and id(v) not in seen:
                seen.add(id(v))
                alive.append(v)     # a bound method is made anew on each access: kept alive,
                _try(qual, v)       # its id cannot be reused by the next object's method
        if plt is not None:
            plt.close("all")

seconds["objects"] = time.monotonic() - started
started = time.monotonic()
unscreened = []
for label, v in data:
    try:
        _screen_data(label, v, counts)
    except Exception as exc:            # reported, so that a blind spot is seen
        unscreened.append(f"{label}: {exc!r}"[:200])
seconds["data"] = time.monotonic() - started
with open(out_path, "wb") as f:
    pickle.dump({"found": found, "broken": broken, "modules": [m.__name__ for m in modules],
                 "callables": len(seen), "calls": tried, "tables": len(data),
                 "objects": objects, "seconds": seconds, "unscreened": unscreened}, f)
sys.stdout.flush()
os._exit(0)
'''


def probe_cases(student: str = "wheel-probe") -> dict:
    """``{exercise: [(args, kwargs, expected, case)]}``: the first cases of every graded function
    that must not raise (hidden ones first), drawn as for ``student``, with the reference's
    answers."""
    from autograder.exercises import REGISTRY
    from autograder.exercises.base import to_plain

    out = {}
    for k, (name, ex) in enumerate(sorted(REGISTRY.items())):
        if ex.kind != "function":
            continue
        rng = np.random.default_rng([k, len(student), 2006])
        rows = []
        for case in ex.draw_cases(rng):
            if case.raises is None:
                rows.append((case.args, case.kwargs, to_plain(ex.expected(case)), case))
        # hidden cases first; a function of no argument has visible cases only
        rows.sort(key=lambda row: row[3].visible)
        assert rows, f"{name}: no case that returns"
        out[name] = rows[:CASES_PER_EXERCISE]
    return out


def find_answers(python: str | Path, workdir: Path, env: dict | None = None,
                 timeout: int = 1500, package: str = "course_lib",
                 path: tuple[str, ...] = ()) -> dict:
    """Run the probe on ``package`` with ``python`` from ``workdir`` (``path``: folders put
    first on its ``sys.path``): ``{"answers": {exercise: [callables that
    answer it]}, "broken": {module: error}, "modules": [...], "callables": n, "calls": n}``."""
    from autograder.exercises import REGISTRY

    cases = probe_cases()
    workdir = Path(workdir)
    workdir.mkdir(parents=True, exist_ok=True)
    sent = {name: [(pickle.dumps(a), pickle.dumps(kw), exp) for a, kw, exp, _ in rows]
            for name, rows in cases.items()}
    (workdir / "cases.pkl").write_bytes(pickle.dumps(sent))
    env = dict(os.environ if env is None else env, MPLBACKEND="Agg",
               PROBE_MEMORY_LIMIT=str(MEMORY_LIMIT), PROBE_CPU_BUDGET=str(CPU_BUDGET),
               PROBE_WALL_BACKSTOP=str(WALL_BACKSTOP), PROBE_FACTORY_BUDGET=str(FACTORY_BUDGET))
    proc = subprocess.run([str(python), "-I", "-c", STUDENT_SIDE, "cases.pkl", "found.pkl",
                           package, *map(str, path)],
                          cwd=workdir, env=env, capture_output=True, text=True,
                          timeout=timeout, check=False, stdin=subprocess.DEVNULL)
    if proc.returncode != 0 or not (workdir / "found.pkl").exists():
        raise RuntimeError(f"the probe failed ({proc.returncode}):\n{proc.stderr[-3000:]}")
    raw = pickle.loads((workdir / "found.pkl").read_bytes())
    answers = {}
    for name, candidates in raw["found"].items():
        ex, rows = REGISTRY[name], cases[name]
        for qual, blob in candidates.items():
            outputs = pickle.loads(blob)
            if all(_matches(ex, row, got) for row, got in zip(rows, outputs)):
                answers.setdefault(name, []).append(qual)
    return {"answers": {k: sorted(v) for k, v in sorted(answers.items())},
            **{k: raw[k] for k in ("broken", "modules", "callables", "calls", "tables",
                                   "objects", "seconds", "unscreened")}}


def _matches(ex, row, got) -> bool:
    """The exercise's own rule (the grader's default: within 1e-6 relative) accepts ``got``."""
    from autograder.exercises.base import close, to_plain

    _, _, expected, _ = row
    try:
        got = to_plain(got)
    except Exception:
        return False
    rule = ex.compare or close()
    try:
        return rule(expected, got) is None
    except Exception:
        return False


def summary(result: dict) -> str:
    return json.dumps(result["answers"], indent=1)
