"""CSV recordings: a header row, then one row per sample.

Reading. Lines starting with ``#`` are comments; the delimiter is the first of ``,``,
``;``, tab found in the header. A column named ``t``/``time`` or whose unit is a time gives
the sample times (s unless its header gives a unit; 0 at the trigger when the axis starts
before 0, else the first 5 % of the record is the baseline); every other column is
one hit, a force or a sensor voltage, named by its header (``hit3``: every message about
the hit says ``hit3``). Units come from the header (:mod:`.common`:
``force [N]``, ``force_N``, ``time_s``, ``voltage_V``); ``units=`` gives the unit of hit
columns whose header has none, and must agree with any header that has one. Without a
time column, ``sample_rate`` (S/s) is required.

Writing. ``time_s`` (s, 0 at the trigger) and one ``hit_NNNN_N`` column per hit, every value
with 17 significant digits, so that a written recording reads back bit for bit.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from ssw.daq.formats.common import (
    TIME_NAMES,
    hit_matrix,
    make_recording,
    parse_column,
    pretrigger,
    quantity_of,
    rate_from_time,
    time_factor,
    to_newtons,
    unit_of,
)
from ssw.daq.recording import Recording
from ssw.errors import RecordingError
from ssw.h5io import atomic_write_text

DELIMITERS = (",", ";", "\t")


def _rows(path: str) -> tuple[list[str], str, list[str]]:
    """Header cells, delimiter and data lines (comments and blank lines removed)."""
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise RecordingError(f"{path}: not a readable CSV file: {exc}") from exc
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise RecordingError(f"{path}: empty CSV file: a header row and data rows expected")
    delim = next((d for d in DELIMITERS if d in lines[0]), ",")
    header = next(csv.reader([lines[0]], delimiter=delim))
    return header, delim, lines[1:]


def _table(path: str, header: list[str], delim: str, lines: list[str]) -> np.ndarray:
    if not lines:
        raise RecordingError(f"{path}: no data rows under the header")
    try:
        data = np.loadtxt(io.StringIO("\n".join(lines)), delimiter=delim, ndmin=2)
    except ValueError:  # find the cell to name it
        for r, line in enumerate(lines, start=2):
            cells = line.split(delim)
            if len(cells) != len(header):
                raise RecordingError(f"{path}: row {r} has {len(cells)} cells, the header "
                                     f"{len(header)}") from None
            for c, cell in enumerate(cells):
                try:
                    float(cell)
                except ValueError:
                    raise RecordingError(f"{path}: row {r}, column {header[c]!r}: {cell!r} is "
                                         "not a number") from None
        raise
    if data.shape[1] != len(header):
        raise RecordingError(f"{path}: {data.shape[1]} columns of data, {len(header)} in the "
                             "header")
    return data


def read(path: str | Path, *, units: str | None = None, sensitivity: float | None = None,
         sample_rate: float | None = None, clipped: str = "raise",
         full_scale: float | None = None, **_: object) -> Recording:
    """Read a CSV recording (module doc). ``units``: unit of hit columns without one.

    Parameters
    ----------
    path : str or pathlib.Path
        The file.
    units : str or None
        The unit of data that carry none (``N``, ``V``, ``lbf``, ...); must agree with a
        stored one.
    sensitivity : float or None
        The sensor sensitivity, V/N (data in volts are divided by it).
    sample_rate : float or None
        The sample rate, S/s, when the file stores no time axis or rate.
    clipped : str
        What to do with clipped hits: ``raise``, ``drop`` or ``keep``.
    full_scale : float or None
        The recording device's largest unclipped force, N (None: no range check).
    **_
        Ignored (the options of other formats).

    Returns
    -------
    ssw.daq.recording.Recording
        The hits, force in N.

    Raises
    ------
    ssw.errors.RecordingError
        When the file cannot be read, a unit is missing or unknown, or no rate is known.
    """
    p = str(path)
    header, delim, lines = _rows(p)
    data = _table(p, header, delim, lines)
    if units is not None and unit_of(units) is None:
        raise RecordingError(f"{p}: --units {units!r} is not a unit of force or voltage")
    parsed = [parse_column(h) for h in header]
    time_cols = [i for i, (name, u) in enumerate(parsed)
                 if name.lower() in TIME_NAMES or quantity_of(unit_of(u)) == "time"]
    if len(time_cols) > 1:
        raise RecordingError(f"{p}: columns {[header[i] for i in time_cols]} are all times; "
                             "one time column expected")
    t = None
    if time_cols:
        i = time_cols[0]
        t = data[:, i] * time_factor(parsed[i][1], f"{p}: column {header[i]!r}")
    cols = [i for i in range(len(header)) if i not in time_cols]
    if not cols:
        raise RecordingError(f"{p}: no hit column besides the time; a force (N) or voltage "
                             "(V) column expected")
    forces = []
    for i in cols:
        u = parsed[i][1]
        where = f"{p}: column {header[i]!r}"
        if u is not None and units is not None and unit_of(u) != unit_of(units):
            raise RecordingError(f"{where}: the header says {u!r}, --units says {units!r}")
        if u is None and units is None:
            raise RecordingError(f"{where} has no unit; name it like 'force [N]' or "
                                 "'force_N' (or V with --sensitivity), or pass --units N")
        forces.append(to_newtons(data[:, i], u or units, sensitivity, where))
    if t is not None:
        rate = rate_from_time(t, f"{p}: column {header[time_cols[0]]!r}")
    elif sample_rate is not None:
        rate = float(sample_rate)
    else:
        raise RecordingError(f"{p}: no time column ('time_s', 'time [s]'); pass the sample "
                             "rate (S/s, --sample-rate)")
    n_pre = pretrigger(t, data.shape[0])
    # each hit named by its column's header, without its unit ("hit3", "hit_0002")
    labels = [parsed[i][0] or header[i].strip() for i in cols]
    return make_recording(p, forces, rate, n_pre, {"format": "csv"}, clipped, full_scale,
                          labels)


def write(path: str | Path, rec: Recording, **_: object) -> Path:
    """Write ``rec`` as CSV (module doc), atomically; returns the path.

    Parameters
    ----------
    path : str or pathlib.Path
        The file to write.
    rec : ssw.daq.recording.Recording
        The recording; its hits of one length and one trigger index.
    **_
        Ignored (the options of other formats).

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    ssw.errors.RecordingError
        When the recording has no hits, or its hits differ in length or trigger index.
    """
    force, n_pre = hit_matrix(rec)
    t = (np.arange(force.shape[0]) - n_pre) / rec.sample_rate
    names = ["time_s"] + [f"hit_{h.index:04d}_N" for h in rec.hits]
    buf = io.StringIO()
    np.savetxt(buf, np.column_stack([t, force]), delimiter=",", fmt="%.17g",
               header=",".join(names), comments="")
    atomic_write_text(path, buf.getvalue())
    return Path(path)
