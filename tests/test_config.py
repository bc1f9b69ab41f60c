"""Config schema and semantic checks: bad values are refused naming the field."""

import copy

import numpy as np
import pytest
import yaml

from ssw.config import DEFAULT_CONFIG, expand_grid, load_config, scenes, validate_config
from ssw.errors import ConfigError
from ssw.materials import get_material, material_set


@pytest.fixture(scope="module")
def thesis_raw():
    return yaml.safe_load(DEFAULT_CONFIG.read_text())


def test_thesis_config_mirrors_the_thesis(thesis_raw):
    cfg = validate_config(copy.deepcopy(thesis_raw))
    # Set 3: E 10..1000 MPa step 10 (100 values) x nu 0.1/0.3/0.5, PLA 0.4 mm (thesis Table 1)
    s3 = scenes(cfg, "set3_soil")
    assert len(s3) == 300
    assert {s.soil_nu for s in s3} == {0.1, 0.3, 0.5}
    assert min(s.soil_E for s in s3) == 10e6 and max(s.soil_E for s in s3) == 1000e6
    assert {s.plate_thickness for s in s3} == {0.4e-3}
    # Set 2: PLA 0.1, 0.2, 0.4, 1.0 mm (and the no-plate reference)
    t2 = sorted({s.plate_thickness for s in scenes(cfg, "set2_thickness")})
    assert t2 == [0.0, 0.1e-3, 0.2e-3, 0.4e-3, 1.0e-3]
    # Set 1: three plate materials at 0.4 mm
    assert {s.plate_material for s in scenes(cfg, "set1_materials")} == {"pla", "al6061", "a36"}
    assert cfg["indenter"]["radius"] == 9.53e-3
    assert cfg["contact"]["steps"] * 1e-7 == pytest.approx(cfg["contact"]["delta_max"])


def test_defaults_are_filled():
    cfg = validate_config({"sets": {"s": {"plate_material": ["pla"],
                                          "plate_thickness": {"values": [4e-4]},
                                          "soil_E": {"values": [5e7]},
                                          "soil_nu": {"values": [0.3]}}}})
    assert cfg["contact"]["interface"] == "frictionless"
    assert cfg["chain"]["sweep"]["soil_nu"] == {"values": [0.1, 0.3, 0.5]}


@pytest.mark.parametrize(
    ("path", "value", "field"),
    [
        (("sets", "set2_thickness", "plate_thickness"), {"values": [-0.4e-3]},
         "sets.set2_thickness.plate_thickness"),
        (("sets", "set3_soil", "soil_nu"), {"values": [0.6]}, "sets.set3_soil.soil_nu"),
        (("sets", "set3_soil", "soil_E"), {"values": [0.0]}, "sets.set3_soil.soil_E"),
        (("sets", "set1_materials", "plate_material"), ["unobtainium"],
         "sets.set1_materials.plate_material[0]"),
        (("indenter", "radius"), -1.0, "indenter.radius"),
        (("contact", "interface"), "glued", "contact.interface"),
        (("chain", "wall_law"), "cheese", "chain.wall_law"),
        (("device",), "no-such-device", "--device"),
    ],
)
def test_bad_values_are_refused_naming_the_field(thesis_raw, path, value, field):
    cfg = copy.deepcopy(thesis_raw)
    node = cfg
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    with pytest.raises(ConfigError) as exc:
        validate_config(cfg)
    assert exc.value.field == field
    assert str(exc.value).startswith(field)
    # the message shows the offending value
    shown = value["values"] if isinstance(value, dict) else value
    assert str(shown).strip("[]'") in str(exc.value)


def test_unknown_key_is_refused(thesis_raw):
    cfg = copy.deepcopy(thesis_raw)
    cfg["contact"]["mesh_sise"] = 3
    with pytest.raises(ConfigError, match="mesh_sise"):
        validate_config(cfg)


def test_grid_expansion_includes_stop_and_refuses_misfit():
    assert np.allclose(expand_grid({"start": 10e6, "stop": 1000e6, "step": 10e6}, "f"),
                       np.arange(1, 101) * 10e6)
    with pytest.raises(ConfigError, match="f"):
        expand_grid({"start": 0.0, "stop": 1.0, "step": 0.3}, "f")


def test_missing_config_file(tmp_path):
    with pytest.raises(ConfigError, match="--config"):
        load_config(tmp_path / "nope.yaml")


