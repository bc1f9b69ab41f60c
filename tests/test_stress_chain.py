"""Stress grid of the chain dynamics: soil E 1 MPa..10 GPa, nu 0.49-0.5, striker
velocities 0.05-3 m/s, chains of 5-200 beads, invalid inputs.

Each case either meets its tolerance against independent truth or stops with a clear
``ssw`` error; never NaN, never a silently wrong TOF. Truth used:

* Energy: without damping the total energy (kinetic + Hertz ``2/5 A d^2.5`` + wall - gravity
  work) is a constant of motion; velocity Verlet keeps it to O(dt^2) without drift. The
  tolerance, 1e-3 of the striker's kinetic energy, is what a TOF to 0.1 % needs (the wave
  speed goes as energy^(1/10) through ``F_m^(1/6)``, Nesterenko 2001).
* Ordering: a stiffer wall (larger ``E* = 1/((1-nu_b^2)/E_b + (1-nu^2)/E)``) returns the
  pulse sooner, so TOF decreases with soil E and with nu at fixed E, and no elastic soil
  is faster than the rigid wall (``E -> inf``).
* Convergence: halving the time step cuts the energy error by 4 (second order).
* Speed limit: no disturbance outruns the chain's long-wave sound speed at the largest
  force (Nesterenko 2001), which bounds the TOF from below.

A physically valid case that ssw refuses is a failure; a refusal is checked for its
stated reason (the field it names).
"""

from __future__ import annotations

import numpy as np
import pytest

from ssw.chain.integrate import simulate
from ssw.chain.params import ChainParams
from ssw.chain.tof import pick_peaks
from ssw.cli import main as ssw_main
from ssw.errors import ConfigError
from ssw.tof import api
from ssw.walls import build_wall

SOIL_E = np.geomspace(1.0e6, 1.0e10, 5)  # Pa, 1 MPa .. 10 GPa
SOIL_NU = np.array([0.49, 0.5])
ENERGY_TOL = 1e-3  # of the striker's kinetic energy


#: Seconds any one case may take before it counts as a hang (the slowest takes ~5 s).
CASE_TIMEOUT_S = 120


pytestmark = pytest.mark.usefixtures("no_hang")  # tests/conftest.py


def _grid() -> tuple[np.ndarray, np.ndarray]:
    """Every (E, nu) of the grid, flat: E varies fastest."""
    E, nu = np.meshgrid(SOIL_E, SOIL_NU)
    return E.ravel(), nu.ravel()


def _run(params: ChainParams, E: np.ndarray, nu: np.ndarray):
    """Batched run with the energy record; (TOF s, max energy error / striker KE)."""
    run = simulate(params, build_wall("hertz", params, E, nu), record_energy=True)
    e = run.energy
    assert np.all(np.isfinite(e[0])), "energy is not finite at t = 0"
    ke0 = 0.5 * params.masses[0] * params.striker_velocity**2
    # A scene's record is NaN after it stopped (its reflected wave has passed the sensor).
    err = np.nanmax(np.abs(e - e[0]), axis=0) / ke0
    return pick_peaks(run.t, run.sensor).tof, err


CASES = [
    pytest.param(dict(striker_velocity=0.05), id="v0.05"),
    pytest.param(dict(striker_velocity=3.0), id="v3"),
    pytest.param(dict(n_beads=5, sensor_index=2), id="5beads"),
    pytest.param(dict(n_beads=200, sensor_index=100, striker_velocity=0.05), id="200beads-v0.05"),
    pytest.param(dict(n_beads=200, sensor_index=100, striker_velocity=3.0), id="200beads-v3"),
]


@pytest.mark.parametrize("case", CASES)
def test_grid_conserves_energy_and_orders_tof(case: dict) -> None:
    """All 10 soils of the grid in one batched run: energy within 1e-3 of the striker's,
    finite positive TOF decreasing with E and nu, never faster than a rigid wall."""
    params = ChainParams(**case)
    E, nu = _grid()
    tof, err = _run(params, E, nu)
    assert np.all(np.isfinite(tof)) and np.all(tof > 0), tof
    assert np.all(err < ENERGY_TOL), err
    tof = tof.reshape(SOIL_NU.size, SOIL_E.size)
    assert np.all(np.diff(tof, axis=1) < 0), "TOF must fall as the soil stiffens"
    assert np.all(tof[1] <= tof[0]), "nu 0.5 is stiffer than 0.49 at equal E"
    rigid = api.tof(1.0e9, 0.3, params, "rigid")
    assert np.all(tof >= rigid * (1 - 1e-9))


def test_energy_error_is_second_order_at_the_extremes() -> None:
    """Halving dt divides the energy error by 4 +- 1.2 at 3 m/s on 1 MPa and 10 GPa soils."""
    E, nu = np.array([1.0e6, 1.0e10]), np.array([0.5, 0.5])
    base = dict(n_beads=10, sensor_index=5, striker_velocity=3.0, gravity=False)
    _, e1 = _run(ChainParams(**base, steps_per_contact=80), E, nu)
    _, e2 = _run(ChainParams(**base, steps_per_contact=160), E, nu)
    np.testing.assert_allclose(e1 / e2, 4.0, atol=1.2)


