"""The ``ssw contact`` CLI contract, the curve file and the MPI run (2 ranks = serial)."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ssw import hertz
from ssw.cli import main
from ssw.config import Scene, all_scenes, library, load_config
from ssw.contact import solve_scene
from ssw.curve import read_curve
from ssw.h5io import read_datasets

REPO = Path(__file__).resolve().parent.parent
CI = str(REPO / "config" / "ci.yaml")
REQUIRED = ("soil_E", "soil_nu", "plate_material", "plate_E", "plate_nu", "plate_thickness",
            "interface", "indenter_radius", "delta_max", "steps", "material_set")


def test_cli_writes_curve(tmp_path, capsys):
    out = tmp_path / "c.h5"
    rc = main(["contact", "--soil-E", "30e6", "--soil-nu", "0.5", "--plate-material", "pla",
               "--plate-thickness", "0.4e-3", "--steps", "20", "--config", CI,
               "--output", str(out), "--json"])
    assert rc == 0
    printed = json.loads(capsys.readouterr().out)
    curve = read_curve(out)
    assert all(k in curve.inputs for k in REQUIRED)
    assert curve.inputs["plate_material"] == "pla" and curve.inputs["material_set"] == "realistic"
    assert np.allclose(printed["force"], curve.force)
    assert len(curve.delta) == 20 and curve.delta[-1] == pytest.approx(1e-4)
    assert curve.pressure["p"].shape[1] == len(curve.pressure["r"])
    # the contact pressure integrates to the force (2 pi r p dr over the profile)
    r, p = curve.pressure["r"], curve.pressure["p"][-1]
    assert np.trapezoid(2 * np.pi * r * p, r) == pytest.approx(curve.force[-1], rel=0.03)


def test_cli_rejects_missing_plate(capsys):
    rc = main(["contact", "--soil-E", "30e6", "--soil-nu", "0.3", "--plate-thickness", "4e-4",
               "--config", CI])
    assert rc == 2
    assert "--plate-material" in capsys.readouterr().err


def test_solve_scene_api_no_plate():
    cfg = load_config(CI)
    curve = solve_scene(Scene("none", 0.0, 80e6, 0.3), cfg["contact"],
                        cfg["indenter"]["radius"], library(cfg))
    fh = hertz.force(curve.delta, hertz.effective_modulus(80e6, 0.3), cfg["indenter"]["radius"])
    assert np.max(np.abs(curve.force / fh - 1)[curve.delta >= 1e-6]) < 5e-3
    assert curve.inputs["plate_material"] == "none" and curve.inputs["plate_E"] is None


@pytest.mark.mpi
def test_two_ranks_share_a_batch_and_give_the_serial_curves(tmp_path):
    """`mpiexec -n 2 ssw contact --scene ... --output-dir D`: the batch's operator groups are
    dealt to the ranks (each solves its own scenes, none twice) and every curve equals the
    serial run's to the bit; rank 0 alone reports."""
    from conftest import require

    require(shutil.which("mpiexec") is not None, "no mpiexec")
    cfg = load_config(CI)
    ids = sorted(s for s in all_scenes(cfg) if s.startswith(("pla-t400um-E50", "al6061")))
    exe = str(Path(sys.executable).parent / "ssw")
    args = ["contact", *[a for i in ids for a in ("--scene", i)], "--config", CI, "--json"]
    par = subprocess.run(["mpiexec", "-n", "2", exe, *args, "--output-dir",
                          str(tmp_path / "par")], capture_output=True, text=True, timeout=300,
                         check=True)
    ser = subprocess.run([exe, *args, "--output-dir", str(tmp_path / "ser")],
                         capture_output=True, text=True, timeout=300, check=True)
    lines = par.stdout.strip().splitlines()
    assert len(lines) == 1  # rank 0 alone reports
    res = json.loads(lines[0])
    assert res["ranks"] == 2 and sorted(res["scenes"]) == ids
    ranks = {c["scene_id"]: c["rank"] for c in res["curves"]}
    assert set(ranks.values()) == {0, 1}  # two operator groups (pla, al6061): one each
    for i in ids:
        a, b = read_curve(tmp_path / "par" / f"{i}.h5"), read_curve(tmp_path / "ser" / f"{i}.h5")
        assert np.array_equal(a.force, b.force) and np.array_equal(a.delta, b.delta)
    assert ser.returncode == 0


def test_schema_defaults_are_the_solver_defaults():
    """One source of truth: the schema's contact defaults equal ssw.contact.DEFAULTS."""
    from ssw.config import load_schema
    from ssw.contact import DEFAULTS

    props = load_schema()["properties"]["contact"]["properties"]
    assert {k: props[k]["default"] for k in DEFAULTS} == DEFAULTS
    for k, v in props.items():
        assert v.get("description"), k


def test_bad_inputs_name_the_field():
    from ssw.contact import solve_curve
    from ssw.errors import ConfigError

    with pytest.raises(ConfigError, match="soil_nu"):
        solve_curve((1e7, 0.6), None, 0.0, 9.53e-3, {})
    with pytest.raises(ConfigError, match=r"contact\.interface"):
        solve_curve((1e7, 0.3), None, 0.0, 9.53e-3, {"interface": "glued"})


