"""Inputs refused before anything is computed, naming the field and the value: NaN and
infinities in every number of every input kind (the study config with its survey and DAQ
sections, the device, the materials library; the DAQ settings built in code are in
tests/test_daq_settings.py), and names that would reach a shell or a file name.

Truth: JSON has no NaN and no infinity, and every numeric field of ssw is a physical value
(a length, a modulus, a time, a count): none may be NaN or infinite. YAML's ``.nan`` and
``.inf`` read as floats that pass every bound of JSON Schema (NaN compares false with any
limit), so each must be refused by the validator itself.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml

from ssw.config import REPO_ROOT, validate_config
from ssw.errors import ConfigError

NON_FINITE = (float("nan"), float("inf"), float("-inf"))
CONFIGS = ("config.yaml", "ci.yaml", "survey_example.yaml")


@pytest.fixture(autouse=True)
def _no_memo(monkeypatch):
    """Every validation here runs the validator (no remembered validations)."""
    monkeypatch.setenv("SSW_CACHE_DIR", "none")


def numeric_leaves(node: Any, path: tuple = ()) -> Iterator[tuple]:
    """The paths of the numbers (not booleans) in a document of dicts and lists."""
    if isinstance(node, dict):
        for k, v in node.items():
            yield from numeric_leaves(v, (*path, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from numeric_leaves(v, (*path, i))
    elif isinstance(node, int | float) and not isinstance(node, bool):
        yield path


def with_value(doc: Any, path: tuple, value: Any) -> Any:
    """A copy of ``doc`` with ``value`` at ``path``."""
    out = copy.deepcopy(doc)
    node = out
    for k in path[:-1]:
        node = node[k]
    node[path[-1]] = value
    return out


def _error_paths(errors: Any) -> set[tuple]:
    """The instance paths of ``errors`` and of the errors of their alternatives."""
    out = set()
    for e in errors:
        out.add(tuple(e.absolute_path))
        out |= _error_paths(e.context)
    return out


@pytest.mark.parametrize("name", CONFIGS)
def test_every_number_of_a_study_config_refuses_nan_and_infinities(name):
    """Every number of the shipped study configs, defaults filled (every section: contact,
    fit, calibration, chain, design, DAQ and its simulation, validation samples, survey
    points and frame), made NaN, +inf or -inf: each is an error of the schema at its own
    field. Then one at a time (every number of the first survey point, every tenth other
    one): refused with
    a ConfigError naming that field and the value."""
    from ssw.config import SCHEMA_PATH
    from ssw.schema import first_error, validator
    from ssw.yamlio import safe_load

    filled = validate_config(yaml.safe_load((REPO_ROOT / "config" / name).read_text()))
    leaves = list(numeric_leaves(filled))
    assert len(leaves) >= 60, len(leaves)
    sections = {p[0] for p in leaves}
    assert {"contact", "chain", "daq", "design", "validation"} <= sections, sections
    if name != "config.yaml":
        assert "survey" in sections
    everywhere = filled
    for i, path in enumerate(leaves):
        everywhere = with_value(everywhere, path, NON_FINITE[i % 3])
    schema = safe_load(SCHEMA_PATH.read_text())
    errors = list(validator(schema).iter_errors(everywhere))
    missed = [p for p in leaves if p not in _error_paths(errors)]
    assert not missed, missed
    assert first_error(schema, everywhere).validator in ("finite", "type")
    for i, path in enumerate(leaves):
        if path[:3] != ("survey", "points", 0) and i % 10:
            continue
        bad = NON_FINITE[i % 3]
        with pytest.raises(ConfigError) as exc:
            validate_config(with_value(filled, path, bad))
        assert exc.value.field == ".".join(map(str, path)), (path, str(exc.value))
        assert f"= {bad!r} is not allowed" in str(exc.value)


def test_the_refusal_says_why():
    """A NaN in a grid's values (one branch of the grid's oneOf) is reported as such, not
    as a grid that matches neither form."""
    raw = yaml.safe_load((REPO_ROOT / "config" / "config.yaml").read_text())
    raw["sets"]["set3_soil"]["soil_nu"] = {"values": [0.1, float("nan"), 0.5]}
    with pytest.raises(ConfigError, match=r"sets\.set3_soil\.soil_nu\.values\.1 = nan is "
                                          r"not allowed: not a finite number"):
        validate_config(raw)
    raw["sets"]["set3_soil"]["soil_nu"] = {"values": [0.1, 0.3, 0.5]}
    raw["daq"]["timeout"] = float("inf")
    with pytest.raises(ConfigError, match=r"daq\.timeout = inf"):
        validate_config(raw)


def test_a_schema_may_let_a_number_be_non_finite():
    """The validator's rule is the schema's to lift: ``allowNonFinite: true``."""
    from ssw.schema import first_error

    schema = {"type": "object", "properties": {
        "strict": {"type": "number"},
        "open": {"type": ["number", "null"], "allowNonFinite": True}}}
    assert first_error(schema, {"open": float("inf"), "strict": 1.0}) is None
    err = first_error(schema, {"open": float("nan"), "strict": float("-inf")})
    assert list(err.absolute_path) == ["strict"] and err.validator == "finite"


def test_every_number_of_the_device_refuses_nan_and_infinities():
    """The shipped device file: every number replaced by NaN, +inf or -inf in turn is
    refused by the device's schema (through the same validator), naming the field."""
    from ssw.device import device_from_dict

    raw = yaml.safe_load((REPO_ROOT / "config" / "devices" / "thesis.yaml").read_text())
    leaves = list(numeric_leaves(raw))
    assert len(leaves) >= 10
    for i, path in enumerate(leaves):
        bad = NON_FINITE[i % 3]
        with pytest.raises(ConfigError) as exc:
            device_from_dict(with_value(raw, path, bad), "thesis.yaml")
        assert exc.value.field.endswith(".".join(map(str, path))), (path, str(exc.value))
        assert math.isnan(exc.value.value) if math.isnan(bad) else exc.value.value == bad


