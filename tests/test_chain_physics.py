"""Chain dynamics against independent truth: conservation, Nesterenko's law, convergence
order, the rigid-wall mirror image, static equilibrium."""

from __future__ import annotations

import numpy as np
import pytest

from ssw.chain.integrate import simulate
from ssw.chain.params import ChainParams
from ssw.chain.statics import initial_state, static_contact_forces
from ssw.chain.wall import PowerWall
from ssw.tof import api
from ssw.walls import build_wall

BASE = ChainParams(gravity=False, striker_velocity=0.5)


def _energy_error(spc: int) -> float:
    p = BASE.with_(n_beads=10, sensor_index=5, steps_per_contact=spc)
    run = simulate(p, build_wall("hertz", p, 100e6, 0.3), t_end=1.0e-3, stop_early=False,
                   record_energy=True)
    e = run.energy[:, 0]
    return float(np.max(np.abs(e - e[0])) / e[0])


def test_energy_conserved_to_1e6_and_error_is_second_order():
    """Without dissipation and gravity the total energy (kinetic + Hertz 2/5 A d^2.5) is a
    constant of motion; the integrator keeps it to O(dt^2) without drift (measured
    1.6e-5, 4.1e-6, 1.0e-6 at 300, 600, 1200 steps per contact: slopes 1.99; the contacts'
    forces, averaged over each step's motion (ssw.chain.impulse), differ from the record's
    Hertz energy's gradient by O(dt^2))."""
    e300, e600, e1200 = (_energy_error(k) for k in (300, 600, 1200))
    assert e1200 < 2e-6
    assert np.log2(e300 / e600) == pytest.approx(2.0, abs=0.25)
    assert np.log2(e600 / e1200) == pytest.approx(2.0, abs=0.25)


def test_dissipation_removes_energy():
    """A dashpot in the contacts can only remove energy (dE/dt = -c sum dv^2 <= 0), and
    what it removes is its work: the record's total (mechanical energy plus the dashpots'
    work, ``run.dissipated``) stays constant to the integrator's error, which falls as
    dt^2 (the work is summed by the trapezoidal rule of the dashpot's power)."""
    drift = []
    for spc in (100, 200):
        p = BASE.with_(n_beads=10, sensor_index=5, damping=5.0, steps_per_contact=spc)
        run = simulate(p, build_wall("hertz", p, 100e6, 0.3), t_end=1.0e-3,
                       stop_early=False, record_energy=True)
        total, lost = run.energy[:, 0], run.dissipated[:, 0]
        e = total - lost
        assert e[-1] < 0.97 * e[0]
        assert np.all(np.diff(e) < 1e-6 * e[0])
        drift.append(np.max(np.abs(total - total[0])) / lost[-1])
    assert drift[1] < 1e-3 and drift[0] / drift[1] > 3.0, drift


def _wave(v: float) -> tuple[float, float]:
    """Solitary wave speed (m/s) and peak force (N) between contacts 30 and 50 of a long chain."""
    p = BASE.with_(n_beads=64, sensor_index=32, striker_velocity=v, steps_per_contact=60)
    w = build_wall("rigid", p, 1e9, 0.3)
    # time for the wave to reach contact 55 at a speed of at least 200 m/s
    run = simulate(p, w, t_end=55 * 2 * p.bead_radius / 200.0 * v ** (-0.2),
                   stop_early=False, record_forces=True)
    F = run.forces[:, 0, :]
    j1, j2 = 30, 50
    times, peaks = [], []
    for j in (j1, j2):
        k = int(np.argmax(F[:, j]))
        ym, y0, yp = F[k - 1, j], F[k, j], F[k + 1, j]
        off = 0.5 * (ym - yp) / (ym - 2 * y0 + yp)
        times.append((k + off) * run.dt)
        peaks.append(y0)
    speed = (j2 - j1) * 2 * p.bead_radius / (times[1] - times[0])
    return speed, float(np.mean(peaks))


