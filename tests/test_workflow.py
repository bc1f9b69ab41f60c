"""The Snakemake workflow: lint, a dry run of the thesis study, refusals, a real tiny study."""

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import h5py

from ssw.config import all_scenes, load_config

ROOT = Path(__file__).resolve().parent.parent
SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))


def _env():
    """The environment of a user who has not activated .venv: its bin is NOT on PATH (the
    workflow must find `python -m ssw` through the interpreter that runs Snakemake)."""
    env = dict(os.environ)
    venv_bin = str(Path(sys.executable).parent)
    env["PATH"] = os.pathsep.join(p for p in env.get("PATH", "").split(os.pathsep)
                                  if p and p != venv_bin)
    env.pop("VIRTUAL_ENV", None)
    return env


def _smk(*args, cwd=ROOT, timeout=600):
    return subprocess.run([SNAKEMAKE, "-s", str(ROOT / "Snakefile"), *args], cwd=cwd,
                          capture_output=True, text=True, env=_env(), timeout=timeout)


def _job_stats(text):
    """Rule -> job count from Snakemake's 'Job stats' table."""
    table = text.split("Job stats:")[1]
    return {m.group(1): int(m.group(2))
            for m in re.finditer(r"^(\w+)\s+(\d+)\s*$", table, re.MULTILINE)}


def test_lint_is_clean():
    r = _smk("--lint", "--cores", "2")
    assert r.returncode == 0, r.stdout + r.stderr
    assert "Lints for" not in r.stdout + r.stderr


def test_dry_run_of_the_thesis_study(tmp_path):
    r = _smk("-n", "--cores", "2", "--directory", str(tmp_path),
             "--configfile", str(ROOT / "config" / "config.yaml"))
    assert r.returncode == 0, r.stdout + r.stderr
    stats = _job_stats(r.stdout)
    cfg = load_config(ROOT / "config" / "config.yaml")
    # every contact scene of every set is one contact job (thesis Table 1: Set 3 alone is
    # 100 soil moduli x 3 Poisson's ratios = 300 scenes)
    n_scenes = len(all_scenes(cfg))
    assert n_scenes >= 300
    # ... computed in batches of up to contact.jobs_per_group scenes, one job (and rule) each
    from ssw.contact.batch import batches
    n_batches = len(batches(cfg))
    assert {r: n for r, n in stats.items() if r.startswith("contact_batch_")} == {
        f"contact_batch_{b}": 1 for b in batches(cfg)} and n_batches < n_scenes / 20
    assert stats["all"] == 1
    assert stats["total"] > n_batches


def test_negative_thickness_is_refused_before_any_job(tmp_path):
    bad = tmp_path / "bad.yaml"
    text = (ROOT / "config" / "ci.yaml").read_text()
    bad.write_text(text.replace("plate_thickness: {values: [0.4e-3]}",
                                "plate_thickness: {values: [-0.4e-3]}", 1))
    assert bad.read_text() != text
    r = _smk("-n", "--cores", "2", "--directory", str(tmp_path), "--configfile", str(bad))
    assert r.returncode != 0
    assert "plate_thickness" in r.stdout + r.stderr
    assert not (tmp_path / "results" / "contact").exists()


def test_tiny_study_end_to_end(tmp_path):
    """The whole pipeline on config/ci.yaml: contact -> fit -> chain -> validation -> report."""
    shutil.copytree(ROOT / "config", tmp_path / "config")
    r = _smk("--cores", "2", "--directory", str(tmp_path), "--configfile",
             str(tmp_path / "config" / "ci.yaml"), timeout=900)
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-4000:]
    res = tmp_path / "results"
    cfg = load_config(tmp_path / "config" / "ci.yaml")
    for sid in all_scenes(cfg):
        with h5py.File(res / "contact" / f"{sid}.h5") as f:
            assert f.attrs["ssw_kind"] == "contact_curve"
            assert f["force"].attrs["units"] == "N"
    assert (res / "fit" / "k_table.h5").is_file()
    assert (res / "chain" / "tof_sweep.h5").is_file()
    assert (res / "report" / "report.html").is_file()
    assert not list(res.rglob("*.part")), "a temporary file was left behind"
    # a second run has nothing to do
    r2 = _smk("-n", "--cores", "2", "--directory", str(tmp_path), "--configfile",
              str(tmp_path / "config" / "ci.yaml"))
    assert "Nothing to be done" in r2.stdout + r2.stderr
