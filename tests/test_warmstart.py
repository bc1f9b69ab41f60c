"""The warm start (ssw.warmstart): a command forked from the warm process prints, writes and
exits as a fresh ``python -m ssw`` process does; one whose imports would differ runs by
itself; signals reach the command; the warm process holds no thread and nothing that
cannot be forked."""

from __future__ import annotations

import json
import os
import shlex
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from ssw import warmstart

TOF = ["tof", "--soil-E", "50e6", "--soil-nu", "0.3", "--calibration", "none", "--json"]


def _env(**extra: str) -> dict[str, str]:
    # no disk cache: every command builds its operators itself, whatever other runs left in
    # ~/.cache/ssw or write there meanwhile
    env = {k: v for k, v in os.environ.items() if k != warmstart.SOCKET_ENV}
    return {**env, **warmstart.ONE_THREAD_ENV, "SSW_CACHE_DIR": "none", **extra}


@pytest.fixture
def warm(tmp_path: Path) -> Iterator[warmstart.WarmProcess]:
    """A warm process serving commands that run in ``tmp_path`` with :func:`_env`."""
    before = os.environ.get(warmstart.SOCKET_ENV)
    proc = warmstart.start(_env(), tmp_path / "warm.log", cwd=tmp_path)
    try:
        end = time.monotonic() + 120  # its imports done: the socket appears
        while not proc.socket.exists():
            assert time.monotonic() < end and proc.process.poll() is None, (
                tmp_path / "warm.log").read_text()
            time.sleep(0.02)
        yield proc
    finally:
        warmstart.stop(proc)
        if before is not None:
            os.environ[warmstart.SOCKET_ENV] = before
    assert not proc.folder.exists()
    assert proc.process.returncode == 0, (tmp_path / "warm.log").read_text()


def _ssw(args: list[str], cwd: Path, socket: Path | None, **env: str
         ) -> subprocess.CompletedProcess:
    extra = {warmstart.SOCKET_ENV: str(socket)} if socket else {}
    return subprocess.run([sys.executable, "-m", "ssw", *args], cwd=cwd, capture_output=True,
                          text=True, env=_env(**extra, **env), timeout=300)


def _served(log: Path) -> list[str]:
    return [line for line in log.read_text().splitlines() if line.startswith("pid ")]


def test_a_forked_command_prints_and_exits_as_a_fresh_process(warm, tmp_path):
    cold = _ssw(TOF, tmp_path, None)
    hot = _ssw(TOF, tmp_path, warm.socket)
    assert cold.returncode == hot.returncode == 0, cold.stderr + hot.stderr
    assert hot.stdout == cold.stdout and '"tof"' in hot.stdout, (cold.stdout, hot.stdout)
    assert hot.stderr == cold.stderr, (cold.stderr, hot.stderr)
    bad = tmp_path / "bad.yaml"
    bad.write_text("sets: {s: {plate_thickness: {values: [-0.4e-3]}}}\n")
    args = ["check-config", "--config", str(bad)]
    cold, hot = _ssw(args, tmp_path, None), _ssw(args, tmp_path, warm.socket)
    assert cold.returncode == hot.returncode == 2
    assert hot.stderr == cold.stderr and "plate_thickness" in hot.stderr
    served = _served(tmp_path / "warm.log")
    assert [line.split(": ", 1)[1] for line in served] == [" ".join(TOF), " ".join(args)]


def test_a_command_whose_imports_would_differ_runs_by_itself(warm, tmp_path):
    """Another BLAS thread count (it moves the TOF's last digits), another working folder:
    the command imports by itself, with its own result; the log says why."""
    other = tmp_path / "elsewhere"
    other.mkdir()
    for cwd, env, why in ((tmp_path, {"OPENBLAS_NUM_THREADS": "2"},
                           "environment variables OPENBLAS_NUM_THREADS"),
                          (other, {}, "the module search path")):
        ref = _ssw(TOF, cwd, None, **env)
        r = _ssw(TOF, cwd, warm.socket, **env)
        assert r.returncode == 0 and r.stdout == ref.stdout, r.stderr
        assert f"runs by itself (differs in {why})" in (tmp_path / "warm.log").read_text()
    assert _served(tmp_path / "warm.log") == []


