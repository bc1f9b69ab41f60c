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
