"""NI TDMS recordings (LabVIEW, NI-DAQmx logging, FlexLogger), read with npTDMS.

Channels. Every channel of the file (or of ``group``) whose name is ``t``/``time`` or
whose unit is a time is a time axis; the others are data, each with the NI waveform
properties ``wf_increment`` (s per sample), ``wf_start_offset`` (s, time of the first
sample; negative when the record starts before its trigger) and ``unit_string`` (``N``,
``V``, ``lbf``, ...: :mod:`.common`). Without ``wf_increment`` the time channel of the
group, or ``sample_rate``, gives the rate. ``units=`` stands in for a missing
``unit_string`` and must agree with a present one.

Two layouts (``split=None`` tells them apart):

* **one channel per hit** (several data channels of equal length): each channel is one
  record, named by the channel; the pretrigger is ``-wf_start_offset / wf_increment``
  samples when the offset is negative, else the first 5 % of the record;
* **one long channel** (a single data channel longer than one record): the hits are cut
  out with the trigger rule of the simulated backend and the ring-buffer software trigger
  (:mod:`ssw.daq.trigger`): level, slope, pretrigger and record length from ``trigger``
  (a :class:`ssw.daq.trigger.TriggerRule`), else from the file's ``ssw_trigger_*``
  properties (written by :func:`write_stream`), else the ``daq:`` defaults; the hits are
  named ``<channel> record k`` (k from 1).

References
----------
NI, "TDMS File Format Internal Structure"; "Waveform properties in TDMS" (``wf_*``).
npTDMS (A. Reeve), ``nptdms.TdmsFile.read``, ``nptdms.TdmsWriter``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ssw.daq.formats.common import (
    TIME_NAMES,
    hit_matrix,
    make_recording,
    pretrigger,
    quantity_of,
    rate_from_time,
    time_factor,
    to_newtons,
    unit_of,
)
from ssw.daq.recording import Recording
from ssw.daq.trigger import TriggerRule, split_records
from ssw.errors import ConfigError, RecordingError
from ssw.h5io import atomic_path

GROUP = "ssw"  # group name of written files


def _nptdms() -> Any:
    try:
        import nptdms
    except ImportError as exc:  # pragma: no cover - npTDMS is a dependency
        raise RecordingError(f"reading TDMS needs the npTDMS package: {exc}") from exc
    return nptdms


def _default_rule(props: dict[str, Any]) -> TriggerRule:
    from ssw.daq.settings import DaqSettings

    d = DaqSettings()
    return TriggerRule(
        level=float(props.get("ssw_trigger_level", d.trigger_level)),
        slope=str(props.get("ssw_trigger_slope", d.trigger_slope)),
        pretrigger_samples=int(props.get("ssw_pretrigger_samples", d.pretrigger_samples)),
        record_samples=int(props.get("ssw_record_samples", d.record_samples)),
    )


def _is_time(name: str, props: dict[str, Any]) -> bool:
    unit = props.get("unit_string")
    return name.strip().lower() in TIME_NAMES or quantity_of(unit_of(unit)) == "time"


def read(path: str | Path, *, units: str | None = None, sensitivity: float | None = None,
         sample_rate: float | None = None, clipped: str = "raise",
         full_scale: float | None = None, group: str | None = None, split: bool | None = None,
         trigger: TriggerRule | None = None, **_: object) -> Recording:
    """Read a TDMS recording (module doc).

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
    group : str or None
        Read only this group (None: every group).
    split : bool or None
        Whether the one data channel is a long stream to cut into hits (None: when it is
        longer than one record).
    trigger : ssw.daq.trigger.TriggerRule or None
        The rule that cuts a long channel (None: the file's ``ssw_trigger_*`` properties, else
        the ``daq:`` defaults).
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
    ssw.errors.ConfigError
        When ``split`` is asked of a file with several data channels.
    """
    nptdms = _nptdms()
    p = str(path)
    try:
        tf = nptdms.TdmsFile.read(p)
    except Exception as exc:  # npTDMS raises ValueError/KeyError/struct.error on bad files
        raise RecordingError(f"{p}: not a readable TDMS file: {exc}") from exc
    groups = [g for g in tf.groups() if group is None or g.name == group]
    if group is not None and not groups:
        raise RecordingError(f"{p}: no group {group!r}; groups: {[g.name for g in tf.groups()]}")
    data, times = [], []
    for g in groups:
        for ch in g.channels():
            props = dict(ch.properties)
            (times if _is_time(ch.name, props) else data).append((g.name, ch, props))
    if not data:
        raise RecordingError(f"{p}: no data channel (groups {[g.name for g in tf.groups()]}); "
                             "a force (N) or voltage (V) channel expected")
    forces, rates, offsets = _channel_forces(data, times, p, units, sensitivity, sample_rate)
    if len({round(r, 6) for r in rates}) != 1:
        raise RecordingError(f"{p}: channels sampled at different rates {sorted(set(rates))} "
                             "S/s; one rate expected")
    rate = rates[0]
    if split is None:
        rule = trigger or _default_rule(dict(tf.properties))
        split = len(forces) == 1 and forces[0].size > rule.record_samples
    if split:
        if len(forces) != 1:
            raise ConfigError("split", True, f"a file with one data channel ({p} has "
                              f"{len(forces)})")
        return _split_stream(p, forces[0], data[0][0], data[0][1].name,
                             trigger or _default_rule(dict(tf.properties)), rate, clipped,
                             full_scale)
    n = forces[0].size
    t = (np.arange(n) / rate + offsets[0]) if offsets[0] < 0 else None
    if len(set(offsets)) != 1:
        raise RecordingError(f"{p}: channels start at different wf_start_offset "
                             f"{sorted(set(offsets))} s; one trigger position expected")
    return make_recording(p, forces, rate, pretrigger(t, n),
                          {"format": "tdms", "layout": "one channel per hit"}, clipped,
                          full_scale, [ch.name for _, ch, _ in data])


def _channel_forces(data: list, times: list, p: str, units: str | None,
                    sensitivity: float | None, sample_rate: float | None
                    ) -> tuple[list[np.ndarray], list[float], list[float]]:
    """Each data channel (``(group, channel, properties)``) as force (N), its sample rate
    (S/s) and its ``wf_start_offset`` (s); RecordingError on a unit missing or contradicted
    by ``units`` (V divided by ``sensitivity``, V/N)."""
    forces, rates, offsets = [], [], []
    for gname, ch, props in data:
        where = f"{p}: channel {gname}/{ch.name}"
        stored = props.get("unit_string")
        stored = str(stored) if stored not in (None, "") else None
        if stored and units and unit_of(stored) != unit_of(units):
            raise RecordingError(f"{where}: unit_string says {stored!r}, --units says {units!r}")
        if stored is None and units is None:
            raise RecordingError(f"{where} has no unit_string property; pass --units N (or V "
                                 "with --sensitivity)")
        forces.append(to_newtons(np.asarray(ch[:], dtype=np.float64), stored or units,
                                 sensitivity, where))
        rates.append(_rate(props, gname, times, sample_rate, p, where))
        offsets.append(float(props.get("wf_start_offset", 0.0)))
    return forces, rates, offsets


def _split_stream(p: str, force: np.ndarray, group: str, name: str, rule: TriggerRule,
                  rate: float, clipped: str, full_scale: float | None) -> Recording:
    """One long channel's force (N, at ``rate`` S/s; channel ``name`` of ``group``) cut into
    hits by the trigger ``rule``
    (:func:`ssw.daq.trigger.split_records`); RecordingError when no hit triggers."""
    hits = split_records(force, rule)
    if not hits:
        raise RecordingError(
            f"{p}: channel {group}/{name}: no hit: the signal (peak "
            f"{np.max(np.abs(force)):.4g} N) never crosses the trigger level "
            f"{rule.level} N ({rule.slope}) with room for a {rule.record_samples}-sample "
            "record")
    meta = {"format": "tdms", "layout": "one long channel, split by the trigger rule",
            "trigger_level": rule.level, "trigger_slope": rule.slope}
    return make_recording(p, hits, rate, rule.pretrigger_samples, meta, clipped,
                          full_scale, [f"{name} record {k + 1}" for k in range(len(hits))])


def _rate(props: dict[str, Any], gname: str, times: list, sample_rate: float | None,
          path: str, where: str) -> float:
    inc = props.get("wf_increment")
    if inc is not None:
        inc = float(inc)
        if not inc > 0:
            raise RecordingError(f"{where}: wf_increment = {inc!r}; a positive time step in s "
                                 "expected")
        return 1.0 / inc
    for g, ch, tprops in times:
        if g == gname:
            tw = f"{path}: channel {g}/{ch.name}"
            t = np.asarray(ch[:], dtype=np.float64) * time_factor(tprops.get("unit_string"), tw)
            return rate_from_time(t, tw)
    if sample_rate is not None:
        return float(sample_rate)
    raise RecordingError(f"{where} has no wf_increment and its group no time channel; pass "
                         "the sample rate (--sample-rate)")


def _channel(nptdms: Any, name: str, data: np.ndarray, rate: float, offset: float,
             unit: str) -> Any:
    props = {"wf_increment": 1.0 / rate, "wf_start_offset": float(offset),
             "wf_samples": int(data.size), "unit_string": unit, "NI_ChannelName": name}
    return nptdms.ChannelObject(GROUP, name, np.asarray(data, dtype=np.float64),
                                properties=props)


def write(path: str | Path, rec: Recording, **_: object) -> Path:
    """Write ``rec`` as TDMS, one channel per hit (force in N, NI waveform properties).

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
    nptdms = _nptdms()
    force, n_pre = hit_matrix(rec)
    offset = -n_pre / rec.sample_rate
    chans = [_channel(nptdms, f"hit_{h.index:04d}", force[:, i], rec.sample_rate, offset, "N")
             for i, h in enumerate(rec.hits)]
    _write(nptdms, path, chans, {"ssw_source": rec.path})
    return Path(path)


