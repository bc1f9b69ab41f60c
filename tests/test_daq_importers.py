"""Lab formats (CSV, TDMS, MAT): units, layouts, round trips, errors, and TOF of known signals.

Truth: recordings of known TOF, the chain's sensor force (``ssw.tof.api``, TOF on its
integration grid) sampled like an NI 9234 by the simulated backend, written by independent
writers (numpy text, npTDMS's own writer), read without flags; and analytic sech^2 pulses.
Round trips (meshio style) use values with infinite decimal expansions.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter
from scipy import io

from ssw.chain.params import ChainParams
from ssw.cli import main
from ssw.daq.formats.common import parse_column, unit_of
from ssw.daq.importers import read_any, write_any
from ssw.daq.recording import RecordedHit, Recording
from ssw.daq.settings import DaqSettings
from ssw.daq.simulated import SimulatedBackend, sech2
from ssw.errors import RecordingError
from ssw.signal.tof import ChainPath, TofOptions, recording_tof

RATE = 51200.0
TOF = 1.15e-3  # s, PCF 30 (thesis Table 2)
LBF = 4.4482216152605  # N per lbf (NIST SP 811)


@pytest.fixture(scope="module")
def chain_hits():
    """Three NI 9234-sampled hits of the chain on PCF 15 (123 MPa) and the chain's own TOF."""
    params = ChainParams()
    b = SimulatedBackend(soil_E=123e6, soil_nu=0.33, chain_params=params, seed=11)
    s = DaqSettings()
    hits = list(b.hits(s, 3))
    # one hit per file here: its TOF, not a session's scatter (min_hits 1)
    return hits, s, b.true_tof, TofOptions(chain=ChainPath.from_params(params), min_hits=1)


def pulses(n_hits=3):
    t = (np.arange(1024) - 64) / RATE  # 0 at the trigger
    cols = [60 * sech2((t - 2e-4 - 3e-6 * i) / 4e-5)
            + 30 * sech2((t - 2e-4 - 3e-6 * i - TOF) / 4e-5) for i in range(n_hits)]
    return t, np.column_stack(cols)


def write_csv(path, header, columns):
    np.savetxt(path, np.column_stack(columns), delimiter=",", header=",".join(header),
               comments="", fmt="%.10g")


@pytest.mark.parametrize(("header", "name", "unit"), [
    ("force [N]", "force", "N"), ("Time (s)", "Time", "s"), ("force_N", "force", "N"),
    ("time_s", "time", "s"), ("voltage_V", "voltage", "V"), ("hit_1", "hit_1", None),
    ("F_lbf", "F", "lbf"), ("sensor_mV", "sensor", "mV"), ("force", "force", None)])
def test_column_units_from_brackets_or_suffixes(header, name, unit):
    n, u = parse_column(header)
    assert n == name and unit_of(u) == unit


def test_time_s_force_n_csv_of_the_chain_reads_without_flags(tmp_path, chain_hits):
    hits, s, true_tof, opts = chain_hits
    t = (np.arange(s.record_samples) - s.pretrigger_samples) / s.sample_rate
    for i, h in enumerate(hits):
        write_csv(tmp_path / f"h{i}.csv", ["time_s", "force_N"], [t, h.force])
        rec = read_any(tmp_path / f"h{i}.csv")
        assert rec.meta["pretrigger_samples"] == s.pretrigger_samples
        assert rec.sample_rate == pytest.approx(s.sample_rate, rel=1e-9)
        tof = recording_tof(rec, opts).tof[0]
        assert abs(tof / true_tof - 1) < 0.002


def tdms_hits(path, hits, s, unit="N", scale=1.0):
    """One channel per hit, written with npTDMS's writer, NI waveform properties."""
    chans = [ChannelObject("Untitled", f"Force {i}", h.force / scale, properties={
        "wf_increment": 1.0 / s.sample_rate, "wf_start_offset": -s.pretrigger_samples
        / s.sample_rate, "wf_samples": h.force.size, "unit_string": unit})
        for i, h in enumerate(hits)]
    with TdmsWriter(str(path)) as w:
        w.write_segment([RootObject(), GroupObject("Untitled"), *chans])


def test_tdms_one_channel_per_hit_of_the_chain(tmp_path, chain_hits):
    hits, s, true_tof, opts = chain_hits
    tdms_hits(tmp_path / "s.tdms", hits, s)
    rec = read_any(tmp_path / "s.tdms")
    assert len(rec.hits) == 3 and rec.meta["layout"] == "one channel per hit"
    assert rec.meta["pretrigger_samples"] == s.pretrigger_samples
    for h, want in zip(rec.hits, hits, strict=True):
        np.testing.assert_array_equal(h.force, want.force)
    res = recording_tof(rec, opts)
    assert np.all(np.abs(res.tof / true_tof - 1) < 0.002)


