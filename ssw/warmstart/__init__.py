"""Warm start: one process that has imported what ssw's commands use forks each
``python -m ssw`` command of a workflow run on this machine, so that no command imports
numpy, scipy, h5py, matplotlib and ssw again.

Why: each job of the thesis study spent 0.35-0.95 s importing before its own work
(``python -X importtime`` on its 19 commands: 10 s in all, a fifth of the study's CPU
time), and its own work takes from 0.05 s to 7 s.

How:

* the workflow starts the warm process (:func:`ssw.warmstart.server.serve`) when a run
  begins on this machine (``workflow/rules/common.smk``, ``onstart``:
  :func:`ssw.warmstart.run.start_for`), and stops it when the run ends; it names the Unix
  socket in ``$SSW_WARM_SOCKET``;
* ``python -m ssw`` (``ssw/__main__.py``) sends the command to that socket (:func:`request`)
  with its working folder, environment, umask and standard streams (as file descriptors);
* the warm process forks; the fork runs ``ssw.cli.main`` on the command in a session of its
  own once the caller confirmed it waits for it, and exits with its status, which the caller
  takes as its own; the caller passes on the signals it receives (SIGTERM, SIGINT, SIGHUP,
  SIGQUIT).

What a fork runs is what a fresh process runs: the warm process only imported modules
(``PRELOAD``) and ran nothing of ssw, every command is a fork of that same unchanged
process, so nothing carries over from one command to the next, and it serves only while
every file it imported is unchanged on disk (after an edit, every command runs by itself).

A command runs by itself, as without the warm process, when nothing answers at the socket,
when the warm process does not answer in time or cannot fork, when the code changed since
it loaded, or when anything that shapes the command's imports or its process differs from
the warm process's (:func:`fingerprint`): the interpreter, the module search path (the
working folder is on it), the interpreter's flags, an environment variable read when
modules load (the BLAS thread counts, the locale, ``PYTHON*``, matplotlib's) or set by a
launcher whose processes must not be forked elsewhere (MPI's ``mpiexec``, a Slurm job), the
resource limits, the CPUs it may run on, its niceness.

Where forking a process that imported these libraries is unsafe the warm start steps aside
and every command runs by itself (:func:`usable`): off POSIX (Windows, where the lab PCs
acquire with NI-DAQmx, has no ``fork``), and on macOS, where system libraries keep threads
that a fork does not copy: numpy's BLAS there is Apple's Accelerate, whose work runs on
Grand Central Dispatch's thread pools (a ``numpy.dot`` in a fork of a process that used it
hangs [2]_), and the Objective-C runtime aborts a fork's child that initializes a class
another thread was initializing at the fork (since macOS 10.13 [3]_). CPython made
``spawn`` the default start method of ``multiprocessing`` on macOS for these crashes
(Python 3.8, bpo-33725 [1]_).

Why ssw's own: ``multiprocessing``'s forkserver serves only the process that started it,
while the commands here are separate processes started by Snakemake's shell.

The warm process is :mod:`ssw.warmstart.server`; starting and stopping it for a run, and the
jobs' benchmark records, :mod:`ssw.warmstart.run`. Their public names are reachable from
here too (``ssw.warmstart.start_for``).

References
----------
.. [1] Python documentation, ``multiprocessing``, "Contexts and start methods": "Changed in
   version 3.8: On macOS, the spawn start method is now the default. The fork start method
   should be considered unsafe as it can lead to crashes of the subprocess. See
   bpo-33725."
.. [2] numpy issue 5752, "NumPy dot hangs when used with multiprocessing (potentially
   Apple Accelerate related?)", https://github.com/numpy/numpy/issues/5752.
.. [3] G. Parker, "Objective-C and fork() in macOS 10.13" (2017),
   http://www.sealiesoftware.com/blog/archive/2017/6/5/Objective-C_and_fork_in_macOS_1013.html:
   "+[X initialize] may have been in progress in another thread when fork() was called"
   and the ``OBJC_DISABLE_INITIALIZE_FORK_SAFETY`` switch.
"""

