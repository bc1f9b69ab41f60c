"""The instrument half from a wheel, on a machine without a compiler, PETSc or MPI.

A lab PC gets ssw as a built wheel (``pip install ssw-*.whl``; docs/setup.md): the compiled
chain step inside it, its core dependencies from wheels, no PETSc or MPI. Two checks:

* default run (and the wheels' own test on Linux, macOS and Windows: ``[tool.cibuildwheel]``
  in pyproject.toml): ``ssw acquire --simulate`` then ``ssw measure`` (the packaged thesis
  device, its plate's contact operators built anew in an empty cache) import neither PETSc,
  MPI nor Snakemake, and the simulate-then-measure round trip gives back the modulus of the
  simulated material within the measured interval;
* ``long`` (``make test-long``, which CI runs): a wheel built here from the tracked
  sources installs into a fresh venv with no compiler on PATH (``CC=false``) and without
  PETSc, MPI or Snakemake, and its ``ssw measure`` of a point, with a calibration written
  by this full install and its operators built in a cache of its own, gives this
  install's E and interval to 1e-9.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
#: Top-level modules the instrument half must not import: the study half's sparse solvers
#: (PETSc and its MPI) and workflow engine (Snakemake). (gmsh is the instrument's too: it
#: meshes the contact of the device's plate, once per geometry, for the wall law.)
STUDY_ONLY = ("petsc4py", "mpi4py", "dolfinx_solver", "dolfinx", "snakemake")
#: The simulated test point: a Sawbones PCF 15 foam (ssw/data/materials.yaml: E 123 MPa,
#: nu 0.33), three hits of the packaged thesis device.
MATERIAL, E_MATERIAL, NU_MATERIAL = "pcf15", 123.0e6, 0.33

#: Run ssw's command lines in one process; print the STUDY_ONLY modules it imported and the
#: last command's standard output, as JSON.
_COMMANDS = """
import contextlib, io, json, sys
from ssw.cli import main
for argv in json.loads(sys.argv[1]):
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        status = main(argv)
    if status:
        sys.exit(f"ssw {{' '.join(argv)}}: exit {{status}}\\n{{out.getvalue()}}")
print(json.dumps({{"imported": sorted({{m.split('.')[0] for m in sys.modules}} & set({study!r})),
                  "stdout": out.getvalue()}}))
