"""The ssw command line: --help everywhere, --json echoes inputs, errors are one line."""

import json
import subprocess
import sys

import pytest

from ssw.cli import build_parser, main


def _subcommands():
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    return sorted(sub.choices)


@pytest.mark.parametrize("cmd", _subcommands())
def test_every_subcommand_has_help_and_json(cmd, capsys):
    with pytest.raises(SystemExit) as exc:
        main([cmd, "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert "usage" in out
    if cmd != "bench":
        assert "--json" in out


def test_top_level_help_lists_every_subcommand(capsys):
    """`ssw --help` formats every subcommand's one-line help (a stray % breaks it)."""
    with pytest.raises(SystemExit) as exc:
        main(["--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    for cmd in _subcommands():
        assert cmd in out


def test_check_config_json_echoes_inputs(capsys):
    assert main(["check-config", "--config", "config/config.yaml", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["config"] == "config/config.yaml"
    assert out["scenes_per_set"]["set3_soil"] == 300
    assert out["chain_sweep_points"] == 300


def test_bad_config_is_one_line_error(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(
        "sets:\n  s:\n    plate_material: [pla]\n    plate_thickness: {values: [-0.4e-3]}\n"
        "    soil_E: {values: [5.0e+7]}\n    soil_nu: {values: [0.3]}\n"
    )
    r = subprocess.run([sys.executable, "-m", "ssw", "check-config", "--config", str(bad)],
                       capture_output=True, text=True)
    assert r.returncode == 2
    assert "sets.s.plate_thickness" in r.stderr and "Traceback" not in r.stderr


SIGTERM_DURING_WRITE = """
import os, signal, sys
import ssw.curve
from ssw.cli import main

real, seen = ssw.curve.write_dataset, []

def write_then_get_cancelled(*args, **kw):
    seen.extend(p.name for p in os.scandir(sys.argv[1]) if p.name.endswith(".part"))
    real(*args, **kw)
    os.kill(os.getpid(), signal.SIGTERM)

ssw.curve.write_dataset = write_then_get_cancelled
rc = main(["contact", "--soil-E", "5e7", "--soil-nu", "0.3", "--plate-thickness", "0",
           "--steps", "10", "--output", os.path.join(sys.argv[1], "curve.h5")])
print("part files seen during the write:", seen)
sys.exit(rc)
"""


def test_sigterm_removes_the_temporary_file(tmp_path):
    """Snakemake and Slurm cancel a job with SIGTERM: `ssw` unwinds (exit 130) and leaves
    neither the output nor its temporary `.part` file, although PETSc (initialized by the
    solve) would install its own aborting SIGTERM handler. The signal is sent from inside
    the HDF5 write, the worst moment: the temporary file exists and is half written."""
    proc = subprocess.run([sys.executable, "-c", SIGTERM_DURING_WRITE, str(tmp_path)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 130, proc.stdout + proc.stderr
    assert ".part" in proc.stdout, "the signal did not arrive while the temporary file existed"
    assert "interrupted" in proc.stderr
    assert not (tmp_path / "curve.h5").exists()
    assert not list(tmp_path.glob("*.part"))
