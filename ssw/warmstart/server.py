"""The warm process (:mod:`ssw.warmstart`): it imports what the study's commands use, then
forks one command for each request at its Unix socket.

A request is a length (:data:`ssw.warmstart.LENGTH`) sent with the caller's three standard
streams (``SCM_RIGHTS``), then its JSON (argv, working folder, environment, umask,
fingerprint, the caller's process ancestry). The warm process answers with the fork's pid,
or leaves the command to run by itself (``{"alone": why}``): another fingerprint, code
changed on disk since it loaded (:class:`CodeWatch`), a failed ``fork()``. The fork runs
the command only once the caller confirmed it waits (:data:`ssw.warmstart.GO`): a caller
gone before that never has its command run, and runs it by itself if it can. When the
command ends, its resource use goes to the run's job records (:func:`write_usage`) and its
status to the caller.

Every request is read without blocking, within :data:`REQUEST_TIMEOUT_S`; a malformed one (a
socket closed before its length or in its middle, a wrong length, more descriptors than
three, text that is not a request) is dropped, and the warm process serves on.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import sys
import time
from typing import TYPE_CHECKING, Any, NoReturn

from ssw.warmstart import (
    FORWARDED,
    GO,
    LENGTH,
    REPLY_TIMEOUT_S,
    TERM_GRACE_S,
    USAGE_FOLDER,
    fingerprint,
    signal_command,
)

if TYPE_CHECKING:
    import selectors

#: What the warm process imports: the modules that the study's commands import (measured
#: with ``python -X importtime`` on each job of ``make study``), and ``scipy.signal``, which
#: every command reading a recording imports (a survey's ``ssw measure`` jobs: 0.45 s each
#: after the rest; the example survey's 5 points 1.3-2.0 s each before it, 0.9-1.2 s with
#: it, ``snakemake --cores 2 --configfile config/survey_example.yaml``, 2 cores,
#: 2026-11-29). None of them starts a thread or MPI (PETSc, gmsh and MPI load in the fork
#: that needs them): a fork of a process with threads would copy their locks, not the
#: threads.
PRELOAD = (
    "numpy", "scipy.linalg", "scipy.sparse", "scipy.sparse.linalg", "scipy.special",
    "scipy.interpolate", "scipy.optimize", "h5py", "matplotlib.pyplot", "PIL.PngImagePlugin",
    "jsonschema", "scipy.signal",
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
#: Longest request accepted (its argv and environment), bytes.
MAX_REQUEST = 1 << 22
#: Seconds a caller has to send its whole request once connected, and to confirm (GO) once
#: it has its command's pid; past them the request is dropped (the fork killed unrun).
REQUEST_TIMEOUT_S = REPLY_TIMEOUT_S
#: Longest wait of the warm process's loop, s (its checks that its run is alive).
POLL_S = 1.0
#: Seconds a fork waits for its go (a little past the caller's deadline to confirm).
GATE_TIMEOUT_S = REQUEST_TIMEOUT_S + 5.0
#: Linux ``prctl`` option: the signal a process gets when its parent ends.
_PR_SET_PDEATHSIG = 1
#: The C library when this is Linux (a fork asks for SIGTERM when the warm process ends).
_LIBC: Any = None


class CodeWatch:
    """What the warm process runs: every file of the modules it imported (and the
    interpreter), with its (mtime in ns, size in bytes) when imported; ssw's own modules
    at the moment they loaded (``ssw.LOADED``), the others' when the watch starts.

    Parameters
    ----------
    modules : dict, optional
        Module objects by name (default ``sys.modules``).
    """

    def __init__(self, modules: dict[str, Any] | None = None) -> None:
        from ssw import LOADED

        files: dict[str, tuple[int, int] | None] = {}
        for mod in list((sys.modules if modules is None else modules).values()):
            path = getattr(mod, "__file__", None)
            if isinstance(path, str):
                files.setdefault(os.path.realpath(path), None)
        files[os.path.realpath(sys.executable)] = None
        for path in files:
            if path in LOADED:
                files[path] = LOADED[path][1]
            else:
                try:
                    st = os.stat(path)
                    files[path] = (st.st_mtime_ns, st.st_size)
                except OSError:
                    files[path] = None
        self.files = {k: v for k, v in files.items() if v is not None}
        self.first_change: str | None = None

    def changed(self) -> str | None:
        """The first file found changed (modified, replaced or removed) since it was
        imported, or None; once one is found, it for good.

        Returns
        -------
        str or None
            Its path.
        """
        if self.first_change is None:
            for path, key in self.files.items():
                try:
                    st = os.stat(path)
                except OSError:
                    self.first_change = path
                    break
                if (st.st_mtime_ns, st.st_size) != key:
                    self.first_change = path
                    break
        return self.first_change


def preload(modules: tuple[str, ...] = PRELOAD) -> None:
    """Import ``modules`` (matplotlib on its Agg backend, as ssw.plotting draws), take the
    checkout's state for the results' provenance (:func:`ssw.provenance.git_state`: the
    forks inherit it), and check that the process may fork: no module of
    :data:`UNFORKABLE` and no thread but this one.

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

    global _LIBC
    matplotlib.use("Agg")
    for name in modules:
        importlib.import_module(name)
    from ssw.provenance import git_state

    git_state()
    if sys.platform.startswith("linux"):
        import ctypes

        _LIBC = ctypes.CDLL(None, use_errno=True)
    bad = sorted(m for m in sys.modules if m.split(".")[0] in UNFORKABLE)
    if bad:
        raise RuntimeError(f"the warm process imported {', '.join(bad[:5])}: it must not "
                           "(they start threads or MPI); take them out of PRELOAD")
    threads = len(os.listdir("/proc/self/task")) if os.path.isdir("/proc/self/task") else 1
    if threads != 1:
        raise RuntimeError(f"the warm process runs {threads} threads after its imports: a "
                           "fork would copy their locks, not them")