def test_tdms_one_long_channel_in_lbf_is_split_by_the_trigger_rule(tmp_path, chain_hits):
    hits, s, true_tof, opts = chain_hits
    rng = np.random.default_rng(2)
    parts = []
    for h in hits:  # quiet stretches (the baseline noise) between the hits
        parts += [rng.normal(0.0, 0.05, 3000), h.force]
    stream = np.concatenate([*parts, rng.normal(0.0, 0.05, 500)])
    ch = ChannelObject("cDAQ1Mod1", "ai0", stream / LBF, properties={
        "wf_increment": 1.0 / s.sample_rate, "wf_start_offset": 0.0, "unit_string": "lbf"})
    with TdmsWriter(str(tmp_path / "long.tdms")) as w:
        w.write_segment([RootObject(), GroupObject("cDAQ1Mod1"), ch])
    rec = read_any(tmp_path / "long.tdms")  # the daq: defaults: 5 N rising, 256 + 1792
    assert "split" in rec.meta["layout"] and len(rec.hits) == 3
    for h, want in zip(rec.hits, hits, strict=True):
        np.testing.assert_allclose(h.force, want.force, rtol=1e-12, atol=1e-12)
    assert np.all(np.abs(recording_tof(rec, opts).tof / true_tof - 1) < 0.002)


def known_recording(path="mem"):
    """Two hits of values with infinite decimal expansions (1/3, pi/7, ...)."""
    k = np.arange(300)
    hits = tuple(RecordedHit(i, (k + 1.0) / 3.0 * (i + 1) + np.pi / 7.0, 40) for i in range(2))
    return Recording(path, {}, 51200.0 / 3.0, hits)


@pytest.mark.parametrize("suffix", [".csv", ".tdms", ".mat"])
def test_round_trip(tmp_path, suffix):
    rec = known_recording()
    path = write_any(tmp_path / f"r{suffix}", rec)
    back = read_any(path)
    assert back.sample_rate == pytest.approx(rec.sample_rate, rel=1e-12)
    assert back.meta["pretrigger_samples"] == 40 and len(back.hits) == 2
    for a, b in zip(rec.hits, back.hits, strict=True):
        assert b.force.dtype == np.float64 and b.force.shape == a.force.shape
        np.testing.assert_array_equal(b.force, a.force)
        assert b.trigger_index == a.trigger_index
    assert not list(tmp_path.glob("*.part"))


def test_csv_in_volts_needs_the_sensitivity(tmp_path):
    t, f = pulses()
    write_csv(tmp_path / "v.csv", ["time [s]"] + [f"hit{i} [V]" for i in range(3)],
              [t, *(f * 11.24e-3).T])
    with pytest.raises(RecordingError, match="sensitivity"):
        read_any(tmp_path / "v.csv")
    rec = read_any(tmp_path / "v.csv", sensitivity=11.24e-3)
    np.testing.assert_allclose(rec.hits[0].force, f[:, 0], rtol=1e-6, atol=1e-6)


