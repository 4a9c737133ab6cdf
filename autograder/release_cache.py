"""What ``nbgrader generate_assignment`` makes of given sources, kept once and copied after.

Preparing a new course root (:func:`autograder.course.prepare_course`: ``release``, ``lab``, and
``grade`` into an ``OUT`` that holds no course yet) runs ``nbgrader generate_assignment``, which
registers every cell of the six notebooks (about 400) in a new SQLite gradebook with one commit,
and so one wait for the disk, each: about 8 s of CPU and as long again waiting on ``fsync``.
Its products, the release notebooks and that gradebook before any student is added, are a pure
function of the source notebooks, the course's configuration (its root left out), the code that
strips explanations, and the versions of nbgrader and of the nbconvert and nbformat that write
the notebooks.

When the environment variable ``AUTOGRADER_COURSE_CACHE`` names a folder, the first preparation
of a fresh root keeps those products there, under a digest of everything they are computed from
(:func:`key`), with the SHA-256 of each file; a later preparation of a fresh root with the same
digest copies them instead of running nbgrader. A copy whose bytes do not match their recorded
digests is ignored and removed (nbgrader runs again and keeps a new one), so a torn or
edited entry is never used. Only a fresh root is served: one whose SQLite gradebook and release
folder do not exist yet, so no student's data can be overwritten. Unset, nothing is kept and
nothing changes.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import uuid
from pathlib import Path

#: The environment variable naming the cache folder (unset: no cache).
ENV = "AUTOGRADER_COURSE_CACHE"
#: The gradebook's file name inside an entry.
GRADEBOOK = "gradebook.db"
#: How many entries the folder keeps (the most recently written).
KEEP = 8


def cache_dir() -> Path | None:
    """The cache folder ``AUTOGRADER_COURSE_CACHE`` names, or ``None`` when it is unset."""
    value = os.environ.get(ENV, "").strip()
    return Path(value) if value else None


def key(notebooks: list[Path], config: str) -> str:
    """A digest of what a release is computed from: the versions of nbgrader, nbconvert and
    nbformat, the configuration ``config`` (written for a placeholder root), the
    explanation-stripping code, and each source notebook's name and bytes."""
    import nbconvert
    import nbformat
    import nbgrader

    from . import explanations

    versions = f"nbgrader {nbgrader.__version__} nbconvert {nbconvert.__version__} " \
               f"nbformat {nbformat.__version__}"
    h = hashlib.sha256(versions.encode() + b"\0")
    h.update(config.encode() + b"\0")
    h.update(Path(explanations.__file__).read_bytes() + b"\0")
    for nb in notebooks:
        h.update(Path(nb).name.encode() + b"\0" + Path(nb).read_bytes() + b"\0")
    return h.hexdigest()[:32]


def _sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _write(path: Path, data: bytes, mode: int) -> None:
    """Write ``data`` to ``path`` whole (a temporary file renamed over it)."""
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex}.tmp")
    tmp.write_bytes(data)
    os.chmod(tmp, mode)
    os.replace(tmp, path)


def _read(entry: Path) -> dict[str, tuple[bytes, int]] | None:
    """``{name: (bytes, mode)}`` of the entry's files, each checked against the digest its
    manifest records; ``None`` when the entry does not exist. A torn, edited or unreadable
    entry is removed (the next :func:`store` replaces it) and reads as ``None``."""
    if not (entry / "manifest.json").is_file():
        return None
    try:
        manifest = json.loads((entry / "manifest.json").read_text(encoding="utf-8"))
        files = {}
        for name, meta in manifest["files"].items():
            data = (entry / name).read_bytes()
            if _sha(data) != meta["sha256"]:
                raise ValueError(f"{name} differs from its digest")
            files[name] = (data, int(meta["mode"]) & 0o777)
        if GRADEBOOK not in files:
            raise ValueError("no gradebook")
        return files
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        shutil.rmtree(entry, ignore_errors=True)
        return None


def restore(digest: str, release_dir: Path, db_file: Path, expected: list[str]) -> bool:
    """Copy the entry ``digest`` into a fresh course: the release notebooks into
    ``release_dir``, the gradebook to ``db_file``. ``False`` (and nothing written) when the
    cache is off, the course is not fresh, the entry is missing or bad (:func:`_read`), or it
    holds other notebooks than ``expected``."""
    folder = cache_dir()
    if folder is None or db_file.exists() or release_dir.exists():
        return False
    files = _read(folder / digest)
    if files is None:
        return False
    released = sorted(n[len("release/"):] for n in files if n.startswith("release/"))
    if released != sorted(expected):
        return False
    release_dir.mkdir(parents=True)
    for name in released:
        _write(release_dir / name, *files[f"release/{name}"])
    _write(db_file, *files[GRADEBOOK])
    return True


def store(digest: str, release_dir: Path, db_file: Path) -> None:
    """Keep a fresh course's release notebooks and gradebook as the entry ``digest`` (nothing
    when the cache is off or the entry exists). Written to a temporary folder renamed into
    place, so a reader sees a whole entry or none; a failure to write is not an error (the
    next preparation runs nbgrader again)."""
    folder = cache_dir()
    if folder is None or (folder / digest).exists():
        return
    tmp = folder / f".{digest}.{uuid.uuid4().hex}.tmp"
    try:
        (tmp / "release").mkdir(parents=True)
        sources = {GRADEBOOK: db_file}
        sources.update({f"release/{p.name}": p for p in sorted(release_dir.glob("*.ipynb"))})
        files = {}
        for name, path in sources.items():
            data = path.read_bytes()
            (tmp / name).write_bytes(data)
            files[name] = {"sha256": _sha(data), "mode": path.stat().st_mode & 0o777}
        (tmp / "manifest.json").write_text(json.dumps({"files": files}, indent=1) + "\n",
                                           encoding="utf-8")
        os.rename(tmp, folder / digest)
    except OSError:  # another process stored it first, or the disk refused: no entry
        pass
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    _prune(folder)


def _prune(folder: Path) -> None:
    """Keep the ``KEEP`` most recently written entries; drop temporary folders a day old (left
    by a process that died while storing)."""
    import time

    try:
        found = [(p, p.stat().st_mtime) for p in folder.iterdir() if p.is_dir()]
    except OSError:
        return
    entries = sorted((e for e in found if not e[0].name.startswith(".")),
                     key=lambda e: e[1], reverse=True)
    stale = [p for p, mtime in found if p.name.startswith(".") and mtime < time.time() - 86400]
    for old in [p for p, _ in entries[KEEP:]] + stale:
        shutil.rmtree(old, ignore_errors=True)


__all__ = ["ENV", "cache_dir", "key", "restore", "store"]
