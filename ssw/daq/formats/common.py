"""Units, column names and the checks every recording format shares.

Units. A recorded quantity is a force (converted to N), a sensor voltage (converted to N
with the sensor's sensitivity in V/N) or a time (converted to s):

=========  ==========================================================================
force      ``N``, ``kN``, ``lbf`` (1 lbf = 4.4482216152605 N exactly, NIST SP 811)
voltage    ``V``, ``mV``
time       ``s``, ``ms``, ``us`` (``µs``)
=========  ==========================================================================

Unit names are matched without regard to case (``force_n`` reads as N), and the spelled
forms ``newton(s)``, ``volt(s)``, ``second(s)`` are accepted.

Column names carry their unit in brackets or parentheses (``force [N]``, ``Time (s)``) or
as a suffix after an underscore (``force_N``, ``time_s``, ``voltage_V``); a name whose
last ``_token`` is not a unit has none (``hit_1``).
"""

from __future__ import annotations

import re
from typing import Any

import numpy as np

from ssw.daq.recording import RecordedHit, Recording, check_hits
from ssw.errors import RecordingError

#: unit -> (quantity, factor to SI)
UNITS: dict[str, tuple[str, float]] = {
    "N": ("force", 1.0),
    "kN": ("force", 1.0e3),
    "lbf": ("force", 4.4482216152605),  # N per lbf, exact (NIST SP 811, B.8)
    "V": ("voltage", 1.0),
    "mV": ("voltage", 1.0e-3),
    "s": ("time", 1.0),
    "ms": ("time", 1.0e-3),
    "us": ("time", 1.0e-6),
}
_ALIASES = {"newton": "N", "newtons": "N", "volt": "V", "volts": "V", "second": "s",
            "seconds": "s", "sec": "s", "µs": "us", "μs": "us"}
_LOOKUP = {**{k.lower(): k for k in UNITS}, **_ALIASES}
#: Names of a time column (case-insensitive, unit removed).
TIME_NAMES = ("t", "time")
#: Share of a record used as baseline when no time axis marks the trigger.
PRE_FRACTION = 0.05
_BRACKETS = re.compile(r"^\s*(?P<name>.*?)\s*[\[\(]\s*(?P<unit>[^\]\)]*?)\s*[\]\)]\s*$")


def unit_of(text: str | None) -> str | None:
    """The canonical unit (a key of :data:`UNITS`) spelled ``text``, or None if unknown.

    Parameters
    ----------
    text : str or None
        The unit as written (case and spelling variants accepted).

    Returns
    -------
    str or None
        The canonical unit.
    """
    if text is None:
        return None
    t = text.strip()
    return t if t in UNITS else _LOOKUP.get(t.lower())


def expected_units(quantity: str | None = None) -> str:
    """The accepted units of a quantity (or of all), for error messages.

    Parameters
    ----------
    quantity : str or None
        ``force``, ``voltage`` or ``time`` (None: all three).

    Returns
    -------
    str
        ``"<quantity>: <unit>, ..."``, quantities separated by ``;``.
    """
    q = [quantity] if quantity else ["force", "voltage", "time"]
    return "; ".join(f"{k}: {', '.join(u for u, (kind, _) in UNITS.items() if kind == k)}"
                     for k in q)


def parse_column(header: str) -> tuple[str, str | None]:
    """``(name, unit text or None)`` of a column header (brackets, parentheses, suffix).

    Parameters
    ----------
    header : str
        The column's header, e.g. ``force [N]``, ``force (N)`` or ``force_N``.

    Returns
    -------
    tuple of (str, str or None)
        The column's name and its unit as written (None: no unit found).
    """
    m = _BRACKETS.match(header)
    if m:
        return m.group("name").strip(), m.group("unit").strip()
    name = header.strip()
    if "_" in name:
        stem, suffix = name.rsplit("_", 1)
        if stem and unit_of(suffix) is not None:
            return stem.strip(), suffix
    return name, None


