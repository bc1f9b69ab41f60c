"""`ssw bench study` measures what it claims: per-stage times from Snakemake's benchmark
records (results/benchmarks/<stage>/<job>.tsv).

A synthetic study with two stages whose jobs sleep known times is the truth: every job
lasts at least its sleep, a stage's busy time is at least the sum of its sleeps and no more
than ``cores x`` the total wall time, and every job is counted once.
"""

from __future__ import annotations

import argparse
import json
import textwrap
from pathlib import Path

import pytest

from ssw.bench import study

ALPHA = textwrap.dedent('''
    rule alpha:
        output:
            "results/alpha/{i}.txt",
        benchmark:
            "results/benchmarks/alpha/{i}.tsv"
        shell:
            "sleep 0.4; echo {wildcards.i} > {output}"
''')
BETA = textwrap.dedent('''
    rule beta:
        input:
            expand("results/alpha/{i}.txt", i=range(4)),
        output:
            a="results/beta/sum.txt",
            b="results/beta/copy.txt",
        log:
            "logs/beta.log",
        benchmark:
            "results/benchmarks/beta/sum.tsv"
        shell:
            "echo started > {log}; sleep 1.0; cat {input} > {output.a}; cp {output.a} {output.b}"
''')
SNAKEFILE = textwrap.dedent('''
    include: "workflow/rules/alpha.smk"
    include: "workflow/rules/beta.smk"


    rule all:
        input:
            "results/beta/sum.txt",
''')


@pytest.fixture
def toy_study(tmp_path: Path) -> Path:
    root = tmp_path / "toy"
    (root / "workflow" / "rules").mkdir(parents=True)
    (root / "workflow" / "rules" / "alpha.smk").write_text(ALPHA)
    (root / "workflow" / "rules" / "beta.smk").write_text(BETA)
    (root / "Snakefile").write_text(SNAKEFILE)
    (root / "config.yaml").write_text("study: toy\n")
    return root


def test_stage_times_bound_the_known_sleeps(toy_study: Path, tmp_path: Path) -> None:
    out = tmp_path / "bench"
    args = argparse.Namespace(
        config=str(toy_study / "config.yaml"), cores=2, snakefile=str(toy_study / "Snakefile"),
        profile=None, workdir=None, increment="none",
        keep=False, timeout=300.0, output_dir=str(out), keep_going=False)
    res = study.run(args)
    stages = res["stages"]
    assert set(stages) == {"alpha", "beta"}
    assert stages["alpha"]["jobs"] == 4 and stages["beta"]["jobs"] == 1  # 2 outputs, 1 job
    assert res["jobs"] == 5
    assert stages["alpha"]["busy_s"] >= 4 * 0.4
    assert all(t >= 0.4 for t in stages["alpha"]["busy_s_per_job"].values())
    assert stages["beta"]["busy_s"] >= 1.0
    # 4 alpha jobs on 2 cores, then beta: at least 2 layers of 0.4 s and 1 s
    assert res["wall_s"] >= 2 * 0.4 + 1.0
    for s in stages.values():
        assert s["busy_s"] <= 2 * res["wall_s"]
    saved = json.loads((out / "study.json").read_text())
    assert saved["stages"].keys() == stages.keys()
    assert "| alpha | 4 |" in (out / "study.md").read_text()
    assert res["increment"] is None


def test_refuses_a_nonempty_workdir(toy_study: Path, tmp_path: Path) -> None:
    from ssw.errors import ConfigError

    busy = tmp_path / "busy"
    busy.mkdir()
    (busy / "x").write_text("x")
    args = argparse.Namespace(
        config=str(toy_study / "config.yaml"), cores=2, snakefile=str(toy_study / "Snakefile"),
        profile=None, workdir=str(busy), increment="none",
        keep=False, timeout=60.0, output_dir=str(tmp_path / "bench"), keep_going=False)
    with pytest.raises(ConfigError, match="workdir"):
        study.run(args)


def test_a_failed_study_still_reports_the_finished_jobs(toy_study: Path, tmp_path: Path) -> None:
    """A failing stage: the command raises SswError, and study.json says failed and keeps
    the times of the jobs that finished."""
    from ssw.errors import SswError

    beta = toy_study / "workflow" / "rules" / "beta.smk"
    beta.write_text(beta.read_text().replace("sleep 1.0;", "exit 3;"))
    out = tmp_path / "bench"
    args = argparse.Namespace(
        config=str(toy_study / "config.yaml"), cores=2, snakefile=str(toy_study / "Snakefile"),
        profile=None, workdir=None, increment="none",
        keep=False, timeout=300.0, output_dir=str(out), keep_going=False)
    with pytest.raises(SswError, match="snakemake failed"):
        study.run(args)
    saved = json.loads((out / "study.json").read_text())
    assert saved["status"] == "failed"
    assert saved["stages"]["alpha"]["jobs"] == 4 and "beta" not in saved["stages"]
    assert "FAILED" in (out / "study.md").read_text()


def test_every_ssw_process_records_its_cpu_time(tmp_path: Path, monkeypatch) -> None:
    """With SSW_USAGE_DIR set, an ssw command leaves its CPU and wall times there, and the
    bench reads them back per job (a process without a job's log: keyed by its command)."""
    import time

    from ssw.cli import USAGE_ENV, main

    monkeypatch.setenv(USAGE_ENV, str(tmp_path / study.USAGE))
    t0 = time.time() - 1.0
    with pytest.raises(SystemExit):
        main(["tof", "--help"])
    rec = study.usage_records(tmp_path, t0)
    assert list(rec) == ["tof"]
    assert rec["tof"]["cpu_s"] > 0 and rec["tof"]["wall_s"] >= rec["tof"]["startup_s"] >= 0
    assert rec["tof"]["max_rss_mb"] > 0
    assert study.usage_records(tmp_path, time.time() + 10.0) == {}  # older records ignored
