"""A calibration refuses to fail silently, names the device it was made for, and every
consumer works with a parameter on its bound; an interval says what it lacks.

The references' TOFs come from the chain itself (Hertz wall, fast) at known parameters:
the truth a calibration must recover, or a misfit it must refuse.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from ssw.calibration import Reference, calibrate, load_calibration, write_calibration
from ssw.calibration.lm import LM_FTOL, Problem, levenberg_marquardt
from ssw.chain.params import chain_params
from ssw.cli import main
from ssw.device import load_device, write_device
from ssw.errors import ConfigError
from ssw.materials import material_set
from ssw.tof import api

NUM = {"steps_per_contact": 80, "t_max": 0.02, "gravity": True, "damping": 0.0}
SOILS = [(38e6, 0.34), (123e6, 0.33), (445e6, 0.30)]


def _tofs(device):
    p = chain_params(device, material_set(), **NUM)
    return np.asarray(api.tof(np.array([e for e, _ in SOILS]), np.array([n for _, n in SOILS]),
                              p, "hertz"), float)


@pytest.fixture(scope="module")
def no_preload():
    """A device without static load (preload 0 N) and its references' TOFs."""
    dev = load_device().with_(preload=0.0, striker_velocity=0.4)
    return dev, _tofs(dev)


def _refs(tofs, std=2e-6):
    stds = np.broadcast_to(std, np.shape(tofs))
    return [Reference(E, nu, float(t), float(u), id=f"r{i}")
            for i, ((E, nu), t, u) in enumerate(zip(SOILS, tofs, stds, strict=True))]


def test_tofs_typed_in_milliseconds_are_refused_and_nothing_is_written(tmp_path, capsys):
    out = tmp_path / "c.json"
    rc = main(["calibrate", "--law", "hertz", "--reference", "38e6,0.34,1.78",
               "--reference", "123e6,0.33,1.46", "--reference", "445e6,0.30,1.15",
               "--free", "striker_velocity", "--free", "preload", "--no-loo",
               "--output", str(out)])
    err = capsys.readouterr().err
    assert rc == 2 and not out.exists()
    assert "TOF = 1.78 s is outside what the device can produce" in err
    assert "TOFs are in seconds" in err


def test_a_parameter_next_to_its_bound_keeps_its_covariance_and_every_consumer_works(
        no_preload, tmp_path, capsys):
    """A device without static load, calibrated with the preload free: the preload is found
    at its bound's edge (0 N within 0.01 N). The exact TOFs put the optimum ON the bound with
    a vanishing gradient, so either the bound holds it (flagged, conditional covariance) or it
    stays a free parameter whose interval reaches the bound; either way the file says which
    consistently, and the inverse (central differences would step to a negative preload) and
    a measurement still work through it."""
    dev, tofs = no_preload
    nominal = dev.with_(preload=3.0, striker_velocity=0.5)
    cal = calibrate(_refs(tofs), nominal, ["striker_velocity", "preload"],
                    materials=material_set(), numerics=NUM, wall="hertz", loo=False)
    assert cal.parameters["preload"] < 0.01 and cal.parameters["striker_velocity"] == \
        pytest.approx(0.4, rel=1e-3)
    held = "preload" in cal.at_bound
    assert held == ("preload" not in cal.covariance_parameters)
    assert held == (cal.parameters["preload"] == 0.0)
    path = tmp_path / "c.json"
    write_calibration(path, cal)
    assert json.loads(path.read_text())["at_bound"] == cal.at_bound
    assert load_calibration(path).at_bound == cal.at_bound
    dev_file = tmp_path / "nominal.yaml"
    write_device(dev_file, nominal)
    rc = main(["invert", "--tof", repr(float(tofs[1])), "--soil-nu", "0.33", "--device",
               str(dev_file), "--calibration", str(path), "--law", "hertz", "--json"])
    res = json.loads(capsys.readouterr().out)
    assert rc == 0 and res["E"] == pytest.approx(123e6, rel=2e-3)
    assert res["E_low"] < 123e6 < res["E_high"]
    # a measurement (simulated hits of the same device) through that calibration
    rec = tmp_path / "p.h5"
    assert main(["acquire", "--simulate", "--material", "pcf15", "--hits", "4", "--law",
                 "hertz", "--device", str(dev_file), "--calibration", "none",
                 "--preload", "0", "--striker-velocity", "0.4", "--sample", "P",
                 "--output", str(rec), "--json"]) == 0
    capsys.readouterr()
    assert main(["measure", str(rec), "--soil-nu", "0.33", "--device", str(dev_file),
                 "--calibration", str(path), "--law", "hertz", "--json"]) == 0
    m = json.loads(capsys.readouterr().out)
    assert m["E_low"] < 123e6 < m["E_high"] and "calibration" in m["contributions_pct"]


