"""The SLURM profile on a real (single-node, localhost) Slurm cluster.

The cluster is started by ``scripts/slurm-local.sh`` (the Makefile's ``test`` target does it
before pytest; the fixture here does it too, idempotently). The equality tests run a
workflow twice, once with the local executor and once through ``snakemake --executor slurm``
with ``workflow/profiles/slurm``, and check both runs produced the same results: a study's
result must not depend on where its jobs ran. The tiny study of ``config/ci.yaml`` runs by
default; a self-contained workflow with MPI jobs (2 ranks: the chain sweep over mpi4py, the
contact FEM over PETSc) is ``slow``. A Ctrl-C test checks that an interrupted run leaves no
job in the queue and no lock. The cluster keeps no accounting (no ``sacct``): the profile
alone must run there (the workflow's cluster check switches the status command to
``squeue``), and a run whose jobs vanish from Slurm must stop with a message
(ssw.cluster.LostJobsWatch).

Skipped, with the reason, only when this process is not root (the script needs root) or the
cluster cannot start on this machine, and never in CI: with ``CI=true`` in the environment
(``.ci/run``) either of those fails the tests instead, so a CI run cannot pass without them.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from ssw.h5io import read_datasets

pytestmark = pytest.mark.slurm

ROOT = Path(__file__).resolve().parents[1]
VENV_BIN = Path(sys.executable).parent
SNAKEMAKE = VENV_BIN / "snakemake"
PROFILE = ROOT / "workflow" / "profiles" / "slurm"
# Nothing about the missing accounting: the workflow's cluster check (ssw.cluster) finds it.
LOCAL_CLUSTER_ARGS = [
    # Poll 1 s after a submission instead of the profile's delay: jobs here take seconds.
    "--slurm-init-seconds-before-status-checks", "1",
]
# What the workflow's onstart does on Slurm (workflow/rules/common.smk), for the test
# workflows here: the status command the cluster needs, the job sizes, the lost-jobs watch.
CLUSTER_CHECK = f"""
import shlex
import sys
sys.path.insert(0, {str(ROOT)!r})
import ssw.workflow as sswwf
sswwf.quote_job_python()


onstart:
    if sswwf.submits_to_slurm(workflow):
        for note in sswwf.prepare_slurm_run(workflow):
            print(f"ssw cluster check: {{note}}", file=sys.stderr)
"""
NO_ACCOUNTING_NOTE = "this Slurm keeps no job accounting"
RUN_TIMEOUT_S = 300
#: s, the longest pause between two status queries of the runs here (ssw.cluster).
STATUS_PAUSE_S = 2.0
# The job names of this test process: another test run on the same machine (and its
# cancel_test_jobs) leaves them alone.
JOB_PREFIX = f"sswtest{os.getpid()}"


def _env() -> dict[str, str]:
    """The environment for snakemake: the venv's binaries first on PATH (sbatch exports it)."""
    env = dict(os.environ)
    env["PATH"] = f"{VENV_BIN}{os.pathsep}{env.get('PATH', '')}"
    env.pop("SNAKEMAKE_PROFILE", None)
    # A status query at most every STATUS_PAUSE_S (the default 30 s is for a real cluster's
    # minutes-long jobs; these take seconds).
    env["SSW_SLURM_STATUS_MAX_S"] = str(STATUS_PAUSE_S)
    return env


def in_ci() -> bool:
    """``CI=true`` in the environment (.ci/run; GitHub Actions and most CI services)."""
    return os.environ.get("CI", "").strip().lower() == "true"


def unavailable(reason: str) -> None:
    """Skip, naming the reason; under ``CI=true`` fail instead (no silent pass in CI)."""
    if in_ci():
        pytest.fail(f"CI=true and the local Slurm cluster is unavailable: {reason}",
                    pytrace=False)
    pytest.skip(reason)


