"""The wire format between the sandbox and the grader (used by the worker, the supervisor and
the grader's :mod:`autograder.isolation.runner`).

Records are length-prefixed JSON (4-byte big-endian length, then ASCII JSON). Values are JSON
scalars, or tagged objects ``{"t": "tuple"|"list"|"dict"|"complex"|"array"}``; arrays are
base64 with a dtype from :data:`ARRAY_DTYPES` and a shape. Nothing else (no pickle, no
archive, nothing compressed). The grader re-validates everything (:func:`decode_value` with a
byte budget), because student code may have replaced any of this in its own process.

Standard library only (NumPy when a value holds arrays): this module runs inside the sandbox.
"""

from __future__ import annotations

import base64
import json
import os
import struct
import sys
import time

FRAME = struct.Struct(">I")        #: the length prefix of every record
MAX_FRAME = 2**32 - 1              #: the longest frame a length prefix can announce
MAX_DEPTH = 8                      #: containers nested deeper are rejected
MAX_INT_BITS = 4096                #: larger ints are rejected (JSON would need > 1233 digits)
SCALAR_COST = 1                    #: budget bytes charged per scalar / container element
RECORD_OVERHEAD = 64 * 1024        #: bytes a record may take beyond its value and its prints
#: The array dtypes allowed across the boundary (little-endian): bool, ints, uints, floats,
#: complex.
ARRAY_DTYPES = frozenset({"|b1", "|i1", "<i2", "<i4", "<i8", "|u1", "<u2", "<u4", "<u8",
                          "<f2", "<f4", "<f8", "<c8", "<c16"})


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


#: The most elements along one axis of a received array (NumPy's own limit is ``2**63 - 1``;
#: a zero-byte array of shape ``[0, 2**70]`` passes every size check and then fails to build).
MAX_AXIS = 2**62


def decode_value(obj, budget: Budget, depth: int = 0):
    """Rebuild a value from its wire form, checking everything.

    Total: whatever ``obj`` is (it comes from a process the student owns), this returns a
    value or raises ``BadValue``, never anything else (an overflowing complex, a shape NumPy
    cannot build, an unhashable dtype, a string with lone surrogates all included)."""
    try:
        return _decode(obj, budget, depth)
    except BadValue:
        raise
    except TooLarge:
        raise BadValue("the result is too large") from None
    except (RecursionError, MemoryError):
        raise BadValue("the result is too large") from None
    except Exception:  # noqa: BLE001 - any other failure is the value's, never the grader's
        raise BadValue("the result has an unexpected form") from None


def plain_text(text: str) -> str:
    """``text`` without lone surrogates (JSON may carry ``"\\ud800"``; UTF-8 cannot)."""
    try:
        text.encode("utf-8")
        return text
    except UnicodeEncodeError:
        return text.encode("utf-8", "replace").decode("utf-8")


def _decode(obj, budget: Budget, depth: int):
    if depth > MAX_DEPTH:
        raise BadValue("the result is nested too deeply")
    t = type(obj)
    if obj is None or t is bool or t is float:
        budget.spend(SCALAR_COST)
        return obj
    if t is int:
        if obj.bit_length() > MAX_INT_BITS:
            raise BadValue(f"an int of more than {MAX_INT_BITS} bits")
        budget.spend(SCALAR_COST)
        return obj
    if t is str:
        budget.spend(len(obj))
        return plain_text(obj)
    if t is not dict:
        raise BadValue("the result has an unexpected form")
    tag, items = obj.get("t"), obj.get("v")
    if type(tag) is not str:
        raise BadValue("the result has an unexpected form")
    if tag == "array":
        return _decode_array(obj, budget)
    if type(items) is not list:
        raise BadValue("the result has an unexpected form")
    budget.spend(SCALAR_COST * len(items))
    if tag == "tuple" or tag == "list":
        out = [_decode(x, budget, depth + 1) for x in items]
        return tuple(out) if tag == "tuple" else out
    if tag == "dict" and all(type(p) is list and len(p) == 2 and type(p[0]) is str
                             for p in items):
        return {plain_text(k): _decode(x, budget, depth + 1) for k, x in items}
    if tag == "complex" and len(items) == 2 and all(type(x) is float for x in items):
        return complex(items[0], items[1])
    if tag == "complex" and len(items) == 2 and all(type(x) in (int, float) for x in items):
        try:
            return complex(float(items[0]), float(items[1]))
        except OverflowError:
            raise BadValue("a complex number out of range") from None
    raise BadValue("the result has an unexpected form")


def _decode_array(obj: dict, budget: Budget):
    import numpy as np

    dtype, shape, data = obj.get("dtype"), obj.get("shape"), obj.get("v")
    if type(dtype) is not str or dtype not in ARRAY_DTYPES or type(data) is not str \
            or type(shape) is not list:
        raise BadValue("an array that does not hold plain numbers")
    if len(shape) > 32 or any(type(n) is not int or not 0 <= n <= MAX_AXIS for n in shape):
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
    try:
        return np.frombuffer(bytearray(raw), dtype=dtype).reshape(shape)
    except (ValueError, OverflowError, TypeError):
        raise BadValue("an array with an invalid shape") from None


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


class CaseStream:
    """The cases file as the supervisor reads it: every case's frame, the names' cases one
    after another in the job's order, so case ``g`` (counted over the whole job) is the file's
    ``g``-th frame.

    Nothing else says where a case is or how long it is: the job document (readable by student
    code) holds no offsets or lengths, and this object keeps only the count of frames passed;
    the file's offset is the kernel's (the workers have no descriptor of the file). Cases are
    read in order, each at most once; a case skipped is passed over by its length prefix,
    never read into memory."""

    def __init__(self, fd: int):
        self.fd, self.at = fd, 0
        os.lseek(fd, 0, os.SEEK_SET)

    def read(self, g: int) -> bytearray:
        """Case ``g``'s whole frame (empty when the file holds no such case or it was read
        already). The caller zeroes it when done, so no worker forked later finds it."""
        while self.at < g:
            n = self._length()
            if n is None:
                return bytearray()
            os.lseek(self.fd, n, os.SEEK_CUR)
            self.at += 1
        n = self._length() if self.at == g else None
        if n is None:
            return bytearray()
        self.at += 1
        buf = bytearray(FRAME.size + n)
        FRAME.pack_into(buf, 0, n)
        done = FRAME.size
        with memoryview(buf) as view:
            while done < len(buf):
                got = os.readv(self.fd, [view[done:]])
                if got <= 0:
                    break
                done += got
        return buf

    def _length(self) -> int | None:
        head = os.read(self.fd, FRAME.size)
        return FRAME.unpack(head)[0] if len(head) == FRAME.size else None


def write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]

