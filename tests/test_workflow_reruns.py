"""Results that follow their inputs: after a whole study (config/ci.yaml), an edit of the
config, the device file or the materials library reruns exactly the jobs that read what
changed (Snakemake's params trigger on each job's slice of the study, ssw.workflow.Study),
a dry run shows them, and neither a dry run nor a lint writes anything.

Edits are made in copies (the config points at a copied device file or materials library);
a copy identical to the shipped one changes nothing: the jobs compare values, not file
names.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest
from snakemake_run import ROOT, job_stats, smk

pytestmark = pytest.mark.usefixtures("ci_study")

CONTACT, CHAIN = {"contact_batch"}, {"calibration", "tof_sweep", "validation"}


def _dry(study: Path, config: Path) -> dict[str, int]:
    r = smk("-n", "--cores", "2", "--directory", str(study), "--configfile", str(config))
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    return job_stats(r.stdout)


def _config(study: Path, tmp: Path, replace: tuple[str, str] = ("", ""),
            device: str | None = None, materials: str | None = None) -> Path:
    """A copy of the study's config with one text replacement and, optionally, its device
    and materials library pointing at copies."""
    text = (study / "config" / "ci.yaml").read_text()
    if replace[0]:
        assert replace[0] in text, replace
        text = text.replace(replace[0], replace[1], 1)
    if device is not None:
        text = text.replace("device: thesis", f"device: {device}", 1)
    if materials is not None:
        text += f"\nmaterials_file: {materials}\n"
    out = tmp / "edited.yaml"
    out.write_text(text)
    return out


def test_no_edit_reruns_nothing_and_identical_copies_change_nothing(ci_study, tmp_path):
    """The study's own config: nothing to do; a config naming identical copies of the
    device and the materials library: nothing to do either (values, not names)."""
    assert _dry(ci_study, ci_study / "config" / "ci.yaml") == {}
    dev = tmp_path / "device.yaml"
    shutil.copy(ROOT / "config" / "devices" / "thesis.yaml", dev)
    mats = tmp_path / "materials.yaml"
    shutil.copy(ROOT / "config" / "materials.yaml", mats)
    assert _dry(ci_study, _config(ci_study, tmp_path, device=str(dev),
                                  materials=str(mats))) == {}


def test_contact_steps_edit_reruns_contact_and_what_follows_only(ci_study, tmp_path):
    """contact.steps shapes every curve: every family's contact job and the fits rerun;
    the chain (the fem wall tabulates its own law) and the validation do not."""
    stats = _dry(ci_study, _config(ci_study, tmp_path, ("steps: 100", "steps: 120")))
    assert stats["contact_batch"] == 2  # ci.yaml's two plate families
    assert stats.get("fit_set", 0) + stats.get("fit_grid", 0) == 2
    assert not CHAIN & set(stats) and "survey_point" not in stats


def test_device_bead_count_edit_reruns_the_chain_not_the_contact(ci_study, tmp_path):
    """The device's bead count: the calibration, the sweep, the validation and the survey
    rerun (and the fits, whose range is the chain's reach: ci.yaml's fit.range.mode chain);
    no contact job (the curves reach the energy bound of contact.delta_mode energy)."""
    dev = tmp_path / "device.yaml"
    dev.write_text((ROOT / "config" / "devices" / "thesis.yaml").read_text().replace(
        "beads: 20", "beads: 22"))
    stats = _dry(ci_study, _config(ci_study, tmp_path, device=str(dev)))
    assert CHAIN <= set(stats), stats
    assert stats["survey_point"] == 3
    assert "contact_batch" not in stats


def test_plate_modulus_edit_reruns_that_plates_scenes(ci_study, tmp_path):
    """PLA's modulus in the materials library: the PLA family's contact job reruns, the
    aluminium family's does not; the chain (its plate is PLA) reruns."""
    mats = tmp_path / "materials.yaml"
    text = (ROOT / "config" / "materials.yaml").read_text()
    assert "    E: 3.5e+9\n" in text
    mats.write_text(text.replace("    E: 3.5e+9\n", "    E: 3.6e+9\n", 1))
    r = smk("-n", "--cores", "2", "--directory", str(ci_study), "--configfile",
            str(_config(ci_study, tmp_path, materials=str(mats))))
    assert r.returncode == 0, r.stderr[-3000:]
    stats = job_stats(r.stdout)
    assert stats["contact_batch"] == 1 and "family=pla-t400um" in r.stdout
    assert "family=al6061-t400um" not in r.stdout
    assert CHAIN <= set(stats)


def test_dry_run_and_lint_write_nothing(ci_study, tmp_path):
    """A dry run and a lint of an edited config leave the study's resolved config (and
    every other file) as it was."""
    cfg = _config(ci_study, tmp_path, ("steps: 100", "steps: 130"))
    # the validations remembered by the jobs (ssw.schema) go: parsing must not write its own
    shutil.rmtree(ci_study / "results" / "cache" / "schema", ignore_errors=True)
    before = {p: (p.stat().st_mtime_ns, p.stat().st_size)
              for p in (ci_study / "results").rglob("*") if p.is_file()}
    assert _dry(ci_study, cfg)
    r = smk("--lint", "--directory", str(ci_study), "--configfile", str(cfg))
    assert r.returncode == 0, r.stderr[-2000:]
    after = {p: (p.stat().st_mtime_ns, p.stat().st_size)
             for p in (ci_study / "results").rglob("*") if p.is_file()}
    assert after == before


