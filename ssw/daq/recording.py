"""HDF5 recordings: one file per sample session, one dataset per hit, flushed per hit.

Layout (``ssw_kind = "daq_recording"``)::

    /                     attrs: ssw_kind, ssw_version, created_utc, inputs_json (the
                          DaqSettings), units = "N", sample_rate (S/s), device, channel,
                          physical_channel, sensor_model, sensitivity (V/N),
                          excitation_current (A), coupling, trigger_* , pretrigger_samples,
                          record_samples, sample_id, plate, operator, synthetic, backend,
                          hw_* (hardware description), n_hits, complete, finished_utc
    /hits/hit_0000 ...    float64 (record_samples,) force, N; attrs: units, trigger_index,
                          t0 (s, time of sample 0 relative to the trigger), timestamp_utc,
                          overloaded, clipped, extra_json

Nothing recorded is ever lost. The session file is (re)written whole after every hit, under
a temporary name, fsync'd and renamed into place (:func:`ssw.h5io.atomic_path`, durable): at
any moment the file on disk is a complete, readable session of the hits recorded so far
(``complete`` turns true only at the end), so a kill, even SIGKILL or a power loss, keeps
hits 1..k once hit k is reported (an HDF5 file killed while open for writing can be left
unreadable, however often it was flushed; a small session rewritten per hit costs
milliseconds). There is no file before the first hit, and an existing file is replaced
(``overwrite``) only by the rename after the first new hit: until then the old session is
intact. Readers raise :class:`ssw.errors.RecordingError` for files that are empty,
truncated, clipped or in the wrong units.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from ssw import __version__
from ssw.daq.backend import Hit
from ssw.daq.settings import DaqSettings
from ssw.errors import ConfigError, RecordingError
from ssw.h5io import to_json

KIND = "daq_recording"
FORCE_UNITS = "N"
CLIP_FRACTION = 0.999  # |F| at or above this fraction of the +-5 V full scale counts as clipped
CLIP_POLICIES = ("raise", "drop", "keep")


def is_clipped(force: np.ndarray, full_scale: float) -> bool:
    """True if any sample reaches ``CLIP_FRACTION`` of the full-scale force ``full_scale``.

    Parameters
    ----------
    force : numpy.ndarray
        The hit's force, N.
    full_scale : float
        The full-scale force, N.

    Returns
    -------
    bool
        Whether ``max |force| >= CLIP_FRACTION * full_scale``.
    """
    return bool(np.any(np.abs(force) >= CLIP_FRACTION * full_scale))


def free_path(path: str | Path) -> Path:
    """``path`` if no file is there, else the first free ``<stem>-<k><suffix>`` (k = 2, 3,
    ...): a new session never replaces an existing recording unless asked to.

    Parameters
    ----------
    path : str or pathlib.Path
        The wished-for file.

    Returns
    -------
    pathlib.Path
        A path where no file is.
    """
    p = Path(path)
    if not p.exists():
        return p
    k = 2
    while (q := p.with_name(f"{p.stem}-{k}{p.suffix}")).exists():
        k += 1
    return q


class RecordingWriter:
    """Write a session file hit by hit (module docstring: the file is rewritten whole,
    atomically and durably, after each hit; use as a context manager).

    Parameters
    ----------
    path : str or pathlib.Path
        The session's HDF5 file. An existing file is replaced only with ``overwrite``,
        and only when the first hit of this session is on disk.
    settings : ssw.daq.settings.DaqSettings
        The acquisition settings (stored as metadata).
    meta : dict
        Sample id, plate, operator, synthetic flag, backend, hardware description.
    overwrite : bool
        Replace an existing file (once the first new hit is on disk).
    """

    def __init__(
        self, path: str | Path, settings: DaqSettings, meta: dict[str, Any], *, overwrite: bool
    ) -> None:
        self.path = Path(path)
        if self.path.exists() and not overwrite:
            raise ConfigError("recording", str(self.path), "a path that does not exist yet "
                              "(pass overwrite to replace a session)")
        self.settings = settings
        self.n = 0
        self._hits: list[tuple[np.ndarray, dict[str, Any]]] = []
        self._attrs: dict[str, Any] = {
            "ssw_kind": KIND, "ssw_version": __version__,
            "created_utc": datetime.now(UTC).isoformat(timespec="seconds"),
            "inputs_json": to_json(settings.to_dict(), sort_keys=True),
            "units": FORCE_UNITS, "sensitivity_units": "V/N",
            "trigger_type": ("analog edge on the force channel: the module's reference "
                             "trigger, or the same rule in software over a continuous "
                             "stream (hw_trigger)"),
            "n_hits": 0, "complete": False,
        }
        for key in ("device", "channel", "physical_channel", "sensor_model", "sensitivity",
                    "excitation_current", "coupling", "sample_rate", "max_force",
                    "trigger_level", "trigger_slope", "pretrigger_samples", "record_samples",
                    "full_scale_force"):
            self._attrs[key] = getattr(settings, key)
        self.set_meta(meta)

    def set_meta(self, meta: dict[str, Any]) -> None:
        """Store ``meta`` as root attributes (non-scalars as JSON); on disk with the next
        write (at once when hits are already there).

        Parameters
        ----------
        meta : dict
            Attribute name -> value (SI units).
        """
        for key, val in meta.items():
            ok = isinstance(val, bool | int | float | str)
            self._attrs[key] = val if ok else to_json(val)
        if self.n:
            self._write()

    def append(self, hit: Hit) -> None:
        """Add one hit as ``hits/hit_NNNN`` and put the session on disk (atomically).

        Parameters
        ----------
        hit : ssw.daq.backend.Hit
            The hit (force in N); flagged clipped when overloaded or at the full-scale force.
        """
        force = np.asarray(hit.force, dtype=np.float64)
        attrs = {
            "units": FORCE_UNITS, "trigger_index": int(hit.trigger_index),
            "t0": -hit.trigger_index / self.settings.sample_rate,
            "timestamp_utc": hit.timestamp_utc, "overloaded": bool(hit.overloaded),
            "clipped": bool(hit.overloaded) or is_clipped(force,
                                                           self.settings.full_scale_force),
            "extra_json": to_json(hit.extra, sort_keys=True),
        }
        self._hits.append((force, attrs))
        self.n += 1
        self._attrs["n_hits"] = self.n
        self._write()

    def mark_complete(self) -> None:
        """Mark the session finished (all requested hits recorded)."""
        self._attrs["complete"] = True
        self._attrs["finished_utc"] = datetime.now(UTC).isoformat(timespec="seconds")
        if self.n:
            self._write()

    def _write(self) -> None:
        """The whole session so far to ``path``: a temporary file, fsync'd, renamed."""
        import h5py

        from ssw.h5io import atomic_path

        with atomic_path(self.path, durable=True) as tmp:
            with h5py.File(tmp, "w") as f:
                for k, v in self._attrs.items():
                    f.attrs[k] = v
                g = f.create_group("hits")
                for i, (force, attrs) in enumerate(self._hits):
                    ds = g.create_dataset(f"hit_{i:04d}", data=force)
                    for k, v in attrs.items():
                        ds.attrs[k] = v

    def close(self) -> None:
        """Nothing to release: the file on disk is always whole."""

    def __enter__(self) -> RecordingWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