def test_materials_sets():
    real, printed = material_set("realistic"), material_set("as_printed")
    # the thesis's Table 1 as printed: Al 10 MPa, PLA 100 MPa, A36 210 MPa
    assert printed["al6061"].E == 10e6 and printed["pla"].E == 100e6 and printed["a36"].E == 210e6
    assert real["al6061"].E == 68.9e9 and real["pla"].E == 3.5e9 and real["a36"].E == 200e9
    # the as-printed set inherits everything else from realistic
    assert printed["pla"].nu == real["pla"].nu and printed["pcf15"] == real["pcf15"]
    assert all(m.source for m in real.values())
    with pytest.raises(ConfigError, match="material"):
        get_material("cheese")


def test_a_remembered_validation_gives_the_filled_config_itself(tmp_path, monkeypatch,
                                                                thesis_raw):
    """The disk memo of valid (schema, config) pairs (ssw.schema.first_file_error) returns
    exactly what jsonschema's validation fills in, key order included, and never stands in
    for a config it has not seen: an invalid one is still refused after a valid one, and
    one with a NaN is neither accepted nor remembered."""
    import json

    monkeypatch.setenv("SSW_CACHE_DIR", str(tmp_path))
    fresh = validate_config(copy.deepcopy(thesis_raw))
    assert list((tmp_path / "schema").glob("*.json"))  # the config's (and its device's)
    again = validate_config(copy.deepcopy(thesis_raw))
    assert json.dumps(again) == json.dumps(fresh)
    monkeypatch.setenv("SSW_CACHE_DIR", "none")
    assert json.dumps(validate_config(copy.deepcopy(thesis_raw))) == json.dumps(fresh)
    monkeypatch.setenv("SSW_CACHE_DIR", str(tmp_path))
    bad = copy.deepcopy(thesis_raw)
    bad["contact"]["steps"] = -3
    with pytest.raises(ConfigError, match=r"contact\.steps"):
        validate_config(bad)
    kept = sorted((tmp_path / "schema").glob("*.json"))
    nan = copy.deepcopy(thesis_raw)
    nan["contact"]["reach_energy"] = float("nan")
    with pytest.raises(ConfigError, match=r"contact\.reach_energy = nan"):
        validate_config(nan)
    assert sorted((tmp_path / "schema").glob("*.json")) == kept


def _config_memo(folder):
    """The remembered validation of a study config in ``folder`` (the one with ``sets``)."""
    import json

    memos = [p for p in (folder / "schema").glob("*.json")
             if "sets" in json.loads(p.read_text())]
    assert len(memos) == 1, memos
    return memos[0]


@pytest.mark.parametrize(("edit", "reason"), [
    # a default the config does not set, made invalid: the schema refuses it again
    (lambda m: m["chain"].update(wall_dynamics="bogus"), r"chain\.wall_dynamics"),
    # a value of the config itself changed (valid): the memo is another config's
    (lambda m: m["contact"].update(steps=999), "does not hold the document"),
    # a default left out: validating it again fills it, so it was not the filled config
    (lambda m: m["chain"].pop("wall_dynamics"), "fills defaults"),
])
def test_a_remembered_validation_that_fails_again_is_discarded(tmp_path, monkeypatch,
                                                                thesis_raw, edit, reason):
    """A memo is validated again when read: one that does not hold its config, fails the
    schema or lacks a default is discarded with a warning naming why, the config itself is
    validated and the right memo written in its place."""
    import json

    from ssw.schema import MemoWarning

    monkeypatch.setenv("SSW_CACHE_DIR", str(tmp_path))
    fresh = validate_config(copy.deepcopy(thesis_raw))
    memo = _config_memo(tmp_path)
    assert json.loads(memo.read_text()) == fresh
    changed = json.loads(memo.read_text())
    edit(changed)
    memo.write_text(json.dumps(changed))
    with pytest.warns(MemoWarning, match=reason):
        got = validate_config(copy.deepcopy(thesis_raw))
    assert json.dumps(got) == json.dumps(fresh)
    assert memo.read_text() == json.dumps(fresh)


def test_a_process_that_turns_memo_writes_off_validates_and_writes_nothing(tmp_path,
                                                                          monkeypatch):
    """The workflow's own process (a Snakefile parse: a dry run, a lint) reads remembered
    validations and writes none; a job's process writes them."""
    from ssw import schema

    raw = yaml.safe_load(DEFAULT_CONFIG.read_text())
    monkeypatch.setenv("SSW_CACHE_DIR", str(tmp_path))
    try:
        schema.set_memo_writes(False)
        quiet = validate_config(copy.deepcopy(raw))
        assert not (tmp_path / "schema").exists()
    finally:
        schema.set_memo_writes(True)
    assert validate_config(copy.deepcopy(raw)) == quiet
    assert len(list((tmp_path / "schema").glob("*.json"))) >= 1
