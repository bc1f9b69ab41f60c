"""The Snakemake workflow: lint, a dry run of the thesis study, refusals, a real tiny study."""

import subprocess
import sys
from pathlib import Path

import h5py
import pytest
from snakemake_run import ROOT, job_stats, smk, user_env

from ssw.config import all_scenes, load_config

_env, _smk, _job_stats = user_env, smk, job_stats


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
    # every contact scene of every set (thesis Table 1: Set 3 alone is 100 soil moduli x 3
    # Poisson's ratios = 300 scenes) is computed by the one job of its plate family (rule
    # contact_batch: seven families of plate material and thickness)
    from ssw.workflow import families

    n_scenes = len(all_scenes(cfg))
    assert n_scenes >= 300
    assert stats["contact_batch"] == len(families(cfg)) == 7
    assert stats["fit_set"] == 2 and stats["fit_grid"] == 1  # Sets 1, 2 and Set 3
    assert stats["tof_sweep"] == 1 and stats["all"] == 1
    # a dry run writes nothing (the resolved config is written when a run starts)
    assert not (tmp_path / "results").exists()


def test_the_end_of_a_run_cancels_the_timers_that_would_hold_its_exit():
    """A non-daemon ``threading.Timer`` (what Snakemake's scheduler arms each round) keeps
    the interpreter alive until it fires; ``end_of_run`` (the workflow's onsuccess and
    onerror) cancels it: the thread ends at once, and its function never runs."""
    import threading
    import time

    from ssw.workflow import end_of_run

    fired = []
    timer = threading.Timer(60.0, lambda: fired.append(1))
    timer.start()
    t0 = time.monotonic()
    assert end_of_run() >= 1
    timer.join(5.0)
    assert not timer.is_alive() and time.monotonic() - t0 < 5.0 and not fired


@pytest.mark.parametrize(("old", "new", "shown"), [
    ("plate_thickness: {values: [0.4e-3]}", "plate_thickness: {values: [-0.4e-3]}",
     "plate_thickness"),
    # the workflow validates with ssw's own validator: NaN passes JSON Schema's bounds
    ("soil_nu: {values: [0.3]}", "soil_nu: {values: [0.3, .nan]}",
     "sets.set1_materials.soil_nu.values.1 = nan"),
    # a name that would run as a command in a shell, or be read as a flag
    ("    - {id: P1,", "    - {id: 'P1;touch pwned',", "survey.points.0.id = 'P1;touch pwned'"),
])
def test_bad_inputs_are_refused_before_any_job(tmp_path, old, new, shown):
    bad = tmp_path / "bad.yaml"
    text = (ROOT / "config" / "ci.yaml").read_text()
    bad.write_text(text.replace(old, new, 1))
    assert bad.read_text() != text
    r = _smk("-n", "--cores", "2", "--directory", str(tmp_path), "--configfile", str(bad))
    assert r.returncode != 0
    assert shown in r.stdout + r.stderr
    assert not (tmp_path / "results").exists() and not (tmp_path / "pwned").exists()


def _shell_commands() -> dict[str, str]:
    """Rule -> its shell command (the string literal of its ``shell:``), from every rule
    file of the workflow."""
    import ast
    import re

    out = {}
    for rules in sorted((ROOT / "workflow" / "rules").glob("*.smk")):
        text = rules.read_text()
        for m in re.finditer(r"^(\s*)rule (\w+):\n(.*?)(?=^\1(?:rule |\S)|\Z)", text,
                             re.MULTILINE | re.DOTALL):
            body = m.group(3)
            sh = re.search(r"^(\s+)shell:\n((?:\1\s+\S.*\n?)+)", body, re.MULTILINE)
            if sh:
                out[m.group(2)] = ast.literal_eval("(" + sh.group(2) + ")")
    return out


def test_every_shell_argument_of_every_rule_is_quoted():
    """Each field of each rule's shell command goes through Snakemake's shell quoting
    (``{...:q}``): a path with a space, a name with ``;`` or ``$(...)`` reaches the command
    as one argument, never as shell syntax."""
    import string

    commands = _shell_commands()
    assert {"contact_batch", "calibration", "tof_sweep", "validation", "survey_point",
            "design_device_table"} <= set(commands), sorted(commands)
    for rule, cmd in commands.items():
        fields = [(f, spec) for _, f, spec, _ in string.Formatter().parse(cmd) if f]
        assert fields, rule
        bare = [f for f, spec in fields if not (spec or "").endswith("q")]
        assert not bare, f"rule {rule}: unquoted {bare} in {cmd!r}"


