"""The course secret: it seeds every student's hidden cases (keep it; never give it out)."""

from __future__ import annotations

import os
import secrets
import sys
from pathlib import Path

DEFAULT_SECRET = Path("~/.config/4f9/secret").expanduser()


def read_secret(path: Path | None) -> bytes:
    """The course secret at ``path`` (created at the default location on first use).

    Raises
    ------
    ValueError
        When the file is empty.
    OSError
        When it cannot be read.
    """
    if path is None:
        path = DEFAULT_SECRET
        if not path.exists():
            path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
            with os.fdopen(fd, "w") as f:
                f.write(secrets.token_hex(32) + "\n")
            print(f"note: created the course secret {path} (keep it: hidden cases and "
                  "re-grades depend on it)", file=sys.stderr)
    data = Path(path).read_bytes().strip()
    if not data:
        raise ValueError(f"the secret file {path} is empty")
    return data
