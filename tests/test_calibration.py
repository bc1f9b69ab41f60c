"""``ssw calibrate`` against an independent reference chain, and its refusals.

The reference TOFs come from a chain written from the equations alone and solved by scipy's
DOP853 (``tests/chain_dop853.py``; nothing of ssw's chain code is used to make them).
ssw's velocity-Verlet TOF differs from such a solution by ~3.5e-5 (README, ``ssw bench
chain``), so a striker speed recovered from these TOFs must be within 0.5 %, the modulus of
an unseen sample within 1 %.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from chain_dop853 import BEAD_MASS, chain_tof

from ssw.calibration import Reference, calibrate, load_calibration, write_calibration
from ssw.chain.params import chain_params
from ssw.device import load_device
from ssw.errors import ConfigError
from ssw.materials import material_set

ROOT = Path(__file__).resolve().parent.parent

V_TRUE = 0.62  # m/s, the reference device's striker speed
SOILS = [(45.0e6, 0.30), (160.0e6, 0.30), (520.0e6, 0.30)]  # references
UNSEEN = (90.0e6, 0.30)  # a sample the calibration never sees


@pytest.fixture(scope="module")
def reference_tofs():
    return {soil: chain_tof(*soil, V_TRUE) for soil in [*SOILS, UNSEEN]}


@pytest.fixture(scope="module")
def device():
    # the shipped thesis device without its plate: a Hertz wall, as in the reference chain
    return load_device("thesis").with_(plate_thickness=0.0, plate_material="none",
                                       striker_velocity=0.45)


NUMERICS = {"gravity": True, "steps_per_contact": 80, "t_max": 0.02, "damping": 0.0}


@pytest.fixture(scope="module")
def calibration(reference_tofs, device):
    refs = [Reference(E, nu, reference_tofs[(E, nu)], 2.0e-6, id=f"E{E / 1e6:g}")
            for E, nu in SOILS]
    return calibrate(refs, device, ["striker_velocity"], materials=material_set(),
                     numerics=NUMERICS, wall="hertz")


def test_recovers_the_striker_speed_of_the_reference_chain(calibration):
    v = calibration.parameters["striker_velocity"]
    assert v == pytest.approx(V_TRUE, rel=5e-3)
    # its standard error follows from the TOF uncertainties (2 us) and is small here
    assert 0 < calibration.parameter_std["striker_velocity"] < 0.01 * V_TRUE


def test_inverts_an_unseen_sample_within_one_percent(calibration, reference_tofs):
    from ssw.tof.inverse import invert

    params = calibration.chain_params()
    E = float(invert(reference_tofs[UNSEEN], UNSEEN[1], params, "hertz").E)
    assert E == pytest.approx(UNSEEN[0], rel=0.01)


def test_leave_one_out_predicts_each_reference(calibration):
    """Each reference's E from a calibration without it: the model is exact here, so every
    prediction lands within 1 % (the integrator's error, amplified ~5x by the inverse)."""
    assert [row["id"] for row in calibration.loo] == ["E45", "E160", "E520"]
    for row in calibration.loo:
        assert row["E_predicted"] == pytest.approx(row["E"], rel=0.01), row


def test_covariance_is_the_gauss_newton_one(calibration):
    """One parameter: var(v) = 1 / sum_i (dT_i/dv / s_i)^2, with dT/dv by a central
    difference of the calibrated device's TOFs (an independent evaluation of the formula)."""
    from ssw.tof import api

    p = calibration.chain_params()
    v = calibration.parameters["striker_velocity"]
    h = 1e-3 * v
    E = np.array([s[0] for s in SOILS])
    up = api.tof(E, 0.3, p.with_(striker_velocity=v + h), "hertz")
    dn = api.tof(E, 0.3, p.with_(striker_velocity=v - h), "hertz")
    dTdv = (up - dn) / (2 * h)
    std = 1.0 / np.sqrt(np.sum((dTdv / 2.0e-6) ** 2))
    assert calibration.parameter_std["striker_velocity"] == pytest.approx(std, rel=0.02)
    assert calibration.singular_values[0] > 0


def test_calibration_file_round_trip_and_use(calibration, tmp_path):
    path = tmp_path / "cal.json"
    write_calibration(path, calibration)
    back = load_calibration(path)
    assert back.parameters == calibration.parameters
    assert back.device == calibration.device.with_(source=back.device.source)
    assert back.wall["law"] == "hertz"
    assert back.chain_params().striker_velocity == pytest.approx(
        calibration.parameters["striker_velocity"], rel=1e-12)


#: A device the model does not describe exactly (tests/chain_dop853.py): its sensor particle
#: 1.5x a bead's mass and a 5 N s/m dashpot in every contact, no preload, striker 0.5 m/s;
#: the model calibrated on it is the plain conservative chain with the sensor a bead.
MISFIT = {"sensor_mass": 1.5 * BEAD_MASS, "damping": 5.0, "preload": 0.0}
MISFIT_V = 0.5
FOAMS = [(38.0e6, 0.34), (123.0e6, 0.33), (445.0e6, 0.30)]  # the thesis's foams
MISFIT_UNSEEN = [(20.0e6, 0.35), (80.0e6, 0.30), (250.0e6, 0.30), (800.0e6, 0.28)]
#: Standard uncertainty of every measured TOF (references and unseen samples), relative.
MISFIT_REL_STD = 0.005


@pytest.fixture(scope="module")
def misfit_tofs():
    return {soil: chain_tof(*soil, MISFIT_V, **MISFIT) for soil in [*FOAMS, *MISFIT_UNSEEN]}


@pytest.mark.long
def test_a_device_the_model_does_not_describe_calibrates_with_the_preload_on_its_bound(
        misfit_tofs, device):
    """The default free parameters (striker speed and preload) on three foams of a device
    whose heavier sensor and dissipative contacts the model lacks: the preload's optimum
    lies below 0 N. The old bounded Levenberg-Marquardt (steps clipped to the bounds)
    stalled and the calibration was refused; now it converges with the preload ON its bound,
    flagged, the striker speed's covariance conditional on it, and the moduli of four
    samples it never saw (20-800 MPa) fall inside their 95 % intervals, each within 5 %."""
    from ssw.modulus import estimate_moduli

    refs = [Reference(E, nu, misfit_tofs[(E, nu)], MISFIT_REL_STD * misfit_tofs[(E, nu)],
                      id=f"E{E / 1e6:g}") for E, nu in FOAMS]
    cal = calibrate(refs, device.with_(preload=3.0), ["striker_velocity", "preload"],
                    materials=material_set(), numerics=NUMERICS, wall="hertz")
    assert cal.at_bound == {"preload": "lower"} and cal.parameters["preload"] == 0.0
    assert cal.covariance_parameters == ("striker_velocity",)
    assert cal.provenance["converged"]
    # every leave-one-out fit holds the preload on its bound too, and predicts its foam
    # within 10 % (a sanity bound: the model error, not the integrator, sets these)
    for row in cal.loo:
        assert row["at_bound"] == {"preload": "lower"}, row
        assert abs(row["error_pct"]) < 10.0, row
    E = np.array([s[0] for s in MISFIT_UNSEEN])
    T = np.array([misfit_tofs[s] for s in MISFIT_UNSEEN])
    est = estimate_moduli(T, MISFIT_REL_STD * T, np.array([s[1] for s in MISFIT_UNSEEN]),
                          cal.chain_params(), "hertz", calibration=cal)
    for e, E_true in zip(est, E, strict=True):
        assert e.E == pytest.approx(E_true, rel=0.05), (E_true, e)
        assert e.E_low <= E_true <= e.E_high, (E_true, e)
        assert e.contributions["calibration"] > 0


def test_a_non_monotone_tof_calibrates_on_one_sample_alone(device):
    """TOF(v) rises then falls with the striker speed under gravity (REFERENCE.md): a
    bracketing root finder fails; the global scan finds the roots and the fit succeeds on
    one sample alone, reporting the other root when there is one."""
    from ssw.tof import api

    p = chain_params(device, material_set(), **NUMERICS)
    v = np.geomspace(0.1, 2.0, 24)
    T = api.tof(np.full(v.size, 38.0e6), 0.34, p, "hertz", vary={"striker_velocity": v})
    assert np.any(np.diff(T) > 0) and np.any(np.diff(T) < 0), "TOF(v) is monotone here"
    target = float(T[np.argmax(T)] - 0.02 * np.ptp(T))  # a TOF with two roots in v
    cal = calibrate([Reference(38.0e6, 0.34, target, 5.0e-6, id="PCF08")], device,
                    ["striker_velocity"], materials=material_set(), numerics=NUMERICS,
                    wall="hertz", loo=False)
    assert cal.references[0]["residual"] == pytest.approx(0.0, abs=0.1 * 5.0e-6)
    assert len(cal.alternatives) >= 1  # the other root is reported
    other = cal.alternatives[0]["striker_velocity"]
    assert abs(np.log(other / cal.parameters["striker_velocity"])) > 0.05


def test_more_parameters_than_references_are_refused_naming_the_flag(device, reference_tofs):
    """Two parameters from one reference (one TOF): the input cannot determine them, so the
    calibration is refused before any run, naming --free and the way on."""
    E, nu = SOILS[0]
    with pytest.raises(ConfigError, match="--free") as exc:
        calibrate([Reference(E, nu, reference_tofs[(E, nu)], 2.0e-6)], device,
                  ["striker_velocity", "preload"], materials=material_set(),
                  numerics=NUMERICS, wall="hertz", loo=False, scan_points=6)
    assert "at most 1 parameter" in str(exc.value) and "add references" in str(exc.value)


def test_parameters_the_references_cannot_separate_answer_labelled(device, reference_tofs,
                                                                   tmp_path):
    """Two references on the same soil carry one TOF's information: the striker speed and
    the preload are not separated (a singular value below the floor). The calibration still
    answers: the direction is named, there are no standard errors, the file says NOT
    IDENTIFIED, and a measurement through it lists the calibration's term as missing."""
    from ssw.modulus import estimate_moduli

    E, nu = SOILS[0]
    T = reference_tofs[(E, nu)]
    refs = [Reference(E, nu, T, 2.0e-6, id="a"), Reference(E, nu, T * (1 + 1e-4), 2.0e-6,
                                                           id="b")]
    cal = calibrate(refs, device, ["striker_velocity", "preload"], materials=material_set(),
                    numerics=NUMERICS, wall="hertz", loo=False, scan_points=6)
    assert cal.unidentified and "striker_velocity" in cal.unidentified[0]
    assert cal.covariance is None and cal.parameter_std is None
    assert any(w.startswith("NOT IDENTIFIED") for w in cal.warnings)
    path = tmp_path / "c.json"
    write_calibration(path, cal)
    back = load_calibration(path)
    assert back.warnings == cal.warnings
    est = estimate_moduli([T], [1e-6], [nu], back.chain_params(), "hertz",
                          calibration=back)[0]
    assert "calibration" in est.missing and "do not identify" in est.missing["calibration"]
    assert any("NOT IDENTIFIED" in n for n in est.notes)


@pytest.mark.parametrize(("text", "field"), [
    ("45e6,0.3", "--reference[0]"), ("45e6,0.3,abc", "--reference[0]"),
    ("45e6,0.7,1e-3", "reference ref0: nu"), ("45e6,0.3,-1e-3", "reference ref0: TOF"),
])
def test_bad_references_are_refused_naming_the_field(text, field):
    from ssw.calibration import parse_reference

    with pytest.raises(ConfigError) as exc:
        parse_reference(text)
    assert field in str(exc.value)


def test_unknown_free_parameter_is_refused(device):
    with pytest.raises(ConfigError, match="--free"):
        calibrate([Reference(45e6, 0.3, 1.5e-3, 1e-5)], device, ["bead_color"],
                  materials=material_set(), numerics=NUMERICS, wall="hertz")


@pytest.mark.parametrize("foam", ["PCF08", "PCF15", "PCF30"])
def test_each_thesis_foam_alone_calibrates_the_striker_speed(foam):
    """The thesis's measured TOFs (Table 2) on the study's device and wall (the exact FEM
    law under the 0.4 mm PLA plate): the striker speed calibrated on ONE foam succeeds for
    each of the three (TOF(v) is not monotone: a bracketing root finder failed on PCF 08
    and PCF 15), and reproduces that foam's TOF."""
    from ssw.config import load_config

    rows = {"PCF08": (38e6, 0.34, 1.78e-3), "PCF15": (123e6, 0.33, 1.46e-3),
            "PCF30": (445e6, 0.30, 1.15e-3)}
    E, nu, tof = rows[foam]
    cfg = load_config(ROOT / "config" / "config.yaml")
    dev = load_device("thesis")
    cal = calibrate([Reference(E, nu, tof, 1.0e-5, id=foam)], dev, ["striker_velocity"],
                    materials=material_set(), numerics=NUMERICS, wall="fem",
                    wall_options={"contact": cfg["contact"]}, loo=False, scan_points=16)
    assert cal.references[0]["residual"] == pytest.approx(0.0, abs=0.1 * 1.0e-5)
    assert 0.1 <= cal.parameters["striker_velocity"] <= 2.0


def test_the_readme_device_calibration_identifies_its_default_parameters(tmp_path, capsys):
    """README "Measuring with your own device", steps 2 and 3, on the example recordings
    (data/recordings: simulated by the chain with the Hertz wall, hence ``--law hertz``):
    ``ssw calibrate --device ... --reference-recording ... --output ...`` without ``--free``
    identifies the striker speed and the preload (before: "--free = None is not allowed").
    The recordings' chain had no preload and struck at the speeds stored with each hit: the
    calibrated speed is within 2 % of their mean, the preload within 0.5 N of 0 (at its
    bound, flagged, or free), and ``ssw measure`` through the file brackets PCF15's 123 MPa."""
    import json

    import h5py

    from ssw.cli import main

    rec = ROOT / "data" / "recordings"
    device = tmp_path / "my_device.yaml"
    device.write_text((ROOT / "config" / "devices" / "thesis.yaml").read_text())
    out = tmp_path / "my_calibration.json"
    args = ["calibrate", "--device", str(device), "--law", "hertz", "--calibration", "none"]
    for name, E, nu in (("PCF08", 38e6, 0.34), ("PCF15", 123e6, 0.33), ("PCF30", 445e6, 0.30)):
        args += ["--reference-recording", f"{rec / name}.h5,{E},{nu}"]
    assert main([*args, "--output", str(out)]) == 0
    capsys.readouterr()
    cal = load_calibration(out)
    assert cal.free == ("striker_velocity", "preload")
    speeds = []
    for name in ("PCF08", "PCF15", "PCF30"):
        with h5py.File(rec / f"{name}.h5") as f:
            speeds += [json.loads(h.attrs["extra_json"])["striker_velocity"]
                       for h in f["hits"].values()]
    assert cal.parameters["striker_velocity"] == pytest.approx(np.mean(speeds), rel=0.02)
    assert cal.parameters["preload"] < 0.5
    assert ("preload" in cal.at_bound) == ("preload" not in cal.covariance_parameters)
    assert main(["measure", str(rec / "PCF15.h5"), "--soil-nu", "0.33", "--device",
                 str(device), "--calibration", str(out), "--json"]) == 0
    m = json.loads(capsys.readouterr().out)
    assert m["E_low"] < 123e6 < m["E_high"]


def test_the_models_jacobian_is_exact_and_agrees_with_central_differences(device):
    """The calibration's Jacobian comes from the chain's forward sensitivities (the Hertz
    wall has them), one run for values and Jacobian, and agrees within 1e-4 relative with
    converged difference quotients of separate TOFs at the same time step (steps 3e-5 and
    1e-4 relative both): central ones, second-order one-sided ones at a preload of 0 N
    (its bound). The former
    central differences (step 1e-3) miss the sensor mass's by up to 1.4 %: the TOF bends
    in it."""
    from ssw.calibration.model import TofModel
    from ssw.calibration.residuals import model_derivatives
    from ssw.device import parameter

    free = ("striker_velocity", "preload", "sensor_mass")
    model = TofModel(device, free, np.array([45e6, 160e6, 520e6]), np.full(3, 0.3),
                     material_set(), NUMERICS, "hertz", {})
    ranges = {"striker_velocity": (0.2, 1.0), "preload": (0.0, 10.0),
              "sensor_mass": (0.01, 0.1)}
    model.fix_time_step(ranges)
    theta = np.array([[0.45, 0.0, 0.03], [0.6, 2.0, 0.05]])
    derivs = model_derivatives(model, ranges)
    assert model.forward() and derivs == model.derivatives
    runs = model.runs
    T, J = derivs(theta)
    assert model.runs == runs + 1  # one run for the values and the whole Jacobian
    assert T == pytest.approx(model(theta), rel=1e-12)
    for rel in (3e-5, 1e-4):
        rows, plan = [], []
        for j, n in enumerate(free):
            h = rel * np.maximum(np.abs(theta[:, j]), parameter(n).scale)
            one_sided = theta[:, j] - h < ranges[n][0]
            for o in (-1, 1, 2):
                pt = theta.copy()
                pt[:, j] += np.where(one_sided, max(o, 0), o) * h
                rows.append(pt)
            plan.append((h, one_sided))
        Ts = model(np.concatenate(rows)).reshape(len(free), 3, *T.shape)
        Jd = np.empty_like(J)
        for j, (h, one_sided) in enumerate(plan):
            lo, hi, hi2 = Ts[j]
            cen = (hi - lo) / (2 * h[:, None])
            one = (-3 * T + 4 * hi - hi2) / (2 * h[:, None])
            Jd[:, :, j] = np.where(one_sided[:, None], one, cen)
        # relative to each row's largest derivative in each parameter (one may cross zero)
        scale = np.abs(Jd).max(axis=1, keepdims=True)
        assert np.all(np.abs(J - Jd) <= 1e-4 * scale), rel