def _copy_tree(dest: Path) -> None:
    """The repository's files (tracked, and new ones git does not ignore) and its compiled
    chain step copied to ``dest``: a clone of the working tree."""
    import shutil

    listed = subprocess.run(["git", "ls-files", "-z", "--cached", "--others",
                             "--exclude-standard"], cwd=ROOT, capture_output=True,
                            check=True).stdout.decode().split("\0")
    built = [str(p.relative_to(ROOT)) for p in (ROOT / "ssw").rglob("*.so")]
    for name in [n for n in listed if n] + built:
        src = ROOT / name
        if src.is_file():
            (dest / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / name)


@pytest.mark.long
def test_a_clone_under_a_folder_with_a_space_and_an_accent_gives_the_same_tables(ci_study,
                                                                                  tmp_path):
    """`make study CONFIG=config/ci.yaml` (the README's command on the CI study) in a clone
    under ``My Études/`` writes the same tables, every CSV row and every HDF5 dataset, as
    the study of the repository itself (``ci_study``): the Makefile, the rules' shell
    commands (the calibration's and the validation's ``--root``, the survey's recording
    paths) and the jobs' PYTHONPATH carry the folder's name whole. The clone starts from a
    copy of the study's operator cache (results/cache: keyed on the source, which the clone
    shares), so its contact operators are read, not built again."""
    import shutil

    import numpy as np

    from ssw.h5io import read_datasets

    clone = tmp_path / "My Études" / "ssw"
    _copy_tree(clone)
    shutil.copytree(ci_study / "results" / "cache", clone / "results" / "cache",
                    ignore=shutil.ignore_patterns("schema"))
    venv = Path(sys.executable).parent.parent
    r = subprocess.run(["make", "-o", "setup", "study", "CONFIG=config/ci.yaml",
                        f"VENV={venv}"], cwd=clone, capture_output=True, text=True,
                       env=_env(), timeout=600)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    # the folder's name reached the jobs' command lines (the calibration's --root)
    summary = (clone / "results" / "calibration" / "summary.json").read_text()
    assert "My \\u00c9tudes" in summary or "My Études" in summary, summary[:2000]

    def tables(root: Path) -> list[Path]:
        return sorted(p.relative_to(root) for p in (root / "results").rglob("*")
                      if p.suffix in {".csv", ".h5"} and "cache" not in p.parts)

    names = tables(clone)
    assert names == tables(ci_study) and len(names) >= 10
    for name in names:
        if name.suffix == ".csv":
            rows = [[x for x in (root / name).read_text().splitlines()
                     if not x.startswith("#")] for root in (clone, ci_study)]
            assert rows[0] == rows[1], name
            continue
        a, b = read_datasets(clone / name), read_datasets(ci_study / name)
        assert sorted(a) == sorted(b), name
        for key in a:
            assert np.array_equal(a[key], b[key], equal_nan=np.asarray(a[key]).dtype.kind == "f"), \
                f"{name}:{key}"


def _csv(path):
    from ssw.h5io import read_rows_csv

    return read_rows_csv(path)


def test_tiny_study_writes_every_output_and_reruns_nothing(ci_study):
    res = ci_study / "results"
    cfg = load_config(ci_study / "config" / "ci.yaml")
    from ssw.workflow import contact_file

    for sid in all_scenes(cfg):
        with h5py.File(ci_study / contact_file(sid)) as f:
            assert f.attrs["ssw_kind"] == "contact_curve"
            assert f["force"].attrs["units"] == "N"
    for name in ("fit/sets/set3_soil/k_table.h5", "chain/tof_sweep.h5",
                 "calibration/calibration.json",
                 "validation/table3_modulus.csv", "survey/survey.csv",
                 "survey/figures/survey_map.png"):
        assert (res / name).is_file(), name
    assert not list(res.rglob("*.part")), "a temporary file was left behind"
    # the jobs ran in forks of the run's warm process (ssw.warmstart), which ended with it
    log = (res / "logs" / "warm-start.log").read_text()
    assert sum(line.startswith("pid ") for line in log.splitlines()) >= 10, log
    r2 = _smk("-n", "--cores", "2", "--directory", str(ci_study), "--configfile",
              str(ci_study / "config" / "ci.yaml"))
    assert "Nothing to be done" in r2.stdout + r2.stderr


#: Thesis Tables 2 and 3 (REFERENCE.md): manufacturer E (Pa), measured TOF (s), the
#: thesis's simulated TOF (s) and its inverted E (Pa).
THESIS = {"PCF08": (38e6, 1.78e-3, 1.80e-3, 39e6), "PCF15": (123e6, 1.46e-3, 1.46e-3, 122e6),
          "PCF30": (445e6, 1.15e-3, 1.15e-3, 442e6)}


