"""Recordings made elsewhere (MATLAB, LabVIEW/NI exports) as :class:`Recording` objects.

Formats (registry :data:`IMPORTERS`, by file suffix):

* ``.csv``: a header row, then one row per sample. A column named ``time``/``t`` (with an
  optional unit ``[s]``) gives the sample times (s, 0 at the trigger); every other column
  is one hit. Units go in brackets: ``hit1 [N]`` (force) or ``hit1 [V]`` (sensor voltage,
  converted with ``sensitivity`` in V/N); columns without a unit are taken as N only if
  ``units="N"`` is passed.
* ``.mat`` (``scipy.io.loadmat``, MATLAB v5/v7): variables ``force`` (N) or ``voltage``
  (V) of shape (n_samples, n_hits) or (n_samples,), and either ``fs`` (S/s) or ``t``
  (s). ``sensitivity`` (V/N) may be stored in the file.

TDMS is not supported: no TDMS reader is installed here (``npTDMS`` would add one).
Sample rates must be uniform; hits must have equal length. Errors are
:class:`ssw.errors.RecordingError`.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ssw.daq.recording import CLIP_POLICIES, RecordedHit, Recording, check_hits
from ssw.errors import ConfigError, RecordingError

PRE_FRACTION = 0.05  # share of a record used as baseline when no time axis marks the trigger
UNIT_RE = re.compile(r"^\s*(?P<name>[^\[\(]*?)\s*(?:[\[\(]\s*(?P<unit>[^\]\)]*)\s*[\]\)])?\s*$")


def _to_newtons(data: np.ndarray, unit: str | None, sensitivity: float | None,
                path: str) -> np.ndarray:
    if unit == "N":
        return data
    if unit == "V":
        if not sensitivity or sensitivity <= 0:
            raise RecordingError(f"{path}: data are in V; pass the sensor sensitivity (V/N) "
                                 "to convert them to N")
        return data / sensitivity
    raise RecordingError(f"{path}: units = {unit!r}; force in 'N' or voltage in 'V' expected")


def _rate_from_time(t: np.ndarray, path: str) -> float:
    dt = np.diff(t)
    if dt.size == 0 or np.any(dt <= 0) or np.ptp(dt) > 1e-6 * np.mean(dt):
        raise RecordingError(f"{path}: the time column is not uniformly increasing")
    return float(1.0 / np.mean(dt))


def _recording(path: str, data: np.ndarray, rate: float, n_pre: int, meta: dict[str, Any],
               clipped: str, full_scale: float | None) -> Recording:
    if data.ndim == 1:
        data = data[:, None]
    if data.size == 0 or data.shape[1] == 0:
        raise RecordingError(f"{path}: empty recording: no samples")
    hits = [RecordedHit(i, np.ascontiguousarray(data[:, i], dtype=np.float64), n_pre)
            for i in range(data.shape[1])]
    kept, dropped = check_hits(path, hits, record_samples=data.shape[0],
                               full_scale=full_scale, clipped=clipped)
    meta = {"units": "N", "sample_rate": rate, "pretrigger_samples": n_pre,
            "record_samples": data.shape[0], "imported_from": path, **meta}
    return Recording(path, meta, rate, tuple(kept), tuple(dropped))


def _pretrigger(t: np.ndarray | None, n: int) -> int:
    if t is not None and t[0] < 0 <= t[-1]:
        return max(int(np.searchsorted(t, 0.0)), 2)
    return max(int(PRE_FRACTION * n), 2)


def read_csv(path: str | Path, *, units: str | None = None, sensitivity: float | None = None,
             sample_rate: float | None = None, clipped: str = "raise",
             full_scale: float | None = None) -> Recording:
    """Read a CSV recording (see the module doc). ``units`` overrides header units."""
    p = str(path)
    try:
        header = Path(p).read_text().splitlines()[0].split(",")
        data = np.loadtxt(p, delimiter=",", skiprows=1, ndmin=2)
    except (OSError, ValueError, IndexError) as exc:
        raise RecordingError(f"{p}: not a readable CSV recording: {exc}") from exc
    names, col_units = [], []
    for h in header:
        m = UNIT_RE.match(h)
        names.append((m.group("name") if m else h).strip().lower())
        col_units.append(m.group("unit").strip() if m and m.group("unit") else None)
    if data.shape[1] != len(names):
        raise RecordingError(f"{p}: {data.shape[1]} columns of data, {len(names)} in the header")
    t = None
    cols = list(range(len(names)))
    if names[0] in ("t", "time"):
        if col_units[0] not in (None, "s"):
            raise RecordingError(f"{p}: time column in {col_units[0]!r}; seconds expected")
        t = data[:, 0]
        cols = cols[1:]
    hit_units = {units or col_units[i] for i in cols}
    if len(hit_units) != 1:
        raise RecordingError(f"{p}: hit columns have mixed units {sorted(map(str, hit_units))}")
    unit = hit_units.pop()
    force = _to_newtons(data[:, cols], unit, sensitivity, p)
    rate = _rate_from_time(t, p) if t is not None else sample_rate
    if rate is None:
        raise RecordingError(f"{p}: no time column; pass sample_rate (S/s)")
    return _recording(p, force, rate, _pretrigger(t, force.shape[0]), {"format": "csv"},
                      clipped, full_scale)


def read_mat(path: str | Path, *, sensitivity: float | None = None, clipped: str = "raise",
             full_scale: float | None = None) -> Recording:
    """Read a MATLAB ``.mat`` recording (see the module doc)."""
    from scipy import io

    p = str(path)
    try:
        mat = io.loadmat(p, squeeze_me=True)
    except (OSError, ValueError, NotImplementedError) as exc:
        raise RecordingError(f"{p}: not a readable MAT file (v7.3 files are HDF5: "
                             f"export as -v7): {exc}") from exc
    if "force" in mat:
        data, unit = np.asarray(mat["force"], dtype=np.float64), "N"
    elif "voltage" in mat:
        data, unit = np.asarray(mat["voltage"], dtype=np.float64), "V"
        sensitivity = sensitivity or (float(mat["sensitivity"]) if "sensitivity" in mat else None)
    else:
        raise RecordingError(f"{p}: no 'force' (N) or 'voltage' (V) variable; found "
                             f"{sorted(k for k in mat if not k.startswith('__'))}")
    data = _to_newtons(data, unit, sensitivity, p)
    t = np.asarray(mat["t"], dtype=np.float64) if "t" in mat else None
    if t is not None:
        rate = _rate_from_time(t, p)
    elif "fs" in mat:
        rate = float(mat["fs"])
    else:
        raise RecordingError(f"{p}: neither 'fs' (S/s) nor 't' (s) is stored")
    return _recording(p, data, rate, _pretrigger(t, data.shape[0]), {"format": "mat"},
                      clipped, full_scale)


def _read_h5(path: str | Path, clipped: str = "raise", **_: Any) -> Recording:
    from ssw.daq.recording import read_recording

    return read_recording(path, clipped=clipped)


IMPORTERS: dict[str, Callable[..., Recording]] = {".csv": read_csv, ".mat": read_mat,
                                                   ".h5": _read_h5, ".hdf5": _read_h5}


def read_any(path: str | Path, *, clipped: str = "raise", **options: Any) -> Recording:
    """Read a recording by its suffix (``.h5``/``.hdf5``, ``.csv``, ``.mat``)."""
    if clipped not in CLIP_POLICIES:
        raise ConfigError("clipped", clipped, f"one of {CLIP_POLICIES}")
    suffix = Path(path).suffix.lower()
    if suffix not in IMPORTERS:
        raise RecordingError(f"{path}: unknown recording format {suffix!r}; one of "
                             f"{sorted(IMPORTERS)} (TDMS: export to CSV or MAT)")
    return IMPORTERS[suffix](path, clipped=clipped, **options)