@dataclass(frozen=True)
class RecordedHit:
    """One hit read back: force (N), its trigger index, flags and metadata.

    ``index`` counts the file's hits from 0; ``label`` is the hit's name as the file gives
    it (a CSV column's header, a TDMS channel's name, an HDF5 dataset's name), which every
    message about the hit uses (:attr:`name`: the label, else ``hit k`` counted from 1).

    Parameters
    ----------
    index : int
        The hit's index in the file, from 0.
    force : numpy.ndarray
        The hit's force, N.
    trigger_index : int
        The index of the trigger sample (the pretrigger sample count).
    clipped : bool
        Whether the hit was flagged clipped when recorded.
    timestamp_utc : str
        ISO-8601 time the hit was recorded (empty: unknown).
    extra : dict
        The hit's metadata (SI units).
    label : str
        The hit's name as the file gives it (empty: ``hit k``).
    """

    index: int
    force: np.ndarray
    trigger_index: int
    clipped: bool = False
    timestamp_utc: str = ""
    extra: dict[str, Any] = field(default_factory=dict)
    label: str = ""

    @property
    def name(self) -> str:
        """The hit's name in messages: its label, else ``hit k`` (k from 1)."""
        return self.label or f"hit {self.index + 1}"


@dataclass(frozen=True)
class Recording:
    """A session: metadata (SI units), sample rate (S/s) and its hits.

    Parameters
    ----------
    path : str
        The file read.
    meta : dict
        The session's metadata (SI units).
    sample_rate : float
        The sample rate, S/s.
    hits : tuple of RecordedHit
        The hits kept.
    dropped : tuple of str
        Why each dropped hit was dropped.
    """

    path: str
    meta: dict[str, Any]
    sample_rate: float
    hits: tuple[RecordedHit, ...]
    dropped: tuple[str, ...] = ()

    @property
    def sample_id(self) -> str:
        """The sample's id (``meta["sample_id"]``; empty when unset)."""
        return str(self.meta.get("sample_id", ""))