def test_an_edit_reruns_what_the_dry_run_said_and_then_nothing(ci_study, tmp_path):
    """A real rerun after a plate edit (in a copy of the study) runs the jobs the dry run
    listed, rewrites the resolved config, and leaves nothing to do."""
    study = tmp_path / "study"
    shutil.copytree(ci_study, study, symlinks=True)
    mats = tmp_path / "materials.yaml"
    mats.write_text((ROOT / "config" / "materials.yaml").read_text().replace(
        "    E: 68.9e+9\n", "    E: 70.0e+9\n", 1))  # aluminium: Set 1's other plate
    cfg = _config(study, tmp_path, materials=str(mats))
    planned = _dry(study, cfg)
    assert planned.get("contact_batch") == 1 and not CHAIN & set(planned), planned
    r = smk("--cores", "2", "--directory", str(study), "--configfile", str(cfg), timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    ran = job_stats(r.stdout + r.stderr)
    assert ran == planned
    assert str(mats) in (study / "results" / "study_config.yaml").read_text()
    assert _dry(study, cfg) == {}


def test_runtime_knobs_do_not_change_the_results(ci_study, tmp_path):
    """How a study runs is not what it computes: the sweep in three jobs instead of one
    (`--set-scatter sweep=3`) gives the same sweep and the same Tables 2 and 3, to the bit."""
    study = tmp_path / "study"
    shutil.copytree(ci_study, study, symlinks=True)
    cfg = study / "config" / "ci.yaml"
    r = smk("--cores", "2", "--directory", str(study), "--configfile", str(cfg),
            "--set-scatter", "sweep=3", timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    ran = job_stats(r.stdout + r.stderr)
    assert ran["tof_sweep"] == 3 and "contact_batch" not in ran and "calibration" not in ran

    def rows(path: Path) -> list[str]:
        return [x for x in path.read_text().splitlines() if not x.startswith("#")]

    for name in ("chain/tof_sweep.csv", "validation/table2_tof.csv",
                 "validation/table3_modulus.csv", "validation/validation.csv"):
        assert rows(study / "results" / name) == rows(ci_study / "results" / name), name


def test_slurm_profile_dry_run_shows_each_jobs_resources(tmp_path):
    """The SLURM profile's dry run of the thesis study (no cluster needed): every job
    declares what it uses, a contact job's memory and time scaled with its family's size."""
    from ssw.config import load_config
    from ssw.workflow import families, mem_mb, runtime_min

    r = smk("-n", "--profile", str(ROOT / "workflow" / "profiles" / "slurm"),
            "--directory", str(tmp_path), "--configfile", str(ROOT / "config" / "config.yaml"))
    assert r.returncode == 0, r.stderr[-3000:]
    fams = families(load_config(ROOT / "config" / "config.yaml"))
    blocks = r.stdout.split("\nrule ")
    for fam, ids in fams.items():
        block = next(b for b in blocks if b.startswith("contact_batch:")
                     and f"family={fam}\n" in b)
        assert re.search(rf"\bmem_mb={mem_mb('contact', len(ids))}\b", block), block
        assert re.search(rf"\bruntime={runtime_min('contact', len(ids))}\b", block), block
    sweep = next(b for b in blocks if b.startswith("tof_sweep:"))
    assert "tasks=1" in sweep and f"mem_mb={mem_mb('sweep', 0)}" in sweep
    assert not (tmp_path / "results").exists()


def test_a_new_plate_thickness_runs_only_its_family_and_its_set(ci_study, tmp_path):
    """One more thickness in Set 1 (0.6 mm): the new families' contact jobs (PLA and
    aluminium at 0.6 mm) and Set 1's fit; no other family, no other set, no chain job."""
    stats = _dry(ci_study, _config(ci_study, tmp_path, (
        "plate_thickness: {values: [0.4e-3]}", "plate_thickness: {values: [0.4e-3, 0.6e-3]}")))
    assert stats["contact_batch"] == 2 and stats["fit_set"] == 1, stats
    assert "fit_grid" not in stats and not CHAIN & set(stats), stats


def test_every_result_records_its_provenance(ci_study):
    """HDF5 attributes, JSON and a CSV's first line record the ssw version, the commit, the
    digest of the job's study inputs (the one Snakemake compares) and the command."""
    import json

    import h5py

    from ssw.config import load_config
    from ssw.h5io import csv_provenance, provenance_of
    from ssw.workflow import Study, contact_file

    cfg = load_config(ci_study / "config" / "ci.yaml")
    study = Study(cfg)
    sid = study.families["pla-t400um"][0]
    with h5py.File(ci_study / contact_file(sid)) as f:
        prov = provenance_of(f)
    assert prov["inputs_sha256"] == study.digest("contact", "pla-t400um")
    assert "contact --family pla-t400um" in prov["command"] and prov["ssw_version"]
    val = json.loads((ci_study / "results" / "validation" / "validation.json").read_text())
    assert val["provenance"]["inputs_sha256"] == study.digest("validation")
    assert val["provenance"]["source_sha256"]
    csv = csv_provenance(ci_study / "results" / "validation" / "table3_modulus.csv")
    assert csv["inputs_sha256"] == study.digest("validation") and "validate" in csv["command"]
    fit = json.loads((ci_study / "results" / "fit" / "sets" / "set3_soil" /
                      "k_table.json").read_text())
    assert fit["provenance"]["inputs_sha256"] == study.digest("fit", "set3_soil")