#: The fields of :func:`ssw.warmstart.fingerprint`, as the warm process's log names them.
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


def parse_request(body: bytes) -> dict[str, Any]:
    """A request's JSON, checked: ``argv`` (a non-empty list of text), ``cwd`` (text),
    ``env`` (text to text), ``umask`` (0 to 0o777), ``fingerprint`` (a mapping) and
    ``pids`` (a list of process ids, optional).

    Parameters
    ----------
    body : bytes
        The request's bytes after its length.

    Returns
    -------
    dict
        The request.

    Raises
    ------
    ValueError
        Naming what is wrong.
    """
    req = json.loads(body)
    if not isinstance(req, dict):
        raise ValueError("not a JSON object")
    argv, env, umask = req.get("argv"), req.get("env"), req.get("umask")
    if not (isinstance(argv, list) and argv and all(isinstance(a, str) for a in argv)):
        raise ValueError("argv is not a list of text")
    if not isinstance(req.get("cwd"), str):
        raise ValueError("cwd is not text")
    if not (isinstance(env, dict)
            and all(isinstance(k, str) and isinstance(v, str) for k, v in env.items())):
        raise ValueError("env is not a mapping of text")
    if not (isinstance(umask, int) and not isinstance(umask, bool) and 0 <= umask <= 0o777):
        raise ValueError("umask is not a file mode mask")
    if not isinstance(req.get("fingerprint"), dict):
        raise ValueError("fingerprint is not a mapping")
    pids = req.setdefault("pids", [])
    if not (isinstance(pids, list) and all(isinstance(p, int) for p in pids)):
        raise ValueError("pids is not a list of process ids")
    return req


