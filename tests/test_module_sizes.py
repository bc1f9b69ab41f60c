"""Short modules and short functions in the physics: no module of the chain, the contact,
the walls, the constitutive models, the TOF or the root finder over 800 lines, no function
there over 100 (from its ``def`` to its last line, docstring included), so that a reader
finds one concept per module and one step per function.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parent.parent / "ssw"

#: The areas held to the limits (folders of ssw, or single modules).
AREAS = ("chain", "contact", "walls", "constitutive", "tof", "roots.py", "bench/chain.py")
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
