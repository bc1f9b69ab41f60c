"""E with its interval (ssw.modulus, ssw.measure): each contribution of the budget against an
independent evaluation of what it stands for, and the interval of a simulated measurement
against the modulus that made it."""

from __future__ import annotations

import numpy as np
import pytest

from ssw.calibration import Reference, calibrate
from ssw.chain.params import chain_params
from ssw.device import load_device
from ssw.errors import ConfigError
from ssw.materials import material_set
from ssw.modulus import COVERAGE_Z, Estimator, estimate_moduli
from ssw.tof import api
from ssw.tof.inverse import invert, invert_batch

DEVICE = load_device("thesis").with_(plate_thickness=0.0, plate_material="none")
NUM = {"gravity": True, "steps_per_contact": 80, "t_max": 0.02, "damping": 0.0}
P = chain_params(DEVICE, material_set(), **NUM)
E0, NU0 = 120.0e6, 0.3


@pytest.fixture(scope="module")
def tof0() -> float:
    return float(api.tof(E0, NU0, P, "hertz"))


def test_the_tof_term_is_the_inverse_of_tof_plus_minus_its_error(tof0):
    """u_tof = sem / (T |k|) is the first-order width of E(T -+ z sem): compare with two
    independent inversions at T -+ 1.96 sem."""
    sem = 2.0e-6
    e = estimate_moduli([tof0], [sem], NU0, P, "hertz")[0]
    assert e.E == pytest.approx(E0, rel=2e-4)
    assert set(e.contributions) == {"tof", "integrator"}
    inv = invert(tof0, NU0, P, "hertz", tof_std=COVERAGE_Z * sem)
    # E_low from T + z sem, E_high from T - z sem; the budget's interval is log-symmetric
    assert e.E_low == pytest.approx(float(inv.E_low), rel=2e-3)
    assert e.E_high == pytest.approx(float(inv.E_high), rel=2e-3)


def test_the_poisson_term_is_the_uniform_spread_of_ln_E(tof0):
    """A range [lo, hi] of nu: u = |ln E(hi) - ln E(lo)| / sqrt(12), E at the middle; both
    ends inverted independently here."""
    e = estimate_moduli([tof0], [0.0], np.array([[0.25, 0.35]]), P, "hertz")[0]
    lo = float(invert(tof0, 0.25, P, "hertz").E)
    hi = float(invert(tof0, 0.35, P, "hertz").E)
    mid = float(invert(tof0, 0.30, P, "hertz").E)
    assert e.nu_range == (0.25, 0.35) and e.nu == pytest.approx(0.30)
    assert e.E == pytest.approx(mid, rel=1e-6)
    assert e.contributions["poisson"] == pytest.approx(abs(np.log(hi / lo)) / np.sqrt(12),
                                                       rel=1e-3)


@pytest.fixture(scope="module")
def calibrated():
    """A device calibrated (striker speed and preload) on three synthetic references made
    by its own model at v = 0.55 m/s, P = 2 N, with 8 us TOF uncertainties."""
    truth = P.with_(striker_velocity=0.55, preload=2.0)
    E = np.array([40e6, 150e6, 500e6])
    T = api.tof(E, 0.3, truth, "hertz")
    refs = [Reference(e, 0.3, float(t), 8.0e-6, id=f"r{i}") for i, (e, t) in
            enumerate(zip(E, T, strict=True))]
    return calibrate(refs, DEVICE, ["striker_velocity", "preload"], materials=material_set(),
                     numerics=NUM, wall="hertz", loo=False, scan_points=8)


def test_the_calibration_term_matches_a_monte_carlo_over_its_covariance(calibrated, tof0):
    """u_cal = sqrt(g^T C g) (linearized): compare with the spread of ln E inverted with 64
    parameter sets drawn from the calibration's covariance (seeded), all in one batch."""
    params = calibrated.chain_params()
    e = estimate_moduli([tof0], [0.0], NU0, params, "hertz", calibration=calibrated)[0]
    names = calibrated.covariance_parameters
    mean = np.array([calibrated.parameters[n] for n in names])
    draws = np.random.default_rng(20261123).multivariate_normal(
        mean, calibrated.covariance_array(), size=64)
    res = invert_batch(np.full(64, tof0), NU0, params, "hertz",
                       vary={n: draws[:, j] for j, n in enumerate(names)})
    mc = float(np.std(np.log(res.E), ddof=1))
    # 64 draws: the sample std is within ~18 % (2 sigma) of the true one
    assert e.contributions["calibration"] == pytest.approx(mc, rel=0.25)
    assert e.contributions["calibration"] > 0