def quantity_of(unit: str | None) -> str | None:
    """``force``, ``voltage`` or ``time`` for a canonical unit.

    Parameters
    ----------
    unit : str or None
        A canonical unit (:func:`unit_of`).

    Returns
    -------
    str or None
        The unit's quantity; None for an unknown unit.
    """
    return UNITS[unit][0] if unit in UNITS else None


def to_newtons(data: np.ndarray, unit: str | None, sensitivity: float | None,
               where: str) -> np.ndarray:
    """``data`` in ``unit`` (force or voltage) as force in N; ``where`` names the source.

    Volts are divided by ``sensitivity`` (V/N). Raises :class:`~ssw.errors.RecordingError` naming
    ``where``, the unit and what was expected.

    Parameters
    ----------
    data : numpy.ndarray
        The values, in ``unit``.
    unit : str or None
        Their unit as written (a force or a voltage).
    sensitivity : float or None
        The sensor sensitivity, V/N (needed for a voltage).
    where : str
        The source (file and column), named in an error.

    Returns
    -------
    numpy.ndarray
        The force, N (float64).

    Raises
    ------
    ssw.errors.RecordingError
        When the unit is missing, unknown or a time, or a voltage comes without a positive
        sensitivity.
    """
    u = unit_of(unit)
    if u is None:
        got = "no unit" if unit is None else f"unit {unit!r}"
        raise RecordingError(f"{where}: {got}; expected a force ({expected_units('force')}) "
                             f"or a sensor voltage ({expected_units('voltage')})")
    kind, factor = UNITS[u]
    if kind == "force":
        return np.asarray(data, dtype=np.float64) * factor
    if kind == "voltage":
        if not sensitivity or not sensitivity > 0:
            raise RecordingError(f"{where}: data are in {u}; pass the sensor sensitivity (V/N, "
                                 "--sensitivity) to convert them to N")
        return np.asarray(data, dtype=np.float64) * factor / sensitivity
    raise RecordingError(f"{where}: unit {u!r} is a time; expected a force "
                         f"({expected_units('force')}) or a sensor voltage "
                         f"({expected_units('voltage')})")


def time_factor(unit: str | None, where: str) -> float:
    """Seconds per ``unit`` of a time axis (``None``: s).

    Parameters
    ----------
    unit : str or None
        The time axis's unit as written (None: s).
    where : str
        The source, named in an error.

    Returns
    -------
    float
        Seconds per unit.

    Raises
    ------
    ssw.errors.RecordingError
        When the unit is not a unit of time.
    """
    if unit is None:
        return 1.0
    u = unit_of(unit)
    if u is None or UNITS[u][0] != "time":
        raise RecordingError(f"{where}: time in {unit!r}; expected {expected_units('time')}")
    return UNITS[u][1]


def rate_from_time(t: np.ndarray, where: str) -> float:
    """Sample rate (S/s) of a uniform, increasing time axis ``t`` (s).

    Parameters
    ----------
    t : numpy.ndarray
        The time axis, s.
    where : str
        The source, named in an error.

    Returns
    -------
    float
        The sample rate, S/s: ``(n - 1) / (t[-1] - t[0])``.

    Raises
    ------
    ssw.errors.RecordingError
        When the steps are not all positive and equal within 1e-6 of their mean.
    """
    dt = np.diff(t)
    if dt.size == 0 or np.any(dt <= 0) or np.ptp(dt) > 1e-6 * np.mean(dt):
        raise RecordingError(f"{where}: the time axis is not uniformly increasing "
                             "(one sample rate expected)")
    return float((t.size - 1) / (t[-1] - t[0]))


def pretrigger(t: np.ndarray | None, n: int) -> int:
    """Pretrigger samples: the first sample at ``t >= 0`` when the axis starts before 0
    (0 at the trigger), else ``PRE_FRACTION`` of the record; at least 2.

    Parameters
    ----------
    t : numpy.ndarray or None
        The time axis, s, 0 at the trigger (None: no axis).
    n : int
        The record's length, samples.

    Returns
    -------
    int
        The pretrigger sample count.
    """
    if t is not None and t[0] < 0 <= t[-1]:
        return max(int(np.searchsorted(t, 0.0)), 2)
    return max(int(PRE_FRACTION * n), 2)