"""


def _acquire(out: str, material: str, seed: int) -> list[str]:
    return ["acquire", "--simulate", "--sample", out.removesuffix(".h5"), "--material",
            material, "--hits", "3", "--seed", str(seed), "--output", out,
            "--calibration", "none"]


def _measure(recording: str, calibration: str) -> list[str]:
    return ["measure", recording, "--soil-nu", str(NU_MATERIAL), "--calibration", calibration,
            "--json"]


def _ssw(python: str | Path, commands: list[list[str]], cwd: Path, cache: Path,
         env: dict[str, str] | None = None) -> tuple[list[str], str]:
    """Run ``commands`` with ``python``'s ssw in ``cwd``, in one process, with the operator
    cache ``cache``: the STUDY_ONLY modules it imported, and the last command's standard
    output."""
    env = {**(os.environ if env is None else env), "SSW_CACHE_DIR": str(cache)}
    run = subprocess.run([str(python), "-c", _COMMANDS.format(study=STUDY_ONLY),
                          json.dumps(commands)], cwd=cwd, env=env, capture_output=True,
                         text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    got = json.loads(run.stdout.splitlines()[-1])
    return got["imported"], got["stdout"]


def test_acquiring_and_measuring_import_no_petsc_mpi_or_snakemake(tmp_path):
    """The instrument half's commands on the packaged device, from an empty operator cache:
    no study-only module, and the simulated material's modulus back within the measured
    95 % interval."""
    imported, out = _ssw(sys.executable, [_acquire("p.h5", MATERIAL, 11),
                                          _measure("p.h5", "none")], tmp_path,
                         tmp_path / "cache")
    assert imported == []
    got = json.loads(out)
    assert got["E_low"] <= E_MATERIAL <= got["E_high"], got


# ------------------------------------------------------------------- the wheel, installed
@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """A wheel of the tracked sources (no build tree left in the repository)."""
    tmp = tmp_path_factory.mktemp("wheel")
    src = tmp / "src"
    files = subprocess.run(["git", "ls-files", "-z", "ssw", "setup.py", "pyproject.toml",
                            "README.md"], cwd=ROOT, capture_output=True, text=True,
                           check=True).stdout.split("\0")
    for name in filter(None, files):
        (src / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(ROOT / name, src / name)
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps",
                    "--no-build-isolation", "-w", str(tmp / "dist"), str(src)],
                   check=True, timeout=600)
    (built,) = (tmp / "dist").glob("ssw-*.whl")
    return built


@pytest.fixture(scope="module")
def instrument_venv(wheel, tmp_path_factory) -> tuple[Path, dict[str, str]]:
    """A fresh venv holding the wheel and its core dependencies (pinned by
    constraints.txt), installed with no compiler: its Python and the environment to run it
    in (PATH its own bin folder alone, CC and CXX ``false``)."""
    venv = tmp_path_factory.mktemp("instrument") / "venv"
    base = getattr(sys, "_base_executable", sys.executable)  # this venv's interpreter
    subprocess.run([base, "-m", "venv", "--without-pip", str(venv)], check=True, timeout=120)
    env = {**os.environ, "PATH": str(venv / "bin"), "CC": "false", "CXX": "false"}
    env.pop("VIRTUAL_ENV", None)
    env.pop("PYTHONPATH", None)
    assert shutil.which("gcc", path=env["PATH"]) is None
    uv = Path(sys.executable).parent / "uv"
    subprocess.run([str(uv), "pip", "install", "--quiet", "--python", str(venv / "bin/python"),
                    "-c", str(ROOT / "constraints.txt"), str(wheel)], env=env, check=True,
                   timeout=600)
    return venv / "bin" / "python", env


@pytest.mark.long
def test_a_wheel_measures_as_the_full_install_without_a_compiler_or_petsc(
        instrument_venv, tmp_path):
    python, env = instrument_venv
    found = subprocess.run(
        [str(python), "-c", "import importlib.util as u; print(*[m for m in "
         f"{STUDY_ONLY!r} if u.find_spec(m)])"], env=env, capture_output=True, text=True,
        check=True).stdout.split()
    assert found == []  # no PETSc, no MPI, no Snakemake in the instrument's venv
    # the full install: three references, a calibration, a test point
    refs = [("ref_soft.h5", "pcf08", 1, 38e6, 0.34), ("ref_mid.h5", "pcf15", 2, 123e6, 0.33),
            ("ref_stiff.h5", "pcf30", 3, 445e6, 0.30)]
    calibrate = ["calibrate", "--free", "striker_velocity", "--free", "preload",
                 "--calibration", "none", "--output", "cal.json"]
    for name, _, _, E, nu in refs:
        calibrate += ["--reference-recording", f"{name},{E:g},{nu:g}"]
    _ssw(sys.executable, [*(_acquire(n, m, s) for n, m, s, _, _ in refs),
                          _acquire("point.h5", MATERIAL, 4), calibrate], tmp_path,
         tmp_path / "cache")
    _, full = _ssw(sys.executable, [_measure("point.h5", "cal.json")], tmp_path,
                   tmp_path / "cache-full")
    # the wheel's own operators (gmsh's mesh, scipy's condensation), no file of the full
    # install's
    imported, wheel_out = _ssw(python, [_measure("point.h5", "cal.json")], tmp_path,
                               tmp_path / "cache-wheel", env)
    assert imported == []
    want, got = json.loads(full), json.loads(wheel_out)
    for key in ("E", "E_low", "E_high"):
        assert got[key] == pytest.approx(want[key], rel=1e-9, abs=0), key


def test_the_wheels_are_tested_by_this_module():
    """``[tool.cibuildwheel]``: each wheel's test runs this module's fast test, from the
    files it copies, on every CPython that requires-python allows."""
    import tomllib

    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())
    cibw = meta["tool"]["cibuildwheel"]
    here = str(Path(__file__).relative_to(ROOT))
    assert here in cibw["test-sources"] and here in cibw["test-command"]
    assert '-m "not slow and not long"' in cibw["test-command"]
    assert all((ROOT / p).exists() for p in cibw["test-sources"])
    floor = meta["project"]["requires-python"].removeprefix(">=").replace(".", "")
    assert cibw["build"][0] == f"cp{floor}-*"
