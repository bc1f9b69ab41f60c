"""Interrupt safety: a run killed at any point never leaves a file that a re-run would use.

Truth: a file under its final name is either absent or complete (every dataset present and
equal to what an uninterrupted writer produces); a re-run after the kill completes and its
results equal an uninterrupted run's.

* ``ssw.h5io`` level: a writer process is SIGKILLed (no cleanup possible) or SIGINTed
  between datasets; the destination must not exist, and the orphaned temporary file must
  not carry the final name.
* Snakemake level: the whole process group of a run is killed mid-job (SIGKILL: Snakemake
  cannot clean up; SIGINT: Ctrl-C), then the run is repeated with the workstation profile
  (``workflow/profiles/default``) and must finish with complete, correct outputs, also
  for a deliberately non-atomic writer (Snakemake's incomplete-file marker must catch it).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from ssw.h5io import read_datasets

ROOT = Path(__file__).resolve().parents[1]
VENV_BIN = Path(sys.executable).parent
PROFILE = ROOT / "workflow" / "profiles" / "default"
N_DATASETS = 6
ROWS = 200_000  # float64 rows per dataset: 1.6 MB, so a write takes measurable time

# A writer that signals its progress through a side file and pauses between datasets, so
# the test can kill it at a chosen point in the middle of writing.
WRITER = textwrap.dedent(f"""
    import sys, time
    import numpy as np
    from ssw.h5io import atomic_h5, write_dataset
    dest, progress = sys.argv[1], sys.argv[2]
    with atomic_h5(dest, kind="interrupt_test", inputs={{"rows": {ROWS}}}) as f:
        for i in range({N_DATASETS}):
            write_dataset(f, f"d{{i}}", np.arange({ROWS}, dtype=float) * (i + 1), "m")
            f.flush()
            with open(progress, "a") as p:
                p.write(f"{{i}}\\n")
            time.sleep(0.1 if i < {N_DATASETS - 1} else 0.5)  # a window before the rename
""")


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PATH"] = f"{VENV_BIN}{os.pathsep}{env.get('PATH', '')}"
    env.pop("SNAKEMAKE_PROFILE", None)
    return env


def _wait_for_lines(path: Path, n: int, proc: subprocess.Popen, timeout: float = 60.0) -> None:
    """Block until ``path`` has ``n`` lines (the writer's progress); fail on timeout/exit."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if path.exists() and len(path.read_text().split()) >= n:
            return
        if proc.poll() is not None:
            pytest.fail(f"process exited early with {proc.returncode}")
        time.sleep(0.02)
    proc.kill()
    pytest.fail(f"no progress line {n} in {path} within {timeout} s")


def check_complete(path: Path) -> None:
    """The file holds every dataset with the uninterrupted writer's values."""
    with h5py.File(path, "r") as f:
        assert f.attrs["ssw_kind"] == "interrupt_test"
        for i in range(N_DATASETS):
            np.testing.assert_array_equal(f[f"d{i}"][...], np.arange(ROWS) * (i + 1.0))
            assert f[f"d{i}"].attrs["units"] == "m"


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGINT, signal.SIGTERM])
@pytest.mark.parametrize("after", [1, N_DATASETS - 1])
def test_killed_writer_leaves_no_file(tmp_path: Path, sig: int, after: int) -> None:
    """Kill an atomic_h5 writer after ``after`` datasets: no file under the final name."""
    dest, progress = tmp_path / "out.h5", tmp_path / "progress"
    proc = subprocess.Popen([sys.executable, "-c", WRITER, str(dest), str(progress)],
                            env=_env())
    _wait_for_lines(progress, after, proc)
    proc.send_signal(sig)
    proc.wait(timeout=30)
    assert proc.returncode != 0
    assert not dest.exists(), "a killed writer left a file under the final name"
    leftovers = [p.name for p in tmp_path.iterdir() if p.name not in {"progress"}]
    # SIGKILL (and SIGTERM, which Python does not catch by default) run no cleanup: the
    # temporary file may stay, but hidden and never under the final name.
    assert all(n.startswith(".out.h5.") and n.endswith(".part") for n in leftovers), leftovers
    if sig == signal.SIGINT:
        assert leftovers == [], f"cleanup after a catchable signal left {leftovers}"
    # The re-run completes, and the orphan does not disturb it.
    progress.unlink()
    subprocess.run([sys.executable, "-c", WRITER, str(dest), str(progress)], env=_env(),
                   check=True, timeout=60)
    check_complete(dest)


