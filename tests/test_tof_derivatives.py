"""The TOF's derivatives: forward sensitivities of the discrete scheme against central
differences of converged TOFs (the same runs at perturbed parameters, a second method), the
methods' labels, and the sensor waveform's derivatives.

Truth: fourth-order central differences (one-sided at a bound of 0) of TOFs, each computed
at the step its parameters give (the step moves with the striker's speed and masses, as a
run of ``ssw tof`` at the perturbed value does), at two relative steps (1e-4, 2e-4); the TOF
is smooth in its parameters to ~1e-10 (tests/test_chain_smooth.py), so the differences
converge: the two steps agree within 1e-4 (the finer one's truncation is 1/15 of their
difference) and the finer one is taken. The forward derivative must match within 1e-4
relative (the required bound; measured 1e-9 - 2e-5), relative to the parameter's largest
derivative over the three scenes (a derivative near 0, at a TOF's extremum in that
parameter, has no relative accuracy of its own).
"""

from __future__ import annotations

import numpy as np
import pytest

from ssw.chain.params import Batch, ChainParams
from ssw.chain.run import run_peaks
from ssw.chain.sensitivity import PARAMETERS, stencil
from ssw.tof import api
from ssw.walls import build_wall

#: PCF 08, 15, 30 of the thesis's Table 2.
E3 = np.array([38e6, 123e6, 445e6])
NU3 = np.array([0.34, 0.33, 0.30])
TOL = 1e-4


def _central(params: ChainParams, make_wall, name: str, dt: float | None, rel: float
             ) -> np.ndarray:
    """Fourth-order differences of TOFs at the fixed step ``dt``, or (None) each at its own
    step (the test's own: each perturbed TOF from its own run)."""
    w0 = make_wall(E3)
    b0 = Batch.of(params, E3.size)
    values = {"E": E3, "striker_velocity": b0.striker_velocity, "preload": b0.preload,
              "striker_mass": b0.masses[:, 0],
              "sensor_mass": b0.masses[:, params.sensor_index],
              "damping": np.full(E3.size, params.damping)}
    st = stencil(name, values[name], rel)
    tofs = []
    for o in st.offsets:
        x = values[name] + o * st.h
        if name == "E":
            pk, _ = run_peaks(params, make_wall(x), dt=dt)
        elif name == "damping":
            pk, _ = run_peaks(params.with_(damping=float(x[0])), w0, dt=dt)
        else:
            pk, _ = run_peaks(Batch.of(params, E3.size, {name: x}), w0, dt=dt)
        tofs.append(pk.tof)
    return st.derivative(tofs)


def _check(params: ChainParams, make_wall, names: tuple[str, ...]) -> dict[str, float]:
    pk, _ = run_peaks(params, make_wall(E3), derivatives=names)
    worst = {}
    for j, name in enumerate(names):
        fine = _central(params, make_wall, name, None, 1e-4)
        coarse = _central(params, make_wall, name, None, 2e-4)
        # the differences converged: at twice the step the fourth-order truncation is 16x
        # larger, so the finer one errs by ~1/15 of their difference
        scale = np.max(np.abs(fine))  # relative to the parameter's largest derivative
        assert np.all(np.abs(coarse - fine) < TOL * scale), (name, coarse, fine)
        err = np.abs(pk.dtof[:, j] - fine) / scale
        worst[name] = float(err.max())
        assert np.all(err < TOL), (name, pk.dtof[:, j], fine)
    return worst


