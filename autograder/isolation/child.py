"""The program that runs INSIDE the grading sandbox (and the wire format both sides share).

Self-contained: the standard library and NumPy only, never ``autograder`` (which is not in the
sandbox). The grader binds this one file read-only into the sandbox and starts it as
``python -I -S child.py --job /job --site DIR --channel-fd N``; the grader itself imports it only
for the wire format (:func:`encode_value`, :func:`decode_value`, :data:`FRAME`).

Inside the sandbox this process is the *supervisor*: it never runs student code. It

1. limits itself (rlimits are inherited and cannot be raised again), becomes non-dumpable (so
   a worker of the same uid can neither ptrace it nor open its descriptors via ``/proc``);
2. executes the instructor's setup cell (trusted, from the source notebook);
3. for each graded name forks a *worker* that executes the name's cells (all within ONE load time
   limit), looks the name up and runs the cases, each under an alarm, with its prints captured,
   and streams each case's encoded result to the supervisor over a pipe;
4. forwards the worker's records to the ONE channel the grader reads, restarts a crashed or
   hung worker for the remaining cases (at most ``max_launches`` processes per name) under
   deadlines of its own that no record of a worker can move (a fixed one per case, a hard end
   per name and per notebook, ``job_timeout``), and kills
   every leftover process between names. When it is PID 1 of its own PID namespace (the
   sandbox), ``kill(-1, SIGKILL)`` cannot reach it, and clears everything else.

The wire format: records are length-prefixed JSON (4-byte big-endian length, then UTF-8 JSON).
Values are JSON scalars, or tagged objects ``{"t": "tuple"|"list"|"dict"|"complex"|"array"}``;
arrays are base64 with a dtype from :data:`ARRAY_DTYPES` and a shape. Nothing else (no pickle,
no archive, nothing compressed). The grader re-validates everything (:func:`decode_value` with
a byte budget), because student code may have replaced any of this in its own process.
"""

from __future__ import annotations

import base64
import json
import os
import signal
import struct
import sys
import time

FRAME = struct.Struct(">I")        #: the length prefix of every record
MAX_DEPTH = 8                      #: containers nested deeper are rejected
MAX_INT_BITS = 4096                #: larger ints are rejected (JSON would need > 1233 digits)
SCALAR_COST = 1                    #: budget bytes charged per scalar / container element
RECORD_OVERHEAD = 64 * 1024        #: bytes a record may take beyond its value and its prints
GRACE = 1.0                        #: seconds the supervisor waits beyond a worker's own alarm
TIMEOUTS_IN_A_ROW = 3              #: after this many timeouts the rest of a name is not run
#: The array dtypes allowed across the boundary (little-endian): bool, ints, uints, floats,
#: complex.
ARRAY_DTYPES = frozenset({"|b1", "|i1", "<i2", "<i4", "<i8", "|u1", "<u2", "<u4", "<u8",
                          "<f2", "<f4", "<f8", "<c8", "<c16"})
#: THE allow-list: the only parts of ``course_lib`` present in the sandbox (the data tables
#: the Q3 setup cell imports, copied as literals by the grader). Anything else under
#: ``course_lib`` is a reference: absent, and reported as such.
ALLOWED_REFERENCE = {"course_lib.marching_cubes": ("CORNERS", "EDGES", "FACES", "N_TRIANGLES",
                                                   "TRI_TABLE")}
#: Whole modules of ``course_lib`` the sandbox holds as they are: they know no answer
#: (``variants`` draws each student's numbers; the grader computes the answers on its side).
ALLOWED_WHOLE_MODULES = ("course_lib.variants",)
ALLOWED_COURSE_MODULES = ("course_lib", *ALLOWED_REFERENCE, *ALLOWED_WHOLE_MODULES)
#: What the grading says of a course_lib import it met (the notebooks' own words).
OFF_LIMITS = "course_lib, the course's reference library, which graded code may not use"
#: What a case raises when it needs what a refused import did not define.
MISSING_AFTER_REFUSAL = (NameError, AttributeError, ImportError)
#: What the grading says when the sandbox refused compiled code (or a call the seccomp filter
#: refuses) that a cell tried to load or make.
REFUSED_CODE = ("graded code may use only NumPy and the standard library modules listed in the "
                "notebook: the sandbox runs no compiled code that a notebook brings")


# ============================================================================================
# the wire format (used by the worker, the supervisor and the grader)


class NotPlain(Exception):
    """A value that may not cross the boundary; ``str(exc)`` says what it was."""


class TooLarge(Exception):
    """A value larger than its byte budget."""


class Budget:
    """Bytes a value may still take on the wire.

    Encoding charges a lower bound of the JSON text (arrays: their base64 size), so a value
    that fits is never refused early; decoding charges an array's data size before decoding
    it. The exact rule is the record's size (:func:`record_cap`).
    """

    def __init__(self, limit: int):
        self.left = int(limit)

    def spend(self, n: int) -> None:
        self.left -= int(n)
        if self.left < 0:
            raise TooLarge("the result is too large")


def _article(name: str) -> str:
    return ("an " if name[:1].lower() in "aeiou" else "a ") + name