SNAKEFILE = textwrap.dedent('''
    # Two writers: `atomic` through ssw.h5io, `naive` straight into the final name (the kind
    # of writer the incomplete marker of Snakemake must catch), then a consumer of both.
    WRITER = config["writer"]


    rule all:
        input:
            "out/summary.txt",


    rule atomic:
        output:
            "out/atomic.h5",
        shell:
            "python -c '{WRITER}' {output} progress_atomic"


    rule naive:
        output:
            "out/naive.txt",
        shell:
            "for i in 1 2 3 4 5 6; do echo line$i >> {output}; echo $i >> progress_naive;"
            " sleep 0.2; done"


    rule summary:
        input:
            h5="out/atomic.h5",
            txt="out/naive.txt",
        output:
            "out/summary.txt",
        shell:
            "python -c 'import h5py; f = h5py.File(\\"{input.h5}\\"); "
            "print(len(f), f[\\"d5\\"][-1])' > {output}; wc -l < {input.txt} >> {output}"
''')


def _snakemake(workdir: Path, writer_file: Path) -> list[str]:
    return [str(VENV_BIN / "snakemake"), "--profile", str(PROFILE), "--cores", "2",
            "--directory", str(workdir), "--config", f"writer={writer_file.read_text()}"]


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGINT])
def test_killed_snakemake_reruns_cleanly(tmp_path: Path, sig: int) -> None:
    """Kill a Snakemake run mid-write (whole process group), re-run with the profile.

    After SIGKILL the lock stays and is removed with ``--unlock`` first (the documented
    recovery); after SIGINT (Ctrl-C) Snakemake releases it itself.
    The re-run must finish, redo the half-written ``naive`` file (6 lines, not fewer or
    more), and the consumer must see complete inputs.
    """
    work = tmp_path / "wf"
    work.mkdir()
    (work / "Snakefile").write_text(SNAKEFILE)
    writer = tmp_path / "writer.py"
    writer.write_text(WRITER.replace("'", '"'))
    proc = subprocess.Popen(_snakemake(work, writer), cwd=work, env=_env(),
                            start_new_session=True, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE)
    _wait_for_lines(work / "progress_atomic", 2, proc)
    _wait_for_lines(work / "progress_naive", 2, proc)
    os.killpg(proc.pid, sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode != 0, err[-2000:]
    time.sleep(0.5)  # let any straggler of the killed group die before looking
    assert not (work / "out" / "atomic.h5").exists()
    assert not (work / "out" / "summary.txt").exists()
    for p in work.glob("progress_*"):
        p.unlink()
    if sig == signal.SIGKILL:
        # A killed Snakemake cannot release its lock; the documented recovery (docs/cluster.md)
        # is `--unlock`, which refuses nothing else: the incomplete markers stay.
        subprocess.run([*_snakemake(work, writer), "--unlock"], cwd=work, env=_env(),
                       check=True, capture_output=True, timeout=60)
    rerun = subprocess.run(_snakemake(work, writer), cwd=work, env=_env(),
                           capture_output=True, text=True, timeout=120)
    assert rerun.returncode == 0, rerun.stderr[-3000:]
    check_complete(work / "out" / "atomic.h5")
    assert (work / "out" / "naive.txt").read_text().split() == [f"line{i}" for i in range(1, 7)]
    count, last, lines = (work / "out" / "summary.txt").read_text().split()
    assert (int(count), float(last), int(lines)) == (N_DATASETS, 6.0 * (ROWS - 1), 6)


CONTACT_STEPS = 400


def _contact_cmd(out: Path) -> list[str]:
    return [str(VENV_BIN / "ssw"), "contact", "--soil-E", "5e7", "--soil-nu", "0.3",
            "--plate-thickness", "0", "--steps", str(CONTACT_STEPS), "--output", str(out)]


@pytest.fixture(scope="module")
def contact_reference(tmp_path_factory):
    """(wall time s, curve) of one uninterrupted `ssw contact` run."""
    from ssw.curve import read_curve

    out = tmp_path_factory.mktemp("reference") / "curve.h5"
    t0 = time.monotonic()
    subprocess.run(_contact_cmd(out), env=_env(), check=True, capture_output=True,
                   timeout=120)
    return time.monotonic() - t0, read_curve(out)


@pytest.mark.parametrize("share", [0.3, 0.6, 0.9, 0.97])
def test_killed_ssw_contact_leaves_nothing_or_a_complete_curve(
    tmp_path: Path, share: float, contact_reference
) -> None:
    """SIGKILL a real `ssw contact` at a share of its uninterrupted run time (the last ones
    fall in the LCP loop or the HDF5 write): the output is absent or a complete curve, and
    the re-run writes the same curve as an uninterrupted run."""
    from ssw.curve import read_curve

    full, reference = contact_reference
    out = tmp_path / "curve.h5"
    proc = subprocess.Popen(_contact_cmd(out), env=_env(), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    time.sleep(share * full)
    proc.kill()
    proc.wait(timeout=30)
    if out.exists():  # finished before the kill: must be the whole curve
        assert read_curve(out).force.shape == (CONTACT_STEPS,)
    assert all(p.name.endswith(".part") for p in tmp_path.iterdir() if p != out)
    subprocess.run(_contact_cmd(out), env=_env(), check=True, capture_output=True,
                   timeout=120)
    again = read_curve(out)
    np.testing.assert_array_equal(again.force, reference.force)
    np.testing.assert_array_equal(again.delta, reference.delta)




@pytest.mark.slow
@pytest.mark.parametrize("share", [0.35, 0.7])
def test_killed_ci_study_reruns_to_the_same_results(tmp_path: Path, share: float) -> None:
    """The tiny study (config/ci.yaml) SIGKILLed (whole process group) at a share of its
    run time, unlocked and re-run, gives the same HDF5 datasets and CSV tables as an
    uninterrupted run."""
    config = ROOT / "config" / "ci.yaml"

    def cmd(work: Path) -> list[str]:
        return [str(VENV_BIN / "snakemake"), "--snakefile", str(ROOT / "workflow" / "Snakefile"),
                "--profile", str(PROFILE), "--cores", "2", "--configfile", str(config),
                "--directory", str(work)]

    ref, cut = tmp_path / "ref", tmp_path / "cut"
    t0 = time.monotonic()
    first = subprocess.run(cmd(ref), cwd=ROOT, env=_env(), capture_output=True, text=True,
                           timeout=600)
    i = first.stderr.find("Error in rule")
    assert first.returncode == 0, f"the uninterrupted run failed:\n{first.stderr[i:i + 2000]}"
    full = time.monotonic() - t0
    proc = subprocess.Popen(cmd(cut), cwd=ROOT, env=_env(), start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(share * full)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait(timeout=60)
    time.sleep(0.5)
    subprocess.run([*cmd(cut), "--unlock"], cwd=ROOT, env=_env(), check=True,
                   capture_output=True, timeout=120)
    rerun = subprocess.run(cmd(cut), cwd=ROOT, env=_env(), capture_output=True, text=True,
                           timeout=600)
    assert rerun.returncode == 0, rerun.stderr[-3000:]
    files = sorted(p.relative_to(ref) for p in (ref / "results").rglob("*")
                   if p.suffix in {".h5", ".csv"})
    assert files == sorted(p.relative_to(cut) for p in (cut / "results").rglob("*")
                           if p.suffix in {".h5", ".csv"})
    assert len(files) >= 10
    for name in files:
        if name.suffix == ".csv":
            assert (cut / name).read_text() == (ref / name).read_text(), name
            continue
        a, b = read_datasets(cut / name), read_datasets(ref / name)
        assert sorted(a) == sorted(b), name
        for key in a:
            assert np.array_equal(a[key], b[key], equal_nan=np.asarray(a[key]).dtype.kind == "f"), \
                f"{name}:{key}"


def _batch_cmd(out_dir: Path, ids: list[str]) -> list[str]:
    scenes = [a for i in ids for a in ("--scene", i)]
    return [str(VENV_BIN / "ssw"), "contact", *scenes, "--config", str(ROOT / "config" / "ci.yaml"),
            "--steps", str(CONTACT_STEPS), "--output-dir", str(out_dir)]


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
def test_killed_contact_batch_leaves_only_complete_curves(tmp_path: Path, sig: int) -> None:
    """A batch (`ssw contact --scene A --scene B --scene C --output-dir D`, what a workflow
    contact job runs) killed right after its first curve appeared: every file under a final
    name is a complete curve, the rest are hidden `.part` files (none after SIGTERM, which
    unwinds); the re-run writes all three, the first equal to the one written before."""
    from ssw.config import load_config
    from ssw.curve import read_curve
    from ssw.workflow import families

    ids = [i for b in families(load_config(ROOT / "config" / "ci.yaml")).values() for i in b][:3]
    out = tmp_path / "contact"
    # a cold operator cache: a scene costs milliseconds once its plate's and soil's condensed
    # operators exist (ssw.contact.operators), ~0.2-0.5 s to build them first; the scenes
    # here need two plates' operators (PLA, aluminium), so the batch is still running when
    # its first curve appears
    env = {**_env(), "SSW_CACHE_DIR": str(tmp_path / "cache")}
    proc = subprocess.Popen(_batch_cmd(out, ids), env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    first = out / f"{ids[0]}.h5"
    t0 = time.monotonic()
    while not first.exists() and proc.poll() is None and time.monotonic() - t0 < 120:
        time.sleep(0.005)
    proc.send_signal(sig)
    proc.wait(timeout=60)
    assert first.exists()
    done = {p.name: read_curve(p).force for p in out.iterdir() if p.suffix == ".h5"}
    assert 1 <= len(done) < len(ids), sorted(done)  # killed mid-batch
    # complete: increments of delta_max / CONTACT_STEPS up to the curve's last indentation,
    # delta_max or the energy reach when that is deeper (ci.yaml: contact.delta_mode energy)
    for name in done:
        c = read_curve(out / name)
        end = max(c.inputs["delta_max"], c.inputs.get("delta_reach") or 0.0)
        assert c.delta[-1] == pytest.approx(end, rel=1e-12), name
        assert c.force.size == int(np.ceil(end / c.inputs["delta_max"] * CONTACT_STEPS - 1e-9))
    rest = [p.name for p in out.iterdir() if p.suffix != ".h5"]
    assert all(n.startswith(".") and n.endswith(".part") for n in rest), rest
    if sig == signal.SIGTERM:
        assert rest == []
    subprocess.run(_batch_cmd(out, ids), env=env, check=True, capture_output=True,
                   timeout=300)
    assert sorted(p.name for p in out.glob("*.h5")) == sorted(f"{i}.h5" for i in ids)
    for name, force in done.items():
        np.testing.assert_array_equal(read_curve(out / name).force, force)


#: The tiny study's Set 1 fit and the two contact families it reads (three jobs).
SET1_FIT = ("results/fit/deviation_set1_materials.csv",
            "results/fit/sets/set1_materials/k_table.csv")


def _run_processes(work: Path, socket: str) -> list[str]:
    """The live processes of a run in ``work``: working folder in it (its jobs, the forks
    that run them), or naming its warm process's socket (the warm process's command line,
    its callers' environment)."""
    out = []
    for d in Path("/proc").iterdir():
        if not d.name.isdigit() or int(d.name) == os.getpid():
            continue
        try:
            cwd = os.readlink(d / "cwd")
            found = [(d / name).read_bytes() for name in ("cmdline", "environ")]
        except OSError:  # gone, or a zombie
            continue
        if cwd.startswith(str(work)) or any(socket.encode() in text for text in found):
            out.append(f"{d.name}: {found[0].replace(bytes(1), b' ')[:160]!r}")
    return out


def _forked_command_runs(pid: int) -> bool:
    """Whether the fork ``pid`` runs its command (``ssw.cli``'s SIGTERM handler set, the
    warm process's SIGCHLD handler gone: its ``SigCgt`` mask)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    mask = int(next(x for x in status.splitlines() if x.startswith("SigCgt:")).split()[1], 16)
    return bool(mask >> (signal.SIGTERM - 1) & 1) and not mask >> (signal.SIGCHLD - 1) & 1


def test_a_warm_process_killed_mid_study_leaves_no_process_and_the_rerun_agrees(
        tmp_path: Path, ci_study: Path) -> None:
    """The run's warm process SIGKILLed while it serves a job of the tiny study (Set 1's
    fit and its two contact families): the job's caller stops the command and fails with a
    message naming SSW_WARM_START=0, the run fails, no process of it is left, and the rerun
    (a new warm process) writes the same tables and curves as the uninterrupted tiny study
    (``ci_study``)."""
    config = ROOT / "config" / "ci.yaml"

    def cmd(work: Path) -> list[str]:
        return [str(VENV_BIN / "snakemake"), "--snakefile", str(ROOT / "workflow" / "Snakefile"),
                "--profile", str(PROFILE), "--cores", "2", "--configfile", str(config),
                "--directory", str(work), *SET1_FIT]

    ref, cut = ci_study, tmp_path / "cut"
    log = cut / "results" / "logs" / "warm-start.log"
    proc = subprocess.Popen(cmd(cut), cwd=ROOT, env=_env(), start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    end, served = time.monotonic() + 300, None
    while served is None:
        assert time.monotonic() < end and proc.poll() is None, "no job was served"
        lines = log.read_text().splitlines() if log.exists() else []
        running = [int(x.split()[1].rstrip(":")) for x in lines if x.startswith("pid ")]
        served = next((p for p in running if _forked_command_runs(p)), None)
        time.sleep(0.01)
    head = lines[0]  # "ssw warm start: pid N, ...; listening at SOCKET"
    warm, socket = int(head.split("pid ")[1].split(",")[0]), head.split("listening at ")[1]
    os.kill(warm, signal.SIGKILL)
    _, err = proc.communicate(timeout=600)
    assert proc.returncode != 0, err[-3000:]
    job_logs = "".join(p.read_text() for p in (cut / "results" / "logs").rglob("*.log"))
    assert "SSW_WARM_START=0" in job_logs, err[-3000:]
    # the run's last processes end as it does; one still there 10 s later was left behind
    left, end = _run_processes(cut, socket), time.monotonic() + 10.0
    while left and time.monotonic() < end:
        time.sleep(0.2)
        left = _run_processes(cut, socket)
    assert left == []
    rerun = subprocess.run(cmd(cut), cwd=ROOT, env=_env(), capture_output=True, text=True,
                           timeout=600)
    assert rerun.returncode == 0, rerun.stderr[-3000:]
    files = sorted(p.relative_to(cut) for p in (cut / "results").rglob("*")
                   if p.suffix in {".h5", ".csv"})
    assert len(files) >= 5 and all(n.parts[1] in ("contact", "fit") for n in files), files
    for name in files:
        if name.suffix == ".csv":
            assert (cut / name).read_text() == (ref / name).read_text(), name
            continue
        a, b = read_datasets(cut / name), read_datasets(ref / name)
        assert sorted(a) == sorted(b), name
        for key in a:
            assert np.array_equal(a[key], b[key], equal_nan=np.asarray(a[key]).dtype.kind == "f"), \
                f"{name}:{key}"