def test_without_a_warm_process_a_command_runs_by_itself(tmp_path):
    ref = _ssw(TOF, tmp_path, None)
    r = _ssw(TOF, tmp_path, tmp_path / "no-such-socket")
    assert r.returncode == 0 and r.stdout == ref.stdout


def test_ssw_warm_start_0_keeps_a_command_from_a_warm_process(warm, tmp_path):
    """The switch holds for a single command too: named a warm process that answers, it
    runs by itself."""
    r = _ssw(CHECK, tmp_path, warm.socket, SSW_WARM_START="0")
    assert r.returncode == 0 and "valid: True" in r.stdout
    assert _served(tmp_path / "warm.log") == []


def _long_command(warm, tmp_path: Path, started: bool = True
                  ) -> tuple[subprocess.Popen, int]:
    """A served command that runs for minutes (a TOF at 200,000 steps per contact), and its
    pid, once forked (``started``: once it runs ``ssw.cli``, its SIGTERM handler set)."""
    caller = subprocess.Popen(
        [sys.executable, "-m", "ssw", *TOF[:-1], "--steps-per-contact", "200000"],
        cwd=tmp_path, env=_env(**{warmstart.SOCKET_ENV: str(warm.socket)}),
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    end = time.monotonic() + 60
    while not _served(tmp_path / "warm.log"):
        assert time.monotonic() < end and caller.poll() is None, "the command was not served"
        time.sleep(0.001)
    pid = int(_served(tmp_path / "warm.log")[0].split()[1].rstrip(":"))
    while started and not _running_ssw(pid):
        assert time.monotonic() < end and caller.poll() is None, "the command did not start"
        time.sleep(0.02)
    return caller, pid


def _running_ssw(pid: int) -> bool:
    """Whether the fork ``pid`` runs its command: SIGCHLD back to its default (the warm
    process's handler gone) and SIGTERM caught (``ssw.cli``'s), from its ``SigCgt`` mask."""
    status = Path(f"/proc/{pid}/status").read_text()
    mask = int(next(x for x in status.splitlines() if x.startswith("SigCgt:")).split()[1], 16)
    return bool(mask >> (signal.SIGTERM - 1) & 1) and not mask >> (signal.SIGCHLD - 1) & 1


def _ends(pid: int, timeout_s: float = 30.0) -> bool:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.02)
    return False


def test_sigterm_to_the_caller_interrupts_the_command(warm, tmp_path):
    """As Snakemake cancels a job: the command unwinds (ssw.cli's SIGTERM handler) and the
    caller exits with its status, 130."""
    caller, pid = _long_command(warm, tmp_path)
    caller.send_signal(signal.SIGTERM)
    _, err = caller.communicate(timeout=60)
    assert caller.returncode == 130, err
    assert "ssw tof: interrupted" in err
    assert _ends(pid)


def test_a_sigterm_as_the_command_starts_is_never_lost(warm, tmp_path):
    """SIGTERM the moment the fork exists: it dies by it (before ``ssw.cli``'s handler) or
    unwinds (after), never runs on as if it had not come."""
    caller, _ = _long_command(warm, tmp_path, started=False)
    caller.send_signal(signal.SIGTERM)
    caller.communicate(timeout=60)
    assert caller.returncode in (130, -signal.SIGTERM)


def test_a_killed_caller_takes_its_command_with_it(warm, tmp_path):
    caller, pid = _long_command(warm, tmp_path)
    caller.kill()
    caller.wait(60)
    assert _ends(pid), "the command outlived its caller"


def _preload(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=_env(), timeout=300)


def test_the_preload_leaves_one_thread_and_nothing_unforkable():
    r = _preload("from ssw.warmstart import preload, PRELOAD\n"
                 "import os, sys\n"
                 "preload()\n"
                 "print(len(os.listdir('/proc/self/task')), all(m in sys.modules for m in "
                 "PRELOAD))")
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["1", "True"]


@pytest.mark.parametrize("code, message", [
    ("import threading, time\n"
     "threading.Thread(target=time.sleep, args=(30,), daemon=True).start()\n"
     "preload(('numpy',))", "runs 2 threads"),
    ("preload(('gmsh',))", "imported gmsh"),
])
def test_the_preload_refuses_a_process_it_could_not_fork(code, message):
    r = _preload(f"from ssw.warmstart import preload\n{code}")
    assert r.returncode != 0 and message in r.stderr