def encode_value(v, budget: Budget, depth: int = 0):
    """``v`` as JSON-ready plain data; ``NotPlain`` (with a reason) or ``TooLarge`` if not."""
    if depth > MAX_DEPTH:
        raise NotPlain(f"a structure nested more than {MAX_DEPTH} deep")
    t = type(v)
    if t is int and v.bit_length() > MAX_INT_BITS:
        raise NotPlain(f"an int of more than {MAX_INT_BITS} bits")
    if v is None or t is bool or t is int or t is float:
        budget.spend(SCALAR_COST)
        return v
    if t is str:
        budget.spend(len(v))
        return v
    if t is complex:
        budget.spend(2 * SCALAR_COST)
        return {"t": "complex", "v": [v.real, v.imag]}
    if t is tuple or t is list:
        budget.spend(SCALAR_COST * len(v))
        return {"t": t.__name__, "v": [encode_value(x, budget, depth + 1) for x in v]}
    if t is dict:
        budget.spend(SCALAR_COST * len(v))
        if any(type(k) is not str for k in v):
            raise NotPlain("a dict whose keys are not all str")
        return {"t": "dict", "v": [[k, encode_value(x, budget, depth + 1)] for k, x in v.items()]}
    np = sys.modules.get("numpy")
    if np is not None and t is np.ndarray:
        return _encode_array(np, v, budget)
    if np is not None and isinstance(v, np.generic) and t.__module__ == "numpy":
        if _wire_dtype(np, v.dtype) is None:
            raise NotPlain(f"a NumPy scalar of dtype {v.dtype}")
        return encode_value(v.item(), budget, depth)
    raise NotPlain(_article(getattr(t, "__name__", "object")))


def _wire_dtype(np, dtype):
    """The little-endian dtype that carries ``dtype``, or None when it is not allowed."""
    if dtype.fields is not None or dtype.subdtype is not None:
        return None
    wire = dtype.newbyteorder("<") if dtype.byteorder == ">" else dtype
    return wire if wire.str in ARRAY_DTYPES else None


