"""The inverse and the modulus budget do not answer wrongly in silence: a TOF table with a
missing value is not invertible; each target of a batched inverse is judged against its
own range; a run beyond a wall's exact law is flagged; each sample gets its own wall error;
the integrator's stated error is what it measures."""

from __future__ import annotations

import numpy as np
import pytest

from ssw.chain.params import ChainParams
from ssw.chain.wall import beyond_exact_reach
from ssw.curve import ForceCurve
from ssw.errors import SolverError
from ssw.modulus import INTEGRATOR_REL_ERROR_80, estimate_moduli
from ssw.tof import api
from ssw.tof.inverse import invert
from ssw.tof.sweep import Sweep
from ssw.walls import build_wall

P = ChainParams(striker_velocity=0.5)


def test_a_tof_table_with_a_missing_value_is_not_invertible():
    E = np.geomspace(10e6, 1000e6, 12)
    T = api.tof(E, 0.3, P, "hertz")
    T[5] = np.nan  # a point whose run failed
    nan = np.full_like(E, np.nan)
    sweep = Sweep(E, np.full_like(E, 0.3), T, nan, nan, nan)
    with pytest.raises(SolverError, match="missing value"):
        invert(float(T[2]), 0.3, P, "hertz", sweep=sweep)


def test_each_target_is_judged_against_its_own_range():
    """Two targets with different striker speeds (``vary``): their TOF ranges differ (the
    longest TOF, at 10 MPa, is 2.55 ms at 0.3 m/s and 2.73 ms at 0.9 m/s), and each interval
    end is clipped at its own target's range, not at the first target's."""
    v = np.array([0.3, 0.9])
    longest = [float(api.tof(10e6, 0.3, P.with_(striker_velocity=x), "hertz")) for x in v]
    assert longest[1] > 1.05 * longest[0]
    t = 0.999 * longest[0]  # inside both ranges; t + 1 % inside the fast striker's only
    inv = invert(np.array([t, t]), 0.3, P, "hertz", tof_std=0.01 * t,
                 vary={"striker_velocity": v})
    assert inv.clipped[0] and inv.E_low[0] == pytest.approx(10e6)
    assert not inv.clipped[1] and inv.E_low[1] > 10e6


def test_a_run_beyond_the_exact_law_is_flagged(monkeypatch):
    """A FEM curve that stops short of what the chain presses in: the table wall extends
    it and the run is flagged; one that reaches further is not; an analytic law never is.
    An estimate through a FEM law computed too shallow (its energy margin cut to half of
    the striker's energy) says its law was extrapolated."""
    import ssw.walls.fem as fem

    R, E_s, nu_s = P.bead_radius, 120e6, 0.3

    def curve(d_max: float) -> ForceCurve:
        d = np.linspace(0.0, d_max, 101)
        F = 4 / 3 * E_s / (1 - nu_s**2) * np.sqrt(R) * d**1.5
        return ForceCurve(delta=d, force=F, contact_radius=np.sqrt(R * d))

    for c, beyond in ((curve(2e-5), True), (curve(2e-3), False)):
        _, run = api.peaks(E_s, nu_s, P, "table", curve=c)
        w = build_wall("table", P, E_s, nu_s, curve=c)
        assert beyond_exact_reach(w, run.peak_wall_indentation)[0] == beyond
    assert not beyond_exact_reach(build_wall("hertz", P, E_s, nu_s), np.array([1.0]))[0]
    contact = {"mesh_growth": 0.3, "mesh_size_contact": 1.5e-5, "soil_radius": 0.2,
               "soil_depth": 0.2}
    p = P.with_(plate_thickness=0.0)
    tof = float(api.tof(E_s, nu_s, p, "fem", contact=contact))
    ok = estimate_moduli([tof], [1e-6], nu_s, p, "fem", {"contact": contact})[0]
    assert not ok.extrapolated
    monkeypatch.setattr(fem, "ENERGY_MARGIN", 0.5)
    short = estimate_moduli([tof], [1e-6], nu_s, p, "fem", {"contact": contact})[0]
    assert short.extrapolated and any("EXTRAPOLATED" in n for n in short.notes)


def test_each_sample_gets_its_own_wall_error():
    """The FEM wall states a larger error on a softer soil (a wider contact feels the finite
    domain more): two samples in one estimate each carry their own, not the first one's."""
    contact = {"mesh_growth": 0.3, "mesh_size_contact": 1.5e-5, "soil_radius": 0.2,
               "soil_depth": 0.2}
    p = P.with_(plate_thickness=0.0)
    E = np.array([20e6, 600e6])
    T = api.tof(E, 0.3, p, "fem", contact=contact)
    est = estimate_moduli(T, [1e-6, 1e-6], 0.3, p, "fem", {"contact": contact})
    w = build_wall("fem", p, E, 0.3, contact=contact)
    errs = [e.contributions["wall"] for e in est]
    np.testing.assert_allclose(errs, w.force_error, rtol=0.05)
    assert errs[0] > 1.5 * errs[1]


def test_the_integrator_error_constant_is_what_it_measures():
    """INTEGRATOR_REL_ERROR_80 bounds the relative TOF error of 80 steps per contact against
    an independent DOP853 solution (rtol 1e-10), over soft to stiff soils and the thesis
    chain's nominal and calibrated striker speeds, and is not more than twice the largest
    measured (a budget term, not a padding)."""
    from ssw.chain.baseline import hertz_wall, solve_dop853

    errs = []
    for v in (0.5247, 0.389):
        p = ChainParams(striker_velocity=v)
        E, nu = np.array([38e6, 445e6, 1000e6]), np.full(3, 0.3)
        pk, run = api.peaks(E, nu, p)
        for i in range(3):
            ref = solve_dop853(p, hertz_wall(p, E[i], nu[i]), t_end=1.5 * run.stop_time[i],
                               rtol=1e-10, sample_dt=2.5e-7).tof[0]
            errs.append(abs(pk.tof[i] / ref - 1))
    worst = max(errs)
    assert worst <= INTEGRATOR_REL_ERROR_80 <= 2 * worst, (errs, INTEGRATOR_REL_ERROR_80)


def test_a_sweep_of_another_model_is_refused(tmp_path, capsys):
    """`ssw invert --table` reads a stored sweep in place of its own model: a sweep made for
    another device (here another striker speed) is refused naming both sides; parts of two
    models do not merge."""
    from ssw.cli import main

    base = ["--law", "hertz", "--calibration", "none", "--soil-E-min", "1e7", "--soil-E-max",
            "1e9", "--soil-E-step", "1e7", "--soil-nu", "0.3"]
    a, b = tmp_path / "a.h5", tmp_path / "b.h5"
    assert main(["tof-sweep", *base, "--output", str(a)]) == 0
    assert main(["tof-sweep", *base, "--striker-velocity", "0.9", "--output", str(b)]) == 0
    capsys.readouterr()
    inv = ["invert", "--tof", "1.5e-3", "--soil-nu", "0.3", "--law", "hertz", "--calibration",
           "none"]
    assert main([*inv, "--table", str(a)]) == 0
    capsys.readouterr()
    assert main([*inv, "--table", str(b)]) == 2
    err = capsys.readouterr().err
    assert f"sweep {b}" in err and "this command's" in err and "chain model" in err
    assert main(["tof-merge", str(a), str(b), "--output", str(tmp_path / "m.h5")]) == 2
    assert "chain model" in capsys.readouterr().err