# ---- batches: several scenes in one process (the workflow's contact jobs)


def test_batch_writes_every_scene_as_the_single_scene_command_does(tmp_path, capsys):
    """`--scene A --scene B --output-dir D` writes D/A.h5 and D/B.h5 with the same datasets
    and inputs as two `--scene X --output F` runs (the batch only saves start-up)."""
    from ssw.workflow import families

    ids = [i for b in families(load_config(CI)).values() for i in b][:2]
    rc = main(["contact", *[a for i in ids for a in ("--scene", i)], "--scene", ids[0],
               "--config", CI, "--output-dir", str(tmp_path / "batch"), "--json"])
    assert rc == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed["scenes"] == ids  # a repeated id is solved once
    assert printed["outputs"] == [str(tmp_path / "batch" / f"{i}.h5") for i in ids]
    assert sorted(p.name for p in (tmp_path / "batch").iterdir()) == sorted(f"{i}.h5" for i in ids)
    for i in ids:
        single = tmp_path / f"single-{i}.h5"
        assert main(["contact", "--scene", i, "--config", CI, "--output", str(single)]) == 0
        a, b = read_datasets(tmp_path / "batch" / f"{i}.h5"), read_datasets(single)
        assert sorted(a) == sorted(b)
        for key in a:
            assert np.array_equal(a[key], b[key]), key
        ca, cb = read_curve(tmp_path / "batch" / f"{i}.h5"), read_curve(single)
        assert ca.inputs == cb.inputs and ca.inputs["scene_id"] == i


@pytest.mark.parametrize(("argv", "field"), [
    (["--scene", "nope", "--scene", "pla-t400um-E50MPa-nu0.300"], "--scene"),
    (["--scene", "pla-t400um-E50MPa-nu0.300", "--scene", "al6061-t400um-E50MPa-nu0.300",
      "--output", "x.h5"], "--output"),
    (["--scene", "pla-t400um-E50MPa-nu0.300", "--scene", "al6061-t400um-E50MPa-nu0.300"],
     "--output-dir"),
    (["--soil-E", "5e7", "--soil-nu", "0.3", "--plate-thickness", "0"], "--scene"),
    (["--scene", "pla-t400um-E50MPa-nu0.300", "--soil-E", "5e7"], "--soil-E"),
])
def test_batch_refusals_write_nothing(tmp_path, capsys, argv, field):
    """A bad batch stops before the first solve (unknown id, --output for several scenes,
    no folder, scene flags) and names the option."""
    out_dir = tmp_path / "out"
    extra = [] if "--output" in argv or field == "--output-dir" else ["--output-dir", str(out_dir)]
    rc = main(["contact", *argv, "--config", CI, *extra])
    assert rc == 2
    assert field in capsys.readouterr().err
    assert not out_dir.exists() or not any(out_dir.iterdir())


def test_families_are_plate_families():
    """Every scene in exactly one family: the scenes of one plate material and thickness (or
    of no plate), whatever set lists them; the family is the scene id's start. The thesis
    study: the 0.4 mm PLA family holds Sets 1 and 3 and Set 2's 0.4 mm scene; Sets 1 and 2
    add one family per other material and thickness. MPI ranks get whole operator groups."""
    from ssw.config import all_scenes
    from ssw.contact.batch import group_key, rank_share
    from ssw.workflow import families

    cfg = load_config(REPO / "config" / "config.yaml")
    scenes = all_scenes(cfg)
    fams = families(cfg)
    ids = [i for b in fams.values() for i in b]
    assert sorted(ids) == sorted(scenes) and len(ids) == len(set(ids))
    for name, members in fams.items():
        keys = {(scenes[i].plate_material, scenes[i].plate_thickness) for i in members}
        assert len(keys) == 1, name
        assert all(i.startswith(name + "-") for i in members)
    assert sorted(fams) == ["a36-t400um", "al6061-t400um", "noplate", "pla-t1000um",
                            "pla-t100um", "pla-t200um", "pla-t400um"]
    assert len(fams["pla-t400um"]) == 300 + 2  # Set 3, and Sets 1 and 2 at their own soils
    # MPI: whole operator groups per rank, every scene once
    fam = [scenes[i] for i in fams["pla-t400um"]]
    shares = [rank_share(fam, r, 3) for r in range(3)]
    assert sorted(i for s in shares for i in s) == list(range(len(fam)))
    for s in shares:
        others = {group_key(fam[i]) for t in shares if t is not s for i in t}
        assert not others & {group_key(fam[i]) for i in s}