class _Caller:
    """One caller's connection and where its request stands: ``reading`` (its bytes and
    descriptors so far), ``confirming`` (forked, pid sent, waiting for its GO: the fork
    waits at its gate), ``running``."""

    __slots__ = ("buf", "command", "deadline", "fds", "gate", "pid", "pids", "sock",
                 "started", "state")

    def __init__(self, sock: socket.socket) -> None:
        self.sock, self.state, self.buf = sock, "reading", bytearray()
        self.fds: list[int] = []
        self.deadline = time.monotonic() + REQUEST_TIMEOUT_S
        self.pid, self.gate, self.pids, self.command = 0, -1, [], ""
        self.started = 0.0


class _Server:
    """The warm process's state: its socket, its callers, its forks and its signals.

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
        self.code = CodeWatch()
        self.callers: set[_Caller] = set()
        self.forks: dict[int, _Caller] = {}  # confirming and running, by pid
        self.unrun: set[int] = set()  # forks killed at their gate, to collect
        self.terminated: dict[int, float] = {}  # pid -> when SIGKILL follows SIGTERM
        self.stopping = False
        self.usage = os.path.join(os.path.dirname(path), USAGE_FOLDER)

    def close_in_fork(self, keep: list[int]) -> None:
        """In a fork: close what it inherited of this process (the sockets, the selector,
        the callers' streams and the other forks' gates) but the descriptors ``keep``."""
        self.selector.close()
        for s in (self.listener, self.wake_r, self.wake_w, *(c.sock for c in self.callers)):
            s.close()
        for fd in [fd for c in self.callers for fd in (*c.fds, c.gate)]:
            if fd >= 0 and fd not in keep:
                os.close(fd)


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
    listener.setblocking(False)
    srv = _Server(listener, path, parent)

    def stop(signum: int, frame: object) -> None:
        srv.stopping = True

    signal.set_wakeup_fd(srv.wake_w.fileno())
    signal.signal(signal.SIGCHLD, lambda signum, frame: None)
    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    srv.selector.register(listener, selectors.EVENT_READ, "accept")
    srv.selector.register(srv.wake_r, selectors.EVENT_READ, "wake")
    # the path appears when it accepts and a SIGTERM stops it cleanly (whoever sees the
    # path may stop it at once)
    os.replace(f"{path}.new", path)
    print(f"ssw warm start: pid {os.getpid()}, {len(sys.modules)} modules loaded, "
          f"{len(srv.code.files)} files watched; listening at {path}", flush=True)
    while not (srv.stopping and not srv.forks and not srv.unrun):
        soonest = min([c.deadline for c in srv.callers if c.state != "running"]
                      + list(srv.terminated.values()), default=time.monotonic() + POLL_S)
        wait = min(POLL_S, max(0.0, soonest - time.monotonic()))
        for key, _ in srv.selector.select(wait):
            if key.data == "accept":
                _accept(srv)
            elif key.data == "wake":
                try:
                    srv.wake_r.recv(4096)
                except OSError:
                    pass
            else:
                _readable(srv, key.data)
        _reap(srv)
        _expire(srv)
        if not srv.stopping and os.getppid() != parent:
            srv.stopping = True
        if srv.stopping:
            _stop_serving(srv)


def _log(text: str) -> None:
    print(text, flush=True)


def _accept(srv: _Server) -> None:
    """Take every waiting connection (read later, without blocking)."""
    import selectors

    while True:
        try:
            conn, _ = srv.listener.accept()
        except OSError:  # none left (BlockingIOError), or the listener closed
            return
        conn.setblocking(False)
        caller = _Caller(conn)
        srv.callers.add(caller)
        srv.selector.register(conn, selectors.EVENT_READ, caller)


def _drop(srv: _Server, c: _Caller, why: str | None = None) -> None:
    """Forget a caller: close its socket and the descriptors it sent; kill its fork when
    the fork has not run (``confirming``); log ``why`` when given."""
    import contextlib

    if why:
        _log(f"a request dropped ({why}){': ' + c.command if c.command else ''}")
    with contextlib.suppress(KeyError, ValueError):
        srv.selector.unregister(c.sock)
    c.sock.close()
    for fd in c.fds:
        with contextlib.suppress(OSError):
            os.close(fd)
    c.fds = []
    if c.state == "confirming":
        with contextlib.suppress(OSError):
            os.kill(c.pid, signal.SIGKILL)  # at its gate: it ran nothing
        srv.forks.pop(c.pid, None)
        srv.unrun.add(c.pid)
    if c.gate >= 0:
        with contextlib.suppress(OSError):
            os.close(c.gate)
        c.gate = -1
    srv.callers.discard(c)


def _readable(srv: _Server, c: _Caller) -> None:
    """A caller's socket is readable: more of its request, its GO, or its end. Whatever
    goes wrong with one caller drops it (logged), never the warm process."""
    try:
        _read(srv, c)
    except Exception as exc:  # a request no check foresaw: this caller's alone
        _drop(srv, c, f"it could not be handled: {exc!r}"[:300])


def _read(srv: _Server, c: _Caller) -> None:
    """:func:`_readable`'s work."""
    try:
        if c.state == "reading":
            data, fds, flags, _ = socket.recv_fds(c.sock, 1 << 16, 4)
            c.fds += fds
            if not data:
                _drop(srv, c, f"the caller left after {len(c.buf)} bytes" if c.buf or c.fds
                      else None)  # a bare connection: a probe (ssw.warmstart.run.answering)
                return
            c.buf += data
            _request_bytes(srv, c, flags)
            return
        data = c.sock.recv(4096)
    except BlockingIOError:
        return
    except OSError as exc:
        _drop(srv, c, f"its socket failed: {exc}")
        return
    if c.state == "confirming":
        if data[:1] == GO[:1]:
            _go(srv, c)
        else:
            _drop(srv, c, "the caller left before it confirmed" if not data
                  else "not a confirmation")
    elif not data:  # running: the caller is gone (killed without passing a signal on)
        _caller_left(srv, c)


