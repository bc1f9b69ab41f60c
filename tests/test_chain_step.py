"""Derivatives through the time step: the TOF a run computes at the step its parameters give
(``ssw.chain.integrate.time_step``, a fixed fraction of a Hertz contact time at the
striker's speed) moves with the striker's speed and masses through the step as well.

Truth, each a second method:

* the step's own sensitivity column (the scheme differentiated in its explicit ``dt``, the
  record's times ``n dt`` on the dense output) against central differences in the step,
  the parameters fixed, of the samples (each step's), of the dense output at fixed times
  and of TOFs;
* the step's analytic derivative (``ssw.chain.integrate.step_tangent``) against central
  differences of ``time_step`` itself, on both of its branches (the striker on bead 1, the
  last bead on a rigid flat) and on a wall stiffer than a rigid flat;
* the total derivatives of ``tof_derivatives`` and ``sensor_derivatives`` against central
  differences of TOFs and of the dense output of runs at the perturbed parameters, each at
  its own step (what ``ssw tof`` gives at the perturbed value), with the FEM and the Hertz
  walls: within 5e-5. The FEM wall's piecewise-linear law makes TOFs piecewise smooth in
  the parameters (a step's indentation crossing a breakpoint), so its differences converge
  only at small steps: second order at relative steps 3e-6 and 1e-5, which agree within
  1e-5 (at 3e-5 they may be 4e-5 off, at 1e-3 2e-4).
"""

from __future__ import annotations

import numpy as np
import pytest

from ssw.chain.dense import evaluate
from ssw.chain.integrate import simulate, step_tangent, time_step
from ssw.chain.params import Batch, ChainParams
from ssw.chain.run import run_peaks
from ssw.chain.sensitivity import STEP, stencil
from ssw.chain.wall import PowerWall
from ssw.tof import api
from ssw.walls import build_wall

E, NU = 1e8, 0.3
#: NI 9234 sample times (s) over the incident and reflected pulses.
TIMES = np.arange(5e-5, 2.2e-3, 1 / 51200)
#: The requirement: relative to converged central differences.
TOL = 5e-5
#: The thesis device at 0.4 m/s (the last bead on a rigid flat sets the step), and a
#: light striker on a sensor at bead 1 (the striker's contact with it sets the step: its
#: speed, its mass and the sensor's all move the step).
DEVICES = {
    "thesis-0.4": ChainParams(striker_velocity=0.4),
    "light-striker-sensor-1": ChainParams(striker_mass=0.012, sensor_index=1,
                                          sensor_mass=0.035, damping=1.5e3,
                                          damping_law="kuwabara_kono"),
}
MOVERS = ("striker_velocity", "striker_mass", "sensor_mass")


def _wall(name: str, p: ChainParams, E: float = E, **extra):
    return build_wall(name, p, E, NU, **extra)


def _value(p: ChainParams, name: str) -> float:
    b = Batch.of(p, 1)
    return {"striker_velocity": p.striker_velocity, "striker_mass": float(b.masses[0, 0]),
            "sensor_mass": float(b.masses[0, p.sensor_index]), "preload": p.preload}[name]