def test_study_tables_2_and_3_against_the_thesis_and_the_manufacturer(ci_study):
    """Calibrated (striker speed and preload) on the three foams' measured TOFs, the device
    reproduces them and the moduli. Tables 2 and 3 are IN-SAMPLE: the measured TOFs are the
    calibration's own references, taken at the manufacturer's moduli, so they show that the
    calibrated model closes on the data it was fitted to (three TOFs, two parameters: one
    degree of freedom), not that it predicts; the thesis's simulated TOF and inverted E
    come from the thesis's own model, compared as such:

    * Table 2: the calibrated model's TOF at the manufacturer's E within 1.5 % of the
      measured TOF (in-sample) and of the thesis's simulated TOF (measured: 0.3-1.0 % and
      0.2-0.7 %);
    * Table 3: the inverted E within 6 % of the manufacturer's (in-sample; measured 2.1 /
      3.5 / 5.5 %: PCF 08 misses the 5 % goal, README "Calibration"), each 95 %
      interval holding the manufacturer's E, and within 5 % of the thesis's own inverted E
      (2.6-2.8 %).

    The one OUT-OF-SAMPLE check is the leave-one-out (each foam's E from a calibration on
    the two others, which never saw its TOF): reported, not tuned. PCF 15 within 10 % and
    PCF 30 within 15 % (measured -7.7 % and +12.9 %, stable as numerical settings change:
    two foams identify both parameters, the fit is exact); PCF 08 within 40 %: without the
    softest foam the two stiffer ones barely pin the static load (the subset's second
    singular value 0.16: a curved valley of near-exact fits, not identified; measured +10 %
    to +31 % as numerical settings change, +14.2 % now, README "Calibration").
    """
    import json

    res = ci_study / "results"
    rows = {r["sample"]: r for r in json.loads(
        (res / "validation" / "validation.json").read_text())["samples"]}
    for sid, (E, t_meas, t_sim, E_thesis) in THESIS.items():
        r = rows[sid]
        assert r["tof_measured"] == pytest.approx(t_meas, rel=1e-12)
        assert r["tof_sim"] == pytest.approx(t_meas, rel=0.015), sid
        assert r["tof_sim"] == pytest.approx(t_sim, rel=0.015), sid
        assert r["E_measured"] == pytest.approx(E, rel=0.06), sid
        assert r["E_low"] < E < r["E_high"], sid
        assert r["E_measured"] == pytest.approx(E_thesis, rel=0.05), sid
    cal = json.loads((res / "calibration" / "calibration.json").read_text())
    assert set(cal["parameters"]) == {"striker_velocity", "preload"}
    assert cal["parameter_std"] is not None and min(cal["singular_values"]) >= 1.0
    loo = {row["id"]: row for row in cal["loo"]}
    assert list(loo) == list(THESIS)
    for sid, tol in (("PCF08", 0.40), ("PCF15", 0.10), ("PCF30", 0.15)):
        assert loo[sid]["E_predicted"] == pytest.approx(THESIS[sid][0], rel=tol), loo[sid]
        assert loo[sid]["chi2"] < 1.0  # two foams, two parameters: fitted (near) exactly
    t3 = _csv(res / "validation" / "table3_modulus.csv")
    assert [r["sample"] for r in t3] == list(THESIS)
    assert "E leave-one-out ssw [MPa]" in t3[0] and "E low 95% [MPa]" in t3[0]


