"""The calibration file is validated when read (``ssw/data/calibration.schema.yaml``): a
field of the wrong type or range, a NaN or an infinity anywhere, a file of the former format:
each refused naming the field, what is allowed and the way on; a valid file round-trips."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ssw.calibration import Reference, calibrate, load_calibration, write_calibration
from ssw.chain.params import chain_params
from ssw.device import load_device
from ssw.errors import ConfigError
from ssw.materials import material_set
from ssw.tof import api

NUM = {"steps_per_contact": 80, "t_max": 0.02, "gravity": True, "damping": 0.0}
SOILS = [(38e6, 0.34), (123e6, 0.33), (445e6, 0.30)]


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """A calibration whose references reject its model (a 1.5x sensor and 5 N s/m dashpots
    the model lacks, 0.1 % TOF uncertainties): its file carries the model-error term."""
    dev = load_device().with_(preload=0.0, striker_velocity=0.5)
    heavy = dev.with_(sensor_mass=1.5 * chain_params(dev, material_set(), **NUM).bead_mass)
    p = chain_params(heavy, material_set(), **{**NUM, "damping": 5.0})
    T = np.asarray(api.tof(np.array([e for e, _ in SOILS]), np.array([n for _, n in SOILS]),
                           p, "hertz"), float)
    refs = [Reference(E, nu, float(t), float(1e-3 * t), id=f"r{i}")
            for i, ((E, nu), t) in enumerate(zip(SOILS, T, strict=True))]
    cal = calibrate(refs, dev.with_(preload=3.0), ["striker_velocity", "preload"],
                    materials=material_set(), numerics=NUM, wall="hertz", loo=False)
    path = tmp_path_factory.mktemp("cal") / "c.json"
    write_calibration(path, cal)
    return cal, path


def test_a_valid_file_round_trips_with_its_model_error(written):
    cal, path = written
    back = load_calibration(path)
    assert back.model_error == cal.model_error and back.model_error["tau"] > 0
    assert back.warnings == cal.warnings and back.parameters == cal.parameters
    assert back.model_term() == cal.model_term()


def _edited(path, tmp_path, edit):
    d = json.loads(path.read_text())
    edit(d)
    out = tmp_path / "edited.json"
    out.write_text(json.dumps(d))  # json writes NaN and Infinity as such
    return out


@pytest.mark.parametrize(("edit", "field", "allowed"), [
    (lambda d: d["references"][1].update(tof=-1e-3), "references.1.tof", "minimum"),
    (lambda d: d["model_error"].update(tau=-0.01), "model_error.tau", "minimum"),
    (lambda d: d["model_error"].pop("tau"), "model_error", "'tau' is a required property"),
    (lambda d: d.update(covariance="none"), "covariance", "not of type"),
    (lambda d: d.pop("warnings"), "(top level)", "'warnings' is a required property"),
    (lambda d: d["at_bound"].update(preload="below"), "at_bound.preload", "is not one of"),
    (lambda d: d["provenance"].update(information={"gain": 0.0}),
     "provenance.information.gain", "minimum"),
])
def test_a_field_out_of_its_schema_is_refused_naming_it(written, tmp_path, edit, field,
                                                        allowed):
    _, path = written
    with pytest.raises(ConfigError) as exc:
        load_calibration(_edited(path, tmp_path, edit))
    assert f"c.json: {field}".replace("c.json", "edited.json") in str(exc.value)
    assert allowed in str(exc.value)


@pytest.mark.parametrize(("edit", "field"), [
    (lambda d: d["references"][0].update(tof_std=float("nan")), "references.0.tof_std"),
    (lambda d: d["covariance"][0].__setitem__(0, float("inf")), "covariance.0.0"),
    (lambda d: d["model_error"].update(tau=float("nan")), "model_error.tau"),
    (lambda d: d["provenance"].update(chi2=float("-inf")), "provenance.chi2"),
])
def test_nan_and_infinities_are_refused_naming_the_field(written, tmp_path, edit, field):
    """JSON Schema's bounds let NaN through (every comparison with NaN is false): a check of
    its own refuses them, and infinities, anywhere in the file."""
    _, path = written
    with pytest.raises(ConfigError) as exc:
        load_calibration(_edited(path, tmp_path, edit))
    assert f"edited.json: {field}" in str(exc.value) and "a finite number" in str(exc.value)


def test_a_file_of_the_former_format_is_refused_saying_how_to_go_on(written, tmp_path):
    _, path = written
    old = _edited(path, tmp_path, lambda d: d.update(schema_version=1))
    with pytest.raises(ConfigError, match="schema_version") as exc:
        load_calibration(old)
    assert "recalibrate with this ssw" in str(exc.value)


def test_a_value_that_is_not_finite_is_not_written(written, tmp_path):
    from dataclasses import replace

    cal, _ = written
    bad = replace(cal, provenance={**cal.provenance, "chi2": float("nan")})
    with pytest.raises(ValueError, match=r"provenance\.chi2"):
        write_calibration(tmp_path / "bad.json", bad)
    assert not (tmp_path / "bad.json").exists()
