"""``ssw design``: the stated sensitivity is the derivative of the chain's TOF
(ssw.tof.api.tof, what ``ssw tof`` prints, by central differences), the recommended plate
is dominated by no feasible plate (those it evaluated and a grid it did not), the device's
own plate (the thesis's 0.4 mm PLA) is among the candidates, and bad input is refused by
name.

A small design (two materials, three soil moduli) keeps the module fast; the whole design
(3 materials x 20 moduli) is timed by ``ssw bench design``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from ssw.cli import main

ROOT = Path(__file__).resolve().parents[1]
CONFIG = str(ROOT / "config" / "config.yaml")
#: The integrator's stated TOF error (relative; ssw.chain.integrate, against DOP853). A
#: scene's TOF does not depend on the batch it runs in (the time step is the chain's:
#: ssw.chain.integrate.time_step), so separate runs reproduce the design's to round-off.
TOF_RTOL = 5e-5
#: Round-off of a TOF between a batched and a separate run of the same scene.
SAME_RTOL = 1e-9
ARGS = ["design", "--config", CONFIG, "--calibration", "none", "--soil-E", "20e6:200e6",
        "--soil-nu", "0.3", "--materials", "pla,al6061", "--thickness", "1e-4:6e-4",
        "--moduli", "3", "--scan-points", "3", "--thickness-tol", "0.05",
        "--soil-yield-limit", "20"]


@pytest.fixture(scope="module")
def design(tmp_path_factory):
    out = tmp_path_factory.mktemp("design") / "design.json"
    assert main([*ARGS, "--output", str(out), "--csv", str(out.with_suffix(".csv"))]) == 0
    return json.loads(out.read_text()), out


@pytest.fixture(scope="module")
def chain():
    from ssw.chain.params import chain_params, numerics_of
    from ssw.config import device_of, library, load_config

    cfg = load_config(CONFIG)
    mats = library(cfg)
    return chain_params(device_of(cfg), mats, **numerics_of(cfg)), mats, dict(cfg["contact"])


def _params_of(chain, c):
    params, mats, _ = chain
    m = mats[c["material"]]
    return params.with_(plate_material=c["material"], plate_thickness=c["thickness"],
                        plate_E=m.E, plate_nu=m.nu, plate_diameter=c["plate_diameter"],
                        striker_velocity=c["striker_velocity"])


def test_json_states_the_question_and_every_candidate(design):
    res, out = design
    assert {"objective", "constraints", "candidates", "recommended", "pareto",
            "provenance"} <= set(res)
    for c in res["candidates"] + [res["recommended"]]:
        assert {"material", "thickness", "sensitivity_E", "sensitivity", "resolution",
                "plate_yield_index", "soil_yield_index"} <= set(c)
        assert len(c["sensitivity_E"]) == 3
        assert c["sensitivity"] == pytest.approx(min(c["sensitivity_E"]))
    assert res["recommended"]["reasons"]
    assert out.with_suffix(".csv").read_text().startswith("# ssw")
    # the scatter is the device file's (the thesis states 1.53e-5 s with the plate)
    assert res["spec"]["tof_scatter"] == pytest.approx(1.53e-5)
    assert "thesis" in res["spec"]["tof_scatter_source"]


def test_candidates_carry_their_checks(design, chain):
    """Each candidate checks its assumptions over the soils (ssw.validity) from what its
    evaluation computed: the contact's small strain is Hertz's sqrt(d / R) of its peak
    indentations, its sample's and plate's yield its own indices (the sample's at the
    stated assumption 0.01 E, named), the beads' from the chain's largest bead-bead force;
    its record states the worst over the soils, and the table one column per check."""
    res, out = design
    params = chain[0]
    for c in res["candidates"]:
        ch = {k: np.asarray(v) for k, v in c["checks_E"].items()}
        d = np.asarray(c["peak_indentation_E"])
        np.testing.assert_allclose(ch["contact_strain"], np.sqrt(d / params.bead_radius),
                                   rtol=1e-12)
        np.testing.assert_allclose(ch["plate_deflection"], d / c["thickness"], rtol=1e-12)
        np.testing.assert_array_equal(ch["sample_yield"], c["soil_yield_E"])
        np.testing.assert_array_equal(ch["plate_yield"], c["plate_yield_E"])
        assert {"bead_yield", "pulse_separation", "wall_reach"} <= set(ch)
        assert "0.01 E" in c["checks_assumed"]["sample_yield"]
        worst = {e["check"]: e for e in c["validity"]}
        assert worst["sample_yield"]["value"] == pytest.approx(c["soil_yield_index"])
        assert worst["plate_yield"]["holds"] == (c["plate_yield_index"] <= 1.0)
        assert ("plate_yield" in " ".join(c["checks_failed"])) == (
            c["plate_yield_index"] > 1.0)
    head = next(ln for ln in out.with_suffix(".csv").read_text().splitlines()
                if not ln.startswith("#"))
    assert head.endswith("recommended,check_contact_strain,check_plate_deflection,"
                         "check_wall_reach,check_pulse_separation,check_bead_yield,"
                         "check_sample_yield,check_plate_yield,checks_failed")


def test_thesis_plate_is_a_candidate_with_its_own_chain(design, chain):
    """The device's 0.4 mm PLA plate is evaluated (source ``reference``) and its TOFs are
    the chain's with the fem wall of that plate."""
    from ssw.tof.api import tof

    res, _ = design
    ref = [c for c in res["candidates"] if c["source"] == "reference"]
    assert len(ref) == 1 and res["reference"]["thickness"] == ref[0]["thickness"]
    c = ref[0]
    assert c["material"] == "pla" and c["thickness"] == pytest.approx(0.4e-3)
    E = np.asarray(c["soil_E"])
    t = tof(E, 0.3, _params_of(chain, c), "fem", contact=chain[2])
    assert np.asarray(c["tof_E"]) == pytest.approx(t, rel=SAME_RTOL)
    assert np.all(np.isfinite([c["plate_yield_index"], c["soil_yield_index"],
                               c["resolution"]]))


