"""Warm start: one process that has imported what ssw's commands use forks each
``python -m ssw`` command of a workflow run on this machine, so that no command imports
numpy, scipy, h5py, matplotlib and ssw again.

Why: each job of the thesis study spent 0.35-0.95 s importing before its own work
(``python -X importtime`` on its 19 commands: 10 s in all, a fifth of the study's CPU
time), and its own work takes from 0.05 s to 7 s.

How:

* the workflow starts :func:`serve` in a process of its own when a run begins on this
  machine (``workflow/rules/common.smk``, ``onstart``: :func:`start_for`), and stops it
  when the run ends (:func:`stop`); it names the Unix socket in ``$SSW_WARM_SOCKET``;
* ``python -m ssw`` (``ssw/__main__.py``) sends the command to that socket
  (:func:`request`) with its working folder, environment, umask and standard streams (as
  file descriptors);
* the warm process forks; the fork runs ``ssw.cli.main`` on the command in a session of its
  own and exits with its status, which the caller takes as its own; the caller passes on the
  signals it receives (SIGTERM, SIGINT, SIGHUP, SIGQUIT).

What a fork runs is what a fresh process runs: the warm process only imported modules
(:data:`PRELOAD`) and ran nothing of ssw, and every command is a fork of that same
unchanged process, so nothing carries over from one command to the next.

A command runs by itself, as without the warm process, when nothing listens at the socket,
or when anything that shapes its imports or its process differs from the warm process's
(:func:`fingerprint`): the interpreter, the module search path (the working folder is on
it), the interpreter's flags, an environment variable read when modules load (the BLAS
thread counts, the locale, ``PYTHON*``, matplotlib's) or set by a launcher whose processes
must not be forked elsewhere (MPI's ``mpiexec``, a Slurm job), the resource limits, the
CPUs it may run on, its niceness.

Why ssw's own: ``multiprocessing``'s forkserver serves only the process that started it,
while the commands here are separate processes started by Snakemake's shell.
"""

from __future__ import annotations

# The caller's side (request) runs in every served command before anything else: it
# imports only these; the warm process's and the run's sides import theirs where used.
import atexit
import json
import os
import signal
import socket
import struct
import sys

TYPE_CHECKING = False  # typing's own costs a served command 3 ms to import
if TYPE_CHECKING:
    import selectors
    import subprocess
    from pathlib import Path
    from typing import Any, NoReturn

#: Environment variable naming the warm process's socket (set by :func:`start`).
SOCKET_ENV = "SSW_WARM_SOCKET"
#: Environment variable that turns the warm start off for a run when it is 0, off, no or
#: false (then every command imports by itself).
SWITCH_ENV = "SSW_WARM_START"
#: What the warm process imports: the modules that the study's commands import (measured
#: with ``python -X importtime`` on each job of ``make study``). None of them starts a
#: thread or MPI (PETSc, gmsh and MPI load in the fork that needs them): a fork of a
#: process with threads would copy their locks, not the threads.
PRELOAD = (
    "numpy", "scipy.linalg", "scipy.sparse", "scipy.sparse.linalg", "scipy.special",
    "scipy.interpolate", "scipy.optimize", "h5py", "matplotlib.pyplot", "PIL.PngImagePlugin",
    "jsonschema",
    "ssw.cli", "ssw.cli.calibrate", "ssw.cli.chain", "ssw.cli.contact", "ssw.cli.design",
    "ssw.cli.fit", "ssw.cli.report", "ssw.cli.validate", "ssw.cli._device", "ssw.cli._sample",
    "ssw.cli._soil", "ssw.calibration.fit", "ssw.calibration.references", "ssw.chain.run",
    "ssw.contact.batch", "ssw.contact.figures", "ssw.contact.petsc_solver",
    "ssw.contact.scene", "ssw.contact.stress", "ssw.contact.substructure", "ssw.curve",
    "ssw.daq.importers", "ssw.design.output", "ssw.design.spec", "ssw.fit.figures",
    "ssw.fit.laws", "ssw.fit.pipeline", "ssw.fit.range", "ssw.measure", "ssw.modulus",
    "ssw.plotting", "ssw.report", "ssw.signal.tof", "ssw.tof.api", "ssw.tof.impact",
    "ssw.tof.inverse", "ssw.tof.sweep", "ssw.validation.figures", "ssw.validation.output",
    "ssw.validation.table", "ssw.walls.fem", "ssw.workflow",
)
#: Modules the warm process must not import (they start threads or MPI when they load or
#: initialize): :func:`preload` refuses to serve when one of them came in.
UNFORKABLE = ("petsc4py", "mpi4py", "dolfinx_solver", "gmsh")
#: Environment variables (by prefix) that shape what a process imports, or that a launcher
#: sets for its own processes: a command whose values differ runs by itself.
IMPORT_ENV = ("PYTHON", "LANG", "LC_", "TZ", "OPENBLAS_", "OMP_", "MKL_", "GOTO_", "MPL",
              "NUMPY_", "SCIPY_", "HDF5_", "PMI", "OMPI_", "HYDRA_", "MPICH_", "SLURM_JOB_ID")