def test_a_run_with_a_warm_process_beside_it(tmp_path):
    """``python -m ssw.warmstart -- COMMAND`` (``make study``): the command's children are
    served, its exit status is the command's, and the warm process ends with it."""
    env = _env()
    ref = _ssw(TOF, tmp_path, None)
    script = tmp_path / "two.sh"
    script.write_text("export PYTHONPATH=$(pwd -P)${PYTHONPATH:+:$PYTHONPATH}\n"  # the rules'
                      "while [ ! -S \"$SSW_WARM_SOCKET\" ]; do sleep 0.02; done\n"
                      f"{shlex.quote(sys.executable)} -m ssw {' '.join(TOF)}\n"
                      f"{shlex.quote(sys.executable)} -m ssw check-config --config missing.yaml\n")
    r = subprocess.run([sys.executable, "-m", "ssw.warmstart", "--log", "warm.log", "--",
                        "sh", str(script)], cwd=tmp_path, env=env, capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 2 and r.stdout == ref.stdout, r.stderr
    assert "ssw check-config: error" in r.stderr
    log = (tmp_path / "warm.log").read_text()
    assert [line.split(": ", 1)[1] for line in _served(tmp_path / "warm.log")] == [
        " ".join(TOF), "check-config --config missing.yaml"]
    folder = Path(log.split("listening at ")[1].split()[0]).parent
    assert not folder.exists()


class _Run:
    """What ``start_for`` reads of a Snakemake run: a local one."""

    local_exec, remote_exec, subprocess_exec, touch, dryrun = True, False, False, False, False


def test_a_run_adopts_the_warm_process_it_was_given(warm, tmp_path, monkeypatch):
    """The workflow's ``onstart`` (``start_for``) starts none when the run inherited one
    that answers, nor for a dry run or a cluster, nor under ``SSW_WARM_START=off``; else
    one, which ``stop_all`` ends."""
    monkeypatch.delenv(warmstart.SOCKET_ENV, raising=False)
    for attr, value in (("dryrun", True), ("local_exec", False), ("remote_exec", True)):
        run = _Run()
        setattr(run, attr, value)
        assert warmstart.start_for(run, "", tmp_path / "log") is None
    monkeypatch.setenv(warmstart.SWITCH_ENV, "off")
    assert warmstart.start_for(_Run(), "", tmp_path / "log") is None
    monkeypatch.delenv(warmstart.SWITCH_ENV)
    monkeypatch.setenv(warmstart.SOCKET_ENV, str(warm.socket))
    assert warmstart.start_for(_Run(), "", tmp_path / "log") is None
    monkeypatch.delenv(warmstart.SOCKET_ENV)
    own = warmstart.start_for(_Run(), str(tmp_path), tmp_path / "log")
    assert own is not None and os.environ[warmstart.SOCKET_ENV] == str(own.socket)
    warmstart.stop_all()
    assert own.process.poll() is not None and warmstart.SOCKET_ENV not in os.environ


def test_a_command_with_other_process_limits_runs_by_itself(warm, tmp_path):
    """A fork keeps the warm process's limits: a command under a tighter one (``ulimit``)
    runs by itself, under its own limit."""
    r = subprocess.run(["sh", "-c", f"ulimit -n 512 && {shlex.quote(sys.executable)} -m ssw "
                              f"{' '.join(TOF)}"],
                       cwd=tmp_path, capture_output=True, text=True, timeout=300,
                       env=_env(**{warmstart.SOCKET_ENV: str(warm.socket)}))
    assert r.returncode == 0 and '"tof"' in r.stdout, r.stderr
    assert "runs by itself (differs in the resource limits)" in (
        tmp_path / "warm.log").read_text()


# ---- a warm process that fails, or is failed
CHECK = ["check-config", "--config", str(Path(__file__).resolve().parents[1] / "config"
                                          / "ci.yaml")]


@pytest.fixture
def injected(tmp_path: Path) -> Iterator[Callable[[str], subprocess.Popen]]:
    """Start a warm process as ``ssw.warmstart.run.start`` does, after running ``prelude``
    in it (the failure it injects); it serves commands run in ``tmp_path`` with
    :func:`_env`, logs to ``tmp_path / "warm.log"``, and ends with the test."""
    import shutil
    import tempfile

    started: list[tuple[subprocess.Popen, Path]] = []

    def start(prelude: str) -> subprocess.Popen:
        folder = Path(tempfile.mkdtemp(prefix="ssw-warm-"))
        code = (f"{prelude}\nimport sys\nfrom ssw.warmstart.server import main\n"
                "main(sys.argv[1], int(sys.argv[2]))")
        with open(tmp_path / "warm.log", "wb") as log:
            proc = subprocess.Popen([sys.executable, "-c", code, str(folder / "socket"),
                                     str(os.getpid())], env=_env(), cwd=tmp_path, stdout=log,
                                    stderr=subprocess.STDOUT, start_new_session=True)
        started.append((proc, folder))
        proc.socket = folder / "socket"  # type: ignore[attr-defined]
        end = time.monotonic() + 120
        while not proc.socket.exists():  # type: ignore[attr-defined]
            assert time.monotonic() < end and proc.poll() is None, (
                tmp_path / "warm.log").read_text()
            time.sleep(0.02)
        return proc

    yield start
    for proc, folder in started:
        if proc.poll() is None:
            proc.kill()
            proc.wait(30)
        shutil.rmtree(folder, ignore_errors=True)


def _blocked_signals(pid: int) -> int:
    status = Path(f"/proc/{pid}/status").read_text()
    return int(next(x for x in status.splitlines() if x.startswith("SigBlk:")).split()[1], 16)


def test_a_failed_fork_runs_the_command_by_itself_and_unblocks_the_signals(injected, tmp_path):
    """``fork()`` fails once (EAGAIN, injected): the command runs by itself with its own
    output; the warm process's signal mask is empty again (the forwarded signals were
    blocked around the fork), it serves the next command, and SIGTERM stops it at once."""
    warm = injected("import os\n"
                    "_fork, _calls = os.fork, []\n"
                    "def fork():\n"
                    "    _calls.append(1)\n"
                    "    if len(_calls) == 1:\n"
                    "        raise BlockingIOError(11, 'Resource temporarily unavailable')\n"
                    "    return _fork()\n"
                    "os.fork = fork\n")
    ref = _ssw(CHECK, tmp_path, None)
    first = _ssw(CHECK, tmp_path, warm.socket)
    assert first.returncode == ref.returncode == 0 and first.stdout == ref.stdout, first.stderr
    log = (tmp_path / "warm.log").read_text()
    assert "runs by itself (the warm process could not fork: [Errno 11]" in log, log
    assert _blocked_signals(warm.pid) == 0
    second = _ssw(CHECK, tmp_path, warm.socket)
    assert second.stdout == ref.stdout and len(_served(tmp_path / "warm.log")) == 1
    warm.send_signal(signal.SIGTERM)
    assert warm.wait(10) == 0


def test_a_pid_that_cannot_be_sent_kills_its_fork_unrun(injected, tmp_path):
    """The reply with the fork's pid fails (EPIPE, injected): the fork is killed at its gate
    before it ran anything, and the caller, without a pid, runs the command by itself: its
    output once, the same as a fresh process's."""
    warm = injected("import socket\n"
                    "_send, _calls = socket.socket.sendall, []\n"
                    "def sendall(self, data, *args):\n"
                    "    if data.startswith(b'{\"pid\"') and not _calls:\n"
                    "        _calls.append(1)\n"
                    "        raise BrokenPipeError(32, 'Broken pipe')\n"
                    "    return _send(self, data, *args)\n"
                    "socket.socket.sendall = sendall\n")
    ref = _ssw(CHECK, tmp_path, None)
    r = _ssw(CHECK, tmp_path, warm.socket)
    assert r.returncode == 0 and r.stdout == ref.stdout and r.stderr == ref.stderr, r.stderr
    log = (tmp_path / "warm.log").read_text()
    line = next(x for x in log.splitlines() if "its pid could not be sent" in x)
    pid = int(line.split("; pid ")[1].split()[0])
    assert _ends(pid, 10) and _served(tmp_path / "warm.log") == []
    again = _ssw(CHECK, tmp_path, warm.socket)
    assert again.stdout == ref.stdout and len(_served(tmp_path / "warm.log")) == 1


#: The request deadline (s) of the warm process in the silent-caller test: long enough for
#: a served check-config on a loaded machine (about 1 s), short of ``REQUEST_TIMEOUT_S``.
SHORT_DEADLINE_S = 5.0

#: A caller that sends a whole valid request (its streams: a pipe it reads) and reads the
#: fork's pid, then leaves (``leave``) or stays silent without confirming (``stay``); it
#: prints the pid, then what the fork wrote to the pipe (nothing: it never ran).
RAW_CALLER = """
import json, os, socket, sys, time
from ssw import warmstart
r, w = os.pipe()
payload = json.dumps({"argv": ["ssw", "check-config", "--config", sys.argv[2]],
                      "cwd": os.getcwd(), "env": dict(os.environ), "umask": 0o22,
                      "fingerprint": warmstart.fingerprint(), "pids": [os.getpid()]}).encode()
s = socket.socket(socket.AF_UNIX)
s.connect(os.environ[warmstart.SOCKET_ENV])
socket.send_fds(s, [warmstart.LENGTH.pack(len(payload))], [0, w, w])
s.sendall(payload)
pid = json.loads(s.makefile("rb").readline())["pid"]
os.close(w)
print(pid, flush=True)
if sys.argv[1] == "stay":
    time.sleep(float(sys.argv[3]))
s.close()
os.set_blocking(r, False)
time.sleep(1.0)
try:
    data = os.read(r, 1000)  # b"": every writer gone (the fork ended)
except BlockingIOError:
    data = b""
print(repr(data) if data else "nothing")
"""


def _raw_caller(mode: str, tmp_path: Path, socket: Path, wait_s: float = 0.0
                ) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-c", RAW_CALLER, mode, CHECK[-1], str(wait_s)],
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=_env(**{warmstart.SOCKET_ENV: str(socket)}))