def _encode_array(np, a, budget: Budget) -> dict:
    wire = _wire_dtype(np, a.dtype)
    if wire is None:
        raise NotPlain(f"an array of dtype {a.dtype} (expected numbers)")
    budget.spend(4 * ((a.size * a.itemsize + 2) // 3))
    data = np.ascontiguousarray(a, dtype=wire).tobytes()
    return {"t": "array", "dtype": wire.str, "shape": list(a.shape),
            "v": base64.b64encode(data).decode("ascii")}


class BadValue(Exception):
    """A received value that is not in the wire format (or larger than its budget)."""


def decode_value(obj, budget: Budget, depth: int = 0):
    """Rebuild a value from its wire form, checking everything (raises ``BadValue``)."""
    if depth > MAX_DEPTH:
        raise BadValue("the result is nested too deeply")
    t = type(obj)
    try:
        if obj is None or t is bool or t is int or t is float:
            budget.spend(SCALAR_COST)
            return obj
        if t is str:
            budget.spend(len(obj))
            return obj
        if t is not dict:
            raise BadValue("the result has an unexpected form")
        tag, items = obj.get("t"), obj.get("v")
        if tag == "array":
            return _decode_array(obj, budget)
        if type(items) is not list:
            raise BadValue("the result has an unexpected form")
        budget.spend(SCALAR_COST * len(items))
        if tag == "tuple" or tag == "list":
            out = [decode_value(x, budget, depth + 1) for x in items]
            return tuple(out) if tag == "tuple" else out
        if tag == "dict" and all(type(p) is list and len(p) == 2 and type(p[0]) is str
                                 for p in items):
            return {k: decode_value(x, budget, depth + 1) for k, x in items}
        if tag == "complex" and len(items) == 2 and all(type(x) in (int, float) for x in items):
            return complex(items[0], items[1])
    except TooLarge:
        raise BadValue("the result is too large") from None
    raise BadValue("the result has an unexpected form")


def _decode_array(obj: dict, budget: Budget):
    import numpy as np

    dtype, shape, data = obj.get("dtype"), obj.get("shape"), obj.get("v")
    if dtype not in ARRAY_DTYPES or type(data) is not str or type(shape) is not list:
        raise BadValue("an array that does not hold plain numbers")
    if len(shape) > 32 or any(type(n) is not int or n < 0 for n in shape):
        raise BadValue("an array with an invalid shape")
    count = 1
    for n in shape:
        count *= n
    nbytes = count * np.dtype(dtype).itemsize
    budget.spend(nbytes)                       # before decoding anything
    if len(data) != 4 * ((nbytes + 2) // 3):
        raise BadValue("an array whose data does not match its shape")
    try:
        raw = base64.b64decode(data, validate=True)
    except ValueError:
        raise BadValue("an array whose data is not base64") from None
    if len(raw) != nbytes:
        raise BadValue("an array whose data does not match its shape")
    return np.frombuffer(bytearray(raw), dtype=dtype).reshape(shape)


def record_cap(result_cap: int, output_bytes: int) -> int:
    """The most bytes one case's record may take: its value (``result_cap`` bytes of JSON),
    its captured prints (at most 12 bytes per character once escaped) and a fixed overhead."""
    return int(result_cap) + 12 * int(output_bytes) + RECORD_OVERHEAD


def frame(record: dict) -> bytes:
    """One record as bytes on the wire (ASCII JSON: every other character is escaped)."""
    data = json.dumps(record, separators=(",", ":")).encode("ascii")
    return FRAME.pack(len(data)) + data


class FrameReader:
    """Reads records from a pipe, never holding more than one capped frame.

    :meth:`next` answers ``(event, payload)``: ``("record", (dict, raw_bytes))``, ``("eof",
    None)``, ``("timeout", None)``, ``("too-large", None)`` (a frame over ``frame_cap`` or
    the stream over ``total_cap``) or ``("garbage", None)`` (not a JSON object). Sizes are
    checked from the length prefix before the frame is read.
    """

    def __init__(self, fd: int, frame_cap: int, total_cap: int | None = None):
        self.fd, self.frame_cap, self.total_cap = fd, int(frame_cap), total_cap
        self.buf = bytearray()
        self.total = 0

    def _parse(self):
        (length,) = FRAME.unpack_from(self.buf)
        if length > self.frame_cap:
            return "too-large", None
        if len(self.buf) < FRAME.size + length:
            return None
        raw = bytes(self.buf[:FRAME.size + length])
        del self.buf[:FRAME.size + length]
        try:
            rec = json.loads(raw[FRAME.size:])
        except (ValueError, RecursionError):
            return "garbage", None
        return ("record", (rec, raw)) if type(rec) is dict else ("garbage", None)

    def next(self, deadline: float, alive=None):
        """The next event; ``alive()`` (if given) is asked whenever the pipe is quiet, and a
        False answer is an ``"eof"`` (a writer may die while a child of it holds the pipe)."""
        import select

        while True:
            if len(self.buf) >= FRAME.size:
                got = self._parse()
                if got is not None:
                    return got
            left = deadline - time.monotonic()
            if left <= 0:
                return "timeout", None
            if not select.select([self.fd], [], [], min(left, 0.1 if alive else 1.0))[0]:
                if alive is not None and not alive():
                    return "eof", None
                continue
            want = FRAME.size + self.frame_cap - len(self.buf)
            if self.total_cap is not None:
                want = min(want, self.total_cap - self.total + 1)
            chunk = os.read(self.fd, max(1, min(want, 1 << 20)))
            if not chunk:
                return "eof", None
            self.total += len(chunk)
            if self.total_cap is not None and self.total > self.total_cap:
                return "too-large", None
            self.buf += chunk


def write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]


# ============================================================================================
# shared by the supervisor and the worker


def _libc_prctl(option: int, arg: int) -> None:
    """``prctl(option, arg)`` (Linux); silently nothing elsewhere."""
    try:
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(option, arg, 0, 0, 0)
    except (OSError, AttributeError):
        pass


_KEPT: list = []      #: libraries loaded for good before the filter
PR_GET_SECCOMP = 21
PR_SET_SECCOMP = 22
SECCOMP_MODE_FILTER = 2
PR_SET_NO_NEW_PRIVS = 38


def _install_filter(bpf: bytes) -> None:
    """Install the seccomp filter ``bpf`` (classic BPF from the grader, see
    ``autograder.isolation.seccomp``) on this process, for good; ``OSError`` if the kernel
    refuses. ``no_new_privs`` first: the kernel demands it of a process without privileges."""
    import ctypes

    class SockFprog(ctypes.Structure):
        _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.c_void_p)]

    libc = ctypes.CDLL(None, use_errno=True)
    code = ctypes.create_string_buffer(bpf, len(bpf))
    prog = SockFprog(len(bpf) // 8, ctypes.addressof(code))
    if libc.prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0 or \
            libc.prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, ctypes.byref(prog), 0, 0) != 0:
        err = ctypes.get_errno()
        raise OSError(err, f"the seccomp filter could not be installed ({os.strerror(err)})")


def _seccomp_supported() -> bool:
    """True when this kernel can install seccomp filters (``PR_GET_SECCOMP`` answers)."""
    import ctypes

    try:
        return ctypes.CDLL(None, use_errno=True).prctl(PR_GET_SECCOMP, 0, 0, 0, 0) >= 0
    except (OSError, AttributeError):
        return False


def _preload(modules: list) -> list:
    """Import the modules a solution may use (the grader's allow-list) while compiled code can
    still be loaded, and ``libgcc_s`` (glibc loads it when a thread ends); what failed, as
    notes."""
    import ctypes
    import importlib

    notes = []
    try:
        _KEPT.append(ctypes.CDLL("libgcc_s.so.1"))   # kept loaded: glibc finds it there later
    except OSError:
        notes.append("the sandbox could not load libgcc_s.so.1: threads may fail")
    for name in modules:
        try:
            importlib.import_module(name)
        except ImportError as exc:
            notes.append(f"the sandbox could not load the allowed module {name} ({exc})")
    return notes


