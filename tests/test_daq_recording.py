"""Session files: round trip, the readers' errors, and interrupted sessions."""

from __future__ import annotations

import h5py
import numpy as np
import pytest

from ssw.daq.backend import Hit, run_session
from ssw.daq.recording import RecordingWriter, read_recording
from ssw.daq.settings import DaqSettings
from ssw.daq.simulated import sech2 as sech2_x
from ssw.errors import RecordingError
from ssw.signal.tof import recording_tof

S = DaqSettings(record_samples=256, pretrigger_samples=32, hits=4)


def sech2(n, centres, heights, width=3.0):
    """Sum of sech^2 pulses on sample indices (N)."""
    k = np.arange(n)[:, None]
    return np.sum(np.asarray(heights) * sech2_x((k - np.asarray(centres)) / width), axis=1)


class ListBackend:
    """Replays given records; raises ``fail`` after ``fail_after`` hits."""

    name = "list"

    def __init__(self, records, fail_after=None, fail=KeyboardInterrupt):
        self.records, self.fail_after, self.fail = records, fail_after, fail

    def describe(self):
        return {"model": "test"}

    def hits(self, settings, n):
        for i in range(n):
            if i == self.fail_after:
                raise self.fail()
            yield Hit(force=self.records[i % len(self.records)], trigger_index=32)


def two_pulse_records(n=4):
    return [sech2(256, [60 + i * 0.3, 140 + i * 0.3], [50.0, 20.0]) for i in range(n)]


def test_round_trip_keeps_values_and_metadata(tmp_path):
    recs = [np.pi * np.linspace(-1, 1, 256) / 7.0, np.e * np.sin(np.arange(256) / 3.0)]
    path = run_session(ListBackend(recs), S, tmp_path / "r.h5", sample_id="PCF08",
                       plate="PLA 0.4 mm", operator="mj", n_hits=2, synthetic=True)
    rec = read_recording(path)
    assert [h.force.dtype for h in rec.hits] == [np.float64, np.float64]
    for h, r in zip(rec.hits, recs, strict=True):
        np.testing.assert_array_equal(h.force, r)
    m = rec.meta
    assert (m["sample_id"], m["plate"], m["operator"], m["units"]) == (
        "PCF08", "PLA 0.4 mm", "mj", "N")
    assert m["sample_rate"] == 51200.0 and m["sensitivity"] == 11.24e-3
    assert m["synthetic"] is True and m["complete"] is True and m["n_hits"] == 2
    with h5py.File(path) as f:
        assert f["hits/hit_0001"].attrs["t0"] == pytest.approx(-32 / 51200.0)
        assert "created_utc" in f.attrs and "ssw_version" in f.attrs


def test_interrupted_session_keeps_every_completed_hit(tmp_path):
    path = tmp_path / "cut.h5"
    with pytest.raises(KeyboardInterrupt):
        run_session(ListBackend(two_pulse_records(), fail_after=3), S, path, sample_id="x")
    rec = read_recording(path)
    assert len(rec.hits) == 3
    assert rec.meta["complete"] is False and rec.meta["n_hits"] == 3
    assert recording_tof(rec).n_accepted == 3


def test_a_new_session_never_touches_an_existing_one(tmp_path):
    """Without overwrite, a second session into the same name goes to the next free name
    and the first file keeps its bytes; a writer asked for an existing path refuses."""
    path = run_session(ListBackend(two_pulse_records()), S, tmp_path / "a.h5", sample_id="x")
    before = path.read_bytes()
    second = run_session(ListBackend(two_pulse_records()), S, path, sample_id="y")
    assert second == tmp_path / "a-2.h5" and path.read_bytes() == before
    assert read_recording(second).meta["sample_id"] == "y"
    third = run_session(ListBackend(two_pulse_records()), S, path, sample_id="z")
    assert third == tmp_path / "a-3.h5"
    with pytest.raises(Exception, match="does not exist yet"):
        RecordingWriter(path, S, {"sample_id": "x"}, overwrite=False)


def test_overwrite_replaces_only_once_the_first_new_hit_is_on_disk(tmp_path):
    """--overwrite: a session that fails before its first hit leaves the old one intact
    (not truncated, not deleted); one that records a hit replaces it, whole."""
    path = run_session(ListBackend(two_pulse_records()), S, tmp_path / "o.h5", sample_id="old")
    before = path.read_bytes()
    with pytest.raises(KeyboardInterrupt):
        run_session(ListBackend(two_pulse_records(), fail_after=0), S, path, sample_id="new",
                    overwrite=True)
    assert path.read_bytes() == before and read_recording(path).meta["sample_id"] == "old"
    with pytest.raises(KeyboardInterrupt):
        run_session(ListBackend(two_pulse_records(), fail_after=1), S, path, sample_id="new",
                    overwrite=True)
    rec = read_recording(path)
    assert rec.meta["sample_id"] == "new" and len(rec.hits) == 1
    assert not list(tmp_path.glob("*.part"))


