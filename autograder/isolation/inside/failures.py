"""What went wrong in a cell or a case, said safely: a ``course_lib`` reference that is not
in the sandbox, compiled code the sandbox refused, how a process ended, and an exception's text
(a student's ``__str__`` or metaclass may raise anything).

Standard library only: this module runs inside the sandbox.
"""

from __future__ import annotations

import os
import signal

#: What a case raises when it needs what a refused import did not define.
MISSING_AFTER_REFUSAL = (NameError, AttributeError, ImportError)
#: What the grading says when the sandbox refused compiled code (or a call the seccomp filter
#: refuses) that a cell tried to load or make.
REFUSED_CODE = ("graded code may use only NumPy and the standard library modules listed in the "
                "notebook: the sandbox runs no compiled code that a notebook brings")


class Policy:
    """The grader's allow-list of ``course_lib``, as the job document carries it (see
    :func:`autograder.isolation.allowlist.sandbox_policy`).

    ``course_modules``: the parts of ``course_lib`` present in the sandbox (anything else under
    ``course_lib`` is a reference); ``off_limits``: what the grading says of a ``course_lib``
    import it met.
    """

    __slots__ = ("course_modules", "off_limits")

    def __init__(self, course_modules, off_limits: str):
        self.course_modules = tuple(str(m) for m in course_modules)
        self.off_limits = str(off_limits)

    @classmethod
    def from_job(cls, job: dict) -> Policy:
        """The policy of a job document (``job["policy"]``); ``SystemExit`` when it has none:
        the grader's problem, said before any record."""
        policy = job.get("policy")
        if not isinstance(policy, dict) or not isinstance(policy.get("course_modules"), list) \
                or not isinstance(policy.get("off_limits"), str):
            raise SystemExit("the sandbox's job names no course_lib policy")
        return cls(policy["course_modules"], policy["off_limits"])


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
                if path.endswith(".so") or "failed to map segment" in safe_str(exc, 2000):
                    return True
            if isinstance(exc, OSError) and (exc.errno == 1 or "failed to map segment"
                                             in safe_str(exc, 2000)):
                return True
            exc = exc.__cause__ or exc.__context__
    except BaseException:  # noqa: BLE001 - a student's exception may raise anything
        pass
    return False


def safe_str(obj, cap: int) -> str:
    try:
        text = str(obj)
    except BaseException:  # noqa: BLE001 - a student's __str__ may raise anything
        text = "<message unavailable>"
    if type(text) is not str:
        text = "<message unavailable>"
    return text if len(text) <= cap else text[:cap] + "..."


def describe_status(status: int) -> str:
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


def reference_module(exc: BaseException, course_modules: tuple[str, ...]) -> str:
    """What of ``course_lib`` an import (or attribute) error was about, else ``""``
    (``course_modules``: the parts of ``course_lib`` the sandbox holds, see :class:`Policy`).

    Decided by the exception's attributes (``ImportError.name``, ``AttributeError.obj`` and
    ``.name``), never by its message: a missing ``course_lib`` module, a name imported from an
    allow-listed module that it does not hold there, or an attribute of a ``course_lib``
    module."""
    if isinstance(exc, ImportError):
        name = exc.name if type(exc.name) is str else ""
        if not (name == "course_lib" or name.startswith("course_lib.")):
            return ""
        if name not in course_modules:
            return name
        return "" if isinstance(exc, ModuleNotFoundError) else f"a reference from {name}"
    if isinstance(exc, AttributeError):
        obj = getattr(exc, "obj", None)
        mod = getattr(obj, "__name__", "") if type(obj).__name__ == "module" else ""
        attr = getattr(exc, "name", "")
        if type(mod) is str and type(attr) is str and mod in course_modules:
            return f"{mod}.{attr}"
    return ""


def exc_name(exc: BaseException) -> str:
    try:
        name = type(exc).__name__
        return name if type(name) is str else "?"
    except BaseException:  # noqa: BLE001
        return "?"


def exc_mro(exc: BaseException) -> list:
    try:
        return [f"{c.__module__}.{c.__qualname__}"[:200] for c in type(exc).__mro__][:20]
    except BaseException:  # noqa: BLE001 - a metaclass may raise anything
        return []

