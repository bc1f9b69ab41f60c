"""A hit with non-finite samples spoils no file: it is rejected with its reason, named as its
file names it, and the other hits are used, in every format (as a dead hit is).

Truth: the same session without the spoilt hit. Its four good hits give E to the last bit;
the file with the spoilt hit must give the same E, and say which hit it rejected and why.
"""

from __future__ import annotations

import json
import shutil

import h5py
import numpy as np
import pytest

from ssw.cli import main
from ssw.daq.importers import read_any, write_any
from ssw.daq.recording import RecordedHit, Recording

#: The spoilt hit (0-based index 2: the file's third hit) and its gap.
BAD, GAP = 2, slice(100, 110)


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    """Five simulated hits of the thesis device on PCF 30 (a session file) and its
    records."""
    d = tmp_path_factory.mktemp("bad_hits")
    path = d / "pcf30.h5"
    assert main(["acquire", "--simulate", "--material", "pcf30", "--sample", "PCF30",
                 "--hits", "5", "--output", str(path), "--calibration", "none"]) == 0
    return d, path, read_any(path)


def _csv(path, rec, hits):
    """A CSV of ``hits`` (indices) with the header ``time_s,hit1_N,...`` numbering every hit
    of the session from 1, so that the file calls its third hit ``hit3``."""
    n_pre = rec.hits[0].trigger_index
    t = (np.arange(rec.hits[0].force.size) - n_pre) / rec.sample_rate
    cols = [rec.hits[i].force.copy() for i in hits]
    if BAD in hits:
        cols[hits.index(BAD)][GAP] = np.nan
    head = ",".join(["time_s", *(f"hit{i + 1}_N" for i in hits)])
    np.savetxt(path, np.column_stack([t, *cols]), delimiter=",", header=head, comments="",
               fmt="%.17g")
    return path


def _spoilt(rec):
    """The session with ten NaN samples in its third hit."""
    hits = []
    for h in rec.hits:
        f = h.force.copy()
        if h.index == BAD:
            f[GAP] = np.nan
        hits.append(RecordedHit(h.index, f, h.trigger_index))
    return Recording(rec.path, rec.meta, rec.sample_rate, tuple(hits))


def _measure(capsys, path):
    assert main(["measure", str(path), "--soil-nu", "0.3", "--calibration", "none",
                 "--stress-checks", "none", "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def _spoilt_file(kind, d, path, rec):
    """The session with the spoilt hit as a ``kind`` file, and the name its file gives it."""
    if kind == "csv":
        return _csv(d / "spoilt.csv", rec, list(range(5))), "hit3"
    if kind == "h5":
        out = d / "spoilt.h5"
        shutil.copy(path, out)
        with h5py.File(out, "r+") as f:
            ds = f["hits/hit_0002"]
            data = ds[()]
            data[GAP] = np.nan
            ds[...] = data
        return out, "hit_0002"
    return write_any(d / "spoilt.tdms", _spoilt(rec)), "hit_0002"


@pytest.mark.parametrize("kind", ["csv", "h5", "tdms"])
def test_a_hit_with_nan_samples_is_rejected_by_its_name_and_the_others_give_e(
        capsys, session, kind):
    """Ten NaN samples in the third hit: `ssw measure` gives E from the four others (the
    same E as the file holding only them), counts 4 of 5 hits, and its rejection names the
    hit as the file does (CSV: its column ``hit3``; HDF5 and TDMS: ``hit_0002``, the
    dataset's and the channel's name) with the reason; `ssw tof-recording` says the same."""
    d, path, rec = session
    good = _measure(capsys, _csv(d / "good.csv", rec, [0, 1, 3, 4]))
    spoilt, name = _spoilt_file(kind, d, path, rec)
    res = _measure(capsys, spoilt)
    assert res["n_accepted"] == 4 and res["n_hits"] + res["n_dropped"] == 5
    assert res["E"] == good["E"] and res["tof_mean"] == good["tof_mean"]
    why = [r for r in res["rejections"] if name in r]
    assert len(why) == 1 and "10 of" in why[0] and "not finite" in why[0], res["rejections"]
    assert main(["tof-recording", str(spoilt), "--calibration", "none"]) == 0
    out = capsys.readouterr().out
    assert "4 of 5 hits accepted" in out and f"{name}: 10 of" in out


def test_every_rejection_names_the_hit_as_its_file_does(session, tmp_path):
    """A dead hit (all zeros) in a CSV whose columns are named ``a``..``e``: the TOF
    picking rejects it as ``c``, not by a 0-based index."""
    from ssw.signal.tof import recording_tof

    _, _, rec = session
    n_pre = rec.hits[0].trigger_index
    t = (np.arange(rec.hits[0].force.size) - n_pre) / rec.sample_rate
    cols = [h.force.copy() for h in rec.hits]
    cols[BAD][:] = 0.0
    path = tmp_path / "dead.csv"
    np.savetxt(path, np.column_stack([t, *cols]), delimiter=",",
               header="time_s,a_N,b_N,c_N,d_N,e_N", comments="", fmt="%.17g")
    res = recording_tof(read_any(path))
    assert res.labels == ("a", "b", "c", "d", "e")
    assert res.n_accepted == 4 and res.reasons[0].startswith("c: ")
    assert res.to_dict()["hits"] == ["a", "b", "c", "d", "e"]