def test_standalone_validate_prints_the_studys_numbers(ci_study, tmp_path):
    """One source of truth: `ssw validate` run by hand in the study's folder, with nothing
    but the config (no --calibration, no --sweep: it finds the study's calibration itself),
    gives the study's Table 3 to the bit."""
    import json

    env = _env()
    env.pop("SSW_CALIBRATION", None)  # a user's shell: the default, auto
    r = subprocess.run([sys.executable, "-m", "ssw", "validate", "--config",
                        str(ci_study / "config" / "ci.yaml"), "--root", str(ROOT),
                        "--outdir", str(tmp_path), "--json"],
                       cwd=ci_study, capture_output=True, text=True, env=env, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    mine = json.loads(r.stdout)
    study = json.loads((ci_study / "results" / "validation" / "validation.json").read_text())
    assert mine["calibration_file"] == "results/calibration/calibration.json"
    assert [s["sample"] for s in mine["samples"]] == [s["sample"] for s in study["samples"]]
    for a, b in zip(mine["samples"], study["samples"], strict=True):
        for key in ("tof_sim", "E_measured", "E_low", "E_high", "E_loo"):
            assert a[key] == b[key], (a["sample"], key, a[key], b[key])


def test_survey_recovers_the_moduli_that_made_it(ci_study):
    """The example survey's recordings were simulated at known moduli (data/survey_example:
    P1 135, P3 104, P4 92 MPa, nu 0.35) through the calibrated device: each 95 % interval
    holds its modulus, and the intervals against the 108 MPa target decide pass,
    inconclusive, fail. The thesis's 0.4 mm PLA plate yields under the bead at every point
    (plate_yield > 1: the contact FEM's peak von Mises stress over PLA's 50 MPa, as ssw
    design finds it, index 2.8 on 10-1000 MPa): E is computed beyond the model's elastic
    plate, so every verdict is inconclusive, with that reason in the table."""
    from ssw.survey import verdict

    rows = {r["id"]: r for r in _csv(ci_study / "results" / "survey" / "survey.csv")}
    truth = {"P1": (135e6, "pass"), "P3": (104e6, "inconclusive"), "P4": (92e6, "fail")}
    for pid, (E, by_interval) in truth.items():
        r = rows[pid]
        lo, hi = float(r["E_low [Pa]"]), float(r["E_high [Pa]"])
        assert lo < E < hi, r
        assert float(r["target_E [Pa]"]) == pytest.approx(108e6)
        assert verdict(lo, hi, 108e6) == by_interval, r
        assert "plate_yield" in r["checks_failed"], r
        assert r["verdict"] == "inconclusive" and "plate_yield" in r["reason"], r


def test_study_tables_carry_their_checks(ci_study):
    """The sweep, the validation and the survey tables carry each row's checks (columns
    named by check, ``checks_failed``) after their own columns, which are unchanged; the
    survey's JSON results carry the validity entries with their limits and sources."""
    import json

    res = ci_study / "results"
    sweep = _csv(res / "chain" / "tof_sweep.csv")
    assert list(sweep[0])[:3] == ["soil_E_Pa", "soil_nu", "tof_s"]
    assert {"contact_strain", "plate_deflection", "wall_reach", "pulse_separation",
            "bead_yield", "sample_yield_upper_bound", "checks_failed"} <= set(sweep[0])
    val = _csv(res / "validation" / "validation.csv")
    assert list(val[0])[-1] == "checks_failed" and "contact_strain [1]" in val[0]
    assert next(iter(val[0])) == "sample"
    survey = _csv(res / "survey" / "survey.csv")
    assert {"checks_failed", "reason"} <= set(survey[0])
    point = json.loads((res / "survey" / "points" / "P1.json").read_text())
    names = {e["check"] for e in point["validity"]}
    assert {"contact_strain", "sample_yield", "plate_yield"} <= names
    assert all({"value", "limit", "holds", "source"} <= set(e) for e in point["validity"])


@pytest.mark.long
def test_study_report_renders_in_a_headless_browser(ci_study):
    """`snakemake --report`: every figure of the study, with the survey's, loads in
    chromium, each category opens, no screenshot is blank (tests/test_report_browser.py)."""
    from test_report_browser import check_report

    r = _smk("--report", str(ci_study / "report.html"), "--directory", str(ci_study),
             "--configfile", str(ci_study / "config" / "ci.yaml"))
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    seen = check_report(ci_study / "report.html", ci_study)
    assert seen["categories"] == ["1. Contact (Stage I)", "2. Fits (Stage I)",
                                  "3. Chain (Stage II)", "4. Validation (Stage III)",
                                  "5. Survey"], seen
    assert seen["images"] and all(w > 0 for _, w in seen["images"]), seen
    assert not seen["blank"], seen


def test_spawned_jobs_name_the_interpreter_quoted(monkeypatch):
    """Snakemake's executors put the interpreter unquoted into a spawned job's command
    (``python -m snakemake ...``); after ``quote_job_python`` (common.smk) the local one
    answers a path with a space and an accent quoted, once, and a plain path as it is.
    (tests/test_slurm.py runs Slurm jobs through the remote ones.)"""
    import shlex

    from snakemake.executors.local import Executor

    from ssw.workflow.run import _SPAWNING_EXECUTORS, quote_job_python

    for module, name in _SPAWNING_EXECUTORS:  # put back as they were after the test
        cls = getattr(sys.modules.get(module), name, None)
        if cls is not None:
            monkeypatch.setattr(cls, "get_python_executable", cls.get_python_executable)
    quote_job_python()
    quote_job_python()  # idempotent: quoted once
    for python in ("/home/me/My Études/ssw/.venv/bin/python", "/usr/bin/python3"):
        monkeypatch.setattr(sys, "executable", python)
        assert Executor.get_python_executable(None) == shlex.quote(python)
        assert shlex.split(Executor.get_python_executable(None)) == [python]