def refused_code(exc: BaseException) -> bool:
    """Whether ``exc`` (or an exception it was raised from or during) is the sandbox refusing
    compiled code or a call: an extension module that could not be loaded, ``dlopen``'s
    "failed to map segment", or ``EPERM`` from a system call. Never raises."""
    try:
        for _ in range(6):
            if exc is None:
                return False
            if isinstance(exc, ImportError) and not isinstance(exc, ModuleNotFoundError):
                path = exc.path if type(exc.path) is str else ""
                if path.endswith(".so") or "failed to map segment" in _safe_str(exc, 2000):
                    return True
            if isinstance(exc, OSError) and (exc.errno == 1 or "failed to map segment"
                                             in _safe_str(exc, 2000)):
                return True
            exc = exc.__cause__ or exc.__context__
    except BaseException:  # noqa: BLE001 - a student's exception may raise anything
        pass
    return False


def _set_rlimits(limits: dict, budget_seconds: float) -> None:
    import resource

    mb = 2**20
    wanted = [(resource.RLIMIT_CORE, 0), (resource.RLIMIT_FSIZE, (limits["scratch_mb"] + 1) * mb),
              (resource.RLIMIT_CPU, int(budget_seconds) + 5)]
    if limits.get("nproc"):
        wanted.append((resource.RLIMIT_NPROC, int(limits["pids"])))
    for which, value in wanted:
        try:
            _soft, hard = resource.getrlimit(which)
            value = value if hard == resource.RLIM_INFINITY else min(value, hard)
            resource.setrlimit(which, (value, value))
        except (ValueError, OSError):
            pass


def _safe_str(obj, cap: int) -> str:
    try:
        text = str(obj)
    except BaseException:  # noqa: BLE001 - a student's __str__ may raise anything
        text = "<message unavailable>"
    if type(text) is not str:
        text = "<message unavailable>"
    return text if len(text) <= cap else text[:cap] + "..."


def _describe_status(status: int) -> str:
    if os.WIFSIGNALED(status):
        sig = os.WTERMSIG(status)
        try:
            name = signal.Signals(sig).name
        except ValueError:
            name = f"signal {sig}"
        hint = {"SIGKILL": " (out of memory, or killed)", "SIGSEGV": " (a segmentation fault)",
                "SIGXCPU": " (out of CPU time)", "SIGABRT": " (aborted)"}.get(name, "")
        return f"the process was killed by {name}{hint}"
    return f"the process exited with code {os.WEXITSTATUS(status)}"


def reference_module(exc: BaseException) -> str:
    """What of ``course_lib`` an import (or attribute) error was about, else ``""``.

    Decided by the exception's attributes (``ImportError.name``, ``AttributeError.obj`` and
    ``.name``), never by its message: a missing ``course_lib`` module, a name imported from an
    allow-listed module that it does not hold there, or an attribute of a ``course_lib``
    module."""
    if isinstance(exc, ImportError):
        name = exc.name if type(exc.name) is str else ""
        if not (name == "course_lib" or name.startswith("course_lib.")):
            return ""
        if name not in ALLOWED_COURSE_MODULES:
            return name
        return "" if isinstance(exc, ModuleNotFoundError) else f"a reference from {name}"
    if isinstance(exc, AttributeError):
        obj = getattr(exc, "obj", None)
        mod = getattr(obj, "__name__", "") if type(obj).__name__ == "module" else ""
        attr = getattr(exc, "name", "")
        if type(mod) is str and type(attr) is str and mod in ALLOWED_COURSE_MODULES:
            return f"{mod}.{attr}"
    return ""


# ============================================================================================
# the worker (a forked process that runs the student's code for one graded name)


class CaseTimeout(BaseException):
    """Raised by the worker's alarm when a cell or a case runs out of time."""


def _on_alarm(signum, frame_):
    raise CaseTimeout("time limit")


class Capture:
    """``sys.stdout``/``sys.stderr`` of a worker: keeps the first ``cap`` characters written
    (a flood of prints costs time, never memory)."""

    encoding = "utf-8"
    errors = "replace"

    def __init__(self, cap: int):
        self.cap, self.parts, self.kept, self.lost = int(cap), [], 0, 0

    def write(self, s) -> int:
        if type(s) is not str:
            s = _safe_str(s, self.cap)
        room = self.cap - self.kept
        if room > 0:
            self.parts.append(s[:room])
            self.kept += min(len(s), room)
        self.lost += max(0, len(s) - max(room, 0))
        return len(s)

    def take(self) -> str:
        """What was written since the last call (capped), and forget it."""
        text = "".join(self.parts)
        if self.lost:
            text += f"\n... [{self.lost} more characters not shown]"
        self.parts, self.kept, self.lost = [], 0, 0
        return text

    def writelines(self, lines) -> None:
        for line in lines:
            self.write(line)

    def flush(self) -> None:
        pass

    def isatty(self) -> bool:
        return False

    def fileno(self) -> int:
        return 1

    def readable(self) -> bool:
        return False

    def writable(self) -> bool:
        return True


