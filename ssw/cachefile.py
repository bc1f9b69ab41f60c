"""Files of ssw's disk cache (:func:`ssw.h5io.cache_root`) that check what they read.

A cache file is a numpy ``.npz`` archive of named arrays plus one record, member
:data:`RECORD`: JSON text of the file's kind, its format version, and the shape and dtype
of every array it holds. A reader states what it needs (:class:`CacheFormat`: the kind, the
version, each array's shape in named dimensions, its dtype kind) and, where it knows them,
the sizes of those dimensions (the layout of a geometry fixes the size of its operators).
:func:`read_arrays` gives the arrays only when every check passes:

* the file reads back whole (every member: the zip CRCs, the ``.npy`` headers);
* it has a record, of the kind and format version asked for (a file of an older format,
  written before the record existed, has none);
* every array the record promises is there, with the promised shape and dtype (a file
  altered after it was written);
* every array the reader needs is there, with the shape the reader's dimensions allow
  (one size per named dimension across the file, and the sizes the reader fixed).

Otherwise the file is removed, a :class:`CacheWarning` names the file and the reason, and
None is returned: the caller rebuilds and writes a new file (:func:`write_arrays`). A cache
never crashes on a bad file and never uses one silently.
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

#: The member of a cache file that holds its record (kind, format version, shapes, dtypes).
RECORD = "__ssw_cache__"


class CacheWarning(UserWarning):
    """A cache file could not be used as it is (unreadable, of another format, an array
    missing or of the wrong shape): it is removed and its content rebuilt."""


@dataclass(frozen=True)
class CacheFormat:
    """What a reader needs of a cache file.

    Parameters
    ----------
    kind : str
        What the file holds (e.g. ``contact.body``); a file of another kind is rebuilt.
    version : int
        The format version this code writes and reads; a file of another is rebuilt.
    arrays : Mapping[str, tuple[str | int, ...]]
        Array name -> its shape: one entry per axis, a fixed size (int) or the name of a
        dimension (str), which has one size across the file; ``()`` for a scalar. A
        dimension named like a scalar integer array of the file has that array's value as
        its size (a count the file records, e.g. a mesh's nodes).
    kinds : Mapping[str, str]
        Array name -> the numpy dtype kinds allowed (``"f"`` float, ``"iu"`` integer,
        ``"b"`` bool, ``"U"`` text).
    optional : frozenset[str]
        Arrays that may be absent (checked when present).
    what : str
        What a file holds, in words (for the warning: ``operator``, ``mesh``).
    """

    kind: str
    version: int
    arrays: Mapping[str, tuple[str | int, ...]]
    kinds: Mapping[str, str]
    optional: frozenset[str] = field(default_factory=frozenset)
    what: str = "file"

    def problem(self, arrays: Mapping[str, np.ndarray],
                dims: Mapping[str, int] | None = None) -> str | None:
        """Why ``arrays`` do not fit this format (None when they do).

        Parameters
        ----------
        arrays : Mapping[str, numpy.ndarray]
            The arrays, by name.
        dims : Mapping[str, int] or None
            Sizes of named dimensions the caller knows.

        Returns
        -------
        str or None
            The first misfit found: a missing array, a wrong dtype, a wrong number of axes,
            a size other than the fixed one, or two sizes for one named dimension.
        """
        sizes = dict(dims or {})
        named = {d for shape in self.arrays.values() for d in shape if isinstance(d, str)}
        for name in sorted(named & set(arrays)):  # counts the file records
            a = arrays[name]
            if a.ndim == 0 and a.dtype.kind in "iu" and sizes.setdefault(name, int(a)) != a:
                return f"array {name!r} is {int(a)}, the caller expects {sizes[name]}"
        for name, shape in self.arrays.items():
            if name not in arrays:
                if name in self.optional:
                    continue
                return f"array {name!r} is missing"
            a = arrays[name]
            if a.dtype.kind not in self.kinds[name]:
                return f"array {name!r} has dtype {a.dtype}, not of kind {self.kinds[name]!r}"
            if a.ndim != len(shape):
                return f"array {name!r} has shape {a.shape}, expected {len(shape)} axes"
            for axis, (got, want) in enumerate(zip(a.shape, shape, strict=True)):
                if isinstance(want, int):
                    if got != want:
                        return f"array {name!r} has shape {a.shape}: axis {axis} is not {want}"
                elif sizes.setdefault(want, got) != got:
                    return (f"array {name!r} has shape {a.shape}: axis {axis} ({want}) is "
                            f"{got}, elsewhere {sizes[want]}")
        return None


def _record_of(fmt: CacheFormat, arrays: Mapping[str, np.ndarray]) -> str:
    """The record of a file of ``fmt`` holding ``arrays`` (JSON text)."""
    return json.dumps({"kind": fmt.kind, "version": fmt.version,
                       "arrays": {k: [list(a.shape), a.dtype.str] for k, a in arrays.items()}},
                      sort_keys=True)


def write_arrays(path: Path | None, fmt: CacheFormat, arrays: Mapping[str, Any]) -> None:
    """Write a cache file of format ``fmt`` atomically and durably, with its record.

    A temporary file in the same folder is fsync'd and renamed into place, then the folder
    is fsync'd (:func:`ssw.h5io.atomic_path`), so that concurrent writers on a shared file
    system never expose a partial file; a failure to write (a full disk, a read-only
    folder) only costs a rebuild later and is not raised.

    Parameters
    ----------
    path : pathlib.Path or None
        The file (None: no disk cache, nothing written).
    fmt : CacheFormat
        The file's format; the arrays must fit it.
    arrays : Mapping[str, array_like]
        The arrays, by name.

    Raises
    ------
    ValueError
        The arrays do not fit ``fmt`` (a defect of the caller: nothing is written).
    """
    if path is None:
        return
    data = {k: np.asarray(v) for k, v in arrays.items()}
    problem = fmt.problem(data)
    if problem is not None:
        raise ValueError(f"a {fmt.kind} cache file cannot hold these arrays: {problem}")
    from ssw.h5io import atomic_path

    data[RECORD] = np.asarray(_record_of(fmt, data))
    try:
        with atomic_path(path, durable=True) as tmp, open(tmp, "wb") as fh:
            np.savez(fh, **data)
    except OSError:
        return


def _misfit(fmt: CacheFormat, data: dict[str, np.ndarray],
            dims: Mapping[str, int] | None) -> str | None:
    """Why the arrays read from a cache file cannot be used (None when they can)."""
    raw = data.pop(RECORD, None)
    if raw is None:
        return "it has no format record (a file of an older format)"
    try:
        record = json.loads(str(raw))
        kind, version, promised = record["kind"], record["version"], record["arrays"]
    except (ValueError, KeyError, TypeError) as exc:
        return f"its format record cannot be read ({exc})"
    if kind != fmt.kind or version != fmt.version:
        return (f"it is a {kind!r} file of format version {version}; this ssw reads "
                f"{fmt.kind!r} files of format version {fmt.version}")
    for name, (shape, dtype) in promised.items():
        if name not in data:
            return f"array {name!r} it promises is missing"
        a = data[name]
        if list(a.shape) != shape or a.dtype.str != dtype:
            return (f"array {name!r} has shape {a.shape} and dtype {a.dtype.str}; the file "
                    f"promises {tuple(shape)} and {dtype}")
    extra = sorted(set(data) - set(promised))
    if extra:
        return f"it holds arrays its record does not list: {extra}"
    return fmt.problem(data, dims)


def read_arrays(path: Path | None, fmt: CacheFormat,
                dims: Mapping[str, int] | None = None) -> dict[str, np.ndarray] | None:
    """The arrays of a cache file, when it is there and fits ``fmt``; else None.

    A file that is there but does not fit (unreadable, no record or another format version,
    an array missing or of another shape than promised or needed) is removed with a
    :class:`CacheWarning` naming it and the reason, and None returned: the caller rebuilds.

    Parameters
    ----------
    path : pathlib.Path or None
        The file (None: no disk cache).
    fmt : CacheFormat
        What the caller needs.
    dims : Mapping[str, int] or None
        Sizes of named dimensions of ``fmt`` the caller knows (checked too).

    Returns
    -------
    dict[str, numpy.ndarray] or None
        The arrays by name (the record left out), or None.
    """
    if path is None or not path.is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as f:
            data = {k: f[k] for k in f.files}  # every member read: zip CRCs checked
    except Exception as exc:  # a damaged file fails in many ways (zip, npy header tokens,
        # sizes); whatever the failure, the file is not used
        discard(path, f"the unreadable cached {fmt.what} {path} ({exc})")
        return None
    problem = _misfit(fmt, data, dims)
    if problem is not None:
        discard(path, f"the cached {fmt.what} {path}: {problem}")
        return None
    return data


def discard(path: Path, what: str) -> None:
    """Remove a cache file that cannot be used, with a :class:`CacheWarning`
    ``rebuilding {what}`` (another process may have replaced or removed it already).

    Parameters
    ----------
    path : pathlib.Path
        The file.
    what : str
        The file and why it cannot be used, in words.
    """
    warnings.warn(f"rebuilding {what}", CacheWarning, stacklevel=3)
    try:
        path.unlink()
    except OSError:
        pass