def test_the_budgets_derivatives_are_converged_difference_quotients(calibrated, tof0):
    """k = d ln TOF / d ln E and the calibration term sqrt(g^T C g), g_j = -(d ln TOF /
    d theta_j) / k, come from the chain's forward sensitivities: central differences of
    separate TOFs at the same time step (relative steps 3e-5, O(h^2) ~ 1e-9) agree within
    1e-4 relative."""
    params = calibrated.chain_params()
    e = estimate_moduli([tof0], [0.0], NU0, params, "hertz", calibration=calibrated)[0]
    names = calibrated.covariance_parameters
    dt = api.tof_derivatives(e.E, NU0, params, "hertz", derivatives=("E",)).dt
    h = 3e-5
    base = {n: float(getattr(params, n)) for n in names}
    Es, vary = [e.E * (1 + h), e.E * (1 - h)], {n: [base[n]] * 2 for n in names}
    steps = {}
    for n in names:
        steps[n] = h * max(abs(base[n]), 1.0)
        for o in (1, -1):
            Es.append(e.E)
            for m in names:
                vary[m].append(base[m] + (o * steps[n] if m == n else 0.0))
    pk, _ = api.peaks(np.array(Es), NU0, params, "hertz", dt=dt,
                      vary={n: np.array(v) for n, v in vary.items()})
    T = pk.tof
    k = np.log(T[0] / T[1]) / np.log((1 + h) / (1 - h))
    assert e.dlnTOF_dlnE == pytest.approx(k, rel=1e-4)
    g = np.array([-np.log(T[2 + 2 * j] / T[3 + 2 * j]) / (2 * steps[n]) / k
                  for j, n in enumerate(names)])
    u = float(np.sqrt(g @ calibrated.covariance_array() @ g))
    assert e.contributions["calibration"] == pytest.approx(u, rel=1e-4)


def test_wall_error_enters_when_the_law_states_one(tof0):
    """A K wall from a table with a stated interpolation error carries it as 'wall'; the
    Hertz wall states none and the estimate lists the term as missing, with the
    uncalibrated device's calibration term."""
    e = estimate_moduli([tof0], [0.0], NU0, P, "hertz")[0]
    assert "wall" not in e.contributions
    assert "states no force error" in e.missing["wall"]
    assert "uncalibrated" in e.missing["calibration"]
    assert e.to_dict()["missing_terms"] == e.missing


def test_an_unknown_tof_scatter_is_a_missing_term(tof0):
    """A TOF standard error of NaN (too few hits): no tof contribution, listed missing."""
    e = estimate_moduli([tof0], [float("nan")], NU0, P, "hertz")[0]
    assert "tof" not in e.contributions and "tof" in e.missing


def test_the_fast_estimator_agrees_with_the_full_budget(tof0):
    """The live estimator's E is the full budget's (one inversion: the same grid, the same
    refinement on the forward model), also for a Poisson's ratio range (E at its middle);
    its interval within 2 % (the TOF term from the grid's slope)."""
    est = Estimator(P, "hertz", {}, NU0)
    r = est(tof0, 3.0e-6)
    full = estimate_moduli([tof0], [3.0e-6], NU0, P, "hertz")[0]
    assert r["E"] == pytest.approx(full.E, rel=1e-12)
    assert r["u"] == pytest.approx(full.u, rel=0.02)
    ranged = Estimator(P, "hertz", {}, (0.25, 0.35))(tof0, 3.0e-6)
    assert ranged["E"] == pytest.approx(
        estimate_moduli([tof0], [3.0e-6], np.array([0.25, 0.35]), P, "hertz")[0].E, rel=1e-12)


def test_the_live_tof_slope_is_the_inversions_interpolant_converging_to_the_chains(tof0):
    """The live estimate's ``d ln E / d TOF`` is the derivative of the inversion's own
    interpolant (:meth:`ssw.tof.inverse.ForwardGrid.interpolant`, PCHIP of ln E against TOF
    on the default 48-point grid). Against the chain's exact forward sensitivity
    (``1 / (E dTOF/dE)``, :func:`ssw.tof.api.tof_derivatives`, an independent evaluation)
    its error falls at least as the square of the grid's spacing (measured 2026-11-29:
    4.6e-4, 5.5e-5, 7.7e-6 at 12, 24, 48 points, about h^3) down to the forward model's
    own floor (3e-6 to 6e-6 at 96 and 192 points)."""
    from ssw.tof.inverse import forward_grid

    der = api.tof_derivatives(np.array([E0]), np.array([NU0]), P, "hertz",
                              derivatives=("E",))
    exact = 1.0 / (E0 * float(np.asarray(der.dtof["E"])[0]))
    err = {}
    for n in (12, 24, 48):
        slope = forward_grid(NU0, P, "hertz", grid_points=n).interpolant(0).derivative()
        err[n] = abs(float(slope(tof0)) / exact - 1.0)
    assert err[24] < err[12] / 4.0
    assert err[48] < err[24] / 4.0 or err[48] < 1.0e-5  # second order, or at the floor
    est = Estimator(P, "hertz", {}, NU0)
    live = float(est._slope(tof0))
    assert live == float(est.grid.interpolant(0).derivative()(tof0))
    assert abs(live / exact - 1.0) <= err[48] * (1 + 1e-9)


