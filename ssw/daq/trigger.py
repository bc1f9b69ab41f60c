"""The software trigger rule, one for every place that cuts hits out of a stream.

The rule (the simulated backend's, :mod:`ssw.daq.simulated`, and the one an analog-edge
reference trigger applies in hardware): a **crossing** at sample ``k`` is
``y[k-1] < level <= y[k]`` for a rising slope, ``y[k-1] > level >= y[k]`` for a falling
one; a record starts ``pretrigger_samples`` before the crossing and holds
``record_samples``; a crossing counts only with ``pretrigger_samples`` samples before it
and room for the whole record after it. After a record, the search resumes at its end
(hold-off), so one hit gives one record.

Three users: :func:`trigger_index` (the simulated backend's first crossing),
:func:`split_records` (a long recorded channel, e.g. one TDMS channel holding every hit),
and :class:`RingTrigger` (continuous acquisition through NI-DAQmx when the module cannot
source an analog reference trigger: chunks in, records out, across chunk boundaries).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ssw.errors import ConfigError, DaqError


@dataclass(frozen=True)
class TriggerRule:
    """Level (N), slope, pretrigger and record length (samples) of the trigger.

    Parameters
    ----------
    level : float
        The trigger level, N.
    slope : str
        ``rising`` or ``falling``.
    pretrigger_samples : int
        Samples kept before the trigger sample.
    record_samples : int
        Samples per record.
    """

    level: float
    slope: str = "rising"
    pretrigger_samples: int = 256
    record_samples: int = 2048

    def __post_init__(self) -> None:
        if self.slope not in ("rising", "falling"):
            raise ConfigError("trigger_slope", self.slope, "rising or falling")
        if not 0 <= self.pretrigger_samples <= self.record_samples - 2:
            raise ConfigError("pretrigger_samples", self.pretrigger_samples,
                              f"between 0 and record_samples - 2 = {self.record_samples - 2}")

    @classmethod
    def of(cls, settings: object) -> TriggerRule:
        """The rule of a :class:`ssw.daq.settings.DaqSettings`.

        Parameters
        ----------
        settings : ssw.daq.settings.DaqSettings
            The acquisition settings.

        Returns
        -------
        TriggerRule
            Its level, slope, pretrigger and record length.
        """
        return cls(settings.trigger_level, settings.trigger_slope,  # type: ignore[attr-defined]
                   settings.pretrigger_samples, settings.record_samples)  # type: ignore[attr-defined]


def crossings(y: np.ndarray, level: float, slope: str) -> np.ndarray:
    """Indices ``k >= 1`` where ``y`` crosses ``level`` (module rule), ascending.

    Parameters
    ----------
    y : numpy.ndarray
        The signal, N.
    level : float
        The trigger level, N.
    slope : str
        ``rising`` (``y[k-1] < level <= y[k]``) or ``falling`` (``y[k-1] > level >= y[k]``).

    Returns
    -------
    numpy.ndarray
        The indices ``k``, int.
    """
    y = np.asarray(y, dtype=np.float64)
    if slope == "rising":
        hit = (y[:-1] < level) & (y[1:] >= level)
    else:
        hit = (y[:-1] > level) & (y[1:] <= level)
    return np.flatnonzero(hit) + 1


def trigger_starts(y: np.ndarray, rule: TriggerRule, *, start: int = 0) -> list[int]:
    """Start indices of every record the rule cuts from ``y`` (from sample ``start`` on).

    Parameters
    ----------
    y : numpy.ndarray
        The signal, N.
    rule : TriggerRule
        The trigger rule.
    start : int
        The first sample a record may start at.

    Returns
    -------
    list of int
        The records' first samples, ascending; a record's crossing comes at least
        ``pretrigger_samples`` after the end of the previous record.
    """
    post = rule.record_samples - rule.pretrigger_samples
    ks = crossings(y, rule.level, rule.slope)
    ks = ks[(ks >= rule.pretrigger_samples) & (ks + post <= y.size)]
    out: list[int] = []
    nxt = start + rule.pretrigger_samples
    for k in ks:  # loop over crossings only (a few per hit), not samples
        if k >= nxt:
            out.append(int(k) - rule.pretrigger_samples)
            nxt = int(k) + post + rule.pretrigger_samples
    return out


def trigger_index(y: np.ndarray, rule: TriggerRule) -> int:
    """First trigger sample of ``y``; :class:`~ssw.errors.DaqError` if none leaves room for a
    record.

    Parameters
    ----------
    y : numpy.ndarray
        The signal, N.
    rule : TriggerRule
        The trigger rule.

    Returns
    -------
    int
        The index of the first trigger sample.

    Raises
    ------
    ssw.errors.DaqError
        When no crossing leaves room for a record.
    """
    starts = trigger_starts(y, rule)
    if not starts:
        raise DaqError(
            f"no trigger: the signal (peak {np.max(np.abs(y)):.4g} N) never crosses "
            f"trigger_level = {rule.level} N ({rule.slope}) with room for a record"
        )
    return starts[0] + rule.pretrigger_samples


def split_records(y: np.ndarray, rule: TriggerRule) -> list[np.ndarray]:
    """Every record (copies, ``record_samples`` each) the rule cuts from a long channel.

    Parameters
    ----------
    y : numpy.ndarray
        The long channel, N.
    rule : TriggerRule
        The trigger rule.

    Returns
    -------
    list of numpy.ndarray
        The records, in order.
    """
    y = np.asarray(y, dtype=np.float64)
    return [y[s : s + rule.record_samples].copy() for s in trigger_starts(y, rule)]


class RingTrigger:
    """The trigger rule applied to a stream that arrives in chunks (continuous acquisition).

    ``feed(chunk)`` appends samples to a ring buffer of ``capacity`` samples and returns
    the records completed so far, in order, with the same crossings, pretrigger and
    hold-off as :func:`trigger_starts` on the whole stream: a crossing in one chunk whose
    record ends in a later chunk is emitted when that chunk arrives. ``samples_seen`` is
    the stream's length so far.

    Parameters
    ----------
    rule : TriggerRule
        The trigger rule.
    capacity : int or None
        The ring buffer's size, samples, at least 2 x ``record_samples`` (None: 4 x).
    """

    def __init__(self, rule: TriggerRule, capacity: int | None = None) -> None:
        self.rule = rule
        self.capacity = int(capacity or 4 * rule.record_samples)
        if self.capacity < 2 * rule.record_samples:
            raise ConfigError("ring buffer", self.capacity,
                              f"at least 2 x record_samples = {2 * rule.record_samples}")
        self._buf = np.zeros(self.capacity)
        self._n = 0  # samples in the buffer (the latest ones of the stream)
        self.samples_seen = 0
        self._next = rule.pretrigger_samples  # first stream index a crossing may have
        self._pending: int | None = None  # stream index of a crossing awaiting its record

    def _window(self) -> tuple[np.ndarray, int]:
        """The buffered samples and the stream index of the first one."""
        return self._buf[: self._n], self.samples_seen - self._n

    def feed(self, chunk: np.ndarray) -> list[np.ndarray]:
        """Append ``chunk`` (N) and return the records it completes.

        Parameters
        ----------
        chunk : numpy.ndarray
            The stream's next samples, N.

        Returns
        -------
        list of numpy.ndarray
            The records completed, ``record_samples`` each, in order.
        """
        x = np.asarray(chunk, dtype=np.float64).ravel()
        out: list[np.ndarray] = []
        while x.size:
            room = self.capacity - self._n
            if room == 0:  # drop the oldest samples no record can still need
                keep = self._keep_from()
                self._buf[: self._n - keep] = self._buf[keep : self._n]
                self._n -= keep
                room = self.capacity - self._n
            take = x[:room]
            self._buf[self._n : self._n + take.size] = take
            self._n += take.size
            self.samples_seen += take.size
            x = x[take.size :]
            out += self._scan()
        return out

    def _keep_from(self) -> int:
        """Buffer index from which samples must be kept (pretrigger of any future record)."""
        first = self.samples_seen - self._n
        need = (self._pending if self._pending is not None
                else max(self.samples_seen - 1, self._next)) - self.rule.pretrigger_samples
        return int(np.clip(need - first, 1, self._n))

    def _scan(self) -> list[np.ndarray]:
        rule = self.rule
        post = rule.record_samples - rule.pretrigger_samples
        out: list[np.ndarray] = []
        while True:
            y, first = self._window()
            if self._pending is None:
                lo = max(self._next - first - 1, 0)  # y[lo] is the sample before a crossing
                ks = crossings(y[lo:], rule.level, rule.slope) + lo + first
                ks = ks[ks >= self._next]
                if ks.size == 0:
                    return out
                self._pending = int(ks[0])
            k = self._pending
            if k + post > self.samples_seen:
                return out
            s = k - rule.pretrigger_samples - first
            out.append(y[s : s + rule.record_samples].copy())
            self._pending = None
            self._next = k + post + rule.pretrigger_samples