#: The thread counts Snakemake's shell gives a job of ``threads: 1`` (every rule of the
#: study): the warm process of a run loads with them.
ONE_THREAD_ENV = {v: "1" for v in ("OMP_NUM_THREADS", "GOTO_NUM_THREADS",
                                   "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                                   "VECLIB_MAXIMUM_THREADS", "NUMEXPR_NUM_THREADS")}
#: Signals a waiting caller passes on to its command.
FORWARDED = (signal.SIGTERM, signal.SIGINT, signal.SIGHUP, signal.SIGQUIT)
#: Length prefix of a request (bytes of its JSON), network order.
_LENGTH = struct.Struct("!I")
#: Longest request accepted (its argv and environment), bytes.
MAX_REQUEST = 1 << 22
#: Seconds the warm process waits for a request's bytes once a caller connected.
REQUEST_TIMEOUT_S = 10.0
#: Seconds between the warm process's checks that the run that started it is alive.
POLL_S = 1.0


def fingerprint() -> dict[str, Any]:
    """What shapes this process's imports; a command is served only when its fingerprint
    equals the warm process's.

    Returns
    -------
    dict
        ``executable`` and ``prefix`` (the interpreter and its environment), ``path`` (the
        module search path, entries resolved: ``''`` is the working folder), ``flags``,
        ``warnoptions`` and ``xoptions`` (the interpreter's options), ``env`` (the
        variables of :data:`IMPORT_ENV`), and the process's resource limits, CPUs and
        niceness (a fork keeps the warm process's).
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


#: The fields of :func:`fingerprint`, as the warm process's log names them.
_FIELDS = {"executable": "the interpreter", "prefix": "the interpreter's environment",
           "path": "the module search path", "flags": "the interpreter's flags",
           "warnoptions": "the warning options", "xoptions": "the -X options",
           "limits": "the resource limits", "cpus": "the CPUs", "nice": "the niceness"}


def _difference(mine: dict[str, Any], theirs: dict[str, Any]) -> str | None:
    """The first field in which two fingerprints differ (for the record), or None."""
    for key in sorted(mine.keys() | theirs.keys()):
        if mine.get(key) != theirs.get(key):
            if key == "env":
                a, b = mine.get(key, {}), theirs.get(key, {})
                names = sorted(k for k in a.keys() | b.keys() if a.get(k) != b.get(k))
                return f"environment variables {', '.join(names)}"
            return _FIELDS.get(key, key)
    return None


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
        The command's exit status; None when it is to run in this process: no warm process
        is named or listens, a standard stream is closed, or the fingerprints differ.
    """
    path = os.environ.get(SOCKET_ENV)
    if not path:
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
    }).encode()
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    # a signal that comes before this process knows its command waits (blocked): then it
    # goes to the command, or, when the command runs here, it acts as on any process
    signal.pthread_sigmask(signal.SIG_BLOCK, FORWARDED)
    try:
        sock.connect(path)
        socket.send_fds(sock, [_LENGTH.pack(len(payload))], [0, 1, 2])
        sock.sendall(payload)
        replies = sock.makefile("rb")
        reply = json.loads(replies.readline() or b"{}")
    except (OSError, ValueError):
        reply = {}
    if "pid" not in reply:
        sock.close()
        signal.pthread_sigmask(signal.SIG_UNBLOCK, FORWARDED)
        return None
    return _wait(int(reply["pid"]), replies, path)