def test_a_writer_without_hits_leaves_no_file_and_an_empty_file_is_an_error(tmp_path):
    path = tmp_path / "empty.h5"
    with RecordingWriter(path, S, {"sample_id": "x"}, overwrite=False) as w:
        w.mark_complete()
    assert not path.exists()
    with h5py.File(path, "w") as f:  # a session file with no hit, made by hand
        f.attrs.update({"ssw_kind": "daq_recording", "units": "N", "sample_rate": 51200.0})
        f.create_group("hits")
    with pytest.raises(RecordingError, match="empty"):
        read_recording(path)


def test_truncated_hit_is_an_error(tmp_path):
    path = run_session(ListBackend([np.zeros(100)]), S, tmp_path / "t.h5", sample_id="x",
                       n_hits=1)
    with pytest.raises(RecordingError, match="truncated: 100 samples"):
        read_recording(path)


def test_truncated_file_is_an_error(tmp_path):
    path = run_session(ListBackend(two_pulse_records()), S, tmp_path / "f.h5", sample_id="x")
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 3])
    with pytest.raises(RecordingError, match="not a readable HDF5"):
        read_recording(path)


def test_clipped_hit_is_an_error_or_dropped(tmp_path):
    recs = two_pulse_records(2)
    recs[1] = np.minimum(recs[1] * 20, S.full_scale_force)  # flat top at +5 V
    path = run_session(ListBackend(recs), S, tmp_path / "c.h5", sample_id="x", n_hits=2)
    with pytest.raises(RecordingError, match="hit_0001 is clipped"):  # its dataset's name
        read_recording(path)
    rec = read_recording(path, clipped="drop")
    assert len(rec.hits) == 1 and "clipped" in rec.dropped[0]


@pytest.mark.parametrize("where", ["root", "hit"])
def test_wrong_units_are_an_error(tmp_path, where):
    path = run_session(ListBackend(two_pulse_records()), S, tmp_path / "u.h5", sample_id="x")
    with h5py.File(path, "a") as f:
        (f if where == "root" else f["hits/hit_0000"]).attrs["units"] = "V"
    with pytest.raises(RecordingError, match="units"):
        read_recording(path)


def test_single_peak_recording_is_an_error(tmp_path):
    single = sech2(256, [60.0], [50.0])
    path = run_session(ListBackend([single]), S, tmp_path / "s.h5", sample_id="x", n_hits=2)
    with pytest.raises(RecordingError, match="single peak"):
        recording_tof(read_recording(path))


def _kill_session_after(path, k: int, n_hits: int, pause_at: int | None) -> None:
    """Run a session of ``n_hits`` in a child process (a backend that pauses 60 s before hit
    ``pause_at``, or never), SIGKILL it (no cleanup, no close) once hit ``k`` is reported."""
    import signal
    import subprocess
    import sys
    import textwrap

    child = textwrap.dedent(f"""
        import time
        import numpy as np
        from ssw.daq.backend import Hit, run_session
        from ssw.daq.settings import DaqSettings

        class Source:
            name = "source"
            def describe(self):
                return {{}}
            def hits(self, settings, n):
                k = np.arange(256.0)
                for i in range(n):
                    if i == {pause_at!r}:
                        time.sleep(60)
                    yield Hit(force=50 / np.cosh((k - 60 - 0.1 * i) / 3) ** 2
                              + 20 / np.cosh((k - 140) / 3) ** 2, trigger_index=32)

        def told(i, hit):
            print(i, flush=True)

        run_session(Source(), DaqSettings(record_samples=256, pretrigger_samples=32),
                    {str(path)!r}, sample_id="k", n_hits={n_hits}, on_hit=told)
    """)
    proc = subprocess.Popen([sys.executable, "-c", child], stdout=subprocess.PIPE, text=True)
    try:
        for _ in range(k):
            proc.stdout.readline()
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()


def test_killed_session_keeps_every_flushed_hit(tmp_path):
    """SIGKILL (no cleanup, no close) during hit 4: the three flushed hits survive."""
    path = tmp_path / "killed.h5"
    _kill_session_after(path, 3, n_hits=5, pause_at=3)
    rec = read_recording(path)
    assert len(rec.hits) == 3 and rec.meta["complete"] is False
    assert recording_tof(rec).n_accepted == 3


@pytest.mark.parametrize("k", [1, 2, 3, 5, 8])
def test_sigkill_while_hits_keep_coming_keeps_hits_1_to_k(tmp_path, k):
    """SIGKILL right after hit k is reported, while the next hits are being written (no
    pause): the file is readable and holds at least hits 1..k, every one whole."""
    path = tmp_path / "fast.h5"
    _kill_session_after(path, k, n_hits=400, pause_at=None)
    rec = read_recording(path)
    assert len(rec.hits) >= k and rec.meta["complete"] is False
    assert all(h.force.size == 256 for h in rec.hits)