def write_stream(path: str | Path, force: np.ndarray, rate: float, rule: TriggerRule, *,
                 unit: str = "N", name: str = "force") -> Path:
    """Write one long channel (``force`` in ``unit``, ``rate`` S/s) with ``rule`` stored as
    the file's ``ssw_trigger_*`` properties (how :func:`read` splits it).

    Parameters
    ----------
    path : str or pathlib.Path
        The file to write.
    force : numpy.ndarray
        The signal, in ``unit``.
    rate : float
        The sample rate, S/s.
    rule : ssw.daq.trigger.TriggerRule
        The trigger rule stored with it.
    unit : str
        The signal's unit (stored as ``unit_string``).
    name : str
        The channel's name.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    nptdms = _nptdms()
    props = {"ssw_trigger_level": float(rule.level), "ssw_trigger_slope": rule.slope,
             "ssw_pretrigger_samples": int(rule.pretrigger_samples),
             "ssw_record_samples": int(rule.record_samples)}
    _write(nptdms, path, [_channel(nptdms, name, force, rate, 0.0, unit)], props)
    return Path(path)


def _write(nptdms: Any, path: str | Path, channels: list, props: dict[str, Any]) -> None:
    with atomic_path(path) as tmp:
        with nptdms.TdmsWriter(str(tmp)) as w:
            w.write_segment([nptdms.RootObject(properties=props),
                             nptdms.GroupObject(GROUP), *channels])