def test_every_number_of_the_materials_library_refuses_nan_and_infinities(monkeypatch):
    """The shipped materials library: every number of every material (E, nu, density,
    strengths), in every set, replaced by NaN, +inf or -inf in turn, refused naming
    ``materials.<key>.<field>``; a value that is not a number is refused as such."""
    from ssw import materials
    from ssw.materials import DEFAULT_LIBRARY, material_set

    lib = yaml.safe_load(DEFAULT_LIBRARY.read_text())
    leaves = list(numeric_leaves(lib))
    assert len(leaves) >= 60
    for i, path in enumerate(leaves):
        bad = NON_FINITE[i % 3]
        edited = with_value(lib, path, bad)
        monkeypatch.setattr(materials, "load_library", lambda p=None, d=edited: d)
        with pytest.raises(ConfigError) as exc:
            material_set(path[0])
        assert exc.value.field == "materials." + ".".join(map(str, path[1:])), \
            (path, str(exc.value))
    edited = with_value(lib, ("realistic", "pla", "E"), "3.5e9")
    monkeypatch.setattr(materials, "load_library", lambda p=None, d=edited: d)
    with pytest.raises(ConfigError, match=r"materials\.pla\.E = '3\.5e9'.*a number"):
        material_set("realistic")


def test_a_nan_in_a_library_file_is_read_and_refused(tmp_path):
    """The same through a YAML file: ``.nan`` reads as a float, and is refused."""
    from ssw.materials import DEFAULT_LIBRARY, material_set

    f = tmp_path / "materials.yaml"
    f.write_text(DEFAULT_LIBRARY.read_text().replace("    density: 1240.0\n",
                                                      "    density: .nan\n", 1))
    with pytest.raises(ConfigError, match=r"materials\.pla\.density = nan"):
        material_set("realistic", f)


BAD_NAMES = ("my soil", "x;touch pwned", "$(touch pwned)", "-x", "../up", "a/b", "")


@pytest.mark.parametrize("bad", BAD_NAMES)
@pytest.mark.parametrize("where", ["set", "soil", "point", "sample", "material"])
def test_names_that_reach_a_shell_or_a_file_name_have_a_pattern(where, bad):
    """Set names, design soil ranges, survey point ids, validation sample ids and material
    keys become file names, wildcards and command arguments: a space, shell syntax, a
    leading dash, a path are refused by the schema, naming the field, the name and what a
    name may hold."""
    raw = yaml.safe_load((REPO_ROOT / "config" / "ci.yaml").read_text())
    if where == "set":
        raw["sets"][bad] = raw["sets"].pop("set1_materials")
        field = "sets"
    elif where == "soil":
        raw["design"] = {"soils": {bad: {"soil_E": [1e7, 1e9], "soil_nu": 0.3}}}
        field = "design.soils"
    elif where == "point":
        raw["survey"]["points"][1]["id"] = bad
        field = "survey.points.1.id"
    elif where == "sample":
        raw["validation"]["samples"][2]["id"] = bad
        field = "validation.samples.2.id"
    else:
        raw["design"] = {"materials": ["pla", bad]}
        field = "design.materials.1"
    with pytest.raises(ConfigError) as exc:
        validate_config(raw)
    assert exc.value.field == field and exc.value.value == bad, str(exc.value)
    assert "letters, digits" in exc.value.allowed


def test_shipped_names_follow_the_patterns():
    """The names the shipped configs and library use all pass (the patterns refuse only
    what would break a file name or a command)."""
    from ssw.materials import DEFAULT_LIBRARY, material_set

    for name in CONFIGS:
        validate_config(yaml.safe_load((REPO_ROOT / "config" / name).read_text()))
    lib = yaml.safe_load(DEFAULT_LIBRARY.read_text())
    assert {k for s in lib for k in material_set(s)} == set(lib["realistic"])


def test_a_library_key_that_is_not_a_name_is_refused(tmp_path):
    """A materials library's key enters scene ids and file names: ``pla x`` is refused."""
    from ssw.materials import DEFAULT_LIBRARY, material_set

    lib = yaml.safe_load(DEFAULT_LIBRARY.read_text())
    lib["realistic"]["pla x"] = lib["realistic"]["pla"]
    f = Path(tmp_path) / "materials.yaml"
    f.write_text(yaml.safe_dump(lib))
    with pytest.raises(ConfigError, match=r"materials\.pla x = 'pla x'.*letters, digits"):
        material_set("realistic", f)