def _attr(x: Any) -> Any:
    if isinstance(x, bytes):
        return x.decode()
    if isinstance(x, np.generic):
        return x.item()
    return x


def check_hits(
    path: str, hits: list[RecordedHit], *, record_samples: int | None, full_scale: float | None,
    clipped: str,
) -> tuple[list[RecordedHit], list[str]]:
    """Apply the readers' checks; return the kept hits and the reasons hits were dropped.

    A hit with non-finite samples (NaN or inf: a gap or an overflow in the record) is
    dropped with its reason, whatever ``clipped`` says, and the other hits kept, as a dead
    hit is rejected by the TOF picking (:func:`ssw.signal.tof.session_tof`); every message
    names a hit as the file labels it (:attr:`RecordedHit.name`).

    Parameters
    ----------
    path : str
        The file, named in errors.
    hits : list of RecordedHit
        The hits read (force in N).
    record_samples : int or None
        The length every hit must have, samples (None: any length).
    full_scale : float or None
        The largest unclipped force, N (None: only the hits' stored ``clipped`` flags).
    clipped : str
        What to do with clipped hits: ``raise``, ``drop`` or ``keep``.

    Returns
    -------
    kept : list of RecordedHit
        The hits kept.
    dropped : list of str
        One reason per hit dropped.

    Raises
    ------
    ssw.errors.ConfigError
        When ``clipped`` is not a policy.
    ssw.errors.RecordingError
        When there are no hits, a hit is truncated or shorter than 8 samples, a clipped hit
        meets ``clipped="raise"``, or every hit is dropped.
    """
    if clipped not in CLIP_POLICIES:
        raise ConfigError("clipped", clipped, f"one of {CLIP_POLICIES}")
    if not hits:
        raise RecordingError(f"{path}: empty recording: no hits stored")
    kept: list[RecordedHit] = []
    dropped: list[str] = []
    for h in hits:
        n = h.force.size
        if record_samples is not None and n != record_samples:
            raise RecordingError(
                f"{path}: {h.name} is truncated: {n} samples, record_samples = "
                f"{record_samples}"
            )
        if n < 8:
            raise RecordingError(f"{path}: {h.name} has {n} samples; at least 8 needed")
        bad = int(np.count_nonzero(~np.isfinite(h.force)))
        if bad:
            first = int(np.flatnonzero(~np.isfinite(h.force))[0])
            dropped.append(f"{h.name}: {bad} of {n} samples are not finite (NaN or inf, "
                           f"the first at sample {first}): a gap in the record; the hit is "
                           "rejected, the others used")
            continue
        clip = h.clipped or (full_scale is not None and is_clipped(h.force, full_scale))
        if clip:
            msg = (f"{h.name} is clipped (overrange at the NI 9234's +-5 V, "
                   f"|F| >= {CLIP_FRACTION} x {full_scale} N)")
            if clipped == "raise":
                raise RecordingError(f"{path}: {msg}; re-record it or read with clipped='drop'")
            if clipped == "drop":
                dropped.append(msg)
                continue
        kept.append(h)
    if not kept:
        raise RecordingError(f"{path}: every hit was dropped: {'; '.join(dropped)}")
    return kept, dropped