@pytest.mark.parametrize("device", [
    pytest.param({}, id="thesis-device"),
    pytest.param({"preload": 5.0, "damping": 2.0, "sensor_reads": "upper"},
                 id="preload-dashpot-upper", marks=pytest.mark.slow),
    pytest.param({"preload": 2.0, "damping": 1.5e3, "damping_law": "kuwabara_kono"},
                 id="preload-kuwabara-kono"),
    pytest.param({"damping": 2.5e-2, "damping_law": "hunt_crossley", "sensor_reads": "lower",
                  "striker_mass": 0.012}, id="hunt-crossley-lower-light-striker"),
])
def test_forward_derivatives_of_the_hertz_wall_match_central_differences(device):
    """Every parameter (E, striker speed, preload, sensor and striker masses, the
    dissipation coefficient) on the thesis device (preload and dissipation 0: one-sided
    differences), on a device with a preload, a dashpot and the sensor read at its upper
    contact, with a preload and Kuwabara-Kono contacts, and with Hunt-Crossley contacts,
    the sensor read at its lower contact and a light striker (whose contact with bead 1,
    not the last bead's on a rigid flat, sets the step)."""
    p = ChainParams().with_(**device)
    _check(p, lambda E: build_wall("hertz", p, E, NU3), tuple(PARAMETERS))


@pytest.mark.parametrize("device", [
    pytest.param({"damping": 1.0}, id="dashpot"),
    pytest.param({"damping": 2.5e-2, "damping_law": "hunt_crossley"}, id="hunt-crossley",
                 marks=pytest.mark.slow),
])
def test_forward_derivatives_of_the_reduced_dynamic_wall_match_central_differences(device):
    """The reduced dynamic wall (a stateful wall with an exact tangent: its quasi-static law,
    dashpot and participating masses differentiated line by line, the step's explicit
    ``dt`` too), soil 1800 kg/m^3, with a contact dashpot or Hunt-Crossley contacts (whose
    damping at the wall follows the wall's force, the soil's dashpot and inertia
    included): E (through the law and the soil's impedance), the striker's speed (which
    moves the step), the sensor's mass and the dissipation coefficient."""
    p = ChainParams(**device)
    _check(p, lambda E: build_wall("hertz", p, E, NU3, dynamics="reduced",
                                   soil_density=1800.0),
           ("E", "striker_velocity", "sensor_mass", "damping"))


def test_dE_of_the_fit_wall_follows_the_k_table_interpolant():
    """The fit wall's E-dependence runs through the K table's PCHIP interpolant (K and the
    power law's C and n vary with E here): its dTOF/dE matches central differences."""
    from ssw.fit.table import KTable

    Eg = np.array([20e6, 60e6, 150e6, 400e6, 900e6])
    nug = np.array([0.3, 0.35])
    lnE = np.log(Eg)
    K = np.stack([1.3 + 0.1 * np.sin(lnE) + 0.05 * j for j in range(2)])
    n = np.stack([1.45 + 0.02 * np.cos(lnE) + 0.01 * j for j in range(2)])
    ones = np.ones((2, Eg.size))
    res = {"rms_rel_residual": 0 * ones, "max_rel_residual": 0 * ones}
    # the power law F = C d^n with F(1e-4 m) = K x Hertz's (the table's reference
    # indentation is the fit ranges' upper end, 1e-4 m)
    A_H = 4 / 3 * Eg[None, :] / (1 - nug[:, None] ** 2) * np.sqrt(9.53e-3)
    C = K * A_H * 1e-4**1.5 / 1e-4**n
    table = KTable("pla", 0.4e-3, 9.53e-3, Eg, nug,
                   {"k_hertz": {"K": K}, "power": {"C": C, "n": n}},
                   {"k_hertz": res, "power": res}, 1e-7 * ones, 1e-4 * ones)
    for law in ("k_hertz", "power"):
        p = ChainParams(fit_law=law)
        res_d = api.tof_derivatives(E3, NU3, p, "fit", derivatives=("E",), k_table=table)
        assert res_d.method["E"] == "forward"
        fine = _central(p, lambda E, p=p: build_wall("fit", p, E, NU3, k_table=table),
                        "E", res_d.dt, 1e-4)
        assert np.all(np.abs(res_d.dtof["E"] / fine - 1) < TOL), (law, res_d.dtof, fine)