def _request_bytes(srv: _Server, c: _Caller, flags: int) -> None:
    """Check a request's bytes so far; handle it once whole."""
    if flags & getattr(socket, "MSG_CTRUNC", 0) or len(c.fds) > 3:
        _drop(srv, c, "more than three descriptors")
        return
    if len(c.buf) < LENGTH.size:
        return
    (size,) = LENGTH.unpack_from(c.buf)
    if size > MAX_REQUEST:
        _drop(srv, c, f"a length of {size} bytes, more than {MAX_REQUEST}")
    elif len(c.buf) > LENGTH.size + size:
        _drop(srv, c, "more bytes than its length")
    elif len(c.buf) == LENGTH.size + size:
        if len(c.fds) != 3:
            _drop(srv, c, f"{len(c.fds)} descriptors, not three")
            return
        try:
            req = parse_request(bytes(c.buf[LENGTH.size:]))
        except (ValueError, RecursionError) as exc:  # JSON errors are ValueErrors
            _drop(srv, c, f"not a request: {str(exc)[:200]}")
            return
        c.buf = bytearray()
        _handle(srv, c, req)


def _alone(srv: _Server, c: _Caller, why: str) -> None:
    """Tell a caller to run its command by itself, and why."""
    import contextlib

    _log(f"runs by itself ({why}): {c.command}")
    with contextlib.suppress(OSError):
        c.sock.sendall(json.dumps({"alone": why}).encode() + b"\n")
    _drop(srv, c)


