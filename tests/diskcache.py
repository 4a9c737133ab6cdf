"""Pure, costly test inputs computed once and kept on disk, keyed by what they are computed from.

``cached(name, sources, compute)`` returns ``compute()``, stored under ``.cache/tests/`` in a
file named by a digest of ``sources`` (their paths and bytes), the Python and NumPy versions:
a change to any source gives a new file, so a stale value is never read. A file lock makes
xdist workers that want the same value wait for the one computing it instead of computing it
twice; an unreadable file is computed again. Use it only for values that are a pure function
of those sources (no clock, no environment, no randomness without a fixed seed).
"""

from __future__ import annotations

import fcntl
import hashlib
import os
import pickle
import sys
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
CACHE = REPO / ".cache" / "tests"


def digest(sources: Iterable[Path]) -> str:
    h = hashlib.sha256(f"{sys.version}|numpy {np.__version__}".encode())
    for path in sorted(Path(p).resolve() for p in sources):
        h.update(str(path.relative_to(REPO) if path.is_relative_to(REPO) else path).encode())
        h.update(b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()[:20]


def cached(name: str, sources: Iterable[Path], compute: Callable[[], object]):
    """``compute()``, read from ``.cache/tests/<name>-<digest>.pickle`` when it is there."""
    CACHE.mkdir(parents=True, exist_ok=True)
    path = CACHE / f"{name}-{digest(sources)}.pickle"
    with open(CACHE / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            if path.exists():
                try:
                    return pickle.loads(path.read_bytes())
                except Exception:  # a torn or foreign file: compute it again
                    pass
            value = compute()
            tmp = path.with_suffix(f".{os.getpid()}.tmp")
            tmp.write_bytes(pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL))
            os.replace(tmp, path)
            for old in CACHE.glob(f"{name}-*.pickle"):
                if old != path:
                    old.unlink(missing_ok=True)
            return value
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)