@pytest.fixture(scope="module")
def slurm_cluster() -> str:
    """Start the local cluster (idempotent); skip with the reason when it cannot start
    (fail under ``CI=true``)."""
    if os.geteuid() != 0:
        unavailable("the local Slurm cluster needs root (scripts/slurm-local.sh installs and "
                    "starts slurm-wlm and munge); run the tests as root")
    try:
        proc = subprocess.run(
            ["bash", str(ROOT / "scripts" / "slurm-local.sh"), "start"],
            capture_output=True, text=True, timeout=240,
        )
    except subprocess.TimeoutExpired:
        unavailable("scripts/slurm-local.sh start did not finish within 240 s")
    if proc.returncode != 0:
        unavailable(f"the local Slurm cluster cannot start: {proc.stderr.strip()[-500:]}")
    sinfo = subprocess.run(["sinfo", "-h", "-o", "%P %T"], capture_output=True, text=True)
    state = sinfo.stdout.strip()
    if sinfo.returncode != 0 or not re.search(r"\b(idle|mix\w*|alloc\w*)\b", state):
        unavailable(f"sinfo shows no usable node after the start: {state!r} {sinfo.stderr!r}")
    return state


def test_ci_does_not_skip(monkeypatch) -> None:
    """Under CI=true an unavailable cluster fails the test run; elsewhere it skips."""
    monkeypatch.setenv("CI", "true")
    with pytest.raises(pytest.fail.Exception, match="CI=true"):
        unavailable("no cluster here")
    monkeypatch.setenv("CI", "false")
    with pytest.raises(pytest.skip.Exception, match="no cluster here"):
        unavailable("no cluster here")


def cancel_test_jobs() -> None:
    """scancel the jobs this module submitted (job names start with the test prefix)."""
    q = subprocess.run(["squeue", "-h", "-o", "%i %j"], capture_output=True, text=True)
    ids = [line.split()[0] for line in q.stdout.splitlines()
           if len(line.split()) == 2 and line.split()[1].startswith(JOB_PREFIX)]
    if ids:
        subprocess.run(["scancel", *ids], check=False)


def failure_summary(log: str) -> str:
    """The first failed rule's report in a Snakemake log (else its tail)."""
    i = log.find("Error in rule")
    return log[i:i + 2000] if i >= 0 else log[-3000:]


def run_snakemake(workdir: Path, args: list[str], timeout: float = RUN_TIMEOUT_S):
    """Run snakemake in ``workdir``; fail the test with its log tail on error."""
    cmd = [str(SNAKEMAKE), "--directory", str(workdir), *args]
    try:
        proc = subprocess.run(cmd, cwd=workdir, env=_env(), capture_output=True, text=True,
                              timeout=timeout)
    except subprocess.TimeoutExpired as exc:
        cancel_test_jobs()
        pytest.fail(f"snakemake did not finish in {timeout} s: {' '.join(cmd)}\n"
                    f"{(exc.stderr or b'')[-3000:]!r}")
    assert proc.returncode == 0, f"{' '.join(cmd)}\n{failure_summary(proc.stderr)}"
    return proc


def tree(root: Path, pattern: str) -> dict[str, bytes]:
    """Relative path -> content of the files under ``root`` matching ``pattern``."""
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.glob(pattern))
            if p.is_file()}