def _signal_command(pid: int, signum: int) -> None:
    """Send ``signum`` to the command running as ``pid`` and its children (its process
    group, once its fork made it a session leader: before that, to it alone)."""
    try:
        os.killpg(pid, signum)
    except ProcessLookupError:
        try:
            os.kill(pid, signum)
        except ProcessLookupError:
            pass
    except PermissionError:
        pass


def _wait(pid: int, replies: Any, path: str) -> int:
    """Wait for the status of the command running as ``pid`` (a session leader), passing
    on the signals this process receives (blocked until now); a command killed by a signal
    kills this process with the same signal."""

    def forward(signum: int, frame: object) -> None:
        _signal_command(pid, signum)

    for sig in FORWARDED:
        signal.signal(sig, forward)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, FORWARDED)
    try:
        line = replies.readline()
    except OSError:
        line = b""
    try:
        status = int(json.loads(line)["status"])
    except (ValueError, KeyError, TypeError):
        print(f"ssw: the warm process ({SOCKET_ENV}={path}) ended before the command "
              f"(pid {pid}) did: its status is unknown", file=sys.stderr)
        return 1
    if status < 0:
        for sig in FORWARDED:
            signal.signal(sig, signal.SIG_DFL)
        sys.stdout.flush()
        os.kill(os.getpid(), -status)
        return 128 - status
    return status


# ---- the warm process
def preload(modules: tuple[str, ...] = PRELOAD) -> None:
    """Import ``modules`` (matplotlib on its Agg backend, as ssw.plotting draws) and check
    that the process may fork: no module of :data:`UNFORKABLE` and no thread but this one.

    Parameters
    ----------
    modules : tuple of str
        Module names.

    Raises
    ------
    RuntimeError
        When an unforkable module came in or a thread runs (named).
    """
    import importlib

    import matplotlib

    matplotlib.use("Agg")
    for name in modules:
        importlib.import_module(name)
    bad = sorted(m for m in sys.modules if m.split(".")[0] in UNFORKABLE)
    if bad:
        raise RuntimeError(f"the warm process imported {', '.join(bad[:5])}: it must not "
                           "(they start threads or MPI); take them out of PRELOAD")
    threads = len(os.listdir("/proc/self/task")) if os.path.isdir("/proc/self/task") else 1
    if threads != 1:
        raise RuntimeError(f"the warm process runs {threads} threads after its imports: a "
                           "fork would copy their locks, not them")


class _Server:
    """The warm process's state: its socket, the callers waiting, and its signals.

    Parameters
    ----------
    listener : socket.socket
        The listening socket.
    path : str
        Its path.
    parent : int
        The process id of the run that started this process.
    """

    def __init__(self, listener: socket.socket, path: str, parent: int) -> None:
        import selectors

        self.listener, self.path, self.parent = listener, path, parent
        self.wake_r, self.wake_w = socket.socketpair()
        for s in (self.wake_r, self.wake_w):
            s.setblocking(False)
        self.selector: selectors.BaseSelector = selectors.DefaultSelector()
        self.mine = fingerprint()
        self.waiting: dict[int, socket.socket] = {}
        self.stopping = False

    def sockets(self) -> list[socket.socket]:
        """Every socket this process holds (a fork closes them all)."""
        return [self.listener, self.wake_r, self.wake_w, *self.waiting.values()]


def serve(path: str, parent: int) -> None:
    """Preload, then fork a command for each request at the Unix socket ``path`` until
    SIGTERM or the end of process ``parent`` (the run that started this one); then wait for
    the commands still running and relay their statuses.

    Parameters
    ----------
    path : str
        The socket's path (created here; its folder must exist).
    parent : int
        The process id of the run that started this one.
    """
    import gc
    import selectors

    preload()
    gc.freeze()  # the forks' collections then leave the preloaded objects' pages shared
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    listener.bind(f"{path}.new")
    listener.listen(128)
    os.replace(f"{path}.new", path)  # the path appears when it accepts
    srv = _Server(listener, path, parent)

    def stop(signum: int, frame: object) -> None:
        srv.stopping = True

    signal.set_wakeup_fd(srv.wake_w.fileno())
    signal.signal(signal.SIGCHLD, lambda signum, frame: None)
    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    srv.selector.register(listener, selectors.EVENT_READ, "accept")
    srv.selector.register(srv.wake_r, selectors.EVENT_READ, "wake")
    print(f"ssw warm start: {len(sys.modules)} modules loaded; listening at {path}",
          flush=True)
    while not (srv.stopping and not srv.waiting):
        for key, _ in srv.selector.select(POLL_S):
            if key.data == "accept":
                _accept(srv)
            elif key.data == "wake":
                try:
                    srv.wake_r.recv(4096)
                except BlockingIOError:
                    pass
            else:
                _caller_left(srv, key.data, key.fileobj)
        _reap(srv)
        if not srv.stopping and os.getppid() != parent:
            srv.stopping = True
        if srv.stopping and srv.listener.fileno() >= 0:
            srv.selector.unregister(srv.listener)
            srv.listener.close()
            if os.path.exists(path):
                os.unlink(path)


