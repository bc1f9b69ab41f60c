"""The run's side of the warm start (:mod:`ssw.warmstart`): start the warm process for a
Snakemake run on this machine and stop it when the run ends; and make the run's
``benchmark:`` records those of the jobs the warm process served.

Benchmark records. Snakemake samples a job's process tree (its shell and the shell's
descendants, ``psutil``; ``snakemake/benchmark.py``) every 0.5 s, then every 30 s, and
writes what it saw: wall time, peak memory, I/O and CPU time. A served job's command runs in
a fork of the warm process, outside that tree: Snakemake would see only the 30 ms caller.
:func:`attach_benchmarks` (called in the run's ``onstart``) adds to each job's record the
resource use of the commands served for it, the kernel's account of each fork
(``wait4``, :func:`ssw.warmstart.server.write_usage`): its CPU time (user and system, with
the children it waited for) to ``cpu_time`` (and to the CPU seconds behind ``mean_load``),
its I/O to ``io_in`` and ``io_out``, and its peak resident memory to ``max_rss`` where it
exceeds what the tree showed. ``max_vms``, ``max_uss`` and ``max_pss`` stay the sampled
tree's (the kernel keeps no peak of them).
"""

from __future__ import annotations

import atexit
import contextlib
import json
import os
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ssw.warmstart import SOCKET_ENV, USAGE_FOLDER, switch_allows, usable

if TYPE_CHECKING:
    import subprocess
    from collections.abc import Iterator