TINY_SNAKEFILE = textwrap.dedent('''
    # A self-contained workflow shaped like the study: many cheap points (grouped into few
    # cluster jobs by the profile), an MPI job, and a summary. Every file is written through
    # ssw.h5io (atomic) by ssw's own Hertz law.
    N_POINTS = int(config.get("n_points", 8))
    SOIL_E = [1.0e6 * 10 ** (4 * i / (N_POINTS - 1)) for i in range(N_POINTS)]  # Pa, 1 MPa..10 GPa


    localrules: all, summary


    rule all:
        input:
            "out/summary.json",


    rule point:
        output:
            "out/points/{i}.json",
        params:
            E=lambda wc: SOIL_E[int(wc.i)],
        resources:
            runtime=5,
            mem_mb=500,
        shell:
            """
            python -c "
    import json, shutil, ssw.hertz as h, ssw.h5io as io
    Es = h.effective_modulus({params.E}, 0.3)          # soil under a rigid sphere, Pa
    F = h.force(1e-6, Es, 9.525e-3)                    # N at 1 um
    io.atomic_write_text('{output}', json.dumps(dict(E={params.E!r}, F=float(F),
        ssw=shutil.which('ssw'))))
    "
            """


    rule mpi_ranks:
        output:
            "out/mpi_ranks.txt",
        resources:
            mpi="mpiexec",
            tasks=2,
            runtime=5,
            mem_mb=500,
        shell:
            "{resources.mpi} -n {resources.tasks}"
            " sh -c 'echo rank=${{PMI_RANK}} size=${{PMI_SIZE}}' | sort > {output}"


    SWEEP = (f"ssw tof-sweep --config {shlex.quote(config['study_config'])} --law hertz"
             " --soil-E-min 1e7 --soil-E-max 1e8 --soil-E-step 3e7 --soil-nu 0.3 0.5")


    rule sweep_serial:
        output:
            "out/sweep_serial.h5",
        shell:
            "{SWEEP} --output {output} > /dev/null"


    rule sweep_mpi:
        output:
            "out/sweep_mpi.h5",
        resources:
            mpi="mpiexec",
            tasks=2,
        shell:
            "{resources.mpi} -n {resources.tasks} {SWEEP} --mpi --output {output} > /dev/null"


    CONTACT = (f"ssw contact --config {shlex.quote(config['study_config'])} --soil-E 5e7"
               " --soil-nu 0.3 --plate-thickness 0 --steps 20")


    rule contact_serial:
        output:
            "out/contact_serial.h5",
        shell:
            "{CONTACT} --output {output} > /dev/null"


    rule contact_mpi:
        output:
            "out/contact_mpi.h5",
        resources:
            mpi="mpiexec",
            tasks=2,
        shell:
            "{resources.mpi} -n {resources.tasks} {CONTACT} --output {output} > /dev/null"


    rule summary:
        input:
            points=expand("out/points/{i}.json", i=range(N_POINTS)),
            ranks="out/mpi_ranks.txt",
            sweeps=["out/sweep_serial.h5", "out/sweep_mpi.h5"],
            contacts=["out/contact_serial.h5", "out/contact_mpi.h5"],
        output:
            "out/summary.json",
        run:
            import h5py
            import ssw.h5io as io
            pts = [json.load(open(p)) for p in input.points]
            tofs = [h5py.File(p, "r")["tof"][()].tolist() for p in input.sweeps]
            forces = [h5py.File(p, "r")["force"][()].tolist() for p in input.contacts]
            io.atomic_write_text(output[0], json.dumps(
                dict(points=pts, ranks=open(input.ranks).read().split("\\n"), tofs=tofs,
                     forces=forces)))
''')


@pytest.mark.slow
def test_tiny_workflow_slurm_equals_local(tmp_path: Path, slurm_cluster: str) -> None:
    """8 grouped points, 2-rank MPI jobs (a rank echo; the chain sweep over mpi4py ranks;
    the contact FEM over PETSc ranks) and a local summary: the SLURM run's files equal the
    local run's, and the MPI results equal the serial ones.

    Also checks grouping (8 points are submitted as 2 jobs of 4, each on 1 core, so they run
    side by side on the 2-CPU node), that the MPI job got 2 ranks, and that jobs found the
    venv's ``ssw`` first on PATH.
    """
    local, slurm = tmp_path / "local", tmp_path / "slurm"
    for d in (local, slurm):
        d.mkdir()
        (d / "Snakefile").write_text("import json\n" + CLUSTER_CHECK + TINY_SNAKEFILE)
    study = ["--config", f"study_config={ROOT / 'config' / 'ci.yaml'}"]
    run_snakemake(local, ["--cores", "2", *study])
    proc = run_snakemake(slurm, [
        "--profile", str(PROFILE), *LOCAL_CLUSTER_ARGS,
        "--groups", "point=points", "--group-components", "points=4", "--cores", "1",
        "--slurm-jobname-prefix", JOB_PREFIX, *study,
    ])
    assert assert_same_results(slurm / "out", local / "out") == 4
    got, want = tree(slurm, "out/**/*.json"), tree(local, "out/**/*.json")
    assert got == want and len(got) == 9
    summary = json.loads((slurm / "out" / "summary.json").read_text())
    assert {p["ssw"] for p in summary["points"]} == {shutil.which("ssw", path=str(VENV_BIN))}
    assert [r for r in summary["ranks"] if r] == ["rank=0 size=2", "rank=1 size=2"]
    # The chain sweep split over 2 MPI ranks inside a SLURM job equals the serial sweep.
    serial, mpi = summary["tofs"]
    assert len(serial) == 8 and np.isfinite(serial).all() and serial == mpi
    # The contact FEM on 2 PETSc ranks inside a SLURM job: the serial curve (the stage's own
    # MPI test uses the same 1e-9 tolerance: one LU factorization, gathered on every rank).
    f_serial, f_mpi = (np.asarray(f) for f in summary["forces"])
    assert f_serial.shape == (20,) and np.all(f_serial > 0)
    np.testing.assert_allclose(f_mpi, f_serial, rtol=1e-9, atol=0)
    # 8 points in groups of 4 -> 2 group jobs, + mpi_ranks + 2 sweeps + 2 contacts: 7 sbatch
    # calls (summary is a local rule).
    assert proc.stderr.count("has been submitted with SLURM jobid") == 7, proc.stderr[-3000:]




