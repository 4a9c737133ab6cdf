"""The system calls a worker may not make: a seccomp filter, built here with libseccomp.

Compiling the course's references hides their source, not their behaviour: anything the students'
copy can *call* could be carried into the sandbox as bytes (a solution cell writes a compiled
module from the students' wheel into ``/tmp`` and imports it). So the worker that runs a
student's cells executes no native code the job brings: once the interpreter, NumPy and the
modules of :data:`~autograder.isolation.allowlist.ALLOWED_MODULES` are loaded, and before any
student text runs, it installs this filter (irrevocable, enforced by the kernel, inherited by
every thread and process it makes). The filter refuses

- new executable memory: ``mmap``, ``mprotect`` and ``pkey_mprotect`` with ``PROT_EXEC``, and
  ``shmat`` (``SHM_EXEC``); so ``dlopen`` of any library not loaded yet fails, and so does
  ctypes or ``mmap`` code injection;
- other ways to run or hide code: ``execve``, ``execveat``, ``memfd_create``, ``memfd_secret``;
- state that outlives the job or reaches other processes: the keyring calls (keyrings are not
  namespaced, so a key added under the job's uid would wait for the next job of that uid),
  ``ptrace``, ``process_vm_readv``/``writev``, ``pidfd_getfd``, ``kcmp``;
- System V IPC (message queues, semaphores, shared memory) and POSIX message queues: the
  workers of one job share the sandbox's IPC namespace, so one name's worker could leave its
  hidden inputs in a queue for a later name's worker, whose visible case would carry them onto
  the page (the scratch folder is emptied between names; an IPC object would not be);
- new namespaces (user namespaces are off inside the sandbox): ``unshare``, ``setns``, and
  ``clone`` with any ``CLONE_NEW*`` bit; ``clone3`` answers ``ENOSYS`` (its flags are in memory
  a filter cannot read), so glibc falls back to ``clone``, as Docker does;
- the rest of Docker's default profile's refusals: ``bpf``, ``userfaultfd``, ``io_uring_*``,
  ``personality``, ``perf_event_open``, the mount family, module and ``kexec`` calls, clocks...

Refused calls fail with ``EPERM`` (never a kill), so an import fails as an ``ImportError`` and
the grading says why (``rejected-code``). Calls of another architecture's ABI (i386
``int 0x80``, x32 numbers) are refused the same way. The grader builds the filter once
(:func:`filter_bytes`, classic BPF) and passes it in the job; the worker installs it with two
``prctl`` calls, so libseccomp is needed on the grader's side only.

Why libseccomp through ``pyseccomp``: libseccomp is the library Docker, systemd and bubblewrap's
callers use to build filters (it knows every architecture's numbers and the x32 trap);
``pyseccomp`` is its API-compatible ctypes binding, so it works in any Python, where Debian's
``python3-seccomp`` exists only for the system interpreter.
"""

from __future__ import annotations

import errno
import functools
import tempfile

PROT_EXEC = 0x4
#: ``CLONE_NEW*`` flags that ``clone`` may not carry (``CLONE_NEWTIME`` lies in ``clone``'s
#: exit-signal byte, so it exists for ``unshare`` and ``clone3`` only: both refused whole).
CLONE_NEW = {"CLONE_NEWNS": 0x00020000, "CLONE_NEWCGROUP": 0x02000000,
             "CLONE_NEWUTS": 0x04000000, "CLONE_NEWIPC": 0x08000000,
             "CLONE_NEWUSER": 0x10000000, "CLONE_NEWPID": 0x20000000,
             "CLONE_NEWNET": 0x40000000}