def _load_cells(nj: dict, ns: dict, limits: dict, send) -> tuple[str, bool]:
    """Execute the name's cells in order, all of them within ONE load time limit, each failure
    a note. Returns what of ``course_lib`` a failing cell tried to use (``""`` if none), and
    whether the sandbox refused a cell's compiled code (:func:`refused_code`)."""
    reference, refused = "", False
    end = time.monotonic() + float(limits["load_timeout"])   # ONE budget for all the cells
    for label, source in nj["cells"]:
        send({"t": "cell", "name": nj["name"], "label": label})
        left = end - time.monotonic()
        note, ref = _run_cell(label, source, ns, left) if left > 0.05 else \
            (f"cell {label} was not run: the cells before it used up the time limit", "")
        if ref == REFUSED_CODE:
            refused = True
        else:
            reference = reference or ref
        if note:
            send({"t": "note", "name": nj["name"], "text": note})
    return reference, refused


def _run_cell(label: str, source: str, ns: dict, timeout: float) -> tuple[str, str]:
    """``(note, reference)`` of one cell: why it failed (``""`` if it did not), and what of
    ``course_lib`` it tried to use (:data:`REFUSED_CODE` when the sandbox refused its code)."""
    try:
        code = compile(source, f"<cell {label}>", "exec")
        try:
            signal.setitimer(signal.ITIMER_REAL, timeout)
            exec(code, ns)
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
    except CaseTimeout:
        return f"cell {label} was stopped: the solution cells together used up their time " \
               "limit (an endless loop at a cell's top level?)", ""
    except SystemExit as exc:
        return f"cell {label} called sys.exit({_safe_str(exc, 100)}): ignored", ""
    except BaseException as exc:  # noqa: BLE001 - student code may raise anything
        ref = reference_module(exc)
        note = f"cell {label} raised {_exc_name(exc)}: {_safe_str(exc, 300)}"
        if ref:
            note += f" ({ref} is from {OFF_LIMITS})"
        elif refused_code(exc):
            ref = REFUSED_CODE
            note += f" ({REFUSED_CODE})"
        return note, ref
    return "", ""


def _exc_name(exc: BaseException) -> str:
    try:
        name = type(exc).__name__
        return name if type(name) is str else "?"
    except BaseException:  # noqa: BLE001
        return "?"


def _exc_mro(exc: BaseException) -> list:
    try:
        return [f"{c.__module__}.{c.__qualname__}"[:200] for c in type(exc).__mro__][:20]
    except BaseException:  # noqa: BLE001 - a metaclass may raise anything
        return []


def _call_case(nj: dict, ns: dict, case: dict, limits: dict, refused: bool = False) -> dict:
    """Run one case; the record's ``kind`` and its value or error (``rejected-code`` when it
    failed because the sandbox refused compiled code, in this case or in the cells before)."""
    timeout = float(limits["case_timeout"])
    try:
        try:
            unlimited = Budget(1 << 62)
            args = decode_value(case["args"], unlimited)
            kwargs = decode_value(case["kwargs"], unlimited)
            target = ns[nj["name"]]
            signal.setitimer(signal.ITIMER_REAL, timeout)
            value = target(*args, **kwargs) if nj["kind"] == "function" else target
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
    except CaseTimeout:
        return {"kind": "timeout", "message": f"took longer than {timeout:g} s"}
    except BaseException as exc:  # noqa: BLE001
        ref = reference_module(exc)
        if ref:
            return {"kind": "reference-used",
                    "message": f"used {ref}, from {OFF_LIMITS}"}
        if refused_code(exc) or (refused and isinstance(exc, MISSING_AFTER_REFUSAL)):
            return {"kind": "rejected-code", "message": f"raised {_exc_name(exc)}: "
                                                        f"{_safe_str(exc, 300)} ({REFUSED_CODE})"}
        return {"kind": "raised", "etype": _exc_name(exc), "mro": _exc_mro(exc),
                "message": _safe_str(exc, 500)}
    return _encode_result(value, int(case["cap"]))


def _encode_result(value, cap: int) -> dict:
    try:
        return {"kind": "returned", "value": encode_value(value, Budget(cap))}
    except NotPlain as exc:
        return {"kind": "rejected", "message": f"returned {exc}, not plain numbers"}
    except TooLarge:
        return {"kind": "rejected", "message": f"result too large (more than {cap} bytes)"}
    except BaseException as exc:  # noqa: BLE001 - e.g. a RecursionError, a MemoryError
        return {"kind": "rejected", "message": f"the result could not be encoded "
                                               f"({_exc_name(exc)})"}