def _accept(srv: _Server) -> None:
    """Take one request: fork its command, or tell the caller to run it by itself."""
    import selectors

    try:
        conn, _ = srv.listener.accept()
    except OSError:
        return
    fds: list[int] = []
    try:
        conn.settimeout(REQUEST_TIMEOUT_S)
        head, fds, _, _ = socket.recv_fds(conn, _LENGTH.size, 3)
        (size,) = _LENGTH.unpack(head)
        if len(fds) != 3 or size > MAX_REQUEST:
            raise ValueError("malformed request")
        body = bytearray()
        while len(body) < size:
            chunk = conn.recv(size - len(body))
            if not chunk:
                raise ValueError("request cut short")
            body += chunk
        req = json.loads(body)
        command = " ".join(req["argv"][1:])
        why = _difference(srv.mine, req["fingerprint"])
        if why is not None:
            print(f"runs by itself (differs in {why}): {command}", flush=True)
            conn.sendall(json.dumps({"alone": why}).encode() + b"\n")
            raise ValueError(why)
        sys.stdout.flush()
        sys.stderr.flush()
        # the caller's signals wait (blocked) until the fork has its own handlers: none is
        # taken by this process's handlers, copied into the fork
        signal.pthread_sigmask(signal.SIG_BLOCK, FORWARDED)
        pid = os.fork()
        if pid == 0:
            _run_command(req, fds, [*srv.sockets(), conn])
        signal.pthread_sigmask(signal.SIG_UNBLOCK, FORWARDED)
        print(f"pid {pid}: {command}", flush=True)
        conn.sendall(json.dumps({"pid": pid}).encode() + b"\n")
    except (OSError, ValueError, KeyError, TypeError):
        conn.close()
        return
    finally:
        for fd in fds:
            os.close(fd)
    srv.waiting[pid] = conn
    srv.selector.register(conn, selectors.EVENT_READ, pid)


def _caller_left(srv: _Server, pid: int, conn: Any) -> None:
    """A caller's socket turned readable: it is gone (killed without passing a signal on);
    its command gets SIGTERM, as Snakemake cancels a job."""
    srv.selector.unregister(conn)
    _signal_command(pid, signal.SIGTERM)


def _reap(srv: _Server) -> None:
    """Collect the commands that ended and send each status to its caller."""
    import contextlib

    while srv.waiting:
        try:
            pid, status = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            return
        if pid == 0:
            return
        conn = srv.waiting.pop(pid, None)
        if conn is None:
            continue
        with contextlib.suppress(KeyError, ValueError):
            srv.selector.unregister(conn)
        with contextlib.suppress(OSError):
            code = os.waitstatus_to_exitcode(status)
            conn.sendall(json.dumps({"status": code}).encode() + b"\n")
        conn.close()


def _run_command(req: dict[str, Any], fds: list[int], sockets: list[socket.socket]
                 ) -> NoReturn:
    """In the fork: become the caller's command (its streams, folder, environment, umask,
    argv; a session of its own; default signals), run ``ssw.cli.main`` and exit with its
    status as the interpreter would, after the exit handlers."""
    import tempfile
    import traceback

    code: Any = 1
    try:
        signal.set_wakeup_fd(-1)
        for sig in (signal.SIGCHLD, signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT):
            signal.signal(sig, signal.SIG_DFL)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, FORWARDED)  # blocked across the fork
        for s in sockets:
            s.close()
        os.setsid()
        for target, fd in enumerate(fds):
            os.dup2(fd, target)
        for fd in fds:
            if fd > 2:
                os.close(fd)
        os.chdir(req["cwd"])
        os.umask(int(req["umask"]))
        os.environ.clear()
        os.environ.update(req["env"])
        tempfile.tempdir = None  # found again from the command's TMPDIR
        sys.argv = list(req["argv"])
        sys.stdout.reconfigure(line_buffering=os.isatty(1))
        from ssw.cli import main

        code = main(sys.argv[1:])
    except SystemExit as exc:
        code = exc.code
    except KeyboardInterrupt:
        traceback.print_exc()
        code = -signal.SIGINT
    except BaseException:
        traceback.print_exc()
        code = 1
    _exit(code)


