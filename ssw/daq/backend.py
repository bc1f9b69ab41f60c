"""Acquisition backends behind one interface, and the session loop that records hits.

A backend yields one finite, reference-triggered record per hit (:class:`Hit`). Two are
registered: ``nidaqmx`` (real hardware, :mod:`ssw.daq.nidaq`) and ``simulated``
(:mod:`ssw.daq.simulated`). :func:`run_session` drives any backend and appends every hit
to a :class:`ssw.daq.recording.RecordingWriter`, which flushes after each one, so an
interruption (exception, Ctrl-C, power loss after the flush) keeps every completed hit.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from ssw.daq.settings import DaqSettings
from ssw.errors import ConfigError


@dataclass(frozen=True)
class Hit:
    """One finite record around one hit.

    Parameters
    ----------
    force : numpy.ndarray
        (record_samples,) sensor force, N, as the module delivers it (scaled).
    trigger_index : int
        Index of the first sample at or after the reference trigger (equals the
        pretrigger sample count).
    timestamp_utc : str
        ISO-8601 time the record was read.
    overloaded : bool
        The hardware reported an overload/overrange on the channel during the hit.
    extra : dict
        Backend-specific metadata (e.g. the simulated wave's true TOF), SI units.
    """

    force: np.ndarray
    trigger_index: int
    timestamp_utc: str = field(default_factory=lambda: datetime.now(UTC).isoformat())
    overloaded: bool = False
    extra: dict[str, Any] = field(default_factory=dict)


class Backend(Protocol):
    """What an acquisition backend provides.

    Other Parameters
    ----------------
    *args
        None: a protocol is not instantiated.
    **kwargs
        None: a protocol is not instantiated.
    """

    name: str

    def describe(self) -> dict[str, Any]:
        """Metadata about the hardware (or simulation) that records go with."""

    def hits(self, settings: DaqSettings, n_hits: int) -> Iterator[Hit]:
        """Yield ``n_hits`` records, one per hit, in order.

        Parameters
        ----------
        settings : ssw.daq.settings.DaqSettings
            The acquisition settings.
        n_hits : int
            How many hits to record.

        Yields
        ------
        Hit
            One record per hit (force in N).
        """


BACKENDS: dict[str, Callable[..., Backend]] = {}


def register_backend(name: str, factory: Callable[..., Backend]) -> None:
    """Make ``factory(**options)`` available as backend ``name``.

    Parameters
    ----------
    name : str
        The backend's name.
    factory : callable
        ``factory(**options)`` returns the backend.
    """
    BACKENDS[name] = factory


def get_backend(name: str, **options: Any) -> Backend:
    """An instance of backend ``name`` (``nidaqmx`` or ``simulated``).

    Parameters
    ----------
    name : str
        The backend's name.
    **options
        Passed to its factory.

    Returns
    -------
    Backend
        The backend.

    Raises
    ------
    ssw.errors.ConfigError
        When no backend has that name.
    """
    _load_builtin()
    if name not in BACKENDS:
        raise ConfigError("backend", name, f"one of {sorted(BACKENDS)}")
    return BACKENDS[name](**options)


def _load_builtin() -> None:
    # Importing the modules registers them; neither imports nidaqmx at import time.
    import ssw.daq.nidaq
    import ssw.daq.simulated  # noqa: F401


def run_session(
    backend: Backend,
    settings: DaqSettings,
    path: str | Path,
    *,
    sample_id: str,
    plate: str = "",
    operator: str = "",
    n_hits: int | None = None,
    synthetic: bool = False,
    notes: str = "",
    overwrite: bool = False,
    on_hit: Callable[[int, Hit], None] | None = None,
) -> Path:
    """Record ``n_hits`` hits (default ``settings.hits``) of one sample into ``path``.

    Nothing is lost (:mod:`ssw.daq.recording`): the session is on disk, whole, after every
    hit; if the backend or ``on_hit`` raises (or the process is killed), the file keeps
    every hit completed so far (``complete = False``) and the error propagates; a session
    that fails before its first hit writes nothing. An existing file at ``path`` is never
    touched unless ``overwrite``: the session goes to the next free name
    (:func:`ssw.daq.recording.free_path`); with ``overwrite`` it is replaced when the first
    new hit is on disk, not before. Returns the file written.

    Parameters
    ----------
    backend : Backend
        The acquisition backend.
    settings : ssw.daq.settings.DaqSettings
        The acquisition settings (stored with the session).
    path : str or pathlib.Path
        The session's HDF5 file.
    sample_id : str
        The sample's id.
    plate : str
        The plate on the sample (free text).
    operator : str
        Who recorded it.
    n_hits : int or None
        How many hits (None: ``settings.hits``).
    synthetic : bool
        Whether the data are simulated.
    notes : str
        Free text stored with the session.
    overwrite : bool
        Replace an existing file at ``path``.
    on_hit : callable or None
        ``on_hit(i, hit)`` after hit ``i`` (from 0) is on disk.

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    ssw.errors.ConfigError
        When ``n_hits`` < 1.
    """
    from ssw.daq.recording import RecordingWriter, free_path

    n = settings.hits if n_hits is None else int(n_hits)
    if n < 1:
        raise ConfigError("hits", n, "at least 1")
    meta = {
        "sample_id": sample_id,
        "plate": plate,
        "operator": operator,
        "synthetic": bool(synthetic),
        "notes": notes,
        "backend": backend.name,
    }
    target = Path(path) if overwrite else free_path(path)
    writer = RecordingWriter(target, settings, meta, overwrite=overwrite)
    for i, hit in enumerate(backend.hits(settings, n)):
        if i == 0:  # a real backend knows its hardware once the task is open
            writer.set_meta({f"hw_{k}": v for k, v in backend.describe().items()})
        writer.append(hit)
        if on_hit is not None:
            on_hit(i, hit)
    writer.mark_complete()
    return target