@pytest.fixture(scope="module")
def heavy_damped():
    """References of a device the model does not describe: its sensor particle 1.5x a
    bead's mass, a 5 N s/m dashpot in every contact, no preload (ssw's own chain, a fast
    stand-in for tests/test_calibration.py's independent solver). Calibrated as a plain
    conservative chain, its soft/stiff TOF contrast asks for a negative preload."""
    dev = load_device().with_(preload=0.0, striker_velocity=0.5)
    heavy = dev.with_(sensor_mass=1.5 * chain_params(dev, material_set(), **NUM).bead_mass)
    p = chain_params(heavy, material_set(), **{**NUM, "damping": 5.0})
    tofs = np.asarray(api.tof(np.array([e for e, _ in SOILS]),
                              np.array([n for _, n in SOILS]), p, "hertz"), float)
    return dev, tofs


def test_a_parameter_beyond_its_bound_is_held_there_flagged_with_a_conditional_covariance(
        heavy_damped, tmp_path, capsys):
    """The preload's optimum lies below 0 N: the bounded Levenberg-Marquardt converges with
    the preload ON its bound (the old one, clipping its steps, stalled: "did not converge"),
    flags it, and gives the striker speed's covariance conditional on it: the Gauss-Newton
    variance of the striker speed alone (preload fixed at 0), computed here from central
    differences of the chain's TOFs; the same value as the calibration of the striker
    speed alone. Consumers take the flag from the file."""
    dev, tofs = heavy_damped
    refs = _refs(tofs, std=0.005 * tofs)
    cal = calibrate(refs, dev.with_(preload=3.0), ["striker_velocity", "preload"],
                    materials=material_set(), numerics=NUM, wall="hertz", loo=False)
    assert cal.at_bound == {"preload": "lower"} and cal.parameters["preload"] == 0.0
    assert cal.covariance_parameters == ("striker_velocity",)
    assert list(cal.parameter_std) == ["striker_velocity"]
    assert np.shape(cal.covariance) == (1, 1) and len(cal.singular_values) == 1
    v = cal.parameters["striker_velocity"]
    p = chain_params(dev.with_(striker_velocity=v), material_set(), **NUM)
    E, nu = np.array([e for e, _ in SOILS]), np.array([n for _, n in SOILS])
    h = 1e-3 * v
    dTdv = (np.asarray(api.tof(E, nu, p.with_(striker_velocity=v + h), "hertz"))
            - np.asarray(api.tof(E, nu, p.with_(striker_velocity=v - h), "hertz"))) / (2 * h)
    std = 1.0 / np.sqrt(np.sum((dTdv / (0.005 * tofs)) ** 2))
    assert cal.parameter_std["striker_velocity"] == pytest.approx(std, rel=0.02)
    alone = calibrate(refs, dev, ["striker_velocity"], materials=material_set(), numerics=NUM,
                      wall="hertz", loo=False)
    assert v == pytest.approx(alone.parameters["striker_velocity"], abs=0.05 * std)
    assert cal.parameter_std["striker_velocity"] == pytest.approx(
        alone.parameter_std["striker_velocity"], rel=0.02)
    path = tmp_path / "c.json"
    write_calibration(path, cal)
    d = json.loads(path.read_text())
    assert d["at_bound"] == {"preload": "lower"}
    assert d["covariance_parameters"] == ["striker_velocity"]
    assert load_calibration(path).at_bound == {"preload": "lower"}
    # a file of an older format (version 1: no model-error term) is refused, saying why
    old = tmp_path / "old.json"
    old.write_text(json.dumps({**{k: v for k, v in d.items()
                                  if k not in ("model_error", "warnings")},
                               "schema_version": 1}))
    with pytest.raises(ConfigError, match="schema_version") as exc:
        load_calibration(old)
    assert "recalibrate" in str(exc.value) and "model_error" in str(exc.value)
    dev_file = tmp_path / "nominal.yaml"
    write_device(dev_file, dev.with_(preload=3.0))
    assert main(["invert", "--tof", repr(float(tofs[1])), "--tof-std", "1e-6", "--soil-nu",
                 "0.33", "--device", str(dev_file), "--calibration", str(path), "--law",
                 "hertz", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["E_low"] < res["E"] < res["E_high"]
    assert res["contributions_pct"]["calibration"] > 0


def test_a_misfit_beyond_its_statistics_calibrates_with_its_model_error_stated(
        heavy_damped, tmp_path, capsys):
    """The heavy, damped device's TOFs with 0.1 % uncertainties: chi^2 far beyond its 95 %
    quantile (before, beyond 99.9 %, the calibration was refused). It calibrates: the file,
    the provenance and ``ssw calibrate``'s JSON and human output state the model-error term
    tau, at the root of its defining equation (its residuals' chi^2 with the term at the
    lower 5 % quantile of chi^2 with its degrees of freedom), and the stated chi^2 is the
    references' own."""
    from scipy.stats import chi2 as chi2_law

    from ssw.calibration.model_error import ModelError

    dev, tofs = heavy_damped
    cal = calibrate(_refs(tofs, std=1e-3 * tofs), dev.with_(preload=3.0),
                    ["striker_velocity", "preload"], materials=material_set(), numerics=NUM,
                    wall="hertz", loo=False)
    term = cal.model_term()
    assert isinstance(term, ModelError) and term.tau > 0 and term.settled
    dof = len(SOILS) - (len(cal.free) - len(cal.at_bound))
    assert term.dof == dof and term.chi2 > chi2_law.ppf(0.95, dof)
    # the file's residuals are the calibrated device's canonical run (its own time step:
    # a TOF ~5e-5 off the fit's runs, 0.5 % of chi^2 here)
    r = np.array(cal.residuals)
    s = 1e-3 * tofs
    assert np.sum(r**2 / s**2) == pytest.approx(cal.provenance["chi2"], rel=0.02)
    with_term = np.sum(r**2 / (s**2 + (term.tau * tofs) ** 2))
    assert with_term == pytest.approx(chi2_law.ppf(0.05, dof), rel=0.02)
    assert cal.warnings[0].startswith("MODEL ERROR") and f"{term.tau:.3g}" in cal.warnings[0]
    assert cal.provenance["model_error_tau"] == term.tau
    path = tmp_path / "c.json"
    write_calibration(path, cal)
    assert load_calibration(path).model_term() == term
    assert json.loads(path.read_text())["model_error"]["tau"] == term.tau
    args = ["calibrate", "--law", "hertz", "--free", "striker_velocity", "--free", "preload",
            "--no-loo"]
    for (E, nu), t in zip(SOILS, tofs, strict=True):
        args += ["--reference", f"{E},{nu},{float(t)!r},{1e-3 * float(t)!r}"]
    assert main([*args, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["model_error"]["tau"] == pytest.approx(term.tau, rel=1e-3)
    assert out["warnings"][0].startswith("MODEL ERROR")
    assert main(args) == 0
    assert "MODEL ERROR" in capsys.readouterr().out
    # ssw invert through the file: the term in its budget, the reference's E inside
    from ssw.modulus import MODEL_TERM

    dev_file = tmp_path / "nominal.yaml"
    write_device(dev_file, dev.with_(preload=3.0))
    assert main(["invert", "--tof", repr(float(tofs[1])), "--tof-std", "1e-6", "--soil-nu",
                 "0.33", "--device", str(dev_file), "--calibration", str(path), "--law",
                 "hertz", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["contributions_pct"][MODEL_TERM] > 0
    assert res["E_low"] < 123e6 < res["E_high"]


def test_mixed_tof_uncertainties_are_refused(no_preload):
    dev, tofs = no_preload
    refs = _refs(tofs)
    refs[1] = Reference(refs[1].E, refs[1].nu, refs[1].tof, None, id="r1")
    with pytest.raises(ConfigError, match="for every reference or for none"):
        calibrate(refs, dev, ["striker_velocity"], materials=material_set(), numerics=NUM,
                  wall="hertz", loo=False)


def test_levenberg_marquardt_converges_on_a_linear_problem_and_stalls_unconverged():
    """On a linear least squares it converges to the normal equations' minimum (within its
    chi^2 tolerance, LM_FTOL); when no step ever lowers chi^2 (a model that only gets
    worse) it stops NOT converged."""
    rng = np.random.default_rng(5)
    A, b = rng.normal(size=(6, 2)), rng.normal(size=6)

    def linear(points):
        return {i: (A @ x - b, A, float((A @ x - b) @ (A @ x - b))) for i, x in points.items()}

    x0 = np.zeros(2)
    pr = Problem(x0, A @ x0 - b, A, float(b @ b), np.eye(2))
    levenberg_marquardt([pr], linear, np.full(2, -10.0), np.full(2, 10.0), 40)
    assert pr.converged
    xs = np.linalg.lstsq(A, b, rcond=None)[0]
    best = float((A @ xs - b) @ (A @ xs - b))
    assert best <= pr.cost <= best + LM_FTOL

    def worse(points):  # every trial point costs more than the start
        return {i: (np.ones(6) * 10, A, 600.0) for i in points}

    pr = Problem(x0, A @ x0 - b, A, float(b @ b), np.eye(2))
    levenberg_marquardt([pr], worse, np.full(2, -10.0), np.full(2, 10.0), 200)
    assert pr.done and not pr.converged
    assert float(b @ b) > LM_FTOL  # it had something to gain


def test_a_covariance_that_is_not_positive_definite_is_refused_on_load(no_preload, tmp_path):
    dev, tofs = no_preload
    cal = calibrate(_refs(tofs), dev.with_(preload=1.0), ["striker_velocity", "preload"],
                    materials=material_set(), numerics=NUM, wall="hertz", loo=False)
    path = tmp_path / "c.json"
    write_calibration(path, cal)
    d = json.loads(path.read_text())
    d["covariance"] = [[1e-4, 2e-3], [2e-3, 1e-4]]  # symmetric, an eigenvalue < 0
    path.write_text(json.dumps(d))
    with pytest.raises(ConfigError, match="positive definite"):
        load_calibration(path)
    d["covariance"] = [[1e-4]]
    path.write_text(json.dumps(d))
    with pytest.raises(ConfigError, match="2 x 2"):
        load_calibration(path)


def test_the_calibration_names_its_device_and_a_mismatch_is_refused(no_preload, tmp_path,
                                                                     capsys):
    """The calibration records the digest of the device it was made for: --device that
    device is fine, a device file with another bead count is refused naming both sides, and
    a flag contradicting the calibration (a device field, a calibrated parameter, the model)
    is refused naming it and the calibrated value."""
    dev, tofs = no_preload
    cal = calibrate(_refs(tofs), dev.with_(preload=1.0), ["striker_velocity", "preload"],
                    materials=material_set(), numerics=NUM, wall="hertz", loo=False)
    path = tmp_path / "c.json"
    write_calibration(path, cal)
    dev_file = tmp_path / "d.yaml"
    write_device(dev_file, dev.with_(preload=1.0))
    base = ["invert", "--tof", repr(float(tofs[1])), "--soil-nu", "0.33", "--law", "hertz",
            "--calibration", str(path)]
    assert main([*base, "--device", str(dev_file)]) == 0
    capsys.readouterr()
    other = tmp_path / "other.yaml"
    write_device(other, dev.with_(preload=1.0, beads=30))
    assert main([*base, "--device", str(other)]) == 2
    err = capsys.readouterr().err
    assert "beads: 20 there, 30 here" in err and "digest differs" in err
    assert main([*base, "--device", str(dev_file), "--beads", "30"]) == 2
    assert "--beads = 30" in (err := capsys.readouterr().err) and "beads = 20" in err
    assert main([*base, "--striker-velocity", "0.5"]) == 2
    assert "identified striker_velocity" in capsys.readouterr().err
    assert main([*base, "--damping", "0.1"]) == 2
    assert "was made with damping = 0.0" in capsys.readouterr().err


def test_too_few_hits_use_the_stated_scatter_or_say_the_term_is_missing(tmp_path, capsys):
    """Two accepted hits (min-hits lowered to 2): the thesis device states its scatter, which
    the TOF term then uses, labelled; a device that states none leaves the term missing, and
    the interval says so."""
    rec = tmp_path / "two.h5"
    assert main(["acquire", "--simulate", "--material", "pcf15", "--hits", "2", "--law",
                 "hertz", "--calibration", "none", "--sample", "T", "--output", str(rec),
                 "--min-hits", "2", "--json"]) == 0
    capsys.readouterr()
    args = ["measure", str(rec), "--soil-nu", "0.33", "--law", "hertz", "--calibration",
            "none", "--min-hits", "2", "--json"]
    assert main(args) == 0
    m = json.loads(capsys.readouterr().out)
    assert "tof (stated scatter)" in m["contributions_pct"] and "tof" not in m["missing_terms"]
    assert any("stated scatter" in n for n in m["notes"])
    bare = load_device().with_(tof_scatter=None)
    dev_file = tmp_path / "bare.yaml"
    write_device(dev_file, bare)
    assert main([*args, "--device", str(dev_file)]) == 0
    m = json.loads(capsys.readouterr().out)
    assert "tof" in m["missing_terms"] and not m["interval_complete"]
    assert "fewer than 3" in m["missing_terms"]["tof"]


def test_a_model_its_references_reject_carries_its_error_into_every_interval(heavy_damped):
    """The heavy, damped device calibrated as a conservative chain with 0.1 % TOF
    uncertainties: its references reject the model. Every interval through the calibration
    carries the term ``model (TOF)`` = tau / |d ln TOF / d ln E| (the slope checked against
    a central difference of the calibrated chain's TOF in E), and unseen moduli of that
    device (20 and 800 MPa, beyond the references' 38-445 MPa) are inside their 95 %
    intervals; without the term (the calibration's covariance alone, conditional on the
    model) the 20 MPa one is not. The live estimator carries the same term. Below the
    rejection quantile there is no term and the interval is the calibration's own (a note
    says chi^2 exceeds its degrees of freedom); at most its degrees of freedom, no note."""
    from dataclasses import replace

    from scipy.stats import chi2 as chi2_law

    from ssw.modulus import MODEL_TERM, Estimator, estimate_moduli

    dev, tofs = heavy_damped
    cal = calibrate(_refs(tofs, std=1e-3 * tofs), dev.with_(preload=3.0),
                    ["striker_velocity", "preload"], materials=material_set(), numerics=NUM,
                    wall="hertz", loo=False)
    tau = cal.model_term().tau
    heavy = dev.with_(sensor_mass=1.5 * chain_params(dev, material_set(), **NUM).bead_mass)
    p = chain_params(heavy, material_set(), **{**NUM, "damping": 5.0})
    E = np.array([20e6, 800e6])
    nus = np.array([0.35, 0.28])
    unseen = np.asarray(api.tof(E, nus, p, "hertz"), float)
    params = cal.chain_params()
    est = estimate_moduli(unseen, np.full(2, 1e-9), nus, params, "hertz", calibration=cal)
    for e, truth in zip(est, E, strict=True):
        h = 1e-3 * e.E
        k = (np.log(api.tof(e.E + h, e.nu, params, "hertz"))
             - np.log(api.tof(e.E - h, e.nu, params, "hertz"))) / np.log((e.E + h) / (e.E - h))
        assert e.contributions[MODEL_TERM] == pytest.approx(tau / abs(float(k)), rel=1e-3)
        assert any("MODEL ERROR" in n for n in e.notes)
        assert e.E_low < truth < e.E_high, (truth, e)
    live = Estimator(params, "hertz", None, 0.35, calibration=cal)(float(unseen[0]), 1e-9)
    assert live["contributions"][MODEL_TERM] == pytest.approx(
        est[0].contributions[MODEL_TERM], rel=1e-3)
    bare = estimate_moduli(unseen[:1], [1e-9], [0.35], params, "hertz",
                           calibration=replace(cal, model_error=None, warnings=[]))[0]
    assert MODEL_TERM not in bare.contributions
    assert not bare.E_low < E[0] < bare.E_high
    dof = len(SOILS) - (len(cal.free) - len(cal.at_bound))
    q95 = chi2_law.ppf(0.95, dof)
    warned = replace(cal, model_error=None, warnings=[],
                     provenance={**cal.provenance, "chi2": 0.5 * (dof + q95)})
    noted = estimate_moduli(unseen[:1], [1e-9], [0.35], params, "hertz",
                            calibration=warned)[0]
    assert (noted.E_low, noted.E_high) == (bare.E_low, bare.E_high)
    assert any("not rejected" in n for n in noted.notes)
    fits = replace(warned, provenance={**cal.provenance, "chi2": 0.9 * dof})
    quiet = estimate_moduli(unseen[:1], [1e-9], [0.35], params, "hertz", calibration=fits)[0]
    assert not any("not rejected" in n for n in quiet.notes)