def _exit(code: Any) -> NoReturn:
    """Exit a fork as the interpreter exits: exit handlers, flushed streams, the status of
    ``SystemExit(code)`` (None 0, an int itself, anything else printed and 1); a negative
    code is death by that signal."""
    import contextlib

    if code is None:
        code = 0
    elif not isinstance(code, int):
        print(code, file=sys.stderr)
        code = 1
    with contextlib.suppress(BaseException):
        atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(BaseException):
            stream.flush()
    if code < 0:
        signal.signal(-code, signal.SIG_DFL)
        os.kill(os.getpid(), -code)
    os._exit(code & 0xFF)


def main(path: str, parent: int) -> NoReturn:
    """The warm process: :func:`serve`, then exit at once (its run waits for its end:
    tearing down the interpreter's thousand modules took 0.15 s, and nothing is left to
    write but the log, flushed here); an error (the preload refused) is printed and exits 1.

    Parameters
    ----------
    path : str
        The socket's path.
    parent : int
        The process id of the run that started this one.
    """
    import traceback

    code = 0
    try:
        serve(path, parent)
    except BaseException:
        traceback.print_exc()
        code = 1
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


# ---- the run that starts and stops it
class WarmProcess:
    """A running warm process.

    Parameters
    ----------
    process : subprocess.Popen
        The process.
    folder : Path
        Its private folder (mode 700), holding the socket.
    socket : Path
        The socket (``$SSW_WARM_SOCKET`` of the commands).
    """

    __slots__ = ("folder", "process", "socket")

    def __init__(self, process: subprocess.Popen, folder: Path, socket: Path) -> None:
        self.process, self.folder, self.socket = process, folder, socket


def switched_on() -> bool:
    """Whether this process may start a warm process: on POSIX (it forks and passes file
    descriptors), unless ``$SSW_WARM_START`` is 0, off, no or false.

    Returns
    -------
    bool
        Whether it may.
    """
    value = os.environ.get(SWITCH_ENV, "")
    return os.name == "posix" and value.strip().lower() not in ("0", "off", "no", "false")


def start(env: dict[str, str], log: Path, cwd: Path | None = None) -> WarmProcess:
    """Start a warm process for the commands of this process's children and name its
    socket in this process's environment (``$SSW_WARM_SOCKET``, which they inherit).

    Parameters
    ----------
    env : dict
        The environment of the commands to serve (the warm process takes it, so that its
        fingerprint is theirs: ``PYTHONPATH``, the thread counts).
    log : Path
        File of the warm process's messages: its start, each command it forked (pid and
        arguments), each it left to run by itself and why, or why it does not serve.
    cwd : Path, optional
        Its working folder (default this process's): the commands' own, which is on their
        module search path.

    Returns
    -------
    WarmProcess
        The process; the commands are served once its imports are done (about 1 s), and run
        by themselves before that.
    """
    import subprocess
    import tempfile
    from pathlib import Path

    folder = Path(tempfile.mkdtemp(prefix="ssw-warm-"))
    path = folder / "socket"
    env = {k: v for k, v in env.items() if k != SOCKET_ENV}
    log.parent.mkdir(parents=True, exist_ok=True)
    with open(log, "wb") as out:
        proc = subprocess.Popen(
            [sys.executable, "-c", "import sys; from ssw.warmstart import main; "
             "main(sys.argv[1], int(sys.argv[2]))", str(path), str(os.getpid())],
            env=env, cwd=cwd, stdin=subprocess.DEVNULL, stdout=out,
            stderr=subprocess.STDOUT, start_new_session=True)
    os.environ[SOCKET_ENV] = str(path)
    return WarmProcess(proc, folder, path)