def assert_same_results(got: Path, want: Path, ignore: tuple[str, ...] = ()) -> int:
    """Same result files; HDF5 datasets and CSV tables identical (the provenance comment
    line of a CSV aside: it names the command). Returns the files compared.

    Logs, figures, JSON summaries and the HTML report carry run times, dates and paths, so
    they are compared by presence only; the numbers they show come from the HDF5/CSV files.
    Paths starting with one of ``ignore`` (logs, benchmarks, the operator cache) are not
    compared at all.
    """
    def files(root: Path) -> list[str]:
        return sorted(n for p in root.rglob("*") if p.is_file()
                      and not (n := str(p.relative_to(root))).startswith(ignore))

    names = files(want)
    assert names == files(got)
    compared = 0
    for name in names:
        a, b = got / name, want / name
        if name.endswith(".h5"):
            da, db = read_datasets(a), read_datasets(b)
            assert sorted(da) == sorted(db), name
            for key in da:
                x, y = np.asarray(da[key]), np.asarray(db[key])
                assert x.shape == y.shape, f"{name}:{key}"
                same = np.array_equal(x, y, equal_nan=x.dtype.kind == "f")
                assert same, f"{name}:{key} differs between the SLURM and the local run"
            compared += 1
        elif name.endswith(".csv"):
            def rows(p: Path) -> list[str]:
                return [x for x in p.read_text().splitlines() if not x.startswith("#")]

            assert rows(a) == rows(b), name
            compared += 1
    return compared


def _sbatch_calls(log: str) -> dict[str, str]:
    """Rule (and wildcards) -> its sbatch call, from a `snakemake --verbose` log of the Slurm
    executor ("sbatch call: sbatch --parsable --job-name ... --comment 'rule_<name>_wildcards_
    <w>' ...")."""
    out = {}
    for m in re.finditer(r"sbatch call: (sbatch [^\n]*)", log):
        call = m.group(1)
        c = re.search(r"--comment '?rule_(\w+?)(?:_wildcards_([^' ]+))?'?\s", call)
        if c:
            out[c.group(1) + (f"[{c.group(2)}]" if c.group(2) else "")] = call
    return out


def _run_study_on_slurm(workdir: Path, config: Path, timeout: float) -> str:
    """The study of ``config`` through the SLURM profile in ``workdir`` (the sweep under MPI
    on 2 ranks: ``--set-resources tof_sweep:tasks=2``, a runtime knob); its log."""
    proc = run_snakemake(workdir, [
        "--snakefile", str(ROOT / "workflow" / "Snakefile"), "--configfile", str(config),
        "--profile", str(PROFILE), *LOCAL_CLUSTER_ARGS, "--verbose",
        "--slurm-jobname-prefix", JOB_PREFIX,
        "--set-resources", "tof_sweep:tasks=2", "tof_sweep:mpi=mpiexec"], timeout=timeout)
    assert NO_ACCOUNTING_NOTE in proc.stderr  # the status command the cluster needs
    return proc.stderr + proc.stdout


def _assert_jobs_ask_for_what_they_use(log: str, config: Path) -> None:
    """Each job's sbatch asks for what it uses: one CPU per task (the rules' threads),
    --ntasks 2 for the MPI sweep, --mem and -t from the rules' resources
    (ssw.workflow.RESOURCES), scaled with a contact family's size (docs/cluster.md lists
    the calls); the light jobs run where Snakemake runs (localrules)."""
    from ssw.config import load_config
    from ssw.workflow import RESOURCES, families, mem_mb, runtime_min

    calls = _sbatch_calls(log)
    fams = families(load_config(config))
    for fam, ids in fams.items():
        call = calls[f"contact_batch[{fam}]"]
        assert f"--mem {mem_mb('contact', len(ids))}" in call, call
        assert f"-t {runtime_min('contact', len(ids))}" in call, call
        assert "--ntasks=1" in call and "--cpus-per-task=1" in call, call
    sweep = next(c for k, c in calls.items() if k.startswith("tof_sweep"))
    assert "--ntasks=2" in sweep and "--cpus-per-task=1" in sweep, sweep
    for rule in ("calibration", "validation"):
        assert f"--mem {mem_mb(rule, 0)}" in calls[rule] and "--ntasks=1" in calls[rule]
    assert set(RESOURCES) >= {"contact", "calibration", "sweep", "validation"}
    assert not any(k.startswith(("sweep_figure", "report_tables", "all")) for k in calls)