def test_dE_of_the_fem_wall_by_implicit_differentiation():
    """The ``fem`` wall's law is differentiated in E through its condensed contact problem
    (piece by piece, at each active set): its dF/dE matches central differences of freshly
    built laws to 1e-8, and dTOF/dE matches central differences of TOFs within 1e-4 on
    123 and 445 MPa (measured 1.4e-5 and 2e-10; on 38 MPa the differences do not converge
    below 1e-5: the piecewise-linear law's breakpoints)."""
    p = ChainParams()
    E2, nu2 = E3[1:], NU3[1:]
    w = build_wall("fem", p, E2, nu2, with_dE=True)
    d = np.linspace(0.1, 0.9, 5)[:, None] * w.d_exact[None, :]
    h = 1e-5
    wp, wm = (build_wall("fem", p, E2 * (1 + s * h), nu2) for s in (1, -1))
    fd = np.array([(wp.force(x) - wm.force(x)) / (2 * h * E2) for x in d])
    exact = np.array([w.dforce_dE(x) for x in d])
    assert np.max(np.abs(exact / fd - 1)) < 1e-6
    res = api.tof_derivatives(E2, nu2, p, "fem", derivatives=("E",))
    assert res.method["E"] == "forward"
    st = stencil("E", E2)
    tofs = [run_peaks(p, build_wall("fem", p, E2 + o * st.h, nu2), dt=res.dt)[0].tof
            for o in st.offsets]
    assert np.all(np.abs(res.dtof["E"] / st.derivative(tofs) - 1) < TOL)


def test_the_methods_are_labelled_honestly():
    """``forward`` derivatives come from a run that carried the sensitivities (the run has
    ``dsensor``) and agree with ``central`` ones; a wall without E-dependence (a table of
    one curve) gets ``central`` for E, equal to the test's own differences with the stated
    step; the history-dependent plastic wall gets ``central`` for every parameter; and the
    base TOF is the same whatever is asked (the sensitivities do not change the run)."""
    from ssw.curve import ForceCurve

    p = ChainParams()
    auto = api.tof_derivatives(E3, NU3, p, "hertz")
    assert set(auto.method.values()) == {"forward"} and auto.run.dsensor is not None
    central = api.tof_derivatives(E3, NU3, p, "hertz", method="central")
    assert set(central.method.values()) == {"central"} and central.run.dsensor is None
    for k in PARAMETERS:
        assert np.all(np.abs(auto.dtof[k] / central.dtof[k] - 1) < TOL), k
    assert np.array_equal(auto.tof, api.tof(E3, NU3, p, "hertz"))
    # a table wall: one FEM-like curve per scene (Hertz's), data for one modulus
    delta = np.linspace(1e-7, 6e-5, 200)
    curve = ForceCurve(delta=delta, force=4 / 3 * 100e6 / 0.91 * np.sqrt(9.53e-3) * delta**1.5,
                       contact_radius=np.sqrt(9.53e-3 * delta), inputs={}, stats={})
    tab = api.tof_derivatives(100e6, 0.3, p, "table", derivatives=("E", "preload"),
                              curve=curve)
    assert tab.method == {"E": "central", "preload": "forward"}
    h = tab.step["E"]
    st = stencil("E", np.array([100e6]))
    assert h == pytest.approx(float(st.h[0]))
    tofs = [run_peaks(p, build_wall("table", p, 100e6 + o * h, 0.3, curve=curve),
                      dt=tab.dt)[0].tof for o in st.offsets]
    assert float(tab.dtof["E"]) == pytest.approx(float(st.derivative(tofs)[0]), rel=1e-12)


