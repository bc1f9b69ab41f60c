"""The study workflow's device design: one job per family, its chains scattered over
``design.device.parts`` jobs (Snakemake's scattergather ``device``), gathered and ranked by
the table rule. On a tiny space (one family of two chains, two parts) run through
``snakemake --cores 2`` the table equals a single ``ssw design --space device`` run of the
same config: the same devices, the same recommended device, the same numbers (the two
parts' chains batched as in the single run); and a part beyond the family's chains is
refused by name."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from ssw.design.device_eval import ARRAYS
from ssw.design.space import DeviceSpace

ROOT = Path(__file__).resolve().parents[1]
VENV_BIN = Path(sys.executable).parent
SPACE = {"study": True, "parts": 2,
         "bead_materials": ["chrome_steel", "tungsten_carbide"], "bead_diameters": [9.525e-3],
         "beads": [12], "sensor_positions": [0.5], "plate_materials": ["pla"],
         "striker_mass_ratio": {"range": [0.5, 1.0], "scan": 2},
         "drop_height": {"range": [2e-3, 8e-3], "scan": 1},
         "plate_thickness": {"range": [1e-4, 1.5e-4], "scan": 1},
         "finalists": 1, "refine_evaluations": 0, "moduli": 2, "plate_yield_limit": 3.0}
KEY = ("bead_material", "bead_diameter", "beads", "sensor_index", "sensor_mass_ratio",
       "striker_mass_ratio", "drop_height", "plate_material", "plate_thickness")


def _env() -> dict[str, str]:
    # No disk cache for either run: a body condensed in the process and one read back from
    # a cache (the workflow's, or ~/.cache/ssw filled by other runs) take different, equally
    # exact paths (their results about 1e-12 apart), and the runs are compared bit for bit.
    return {**os.environ, "PATH": f"{VENV_BIN}{os.pathsep}{os.environ.get('PATH', '')}",
            "SSW_CACHE_DIR": "none"}


# long: a whole Snakemake run of the device design; the default run checks the same
# equality of parts merged and one run through the commands the rules call
# (tests/test_design_scale.py::test_a_design_split_into_parts_and_merged_is_the_single_run)
@pytest.mark.long
def test_scattered_families_give_the_single_run_table(tmp_path):
    cfg = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    cfg["calibration"]["use"] = False
    cfg["design"]["soils"] = {"tiny": {"soil_E": [20e6, 200e6], "soil_nu": 0.3}}
    cfg["design"]["device"] = SPACE
    (tmp_path / "config.yaml").write_text(yaml.safe_dump(cfg))
    target = "results/design/device/tiny.json"
    proc = subprocess.run(
        [str(VENV_BIN / "snakemake"), "-s", str(ROOT / "workflow" / "Snakefile"),
         "--configfile", str(tmp_path / "config.yaml"), "--directory", str(tmp_path),
         "--cores", "2", target], cwd=tmp_path, env=_env(), capture_output=True, text=True,
        timeout=1800)
    assert proc.returncode == 0, proc.stderr[-3000:]
    parts = sorted((tmp_path / "results/design/device/tiny/9525um_pla").glob("*.json"))
    assert [p.name for p in parts] == ["1-of-2.json", "2-of-2.json"]
    chains = [{c["bead_material"] for c in json.loads(p.read_text())["candidates"]
               if c["source"] == "scan"} for p in parts]
    assert chains == [{"chrome_steel"}, {"tungsten_carbide"}]  # one chain a part
    single = tmp_path / "single.json"
    proc = subprocess.run(
        [sys.executable, "-m", "ssw", "design", "--space", "device", "--soil-range", "tiny",
         "--config", str(tmp_path / "results" / "study_config.yaml"), "--calibration", "none",
         "--output", str(single)], cwd=tmp_path, env=_env(), capture_output=True, text=True,
        timeout=1800)
    assert proc.returncode == 0, proc.stderr[-3000:]
    a = json.loads(single.read_text())
    b = json.loads((tmp_path / target).read_text())
    assert b["recommended"]["label"] == a["recommended"]["label"]
    assert b["recommended"]["resolution"] == a["recommended"]["resolution"]

    def rows(res):
        return {tuple(c[k] for k in KEY): c for c in res["candidates"]}

    ra, rb = rows(a), rows(b)
    assert set(ra) == set(rb) and len(ra) == 5  # 2 chains x 2 strikers and the base device
    same_step = [k for k in ra if ra[k]["step"] == rb[k]["step"]]
    assert len(same_step) >= 4  # a part's best is evaluated at its own step too
    for k in same_step:
        for name in ARRAYS:
            assert rb[k][name] == ra[k][name], (k, name)


def test_a_part_beyond_the_chains_is_refused():
    from ssw.errors import ConfigError

    space = DeviceSpace(bead_materials=("chrome_steel",), beads=(12,),
                        sensor_positions=(0.5,))
    assert len(space.family_points(9.525e-3, "pla", 0, 1)) > 0
    with pytest.raises(ConfigError, match=r"design\.device\.parts"):
        space.family_points(9.525e-3, "pla", 0, 2)