def _malformed(socket_path: Path, kind: str) -> None:
    """Send the warm process a malformed request of ``kind`` and close."""
    import socket

    def whole(body: bytes) -> list[bytes]:
        return [warmstart.LENGTH.pack(len(body)), body]

    request = json.dumps({"argv": ["ssw", "--version"], "cwd": "/", "env": {}, "umask": 18,
                          "fingerprint": {}}).encode()
    # the first field compared that differs, the environment, is not a mapping
    odd = json.dumps({"argv": ["ssw", "--version"], "cwd": "/", "env": {}, "umask": 18,
                      "fingerprint": {"cpus": sorted(os.sched_getaffinity(0)),
                                      "env": ["not", "a", "mapping"]}}).encode()
    frames = {
        "closed before its length": [],
        "a length cut short": [b"\x00\x00"],
        "a body cut short": [warmstart.LENGTH.pack(100), b'{"argv": '],
        "no JSON": whole(b"\xff\xfegarbage"),
        "JSON not an object": whole(b"[1, 2, 3]"),
        "argv not text": whole(b'{"argv": [1, 2], "cwd": 3, "env": "x"}'),
        "a length too long": [warmstart.LENGTH.pack(1 << 30)],
        "more bytes than its length": [warmstart.LENGTH.pack(2), b"{}{}"],
        "no descriptors": whole(request),
        "five descriptors": whole(request),
        "deep JSON": whole(b"[" * 100_000 + b"]" * 100_000),
        "a fingerprint of another shape": whole(odd),
    }[kind]
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
        s.connect(str(socket_path))
        fds = [] if kind in ("no descriptors", "closed before its length") else [0, 1, 2]
        fds = [0, 1, 2, 1, 2] if kind == "five descriptors" else fds
        for i, frame in enumerate(frames):
            if i == 0 and fds:
                socket.send_fds(s, [frame], fds)
            else:
                s.sendall(frame)


