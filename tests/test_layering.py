"""The house is layered: data at the bottom, physics above, applications, then the command
line and the workflow on top. Every import of every module (at module level or inside a
function, found statically) goes down or sideways within its area, never up; the data layer
imports no heavy library (the workflow imports it when it parses).
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parent.parent / "ssw"

#: Each area (a module or subpackage of ssw) and the areas it may import. An area not
#: listed may import nothing of ssw but the foundation.
FOUNDATION = {"ssw", "errors", "provenance", "schema", "roots", "hertz", "materials", "h5io",
              "plotting", "progress", "curve", "yamlio", "cachefile"}
DATA = {"device", "config", "sample", "constitutive"}
ALLOWED: dict[str, set[str]] = {
    # foundation: errors at the very bottom
    "errors": set(), "ssw": set(), "schema": {"yamlio", "h5io"}, "yamlio": set(),
    "roots": {"errors"},
    "hertz": {"errors", "roots"},
    "materials": {"errors", "yamlio"}, "provenance": {"errors", "ssw"},
    "h5io": {"errors", "ssw", "provenance"}, "plotting": {"h5io"}, "progress": set(),
    "curve": {"errors", "h5io"},
    # a disk cache's files: their format version and the shapes they promise
    "cachefile": {"h5io"},
    # data
    "device": FOUNDATION, "sample": FOUNDATION, "constitutive": FOUNDATION,
    "config": FOUNDATION | {"device", "sample", "constitutive"},
    # physics: the chain knows the wall protocol only; the laws by name are ssw.walls.
    # The peak rule (ssw.signal.rule) is the signal area's: the chain reads it
    "contact": FOUNDATION | DATA,
    "signal": FOUNDATION,
    "chain": FOUNDATION | DATA | {"signal"},
    "fit": FOUNDATION | DATA | {"contact", "chain"},
    "dynamics": FOUNDATION | DATA | {"contact", "chain"},
    "walls": FOUNDATION | DATA | {"contact", "chain", "fit", "dynamics"},
    # the device's TOF on a sample: the chain on a law named in ssw.walls
    # the checks of a result's assumptions: pure functions of a run, its contact stresses
    "validity": FOUNDATION | DATA | {"chain", "signal", "walls"},
    "tof": FOUNDATION | DATA | {"contact", "chain", "fit", "walls", "validity"},
    "daq": FOUNDATION | DATA | {"chain", "signal", "walls", "tof"},
    # applications
    "modulus": FOUNDATION | DATA | {"chain", "walls", "tof"},
    "calibration": FOUNDATION | DATA | {"chain", "walls", "tof", "signal", "daq", "modulus"},
    "measure": FOUNDATION | DATA | {"modulus", "signal", "daq", "chain", "walls", "tof",
                                    "calibration", "contact", "validity"},
    "survey": FOUNDATION | DATA | {"validity"},
    "validation": FOUNDATION | DATA | {"calibration", "chain", "walls", "tof", "daq",
                                       "modulus", "signal", "validity", "measure"},
    # the design predicts what the instrument would measure and builds a virtual prototype:
    # it calls the calibration and the measurement, which know nothing of it
    "design": FOUNDATION | DATA | {"contact", "chain", "walls", "tof", "fit", "modulus",
                                   "signal", "daq", "validity", "calibration", "measure"},
    "lift": FOUNDATION | DATA | {"contact", "chain", "tof", "fit"},
    "report": FOUNDATION | {"validity"},
    # a cluster job pending beyond its limit; the cluster's watch of its jobs
    "pending": FOUNDATION,
    "cluster": FOUNDATION | {"pending"},
    "workflow": FOUNDATION | DATA | {"cluster", "survey", "pending"},
}
# the top: the command line, the benchmarks, and the warm start (it forks the command line
# from a process that imported all of it)
TOP = {"cli", "bench", "__main__", "warmstart"}


def _modname(p: Path) -> str:
    parts = list(p.relative_to(PKG.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_modname(p): p for p in PKG.rglob("*.py")}


def _imports(path: Path, module_level: bool = False) -> set[str]:
    """The ssw modules a file imports (every import statement, or the module level's)."""
    tree = ast.parse(path.read_text())
    name = _modname(path)
    pkg = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    nodes = tree.body if module_level else list(ast.walk(tree))
    out = set()
    for n in nodes:
        if isinstance(n, ast.Import):
            out.update(a.name for a in n.names)
        elif isinstance(n, ast.ImportFrom):
            base = n.module or ""
            if n.level:
                parts = pkg.split(".")[: len(pkg.split(".")) - n.level + 1]
                base = ".".join([*parts, base] if base else parts)
            for a in n.names:
                out.add(f"{base}.{a.name}" if f"{base}.{a.name}" in MODULES else base)
    return {m for m in out if m in MODULES and m != name}


def _area(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "ssw"


def test_every_import_goes_down_the_layers():
    bad = []
    for mod, path in sorted(MODULES.items()):
        area = _area(mod)
        if area in TOP:
            continue
        assert area in ALLOWED, f"{mod}: area {area} has no place in the layers (ALLOWED)"
        allowed = ALLOWED[area] | {area}
        bad += [f"{mod} imports {t}" for t in sorted(_imports(path))
                if _area(t) not in allowed]
    assert not bad, "imports against the layers:\n" + "\n".join(bad)


def test_the_areas_form_no_cycle():
    """What the areas import of each other (every import, inside functions too) is a
    directed acyclic graph: no area reaches itself through another (the top, the command
    line and the benchmarks, aside)."""
    graph: dict[str, set[str]] = {}
    for mod, path in MODULES.items():
        area = _area(mod)
        if area not in TOP:
            graph.setdefault(area, set()).update(
                a for a in map(_area, _imports(path)) if a != area and a not in TOP)
    done: set[str] = set()

    def reach(v: str, trail: tuple[str, ...]) -> None:
        assert v not in trail, "areas in a cycle: " + " -> ".join((*trail, v))
        if v not in done:
            for w in sorted(graph.get(v, ())):
                reach(w, (*trail, v))
            done.add(v)

    for v in sorted(graph):
        reach(v, ())


def test_no_import_cycle_at_module_level():
    """Tarjan's strongly connected components of the module-level import graph."""
    graph = {m: _imports(p, module_level=True) for m, p in MODULES.items()}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    cycles: list[list[str]] = []
    counter = [0]
    sys.setrecursionlimit(10000)

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    for v in graph:
        if v not in index:
            visit(v)
    assert not cycles, cycles


@pytest.mark.parametrize("module", ["ssw.config", "ssw.device", "ssw.materials",
                                    "ssw.workflow"])
def test_the_data_layer_imports_no_heavy_library(module):
    """What the workflow imports when it parses: no scipy, h5py, matplotlib, gmsh, PETSc."""
    heavy = ("scipy", "h5py", "matplotlib", "gmsh", "petsc4py", "mpi4py", "nptdms")
    code = (f"import sys, {module}; "
            f"print(' '.join(m for m in {heavy!r} if m in sys.modules))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       check=True)
    assert r.stdout.strip() == "", f"{module} imports {r.stdout.strip()}"