def test_family_batch_refusals(tmp_path, capsys):
    """`--family` names a family of the config, and not with --scene."""
    rc = main(["contact", "--family", "pla-t999um", "--config", CI, "--output-dir",
               str(tmp_path / "o")])
    assert rc == 2 and "--family" in capsys.readouterr().err
    rc = main(["contact", "--family", "pla-t400um", "--scene", "pla-t400um-E50MPa-nu0.300",
               "--config", CI, "--output-dir", str(tmp_path / "o")])
    assert rc == 2 and "--scene" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_delta_mode_energy_reaches_the_hertz_energy(tmp_path):
    """contact.delta_mode energy: a curve goes on past delta_max, with the increments of
    delta_max / steps all along, to where a Hertz half-space of the softer of soil and plate
    stores contact.reach_energy: (2/5) A d^2.5 = W (closed form), independent of the device;
    a stiff soil's ends at delta_max when that is deeper."""
    ROOT = Path(__file__).resolve().parent.parent
    cfg = load_config(ROOT / "config" / "ci.yaml")
    assert cfg["contact"]["delta_mode"] == "energy"
    W, R = cfg["contact"]["reach_energy"], cfg["indenter"]["radius"]
    soft = "pla-t400um-E30MPa-nu0.300"
    steps = int(cfg["contact"]["steps"])
    assert main(["contact", "--config", str(ROOT / "config" / "ci.yaml"), "--scene", soft,
                 "--output", str(tmp_path / "soft.h5")]) == 0
    c = read_curve(tmp_path / "soft.h5")
    A = 4.0 / 3.0 * 30e6 / (1 - 0.3**2) * np.sqrt(R)  # the soil is softer than PLA
    need = (2.5 * W / A) ** 0.4
    assert 0.4 * A * need**2.5 == pytest.approx(W, rel=1e-12)
    assert need > 2 * cfg["contact"]["delta_max"]
    h = cfg["contact"]["delta_max"] / steps
    assert c.delta[-1] == pytest.approx(need, rel=1e-12) and c.delta.size == np.ceil(need / h)
    np.testing.assert_allclose(np.diff(c.delta[:-1]), h, rtol=1e-9)
    # the same reach whatever the device: a 40-bead device changes nothing
    dev = tmp_path / "dev.yaml"
    dev.write_text((ROOT / "config" / "devices" / "thesis.yaml").read_text()
                   .replace("beads: 20", "beads: 40"))
    cfg2 = tmp_path / "c2.yaml"
    cfg2.write_text((ROOT / "config" / "ci.yaml").read_text().replace(
        "device: thesis", f"device: {dev}"))
    assert main(["contact", "--config", str(cfg2), "--scene", soft,
                 "--output", str(tmp_path / "soft2.h5")]) == 0
    np.testing.assert_array_equal(read_curve(tmp_path / "soft2.h5").delta, c.delta)


def test_delta_mode_chain_extends_the_curve_to_what_the_chain_reaches(tmp_path):
    """contact.delta_mode chain: a soft soil's curve goes on past delta_max to the chain's
    indentation (Hertz wall of the softer material, fit.range.factor) with the increments of
    delta_max / steps all along, the curve a fixed-mode run to that indentation with as many
    steps gives; a stiff soil's ends at delta_max or just past it."""
    from ssw.fit.range import scene_delta_max

    ROOT = Path(__file__).resolve().parent.parent
    chain_cfg = tmp_path / "chain.yaml"
    chain_cfg.write_text((ROOT / "config" / "ci.yaml").read_text().replace(
        "delta_mode: energy", "delta_mode: chain"))
    cfg = load_config(chain_cfg)
    assert cfg["contact"]["delta_mode"] == "chain"
    soft, stiff = "pla-t400um-E30MPa-nu0.300", "pla-t400um-E660MPa-nu0.300"
    steps = int(cfg["contact"]["steps"])
    assert main(["contact", "--config", str(chain_cfg), "--scene", soft,
                 "--scene", stiff, "--output-dir", str(tmp_path / "chain")]) == 0
    c = read_curve(tmp_path / "chain" / f"{soft}.h5")
    pla = library(cfg)["pla"]
    need = scene_delta_max(30e6, 0.3, cfg, (pla.E, pla.nu))
    assert need > 2 * cfg["contact"]["delta_max"]  # 30 MPa: the chain presses > 0.2 mm
    h = cfg["contact"]["delta_max"] / steps  # one step over the whole curve
    assert c.delta[-1] == pytest.approx(need, rel=1e-12) and c.delta.size == np.ceil(need / h)
    np.testing.assert_allclose(np.diff(c.delta[:-1]), h, rtol=1e-9)
    assert np.all(np.diff(c.force) > 0)
    end = h * (c.delta.size - 1)  # the last whole step
    assert main(["contact", "--config", str(chain_cfg), "--scene", soft,
                 "--delta-max", repr(end), "--steps", str(c.delta.size - 1),
                 "--output", str(tmp_path / "fixed.h5")]) == 0
    f = read_curve(tmp_path / "fixed.h5")
    np.testing.assert_allclose(f.delta, c.delta[:-1], rtol=1e-12)
    np.testing.assert_allclose(f.force, c.force[:-1], rtol=1e-12)
    s = read_curve(tmp_path / "chain" / f"{stiff}.h5")
    need_stiff = scene_delta_max(660e6, 0.3, cfg, (pla.E, pla.nu))
    assert need_stiff < 1.5 * cfg["contact"]["delta_max"]
    assert s.delta[-1] == pytest.approx(max(need_stiff, cfg["contact"]["delta_max"]), rel=1e-12)