MALFORMED = ("closed before its length", "a length cut short", "a body cut short", "no JSON",
             "JSON not an object", "argv not text", "a length too long",
             "more bytes than its length", "no descriptors", "five descriptors", "deep JSON",
             "a fingerprint of another shape")


def test_malformed_requests_leave_it_serving(warm, tmp_path):
    """Every kind of malformed request is dropped (logged), the warm process serves on; a
    caller that leaves with its pid unconfirmed has its fork killed before it ran (nothing
    written to its streams); and meanwhile a real command is served as before."""
    server = warm.process.pid
    fds = len(os.listdir(f"/proc/{server}/fd"))
    for kind in MALFORMED:
        _malformed(warm.socket, kind)
    left = _raw_caller("leave", tmp_path, warm.socket)
    out, err = left.communicate(timeout=120)
    assert left.returncode == 0, err
    pid, written = out.split()
    assert written == "nothing" and _ends(int(pid), 10)
    ref = _ssw(CHECK, tmp_path, None)
    r = _ssw(CHECK, tmp_path, warm.socket)
    assert r.returncode == 0 and r.stdout == ref.stdout, r.stderr
    assert warm.process.poll() is None
    end = time.monotonic() + 10  # the streams it was sent, closed
    while len(os.listdir(f"/proc/{server}/fd")) != fds and time.monotonic() < end:
        time.sleep(0.05)
    assert len(os.listdir(f"/proc/{server}/fd")) == fds
    log = (tmp_path / "warm.log").read_text()
    dropped = [line for line in log.splitlines() if line.startswith("a request dropped (")]
    # each kind logged (in the order the warm process read them) but the bare connection
    # (a probe's), and the unconfirmed caller
    assert len(dropped) == len(MALFORMED) - 1 + 1, log
    assert sum(x.startswith("a request dropped (the caller left before it confirmed)")
               for x in dropped) == 1, log
    assert [line.split(": ", 1)[1] for line in _served(tmp_path / "warm.log")] == [
        " ".join(CHECK)]