from __future__ import annotations

# The caller's side (request) runs in every served command before anything else: it
# imports only these; the warm process's and the run's sides import theirs where used.
import json
import os
import select
import signal
import socket
import struct
import sys
import time

TYPE_CHECKING = False  # typing's own costs a served command 3 ms to import
if TYPE_CHECKING:
    from typing import Any

#: Environment variable naming the warm process's socket (set by
#: :func:`ssw.warmstart.run.start`).
SOCKET_ENV = "SSW_WARM_SOCKET"
#: Environment variable that turns the warm start off for a run when it is 0, off, no or
#: false (then every command imports by itself).
SWITCH_ENV = "SSW_WARM_START"
#: Signals a waiting caller passes on to its command (those of them this system has).
FORWARDED = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGINT", "SIGHUP", "SIGQUIT")
                  if hasattr(signal, name))
#: Length prefix of a request (bytes of its JSON), network order.
LENGTH = struct.Struct("!I")
#: What a caller sends once it has its command's pid: it waits for the command (the fork
#: runs it only then; a caller gone before it never has its command run).
GO = b"go\n"
#: Seconds a caller waits for the warm process to take its request and answer with a pid;
#: past it the command runs by itself (no fork runs it: a fork waits for :data:`GO`).
REPLY_TIMEOUT_S = 10.0
#: Seconds between a waiting caller's checks that its command and the warm process live.
CHECK_S = 2.0
#: Seconds a caller waits for its command's status once the command ended (the warm
#: process reaps it at once); past it the warm process is taken for dead.
STATUS_GRACE_S = 10.0
#: Seconds a command has to end after SIGTERM before its process group gets SIGKILL.
TERM_GRACE_S = 10.0
#: Folder of the served commands' resource records, beside the socket (written by the warm
#: process, read by the run's benchmark records: :func:`ssw.warmstart.run.served_usage`).
USAGE_FOLDER = "jobs"
#: The message of a caller whose warm process ended while its command ran.
DIED = ("ssw: the warm process ({socket}) ended while it ran this command (pid {pid}); the "
        "command was stopped and its status is unknown: run it again, or run without the "
        f"warm start ({SWITCH_ENV}=0)")


def usable() -> bool:
    """Whether this system can serve commands from a warm process: POSIX with ``fork``,
    Unix sockets and descriptor passing, and not macOS (module docstring: its system
    libraries' threads make a fork of a process that imported them unsafe).

    Returns
    -------
    bool
        Whether it can.
    """
    return (os.name == "posix" and sys.platform != "darwin" and hasattr(os, "fork")
            and hasattr(socket, "AF_UNIX") and hasattr(socket, "send_fds"))


def switch_allows() -> bool:
    """Whether ``$SSW_WARM_START`` leaves the warm start on (unset, or anything but 0, off,
    no and false).

    Returns
    -------
    bool
        Whether it does.
    """
    return os.environ.get(SWITCH_ENV, "").strip().lower() not in ("0", "off", "no", "false")


def fingerprint() -> dict[str, Any]:
    """What shapes this process's imports; a command is served only when its fingerprint
    equals the warm process's.

    Returns
    -------
    dict
        ``executable`` and ``prefix`` (the interpreter and its environment), ``path`` (the
        module search path, entries resolved: ``''`` is the working folder), ``flags``,
        ``warnoptions`` and ``xoptions`` (the interpreter's options), ``env`` (the
        variables of ``IMPORT_ENV``), and the process's resource limits, CPUs and niceness
        (a fork keeps the warm process's).
    """
    import resource

    return {
        "executable": os.path.realpath(sys.executable),
        "prefix": sys.prefix,
        "path": [os.path.realpath(p or os.curdir) for p in sys.path],
        "flags": list(sys.flags),
        "warnoptions": list(sys.warnoptions),
        "xoptions": {k: str(v) for k, v in sys._xoptions.items()},
        "env": {k: v for k, v in sorted(os.environ.items()) if k.startswith(IMPORT_ENV)},
        "limits": {k: list(resource.getrlimit(getattr(resource, k)))
                   for k in sorted(dir(resource)) if k.startswith("RLIMIT_")},
        "cpus": sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
        "nice": os.getpriority(os.PRIO_PROCESS, 0),
    }


