"""``grade``'s batch in chunks of students, what is graded kept after each chunk.

A batch stopped by a time limit used to leave no ``grades.csv`` at all: the outputs were written
once, at the end. :func:`grade_in_chunks` calls the public
:func:`~autograder.grade.batch.grade_batch` on a few students at a time (``chunk``, by default
eight per sandbox slot, so the slots stay busy and the pause between chunks is one notebook's
time at most) and hands the merged batch to ``on_chunk`` after each, which ``grade`` uses to
rewrite ``grades.csv`` atomically (:func:`write_csv_atomic`). A kill then loses at most the chunk
in flight; running ``grade`` again re-grades everyone, as before.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

from ..grade.batch import Options, grade_batch
from ..grade.reading import discover_students
from ..model import Batch, SourceNotebook
from ..outputs import csv as csv_output


def grade_in_chunks(submitted: Path, sources: list[SourceNotebook], opts: Options,
                    on_chunk=None, chunk: int | None = None) -> Batch:
    """The batch of every student of ``submitted``, graded ``chunk`` students at a time;
    ``on_chunk(batch so far)`` after each chunk."""
    students = discover_students(Path(submitted))
    size = chunk or max(8, 8 * opts.jobs)
    if size < 1:
        raise ValueError(f"chunk must be at least 1, got {size}")
    merged = Batch([], {}, [])
    for start in range(0, max(1, len(students)), size):
        part = grade_batch(submitted, sources, opts, students=students[start:start + size])
        merged.results.extend(part.results)
        merged.submissions.update(part.submissions)
        merged.students.extend(part.students)
        if on_chunk is not None:
            on_chunk(merged)
        if opts.progress and len(students) > size:
            print(f"{len(merged.students)} of {len(students)} students graded",
                  file=sys.stderr)
    return merged


def write_csv_atomic(batch: Batch, path: Path) -> None:
    """``grades.csv`` of ``batch`` through a temporary file and a rename (a kill while writing
    leaves the previous file whole)."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.partial")
    csv_output.write_csv(batch.results, tmp)
    os.replace(tmp, path)