def _handle(srv: _Server, c: _Caller, req: dict[str, Any]) -> None:
    """A whole request: fork its command (it waits at its gate), send the caller its pid;
    or leave the command to run by itself."""
    c.command, c.pids, c.started = " ".join(req["argv"][1:]), req["pids"], time.time()
    differs = _difference(srv.mine, req["fingerprint"])
    if differs is not None:
        _alone(srv, c, f"differs in {differs}")
        return
    changed = srv.code.changed()
    if changed is not None:
        _alone(srv, c, f"the code changed since the warm process loaded it: {changed}")
        return
    sys.stdout.flush()
    sys.stderr.flush()
    gate_r, gate_w = os.pipe()
    # the caller's signals wait (blocked) until the fork has its own handlers: none is
    # taken by this process's handlers, copied into the fork
    signal.pthread_sigmask(signal.SIG_BLOCK, FORWARDED)
    me = os.getpid()
    try:
        pid = os.fork()
    except OSError as exc:
        signal.pthread_sigmask(signal.SIG_UNBLOCK, FORWARDED)
        os.close(gate_r)
        os.close(gate_w)
        _alone(srv, c, f"the warm process could not fork: {exc}")
        return
    if pid == 0:
        try:
            os.close(gate_w)
            srv.close_in_fork(c.fds)
        except BaseException:
            os._exit(1)
        _run_command(req, c.fds, gate_r, me)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, FORWARDED)
    os.close(gate_r)
    for fd in c.fds:
        os.close(fd)
    c.fds, c.pid, c.gate, c.state = [], pid, gate_w, "confirming"
    c.deadline = time.monotonic() + REQUEST_TIMEOUT_S
    srv.forks[pid] = c
    try:
        c.sock.sendall(json.dumps({"pid": pid}).encode() + b"\n")
    except OSError as exc:
        _drop(srv, c, f"its pid could not be sent ({exc}); pid {pid} killed unrun")


def _go(srv: _Server, c: _Caller) -> None:
    """The caller confirmed: open the fork's gate."""
    try:
        os.write(c.gate, b"1")
    except OSError:
        pass  # the fork is gone: its status comes from _reap
    os.close(c.gate)
    c.gate, c.state = -1, "running"
    _log(f"pid {c.pid}: {c.command}")


def _caller_left(srv: _Server, c: _Caller) -> None:
    """A running command's caller is gone (killed without passing a signal on): its command
    gets SIGTERM, as Snakemake cancels a job, and SIGKILL :data:`TERM_GRACE_S` later."""
    import contextlib

    with contextlib.suppress(KeyError, ValueError):
        srv.selector.unregister(c.sock)
    if signal_command(c.pid, signal.SIGTERM):
        srv.terminated.setdefault(c.pid, time.monotonic() + TERM_GRACE_S)


def _expire(srv: _Server) -> None:
    """Past their deadlines: requests not whole, confirmations not come (the fork is killed
    unrun), commands that outlived SIGTERM (SIGKILL to their group)."""
    now = time.monotonic()
    for c in [c for c in srv.callers if c.state != "running" and c.deadline <= now]:
        _drop(srv, c, f"no {'whole request' if c.state == 'reading' else 'confirmation'} "
                      f"in {REQUEST_TIMEOUT_S:g} s")
    for pid, when in list(srv.terminated.items()):
        if when <= now:
            signal_command(pid, signal.SIGKILL)
            del srv.terminated[pid]


def _stop_serving(srv: _Server) -> None:
    """Stop taking requests: the listener closed, its path removed, the requests not yet
    running dropped (their callers run them by themselves)."""
    import contextlib

    if srv.listener.fileno() >= 0:
        with contextlib.suppress(KeyError, ValueError):
            srv.selector.unregister(srv.listener)
        srv.listener.close()
        with contextlib.suppress(OSError):
            os.unlink(srv.path)
    for c in [c for c in srv.callers if c.state != "running"]:
        _drop(srv, c)


