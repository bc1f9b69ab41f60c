"""Recordings made elsewhere (LabVIEW/NI TDMS, CSV exports, MATLAB) as
:class:`~ssw.daq.recording.Recording`.

A registry by file suffix (:data:`FORMATS`), as meshio's: each format module of
:mod:`ssw.daq.formats` reads a file into a :class:`ssw.daq.recording.Recording` (force in
N, one record per hit) and writes one back:

* ``.csv`` (:mod:`ssw.daq.formats.csvfile`): a time column and one column per hit, units
  in the header (``time_s,force_N``, ``time [s],force [N]``, ``voltage_V``);
* ``.tdms`` (:mod:`ssw.daq.formats.tdmsfile`, npTDMS): NI waveform channels
  (``wf_increment``, ``wf_start_offset``, ``unit_string``), one channel per hit or one long
  channel split with the acquisition's trigger rule;
* ``.mat`` (:mod:`ssw.daq.formats.matfile`): ``force``/``voltage`` with ``fs`` or ``t``;
* ``.h5``/``.hdf5``: ssw's own session files (:func:`ssw.daq.recording.read_recording`).

Units are converted to SI (:mod:`ssw.daq.formats.common`: N, kN, lbf; V, mV with the
sensor's sensitivity; s, ms, us). Every error is a :class:`ssw.errors.RecordingError`
naming the file, the column (or channel, variable) and what was expected.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ssw.daq.formats import csvfile, matfile, tdmsfile
from ssw.daq.recording import CLIP_POLICIES, Recording
from ssw.errors import ConfigError, RecordingError


def _read_h5(path: str | Path, clipped: str = "raise", full_scale: float | None = None,
             **_: Any) -> Recording:
    from ssw.daq.recording import read_recording

    return read_recording(path, clipped=clipped, full_scale=full_scale)


@dataclass(frozen=True)
class Format:
    """A recording format: its name, reader and (optional) writer.

    Parameters
    ----------
    name : str
        The format's name (``CSV``, ``TDMS``, ...).
    read : callable
        ``read(path, **options)`` returns a :class:`~ssw.daq.recording.Recording`.
    write : callable or None
        ``write(path, recording, **options)`` returns the path written (None: not writable).
    """

    name: str
    read: Callable[..., Recording]
    write: Callable[..., Path] | None = None


#: Registry: file suffix -> :class:`Format` (its reader and writer).
FORMATS: dict[str, Format] = {}


def register_format(suffixes: tuple[str, ...], fmt: Format) -> None:
    """Make ``fmt`` the format of files ending in each of ``suffixes`` (with the dot).

    Parameters
    ----------
    suffixes : tuple of str
        The file suffixes, with the dot (matched case-insensitively).
    fmt : Format
        The reader and writer.
    """
    for s in suffixes:
        FORMATS[s.lower()] = fmt


register_format((".csv",), Format("csv", csvfile.read, csvfile.write))
register_format((".tdms",), Format("tdms", tdmsfile.read, tdmsfile.write))
register_format((".mat",), Format("mat", matfile.read, matfile.write))
register_format((".h5", ".hdf5"), Format("ssw session (HDF5)", _read_h5))

#: Back-compatible name: suffix -> reader.
IMPORTERS: dict[str, Callable[..., Recording]] = {k: f.read for k, f in FORMATS.items()}


def _format(path: str | Path) -> Format:
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise RecordingError(f"{path}: unknown recording format {suffix!r}; one of "
                             f"{sorted(FORMATS)}")
    return FORMATS[suffix]


def read_any(path: str | Path, *, clipped: str = "raise", **options: Any) -> Recording:
    """Read a recording by its suffix (module doc).

    Options (all formats accept them; each uses those that apply): ``units`` (unit of data
    without one, e.g. ``N``, ``V``, ``lbf``), ``sensitivity`` (V/N), ``sample_rate``
    (S/s, when the file has no time axis), ``full_scale`` (N: the recording device's
    largest unclipped force, ``ssw.device.Device.full_scale_force``; every hit is checked
    against it, whatever the format, an ssw session's own stored range included: the
    smaller applies), and for TDMS ``group``, ``split``, ``trigger``. ``clipped``:
    ``raise``, ``drop`` or ``keep`` clipped hits.

    Parameters
    ----------
    path : str or pathlib.Path
        The recording file.
    clipped : str
        ``raise``, ``drop`` or ``keep``.
    **options
        The options above.

    Returns
    -------
    ssw.daq.recording.Recording
        The hits, force in N.

    Raises
    ------
    ssw.errors.ConfigError
        When ``clipped`` is not a policy.
    ssw.errors.RecordingError
        When the file is missing, its suffix unknown or its content unreadable.
    """
    if clipped not in CLIP_POLICIES:
        raise ConfigError("clipped", clipped, f"one of {CLIP_POLICIES}")
    if not Path(path).is_file():
        raise RecordingError(f"{path}: no such recording file")
    return _format(path).read(path, clipped=clipped, **options)


def write_any(path: str | Path, recording: Recording, **options: Any) -> Path:
    """Write ``recording`` in the format of ``path``'s suffix (CSV, TDMS, MAT).

    Parameters
    ----------
    path : str or pathlib.Path
        The file to write; its suffix picks the format.
    recording : ssw.daq.recording.Recording
        The recording.
    **options
        Passed to the format's writer.

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    ssw.errors.RecordingError
        When the format cannot be written, or the suffix is unknown.
    """
    fmt = _format(path)
    if fmt.write is None:
        raise RecordingError(f"{path}: ssw does not write {fmt.name} files this way "
                             f"(writable: {sorted(k for k, f in FORMATS.items() if f.write)})")
    return fmt.write(path, recording, **options)
