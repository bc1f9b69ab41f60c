"""``ssw acquire`` and ``ssw tof-recording`` end to end."""

from __future__ import annotations

import json

import pytest

from ssw.cli import main


def run_json(capsys, argv):
    assert main([*argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_simulated_acquire_then_tof_recording(capsys, tmp_path):
    out = tmp_path / "s.h5"
    a = run_json(capsys, ["acquire", "--simulate", "--tof", "1.3e-3", "--hits", "3",
                          "--sample", "T1", "--output", str(out)])
    assert a["backend"] == "simulated" and a["n_accepted"] == 3
    assert abs(a["tof_mean"] - 1.3e-3) < 0.5 / 51200
    b = run_json(capsys, ["tof-recording", str(out)])
    assert b["tof_per_hit"] == a["tof_per_hit"] and b["synthetic"] is True


def test_simulated_acquire_from_the_chain(capsys, tmp_path):
    a = run_json(capsys, ["acquire", "--simulate", "--material", "pcf15", "--wall", "hertz",
                          "--hits", "3", "--sample", "PCF15", "--output",
                          str(tmp_path / "c.h5")])
    assert abs(a["tof_mean"] - a["true_tof"]) < 0.5 / 51200


def test_tof_recording_of_a_one_hit_file_says_how_to_accept_it(capsys, tmp_path):
    """One good hit and the default of three: refused with the flag that accepts it
    (``--min-hits 1``), not an empty list of rejections; with that flag, its TOF (the
    simulated pulses' 1.3 ms, to half a sample)."""
    out = tmp_path / "one.h5"
    run_json(capsys, ["acquire", "--simulate", "--tof", "1.3e-3", "--hits", "1",
                      "--min-hits", "1", "--sample", "T1", "--output", str(out)])
    assert main(["tof-recording", str(out)]) == 2
    err = capsys.readouterr().err
    assert "1 of 1 hits accepted, at least 3 needed" in err
    assert "--min-hits 1" in err and "rejected" not in err
    b = run_json(capsys, ["tof-recording", str(out), "--min-hits", "1"])
    assert b["n_accepted"] == 1 and abs(b["tof_mean"] - 1.3e-3) < 0.5 / 51200


def test_real_acquire_without_driver_fails_cleanly(capsys, tmp_path):
    assert main(["acquire", "--sample", "X", "--output", str(tmp_path / "r.h5")]) == 2
    assert "NI-DAQmx driver is not installed" in capsys.readouterr().err
    assert not (tmp_path / "r.h5").exists()  # no hit recorded: no file left behind


@pytest.mark.parametrize("content", [b"", b"not hdf5 at all"])
def test_tof_recording_of_a_broken_file_fails_cleanly(capsys, tmp_path, content):
    p = tmp_path / "bad.h5"
    p.write_bytes(content)
    assert main(["tof-recording", str(p)]) == 2
    assert "not a readable HDF5" in capsys.readouterr().err


def test_acquire_prints_each_hits_tof_and_the_running_modulus(capsys, tmp_path):
    """At the bench (no --json): one stderr line per hit with its TOF and, the soil's nu
    being known, E with its interval inverted through the chain. The simulated foam's own
    modulus (123 MPa) comes back within 0.5 %: TOF picking within 0.5 us (0.03 %) times
    the TOF ~ E^-1/5 sensitivity, plus the inverse's interpolation on its E grid."""
    assert main(["acquire", "--simulate", "--material", "pcf15", "--wall", "hertz", "--hits",
                 "3", "--sample", "P1", "--output", str(tmp_path / "p.h5")]) == 0
    lines = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("hit ")]
    assert [ln.split(":")[0] for ln in lines] == ["hit 1", "hit 2", "hit 3"]
    assert all("TOF" in ln and "MPa" in ln for ln in lines)
    E = float(lines[-1].split("| E ")[1].split(" MPa")[0])
    lo, hi = (float(x) for x in lines[-1].split("[")[1].split("]")[0].split(","))
    assert lo <= E <= hi and abs(E / 123.0 - 1) < 0.005


def test_tof_recording_reads_tdms_and_reports_the_bound(capsys, tmp_path):
    a = run_json(capsys, ["acquire", "--simulate", "--tof", "1.3e-3", "--hits", "3",
                          "--sample", "T1", "--output", str(tmp_path / "s.h5")])
    from ssw.daq.importers import read_any, write_any

    write_any(tmp_path / "s.tdms", read_any(tmp_path / "s.h5"))
    b = run_json(capsys, ["tof-recording", str(tmp_path / "s.tdms")])
    assert b["format"] == "tdms" and b["tof_per_hit"] == a["tof_per_hit"]
    assert 0 < b["min_tof"] < b["tof_mean"]