def test_long_slow_chain_on_soft_soil_solves() -> None:
    """200 beads at 0.05 m/s on 1 MPa soil, a physically valid case: it must solve (a
    refusal is a failure), though its reflected wave passes the sensor only after t_max:
    the soft soil barely loads (its force peaks ~55 ms after the hit), so the early-stop
    rule closes the record at ~0.11 s and ssw.tof.api extends the run (doubling t_max).
    Its TOF meets independent truth:

    * energy conserved within ENERGY_TOL of the striker's kinetic energy (over the first
      30 ms: the incident wave, its reflection and their return to the sensor);
    * no faster than physics allows: no disturbance outruns the long-wave sound speed of a
      Hertzian chain at the largest force, ``c0(F) = 2R sqrt(k/m)``, ``k = dF/dd = 3/2
      A^(2/3) F^(1/3)`` (Nesterenko 2001; Daraio et al. 2006: ``0.9314 (4 E^2 F / (a^2
      rho^3 (1-nu^2)^2))^(1/6)``), so ``TOF >= 2 L / (1.05 c0(F_max))``, L the path from the
      sensor's centre to the wall, F_max <= the chain's weight on the wall plus twice the
      two-bead impact force (a wave never exceeds its impact, a reflection at most doubles
      it), 1.05 the discrete chain's excess over the long-wave limit (< 2 %,
      tests/test_chain_physics.py). Measured: TOF 7.11 ms, bound 5.6 ms; a pick of the
      incident pulse's tail (5.3 ms after the hit, TOF 1.2 ms) would fail it.
    """
    params = ChainParams(n_beads=200, sensor_index=100, striker_velocity=0.05)
    E, nu, v = np.array([1.0e6]), np.array([0.5]), params.striker_velocity
    tof = api.tof(E, nu, params)  # t_max 20 ms: extended, never refused
    run = simulate(params, build_wall("hertz", params, E, nu), t_end=0.03, stop_early=False,
                   record_energy=True)
    e = run.energy[:, 0]
    assert np.max(np.abs(e - e[0])) < ENERGY_TOL * 0.5 * params.masses[0] * v**2
    R, m, A = params.bead_radius, params.bead_mass, params.bead_coefficient
    d_impact = (5.0 * (m / 2.0) * v**2 / (4.0 * A)) ** 0.4  # m, Johnson 1985 eq. 11.22
    f_max = params.g * m * (params.n_beads - 1) + 2.0 * A * d_impact**1.5  # N
    c0 = 2.0 * R * np.sqrt(1.5 * A ** (2.0 / 3.0) * f_max ** (1.0 / 3.0) / m)  # m/s
    path = (params.n_beads - 1 - params.sensor_index) * 2.0 * R + R  # m
    assert np.isfinite(tof[0]) and tof[0] >= 2.0 * path / (1.05 * c0), (tof, 2 * path / c0)


@pytest.mark.parametrize(("kwargs", "soil", "field"), [
    pytest.param({}, (np.nan, 0.3), "soil_E", id="nan-E"),
    pytest.param({}, (-1.0e6, 0.3), "soil_E", id="negative-E"),
    pytest.param({}, (1.0e7, 0.6), "soil_nu", id="nu-0.6"),
    pytest.param({"striker_velocity": 0.0}, (1.0e7, 0.3), "striker_velocity", id="v0"),
    pytest.param({"n_beads": 2}, (1.0e7, 0.3), "beads", id="2beads"),
    pytest.param({"steps_per_contact": 1}, (1.0e7, 0.3), "steps_per_contact", id="spc1"),
])
def test_invalid_inputs_raise_config_error(kwargs: dict, soil: tuple, field: str) -> None:
    """Inputs outside the physics raise ConfigError naming the field, before any run."""
    with pytest.raises(ConfigError, match=field):
        api.tof(soil[0], soil[1], ChainParams(**kwargs))


@pytest.mark.parametrize("argv", [
    ["tof", "--soil-E", "nan", "--soil-nu", "0.3", "--law", "hertz"],
    ["contact", "--soil-E", "nan", "--soil-nu", "0.3", "--plate-thickness", "0",
     "--steps", "5"],
])
def test_cli_refuses_nan(argv: list[str], tmp_path, capsys) -> None:
    """`ssw tof` / `ssw contact` with a NaN modulus: exit 2 and a one-line ssw error that
    names the field and the value (not any exit 2: a usage error exits 2 as well)."""
    if argv[0] == "contact":
        argv = [*argv, "--output", str(tmp_path / "c.h5")]
    assert ssw_main(argv) == 2
    err = capsys.readouterr().err
    assert "error" in err and "Traceback" not in err
    assert "soil_E = " in err and "nan" in err and "not allowed" in err, err
    assert not (tmp_path / "c.h5").exists()