def stop(warm: WarmProcess, timeout_s: float = 10.0) -> None:
    """Stop a warm process (once its commands ended) and remove its folder; this process's
    later commands run by themselves.

    Parameters
    ----------
    warm : WarmProcess
        What :func:`start` returned.
    timeout_s : float
        Seconds to wait for it before killing it.
    """
    import shutil
    import subprocess

    if os.environ.get(SOCKET_ENV) == str(warm.socket):
        del os.environ[SOCKET_ENV]
    if warm.process.poll() is None:
        warm.process.terminate()
        try:
            warm.process.wait(timeout_s)
        except subprocess.TimeoutExpired:
            warm.process.kill()
            warm.process.wait()
    shutil.rmtree(warm.folder, ignore_errors=True)


_RUNNING: list[WarmProcess] = []


def job_env(root: str) -> dict[str, str]:
    """The environment of the workflow's jobs, as far as their fingerprint reads it: this
    process's, with the repository first on ``PYTHONPATH`` (what the rules' shell prefix
    exports, ``workflow/rules/common.smk``) and Snakemake's thread counts of a one-thread
    job (:data:`ONE_THREAD_ENV`).

    Parameters
    ----------
    root : str
        The repository (resolved).

    Returns
    -------
    dict
        The environment.
    """
    path = os.pathsep.join([root, *filter(None, [os.environ.get("PYTHONPATH")])])
    return {**os.environ, "PYTHONPATH": path, **ONE_THREAD_ENV}


def start_for(workflow: Any, root: str, log: Path) -> WarmProcess | None:
    """Start the warm process of a Snakemake run when its jobs run on this machine (not on
    a cluster, nor a touch or a dry run), ``$SSW_WARM_START`` allows, and no warm process
    was started for it already (by :func:`run_with`, whose ``$SSW_WARM_SOCKET`` the run
    inherits); :func:`stop_all` ends it.

    Parameters
    ----------
    workflow : snakemake.workflow.Workflow
        The run.
    root : str
        The repository (resolved), first on its jobs' ``PYTHONPATH`` (:func:`job_env`).
    log : Path
        File of the warm process's messages.

    Returns
    -------
    WarmProcess or None
        The process, or None when the run does not take one of its own.
    """
    local = bool(getattr(workflow, "local_exec", False))
    remote = bool(getattr(workflow, "remote_exec", False)
                  or getattr(workflow, "subprocess_exec", False))
    idle = bool(getattr(workflow, "touch", False) or getattr(workflow, "dryrun", False))
    if not local or remote or idle or not switched_on():
        return None
    given = os.environ.get(SOCKET_ENV)
    if given and os.path.isdir(os.path.dirname(given)):
        return None
    warm = start(job_env(root), log)
    _RUNNING.append(warm)
    return warm


def run_with(command: list[str], log: Path) -> int:
    """Run ``command`` (a Snakemake run of the study, started in the repository) with a warm
    process for its jobs started beside it, so that its imports overlap Snakemake's own
    start (about 1.4 s, on one core) instead of the first jobs: ``make study``.

    Parameters
    ----------
    command : list of str
        The program and its arguments.
    log : Path
        File of the warm process's messages.

    Returns
    -------
    int
        The command's exit status (128 + the signal that ended it).
    """
    import subprocess

    warm = start(job_env(os.path.realpath(os.getcwd())), log) if switched_on() else None
    try:
        proc = subprocess.Popen(command)
        while True:
            try:
                code = proc.wait()
                break
            except KeyboardInterrupt:  # Ctrl-C reached the command too: wait for its end
                continue
    finally:
        if warm is not None:
            stop(warm)
    return 128 - code if code < 0 else code


def stop_all() -> None:
    """Stop every warm process this process started (:func:`start_for`)."""
    while _RUNNING:
        stop(_RUNNING.pop())


atexit.register(stop_all)


def _cli(argv: list[str]) -> int:
    """``python -m ssw.warmstart [--log FILE] -- COMMAND...``: :func:`run_with`."""
    import argparse
    from pathlib import Path

    parser = argparse.ArgumentParser(
        prog="python -m ssw.warmstart",
        description="Run a Snakemake run of the study with ssw's warm process started beside "
        "it (the workflow starts one by itself otherwise, when its run begins).")
    parser.add_argument("--log", default="results/logs/warm-start.log",
                        help="file of the warm process's messages")
    parser.add_argument("command", nargs=argparse.REMAINDER,
                        help="the command, after --")
    args = parser.parse_args(argv)
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        parser.error("a command is required after --")
    return run_with(command, Path(args.log))


if __name__ == "__main__":
    raise SystemExit(_cli(sys.argv[1:]))
