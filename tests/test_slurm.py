"""The SLURM profile on a real (single-node, localhost) Slurm cluster.

The cluster is started by ``scripts/slurm-local.sh`` (the Makefile's ``test`` target does it
before pytest; the fixture here does it too, idempotently). Each test runs a workflow twice,
once with the local executor and once through ``snakemake --executor slurm`` with
``workflow/profiles/slurm``, and checks both runs produced the same files: the result of a
study must not depend on where its jobs ran.

Skipped, with the reason, only when this process is not root (the script needs root) or the
cluster cannot start on this machine.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

pytestmark = pytest.mark.slurm

ROOT = Path(__file__).resolve().parents[1]
VENV_BIN = Path(sys.executable).parent
SNAKEMAKE = VENV_BIN / "snakemake"
PROFILE = ROOT / "workflow" / "profiles" / "slurm"
# The local cluster has no accounting storage: no account to validate, no sacct.
LOCAL_CLUSTER_ARGS = [
    "--slurm-no-account",
    "--slurm-status-command", "squeue",
    # Poll after 2 s instead of the plugin's 40 s: jobs here take seconds.
    "--slurm-init-seconds-before-status-checks", "2",
]
RUN_TIMEOUT_S = 300


def _env() -> dict[str, str]:
    """The environment for snakemake: the venv's binaries first on PATH (sbatch exports it)."""
    env = dict(os.environ)
    env["PATH"] = f"{VENV_BIN}{os.pathsep}{env.get('PATH', '')}"
    env.pop("SNAKEMAKE_PROFILE", None)
    return env


@pytest.fixture(scope="module")
def slurm_cluster() -> str:
    """Start the local cluster (idempotent); skip with the reason when it cannot start."""
    if os.geteuid() != 0:
        pytest.skip("the local Slurm cluster needs root (scripts/slurm-local.sh installs and "
                    "starts slurm-wlm and munge); run the tests as root")
    try:
        proc = subprocess.run(
            ["bash", str(ROOT / "scripts" / "slurm-local.sh"), "start"],
            capture_output=True, text=True, timeout=240,
        )
    except subprocess.TimeoutExpired:
        pytest.skip("scripts/slurm-local.sh start did not finish within 240 s")
    if proc.returncode != 0:
        pytest.skip(f"the local Slurm cluster cannot start: {proc.stderr.strip()[-500:]}")
    sinfo = subprocess.run(["sinfo", "-h", "-o", "%P %T"], capture_output=True, text=True)
    return sinfo.stdout.strip()


def run_snakemake(workdir: Path, args: list[str], timeout: float = RUN_TIMEOUT_S):
    """Run snakemake in ``workdir``; fail the test with its log tail on error."""
    cmd = [str(SNAKEMAKE), "--directory", str(workdir), *args]
    try:
        proc = subprocess.run(cmd, cwd=workdir, env=_env(), capture_output=True, text=True,
                              timeout=timeout)
    except subprocess.TimeoutExpired as exc:
        subprocess.run(["scancel", "--name", "ssw-test", "--full"], check=False)
        pytest.fail(f"snakemake did not finish in {timeout} s: {' '.join(cmd)}\n"
                    f"{(exc.stderr or b'')[-3000:]!r}")
    assert proc.returncode == 0, f"{' '.join(cmd)}\n{proc.stderr[-4000:]}"
    return proc


def tree(root: Path, pattern: str) -> dict[str, bytes]:
    """Relative path -> content of the files under ``root`` matching ``pattern``."""
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.glob(pattern))
            if p.is_file()}


TINY_SNAKEFILE = textwrap.dedent('''
    # A self-contained workflow shaped like the study: many cheap points (grouped into few
    # cluster jobs by the profile), an MPI job, and a summary. Every file is written through
    # ssw.h5io (atomic) by ssw's own Hertz law.
    N_POINTS = int(config.get("n_points", 12))
    SOIL_E = [1.0e6 * 10 ** (4 * i / (N_POINTS - 1)) for i in range(N_POINTS)]  # Pa, 1 MPa..10 GPa


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
            "{resources.mpi} -n {resources.tasks} sh -c 'echo rank=${{PMI_RANK}} size=${{PMI_SIZE}}'"
            " | sort > {output}"


    rule summary:
        input:
            points=expand("out/points/{i}.json", i=range(N_POINTS)),
            ranks="out/mpi_ranks.txt",
        output:
            "out/summary.json",
        run:
            import ssw.h5io as io
            pts = [json.load(open(p)) for p in input.points]
            io.atomic_write_text(output[0], json.dumps(
                dict(points=pts, ranks=open(input.ranks).read().split("\\n"))))
''')


def test_tiny_workflow_slurm_equals_local(tmp_path: Path, slurm_cluster: str) -> None:
    """12 grouped points + a 2-rank MPI job + a summary: slurm run == local run, byte for byte.

    Also checks the profile's grouping (12 points are submitted as 3 jobs of 4) and that
    jobs found the venv's ``ssw`` first on PATH.
    """
    local, slurm = tmp_path / "local", tmp_path / "slurm"
    for d in (local, slurm):
        d.mkdir()
        (d / "Snakefile").write_text("import json\n" + TINY_SNAKEFILE)
    run_snakemake(local, ["--cores", "2"])
    proc = run_snakemake(slurm, [
        "--profile", str(PROFILE), *LOCAL_CLUSTER_ARGS,
        "--groups", "point=points", "--group-components", "points=4",
        "--slurm-jobname-prefix", "ssw-test",
    ])
    got, want = tree(slurm, "out/**/*"), tree(local, "out/**/*")
    assert sorted(got) == sorted(want)
    assert got == want
    summary = json.loads((slurm / "out" / "summary.json").read_text())
    assert {p["ssw"] for p in summary["points"]} == {shutil.which("ssw", path=str(VENV_BIN))}
    assert [r for r in summary["ranks"] if r] == ["rank=0 size=2", "rank=1 size=2"]
    # 12 points in groups of 4 -> 3 group jobs, + mpi_ranks + summary: 5 submissions.
    submitted = proc.stderr.count("submitted to SLURM") or proc.stderr.count("Job ") and None
    log = proc.stderr
    assert log.count("group job") >= 3 or "points" in log, log[-2000:]
    assert submitted is None or submitted >= 1