#: Calls refused whatever their arguments.
REFUSED = (
    # running or hiding code
    "execve", "execveat", "memfd_create", "memfd_secret", "shmat", "uselib",
    # a code segment of the process's own (Docker's default profile refuses it too)
    "modify_ldt",
    # the kernel keyrings (not namespaced: a key would outlive the job)
    "add_key", "keyctl", "request_key",
    # System V IPC and POSIX message queues: shared by the job's workers, outliving each one
    "msgget", "msgsnd", "msgrcv", "msgctl", "semget", "semop", "semtimedop", "semctl",
    "shmget", "shmdt", "shmctl", "mq_open", "mq_unlink", "mq_timedsend", "mq_timedreceive",
    "mq_notify", "mq_getsetattr", "ipc",
    # other processes' memory
    "ptrace", "process_vm_readv", "process_vm_writev", "pidfd_getfd", "kcmp",
    "process_madvise",
    # namespaces
    "unshare", "setns",
    # kernel attack surface a computation never needs (Docker's default profile)
    "bpf", "userfaultfd", "io_uring_setup", "io_uring_enter", "io_uring_register",
    "personality", "perf_event_open", "fanotify_init", "lookup_dcookie", "syslog",
    "mount", "umount2", "pivot_root", "chroot", "move_mount", "open_tree", "fsopen", "fsmount",
    "fsconfig", "fspick", "mount_setattr", "name_to_handle_at", "open_by_handle_at",
    "init_module", "finit_module", "delete_module", "kexec_load", "kexec_file_load",
    "acct", "swapon", "swapoff", "reboot", "quotactl", "quotactl_fd", "nfsservctl", "ustat",
    "sysfs", "_sysctl", "vhangup", "iopl", "ioperm", "create_module", "get_kernel_syms",
    "query_module", "settimeofday", "clock_settime", "clock_adjtime", "adjtimex",
    "mbind", "set_mempolicy", "move_pages", "migrate_pages",
)
#: Calls refused only with ``PROT_EXEC`` in their protection argument (argument 2).
EXEC_MAPPINGS = ("mmap", "mprotect", "pkey_mprotect")


class SeccompUnavailable(RuntimeError):
    """libseccomp (``libseccomp2``) or its binding ``pyseccomp`` is missing."""


def _library():
    try:
        import pyseccomp
    except (ImportError, RuntimeError, OSError) as exc:
        raise SeccompUnavailable(f"the seccomp filter cannot be built ({exc}): install "
                                 "libseccomp2 (`make sandbox-deps`) and the Python package "
                                 "pyseccomp") from None
    return pyseccomp


def build_filter():
    """The filter as a ``pyseccomp.SyscallFilter`` (default: allow; refusals: ``EPERM``)."""
    sc = _library()
    eperm = sc.ERRNO(errno.EPERM)
    flt = sc.SyscallFilter(sc.ALLOW)
    flt.set_attr(sc.Attr.ACT_BADARCH, eperm)     # i386 and x32 numbers: refused
    for name in REFUSED:
        if sc.resolve_syscall(sc.Arch.NATIVE, name) < 0:
            continue                              # no such call on this architecture
        flt.add_rule(eperm, name)
    for name in EXEC_MAPPINGS:
        flt.add_rule(eperm, name, sc.Arg(2, sc.MASKED_EQ, PROT_EXEC, PROT_EXEC))
    for bit in CLONE_NEW.values():                 # rules of one call are alternatives
        flt.add_rule(eperm, "clone", sc.Arg(0, sc.MASKED_EQ, bit, bit))
    flt.add_rule(sc.ERRNO(errno.ENOSYS), "clone3")
    return flt


@functools.cache
def filter_bytes() -> bytes:
    """The filter as classic BPF (``struct sock_filter`` array), built once per process."""
    flt = build_filter()
    with tempfile.TemporaryFile() as f:
        flt.export_bpf(f)
        f.flush()
        f.seek(0)
        data = f.read()
    if not data or len(data) % 8:
        raise SeccompUnavailable(f"libseccomp exported {len(data)} bytes, not a BPF program")
    return data


def available() -> bool:
    """True when the filter can be built here."""
    try:
        filter_bytes()
    except (SeccompUnavailable, OSError):
        return False
    return True