def make_recording(path: str, data: np.ndarray | list[np.ndarray], rate: float, n_pre: int,
                   meta: dict[str, Any], clipped: str, full_scale: float | None,
                   labels: list[str] | None = None) -> Recording:
    """A :class:`~ssw.daq.recording.Recording` of hits (columns of ``data``, N) after the
    readers' checks; ``labels`` name the hits as the file does (a column's header, a
    channel's name; default ``hit k`` from 1).

    Parameters
    ----------
    path : str
        The source file, named in errors and stored as ``imported_from``.
    data : numpy.ndarray or list of numpy.ndarray
        The hits' forces, N: a (n_samples, n_hits) array, or one array per hit (lengths may
        differ).
    rate : float
        The sample rate, S/s.
    n_pre : int
        The pretrigger sample count (the trigger index of every hit).
    meta : dict
        The format's metadata (SI units), added to the recording's.
    clipped : str
        What to do with clipped hits: ``raise``, ``drop`` or ``keep``.
    full_scale : float or None
        The largest unclipped force, N (None: no range check).
    labels : list of str or None
        The hits' names (None: ``hit k``).

    Returns
    -------
    ssw.daq.recording.Recording
        The checked recording (:func:`ssw.daq.recording.check_hits`).

    Raises
    ------
    ssw.errors.RecordingError
        When the data are empty, the rate is not positive, the labels do not match the hits,
        or a check of :func:`ssw.daq.recording.check_hits` fails.
    """
    cols = [np.asarray(c, dtype=np.float64) for c in
            (data if isinstance(data, list) else np.atleast_2d(np.asarray(data).T))]
    if not cols or cols[0].size == 0:
        raise RecordingError(f"{path}: empty recording: no samples")
    if not np.isfinite(rate) or rate <= 0:
        raise RecordingError(f"{path}: sample rate {rate!r}; a positive rate in S/s expected")
    # each hit at its own length (a TDMS file may hold 359- and 360-sample hits): the TOF
    # is picked hit by hit
    n = max(c.size for c in cols)
    if labels is not None and len(labels) != len(cols):
        raise RecordingError(f"{path}: {len(labels)} hit names for {len(cols)} hits")
    hits = [RecordedHit(i, np.ascontiguousarray(c), n_pre,
                        label=labels[i] if labels is not None else "")
            for i, c in enumerate(cols)]
    kept, dropped = check_hits(path, hits, record_samples=None, full_scale=full_scale,
                               clipped=clipped)
    meta = {"units": "N", "sample_rate": rate, "pretrigger_samples": n_pre,
            "record_samples": n, "imported_from": path, **meta}
    return Recording(path, meta, float(rate), tuple(kept), tuple(dropped))


def hit_matrix(rec: Recording) -> tuple[np.ndarray, int]:
    """``(force (n_samples, n_hits) N, pretrigger samples)`` of a recording for writers.

    Parameters
    ----------
    rec : ssw.daq.recording.Recording
        The recording.

    Returns
    -------
    force : numpy.ndarray
        The hits' forces, (n_samples, n_hits), N.
    n_pre : int
        The pretrigger sample count.

    Raises
    ------
    ssw.errors.RecordingError
        When there are no hits, or they differ in length or trigger index.
    """
    if not rec.hits:
        raise RecordingError(f"{rec.path}: no hits to write")
    n_pre = {h.trigger_index for h in rec.hits}
    lengths = {h.force.size for h in rec.hits}
    if len(n_pre) != 1 or len(lengths) != 1:
        raise RecordingError(f"{rec.path}: hits differ in length or trigger index; one of each "
                             "expected to write a table")
    return np.column_stack([h.force for h in rec.hits]), n_pre.pop()