def test_nesterenko_solitary_wave_speed():
    """V_s = 0.6802 [2E/(a rho^1.5 (1-nu^2))]^(1/3) F_m^(1/6) (Daraio et al. 2006): slope 1/6
    over two decades of force, and the level within 2 % (a discrete chain runs slightly
    faster than the long-wave limit, by the same share at every amplitude)."""
    p = BASE
    a = 2 * p.bead_radius
    coef = 0.6802 * (2 * p.bead_E / (a * p.bead_density**1.5 * (1 - p.bead_nu**2))) ** (1 / 3)
    speeds, forces = zip(*(_wave(v) for v in (0.05, 0.5, 5.0)), strict=True)
    slope = np.polyfit(np.log(forces), np.log(speeds), 1)[0]
    assert slope == pytest.approx(1 / 6, abs=0.003)
    ratio = np.array(speeds) / (coef * np.array(forces) ** (1 / 6))
    assert np.all(np.abs(ratio - 1) < 0.02)
    assert np.ptp(ratio) < 0.003


def test_rigid_wall_is_the_mirror_image_of_a_symmetric_collision():
    """A bead on a rigid flat obeys F = 2^1.5 A u^1.5 = A (2u)^1.5: the wall is the mirror
    plane of a chain of 2N beads hit at both ends with opposite speeds. The wall force of
    the N-bead chain equals the middle contact force of the 2N chain up to the step's
    treatment of a contact's opening and closing (a bead pair's law is averaged over the
    step's motion, ssw.chain.impulse; a wall's is not): measured 7.1e-5, 3.4e-5, 9.0e-6 of
    the peak force at 100, 200, 400 steps per contact, so within 1.5e-4 and falling at
    least 1.8x when the step halves."""
    diffs = []
    for spc in (100, 200):
        p = BASE.with_(n_beads=8, sensor_index=4, steps_per_contact=spc)
        run_w = simulate(p, build_wall("rigid", p, 1e9, 0.3), t_end=1.2e-3,
                         stop_early=False, record_forces=True)
        p2 = p.with_(n_beads=16, sensor_index=8)
        far = PowerWall(np.array([1.0]), np.array([1.5]))  # never touched: the chain moves up
        u, v = initial_state(p2, far)
        v[0, -1] = -p.striker_velocity
        run_m = simulate(p2, far, t_end=1.2e-3, dt=run_w.dt, stop_early=False,
                         record_forces=True, initial=(u, v))
        f_wall = run_w.forces[:, 0, -1]
        f_mid = run_m.forces[:, 0, 7]
        diffs.append(np.max(np.abs(f_wall - f_mid)) / np.max(f_wall))
    assert diffs[0] < 1.5e-4 and diffs[1] < diffs[0] / 1.8, diffs


def test_hertz_wall_tends_to_the_rigid_wall():
    """E_soil -> infinity: the Hertz wall's 1/E* loses the soil term; TOF -> rigid TOF."""
    p = ChainParams(striker_velocity=0.5246)
    t_rigid = api.tof(1e9, 0.3, p, "rigid")
    t_stiff = api.tof(1e18, 0.3, p, "hertz")
    assert t_stiff == pytest.approx(t_rigid, rel=1e-6)
    assert api.tof(1e12, 0.3, p, "hertz") > t_rigid


def test_gravity_state_is_static_equilibrium():
    """Beads 1..N-1 rest: each contact carries the weight above it, the wall the whole
    weight (except the striker). Were the initial state not in equilibrium every contact
    would ring from t = 0; in equilibrium only the striker's arrival disturbs the chain,
    and in 0.2 ms that disturbance (linear sound speed ~300 m/s at ~1 N precompression)
    does not reach beyond bead 6."""
    p = ChainParams(striker_velocity=1e-9, n_beads=12, sensor_index=6)
    F = static_contact_forces(p)
    w = p.g * p.bead_mass
    np.testing.assert_allclose(F[1:], w * np.arange(1, 12), rtol=1e-12)
    run = simulate(p, build_wall("hertz", p, 50e6, 0.3), t_end=2e-4, stop_early=False,
                   record_forces=True)
    drift = np.abs(run.forces[:, 0, 6:] - F[6:])
    assert np.max(drift) < 1e-10 * F[-1]


def test_batched_verlet_agrees_with_scipy_dop853():
    """Two methods, one model: the default Verlet TOF is within 1e-4 of an adaptive
    8th-order solve (scipy DOP853, rtol 1e-9), with gravity and a soft Hertz wall."""
    from ssw.chain.baseline import solve_dop853

    p = ChainParams(striker_velocity=0.5247)
    w = build_wall("hertz", p, 38e6, 0.34)
    ours = float(api.tof(38e6, 0.34, p))
    ref = solve_dop853(p, w, t_end=2.6e-3, rtol=1e-9, atol=1e-15)
    assert ours == pytest.approx(ref.tof, rel=1e-4)