def _case_record(nj: dict, i: int, ns: dict, limits: dict, loaded: tuple[str, bool],
                 capture) -> bytes:
    case = nj["cases"][i]
    reference, refused = loaded
    capture.take()
    t0 = time.monotonic()
    if nj["name"] in ns:
        rec = _call_case(nj, ns, case, limits, refused)
    elif reference:
        rec = {"kind": "reference-used",
               "message": f"{nj['name']!r} is not defined: its cell used {reference}, "
                          f"from {OFF_LIMITS}"}
    elif refused:
        rec = {"kind": "rejected-code",
               "message": f"{nj['name']!r} is not defined: {REFUSED_CODE}"}
    else:
        rec = {"kind": "not-run", "message": f"{nj['name']!r} is not defined after its cells"}
    rec.update(t="case", name=nj["name"], i=i, seconds=time.monotonic() - t0,
               printed=capture.take())
    try:
        data = frame(rec)
    except (ValueError, TypeError, RecursionError):
        rec.update(kind="rejected", value=None, message="the result could not be encoded")
        data = frame(rec)
    if len(data) > record_cap(case["cap"], limits["output_bytes"]):
        rec.update(kind="rejected", value=None, printed=rec["printed"][:1000],
                   message=f"result too large (more than {case['cap']} bytes)")
        data = frame(rec)
    return data


def _worker_setup(limits: dict, bpf: bytes = b"") -> Capture:
    """Make this forked process a worker: own session, no descriptors of the supervisor, its
    memory limit, first in line for the OOM killer, prints captured, and last, before any
    student text runs, the seccomp filter ``bpf`` (when the job has one)."""
    import resource

    os.setsid()
    null = os.open(os.devnull, os.O_RDWR)
    for fd in (0, 1, 2):
        os.dup2(null, fd)
    os.close(null)
    try:
        mem = int(limits["memory_mb"]) * 2**20
        resource.setrlimit(resource.RLIMIT_AS, (mem, mem))
    except (ValueError, OSError):
        pass
    try:
        with open("/proc/self/oom_score_adj", "w") as f:
            f.write("1000")
    except OSError:
        pass
    signal.signal(signal.SIGALRM, _on_alarm)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    capture = Capture(int(limits["output_bytes"]))
    sys.stdout = sys.stderr = capture
    if bpf:
        _install_filter(bpf)
    return capture


def worker_main(nj: dict, ns: dict, start: int, limits: dict, out_fd: int,
                bpf: bytes = b"") -> None:
    """The worker's whole life: cells, then cases ``start...``, each streamed; never returns."""
    code = 0
    try:
        capture = _worker_setup(limits, bpf)

        def send(rec):
            write_all(out_fd, frame(rec))

        loaded = _load_cells(nj, ns, limits, send)
        send({"t": "loaded", "name": nj["name"], "defined": nj["name"] in ns,
              "printed": capture.take()})
        for i in range(start, len(nj["cases"])):
            send({"t": "start", "name": nj["name"], "i": i})
            write_all(out_fd, _case_record(nj, i, ns, limits, loaded, capture))
        send({"t": "done", "name": nj["name"]})
    except BaseException:  # noqa: BLE001 - e.g. the pipe closed: the supervisor decides
        code = 70
    os._exit(code)


# ============================================================================================
# the supervisor (runs no student code)

PR_SET_PDEATHSIG = 1
PR_SET_DUMPABLE = 4


def name_budget(limits: dict, n_cases: int) -> float:
    """The most wall seconds one graded name may take: every launch's load budget and every
    case's time limit (the grader's job budget adds these up)."""
    load = float(limits["load_timeout"]) + GRACE
    case = float(limits["case_timeout"]) + GRACE
    return int(limits["max_launches"]) * load + max(1, n_cases) * case


def kill_leftovers(worker_pid: int | None) -> None:
    """Kill every process of the job but this one (as PID 1 of the sandbox: ``kill(-1)``;
    elsewhere the worker's process group) and reap them."""
    if os.getpid() != 1:
        if worker_pid:
            try:
                os.killpg(worker_pid, signal.SIGKILL)
            except OSError:
                pass
            try:
                os.waitpid(worker_pid, 0)
            except ChildProcessError:
                pass
        return
    end = time.monotonic() + 5.0
    while time.monotonic() < end:
        try:
            os.kill(-1, signal.SIGKILL)
        except ProcessLookupError:
            pass
        try:
            while os.waitpid(-1, os.WNOHANG)[0] > 0:
                pass
        except ChildProcessError:
            return
        time.sleep(0.002)


