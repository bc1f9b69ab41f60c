"""The warm start (ssw.warmstart): a command forked from the warm process prints, writes and
exits as a fresh ``python -m ssw`` process does; one whose imports would differ runs by
itself; signals reach the command; the warm process holds no thread and nothing that
cannot be forked."""

from __future__ import annotations

import os
import shlex
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
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


def test_a_run_adopts_the_warm_process_it_was_given(tmp_path, monkeypatch):
    """The workflow's ``onstart`` (``start_for``) starts none when the run inherited one,
    nor for a dry run or a cluster, nor under ``SSW_WARM_START=off``; else one, which
    ``stop_all`` ends."""

    class Run:
        local_exec, remote_exec, subprocess_exec, touch, dryrun = True, False, False, False, False

    monkeypatch.delenv(warmstart.SOCKET_ENV, raising=False)
    for attr, value in (("dryrun", True), ("local_exec", False), ("remote_exec", True)):
        run = Run()
        setattr(run, attr, value)
        assert warmstart.start_for(run, "", tmp_path / "log") is None
    monkeypatch.setenv(warmstart.SWITCH_ENV, "off")
    assert warmstart.start_for(Run(), "", tmp_path / "log") is None
    monkeypatch.delenv(warmstart.SWITCH_ENV)
    monkeypatch.setenv(warmstart.SOCKET_ENV, str(tmp_path / "socket"))
    assert warmstart.start_for(Run(), "", tmp_path / "log") is None
    monkeypatch.delenv(warmstart.SOCKET_ENV)
    warm = warmstart.start_for(Run(), str(tmp_path), tmp_path / "log")
    assert warm is not None and os.environ[warmstart.SOCKET_ENV] == str(warm.socket)
    warmstart.stop_all()
    assert warm.process.poll() is not None and warmstart.SOCKET_ENV not in os.environ


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
