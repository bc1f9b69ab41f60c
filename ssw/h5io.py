"""HDF5 conventions of ssw: one file per job, SI units in attributes, atomic writes.

Every file written through :func:`atomic_h5` carries the root attributes

* ``ssw_kind``: what the file holds (``"contact_curve"``, ``"chain_run"``, ...);
* ``ssw_version``: the package version that wrote it;
* ``created_utc``: ISO-8601 time stamp;
* ``inputs_json``: every input that produced it, as JSON (SI units);
* its provenance (:func:`ssw.provenance.record`): ``ssw_commit`` (empty when unknown),
  ``ssw_dirty``, ``ssw_source_sha256``, ``inputs_sha256`` and ``command``.

CSV tables (:func:`write_rows_csv`) start with one comment line of the same provenance
(``# ssw <version> commit ... command: ...``); :func:`read_rows_csv` skips it.

Every dataset written through :func:`write_dataset` has a ``units`` attribute (``"1"`` for
dimensionless) and, optionally, a ``description``. A file is written under a temporary name
in the destination folder and renamed into place only when complete, so an interrupted run
never leaves a file that looks finished.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from collections.abc import Iterator, Mapping
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from ssw import __version__
from ssw.errors import SswError


def _json_default(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serializable: {type(obj).__name__}")


def to_json(obj: Any, **kw: Any) -> str:
    """JSON text of ``obj``; numpy arrays and scalars and paths are converted.

    Parameters
    ----------
    obj : object
        The value (dicts, lists, numbers, text, numpy arrays and scalars, paths).
    **kw
        Passed to :func:`json.dumps` (e.g. ``sort_keys``, ``indent``).

    Returns
    -------
    str
        The JSON text.

    Raises
    ------
    TypeError
        When a value is of none of these types.
    """
    return json.dumps(obj, default=_json_default, **kw)


def _umask() -> int:
    """The process's file mode creation mask (read by setting and restoring it)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str], *, durable: bool = False) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it to ``path`` on success.

    On an exception the temporary file is removed and ``path`` is left untouched. With
    ``durable`` the temporary file is fsync'd before the rename and the folder after it, so
    the new content survives a crash or a power loss once this returns.

    Parameters
    ----------
    path : str or os.PathLike
        The destination file (its folder is created).
    durable : bool
        Whether to fsync the file and its folder.

    Yields
    ------
    pathlib.Path
        The temporary file to write (mode as the umask allows, not 0600).
    """
    dest = Path(path)
    dest.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{dest.name}.", suffix=".part", dir=dest.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    tmp_path.chmod(0o666 & ~_umask())  # mkstemp makes 0600; results are files like any other
    try:
        yield tmp_path
        if durable:
            fsync_path(tmp_path)
        os.replace(tmp_path, dest)
        if durable:
            fsync_path(dest.parent)
    finally:
        if tmp_path.exists():
            tmp_path.unlink()


def fsync_path(path: str | os.PathLike[str]) -> None:
    """fsync a file or a folder (a folder: so that a rename in it is on disk); a no-op
    where the platform cannot.

    Parameters
    ----------
    path : str or os.PathLike
        The file or folder.
    """
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def cache_root() -> Path | None:
    """ssw's disk cache folder, for files it can always rebuild (condensed contact operators,
    validated configs): ``$SSW_CACHE_DIR`` (default ``~/.cache/ssw``).

    Returns
    -------
    pathlib.Path or None
        The folder (it may not exist yet); None when ``SSW_CACHE_DIR`` is ``none``, ``off``
        or empty (no disk cache).
    """
    root = os.environ.get("SSW_CACHE_DIR")
    if root is not None and root.strip().lower() in ("none", "off", ""):
        return None
    return Path(root) if root else Path.home() / ".cache" / "ssw"


def atomic_write_text(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` to ``path`` atomically.

    Parameters
    ----------
    path : str or os.PathLike
        The destination file.
    text : str
        The content.
    """
    with atomic_path(path) as tmp:
        tmp.write_text(text)