def _reap(srv: _Server) -> None:
    """Collect the commands that ended: each one's resource use to the run's records
    (:func:`write_usage`), then its status to its caller."""
    import contextlib

    while srv.forks or srv.unrun:
        try:
            pid, status, usage = os.wait4(-1, os.WNOHANG)
        except ChildProcessError:
            srv.forks.clear()
            srv.unrun.clear()
            return
        if pid == 0:
            return
        srv.unrun.discard(pid)
        srv.terminated.pop(pid, None)
        c = srv.forks.pop(pid, None)
        if c is None:
            continue
        if c.state != "running":  # ended at its gate (the warm process's own deadline)
            _drop(srv, c)
            continue
        code = os.waitstatus_to_exitcode(status)
        with contextlib.suppress(OSError):
            write_usage(srv.usage, pid, c.pids, c.started, usage, code)
        with contextlib.suppress(OSError):
            c.sock.setblocking(True)
            c.sock.settimeout(1.0)
            c.sock.sendall(json.dumps({"status": code}).encode() + b"\n")
        c.state = "done"
        _drop(srv, c)


def write_usage(folder: str, pid: int, pids: list[int], started: float, usage: Any,
                code: int) -> None:
    """Record what a served command used (``folder/<pid>.json``, written atomically): the
    kernel's account of the fork and the children it waited for (``wait4``), which the
    run's benchmark records take as the job's own (:func:`ssw.warmstart.run.served_usage`).

    Parameters
    ----------
    folder : str
        The records' folder (created if missing).
    pid : int
        The fork's process id.
    pids : list of int
        Its caller's process id and the caller's ancestors' (the job's shell among them).
    started : float
        When the request came (Unix time, s).
    usage : resource.struct_rusage
        The fork's resource use.
    code : int
        Its exit status (negative: the signal that ended it).
    """
    from pathlib import Path

    from ssw.h5io import atomic_write_text

    record = {
        "pid": pid, "pids": pids, "start": started, "end": time.time(), "status": code,
        "cpu_s": usage.ru_utime + usage.ru_stime, "user_s": usage.ru_utime,
        "sys_s": usage.ru_stime,
        # Linux counts ru_maxrss in KiB, and block I/O in 512-byte units (getrusage(2))
        "max_rss_mb": usage.ru_maxrss / 1024.0,
        "io_in_mb": usage.ru_inblock * 512 / 2**20, "io_out_mb": usage.ru_oublock * 512 / 2**20,
    }
    Path(folder).mkdir(mode=0o700, exist_ok=True)
    atomic_write_text(Path(folder) / f"{pid}.json", json.dumps(record))


def _run_command(req: dict[str, Any], fds: list[int], gate: int, parent: int) -> NoReturn:
    """In the fork: become the caller's command (its streams, folder, environment, umask,
    argv; a session of its own; default signals; SIGTERM when the warm process ends), wait
    at the gate for the caller's confirmation (none: exit unrun), run ``ssw.cli.main`` and
    exit with its status as the interpreter would, after the exit handlers."""
    import tempfile
    import traceback

    code: Any = 1
    try:
        signal.set_wakeup_fd(-1)
        for sig in (signal.SIGCHLD, signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT):
            signal.signal(sig, signal.SIG_DFL)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        if _LIBC is not None:
            _LIBC.prctl(_PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)
        if os.getppid() != parent:  # the warm process ended before the request was set
            os._exit(1)
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
        if not _opened(gate):
            os._exit(1)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, FORWARDED)  # blocked across the fork
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


def _opened(gate: int) -> bool:
    """Wait (at most :data:`GATE_TIMEOUT_S`) for the warm process to open the gate: True
    when it did, False when it closed it or ended (the caller did not confirm)."""
    import select

    ready, _, _ = select.select([gate], [], [], GATE_TIMEOUT_S)
    opened = bool(ready) and os.read(gate, 1) == b"1"
    os.close(gate)
    return opened


def _exit(code: Any) -> NoReturn:
    """Exit a fork as the interpreter exits: exit handlers, flushed streams, the status of
    ``SystemExit(code)`` (None 0, an int itself, anything else printed and 1); a negative
    code is death by that signal."""
    import atexit
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
