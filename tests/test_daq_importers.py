"""CSV and MAT importers: units, time axes, and TOF of imported analytic pulses."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import io

from ssw.daq.importers import read_any
from ssw.daq.simulated import sech2
from ssw.errors import RecordingError
from ssw.signal.tof import recording_tof

RATE = 51200.0
TOF = 1.15e-3  # s, PCF 30 (thesis Table 2)


def pulses(n_hits=3):
    t = (np.arange(1024) - 64) / RATE  # 0 at the trigger
    cols = [60 * sech2((t - 2e-4 - 3e-6 * i) / 4e-5)
            + 30 * sech2((t - 2e-4 - 3e-6 * i - TOF) / 4e-5) for i in range(n_hits)]
    return t, np.column_stack(cols)


def write_csv(path, t, data, unit):
    head = ",".join(["time [s]"] + [f"hit{i} [{unit}]" for i in range(data.shape[1])])
    np.savetxt(path, np.column_stack([t, data]), delimiter=",", header=head, comments="")


def test_csv_in_newtons(tmp_path):
    t, f = pulses()
    write_csv(tmp_path / "r.csv", t, f, "N")
    rec = read_any(tmp_path / "r.csv")
    assert rec.sample_rate == pytest.approx(RATE) and len(rec.hits) == 3
    assert rec.meta["pretrigger_samples"] == 64
    assert np.max(np.abs(recording_tof(rec).tof - TOF)) < 0.5 / RATE


def test_csv_in_volts_needs_the_sensitivity(tmp_path):
    t, f = pulses()
    write_csv(tmp_path / "v.csv", t, f * 11.24e-3, "V")
    with pytest.raises(RecordingError, match="sensitivity"):
        read_any(tmp_path / "v.csv")
    rec = read_any(tmp_path / "v.csv", sensitivity=11.24e-3)
    np.testing.assert_allclose(rec.hits[0].force, f[:, 0], rtol=1e-6, atol=1e-9)


def test_csv_in_foreign_units_is_an_error(tmp_path):
    t, f = pulses()
    write_csv(tmp_path / "l.csv", t, f / 4.448, "lbf")
    with pytest.raises(RecordingError, match="units = 'lbf'"):
        read_any(tmp_path / "l.csv")


def test_mat_round_trip(tmp_path):
    _, f = pulses()
    io.savemat(tmp_path / "r.mat", {"voltage": f * 11.24e-3, "fs": RATE, "sensitivity": 11.24e-3})
    rec = read_any(tmp_path / "r.mat")
    assert len(rec.hits) == 3
    assert np.max(np.abs(recording_tof(rec).tof - TOF)) < 0.5 / RATE
    io.savemat(tmp_path / "bad.mat", {"x": f})
    with pytest.raises(RecordingError, match="no 'force'"):
        read_any(tmp_path / "bad.mat")


def test_unknown_format_is_an_error(tmp_path):
    (tmp_path / "r.tdms").write_bytes(b"TDSm")
    with pytest.raises(RecordingError, match="unknown recording format"):
        read_any(tmp_path / "r.tdms")