#: Environment variables (by prefix) that shape what a process imports, or that a launcher
#: sets for its own processes: a command whose values differ runs by itself.
IMPORT_ENV = ("PYTHON", "LANG", "LC_", "TZ", "OPENBLAS_", "OMP_", "MKL_", "GOTO_", "MPL",
              "NUMPY_", "SCIPY_", "HDF5_", "PMI", "OMPI_", "HYDRA_", "MPICH_", "SLURM_JOB_ID")


def ancestry(limit: int = 32) -> list[int]:
    """This process's id and its ancestors' (parent first), up to ``limit`` of them, read
    from ``/proc`` (elsewhere: this process and its parent). A served job's benchmark
    record finds its command by them (:mod:`ssw.warmstart.run`).

    Parameters
    ----------
    limit : int
        Most ids returned.

    Returns
    -------
    list of int
        The ids, this process's first.
    """
    pids = [os.getpid(), os.getppid()]
    while len(pids) < limit and pids[-1] > 1:
        try:
            with open(f"/proc/{pids[-1]}/stat", "rb") as fh:
                parent = int(fh.read().rsplit(b")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            break
        if parent < 1:
            break
        pids.append(parent)
    return pids


# ---- the caller: python -m ssw
def request(argv: list[str] | None = None) -> int | None:
    """Run this process's ``ssw`` command in a fork of the warm process and wait for it.

    Parameters
    ----------
    argv : list of str, optional
        The command line (default ``sys.argv``: the program, then ssw's arguments).

    Returns
    -------
    int or None
        The command's exit status; None when it is to run in this process: this system
        does not serve (:func:`usable`), ``$SSW_WARM_START`` is off, no warm process is
        named or answers in :data:`REPLY_TIMEOUT_S`, a standard stream is closed, or the
        warm process leaves it to run by itself (another fingerprint, changed code, a
        failed fork).
    """
    path = os.environ.get(SOCKET_ENV)
    if not path or not usable() or not switch_allows():
        return None
    try:
        for fd in (0, 1, 2):
            os.fstat(fd)
    except OSError:
        return None
    umask = os.umask(0)
    os.umask(umask)
    payload = json.dumps({
        "argv": list(sys.argv if argv is None else argv), "cwd": os.getcwd(),
        "env": dict(os.environ), "umask": umask, "fingerprint": fingerprint(),
        "pids": ancestry(),
    }).encode()
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    sock.settimeout(REPLY_TIMEOUT_S)
    # a signal that comes before this process knows its command waits (blocked, at most
    # REPLY_TIMEOUT_S): then it goes to the command, or, when the command runs here, it
    # acts as on any process
    signal.pthread_sigmask(signal.SIG_BLOCK, FORWARDED)
    reply: dict[str, Any] = {}
    replies = sock.makefile("rb")
    try:
        sock.connect(path)
        socket.send_fds(sock, [LENGTH.pack(len(payload))], [0, 1, 2])
        sock.sendall(payload)
        reply = json.loads(replies.readline() or b"{}")
        if isinstance(reply, dict) and isinstance(reply.get("pid"), int):
            sock.sendall(GO)  # from here on the command is this caller's: it waits
        else:
            reply = {}
    except (OSError, ValueError):
        reply = {}
    if "pid" not in reply:
        sock.close()
        signal.pthread_sigmask(signal.SIG_UNBLOCK, FORWARDED)
        return None
    return _wait(int(reply["pid"]), sock, replies, path)


def signal_command(pid: int, signum: int) -> bool:
    """Send ``signum`` to the command running as ``pid`` and its children (its process
    group, once its fork made it a session leader: before that, to it alone).

    Parameters
    ----------
    pid : int
        The command's process id (its process group's once it runs).
    signum : int
        The signal.

    Returns
    -------
    bool
        Whether a process got it (False: the command and its group are gone).
    """
    try:
        os.killpg(pid, signum)
        return True
    except ProcessLookupError:
        try:
            os.kill(pid, signum)
            return True
        except ProcessLookupError:
            return False
    except PermissionError:
        return False


def stop_command(pid: int, grace_s: float = TERM_GRACE_S) -> None:
    """End the command running as ``pid`` and its process group: SIGTERM (it unwinds and
    removes its temporary files), then SIGKILL to what is left after ``grace_s``.

    Parameters
    ----------
    pid : int
        The command's process id.
    grace_s : float
        Seconds to wait for the group to end after SIGTERM.
    """
    if not signal_command(pid, signal.SIGTERM):
        return
    end = time.monotonic() + grace_s
    while time.monotonic() < end:
        if not signal_command(pid, 0):
            return
        time.sleep(0.02)
    signal_command(pid, signal.SIGKILL)


def _ended(pid: int) -> bool:
    """Whether process ``pid`` ended (gone, or a zombie its parent has not collected)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except PermissionError:
        return False
    try:
        with open(f"/proc/{pid}/stat", "rb") as fh:
            return fh.read().rsplit(b")", 1)[1].split()[0] in (b"Z", b"X")
    except (OSError, IndexError):
        return False


def _wait(pid: int, sock: socket.socket, replies: Any, path: str) -> int:
    """Wait for the status of the command running as ``pid`` (a session leader), passing
    on the signals this process receives (blocked until now); a command killed by a signal
    kills this process with the same signal. When the warm process ends first, or no
    status comes within :data:`STATUS_GRACE_S` of the command's end, the command's process
    group is stopped (:func:`stop_command`) and this process exits 1 with a message naming
    ``SSW_WARM_START=0``."""

    def forward(signum: int, frame: object) -> None:
        signal_command(pid, signum)

    for sig in FORWARDED:
        signal.signal(sig, forward)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, FORWARDED)
    line, ended_at = b"", None
    try:
        sock.settimeout(None)
        while True:
            ready, _, _ = select.select([sock], [], [], CHECK_S)
            if ready:
                line = replies.readline()
                break
            if not _ended(pid):
                ended_at = None
            elif ended_at is None:
                ended_at = time.monotonic()
            elif time.monotonic() - ended_at > STATUS_GRACE_S:
                break  # the command ended long ago and no status came: the warm process hangs
    except (OSError, ValueError):
        line = b""
    try:
        status = int(json.loads(line)["status"])
    except (ValueError, KeyError, TypeError):
        stop_command(pid)
        print(DIED.format(socket=f"{SOCKET_ENV}={path}", pid=pid), file=sys.stderr)
        return 1
    if status < 0:
        for sig in FORWARDED:
            signal.signal(sig, signal.SIG_DFL)
        sys.stdout.flush()
        os.kill(os.getpid(), -status)
        return 128 - status
    return status


#: Names of :mod:`ssw.warmstart.run` and :mod:`ssw.warmstart.server` reachable from here
#: (imported when first used: the caller imports neither).
_ELSEWHERE = {
    **dict.fromkeys(("WarmProcess", "switched_on", "start", "stop", "job_env", "start_for",
                     "run_with", "stop_all", "answering", "ONE_THREAD_ENV",
                     "attach_benchmarks", "served_usage"), "run"),
    **dict.fromkeys(("PRELOAD", "UNFORKABLE", "preload", "serve", "main", "CodeWatch"),
                    "server"),
}


def __getattr__(name: str) -> Any:
    """``ssw.warmstart.start_for`` and the like: the name from the module defining it."""
    if name in _ELSEWHERE:
        import importlib

        return getattr(importlib.import_module(f"{__name__}.{_ELSEWHERE[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