class NameSupervisor:
    """Runs one graded name: launches workers, forwards their records, fills in the cases a
    dead or hung worker could not report."""

    def __init__(self, nj: dict, ns: dict, limits: dict, channel: int,
                 job_deadline: float = float("inf"), bpf: bytes = b""):
        self.nj, self.ns, self.limits, self.channel = nj, ns, limits, channel
        self.bpf = bpf             #: the seccomp filter every worker installs
        self.n = len(nj["cases"])
        #: the hard end of this name: its own budget, never beyond the notebook's
        self.hard = min(job_deadline, time.monotonic() + name_budget(limits, self.n))
        self.job_deadline = job_deadline
        self.deadlines: dict = {}  # case index -> its deadline, fixed once set
        self.next = 0              # the first case without an outcome
        self.launches = 0
        self.timeouts = 0          # timeouts in a row
        self.label = "?"           # the cell running now
        self.pid = 0
        self.status = None         # the worker's wait status, once collected

    def emit(self, rec: dict) -> None:
        rec.setdefault("name", self.nj["name"])
        write_all(self.channel, frame(rec))

    def settle(self, kind: str, message: str, seconds: float = 0.0) -> None:
        """Give case ``self.next`` an outcome of the supervisor's own."""
        self.emit({"t": "case", "i": self.next, "kind": kind, "message": message,
                   "seconds": seconds})
        self.timeouts = self.timeouts + 1 if kind == "timeout" else 0
        self.next += 1

    def settle_rest(self, kind: str, message: str) -> None:
        while self.next < self.n:
            self.settle(kind, message)

    def run(self) -> None:
        self.emit({"t": "name"})
        while self.next < self.n or self.launches == 0:
            if time.monotonic() >= self.hard:
                self.settle_rest("not-run", self.out_of_time())
                break
            if self.launches >= int(self.limits["max_launches"]):
                self.settle_rest("not-run", f"not run: the process died {self.launches} times")
                break
            if not self.launch():
                break
        self.settle_rest("not-run", "not run")
        kill_leftovers(self.pid)
        self.emit({"t": "end", "launches": self.launches})

    def launch(self) -> bool:
        """One worker process; True when another should continue with the remaining cases."""
        kill_leftovers(self.pid)
        self.launches += 1
        rfd, wfd = os.pipe()
        try:
            pid = os.fork()
        except OSError as exc:
            os.close(rfd)
            os.close(wfd)
            self.settle_rest("crashed", f"could not start a process ({exc.strerror})")
            return False
        if pid == 0:   # the worker: never returns into the supervisor's code
            try:
                os.close(rfd)
                os.close(self.channel)
                worker_main(self.nj, self.ns, self.next, self.limits, wfd, self.bpf)
            finally:
                os._exit(70)
        os.close(wfd)
        self.pid, self.status = pid, None
        try:
            return self.watch(FrameReader(rfd, self.frame_cap()))
        finally:
            os.close(rfd)

    def frame_cap(self) -> int:
        caps = [int(c["cap"]) for c in self.nj["cases"]] or [0]
        return record_cap(max(caps), int(self.limits["output_bytes"]))

    def out_of_time(self) -> str:
        """Why the cases left have no result once the name's or the notebook's time is up."""
        if time.monotonic() >= self.job_deadline:
            return (f"not run: the notebook used up its time ({self.limits['job_timeout']:g} s "
                    "for all its cells and cases)")
        return "not run: this test used up its time (every restart included)"

    def case_deadline(self, i: int, now: float) -> float:
        """Case ``i``'s deadline, fixed the first time it is asked for (nothing the worker
        sends can move it)."""
        if i not in self.deadlines:
            self.deadlines[i] = now + float(self.limits["case_timeout"]) + GRACE
        return min(self.deadlines[i], self.hard)

    def watch(self, reader: FrameReader) -> bool:
        """Forward one worker's records. The deadlines are the supervisor's: ONE for loading
        all the cells, one per case (fixed when the case is first due: after loading or after
        the previous case's result), and the name's hard end; frames cannot move them."""
        loading, started = True, time.monotonic()
        deadline = min(started + float(self.limits["load_timeout"]) + GRACE, self.hard)
        while True:
            event, payload = reader.next(deadline, self.worker_alive)
            if event != "record":
                return self.failed(event, loading, started)
            rec, raw = payload
            t, now = rec.get("t"), time.monotonic()
            if rec.get("name") != self.nj["name"]:
                return self.failed("garbage", loading, started)
            if t == "cell" and loading:   # the label only: the load deadline stays
                self.label = str(rec.get("label"))[:100]
            elif t == "note" and loading:
                if self.launches == 1:
                    self.emit({"t": "note", "text": str(rec.get("text"))[:2000]})
            elif t == "loaded" and loading:
                loading, started = False, now
                deadline = self.case_deadline(self.next, now)
                if self.launches == 1:
                    self.emit({"t": "loaded", "defined": rec.get("defined") is True,
                               "printed": str(rec.get("printed"))[:2 * self.limits["output_bytes"]]})
            elif t == "start" and not loading and rec.get("i") == self.next:
                deadline = self.case_deadline(self.next, now)
            elif t == "case" and not loading and rec.get("i") == self.next:
                if not self.forward_case(rec, raw):
                    return False
                started, deadline = now, self.case_deadline(self.next, now)
            elif t == "done" and not loading:
                return False
            else:
                return self.failed("garbage", loading, started)

    def forward_case(self, rec: dict, raw: bytes) -> bool:
        """Pass case ``self.next``'s result on; False when the rest of the name is not run."""
        write_all(self.channel, raw)
        self.timeouts = self.timeouts + 1 if rec.get("kind") == "timeout" else 0
        self.next += 1
        if self.timeouts >= TIMEOUTS_IN_A_ROW:
            self.settle_rest("not-run", f"not run: the {TIMEOUTS_IN_A_ROW} cases "
                                        "before it timed out")
            return False
        return True

    def worker_alive(self) -> bool:
        """False once the worker has exited (its wait status is kept)."""
        if self.status is None:
            try:
                pid, status = os.waitpid(self.pid, os.WNOHANG)
            except ChildProcessError:
                pid, status = self.pid, 0
            if pid:
                self.status = status
        return self.status is None

    def exit_status(self, wait: float) -> str:
        end = time.monotonic() + wait
        while self.worker_alive():
            if time.monotonic() >= end:
                return "the process stopped responding"
            time.sleep(0.005)
        return _describe_status(self.status)

    def failed(self, event: str, loading: bool, started: float) -> bool:
        """The worker died, hung or sent something wrong: settle what it left, decide."""
        why = self.exit_status(1.0) if event == "eof" else ""
        kill_leftovers(self.pid)
        spent = time.monotonic() - started
        if event == "timeout" and time.monotonic() >= self.hard:
            self.settle_rest("not-run", self.out_of_time())
            return False
        if loading:
            if event == "timeout":
                self.settle_rest("timeout", f"the cells did not finish within "
                                            f"{self.limits['load_timeout']:g} s (cell "
                                            f"{self.label} was running)")
            elif event == "eof":
                self.settle_rest("crashed", f"crashed while running cell {self.label}: {why}")
            else:
                self.settle_rest("rejected", "the cells produced an unrecognised record")
            return False
        if self.next >= self.n:
            return False
        if event == "timeout":
            self.settle("timeout", f"took longer than {self.limits['case_timeout']:g} s "
                                   "(stopped by the supervisor)", spent)
            if self.timeouts >= TIMEOUTS_IN_A_ROW:
                self.settle_rest("not-run", f"not run: the {TIMEOUTS_IN_A_ROW} cases before "
                                            "it timed out")
                return False
        elif event == "eof":
            self.settle("crashed", why, spent)
        elif event == "too-large":
            self.settle("rejected", "result too large", spent)
        else:
            self.settle("rejected", "produced an unrecognised record", spent)
        return True