def read_recording(path: str | Path, *, clipped: str = "raise",
                   full_scale: float | None = None) -> Recording:
    """Read a session file written by :class:`RecordingWriter`.

    Parameters
    ----------
    path : str or pathlib.Path
        The HDF5 file.
    clipped : str
        What to do with clipped hits: ``raise`` (:class:`~ssw.errors.RecordingError`),
        ``drop`` (skip them, listed in ``Recording.dropped``) or ``keep``.
    full_scale : float or None
        The device's largest unclipped force, N, checked as well as the session's own
        stored one (the smaller applies).

    Returns
    -------
    Recording
        The session's hits (force in N) and metadata.

    Raises
    ------
    RecordingError
        The file is unreadable (truncated HDF5), not a recording, in other units than N,
        holds no hits, a hit is shorter than ``record_samples``, a hit is clipped (with
        ``clipped="raise"``), or no hit is left (a hit with non-finite samples is dropped,
        named by its dataset, ``hit_0002``).
    """
    import h5py

    p = str(path)
    if not Path(p).is_file():
        raise RecordingError(f"{p}: no such recording file")
    try:
        f = h5py.File(p, "r")
    except OSError as exc:
        raise RecordingError(
            f"{p}: not a readable HDF5 file (truncated or corrupt): {exc}"
        ) from exc
    with f:
        meta = {k: _attr(v) for k, v in f.attrs.items()}
        if meta.get("ssw_kind") != KIND:
            raise RecordingError(f"{p}: ssw_kind = {meta.get('ssw_kind')!r}, expected {KIND!r}")
        units = meta.get("units")
        if units != FORCE_UNITS:
            raise RecordingError(
                f"{p}: units = {units!r}; recordings must hold force in {FORCE_UNITS!r} "
                "(convert volts with the sensor sensitivity before storing)"
            )
        rate = meta.get("sample_rate")
        if not isinstance(rate, int | float) or rate <= 0:
            raise RecordingError(f"{p}: sample_rate = {rate!r}; a positive rate in S/s needed")
        group = f.get("hits")
        names = sorted(group.keys()) if group is not None else []
        hits = []
        for i, name in enumerate(names):
            ds = group[name]
            u = _attr(ds.attrs.get("units"))
            if u != FORCE_UNITS:
                raise RecordingError(f"{p}: {name} has units {u!r}, expected {FORCE_UNITS!r}")
            hits.append(RecordedHit(
                index=i,
                force=np.asarray(ds[()], dtype=np.float64),
                trigger_index=int(ds.attrs.get("trigger_index", 0)),
                clipped=bool(ds.attrs.get("clipped", False)),
                timestamp_utc=str(_attr(ds.attrs.get("timestamp_utc", ""))),
                extra=json.loads(_attr(ds.attrs.get("extra_json", "{}"))),
                label=name,
            ))
    scales = [x for x in (meta.get("full_scale_force"), full_scale) if x is not None]
    kept, dropped = check_hits(
        p, hits, record_samples=meta.get("record_samples"),
        full_scale=min(scales) if scales else None, clipped=clipped,
    )
    return Recording(p, meta, float(rate), tuple(kept), tuple(dropped))
