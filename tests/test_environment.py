"""The environment's pins, by either route of scripts/setup.sh: every runtime dependency is
pinned in constraints.txt; the venv runs the pinned PETSc, petsc4py and mpi4py (the binary
route's wheel or the source route's build); the rules' conda environment
(workflow/envs/ssw.yaml) holds the source route's packages at the same versions."""

from __future__ import annotations

import importlib.metadata
import json
import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parent.parent
#: PyPI name -> conda-forge name where they differ.
CONDA_NAMES = {"matplotlib": "matplotlib-base", "gmsh": "python-gmsh",
               "nidaqmx": "nidaqmx-python"}
#: Runtime dependencies the rules do not need in their environment: Snakemake runs the
#: rules, it is not run by them.
NOT_IN_RULES = {"snakemake"}
#: The extras of pyproject.toml that carry PETSc, per route of scripts/setup.sh.
ROUTE_EXTRAS = {"binary": "petsc", "source": "petsc-source"}


def _pins() -> dict[str, str]:
    pins = {}
    for line in (ROOT / "constraints.txt").read_text().splitlines():
        line = line.split("#")[0].strip()
        if line:
            name, version = line.split("==")
            pins[name.strip().lower()] = version.strip()
    return pins


def _runtime(route: str) -> set[str]:
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    extras = meta["optional-dependencies"]
    names = [*meta["dependencies"], *extras["study"], *extras[ROUTE_EXTRAS[route]]]
    return {re.split(r"[<>=\[ ;]", n)[0].lower() for n in names}


def _conda() -> dict[str, str | None]:
    env = yaml.safe_load((ROOT / "workflow" / "envs" / "ssw.yaml").read_text())
    out: dict[str, str | None] = {}
    for dep in env["dependencies"]:
        m = re.fullmatch(r"([\w.-]+)\s*(?:==?\s*([\w.]+))?", dep.strip())
        assert m, dep
        out[m.group(1).lower()] = m.group(2)
    return out


def _installed(name: str) -> str | None:
    try:
        return importlib.metadata.version(name)
    except importlib.metadata.PackageNotFoundError:
        return None


@pytest.mark.parametrize("route", sorted(ROUTE_EXTRAS))
def test_every_runtime_dependency_is_pinned(route):
    pins = _pins()
    missing = sorted(n for n in _runtime(route) if n not in pins)
    assert not missing, f"{route} route: dependencies without a pin in constraints.txt: {missing}"


def test_both_routes_pin_one_petsc():
    """The source route builds the PETSc the binary wheel carries (one version either way)."""
    pins = _pins()
    assert pins["petsc"] == pins["petsc4py"]


def test_the_venv_runs_the_pinned_petsc_stack():
    """Whichever route made this venv: its PETSc, petsc4py and mpi4py are the pinned ones,
    and the binary route's venv holds no second PETSc from PyPI."""
    from ssw.contact.petsc_solver import _petsc

    pins = _pins()
    PETSc = _petsc()
    import mpi4py
    import petsc4py

    assert ".".join(map(str, PETSc.Sys.getVersion())) == pins["petsc"]
    assert petsc4py.__version__ == pins["petsc4py"]
    assert mpi4py.__version__ == pins["mpi4py"]
    wheel = _installed("dolfinx-solver-real")
    if wheel is not None:  # binary route
        assert wheel == pins["dolfinx-solver-real"]
        assert _installed("mpich") == pins["mpich"]
        assert _installed("petsc") is None and _installed("petsc4py") is None
    else:  # source route
        assert _installed("petsc") == pins["petsc"]
        assert _installed("petsc4py") == pins["petsc4py"]


def test_conda_environment_matches_the_source_route_pins():
    pins, conda = _pins(), _conda()
    for name in sorted(_runtime("source") - NOT_IN_RULES):
        cname = CONDA_NAMES.get(name, name)
        assert cname in conda, f"{name} ({cname}) is not in workflow/envs/ssw.yaml"
        assert conda[cname] == pins[name], (name, conda[cname], pins[name])
    assert conda["python"] == "3.11"


def test_setup_refuses_an_unknown_route():
    """``SSW_PETSC`` takes binary or source; anything else stops before any change."""
    run = subprocess.run(["bash", str(ROOT / "scripts" / "setup.sh")], capture_output=True,
                         text=True, env={**os.environ, "SSW_PETSC": "conda"}, timeout=60)
    assert run.returncode != 0
    assert "SSW_PETSC = 'conda' is not allowed: binary (the default) or source" in run.stderr


#: What a process that imports petsc4py (and mpi4py) by itself reports: PETSc's version,
#: its world size against MPI's, and every MPI library it mapped (one, or two MPIs).
_PETSC_ALONE = """
import json, re, sys
{first}
from mpi4py import MPI
maps = open("/proc/self/maps").read()
# a map's path is its sixth field to the line's end: it may hold spaces
mpis = sorted({{p for p in re.findall(r"^(?:\\S+\\s+){{5}}(/.*/libmpi(?:ch)?\\.so[.\\d]*)$",
                                     maps, re.M)}})
print(json.dumps([".".join(map(str, PETSc.Sys.getVersion())), PETSc.COMM_WORLD.getSize(),
                  MPI.COMM_WORLD.Get_size(), *mpis]))
"""


@pytest.mark.parametrize("first", [
    "from petsc4py import PETSc",
    "import petsc4py; petsc4py.init([]); from petsc4py import PETSc",
])
def test_petsc4py_imports_by_itself(first):
    """A user's script beside ssw: petsc4py without ssw or dolfinx_solver imported first runs
    the pinned PETSc on one MPI library (the binary route: the mpich wheel's, which the
    start-up hook of scripts/setup.sh loads first; the source route: the system's MPICH)."""
    run = subprocess.run([sys.executable, "-c", _PETSC_ALONE.format(first=first)],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]
    version, petsc_size, mpi_size, *mpis = json.loads(run.stdout.splitlines()[0])
    assert version == _pins()["petsc"]
    assert petsc_size == mpi_size == 1
    assert len({os.path.realpath(p) for p in mpis}) == 1, mpis
    if _installed("dolfinx-solver-real") is not None:  # binary route: the wheel's MPI
        assert Path(os.path.realpath(mpis[0])).parent == Path(sys.prefix) / "lib"


def test_the_start_up_hook_loads_nothing_until_petsc_is_imported():
    """Every start of the venv's Python runs the hook (binary route): it must not import
    MPI, PETSc or dolfinx_solver for a script that does not use them."""
    code = ("import sys; print(*sorted(m for m in ('_ssw_petsc_first', 'dolfinx_solver', "
            "'mpi4py', 'mpi4py.MPI', 'petsc4py', 'numpy') if m in sys.modules))")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=60, check=True)
    loaded = run.stdout.split()
    binary = _installed("dolfinx-solver-real") is not None
    assert loaded == (["_ssw_petsc_first"] if binary else [])