def test_live_E_of_a_session_is_what_ssw_measure_gives(tmp_path):
    """A session simulated through the NI 9234 model, fed hit by hit to acquisition's live
    hook (:class:`ssw.signal.live.LiveTof` with the :class:`Estimator` of ``ssw
    acquire``): after the last hit its E is ``ssw measure``'s on the same file (the same
    mean TOF and one inversion; the interpolated grid alone was 2e-6 off at 200 MPa)."""
    from ssw.daq.backend import run_session
    from ssw.daq.recording import read_recording
    from ssw.daq.settings import DaqSettings
    from ssw.daq.simulated import SimulatedBackend
    from ssw.measure import measure
    from ssw.signal.live import LiveTof

    s = DaqSettings(hits=5, record_samples=1024, pretrigger_samples=64)
    path = run_session(SimulatedBackend(soil_E=200e6, soil_nu=NU0, chain_params=P, seed=5,
                                        wall="hertz"), s, tmp_path / "s.h5", sample_id="X",
                       synthetic=True)
    rec = read_recording(path)
    live = LiveTof(rec.sample_rate, int(rec.meta["pretrigger_samples"]),
                   estimate=Estimator(P, "hertz", {}, NU0))
    for hit in rec.hits:
        report = live.add(hit.force)
    m = measure([rec], NU0, P, "hertz")
    assert report.n_accepted == m.n_accepted == 5
    assert report.tof_mean == pytest.approx(m.tof_mean, rel=1e-15)
    assert report.estimate["E"] == pytest.approx(m.E, rel=1e-12)


def test_a_forward_grid_with_a_missing_tof_is_not_inverted(monkeypatch, tof0):
    """The inversion's guard: a forward TOF(E) with a NaN (a failed forward run) is refused
    by every path, the live estimator's too (its own check compared TOF differences, which
    a NaN passes)."""
    from ssw.errors import SolverError
    from ssw.tof import inverse

    real = api.tof

    def with_a_hole(E, *args, **kwargs):
        T = np.array(real(E, *args, **kwargs), float)
        T[np.size(T) // 2] = np.nan
        return T

    monkeypatch.setattr(inverse.api, "tof", with_a_hole)
    with pytest.raises(SolverError, match="missing value"):
        Estimator(P, "hertz", {}, NU0)
    with pytest.raises(SolverError, match="missing value"):
        invert_batch([tof0], NU0, P, "hertz")
    with pytest.raises(SolverError, match="missing value"):
        invert(tof0, NU0, P, "hertz")


def test_bad_inputs_are_refused():
    with pytest.raises(ConfigError, match="tof_sem"):
        estimate_moduli([1e-3], [-1.0], NU0, P, "hertz")
    with pytest.raises(ConfigError, match="soil_nu"):
        estimate_moduli([1e-3], [0.0], np.array([[0.4, 0.3]]), P, "hertz")


def test_a_simulated_session_measures_the_modulus_that_made_it(tmp_path):
    """ssw measure on a session simulated through the NI 9234 model (noise, jitter,
    quantization, filter) at a known E: the 95 % interval contains it."""
    from ssw.daq.backend import run_session
    from ssw.daq.recording import read_recording
    from ssw.daq.settings import DaqSettings
    from ssw.daq.simulated import SimulatedBackend
    from ssw.measure import measure

    s = DaqSettings(hits=6, record_samples=1024, pretrigger_samples=64)
    path = run_session(SimulatedBackend(soil_E=E0, soil_nu=NU0, chain_params=P, seed=11,
                                        wall="hertz"), s, tmp_path / "s.h5", sample_id="X",
                       synthetic=True)
    m = measure([read_recording(path)], NU0, P, "hertz")
    assert m.E_low < E0 < m.E_high
    assert m.n_accepted == 6 and m.synthetic
    assert set(m.contributions) >= {"tof", "sampling", "integrator"}
    # pooling two sessions of the same point halves nothing systematic but adds hits
    m2 = measure([read_recording(path), read_recording(path)], NU0, P, "hertz")
    assert m2.n_accepted == 12 and m2.tof_mean == pytest.approx(m.tof_mean, rel=1e-12)


@pytest.mark.parametrize(("text", "ok"), [("0.3", 0.3), ("0.25:0.35", (0.25, 0.35)),
                                          ("0.35:0.25", None), ("0.6", None), ("abc", None)])
def test_poisson_ratio_argument(text, ok):
    from ssw.measure import parse_nu

    if ok is None:
        with pytest.raises(ConfigError, match="--soil-nu"):
            parse_nu(text)
    else:
        assert parse_nu(text) == ok
