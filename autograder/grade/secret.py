"""The course secret: it seeds every student's hidden cases (keep it; never give it out)."""

from __future__ import annotations

import os
import secrets
import sys
from pathlib import Path

DEFAULT_SECRET = Path("~/.config/4f9/secret").expanduser()


def read_secret(path: Path | None, graded: str = "") -> bytes:
    """The course secret at ``path`` (default :data:`DEFAULT_SECRET`), created on first use.

    ``graded`` names the grades the course already has (empty: none). Then a missing secret
    is not created: a new one would draw other hidden cases than the grades were judged on (a
    second instructor's login, a new machine, a mistyped ``--secret-file``), so the caller must
    bring the secret over.

    Raises
    ------
    ValueError
        When the file is empty, or missing while the course already has grades.
    OSError
        When it cannot be read.
    """
    path = DEFAULT_SECRET if path is None else Path(path)
    if not path.exists():
        if graded:
            raise ValueError(
                f"{path} does not exist, but this course already has grades ({graded}); a new "
                "secret would draw other hidden cases. Copy the secret the course was graded "
                f"with to {path} (e.g. scp otherhost:.config/4f9/secret {path}; chmod 600 "
                f"{path}), or point --secret-file at it; --new-secret starts a new one anyway")
        else:
            path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
            with os.fdopen(fd, "w") as f:
                f.write(secrets.token_hex(32) + "\n")
            print(f"note: created the course secret {path} (keep it: hidden cases and "
                  "re-grades depend on it)", file=sys.stderr)
    data = path.read_bytes().strip()
    if not data:
        raise ValueError(f"the secret file {path} is empty")
    return data
