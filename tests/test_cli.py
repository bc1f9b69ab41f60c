"""The ssw command line: --help everywhere and grouped, --json echoes inputs, human output
is a short summary, errors are one line."""

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


def _help_sections(out: str) -> dict[str, list[str]]:
    """Section title -> the command names listed under it (an indented first word; a long
    name's help wraps onto the next line)."""
    import re

    sections: dict[str, list[str]] = {}
    title = None
    for line in out.splitlines():
        if line and not line.startswith(" ") and line.endswith(":"):
            title = line[:-1]
            sections[title] = []
        elif title is not None and (m := re.match(r"^  ([a-z][\w-]*)(\s|$)", line)):
            sections[title].append(m.group(1))
    return sections


def test_top_level_help_groups_every_subcommand_once(capsys):
    """`ssw --help` lists every subcommand exactly once, under the section of its group
    (ssw.cli.GROUPS: the study, the instrument, design, analysis, tools), and none in the
    section of commands no group names; its one-line helps format (a stray % breaks it)."""
    from ssw.cli import GROUPS, UNGROUPED

    with pytest.raises(SystemExit) as exc:
        main(["--help"])
    assert exc.value.code == 0
    sections = _help_sections(capsys.readouterr().out)
    listed = [c for t, cmds in sections.items() if t != "options" for c in cmds]
    assert sorted(listed) == _subcommands()  # each exactly once
    assert UNGROUPED not in sections, f"commands in no group of ssw.cli.GROUPS: " \
        f"{sections.get(UNGROUPED)}"
    for title, names in GROUPS.items():
        assert sections[title] == [n for n in names if n in listed], title
    for word in ("the study", "the instrument", "design", "analysis", "tools"):
        assert any(t.startswith(word) for t in sections), word


def test_design_help_says_plates_and_whole_devices(capsys):
    """`ssw design` designs the plate or the whole device (--space); its help says both."""
    with pytest.raises(SystemExit):
        main(["--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert "design plates" in out and "whole devices" in out


def test_tof_human_output_is_a_short_summary(capsys):
    """`ssw tof` without --json: at most 15 lines holding the TOF (the --json result's, to
    the 10 ns printed), the peaks, the checks in one line and the derivatives in one line."""
    args = ["tof", "--soil-E", "50e6", "--soil-nu", "0.3", "--law", "hertz",
            "--stress-checks", "bound"]
    assert main(args) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert main([*args, "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert len(lines) <= 15, lines
    assert lines[0].startswith(f"TOF {res['tof'] * 1e3:.5f} ms"), lines[0]
    assert [ln for ln in lines if ln.startswith("checks:")] != []
    failed = [e["check"] for e in res["validity"] if not e["holds"]]
    check_line = next(ln for ln in lines if ln.startswith("checks:"))
    assert all(name in check_line for name in failed), (failed, check_line)
    deriv = [ln for ln in lines if ln.startswith("dTOF/d")]
    assert len(deriv) == 1 and "E " in deriv[0] and "striker_velocity" in deriv[0]
    assert not any("{" in ln for ln in lines), "a dictionary dumped"


def test_generic_summary_leaves_dictionaries_to_json():
    """A command without its own printer: scalars shown, nested dictionaries and long lists
    left to --json (and the summary says so), a grid's checks counted against their limits."""
    from ssw.cli._summary import MORE, default

    out = default({"valid": True, "tof": [1e-3] * 10, "device_values": {"beads": 20},
                   "validity": {"contact_strain": [0.1, 0.3], "wall_reach": [0.5, 0.5]},
                   "validity_meta": {"rules": {"contact_strain": {"limit": 0.2},
                                               "wall_reach": {"limit": 1.0}}}})
    lines = out.splitlines()
    assert lines[0] == "valid: True" and lines[1].startswith("tof: 10 values")
    assert "contact_strain fails at 1 of 2" in out and "wall_reach holds" in out
    assert "beads" not in out and lines[-1] == MORE


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
