"""The rules' conda environment (workflow/envs/ssw.yaml) holds every runtime dependency of
ssw, each at the version constraints.txt pins (the versions the tests run with)."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parent.parent
#: PyPI name -> conda-forge name where they differ.
CONDA_NAMES = {"matplotlib": "matplotlib-base", "gmsh": "python-gmsh",
               "nidaqmx": "nidaqmx-python"}
#: Runtime dependencies the rules do not need in their environment: Snakemake runs the
#: rules, it is not run by them.
NOT_IN_RULES = {"snakemake"}


def _pins() -> dict[str, str]:
    pins = {}
    for line in (ROOT / "constraints.txt").read_text().splitlines():
        line = line.split("#")[0].strip()
        if line:
            name, version = line.split("==")
            pins[name.strip().lower()] = version.strip()
    return pins


def _runtime() -> set[str]:
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    names = [*meta["dependencies"], *meta["optional-dependencies"]["mpi"], "petsc"]
    return {re.split(r"[<>=\[ ;]", n)[0].lower() for n in names} - NOT_IN_RULES


def _conda() -> dict[str, str | None]:
    env = yaml.safe_load((ROOT / "workflow" / "envs" / "ssw.yaml").read_text())
    out: dict[str, str | None] = {}
    for dep in env["dependencies"]:
        m = re.fullmatch(r"([\w.-]+)\s*(?:==?\s*([\w.]+))?", dep.strip())
        assert m, dep
        out[m.group(1).lower()] = m.group(2)
    return out


def test_every_runtime_dependency_is_pinned():
    pins = _pins()
    missing = sorted(n for n in _runtime() if n not in pins)
    assert not missing, f"runtime dependencies without a pin in constraints.txt: {missing}"


def test_conda_environment_matches_the_pins():
    pins, conda = _pins(), _conda()
    for name in sorted(_runtime()):
        cname = CONDA_NAMES.get(name, name)
        assert cname in conda, f"{name} ({cname}) is not in workflow/envs/ssw.yaml"
        assert conda[cname] == pins[name], (name, conda[cname], pins[name])
    assert conda["python"] == "3.11"