#: The thread counts Snakemake's shell gives a job of ``threads: 1`` (every rule of the
#: study): the warm process of a run loads with them.
ONE_THREAD_ENV = {v: "1" for v in ("OMP_NUM_THREADS", "GOTO_NUM_THREADS",
                                   "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                                   "VECLIB_MAXIMUM_THREADS", "NUMEXPR_NUM_THREADS")}
#: Seconds a check that a warm process answers waits for it to accept.
PROBE_TIMEOUT_S = 1.0
#: File of the warm process's id, in its folder (written by :func:`start`).
PID_FILE = "pid"


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
    """Whether this process may start a warm process: where commands can be served
    (:func:`ssw.warmstart.usable`: POSIX, not macOS), unless ``$SSW_WARM_START`` is 0, off,
    no or false.

    Returns
    -------
    bool
        Whether it may.
    """
    return usable() and switch_allows()


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
        arguments), each it left to run by itself and why, each request it dropped, or why
        it does not serve.
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

    folder = Path(tempfile.mkdtemp(prefix="ssw-warm-"))
    path = folder / "socket"
    env = {k: v for k, v in env.items() if k != SOCKET_ENV}
    log.parent.mkdir(parents=True, exist_ok=True)
    with open(log, "wb") as out:
        proc = subprocess.Popen(
            [sys.executable, "-c", "import sys; from ssw.warmstart.server import main; "
             "main(sys.argv[1], int(sys.argv[2]))", str(path), str(os.getpid())],
            env=env, cwd=cwd, stdin=subprocess.DEVNULL, stdout=out,
            stderr=subprocess.STDOUT, start_new_session=True)
    (folder / PID_FILE).write_text(f"{proc.pid}\n")
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
            warm.process.wait(timeout_s)
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


def answering(path: str, timeout_s: float = PROBE_TIMEOUT_S) -> bool:
    """Whether a warm process answers at ``path`` or is starting there: its socket accepts a
    connection within ``timeout_s``, or the process named in its folder (:func:`start`)
    still runs and has not opened it yet. False for a name left over from a run that ended
    (a stale ``$SSW_WARM_SOCKET``).

    Parameters
    ----------
    path : str
        The socket's path.
    timeout_s : float
        Seconds to wait for the connection.

    Returns
    -------
    bool
        Whether it answers or starts.
    """
    import socket

    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as probe:
        probe.settimeout(timeout_s)
        try:
            probe.connect(path)
            return True
        except OSError:
            pass
    if os.path.exists(path):  # a socket nothing listens at
        return False
    try:
        pid = int(Path(path).with_name(PID_FILE).read_text())
        os.kill(pid, 0)
    except (OSError, ValueError):
        return False
    for _ in range(20):  # the process of that id starts this socket's warm process (not
        try:            # a reused id); its command line reads empty while it execs
            command = Path(f"/proc/{pid}/cmdline").read_bytes()
        except OSError:
            return True
        if command:
            return path.encode() in command
        time.sleep(0.01)
    return True


def start_for(workflow: Any, root: str, log: Path) -> WarmProcess | None:
    """Start the warm process of a Snakemake run when its jobs run on this machine (not on
    a cluster, nor a touch or a dry run), ``$SSW_WARM_START`` allows, and no warm process
    answers for it already (started by :func:`run_with`, whose ``$SSW_WARM_SOCKET`` the run
    inherits; a name nothing answers at is left over, and replaced); :func:`stop_all` ends
    it. Its jobs' benchmark records become their commands' (:func:`attach_benchmarks`).

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
    attach_benchmarks()
    given = os.environ.get(SOCKET_ENV)
    if given and answering(given):
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


# ---- the jobs' benchmark records
def served_usage(folder: Path, pid: int, since: float, until: float) -> list[dict[str, Any]]:
    """The resource records (:func:`ssw.warmstart.server.write_usage`) of the commands
    served for a job: requested between ``since`` and ``until`` by a caller that descends
    from process ``pid`` (the job's shell); their files are removed (each counts once).

    Parameters
    ----------
    folder : Path
        The records' folder.
    pid : int
        The job's process (its shell).
    since : float
        The job's start (Unix time, s).
    until : float
        The job's end (Unix time, s).

    Returns
    -------
    list of dict
        The records.
    """
    out = []
    for f in sorted(folder.glob("*.json")) if folder.is_dir() else []:
        try:
            rec = json.loads(f.read_text())
        except (OSError, ValueError):
            continue
        if pid in rec.get("pids", ()) and since <= rec.get("start", -1.0) <= until:
            out.append(rec)
            with contextlib.suppress(OSError):
                f.unlink()
    return out


def add_served(record: Any, served: list[dict[str, Any]]) -> None:
    """Add the served commands' resource use to a Snakemake benchmark record (module
    docstring): CPU s, peak memory MB, I/O MB.

    Parameters
    ----------
    record : snakemake.benchmark.BenchmarkRecord
        The job's record (its sampled process tree).
    served : list of dict
        :func:`served_usage` of the job.
    """
    if not served:
        return
    cpu = sum(float(r["cpu_s"]) for r in served)
    record.cpu_time = (record.cpu_time or 0.0) + cpu
    record.cpu_usage = (record.cpu_usage or 0.0) + cpu
    record.max_rss = max(record.max_rss or 0.0, *(float(r["max_rss_mb"]) for r in served))
    record.io_in = (record.io_in or 0.0) + sum(float(r["io_in_mb"]) for r in served)
    record.io_out = (record.io_out or 0.0) + sum(float(r["io_out_mb"]) for r in served)
    record.data_collected = True


def attach_benchmarks() -> bool:
    """Make this Snakemake process's benchmark records include the commands the warm process
    serves for each job (module docstring): ``snakemake.benchmark.benchmarked``, which
    samples a job's shell, also notes the shell and the job's time span on its record, and
    ``write_benchmark_records`` adds the commands served for it then (Snakemake imports
    both from ``snakemake.benchmark`` when a job runs). Once per process.

    Returns
    -------
    bool
        Whether the records take them (False: no Snakemake here, or one whose benchmark
        module differs).
    """
    try:
        import snakemake.benchmark as bench
    except ImportError:
        return False
    sample, write = (getattr(bench, n, None) for n in ("benchmarked", "write_benchmark_records"))
    if sample is None or write is None:
        return False
    if getattr(sample, "ssw_served", False):
        return True

    @contextlib.contextmanager
    def benchmarked(*args: Any, **kwargs: Any) -> Iterator[Any]:
        pid = args[0] if args else kwargs.get("pid")
        since = time.time()
        with sample(*args, **kwargs) as record:
            yield record
        if pid and int(pid) != os.getpid():  # a shell's tree, not Snakemake's own `run:`
            record.ssw_job = (int(pid), since, time.time())

    def write_benchmark_records(records: Any, path: Any, *args: Any, **kwargs: Any) -> Any:
        socket = os.environ.get(SOCKET_ENV)
        for record in records:
            job = getattr(record, "ssw_job", None)
            if job is not None and socket:
                add_served(record, served_usage(Path(socket).parent / USAGE_FOLDER, *job))
        return write(records, path, *args, **kwargs)

    benchmarked.ssw_served = True  # type: ignore[attr-defined]
    bench.benchmarked = benchmarked
    bench.write_benchmark_records = write_benchmark_records
    return True