@pytest.mark.parametrize("wall", ["hertz", "fem", "reduced"])
def test_the_step_column_is_the_derivative_in_the_step(wall):
    """The run's step column (``derivatives=("dt",)`` at a given step) against second-order
    central differences in the step (relative step 1e-6), the parameters fixed, with
    Kuwabara-Kono contacts, on the Hertz, FEM and reduced dynamic (stateful) walls: each
    step's sample within 1e-6 of the largest (measured 5e-8 - 1e-7, falling as h^2: the
    scheme's derivative is exact). The dense output at fixed times and the TOF are C2 and
    C1 only where the step moves the samples' times past them (the quintic's third
    derivative jumps at the samples) and the differences converge slowly: within 2e-4
    (measured 1.6-5.1e-5 and 2e-7 - 2.3e-5). Without the record's times ``n dt`` the TOF's
    would be 1e4 times off."""
    p = ChainParams(damping=1.5e3, damping_law="kuwabara_kono", preload=1.0)
    extra = {"dynamics": "reduced", "soil_density": 1800.0} if wall == "reduced" else {}
    w = _wall("hertz" if wall == "reduced" else wall, p, **extra)
    dt0 = time_step(p, w)
    run = simulate(p, w, dt=dt0, t_end=2.3e-3, stop_early=False, derivatives=(STEP,))
    pk, _ = run_peaks(p, w, dt=dt0, derivatives=(STEP,))
    got = api.sensor_derivatives(E, NU, p, "hertz" if wall == "reduced" else wall,
                                 times=TIMES, derivatives=(STEP,), dt=dt0, t_end=2.3e-3,
                                 **extra)
    st = stencil(STEP, np.array([dt0]), 1e-6, order=2)
    runs = [simulate(p, w, dt=dt0 + o * float(st.h[0]), t_end=2.3e-3, stop_early=False)
            for o in st.offsets]
    n = min(r.sensor.shape[0] for r in runs)
    fd = st.derivative([r.sensor[:n, 0] for r in runs])
    err = np.max(np.abs(run.dsensor[:n, 0, 0] - fd)) / np.max(np.abs(fd))
    assert err < 1e-6, err
    fd = st.derivative([evaluate(r, TIMES)[0][:, 0] for r in runs])
    err = np.max(np.abs(got.dsensor[:, 0, 0] - fd)) / np.max(np.abs(fd))
    assert err < 2e-4, err
    fd = st.derivative([run_peaks(p, w, dt=dt0 + o * float(st.h[0]))[0].tof
                        for o in st.offsets])
    assert abs(pk.dtof[0, 0] / fd[0] - 1) < 2e-4, (pk.dtof[0, 0], fd)


def test_step_tangent_is_the_derivative_of_time_step():
    """``step_tangent`` against central differences of ``time_step``, within 1e-7: the last
    bead on a rigid flat (striker speed only), the striker on bead 1 (its speed, its mass,
    the sensor's mass at bead 1), a wall stiffer than a rigid flat (F = C d^1.4 with C
    proportional to E: the wall's Hertz equivalent at the impact's overlap, which moves with
    the speed and the masses, and E), and a batch whose faster scene sets the step (the
    slower one's step share is 0)."""
    def fd_step(p, make_wall, name, value):
        h = 1e-6 * abs(value)
        out = []
        for s in (1.0, -1.0):
            x = value + s * h
            if name == "E":
                out.append(time_step(p, make_wall(x)))
            else:
                out.append(time_step(Batch.of(p, 1, {name: x}), make_wall(E)))
        return (out[0] - out[1]) / (2 * h)

    cases = [(DEVICES["thesis-0.4"], lambda e: _wall("hertz", DEVICES["thesis-0.4"], e)),
             (DEVICES["light-striker-sensor-1"],
              lambda e: _wall("hertz", DEVICES["light-striker-sensor-1"], e))]
    stiff = ChainParams(striker_velocity=0.4)
    cases.append((stiff, lambda e: PowerWall(np.array([4e3 * e]), np.array([1.4]),
                                             dcoef_dE=np.array([4e3]))))
    for p, make_wall in cases:
        w = make_wall(E)
        names = (*MOVERS, "E")
        got = step_tangent(p, w, time_step(p, w), names)[0]
        for j, name in enumerate(names):
            value = E if name == "E" else _value(p, name)
            fd = fd_step(p, make_wall, name, value)
            scale = max(abs(fd), 1e-300)
            assert abs(got[j] - fd) <= 1e-7 * scale + 1e-22, (name, got[j], fd)
    # the stiff wall and the light striker exercise their branches: E and the masses move
    p, make_wall = cases[2]
    assert step_tangent(p, make_wall(E), time_step(p, make_wall(E)), ("E",))[0, 0] != 0
    p = DEVICES["light-striker-sensor-1"]
    w = _wall("hertz", p)
    assert np.all(step_tangent(p, w, time_step(p, w), MOVERS)[0] != 0)
    # a batch: the faster striker sets the step
    p = ChainParams()
    b = Batch.of(p, 2, {"striker_velocity": np.array([0.5, 0.6])})
    w = build_wall("hertz", p, np.full(2, E), np.full(2, NU))
    dt = time_step(b, w)
    got = step_tangent(b, w, dt, ("striker_velocity",))[:, 0]
    assert got[0] == 0 and got[1] == pytest.approx(
        fd_step(p.with_(striker_velocity=0.6), lambda e: _wall("hertz", p, e),
                "striker_velocity", 0.6), rel=1e-7)


