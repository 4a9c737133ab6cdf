"""The OS-level grading sandbox: run one student's notebook where its code cannot reach
anything but its own inputs.

    from autograder.isolation import Limits, NotebookJob, NameJob, CaseInput, probe, run_notebook
    runs = run_notebook(job, Limits(), probe())      # {name: autograder.model.NameRun}

See :mod:`.runner` (the grader's side), :mod:`.inside` (the program inside the sandbox: its
supervisor, its workers, and the wire format both sides share), :mod:`.bwrap` (the sandbox
itself), :mod:`.seccomp` (the system calls a worker may not make), :mod:`.allowlist` (the
grading policy: the modules a solution may use, the allow-listed ``course_lib``),
:mod:`.identity` (a uid per job) and :mod:`.cgroup` (the whole job's memory and process
limits).
"""

from .bwrap import UNSAFE_WARNING, IsolationError, IsolationUnavailable, Mode, probe
from .jobs import CaseInput, Limits, NameJob, NotebookJob
from .runner import run_notebook

__all__ = ["CaseInput", "IsolationError", "IsolationUnavailable", "Limits", "Mode", "NameJob",
           "NotebookJob", "UNSAFE_WARNING", "probe", "run_notebook"]