def _notebook_helpers(ns: dict) -> None:
    """What a notebook cell may expect from IPython (magics were stripped by the grader)."""

    class NoIPython:
        def __getattr__(self, name):
            return lambda *a, **k: None

    no_ipython = NoIPython()
    ns.setdefault("display", lambda *a, **k: None)
    ns.setdefault("get_ipython", lambda: no_ipython)


def run_setup(source: str, ns: dict, timeout: float) -> list:
    """Execute the instructor's setup cell (trusted) under a time limit; notes on failure."""
    def on_alarm(signum, frame_):
        raise CaseTimeout("time limit")

    signal.signal(signal.SIGALRM, on_alarm)
    notes = []
    try:
        try:
            signal.setitimer(signal.ITIMER_REAL, timeout)
            exec(compile(source, "<setup cell>", "exec"), ns)
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
    except CaseTimeout:
        notes.append(f"the setup cell did not finish within {timeout:g} s")
    except BaseException as exc:  # noqa: BLE001 - reported, never fatal
        notes.append(f"the setup cell raised {_exc_name(exc)}: {_safe_str(exc, 300)}")
    signal.signal(signal.SIGALRM, signal.SIG_IGN)
    _notebook_helpers(ns)
    return notes


def _parse_args(argv: list) -> dict:
    opts = {"--job": "/job", "--site": "", "--channel-fd": ""}
    it = iter(argv)
    for arg in it:
        if arg not in opts:
            raise SystemExit(f"child.py: unknown argument {arg!r}")
        opts[arg] = next(it)
    return opts


def main(argv: list) -> None:
    """The supervisor's entry point: ``child.py --job FILE --site DIR --channel-fd N``."""
    opts = _parse_args(argv)
    channel = int(opts["--channel-fd"])
    _libc_prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
    _libc_prctl(PR_SET_DUMPABLE, 0)
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, signal.SIG_DFL)
    with open(opts["--job"], "rb") as f:
        job = json.loads(f.read())
    limits = job["limits"]
    job_deadline = time.monotonic() + float(limits["job_timeout"])
    _set_rlimits(limits, float(limits["budget_seconds"]))
    # the interpreter's own standard library, then the site dir (NumPy, the allowed tables)
    stdlib = [p for p in sys.path if p.startswith(sys.base_prefix + os.sep)]
    sys.path[:] = stdlib + ([opts["--site"]] if opts["--site"] else [])
    import builtins

    import numpy  # noqa: F401 - imported once here, inherited by every worker

    bpf = base64.b64decode(job.get("filter") or "")
    if bpf and not _seccomp_supported():   # before any record: the grader's problem
        raise SystemExit("child.py: this kernel cannot install seccomp filters")
    notes = _preload(list(job.get("modules") or ()))
    sys.stdout = sys.stderr = Capture(int(limits["output_bytes"]))
    ns = {"__name__": "__main__", "__builtins__": builtins}
    for note in notes + run_setup(job["setup"], ns, float(limits["load_timeout"])):
        write_all(channel, frame({"t": "note", "name": None, "text": note}))
    import gc

    gc.freeze()   # what the workers inherit is never collected there: no copy-on-write storm
    for nj in job["names"]:
        NameSupervisor(nj, ns, limits, channel, job_deadline, bpf).run()
    write_all(channel, frame({"t": "done"}))
    os._exit(0)


if __name__ == "__main__":
    main(sys.argv[1:])