def _tof_fd(p: ChainParams, w, name: str, rel: float) -> float:
    """Second-order central differences of TOFs, each run at its own step."""
    v = _value(p, name)
    st = stencil(name, np.array([v]), rel, order=2)
    tofs = [run_peaks(Batch.of(p, 1, {name: v + o * float(st.h[0])}), w)[0].tof
            for o in st.offsets]
    return float(st.derivative(tofs)[0])


@pytest.mark.parametrize("device", list(DEVICES))
@pytest.mark.parametrize("wall", ["fem", "hertz"])
def test_tof_derivatives_through_the_step_match_converged_central_differences(wall, device):
    """``tof_derivatives``'s striker speed, striker mass and sensor mass (every parameter
    the step reads), and the preload (which it does not), within 5e-5 of converged central
    differences of TOFs at the perturbed values (measured 4e-9 - 4e-7, and 1e-5 for the
    light striker's mass on the FEM wall: its TOF is piecewise smooth, the forward
    derivative the local one); at a fixed step (``dt`` given) the striker speed's
    derivative misses the step's share (1.4-2.4e-4 here, the gap this closes)."""
    p = DEVICES[device]
    w = _wall(wall, p)
    res = api.tof_derivatives(E, NU, p, wall, derivatives=(*MOVERS, "preload"))
    for name in (*MOVERS, "preload"):
        fine, coarse = _tof_fd(p, w, name, 3e-6), _tof_fd(p, w, name, 1e-5)
        assert abs(coarse / fine - 1) < 1e-5, (name, fine, coarse)  # converged
        assert res.method[name] == "forward"
        assert abs(float(res.dtof[name]) / fine - 1) < TOL, (name, res.dtof[name], fine)
    fixed, _ = run_peaks(p, w, dt=res.dt, derivatives=("striker_velocity",))
    gap = abs(fixed.dtof[0, 0] / float(res.dtof["striker_velocity"]) - 1)
    assert gap > 2 * TOL, gap


@pytest.mark.parametrize("wall", ["fem", "hertz"])
def test_sensor_derivatives_through_the_step_match_central_differences(wall):
    """``sensor_derivatives`` at its default step (the parameters' own): the dense output's
    derivatives at NI 9234 sample times with respect to every parameter the step reads,
    within 5e-5 of the largest value of central differences of the dense output of runs at
    the perturbed values, each at its own step (second order, relative step 1e-6; measured
    2e-9 - 3e-8; the derivatives at a fixed step are 5.2-5.5e-5 off)."""
    p = DEVICES["light-striker-sensor-1"]
    got = api.sensor_derivatives(E, NU, p, wall, times=TIMES, derivatives=MOVERS,
                                 t_end=2.3e-3)
    w = _wall(wall, p)
    for j, name in enumerate(MOVERS):
        v = _value(p, name)
        st = stencil(name, np.array([v]), 1e-6, order=2)
        S = [evaluate(simulate(Batch.of(p, 1, {name: v + o * float(st.h[0])}), w,
                               t_end=2.3e-3, stop_early=False), TIMES)[0][:, 0]
             for o in st.offsets]
        fd = st.derivative(S)
        err = np.max(np.abs(got.dsensor[:, 0, j] - fd)) / np.max(np.abs(fd))
        assert err < TOL, (name, err)


def test_a_run_whose_parameters_leave_the_step_carries_no_step_column():
    """E on a physical wall, the preload and the dissipation do not move the step: their
    run carries no extra column (its cost stays), and its derivatives are those at the
    fixed step to the bit; the striker's speed adds the step's column."""
    p = ChainParams()
    w = _wall("hertz", p)
    names = ("E", "preload", "damping")
    pk, run = run_peaks(p, w, derivatives=names)
    fixed, _ = run_peaks(p, w, derivatives=names, dt=run.dt)
    assert run.tangent.names == names
    assert np.array_equal(pk.dtof, fixed.dtof)
    _, run = run_peaks(p, w, derivatives=("E", "striker_velocity"))
    assert run.tangent.names == ("E", "striker_velocity", STEP)