@pytest.mark.long
def test_ci_study_slurm_equals_local(tmp_path: Path, slurm_cluster: str,
                                    request: pytest.FixtureRequest) -> None:
    """The whole CI study (config/ci.yaml: contact -> fits -> the fem wall -> calibration ->
    the sweep under MPI on 2 ranks -> Tables 2-3 -> survey) through the SLURM profile
    finishes, and its tables and result files equal the local run's (the suite's
    ``ci_study``, ``--cores 2``), bit for bit; each job asked Slurm for what it uses.
    (The thesis study's run, 300 scenes more, is test_thesis_study_slurm_equals_local,
    ``slow``: the same checks at the study's size.) The local run is asked for once the
    Slurm run is done: under pytest-xdist another worker computes it meanwhile, instead of
    waiting for this one to."""
    config = ROOT / "config" / "ci.yaml"
    log = _run_study_on_slurm(tmp_path, config, timeout=900)
    ci_study = request.getfixturevalue("ci_study")
    n = assert_same_results(tmp_path / "results", ci_study / "results",
                            ignore=("benchmarks/", "logs/", "cache/"))
    assert n >= 20, f"only {n} result files compared"
    _assert_jobs_ask_for_what_they_use(log, config)


@pytest.mark.slow
def test_thesis_study_slurm_equals_local(tmp_path: Path, slurm_cluster: str) -> None:
    """The whole thesis study (config/config.yaml) through the SLURM profile finishes, and
    its tables and result files equal a local run's, bit for bit, each job asking for what
    it uses. ``slow``: test_ci_study_slurm_equals_local makes the same checks on the CI
    study; this one adds the thesis study's size (302 scenes in one contact family)."""
    config = ROOT / "config" / "config.yaml"
    local, slurm = tmp_path / "local", tmp_path / "slurm"
    for d in (local, slurm):
        d.mkdir()
    run_snakemake(local, ["--snakefile", str(ROOT / "workflow" / "Snakefile"),
                          "--configfile", str(config), "--cores", "2"], timeout=600)
    log = _run_study_on_slurm(slurm, config, timeout=900)
    n = assert_same_results(slurm / "results", local / "results",
                            ignore=("benchmarks/", "logs/", "cache/"))
    assert n >= 20, f"only {n} result files compared"
    _assert_jobs_ask_for_what_they_use(log, config)


def test_a_job_larger_than_any_node_is_an_error_not_a_wait(tmp_path: Path,
                                                          slurm_cluster: str) -> None:
    """A rule asking for more memory than the largest node has stops the run before any
    submission, naming the rule, the resource and the node's size."""
    proc = subprocess.run(
        [str(SNAKEMAKE), "--directory", str(tmp_path), "--snakefile",
         str(ROOT / "workflow" / "Snakefile"), "--configfile",
         str(ROOT / "config" / "ci.yaml"), "--profile", str(PROFILE), *LOCAL_CLUSTER_ARGS,
         "--slurm-jobname-prefix", JOB_PREFIX,
         "--set-resources", "calibration:mem_mb=99000000"],
        cwd=tmp_path, env=_env(), capture_output=True, text=True, timeout=120)
    log = proc.stdout + proc.stderr
    assert proc.returncode != 0, log[-2000:]
    assert "rule calibration asks for mem_mb=99000000" in log, log[-3000:]
    assert "the largest node has" in log
    assert "submitted with SLURM jobid" not in log
    assert _test_jobs() == []


SLOW_SNAKEFILE = textwrap.dedent('''
    rule all:
        input:
            expand("out/{i}.txt", i=range(3)),


    rule slow:
        output:
            "out/{i}.txt",
        shell:
            "sleep 120; touch {output}"
''')


def _test_jobs() -> list[str]:
    q = subprocess.run(["squeue", "-h", "-o", "%j %T"], capture_output=True, text=True)
    return [line for line in q.stdout.splitlines() if line.startswith(JOB_PREFIX)]


