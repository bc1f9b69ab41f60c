"""Short modules and short functions in the physics: no module of the chain, the contact,
the walls, the constitutive models, the TOF, the root finder, the calibration or the
measurement over 800 lines, no function there over 100 (from its ``def`` to its last line,
docstring included), so that a reader finds one concept per module and one step per
function.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parent.parent / "ssw"

#: The areas held to the limits (folders of ssw, or single modules).
AREAS = ("chain", "contact", "walls", "constitutive", "tof", "roots.py", "bench/chain.py",
         "calibration", "measure")
#: Most lines of a module.
MODULE_LINES = 800
#: Most lines of a function (``def`` to its last line).
FUNCTION_LINES = 100


def _files() -> list[Path]:
    out: list[Path] = []
    for area in AREAS:
        path = PKG / area
        out += sorted(path.rglob("*.py")) if path.is_dir() else [path]
    return out


@pytest.mark.parametrize("path", _files(), ids=lambda p: str(p.relative_to(PKG)))
def test_module_and_its_functions_are_short(path):
    """The module's length and each function's, against the limits."""
    text = path.read_text()
    assert len(text.splitlines()) <= MODULE_LINES, f"{path.name}: split it by concept"
    long = [(node.name, node.end_lineno - node.lineno + 1)
            for node in ast.walk(ast.parse(text))
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
            and node.end_lineno - node.lineno + 1 > FUNCTION_LINES]
    assert not long, f"{path.name}: functions over {FUNCTION_LINES} lines: {long}"


def test_the_moved_names_are_importable_where_they_were():
    """The wall laws and the contact operators' records moved to modules of their own; the
    names their users import stay importable from the modules they came from, the same
    objects."""
    import ssw.chain.wall as wall
    import ssw.chain.wall_base as base
    import ssw.chain.wall_power as power
    import ssw.chain.wall_table as table
    import ssw.contact.coupling as coupling
    import ssw.contact.operators as ops
    import ssw.contact.retained as retained

    moved = {
        wall: {base: ("compliance_scale", "compliance_scale_dE", "force_indentation",
                      "scene_arrays"),
               power: ("PowerWall", "fit_wall", "hertz_wall", "rigid_wall"),
               table: ("TABLE_CELLS", "TABLE_TAIL", "TableWall", "table_wall")},
        ops: {retained: ("BodyOperator", "Layout", "sphere_gap0"),
              coupling: ("SCENES_KEPT", "SceneLCP", "coupled_stiffness", "scene_lcp")},
    }
    for old, homes in moved.items():
        for new, names in homes.items():
            for name in names:
                assert getattr(old, name) is getattr(new, name), (old.__name__, name)


def test_the_calibration_s_moved_names_are_importable_where_they_were():
    """The calibration of records, the TOF calibration's scan and the measurement of
    records moved to modules of their own; every name stays importable from the module it
    came from, the same object."""
    import ssw.calibration.fit as fit
    import ssw.calibration.hits as hits
    import ssw.calibration.observation as observation
    import ssw.calibration.scan as scan
    import ssw.calibration.start as start
    import ssw.calibration.waveform as waveform
    import ssw.calibration.waveform_fit as waveform_fit
    import ssw.measure as measure
    import ssw.measure.records as records

    moved = {
        waveform: {hits: ("LEVELS", "PARAMETERS", "GLOBALS", "CHAIN_GLOBALS", "PER_HIT",
                          "LEAD", "RAIL_SHARE", "Hits", "State", "Column", "columns_of",
                          "get", "put", "device_globals", "parameter"),
                   observation: ("Observed", "Setup", "observe", "initial_state",
                                 "coordinate", "to_x", "from_x", "dtheta_dx", "_corrected",
                                 "_bounds"),
                   waveform_fit: ("FLAG_QUANTILE", "Fit", "fit", "global_covariance",
                                  "noise_std", "propagated", "_Explained"),
                   start: ("START_SENSOR_MASS", "START_DAMPING", "START_ITERATIONS",
                           "START_FLOOR", "REFINE_LEVELS", "REFINE_POINTS", "model_floor",
                           "start_damping", "global_start", "refine_start", "_fit_points")},
        fit: {scan: ("SCAN_POINTS_1D", "SCAN_BUDGET", "STARTS", "PRUNE_AFTER", "PRUNE_CHI2",
                     "DISTINCT", "Solution", "scan_ranges", "scan_grid", "_lm_batch",
                     "_scaled", "_starts", "_pick")},
        measure: {records: ("measure_information",)},
    }
    for old, homes in moved.items():
        for new, names in homes.items():
            for name in names:
                assert getattr(old, name) is getattr(new, name), (old.__name__, name)
