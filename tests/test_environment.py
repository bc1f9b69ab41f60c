"""The environment's pins, by either route of scripts/setup.sh: every runtime dependency is
pinned in constraints.txt; the venv runs the pinned PETSc, petsc4py and mpi4py (the binary
route's wheel or the source route's build); the rules' conda environment
(workflow/envs/ssw.yaml) holds the source route's packages at the same versions."""

from __future__ import annotations

import importlib.metadata
import os
import re
import subprocess
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
    names = [*meta["dependencies"], *meta["optional-dependencies"][ROUTE_EXTRAS[route]]]
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
