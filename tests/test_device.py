"""The device file: schema, defaults, overrides, round trip, its dissipation as the source of
truth of the chain's; and the chain physics it adds (a preload on the column, what the
sensor reads), checked against analytic truth."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from ssw.chain.integrate import simulate
from ssw.chain.params import Batch, chain_params, numerics_of
from ssw.chain.run import run_peaks
from ssw.chain.statics import initial_state, static_contact_forces
from ssw.device import (
    STANDARD_GRAVITY,
    available_devices,
    device_from_dict,
    load_device,
    write_device,
)
from ssw.errors import ConfigError
from ssw.materials import material_set
from ssw.tof import api
from ssw.walls import build_wall


def test_the_thesis_device_is_shipped_and_default():
    assert "thesis" in available_devices()
    d = load_device()
    assert d.name == "thesis" and d.beads == 20 and d.sensor_index == 10
    assert d.plate_material == "pla" and d.plate_thickness == pytest.approx(0.4e-3)
    assert d.plate_diameter == pytest.approx(49.5e-3) and d.sensitivity == pytest.approx(11.24e-3)
    assert d.beads_below_sensor == 9


def test_round_trip(tmp_path):
    d = load_device().with_(preload=2.5, sensor_mass=0.04, sensor_reads="lower",
                            dissipation_law="hunt_crossley", dissipation=0.02,
                            striker_mass_std=2e-5)
    write_device(tmp_path / "d.yaml", d, "# a test device")
    back = load_device(tmp_path / "d.yaml")
    assert back.with_(source="") == d.with_(source="")


def test_drop_height_gives_the_free_fall_speed():
    d = load_device().with_(drop_height=0.02)
    assert d.striker_velocity == pytest.approx(np.sqrt(2 * STANDARD_GRAVITY * 0.02))
    assert d.drop_height == pytest.approx(0.02)
    raw = load_device().to_dict()
    raw["striker"] = {"mass": None, "velocity": None, "drop_height": 0.02}
    assert device_from_dict(raw).striker_velocity == pytest.approx(d.striker_velocity)


def test_more_beads_keep_the_beads_below_the_sensor():
    d = load_device().with_(beads=30)
    assert d.sensor_index == 20 and d.beads_below_sensor == 9


@pytest.mark.parametrize(("path", "value", "field"), [
    (("chain", "beads"), 2, "chain.beads"),
    (("sensor", "reads"), "both", "sensor.reads"),
    (("plate", "interface"), "glued", "plate.interface"),
    (("striker", "velocity"), -1.0, "striker.velocity"),
    (("daq_sensor", "sensitivity"), 0.0, "daq_sensor.sensitivity"),
    (("chain", "preload"), -1.0, "chain.preload"),
    (("dissipation", "law"), "tsuji", "dissipation.law"),
    (("dissipation", "coefficient"), -1.0, "dissipation.coefficient"),
    (("striker", "mass_std"), 0.0, "striker.mass_std"),
    (("striker", "mass_std"), float("nan"), "striker.mass_std"),
])
def test_bad_fields_are_refused_naming_them(path, value, field):
    raw = load_device().to_dict()
    raw[path[0]][path[1]] = value
    with pytest.raises(ConfigError) as exc:
        device_from_dict(raw, "x.yaml")
    assert field in str(exc.value) and str(value) in str(exc.value)


def test_striker_needs_exactly_one_of_speed_and_height():
    raw = load_device().to_dict()
    raw["striker"] = {"mass": None, "velocity": 0.5, "drop_height": 0.01}
    with pytest.raises(ConfigError, match="exactly one of velocity"):
        device_from_dict(raw)


def test_unknown_device_names_the_shipped_ones():
    with pytest.raises(ConfigError, match="thesis"):
        load_device("no-such-device")


def test_chain_params_carry_the_device_and_its_materials():
    mats = material_set()
    p = chain_params(load_device().with_(preload=3.0), mats, steps_per_contact=60)
    assert p.n_beads == 20 and p.preload == 3.0 and p.steps_per_contact == 60
    assert p.bead_E == mats["chrome_steel"].E and p.plate_E == mats["pla"].E
    assert p.plate_nu == mats["pla"].nu and p.plate_diameter == pytest.approx(49.5e-3)


def test_the_device_is_the_source_of_truth_of_the_dissipation():
    """A device file without ``dissipation:`` is conservative (the dashpot at 0: the
    shipped device and the default study unchanged); the device's law and coefficient reach
    the chain; the config's ``chain.damping`` (null by default) replaces the coefficient
    when given, in the device law's unit, and ``--damping`` / ``--damping-law`` replace
    them for one command."""
    import argparse

    from ssw.cli._device import add_device_options, chain_context
    from ssw.config import load_config

    raw = load_device().to_dict()
    del raw["dissipation"]
    d = device_from_dict(raw)
    assert (d.dissipation_law, d.dissipation) == ("dashpot", 0.0)
    mats = material_set()
    cfg = load_config(None)
    assert cfg["chain"]["damping"] is None and "damping" not in numerics_of(cfg)
    p = chain_params(load_device(), mats, **numerics_of(cfg))
    assert (p.damping_law, p.damping) == ("dashpot", 0.0)
    kk = load_device().with_(dissipation_law="kuwabara_kono", dissipation=1.5e3)
    p = chain_params(kk, mats, **numerics_of(cfg))
    assert (p.damping_law, p.damping) == ("kuwabara_kono", 1.5e3)
    over = {**cfg, "chain": {**cfg["chain"], "damping": 900.0}}
    p = chain_params(kk, mats, **numerics_of(over))
    assert (p.damping_law, p.damping) == ("kuwabara_kono", 900.0)
    parser = argparse.ArgumentParser()
    add_device_options(parser)
    args = parser.parse_args(["--calibration", "none", "--wall", "hertz", "--damping-law",
                              "hunt_crossley", "--damping", "0.02"])
    ctx = chain_context(args)
    assert (ctx.params.damping_law, ctx.params.damping) == ("hunt_crossley", 0.02)


def test_a_conservative_devices_digest_does_not_depend_on_the_laws_name():
    """A calibration records the digest of the device's physics: a device without
    dissipation digests the same whatever its law's name (so calibrations made before the
    device stated its dissipation still apply), and a coefficient changes it."""
    from ssw.calibration.file import device_digest

    mats = material_set()
    base = load_device()
    same = base.with_(dissipation_law="kuwabara_kono")
    damped = base.with_(dissipation=1.0)
    assert device_digest(same, mats) == device_digest(base, mats)
    assert device_digest(damped, mats) != device_digest(base, mats)
    assert "dissipation" not in base.physics_dict() and "dissipation" in damped.physics_dict()


def test_the_striker_s_stated_uncertainty_is_its_prior_not_its_physics():
    """``striker.mass_std`` (kg) is the prior's width of the striker's mass in calibrations
    of records (a striker weighed to 0.1 % is held to 0.1 %); unstated, 5 % of the mass.
    A statement about the device, not its physics: the digest a calibration records of the
    device does not change with it."""
    from ssw.calibration.file import device_digest
    from ssw.calibration.hits import device_priors

    mats = material_set()
    base = load_device()
    weighed = base.with_(striker_mass_std=6e-5)
    assert device_digest(weighed, mats) == device_digest(base, mats)
    bead = chain_params(base, mats).masses[0]  # the thesis striker is a bead
    assert device_priors(chain_params(base, mats)) == {
        "striker_mass": pytest.approx((bead, 0.05 * bead), rel=1e-15)}
    assert device_priors(chain_params(weighed, mats),
                         {"striker_mass": weighed.striker_mass_std}) == {
        "striker_mass": pytest.approx((bead, 6e-5), rel=1e-15)}


# ------------------------------------------------------------------ chain physics it adds
P = chain_params(load_device(), material_set(), steps_per_contact=80)


def test_preload_statics_carry_the_weight_and_the_preload():
    """Static equilibrium: contact j >= 1 carries P + g sum_{k=1..j} m_k, the wall the
    preload plus the weight of beads 1..N-1 (the striker arrives from above)."""
    pre = 4.0
    F = static_contact_forces(P.with_(preload=pre))
    m = P.bead_mass
    assert F[0] == 0.0
    np.testing.assert_allclose(F[1:], pre + STANDARD_GRAVITY * m * np.arange(1, P.n_beads),
                               rtol=1e-12)
    # and the initial state is at rest in that equilibrium: no acceleration below bead 1
    wall = build_wall("hertz", P, 100e6, 0.3)
    run = simulate(P.with_(preload=pre, striker_velocity=1e-9), wall, t_end=2e-5,
                   stop_early=False, record_forces=True)
    f0, f1 = run.forces[0, 0], run.forces[-1, 0]
    np.testing.assert_allclose(f1[1:], f0[1:], rtol=1e-6)


def test_energy_with_a_preload_is_conserved():
    """The preload is a constant force: kinetic + elastic - g sum m u - P u_1 is a conserved
    quantity; the integrator keeps its error small (measured at 80 steps per contact: at
    most 2.1e-4 of the striker's energy during the contacts, 5e-6 after them, 3 ms; the
    contacts exert their laws averaged over each step's relative motion, ssw.chain.impulse,
    which the record's Hertz energy does not follow to O(dt^2); 5e-5 and 2e-7 at 160
    steps). The preload's work matters: a force without its potential term (or the
    reverse) would make the total drift by ~P du_1, ~2 % of the striker's energy here, 70x
    the bound."""
    p = P.with_(preload=6.0)
    run = api.run_chain(p, 80e6, 0.3, "hertz", t_end=3e-3)
    e = run.energy[:, 0]
    ke0 = 0.5 * p.bead_mass * p.striker_velocity**2
    assert np.max(np.abs(e - e[0])) < 3e-4 * ke0
    assert abs(e[-1] - e[0]) < 5e-5 * ke0


def test_the_sensor_reads_its_upper_lower_or_mean_contact():
    wall = build_wall("hertz", P, 120e6, 0.3)
    runs = {r: simulate(P.with_(sensor_reads=r), wall, t_end=2e-3, stop_early=False,
                        record_forces=True) for r in ("mean", "upper", "lower")}
    f = runs["mean"].forces[:, 0]
    s = P.sensor_index
    np.testing.assert_allclose(runs["upper"].sensor[:, 0], f[:, s - 1], rtol=1e-12)
    np.testing.assert_allclose(runs["lower"].sensor[:, 0], f[:, s], rtol=1e-12)
    np.testing.assert_allclose(runs["mean"].sensor[:, 0], 0.5 * (f[:, s - 1] + f[:, s]),
                               rtol=1e-12)


def test_a_batch_of_parameter_sets_equals_separate_runs():
    """Per-scene striker speeds and preloads in one run give each scene's own TOF (the same
    time step: the batch's shortest)."""
    v = np.array([0.3, 0.5, 0.9])
    pre = np.array([0.0, 2.0, 5.0])
    b = Batch.of(P, 3, {"striker_velocity": v, "preload": pre})
    wall = build_wall("hertz", P, np.full(3, 200e6), 0.3)
    from ssw.chain.integrate import time_step

    dt = time_step(b, wall)
    pk, _ = run_peaks(b, wall, dt=dt)
    for i in range(3):
        one, _ = run_peaks(P.with_(striker_velocity=v[i], preload=pre[i]), wall.take([i]),
                               dt=dt)
        assert pk.tof[i] == pytest.approx(float(one.tof[0]), rel=1e-12)


def test_initial_state_is_per_scene():
    b = Batch.of(P, 2, {"preload": [0.0, 10.0]})
    wall = build_wall("hertz", P, np.full(2, 50e6), 0.3)
    u, _ = initial_state(b, wall)
    assert u[1, -1] > u[0, -1] > 0  # the preloaded chain presses deeper


def test_device_file_yaml_is_documented():
    """Every key of the shipped device file has a comment (STYLE.md: every config key says
    what it means)."""
    from ssw.device import DEVICES_DIR

    text = (DEVICES_DIR / "thesis.yaml").read_text()
    data = yaml.safe_load(text)
    for section in ("chain", "sensor", "striker", "plate", "daq_sensor", "dissipation"):
        for key in data[section]:
            line = next(ln for ln in text.splitlines() if ln.strip().startswith(f"{key}:"))
            assert "#" in line or (section == "chain" and key == "bead_material") or (
                section == "daq_sensor" and key == "model"), line