def test_csv_without_units_needs_the_units_flag(tmp_path, capsys):
    t, f = pulses(1)
    write_csv(tmp_path / "n.csv", ["time", "hit"], [t, f[:, 0]])
    with pytest.raises(RecordingError, match=r"n\.csv: column 'hit' has no unit.*--units N"):
        read_any(tmp_path / "n.csv")
    assert main(["tof-recording", str(tmp_path / "n.csv"), "--units", "N", "--min-hits", "1",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert abs(out["tof_mean"] - TOF) < 0.05 / RATE


@pytest.mark.parametrize(("header", "kwargs", "match"), [
    (["time_s", "force_psi"], {}, r"column 'force_psi' has no unit"),
    (["time_s", "force [psi]"], {}, r"column 'force \[psi\]': unit 'psi'; expected a force "
                                    r"\(force: N, kN, lbf\)"),
    (["time_min", "force_N"], {}, r"column 'time_min'.*no unit"),
    (["time [min]", "force_N"], {}, r"column 'time \[min\]': time in 'min'; expected"),
    (["time_s", "force_N"], {"units": "V"}, r"column 'force_N': the header says 'N', --units "
                                            r"says 'V'"),
])
def test_csv_errors_name_the_file_the_column_and_what_is_expected(tmp_path, header, kwargs,
                                                                    match):
    t, f = pulses(1)
    write_csv(tmp_path / "e.csv", header, [t, f[:, 0]])
    with pytest.raises(RecordingError, match=match) as err:
        read_any(tmp_path / "e.csv", **kwargs)
    assert "e.csv" in str(err.value)


def test_csv_non_numeric_cell_is_located(tmp_path):
    (tmp_path / "x.csv").write_text("time_s,force_N\n0.0,1.0\n1e-5,abc\n")
    with pytest.raises(RecordingError, match=r"row 3, column 'force_N': 'abc' is not a number"):
        read_any(tmp_path / "x.csv")


def test_lbf_is_converted_to_newtons(tmp_path):
    t, f = pulses(1)
    write_csv(tmp_path / "l.csv", ["time [s]", "force [lbf]"], [t, f[:, 0] / LBF])
    np.testing.assert_allclose(read_any(tmp_path / "l.csv").hits[0].force, f[:, 0], rtol=1e-9,
                               atol=1e-9)


def test_tdms_errors_name_the_channel(tmp_path):
    ch = ChannelObject("g", "ai0", np.zeros(500), properties={"wf_increment": 1 / RATE})
    with TdmsWriter(str(tmp_path / "u.tdms")) as w:
        w.write_segment([RootObject(), GroupObject("g"), ch])
    with pytest.raises(RecordingError, match=r"u\.tdms: channel g/ai0 has no unit_string"):
        read_any(tmp_path / "u.tdms")
    ch = ChannelObject("g", "ai0", np.zeros(5000), properties={"unit_string": "N"})
    with TdmsWriter(str(tmp_path / "r.tdms")) as w:
        w.write_segment([RootObject(), GroupObject("g"), ch])
    with pytest.raises(RecordingError, match=r"channel g/ai0 has no wf_increment"):
        read_any(tmp_path / "r.tdms")
    with pytest.raises(RecordingError, match=r"no hit: .* never crosses the trigger level 5"):
        read_any(tmp_path / "r.tdms", sample_rate=RATE)


def test_mat_round_trip_in_volts(tmp_path):
    _, f = pulses()
    io.savemat(tmp_path / "r.mat", {"voltage": f * 11.24e-3, "fs": RATE, "sensitivity": 11.24e-3})
    rec = read_any(tmp_path / "r.mat")
    assert len(rec.hits) == 3
    assert np.max(np.abs(recording_tof(rec).tof - TOF)) < 0.05 / RATE
    io.savemat(tmp_path / "bad.mat", {"x": f})
    with pytest.raises(RecordingError, match="no 'force'"):
        read_any(tmp_path / "bad.mat")


def test_unknown_format_is_an_error(tmp_path):
    (tmp_path / "r.wav").write_bytes(b"RIFF")
    with pytest.raises(RecordingError, match=r"unknown recording format '\.wav'"):
        read_any(tmp_path / "r.wav")


def test_tdms_hits_of_different_lengths_are_read_each_at_its_own(tmp_path, chain_hits):
    """A TDMS file whose hits differ in length by a sample (359 and 360 samples, as a
    LabVIEW export that cut its records by time): read, each hit at its own length, and
    the TOF picked per hit (a table of one length was refused)."""
    hits, s, true_tof, opts = chain_hits
    cut = [h.force[:s.record_samples - (i % 2)] for i, h in enumerate(hits)]
    chans = [ChannelObject("Untitled", f"Force {i}", f, properties={
        "wf_increment": 1.0 / s.sample_rate, "wf_start_offset": -s.pretrigger_samples
        / s.sample_rate, "wf_samples": f.size, "unit_string": "N"})
        for i, f in enumerate(cut)]
    with TdmsWriter(str(tmp_path / "ragged.tdms")) as w:
        w.write_segment([RootObject(), GroupObject("Untitled"), *chans])
    rec = read_any(tmp_path / "ragged.tdms")
    assert [h.force.size for h in rec.hits] == [f.size for f in cut]
    assert len({f.size for f in cut}) == 2
    res = recording_tof(rec, opts)
    assert np.all(np.abs(res.tof / true_tof - 1) < 0.002)


@pytest.mark.parametrize("suffix", [".csv", ".tdms", ".mat"])
def test_imported_hits_are_checked_for_clipping_against_the_device(tmp_path, suffix):
    """A hit that reaches the device's full scale (the thesis sensor on the NI 9234's +-5 V:
    444.8 N) is clipped whatever the file's format: refused, or dropped with its reason;
    `ssw measure` drops it and says so."""
    from ssw.device import load_device

    full = load_device().full_scale_force
    assert full == pytest.approx(5.0 / 11.24e-3)
    _, f = pulses(4)
    f[:, 1] = np.minimum(f[:, 1] * 10.0, full)  # the second hit saturates at full scale
    rec = Recording("mem", {"pretrigger_samples": 64}, RATE,
                    tuple(RecordedHit(i, f[:, i].copy(), 64) for i in range(4)))
    path = write_any(tmp_path / f"c{suffix}", rec)
    # the hit as the written file names it: its column, its channel, its MAT column
    name = {".csv": "hit_0001", ".tdms": "hit_0001", ".mat": "force column 2"}[suffix]
    assert len(read_any(path).hits) == 4  # without a range: nothing to check against
    with pytest.raises(RecordingError, match=f"{name} is clipped"):
        read_any(path, full_scale=full)
    kept = read_any(path, full_scale=full, clipped="drop")
    assert len(kept.hits) == 3 and f"{name} is clipped" in kept.dropped[0]