def test_a_silent_caller_holds_up_nobody_and_is_dropped_in_time(injected, tmp_path):
    """A caller that connects and sends nothing, and one that has its pid and never
    confirms: another command is served meanwhile; after the request deadline both are
    dropped, the unconfirmed fork killed unrun. (The deadline is cut from
    ``REQUEST_TIMEOUT_S`` to :data:`SHORT_DEADLINE_S` in the warm process: the same
    expiry, sooner.)"""
    import socket

    warm = injected("import ssw.warmstart.server as s\n"
                    f"s.REQUEST_TIMEOUT_S = {SHORT_DEADLINE_S!r}")
    silent = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    silent.connect(str(warm.socket))
    stay = _raw_caller("stay", tmp_path, warm.socket, wait_s=SHORT_DEADLINE_S + 2.0)
    pid = int(stay.stdout.readline())
    t0 = time.monotonic()
    r = _ssw(CHECK, tmp_path, warm.socket)
    assert r.returncode == 0 and len(_served(tmp_path / "warm.log")) == 1
    assert time.monotonic() - t0 < SHORT_DEADLINE_S  # not held up by the two
    assert _ends(pid, SHORT_DEADLINE_S + 2.0)
    out, _ = stay.communicate(timeout=60)
    assert out.split() == ["nothing"]
    assert silent.recv(16) == b""  # dropped
    silent.close()
    log = (tmp_path / "warm.log").read_text()
    assert f"a request dropped (no whole request in {SHORT_DEADLINE_S:g} s)" in log
    assert f"a request dropped (no confirmation in {SHORT_DEADLINE_S:g} s)" in log


def test_a_caller_whose_warm_process_dies_stops_its_command(injected, tmp_path):
    """The warm process SIGKILLed while a served command runs: the caller stops the
    command's process group and exits 1 with a message that names SSW_WARM_START=0; no
    process of the command is left. (The fork's own request to get SIGTERM when the warm
    process ends is disabled here: the caller alone stops it.)"""
    warm = injected("import ssw.warmstart.server as s\ns._PR_SET_PDEATHSIG = -1  # no such")
    caller, pid = _long_command(warm, tmp_path)
    warm.kill()
    _, err = caller.communicate(timeout=60)
    assert caller.returncode == 1, err
    assert "ended while it ran this command" in err and "SSW_WARM_START=0" in err
    assert _ends(pid, 5)


def test_a_command_ends_with_its_warm_process_when_its_caller_is_gone_too(injected, tmp_path):
    """The caller and then the warm process SIGKILLed (nothing left to pass a signal on):
    the fork gets SIGTERM from the kernel when the warm process ends, and unwinds."""
    warm = injected("")
    caller, pid = _long_command(warm, tmp_path)
    os.kill(warm.pid, signal.SIGSTOP)  # the caller's end unseen: only the kernel acts
    caller.kill()
    caller.wait(60)
    assert not _ends(pid, 1.0)
    warm.kill()
    assert _ends(pid, 30)


