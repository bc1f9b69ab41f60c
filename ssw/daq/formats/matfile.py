"""MATLAB ``.mat`` recordings (``scipy.io``, MATLAB v5/v7; v7.3 files are HDF5).

Variables: ``force`` (N) or ``voltage`` (V) of shape (n_samples, n_hits) or
(n_samples,), and ``fs`` (S/s) or ``t`` (s, 0 at the trigger when it starts before 0);
the hits named ``force column k`` (k from 1); optional ``sensitivity`` (V/N) and
``units`` (the unit of ``force``/``voltage`` when it is not N/V, e.g. ``lbf``, ``mV``).
Written files hold ``force`` (N), ``t`` and ``fs``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ssw.daq.formats.common import (
    hit_matrix,
    make_recording,
    pretrigger,
    rate_from_time,
    to_newtons,
    unit_of,
)
from ssw.daq.recording import Recording
from ssw.errors import RecordingError
from ssw.h5io import atomic_path


def read(path: str | Path, *, units: str | None = None, sensitivity: float | None = None,
         sample_rate: float | None = None, clipped: str = "raise",
         full_scale: float | None = None, **_: object) -> Recording:
    """Read a ``.mat`` recording (module doc).

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
    from scipy import io

    p = str(path)
    try:
        mat = io.loadmat(p, squeeze_me=True)
    except (OSError, ValueError, NotImplementedError) as exc:
        raise RecordingError(f"{p}: not a readable MAT file (v7.3 files are HDF5: "
                             f"export as -v7): {exc}") from exc
    stored = str(mat["units"]) if "units" in mat else None
    if "force" in mat:
        var, default = "force", "N"
    elif "voltage" in mat:
        var, default = "voltage", "V"
        if sensitivity is None and "sensitivity" in mat:
            sensitivity = float(mat["sensitivity"])
    else:
        raise RecordingError(f"{p}: no 'force' (N) or 'voltage' (V) variable; found "
                             f"{sorted(k for k in mat if not k.startswith('__'))}")
    unit = units or stored or default
    if stored and units and unit_of(stored) != unit_of(units):
        raise RecordingError(f"{p}: variable {var!r}: the file says {stored!r}, --units says "
                             f"{units!r}")
    data = np.asarray(mat[var], dtype=np.float64)
    if data.ndim == 1:
        data = data[:, None]
    data = to_newtons(data, unit, sensitivity, f"{p}: variable {var!r}")
    t = np.asarray(mat["t"], dtype=np.float64).ravel() if "t" in mat else None
    if t is not None:
        if t.size != data.shape[0]:
            raise RecordingError(f"{p}: variable 't' has {t.size} samples, {var!r} "
                                 f"{data.shape[0]}")
        rate = rate_from_time(t, f"{p}: variable 't'")
    elif "fs" in mat:
        rate = float(mat["fs"])
    elif sample_rate is not None:
        rate = float(sample_rate)
    else:
        raise RecordingError(f"{p}: neither 'fs' (S/s) nor 't' (s) is stored; pass the "
                             "sample rate (--sample-rate)")
    k = data.shape[1]
    labels = [var if k == 1 else f"{var} column {i + 1}" for i in range(k)]
    return make_recording(p, [data[:, i] for i in range(k)], rate,
                          pretrigger(t, data.shape[0]), {"format": "mat"}, clipped, full_scale,
                          labels)


def write(path: str | Path, rec: Recording, **_: object) -> Path:
    """Write ``rec`` as ``.mat`` (``force`` N, ``t`` s, ``fs`` S/s), atomically.

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
    from scipy import io

    force, n_pre = hit_matrix(rec)
    t = (np.arange(force.shape[0]) - n_pre) / rec.sample_rate
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        io.savemat(fh, {"force": force, "t": t, "fs": rec.sample_rate, "units": "N"})
    return Path(path)
