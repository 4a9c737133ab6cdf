"""The one place ``grade`` meets the OS-level sandbox (:mod:`autograder.isolation`)."""

from __future__ import annotations

try:
    from ..isolation import UNSAFE_WARNING, IsolationUnavailable, Mode, probe, run_notebook
    from ..isolation.jobs import CaseInput, Limits, NameJob, NotebookJob
except ImportError:  # TEMPORARY until branch iso is merged
    from .standin import (UNSAFE_WARNING, CaseInput, IsolationUnavailable, Limits, Mode, NameJob,
                          NotebookJob, probe, run_notebook)

__all__ = ["UNSAFE_WARNING", "CaseInput", "IsolationUnavailable", "Limits", "Mode", "NameJob",
           "NotebookJob", "probe", "run_notebook"]