def test_a_stale_socket_name_neither_holds_a_command_nor_keeps_a_run_from_its_own(
        tmp_path, monkeypatch):
    """``SSW_WARM_SOCKET`` names a socket nothing listens at (a run that ended, its folder
    still there): a command runs by itself at once, and ``start_for`` starts the run's own
    warm process; a name whose warm process is still starting (its id in the folder, its
    socket not yet open) is adopted."""
    import socket

    stale = tmp_path / "old" / "socket"
    stale.parent.mkdir()
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
        s.bind(str(stale))
    assert stale.exists()
    ref = _ssw(CHECK, tmp_path, None)
    t0 = time.monotonic()
    r = _ssw(CHECK, tmp_path, stale)
    assert r.returncode == 0 and r.stdout == ref.stdout
    assert time.monotonic() - t0 < warmstart.REPLY_TIMEOUT_S
    assert not warmstart.answering(str(stale))
    monkeypatch.setenv(warmstart.SOCKET_ENV, str(stale))
    own = warmstart.start_for(_Run(), str(tmp_path), tmp_path / "log")
    try:
        assert own is not None and os.environ[warmstart.SOCKET_ENV] == str(own.socket)
        # before its socket opens, the new warm process counts as answering: adopted
        assert warmstart.answering(str(own.socket))
        assert warmstart.start_for(_Run(), str(tmp_path), tmp_path / "log") is None
    finally:
        warmstart.stop_all()
    assert not warmstart.answering(str(own.socket))


def test_the_warm_start_steps_aside_where_fork_is_unsafe(monkeypatch, tmp_path):
    """On macOS and off POSIX no run starts a warm process and no command asks one, even
    with ``SSW_WARM_SOCKET`` set; the module loads without the POSIX-only signals."""
    monkeypatch.setenv(warmstart.SOCKET_ENV, str(tmp_path / "socket"))
    for target, name, value in ((sys, "platform", "darwin"), (os, "name", "nt")):
        with monkeypatch.context() as m:
            m.setattr(target, name, value)
            assert not warmstart.usable() and not warmstart.switched_on()
            assert warmstart.start_for(_Run(), str(tmp_path), tmp_path / "log") is None
            assert warmstart.request(["ssw", "--version"]) is None
    r = _preload("import signal\n"
                 "del signal.SIGHUP, signal.SIGQUIT\n"
                 "import ssw.warmstart as w, ssw.warmstart.run\n"
                 "print(sorted(s.name for s in w.FORWARDED))")
    assert r.returncode == 0 and r.stdout.split() == ["['SIGINT',", "'SIGTERM']"], r.stderr


# ---- the code that runs
def _copy_of_ssw(where: Path) -> Path:
    """A copy of the package (its compiled chain step too) in ``where``, with the
    repository's config beside it: a command run in ``where`` imports this copy."""
    import shutil

    root = Path(__file__).resolve().parents[1]
    shutil.copytree(root / "ssw", where / "ssw", ignore=shutil.ignore_patterns("__pycache__"))
    (where / "config").symlink_to(root / "config")
    return where


def _edit(path: Path) -> None:
    with open(path, "a") as fh:
        fh.write("\n# an edit made while a run goes on\n")


def _source_of(r: subprocess.CompletedProcess) -> str:
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)["provenance"]["source_sha256"]


#: In a process of a copy of ssw: load what ``ssw tof`` and the contact operators run, edit
#: (argv[1:]) two of those files, then print the hashes its results and its operators'
#: cache would carry.
HASHES_AFTER_AN_EDIT = """
import sys
import ssw.cli.chain, ssw.contact.operators as ops, ssw.tof.api
from ssw import provenance
for path in sys.argv[1:]:
    with open(path, "a") as fh:
        fh.write("\\n# an edit made while the process runs\\n")
provenance.set_context(["ssw.cli.chain"])
print(provenance.record({})["source_sha256"], ops._code_hash())
"""
HASHES = ("import ssw.contact.operators as ops\nfrom ssw import provenance\n"
          "provenance.set_context(['ssw.cli.chain'])\n"
          "print(provenance.record({})['source_sha256'], ops._code_hash())")