def test_sensitivity_is_the_derivative_of_ssw_tof(design, chain):
    """S(E) = |d ln TOF / d ln E|, the exact derivative of the discrete TOF: central
    differences of separate ssw.tof.api.tof runs at E e^(+-h), h = 2e-3 (truncation
    O(h^2) ~ 1e-6, the smooth TOF's noise over h ~ 1e-8 / h), agree within 1e-4
    relative. The former difference quotient (h = 0.05) misses them by its truncation."""
    from ssw.tof.api import tof

    res, _ = design
    h = 2e-3
    for c in (res["recommended"], res["reference"]):
        p = _params_of(chain, c)
        E = np.asarray(c["soil_E"])
        S = np.asarray(c["sensitivity_E"])
        T = np.asarray(c["tof_E"])
        for k in (0, E.size - 1):
            lo, hi = (float(tof(E[k] * np.exp(s * h), 0.3, p, "fem", contact=chain[2]))
                      for s in (-1, 1))
            fd = abs(np.log(hi) - np.log(lo)) / (2 * h)
            assert S[k] == pytest.approx(fd, rel=1e-4)
            assert lo > T[k] > hi  # the TOF falls as the soil stiffens


def _dominates(a, b, tol=0.0):
    """``a`` is at least as sensitive and yields the sample no more, one strictly."""
    ge = a["sensitivity"] >= b["sensitivity"] * (1 + tol)
    le = a["soil_yield_index"] <= b["soil_yield_index"]
    strict = a["sensitivity"] > b["sensitivity"] * (1 + tol) or \
        a["soil_yield_index"] < b["soil_yield_index"]
    return ge and le and strict


def test_no_feasible_candidate_dominates_the_recommended(design, chain):
    """Among the candidates evaluated and a grid of plates the search never tried, no
    feasible one (plate elastic, mass and soil within the limits) is more sensitive and
    yields the sample less. The grid's sensitivity is allowed the TOF noise of the chain
    (2 TOF_RTOL / h relative, the search cannot see below it)."""
    from ssw.design.evaluate import Candidate, Evaluator
    from ssw.design.spec import DesignSpec

    res, _ = design
    rec = res["recommended"]
    feasible = [c for c in res["candidates"] if c["feasible"]]
    assert rec["feasible"] and len(feasible) >= 2  # the check is not vacuous
    assert not any(_dominates(c, rec) for c in feasible)
    spec_fields = {k: (tuple(v) if isinstance(v, list) else v)
                   for k, v in res["spec"].items() if k != "soil_E_grid"}
    spec = DesignSpec(**spec_fields)
    params, mats, contact = chain
    ev = Evaluator(spec, params, mats, contact)
    tol = 2 * TOF_RTOL / spec.log_step / rec["sensitivity"]
    tried = {(c["material"], round(c["thickness"], 7)) for c in res["candidates"]}
    grid = []
    for m in ("pla", "al6061"):
        for t in (1.3e-4, 2.0e-4, 4.5e-4):
            assert (m, round(t, 7)) not in tried
            grid.append(ev(m, t).to_dict())
    assert any(c["plate_yield_index"] > 1 for c in grid)  # the limit binds on the grid
    for c in grid:
        c_ok = Candidate.from_dict(c, ev.limits).feasible
        assert not (c_ok and _dominates(c, rec, tol)), (c["material"], c["thickness"])


def test_merged_results_rank_like_one_design(design, tmp_path):
    """Two results of the same question merge into one ranking with the same recommended
    plate (the workflow runs one job per material)."""
    res, out = design
    other = tmp_path / "copy.json"
    other.write_text(json.dumps({**res, "candidates": res["candidates"][::-1]}))
    merged = tmp_path / "merged.json"
    assert main(["design", "--merge", str(out), str(other), "--output", str(merged)]) == 0
    m = json.loads(merged.read_text())
    assert (m["recommended"]["material"], m["recommended"]["thickness"]) == \
        (res["recommended"]["material"], res["recommended"]["thickness"])
    assert len(m["candidates"]) == len(res["candidates"])


@pytest.mark.parametrize("flags, field", [
    (["--soil-E", "2e8:2e7", "--soil-nu", "0.3"], "--soil-E"),
    (["--soil-E", "2e7:2e8", "--soil-nu", "0.3", "--materials", "unobtainium"], "--materials"),
    (["--soil-E", "2e7:2e8", "--soil-nu", "0.3", "--thickness", "3e-3:1e-4"], "--thickness"),
    (["--soil-nu", "0.3"], "--soil-E"),
])
def test_bad_input_is_refused_by_name(flags, field, capsys):
    assert main(["design", "--config", CONFIG, "--calibration", "none", *flags]) == 2
    assert field in capsys.readouterr().err