def test_the_plastic_wall_is_differentiated_by_central_differences():
    """The plastic wall (history-dependent, no tangent) is labelled ``central``: its
    striker-speed derivative (differences at the base step plus the step's share) agrees
    with the test's own fourth-order differences of TOFs each run at its own step within
    1e-4 (measured 2.2e-5 at relative steps 1e-4 and 3e-5: the plastic wall's TOF is smooth
    in the step only to ~25 % of the step's share, 1e-4 of this derivative, as its yield
    events fall on steps), and is close to the elastic sample's (a sample far below yield:
    445 MPa, von Mises 50 MPa)."""
    from ssw.constitutive import model_from

    p = ChainParams(plate_thickness=0.0)
    model = model_from({"model": "von-mises", "yield_stress": 50e6})
    res = api.tof_derivatives(445e6, 0.3, p, "plastic", derivatives=("striker_velocity",),
                              soil_model=model)
    assert res.method == {"striker_velocity": "central"}
    w = build_wall("plastic", p, 445e6, 0.3, soil_model=model)
    st = stencil("striker_velocity", np.array([p.striker_velocity]))
    tofs = [run_peaks(Batch.of(p, 1, {"striker_velocity": p.striker_velocity + o * st.h}),
                      w)[0].tof for o in st.offsets]
    assert float(res.dtof["striker_velocity"]) == pytest.approx(
        float(st.derivative(tofs)[0]), rel=1e-4)
    elastic = api.tof_derivatives(445e6, 0.3, p, "hertz", derivatives=("striker_velocity",))
    assert float(res.dtof["striker_velocity"]) == pytest.approx(
        float(elastic.dtof["striker_velocity"]), rel=0.05)


def test_sensor_waveform_derivatives_at_recorded_times():
    """d(sensor)/dE and d(sensor)/d(striker speed) on the dense output at NI 9234 sample
    times (19.5 us, not on the integrator's grid) match central differences of the dense
    output of perturbed runs (each at its own step: the striker speed moves it) to 1e-6 of
    their largest value."""
    from ssw.chain.dense import evaluate
    from ssw.chain.integrate import simulate

    p = ChainParams()
    times = np.arange(5e-5, 2.4e-3, 1 / 51200)
    got = api.sensor_derivatives(123e6, 0.33, p, "hertz", times=times,
                                 derivatives=("E", "striker_velocity"), t_end=2.5e-3)
    for j, name in enumerate(got.names):
        st = stencil(name, np.array([123e6 if name == "E" else p.striker_velocity]))
        S = []
        for o in st.offsets:
            x = float(st.h[0] * o)
            if name == "E":
                run = simulate(p, build_wall("hertz", p, 123e6 + x, 0.33), t_end=2.5e-3,
                               stop_early=False)
            else:
                run = simulate(p.with_(striker_velocity=p.striker_velocity + x),
                               build_wall("hertz", p, 123e6, 0.33), t_end=2.5e-3,
                               stop_early=False)
            S.append(evaluate(run, times)[0][:, 0])
        fd = st.derivative(S)
        exact = got.dsensor[:, 0, j]
        assert np.max(np.abs(exact - fd)) < 1e-6 * np.max(np.abs(fd)), name


def test_dense_output_rate_and_per_scene_times():
    """The dense output's time derivative (``rate``: what a trigger's time offset changes)
    matches central differences of the dense output in time, and times given per scene (a
    recording's samples per hit) give each scene's own values."""
    from ssw.chain.dense import evaluate
    from ssw.chain.integrate import simulate

    p = ChainParams()
    run = simulate(Batch.of(p, 2), build_wall("hertz", p, np.array([38e6, 445e6]),
                                              np.array([0.34, 0.3])), t_end=2.0e-3,
                   stop_early=False)
    t = np.arange(1e-4, 1.9e-3, 1 / 51200)
    S, _, rate = evaluate(run, t, rate=True)
    h = 1e-3 * run.dt
    fd = (evaluate(run, t + h)[0] - evaluate(run, t - h)[0]) / (2 * h)
    assert np.max(np.abs(rate - fd)) < 1e-5 * np.max(np.abs(fd))
    per = np.stack([t, t + 3.3e-6], axis=1)
    Sp = evaluate(run, per)[0]
    assert np.allclose(Sp[:, 0], S[:, 0], rtol=0, atol=1e-12)
    assert np.allclose(Sp[:, 1], evaluate(run, t + 3.3e-6)[0][:, 1], rtol=0, atol=1e-12)