def test_an_edit_of_ssw_during_a_run_labels_nothing_with_code_that_did_not_make_it(tmp_path):
    """Files of ssw edited while a warm process serves: the next command runs by itself
    (the new code, labelled with its hash; the log says why), never a fork of the old code
    labelled with the new hash; and a process that loaded the old code labels its results
    and its contact operators' cache key with the old code's hashes (those of a process
    that ran on the unedited files), not with the files' on disk when it writes."""
    pkg = _copy_of_ssw(tmp_path / "pkg")
    edited = [pkg / "ssw" / "tof" / "api.py", pkg / "ssw" / "contact" / "mesh.py"]
    before = _source_of(_ssw(TOF, pkg, None))
    old = subprocess.run([sys.executable, "-c", HASHES], cwd=pkg, capture_output=True,
                         text=True, env=_env(), timeout=300).stdout.split()
    warm = warmstart.start(_env(), tmp_path / "warm.log", cwd=pkg)
    try:
        end = time.monotonic() + 120
        while not warm.socket.exists():
            assert time.monotonic() < end and warm.process.poll() is None
            time.sleep(0.02)
        assert _source_of(_ssw(TOF, pkg, warm.socket)) == before
        assert len(_served(tmp_path / "warm.log")) == 1
        _edit(edited[0])
        after = _source_of(_ssw(TOF, pkg, warm.socket))
    finally:
        warmstart.stop(warm)
    log = (tmp_path / "warm.log").read_text()
    assert f"the code changed since the warm process loaded it: {edited[0]}" in log, log
    assert len(_served(tmp_path / "warm.log")) == 1
    assert after == _source_of(_ssw(TOF, pkg, None)) != before
    # a process that loaded the code, then the files edited under it
    other = _copy_of_ssw(tmp_path / "other")
    r = subprocess.run([sys.executable, "-c", HASHES_AFTER_AN_EDIT,
                        *(str(other / p.relative_to(pkg)) for p in edited)], cwd=other,
                       capture_output=True, text=True, env=_env(), timeout=300)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == old
    new = subprocess.run([sys.executable, "-c", HASHES], cwd=other, capture_output=True,
                         text=True, env=_env(), timeout=300).stdout.split()
    assert len(new) == 2 and new[0] != old[0] and new[1] != old[1]


# ---- the benchmark records
BENCH_SNAKEFILE = """
import os
from pathlib import Path

import ssw.warmstart as warm


onstart:
    warm.start_for(workflow, {root!r}, Path("warm.log"))


onsuccess:
    warm.stop_all()


onerror:
    warm.stop_all()


rule tof:
    output:
        "tof.json",
    benchmark:
        "bench.tsv"
    shell:
        "export PYTHONPATH={shell_root}${{{{PYTHONPATH:+:$PYTHONPATH}}}}; "
        "while [ ! -S $SSW_WARM_SOCKET ]; do sleep 0.02; done; "  # its imports done
        "python -m ssw {args} > {{output}}"
"""


def test_the_benchmark_record_of_a_served_job_is_the_jobs_own(tmp_path):
    """A Snakemake job with a ``benchmark:`` record, served by the run's warm process: the
    record's CPU time and peak memory are those of the command itself (what it measured of
    itself with getrusage, ``ssw.cli._record_usage``), not the 30 ms caller's."""
    from ssw.cli import USAGE_ENV

    root = str(Path(__file__).resolve().parents[1])
    args = " ".join([*TOF, "--steps-per-contact", "10000"])
    snakefile = BENCH_SNAKEFILE.format(root=root, shell_root=shlex.quote(root), args=args)
    (tmp_path / "Snakefile").write_text(snakefile)
    env = _env(**{USAGE_ENV: str(tmp_path / "usage")})
    env.pop("PYTHONPATH", None)
    r = subprocess.run([str(Path(sys.executable).with_name("snakemake")), "--cores", "1",
                        "--snakefile", str(tmp_path / "Snakefile"), "--directory",
                        str(tmp_path)], cwd=tmp_path, env=env, capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    assert len(_served(tmp_path / "warm.log")) == 1, (tmp_path / "warm.log").read_text()
    (own,) = [json.loads(p.read_text()) for p in (tmp_path / "usage").glob("*.json")]
    assert own["cpu_s"] > 0.3  # the command's own work: the record has something to show
    head, row = (tmp_path / "bench.tsv").read_text().splitlines()[:2]
    rec = dict(zip(head.split("\t"), row.split("\t"), strict=True))
    # the record adds the fork's whole account (wait4: at least what it saw of itself)
    # to the sampled shell and caller (tens of ms)
    # (the record's figures have two decimals)
    assert own["cpu_s"] - 0.005 <= float(rec["cpu_time"]) <= own["cpu_s"] + 1.0, (rec, own)
    assert float(rec["max_rss"]) >= own["max_rss_mb"] - 0.005, (rec, own)
    assert not list((tmp_path / "usage").glob("*.tmp"))