def read_datasets(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Every dataset of an HDF5 file, by its path in the file (attributes not included).

    Parameters
    ----------
    path : str or os.PathLike
        The HDF5 file.

    Returns
    -------
    dict
        Dataset path (e.g. ``"group/name"``) -> its value (array or scalar).
    """
    import h5py

    out: dict[str, Any] = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: out.__setitem__(name, obj[()])
                     if isinstance(obj, h5py.Dataset) else None)
    return out


def write_rows_csv(rows: list[dict[str, Any]], path: str | os.PathLike[str],
                   inputs: Any = None) -> None:
    """Rows (dicts) to a CSV file, atomically; columns in order of first appearance. The
    first line is the provenance comment (:func:`ssw.provenance.csv_comment`) of a table
    made from ``inputs`` (default: the rows themselves).

    Parameters
    ----------
    rows : list of dict
        The table's rows; a key missing from a row leaves its cell empty.
    path : str or os.PathLike
        The CSV file.
    inputs : object, optional
        What the table was made from (JSON-able), for its provenance.
    """
    import csv
    import io

    from ssw.provenance import csv_comment, record

    buf = io.StringIO()
    buf.write(csv_comment(record(rows if inputs is None else inputs)))
    cols = list(dict.fromkeys(k for r in rows for k in r))
    w = csv.DictWriter(buf, fieldnames=cols, lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    atomic_write_text(path, buf.getvalue())


def write_json(path: str | os.PathLike[str], result: Mapping[str, Any], inputs: Any) -> None:
    """A JSON result to ``path`` atomically, with its ``provenance``
    (:func:`ssw.provenance.record` of ``inputs``).

    Parameters
    ----------
    path : str or os.PathLike
        The JSON file.
    result : Mapping
        The result (JSON-able via :func:`to_json`).
    inputs : object
        What the result was made from, for its provenance.
    """
    from ssw.provenance import record

    atomic_write_text(path, to_json({**result, "provenance": record(inputs)}) + "\n")


def write_csv_text(path: str | os.PathLike[str], text: str, inputs: Any) -> None:
    """A CSV table's ``text`` to ``path`` atomically, after its provenance comment line
    (:func:`ssw.provenance.csv_comment`) for a table made from ``inputs``.

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file.
    text : str
        The table's text (header and rows).
    inputs : object
        What the table was made from, for its provenance.
    """
    from ssw.provenance import csv_comment, record

    atomic_write_text(path, csv_comment(record(inputs)) + text)


def read_rows_csv(path: str | os.PathLike[str]) -> list[dict[str, str]]:
    """Rows of a CSV table (:func:`write_rows_csv`) as dicts of text; comment lines
    (``#`` first) skipped.

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file.

    Returns
    -------
    list of dict of str to str
        One dict per row, column name -> cell text.
    """
    import csv

    with open(path, newline="") as fh:
        return list(csv.DictReader(line for line in fh if not line.startswith("#")))


def csv_provenance(path: str | os.PathLike[str]) -> dict[str, Any] | None:
    """The provenance of a CSV table written by ssw (its first line), or None.

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file.

    Returns
    -------
    dict or None
        The provenance (:func:`ssw.provenance.parse_csv_comment`); None when the first line is
        not ssw's provenance comment.
    """
    from ssw.provenance import parse_csv_comment

    with open(path) as fh:
        return parse_csv_comment(fh.readline())


def provenance_of(f: Any) -> dict[str, Any]:
    """The provenance attributes of an open ssw HDF5 file (missing ones are None).

    Parameters
    ----------
    f : h5py.File
        The open file.

    Returns
    -------
    dict
        ``ssw_version``, ``commit``, ``dirty``, ``source_sha256``, ``inputs_sha256`` and
        ``command``.
    """
    a = f.attrs
    commit = a.get("ssw_commit")
    return {"ssw_version": a.get("ssw_version"), "commit": commit or None,
            "dirty": None if "ssw_dirty" not in a else bool(a["ssw_dirty"]),
            "source_sha256": a.get("ssw_source_sha256"),
            "inputs_sha256": a.get("inputs_sha256"), "command": a.get("command")}


def new_attrs(obj: Any, values: Mapping[str, Any]) -> None:
    """Create attributes on an HDF5 object that has none of these names yet, stored exactly
    as ``obj.attrs[name] = value`` stores them (the same HDF5 type, shape and value).

    Why not h5py's ``attrs[name] = value``: that call also checks for an existing attribute
    to delete, guesses the type of every value and converts it twice, which a new object does
    not need: 302 contact curves (39 attributes each) are written in 0.91 s of CPU instead of
    1.13 s (:func:`ssw.curve.write_curve`, best of 3). Text goes as h5py's variable-length
    UTF-8 string; any value numpy does not turn into a number or bool array (bytes, lists
    of text, objects) is left to h5py itself.

    Parameters
    ----------
    obj : h5py.File, h5py.Group or h5py.Dataset
        The object, open for writing.
    values : Mapping
        Attribute name -> value.
    """
    import h5py
    from h5py import h5a, h5s, h5t

    text = h5py.string_dtype()
    for name, value in values.items():
        if isinstance(value, str):
            data = np.array(value, dtype=text)
        else:
            data = np.asarray(value, order="C")
            if data.dtype.kind not in "biuf":
                obj.attrs[name] = value
                continue
        attr = h5a.create(obj.id, name.encode(), h5t.py_create(data.dtype, logical=True),
                          h5s.create_simple(data.shape))
        try:
            attr.write(data, mtype=h5t.py_create(data.dtype))
        finally:
            attr.close()


@contextlib.contextmanager
def atomic_h5(
    path: str | os.PathLike[str], *, kind: str, inputs: Mapping[str, Any]
) -> Iterator[Any]:
    """Open a new HDF5 file for writing that appears at ``path`` only when complete.

    Parameters
    ----------
    path : str or os.PathLike
        Destination file.
    kind : str
        Value of the ``ssw_kind`` root attribute.
    inputs : Mapping
        Every input that produced the file (SI units); stored as ``inputs_json``.

    Yields
    ------
    h5py.File
        The temporary file, open for writing, its provenance attributes set.
    """
    import h5py

    from ssw.provenance import record

    prov = record(dict(inputs))
    with atomic_path(path) as tmp:
        with h5py.File(tmp, "w") as f:
            new_attrs(f, {
                "ssw_kind": kind, "ssw_version": __version__,
                "created_utc": datetime.now(UTC).isoformat(timespec="seconds"),
                "inputs_json": to_json(dict(inputs), sort_keys=True),
                "ssw_commit": prov["commit"] or "", "ssw_dirty": bool(prov["dirty"]),
                "ssw_source_sha256": prov["source_sha256"],
                "inputs_sha256": prov["inputs_sha256"], "command": prov["command"]})
            yield f


def write_dataset(
    group: Any, name: str, data: Any, units: str, description: str = "", **kw: Any
) -> Any:
    """Create dataset ``name`` in ``group`` with a ``units`` attribute (SI; ``"1"``: none).

    Parameters
    ----------
    group : h5py.Group or h5py.File
        The group, open for writing.
    name : str
        The dataset's name.
    data : array_like
        The values, in ``units``.
    units : str
        The SI unit of the values (``"1"``: dimensionless).
    description : str
        Stored as the ``description`` attribute when not empty.
    **kw
        Passed to :meth:`h5py.Group.create_dataset` (e.g. ``compression``).

    Returns
    -------
    h5py.Dataset
        The new dataset.
    """
    ds = group.create_dataset(name, data=np.asarray(data), **kw)
    new_attrs(ds, {"units": units, **({"description": description} if description else {})})
    return ds


def read_inputs(f: Any) -> dict[str, Any]:
    """The ``inputs_json`` root attribute of an open ssw HDF5 file, as a dict.

    Parameters
    ----------
    f : h5py.File
        The open file.

    Returns
    -------
    dict
        The inputs that produced the file.

    Raises
    ------
    ssw.errors.SswError
        When the file has no ``inputs_json`` attribute.
    """
    raw = f.attrs.get("inputs_json")
    if raw is None:
        raise SswError(f"{getattr(f, 'filename', f)} is not an ssw file (no inputs_json)")
    return json.loads(raw)


def check_kind(f: Any, kind: str) -> None:
    """Raise :class:`~ssw.errors.SswError` unless the open file's ``ssw_kind`` is ``kind``.

    Parameters
    ----------
    f : h5py.File
        The open file.
    kind : str
        The expected ``ssw_kind``.

    Raises
    ------
    ssw.errors.SswError
        When the file's ``ssw_kind`` differs.
    """
    got = f.attrs.get("ssw_kind")
    if got != kind:
        raise SswError(f"{getattr(f, 'filename', f)}: ssw_kind is {got!r}, expected {kind!r}")