def _test_jobs_after_cancel(timeout_s: float) -> list[str]:
    """This module's jobs still queued once the ones cancelled have left.

    A cancelled job passes through COMPLETING while slurmd kills its steps, which takes
    seconds on a loaded node; a job that was never cancelled stays PENDING or RUNNING.
    Polls until the queue holds none of them or ``timeout_s`` (s) passes, and returns
    what is left then (read before any clean-up cancels them)."""
    deadline = time.monotonic() + timeout_s
    jobs = _test_jobs()
    while jobs and time.monotonic() < deadline:
        time.sleep(0.5)
        jobs = _test_jobs()
    return jobs


def test_ctrl_c_cancels_the_slurm_jobs(tmp_path: Path, slurm_cluster: str) -> None:
    """Ctrl-C (SIGINT) on a Snakemake run with the SLURM profile, while one job runs and
    others wait in the queue: every submitted job leaves the queue, no output appears, and
    the lock is released so the same command can run again (docs/cluster.md section 4)."""
    (tmp_path / "Snakefile").write_text(CLUSTER_CHECK + SLOW_SNAKEFILE)
    cmd = [str(SNAKEMAKE), "--directory", str(tmp_path), "--profile", str(PROFILE),
           *LOCAL_CLUSTER_ARGS, "--cores", "1", "--slurm-jobname-prefix", JOB_PREFIX]
    proc = subprocess.Popen(cmd, cwd=tmp_path, env=_env(), start_new_session=True,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline:
            jobs = _test_jobs()
            if len(jobs) == 3 and any("RUNNING" in j for j in jobs):
                break
            assert proc.poll() is None, proc.communicate()[0][-3000:]
            time.sleep(0.5)
        else:
            pytest.fail(f"the 3 jobs were not submitted and started within 90 s: {jobs}")
        os.killpg(proc.pid, signal.SIGINT)
        log = proc.communicate(timeout=120)[0]
        left = _test_jobs_after_cancel(timeout_s=60.0)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        cancel_test_jobs()
    assert proc.returncode != 0
    assert left == [], log[-2000:]
    assert "Terminating processes on user request" in log, log[-2000:]
    assert not list((tmp_path / "out").glob("*.txt")) if (tmp_path / "out").exists() else True
    locks = tmp_path / ".snakemake" / "locks"
    assert not locks.exists() or not any(locks.iterdir()), "the lock was not released"


def _rename_test_jobs(new_name: str) -> list[str]:
    """Give this module's queued/running jobs another SLURM job name: the executor plugin
    (and the workflow's watch) query a run's jobs by its name, so to the run they vanish
    as if slurmctld had forgotten them. Returns the job ids."""
    q = subprocess.run(["squeue", "-h", "-o", "%i %j"], capture_output=True, text=True)
    ids = [line.split()[0] for line in q.stdout.splitlines()
           if len(line.split()) == 2 and line.split()[1].startswith(f"{JOB_PREFIX}_")]
    for jid in ids:
        subprocess.run(["scontrol", "update", f"jobid={jid}", f"jobname={new_name}"],
                       check=True, capture_output=True)
    return ids


# long: 15-20 s of waiting on the cluster; the watch's rule (lost after the grace, not
# before; one call back) is checked in the default run by tests/test_cluster.py
# (test_vanished_jobs_are_lost_after_the_grace_not_before,
# test_the_watch_thread_calls_back_once_and_ends)
@pytest.mark.long
def test_jobs_that_vanish_from_slurm_stop_the_run_with_a_message(tmp_path: Path,
                                                                 slurm_cluster: str) -> None:
    """The executor plugin takes a job its status query does not list as still queued, and
    would wait for it forever. Once every job of the run has vanished from Slurm, the
    workflow's watch (ssw.cluster.LostJobsWatch) stops the run with a message naming the
    jobs: within the grace and a poll, and Snakemake exits soon after. The grace and the
    poll are the environment's (``SSW_SLURM_VANISH_GRACE_S``, ``SSW_SLURM_WATCH_POLL_S``:
    ``ssw.cluster.slurm_timing``), shorter than the defaults (60 s, 15 s) so that the test
    does not idle a worker for two minutes; tests/test_cluster.py checks the defaults."""
    grace_s, poll_s = 12.0, 3.0
    (tmp_path / "Snakefile").write_text(CLUSTER_CHECK + SLOW_SNAKEFILE)
    cmd = [str(SNAKEMAKE), "--directory", str(tmp_path), "--profile", str(PROFILE),
           *LOCAL_CLUSTER_ARGS, "--slurm-jobname-prefix", JOB_PREFIX]
    env = {**_env(), "SSW_SLURM_VANISH_GRACE_S": str(grace_s),
           "SSW_SLURM_WATCH_POLL_S": str(poll_s)}
    log_path = tmp_path / "snakemake.log"
    with open(log_path, "w") as log:
        proc = subprocess.Popen(cmd, cwd=tmp_path, env=env, stdout=log,
                                stderr=subprocess.STDOUT, text=True)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and len(_test_jobs()) < 3:
            assert proc.poll() is None, log_path.read_text()[-3000:]
            time.sleep(0.5)
        assert len(_test_jobs()) == 3, f"3 jobs not submitted within 120 s: {_test_jobs()}"
        gone = _rename_test_jobs(f"{JOB_PREFIX}-renamed")
        t0 = time.monotonic()
        message_s = None
        while proc.poll() is None and time.monotonic() - t0 < 300:
            if message_s is None and "Lost cluster jobs" in log_path.read_text():
                message_s = time.monotonic() - t0
            time.sleep(0.5)
        exit_s = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
        cancel_test_jobs()
    text = log_path.read_text()
    assert proc.returncode not in (None, 0), text[-3000:]
    assert len(gone) == 3
    assert "Slurm lists no job of this run any more" in text, text[-3000:]
    assert "waits for 3 cluster job(s): slow[i=0], slow[i=1], slow[i=2]" in text
    message_s = exit_s if message_s is None else message_s
    assert message_s >= grace_s, (message_s, text[-2000:])
    assert message_s <= grace_s + 2 * poll_s + 15, (message_s, text[-2000:])
    # Snakemake exits after the current pause between status queries (at most
    # STATUS_PAUSE_S) and its own shutdown
    assert exit_s <= message_s + STATUS_PAUSE_S + 15, (exit_s, message_s)
    print(f"vanished jobs: message after {message_s:.0f} s, exit after {exit_s:.0f} s")


HELD_SNAKEFILE = textwrap.dedent('''
    rule all:
        input:
            "out/held.txt",


    rule held:
        output:
            "out/held.txt",
        resources:
            slurm_extra="'--hold'",
        shell:
            "touch {output}"
''')


def _run_held(tmp_path: Path, resources: list[str], marker: str, reports: int,
              poll_s: float, timeout_s: float = 150) -> tuple[str, list[float], bool, int]:
    """Run HELD_SNAKEFILE through the profile (its one job submitted held: Slurm keeps it
    pending, squeue's reason JobHeldUser), with ``--set-resources`` ``resources``, until
    ``marker`` is in the log ``reports`` times: the log, the seconds from the job's first
    sight in squeue to each of those reports, whether Snakemake was still running after the
    last (then it is stopped with SIGINT), and its exit status."""
    (tmp_path / "Snakefile").write_text(CLUSTER_CHECK + HELD_SNAKEFILE)
    cmd = [str(SNAKEMAKE), "--directory", str(tmp_path), "--profile", str(PROFILE),
           *LOCAL_CLUSTER_ARGS, "--slurm-jobname-prefix", JOB_PREFIX,
           "--set-resources", *resources]
    env = {**_env(), "SSW_SLURM_WATCH_POLL_S": str(poll_s)}
    log_path = tmp_path / "snakemake.log"
    with open(log_path, "w") as log:
        proc = subprocess.Popen(cmd, cwd=tmp_path, env=env, stdout=log,
                                stderr=subprocess.STDOUT, text=True)
    seen: list[float] = []
    running = False
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and not _test_jobs():
            assert proc.poll() is None, log_path.read_text()[-3000:]
            time.sleep(0.5)
        assert _test_jobs(), f"the held job was not submitted within 120 s: {_test_jobs()}"
        t0 = time.monotonic()
        while len(seen) < reports and time.monotonic() - t0 < timeout_s:
            if log_path.read_text().count(marker) > len(seen):
                seen.append(time.monotonic() - t0)
            elif proc.poll() is not None:
                break
            time.sleep(0.5)
        running = proc.poll() is None
        if running and "pending beyond their limit" in log_path.read_text():
            proc.wait(timeout=60)  # stopped: Snakemake ends after its current pause
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(timeout=60)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        cancel_test_jobs()
    return log_path.read_text(), seen, running, proc.returncode


# long: 15-20 s of waiting on a held job; the pending rule is checked in the default run by
# tests/test_cluster.py (test_a_job_pending_beyond_its_limit_stops_the_run_with_squeues_reason,
# test_the_watch_thread_stops_a_run_whose_job_pends_beyond_its_limit)
@pytest.mark.long
def test_a_job_that_pends_beyond_its_limit_stops_the_run_with_squeues_reason(
        tmp_path: Path, slurm_cluster: str) -> None:
    """A job Slurm never starts (held) stops the run once it has pended its limit (the job
    resource ssw_pending_s, here 8 s for the rule; the profile's own is an hour), with a
    message naming the job and squeue's reason for it: within the limit and two looks of
    the watch (SSW_SLURM_WATCH_POLL_S, here 2 s)."""
    limit_s, poll_s = 8.0, 2.0
    text, seen, _, status = _run_held(tmp_path, [f"held:ssw_pending_s={limit_s:g}"],
                                      "pending beyond their limit", 1, poll_s)
    assert seen, text[-3000:]
    assert status != 0, text[-3000:]
    assert "Cluster jobs pending beyond their limit: 1 job(s): held (Slurm job" in text
    assert "squeue's reason: JobHeldUser" in text and f"limit {limit_s:g} s" in text
    assert limit_s - poll_s - 1 <= seen[0] <= limit_s + 2 * poll_s + 15, (seen, text[-2000:])
    print(f"held job: the run stopped {seen[0]:.0f} s after it was queued "
          f"(limit {limit_s:g} s)")


# long: 15-20 s of waiting on a held job; the waiting rule is checked in the default run by
# tests/test_cluster.py (test_a_waiting_run_reports_a_pending_job_once_per_limit,
# test_the_watch_thread_reports_a_pending_job_and_waits)
@pytest.mark.long
def test_a_run_told_to_wait_reports_a_pending_job_and_keeps_waiting(
        tmp_path: Path, slurm_cluster: str) -> None:
    """The same held job with ssw_on_pending=wait: the run reports it with squeue's reason
    after its limit, again after a further limit, and goes on waiting (then it is
    interrupted and the job cancelled)."""
    limit_s, poll_s = 6.0, 2.0
    text, seen, running, _ = _run_held(
        tmp_path, [f"held:ssw_pending_s={limit_s:g}", "held:ssw_on_pending=wait"],
        "The run waits for them", 2, poll_s)
    assert len(seen) == 2 and running, (seen, running, text[-3000:])
    assert "ssw cluster check: 1 cluster job(s) pend beyond their limit: held" in text
    assert "squeue's reason: JobHeldUser" in text and "Cluster jobs pending" not in text
    assert limit_s - poll_s - 1 <= seen[0] <= limit_s + 2 * poll_s + 15, (seen, text[-2000:])
    assert limit_s - poll_s <= seen[1] - seen[0] <= limit_s + 2 * poll_s + 5, seen


@pytest.mark.slow
def test_the_profile_alone_runs_a_study_on_a_cluster_without_accounting(
        tmp_path: Path, slurm_cluster: str) -> None:
    """`snakemake --profile workflow/profiles/slurm` and nothing else about the cluster
    (no --slurm-status-command, no --slurm-no-account; the job-name prefix only lets the
    test clean up) runs the CI study on this cluster without accounting: the workflow's
    check switches the status command to squeue and says so. (The environment holds the
    status queries 2 s apart at most, as for every run here: ``_env``.)"""
    start = time.monotonic()
    proc = run_snakemake(tmp_path, [
        "--snakefile", str(ROOT / "workflow" / "Snakefile"), "--configfile",
        str(ROOT / "config" / "ci.yaml"), "--profile", str(PROFILE),
        "--slurm-jobname-prefix", JOB_PREFIX], timeout=900)
    log = proc.stdout + proc.stderr
    assert NO_ACCOUNTING_NOTE in log and "--slurm-status-command squeue" in log
    assert (tmp_path / "results" / "validation" / "validation.csv").is_file()
    assert (tmp_path / "results" / "survey" / "survey.geojson").is_file()
    print(f"the CI study through the profile alone: {time.monotonic() - start:.0f} s")
