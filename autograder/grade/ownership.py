"""What ``grade`` wrote, handed back to the course's owner when it ran as root.

Grading runs as root (only root gives each job a uid and a cgroup, :mod:`autograder.isolation`),
but the instructor who then marks in the Formgrader, exports and hands back is an ordinary
account: a gradebook, an ``autograded/`` folder or an output folder left owned by root would
refuse their writes ("attempt to write a readonly database"). So every file that root created
or rewrote under the course root and the output folder is given to whoever owns that folder;
a course folder that root owns (the hub's grader account runs the service as root with its
group, ``deploy/``) is left as it is.
"""

from __future__ import annotations

import os
from pathlib import Path


def give_back(folder: Path, trees) -> int:
    """Chown every root-owned entry of ``trees`` (paths at or below ``folder``, which need not
    exist) to ``folder``'s owner and group when this process is root and the folder is not
    root's; symbolic links are changed themselves, never followed. The number of entries
    changed."""
    if os.geteuid() != 0:
        return 0
    try:
        owner = os.stat(folder)
    except OSError:
        return 0
    if owner.st_uid == 0:
        return 0
    changed = 0
    for tree in trees:
        for path in _entries(Path(tree)):
            try:
                st = os.lstat(path)
                if st.st_uid == 0:
                    os.lchown(path, owner.st_uid, owner.st_gid)
                    changed += 1
            except OSError:
                continue
    return changed


def _entries(tree: Path):
    """``tree`` and, for a folder, everything below it (links not followed)."""
    if not os.path.lexists(tree):
        return
    yield tree
    if tree.is_dir() and not tree.is_symlink():
        for top, dirs, files in os.walk(tree):
            for name in dirs + files:
                yield Path(top) / name
