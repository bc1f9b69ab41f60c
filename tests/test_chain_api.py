"""The chain's public API, the inverse, sweeps (chunks, MPI) and the CLI contract."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from ssw.chain.params import ChainParams
from ssw.chain.run import peak_wall_indentation
from ssw.cli import main
from ssw.config import load_config
from ssw.errors import ConfigError, OutOfRangeError
from ssw.tof import api
from ssw.tof.inverse import invert
from ssw.tof.sweep import chunk_slice, grid_points, merge_sweeps, read_sweep, run_sweep

P = ChainParams(striker_velocity=0.5246)
ROOT = Path(__file__).resolve().parent.parent


def test_inverse_of_forward_is_identity():
    E = np.array([12e6, 38e6, 123e6, 445e6, 987e6])
    res = invert(api.tof(E, 0.3, P), 0.3, P)
    np.testing.assert_allclose(res.E, E, rtol=1e-6)


def test_inverse_interval_brackets_and_out_of_range_names_the_range():
    T = float(api.tof(123e6, 0.33, P))
    res = invert(T, 0.33, P, tof_std=1.53e-5)
    assert res.E_low < res.E < res.E_high  # longer TOF = softer soil
    lo, hi = res.tof_range
    with pytest.raises(OutOfRangeError, match=r"valid range \["):
        invert(hi * 1.05, 0.33, P)
    with pytest.raises(OutOfRangeError, match="MPa"):
        invert(lo * 0.95, 0.33, P)


def test_tof_is_vectorized_and_decreases_with_E():
    E = np.array([[20e6], [200e6]])
    nu = np.array([0.1, 0.3, 0.5])
    T = api.tof(E, nu, P)
    assert T.shape == (2, 3)
    assert np.all(T[0] > T[1])


def test_peak_wall_indentation_is_below_the_energy_bound():
    """Without gravity, the wall cannot store more than the striker's kinetic energy:
    2/5 A_w d^2.5 <= m v^2 / 2, so d <= (5 m v^2 / (4 A_w))^(2/5)."""
    p = P.with_(gravity=False)
    E = np.array([10e6, 100e6, 1000e6])
    d = peak_wall_indentation(E, 0.3, p)
    bound = (5 * p.bead_mass * p.striker_velocity**2 / (4 * p.wall_coefficient(E, 0.3))) ** 0.4
    assert np.all(d > 0.3 * bound)
    assert np.all(d <= bound)


def test_sensor_signal_shapes_and_baseline():
    t, F = api.sensor_signal(50e6, 0.3, P)
    assert t.ndim == 1 and F.shape == t.shape
    s = P.sensor_index
    expected = 0.5 * P.g * P.bead_mass * (s - 1 + s)  # static mean of the two contacts
    assert F[0] == pytest.approx(expected, rel=1e-9)
    t2, F2 = api.sensor_signal([50e6, 60e6], 0.3, P, t_end=1e-3)
    assert F2.shape == (t2.size, 2) and t2[-1] == pytest.approx(1e-3, abs=2 * t2[1])


def test_uniform_sensor_ignores_sensor_mass():
    heavy = P.with_(sensor_mass=0.08)
    assert api.tof(80e6, 0.3, heavy.with_(uniform=True)) == pytest.approx(
        float(api.tof(80e6, 0.3, P)), rel=1e-12
    )
    assert abs(float(api.tof(80e6, 0.3, heavy)) / float(api.tof(80e6, 0.3, P)) - 1) > 1e-3


def test_sweep_chunks_merge_to_the_whole_and_do_not_depend_on_the_batch():
    E, nu = grid_points(np.arange(10e6, 200e6, 30e6), [0.1, 0.5])
    whole = run_sweep(P, E, nu)
    parts = [run_sweep(P, E[chunk_slice(E.size, c, 3)], nu[chunk_slice(E.size, c, 3)])
             for c in range(3)]
    merged = merge_sweeps(parts)
    np.testing.assert_allclose(merged.sorted().tof, whole.sorted().tof, rtol=1e-12)


def test_params_from_config_reads_the_library():
    cfg = load_config(ROOT / "config" / "config.yaml")
    p = ChainParams.from_config(cfg)
    assert p.bead_E == 200e9 and p.bead_density == 7810.0
    assert ChainParams.from_config(cfg, n_beads=12, sensor_index=6).n_beads == 12
    with pytest.raises(ConfigError, match="sensor_index"):
        ChainParams(n_beads=10, sensor_index=9)


def _cli(args, capsys):
    assert main(args) == 0
    return json.loads(capsys.readouterr().out)


def test_cli_chain_writes_time_and_contact_forces(tmp_path, capsys):
    out = tmp_path / "run.h5"
    res = _cli(["chain", "--beads", "12", "--striker-velocity", "0.5", "--no-gravity",
                "--wall", "hertz", "--soil-E", "1e8", "--soil-nu", "0.3", "--t-end", "1e-3",
                "--output", str(out), "--json"], capsys)
    with h5py.File(out) as f:
        t, F = f["time"][()], f["contact_force"][()]
        assert f["contact_force"].attrs["units"] == "N"
    assert F.shape == (t.size, 12) and res["n_contacts"] == 12
    assert t[-1] == pytest.approx(1e-3, abs=2 * t[1])
    # the striker's first contact (column 0) loads first; the wall (last) is last
    first = np.argmax(F > 1.0, axis=0)
    assert first[0] < first[5] < first[-1]


def test_cli_tof_sweep_and_invert_agree(tmp_path, capsys):
    base = ["--law", "hertz", "--striker-velocity", "0.5246", "--json"]
    one = _cli(["tof", "--soil-E", "1.2e8", "--soil-nu", "0.3", *base], capsys)
    sw = _cli(["tof-sweep", "--soil-E-min", "6e7", "--soil-E-max", "1.8e8",
               "--soil-E-step", "6e7", "--soil-nu", "0.3", *base,
               "--output", str(tmp_path / "s.h5"), "--csv", str(tmp_path / "s.csv")], capsys)
    assert sw["tof"][1] == pytest.approx(one["tof"], rel=1e-12)
    inv = _cli(["invert", "--tof", str(one["tof"]), "--tof-std", "1e-5", "--soil-nu", "0.3",
                *base], capsys)
    assert inv["E"] == pytest.approx(1.2e8, rel=1e-6)
    assert read_sweep(tmp_path / "s.h5")[0].tof.size == 3
    head = (tmp_path / "s.csv").read_text().splitlines()[:2]
    assert head[0].startswith("# ssw ") and head[1].startswith("soil_E_Pa,")  # provenance


def test_cli_tof_reports_its_derivatives(capsys):
    """``ssw tof --json`` gives ``dtof_dE`` and ``dtof_d<parameter>`` (s per SI unit) with
    the method of each: forward sensitivities here (Hertz wall), equal to the API's and to
    central differences of the CLI's own TOFs within 1e-4 (E, striker speed); ``--derivatives
    none`` gives the same TOF and no derivatives."""
    from ssw.chain.sensitivity import PARAMETERS

    base = ["--law", "hertz", "--calibration", "none", "--soil-nu", "0.3", "--json"]
    res = _cli(["tof", "--soil-E", "1.2e8", *base], capsys)
    assert set(res["derivative_method"]) == set(PARAMETERS)
    assert set(res["derivative_method"].values()) == {"forward"}
    for name in PARAMETERS:
        assert np.isfinite(res[f"dtof_d{name}"])
    assert res["derivative_units"]["dtof_dE"] == "s/(Pa)"
    plain = _cli(["tof", "--soil-E", "1.2e8", *base, "--derivatives", "none"], capsys)
    assert plain["tof"] == res["tof"] and "dtof_dE" not in plain
    h = 1e-4
    up, down = (_cli(["tof", "--soil-E", str(1.2e8 * (1 + s * h)), *base, "--derivatives",
                      "none"], capsys)["tof"] for s in (1, -1))
    assert (up - down) / (2 * h * 1.2e8) == pytest.approx(res["dtof_dE"], rel=1e-4)
    v = res["striker_velocity"]
    up, down = (_cli(["tof", "--soil-E", "1.2e8", *base, "--derivatives", "none",
                      "--striker-velocity", str(v * (1 + s * h))], capsys)["tof"]
                for s in (1, -1))
    assert (up - down) / (2 * h * v) == pytest.approx(res["dtof_dstriker_velocity"],
                                                      rel=1e-4)


def test_the_striker_speed_derivative_through_the_fem_wall_is_the_discrete_tofs(capsys):
    """Through the default (FEM) wall, ``dtof_dstriker_velocity`` is the derivative of the
    TOF the chain computes, its step's dependence on the speed included: central differences
    of the CLI's own TOFs at a relative step of 1e-5 agree within 1e-6 (measured 2026-11-29:
    4e-9). At relative steps of 1e-4 to 1e-3 they differ by
    8e-5: the piecewise-linear law's breakpoints put kinks in the discrete TOF as the
    indentation crosses them from one speed to the next, which a wide difference averages."""
    base = ["tof", "--soil-E", "1e8", "--soil-nu", "0.3", "--calibration", "none", "--json"]
    v, h = 0.4, 1e-5
    res = _cli([*base, "--striker-velocity", str(v)], capsys)
    assert res["derivative_method"]["striker_velocity"] == "forward"
    up, down = (_cli([*base, "--derivatives", "none", "--striker-velocity",
                      repr(v * (1 + s * h))], capsys)["tof"] for s in (1, -1))
    assert (up - down) / (2 * h * v) == pytest.approx(res["dtof_dstriker_velocity"],
                                                      rel=1e-6)


def test_cli_reports_out_of_range_tof(capsys):
    assert main(["invert", "--tof", "0.05", "--soil-nu", "0.3", "--law", "hertz"]) == 2
    assert "valid range" in capsys.readouterr().err


@pytest.mark.mpi
def test_mpi_sweep_gives_the_serial_answer(tmp_path):
    from conftest import require

    require(shutil.which("mpiexec") is not None, "no mpiexec")
    import mpi4py  # noqa: F401  (a dependency: set-up builds it)
    ssw = str(Path(sys.executable).parent / "ssw")
    args = ["tof-sweep", "--law", "hertz", "--soil-E-min", "1e7", "--soil-E-max", "1e8",
            "--soil-E-step", "1e7", "--soil-nu", "0.1", "0.5", "--json"]
    par = subprocess.run(["mpiexec", "-n", "2", ssw, *args, "--mpi"], capture_output=True,
                         text=True, check=True, cwd=ROOT, timeout=120)
    ser = subprocess.run([ssw, *args], capture_output=True, text=True, check=True, cwd=ROOT,
                         timeout=120)
    a, b = json.loads(par.stdout), json.loads(ser.stdout)
    assert a["ranks"] == 2 and b["ranks"] == 1
    np.testing.assert_allclose(a["tof"], b["tof"], rtol=1e-12)  # batch: last-bit rounding


@pytest.mark.parametrize("change", [{}, {"gravity": False}, {"n_beads": 30, "sensor_index": 25},
                                    {"striker_velocity": 3.0}])
def test_early_stop_does_not_change_the_tof(change):
    """Stopping a scene early (integrate's rule) picks the same peaks as running every
    scene 2.5 times longer, from very soft to stiffer-than-rock walls."""
    from ssw.chain.integrate import simulate
    from ssw.chain.tof import pick_peaks
    from ssw.walls import build_wall

    p = P.with_(**change)
    w = build_wall("hertz", p, np.geomspace(5e6, 2e9, 12), 0.3)
    short = simulate(p, w)
    long = simulate(p, w, t_end=2.5 * np.nanmax(short.stop_time), stop_early=False)
    assert not np.any(np.isnan(short.stop_time))
    np.testing.assert_array_equal(pick_peaks(short.t, short.sensor).tof,
                                  pick_peaks(long.t, long.sensor).tof)


def test_workflow_helpers_name_the_wall_inputs():
    from ssw import workflow as wf

    cfg = load_config(ROOT / "config" / "config.yaml")
    assert cfg["chain"]["wall_law"] == "fem" and wf.wall_inputs(cfg, "R") == {}
    cfg["chain"]["wall_law"] = "fit"
    kt = "R/fit/sets/set3_soil/k_table.h5"  # fit.set's table
    assert wf.wall_inputs(cfg, "R") == {"k_table": kt}
    assert wf.calibrated_inputs(cfg, "R") == {"k_table": kt,
                                              "calibration": "R/calibration/calibration.json"}
    cfg["chain"]["wall_law"] = "table"
    ids = wf.sweep_scene_ids(cfg)  # the thesis sweep is Set 3's grid: every point has a curve
    assert len(ids) == 300 and len(wf.wall_inputs(cfg, "R")["curves"]) == 300
    cfg["chain"]["sweep"]["soil_E"] = {"values": [15e6]}
    with pytest.raises(ValueError, match="no set"):
        wf.sweep_scene_ids(cfg)
