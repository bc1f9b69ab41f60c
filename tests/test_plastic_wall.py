"""The plastic wall (ssw.walls.plastic) and consecutive hits (ssw.walls.hits): the chain's
energy balance, the elastic limit against Hertz, shakedown, the law's continuity and its
interpolation between tabulated levels against a fresh FEM path."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from ssw.chain.integrate import simulate
from ssw.chain.params import chain_params
from ssw.chain.run import run_peaks
from ssw.constitutive import VonMises
from ssw.device import load_device
from ssw.errors import ConfigError
from ssw.walls import build_wall
from ssw.walls.fem import DOMAIN_ERROR_COEF, FORCE_ERROR_COEF
from ssw.walls.hits import run_hits
from ssw.walls.plastic import Settings, plastic_wall

E, NU, Y = 38.0e6, 0.34, 1.4e6  # PCF 08 with the catalogue's compressive strength as Y
CHEAP = Settings(levels=6, increments=8)


def _params(short: bool = False, **kw):
    dev = load_device("thesis")
    if short:  # a 10-bead chain: half the steps, the same physics
        dev = dev.with_(beads=10, sensor_index=5)
    return replace(chain_params(dev), plate_thickness=0.0, **kw)


def _wall(Y_: float = Y):
    return plastic_wall(_params(), E, NU, soil_model=VonMises(Y_), settings=CHEAP)


def _placed(w, short: bool = False):
    from ssw.chain.statics import static_contact_forces

    F0 = np.array([static_contact_forces(_params(short))[-1]])
    return w.with_history(w.indentation(F0))


def _balance(w, steps: int) -> tuple[float, float]:
    """Largest |E(t) - E(0)| over a hit of the 10-bead chain relative to the striker's
    kinetic energy, with E = chain kinetic + contacts' elastic - gravity potential + wall
    stored + wall dissipated; and the energy the wall dissipated in the hit (J)."""
    p = _params(True, steps_per_contact=steps)
    run = simulate(p, w, record_energy=True)
    e = run.energy[:, 0]
    e = e[np.isfinite(e)]
    ke = 0.5 * p.masses[0] * p.striker_velocity**2
    d_new = max(float(w.d_max0[0]), float(run.peak_wall_indentation[0]))
    lost = w.energies(np.zeros(1), np.array([d_new]))[1] - w.energies(np.zeros(1), w.d_max0)[1]
    return float(np.max(np.abs(e - e[0])) / ke), float(lost[0])


@pytest.mark.long
def test_energy_balance_per_hit():
    """Striker kinetic energy + gravity work = chain kinetic + stored + wall stored + wall
    dissipated over a hit, to 2e-6 of the striker's energy at 1000 steps per contact
    (measured 1.5e-6: the bead contacts' forces, averaged over each step's motion by
    ssw.chain.impulse, follow the record's Hertz energy to O(dt^2)); the residual is the
    integrator's second-order error (it falls 4x when the step halves). Two hits: the first
    on the virgin sample, the second reloading along the first's unloading curve, then
    yielding."""
    w = _placed(_wall(), short=True)
    for hit in range(2):
        e1, lost = _balance(w, 100)
        e2, _ = _balance(w, 200)
        assert lost > 1e-5  # the wall dissipates a share of the hit: a real balance
        assert 3.0 < e1 / e2 < 5.0
        if hit == 1:
            assert _balance(w, 1000)[0] < 2e-6
        run = simulate(_params(True), w)
        w = w.with_history(run.peak_wall_indentation)


def test_elastic_limit_is_hertz():
    """A sample that never yields gives the Hertz wall's law and TOF within the FEM's stated
    error (mesh growth^2 and the finite domain's stiffening)."""
    p = _params()
    w = plastic_wall(p, E, NU, soil_model=VonMises(1e12), settings=CHEAP)
    h = build_wall("hertz", p, E, NU)
    d = w.exact_reach[0] * np.linspace(0.05, 1.0, 40)
    # the domain's stiffening at the largest contact radius a_top (domain = CHEAP.domain a_top)
    bound = np.hypot(FORCE_ERROR_COEF * CHEAP.growth**2, DOMAIN_ERROR_COEF / CHEAP.domain)
    f_h = np.array([h.force(np.array([x]))[0] for x in d])
    rel = np.array([w.force_at(np.array([x]), np.array([x]))[0] for x in d]) / f_h - 1.0
    assert np.sqrt(np.mean(rel**2)) < bound
    # below the largest indentation the law is the same: no hysteresis
    assert w.force_at(d[10:11], d[-1:])[0] == pytest.approx(f_h[10], rel=bound)
    tof_p = run_peaks(p, w)[0].tof[0]
    tof_h = run_peaks(p, h)[0].tof[0]
    assert abs(tof_p / tof_h - 1.0) < bound


def test_elastic_limit_through_the_plate_is_the_elastic_engine():
    """Through the device's 0.4 mm PLA plate, a sample that never yields gives the elastic
    engine's law (substructured, the config's graded mesh: another mesh, assembly and
    contact solver) within the tables' stated error, and the ``fem`` wall's TOF (the chain's
    peak lies inside the fem wall's exact reach) to 1e-2 of that error."""
    from ssw.contact.scene import solve_curve

    p = replace(chain_params(load_device("thesis")), steps_per_contact=100)
    assert p.plate_thickness == 0.4e-3
    w = plastic_wall(p, E, NU, soil_model=VonMises(1e12), settings=CHEAP)
    d = w.exact_reach[0] * np.linspace(0.1, 1.0, 19)
    cfg = {"delta_max": float(d[-1]), "steps": 40, "plate_diameter": p.plate_diameter,
           "interface": p.plate_interface}
    el, _ = solve_curve((E, NU), (p.plate_E, p.plate_nu), p.plate_thickness, p.bead_radius,
                        cfg)
    bound = np.hypot(FORCE_ERROR_COEF * CHEAP.growth**2, DOMAIN_ERROR_COEF / CHEAP.domain)
    f_w = np.array([w.force_at(np.array([x]), np.array([x]))[0] for x in d])
    rel = f_w / np.interp(d, el.delta, el.force) - 1.0
    assert np.sqrt(np.mean(rel**2)) < bound
    fem = build_wall("fem", p, E, NU)
    run = run_peaks(p, fem)
    assert run[1].peak_wall_indentation[0] < fem.exact_reach[0]
    assert abs(run_peaks(p, w)[0].tof[0] / run[0].tof[0] - 1.0) < 0.1 * bound


def test_shakedown():
    """The second hit adds less permanent set and dissipates less than the first."""
    res = run_hits(_params(), _wall(), 2)
    inc, lost = res.set_increment[:, 0], res.dissipated[:, 0]
    assert inc[0] > 0 and lost[0] > 0
    assert 0 <= inc[1] < inc[0]
    assert 0 <= lost[1] < lost[0]
    assert np.all(np.diff(res.permanent_set[:, 0]) >= 0)


def test_force_continuous_at_dmax_and_zero_below_residual():
    w = _wall()
    reach = w.exact_reach[0]
    for dm in reach * np.array([0.03, 0.2, 0.37, 0.61, 0.95, 1.2]):
        d_max = np.array([dm])
        FL = w.force_at(d_max, d_max)[0]
        for eps in (1e-6, 1e-9):
            below = w.force_at(d_max * (1 - eps), d_max)[0]
            assert below == pytest.approx(FL, rel=50 * eps * 1.5 + 1e-12)
        d_res = w.residual_indentation(d_max)[0]
        assert 0 <= d_res < dm
        assert np.all(w.force_at(np.linspace(0, d_res, 7), np.full(7, dm)) == 0.0)
        # the energies against the work of the law's own forces (trapezoid quadrature,
        # exact to ~1e-11 for these piecewise linear laws): loading along the virgin curve
        # does stored + dissipated; the unloading curve gives back what is stored, at d_max
        # and half-way down
        x = np.linspace(0.0, dm, 200_001)
        virgin_work = np.trapezoid(w.force_at(x, x), x)
        stored, lost = (e[0] for e in w.energies(d_max, d_max))
        for d in (dm, 0.5 * (d_res + dm)):
            xu = np.linspace(d_res, d, 200_001)
            released = np.trapezoid(w.force_at(xu, np.full(xu.size, dm)), xu)
            assert w.energies(np.array([d]), d_max)[0][0] == pytest.approx(released, rel=1e-9)
        assert stored + lost == pytest.approx(virgin_work, rel=1e-9)
        assert lost >= 0
    # the unloading law is monotone in d
    d_max = np.full(200, 0.5 * reach)
    F = w.force_at(np.linspace(0, 0.5 * reach, 200), d_max)
    assert np.all(np.diff(F) >= 0)


def test_interpolated_level_matches_a_fresh_fem_path():
    """Between two tabulated levels the interpolated unloading curve (normalized variable)
    matches an FEM loading-unloading path computed at that very d_max."""
    from ssw.contact.mesh import MeshSettings, build_mesh
    from ssw.contact.plastic import solve_path

    w = _wall()
    p = _params()
    levels = w.d_m[0]
    dm = 0.5 * (levels[2] + levels[3])
    top = w.exact_reach[0]
    a = np.sqrt(p.bead_radius * top)
    mesh = build_mesh(0.0, 0.0, MeshSettings(CHEAP.domain * a, CHEAP.domain * a,
                                             a / CHEAP.fine, CHEAP.growth, 8.0 * a, 1))
    n = CHEAP.increments
    c = solve_path(mesh, E, NU, VonMises(Y), p.bead_radius, dm * np.arange(1, n + 1) / n,
                   unload=True)
    down = c.branch == 1
    d_res = w.residual_indentation(np.array([dm]))[0]
    assert d_res == pytest.approx(c.residual_indentation, rel=0.05)
    f_wall = w.force_at(c.delta[down], np.full(down.sum(), dm))
    f_peak = float(c.force[c.branch == 0][-1])
    assert np.max(np.abs(f_wall - c.force[down])) < 0.03 * f_peak


def test_tof_hits_cli(capsys):
    """``ssw tof --hits``: one row per hit, the sample's history carried (the set grows);
    through the device's plate the sample takes less permanent set; a plate that may leave
    the sample (the unilateral interface) is refused."""
    import json

    from ssw.cli import main

    args = ["tof", "--hits", "2", "--soil-material", "pcf08", "--soil-model", "von-mises",
            "--plastic-levels", "6", "--plastic-increments", "8", "--calibration", "none"]
    assert main([*args, "--plate-thickness", "0", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    rows = res["hits"]
    assert [r["hit"] for r in rows] == [1, 2]
    assert res["soil_model"]["yield_stress"] == Y  # the library's strength, not fitted
    assert rows[1]["permanent_set"] >= rows[0]["permanent_set"] > 0
    # its checks: small strain and the plastic law's reach at the largest indentation; the
    # yield is the plastic model's own (ssw.validity)
    assert {e["check"] for e in res["validity"]} == {"contact_strain", "wall_reach"}
    assert set(res["checks_skipped"]) == {"sample_yield", "plate_yield"}
    assert main([*args, "--plate-thickness", "4e-4", "--json"]) == 0
    plated = json.loads(capsys.readouterr().out)
    assert plated["plate_thickness"] == 4e-4 and plated["plate_material"] == "pla"
    assert 0 < plated["hits"][0]["permanent_set"] < rows[0]["permanent_set"]
    assert main([*args, "--plate-thickness", "4e-4", "--plate-interface", "unilateral"]) != 0
    assert "interface" in capsys.readouterr().err


def test_models_per_scene_and_calibration_refusals(capsys):
    """A wall of several scenes takes one model each (a count that fits neither one nor the
    scenes is refused); ``ssw calibrate --soil-model`` takes the config's samples (their
    materials give the strengths) and writes no calibration file."""
    from ssw.cli import main
    from ssw.errors import ConfigError

    p = _params()
    with pytest.raises(ConfigError, match="one per scene"):
        plastic_wall(p, [E, 2 * E, 3 * E], NU, soil_model=(VonMises(Y), VonMises(2 * Y)),
                     settings=CHEAP)
    w = plastic_wall(p, [E, E], NU, soil_model=(VonMises(1e12), VonMises(Y)), settings=CHEAP)
    d = w.exact_reach * 0.9
    f_el, f_pl = (w.take(np.array([i])).force_at(d[i:i + 1], d[i:i + 1])[0] for i in (0, 1))
    assert f_pl < f_el  # the yielding scene is the softer one at the same indentation
    assert main(["calibrate", "--reference", "38e6,0.34,1.78e-3", "--free",
                 "striker_velocity", "--soil-model", "von-mises"]) != 0
    assert "--from-config" in capsys.readouterr().err
    assert main(["calibrate", "--from-config", "--soil-model", "von-mises", "--output",
                 "x.json"]) != 0
    assert "--output" in capsys.readouterr().err


def test_yielding_plate_on_an_elastic_sample():
    """A yielding PLA plate (the library's von Mises strength) on an elastic sample, hit
    twice: the plate alone keeps a permanent set, split into the interface's depth (its
    permanent bending) and its thinning; the second hit dissipates less than the first
    (shakedown); with the plate's yield stress out of reach the wall is the elastic plate's
    (the virgin law of a plastic sample that never yields, to the tables' interpolation)."""
    from ssw.constitutive import model_of_strength
    from ssw.materials import material_set

    p = chain_params(load_device("thesis"))
    pla = model_of_strength("von-mises", material_set("realistic")["pla"].strength)
    w = plastic_wall(p, E, NU, plate_model=pla, settings=CHEAP)
    res = run_hits(p, w, 2)
    assert res.permanent_set[0, 0] > 0 and res.static_set[0] >= 0
    np.testing.assert_allclose(res.interface_set + res.plate_thinning, res.permanent_set,
                               rtol=1e-12)
    assert res.plate_thinning[0, 0] > 0 and res.interface_set[0, 0] > 0
    assert 0 < res.dissipated[1, 0] < res.dissipated[0, 0]
    stiff = plastic_wall(p, E, NU, plate_model=VonMises(1e12), settings=CHEAP)
    ref = plastic_wall(p, E, NU, soil_model=VonMises(1e12), settings=CHEAP)
    d = np.linspace(0.1, 1.0, 10) * float(ref.exact_reach[0]) * 0.5
    f, f_ref = stiff.force(d), ref.force(d)
    assert np.all(np.isfinite(f)) and np.max(np.abs(f / f_ref - 1)) < 0.03
    with pytest.raises(ConfigError, match="plate_model"):
        plastic_wall(replace(p, plate_thickness=0.0), E, NU, plate_model=pla, settings=CHEAP)
    with pytest.raises(ConfigError, match="soil_model"):
        plastic_wall(p, E, NU, settings=CHEAP)
