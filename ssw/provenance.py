"""Provenance: what made a result (code, inputs, command), and the checks that combine them.

Every result ssw writes records (:func:`record`):

* ``ssw_version``: the package version; ``commit``: the git commit of the source tree when
  it is a git checkout (else None), ``dirty`` whether it had uncommitted changes;
* ``source_sha256``: a hash of the package's source files that produced it
  (:func:`source_hash`: the static import closure of the modules named, so a change in a
  module the result does not depend on does not change it), each as the process loaded it
  (``ssw.LOADED``): a file edited while the process runs labels nothing it made;
* ``inputs_sha256``: :func:`digest` of every input that made it (the command's options,
  the config's slice it read, the devices, materials and files it read: each file by its
  own digest);
* ``command``: the command line.

HDF5 files carry these as root attributes (:mod:`ssw.h5io`), JSON results as a
``provenance`` object, CSV tables as a first comment line (``# ssw ...``).

Commands that combine results compare their digests (:func:`require_match`) and refuse a
mismatch with a message naming both sides.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import re
import shlex
import subprocess
import sys
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from ssw import LOADED, __version__
from ssw.errors import SswError

PACKAGE_DIR = Path(__file__).resolve().parent
#: Hex digits kept of a SHA-256 (80 bits: no accidental collision among a study's results).
DIGEST_HEX = 20


class ProvenanceError(SswError, ValueError):
    """Results that do not belong together (made from different inputs), or a result whose
    provenance is missing where it is required."""


# ----------------------------------------------------------------------------- digests
def _canonical(obj: Any) -> Any:
    """Plain JSON-able form with a fixed float text (shortest round-trip repr), sorted keys
    (done by the encoder), tuples as lists, paths as text, numpy values as Python ones."""
    if isinstance(obj, Mapping):
        return {str(k): _canonical(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_canonical(v) for v in obj]
    if isinstance(obj, Path):
        return str(obj)
    if hasattr(obj, "tolist") and not isinstance(obj, str | bytes):  # numpy arrays/scalars
        return _canonical(obj.tolist())
    if isinstance(obj, bool) or obj is None or isinstance(obj, str | int):
        return obj
    if isinstance(obj, float):
        if math.isnan(obj) or math.isinf(obj):
            return repr(obj)
        return obj
    if hasattr(obj, "__dataclass_fields__"):
        from dataclasses import asdict

        return _canonical(asdict(obj))
    raise TypeError(f"cannot digest a {type(obj).__name__}")


def canonical_json(obj: Any) -> str:
    """Canonical JSON text of ``obj`` (sorted keys, no spaces): equal values, equal text.

    Parameters
    ----------
    obj : object
        A JSON-able value (numpy arrays and scalars, paths and tuples are converted).

    Returns
    -------
    str
        The canonical JSON text.
    """
    return json.dumps(_canonical(obj), sort_keys=True, separators=(",", ":"))


def digest(obj: Any) -> str:
    """SHA-256 (first :data:`DIGEST_HEX` hex digits) of :func:`canonical_json` of ``obj``.

    Parameters
    ----------
    obj : object
        A JSON-able value.

    Returns
    -------
    str
        The hex digest.
    """
    return hashlib.sha256(canonical_json(obj).encode()).hexdigest()[:DIGEST_HEX]


def file_digest(path: str | Path) -> str:
    """SHA-256 (first :data:`DIGEST_HEX` hex digits) of a file's bytes.

    Parameters
    ----------
    path : str or pathlib.Path
        The file.

    Returns
    -------
    str
        The hex digest.
    """
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()[:DIGEST_HEX]


# ----------------------------------------------------------------------------- code
@functools.lru_cache(maxsize=2048)
def _module_path(name: str) -> Path | None:
    """The source file of an ``ssw`` module name, or None (not in the package); kept for
    the process (a closure looks the same names up thousands of times: the workflow hashes
    every step's closure when it builds its jobs)."""
    if name != "ssw" and not name.startswith("ssw."):
        return None
    rel = name.split(".")[1:]
    base = PACKAGE_DIR.joinpath(*rel)
    if base.is_dir() and (base / "__init__.py").is_file():
        return base / "__init__.py"
    f = base.with_suffix(".py")
    return f if f.is_file() else None


#: ``import a.b as c, d`` and ``from .x import (y, z)`` statements (a parenthesized name list
#: may span lines). Found by text, not by parsing: a docstring that shows an import only adds
#: a module to a closure (a conservative error), and scanning is ~20x faster than ``ast``.
_IMPORT_RE = re.compile(
    r"^[ \t]*(?:from[ \t]+(?P<base>\.*[\w.]*)[ \t]+import[ \t]+"
    r"(?P<names>\([^)]*\)|[^\n#;]+)|import[ \t]+(?P<mods>[^\n#;]+))",
    re.MULTILINE)


@functools.lru_cache(maxsize=512)
def _imports_of(path: Path) -> tuple[str, ...]:
    """The ``ssw`` modules a source file imports anywhere (top level or inside functions),
    found statically (no import is executed)."""
    pkg = _package_of(path)
    out: list[str] = []
    for m in _IMPORT_RE.finditer(path.read_text()):
        if m.group("mods"):
            out.extend(part.split()[0] for part in m.group("mods").split(",") if part.strip())
            continue
        base = m.group("base")
        level = len(base) - len(base.lstrip("."))
        base = base.lstrip(".")
        if level:
            parts = pkg.split(".")
            parts = parts[: len(parts) - level + 1]
            base = ".".join([*parts, base] if base else parts)
        out.append(base)
        names = m.group("names").strip("() \t\n")
        out.extend(f"{base}.{n.split()[0]}" for n in names.replace("\n", " ").split(",")
                   if n.strip() and n.split()[0] != "*")  # `from pkg import module`
    return tuple(m for m in dict.fromkeys(out) if m == "ssw" or m.startswith("ssw."))


def _package_of(path: Path) -> str:
    rel = path.relative_to(PACKAGE_DIR.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
        return ".".join(parts)
    return ".".join(parts[:-1])


def module_closure(modules: Iterable[str], packages: bool = True) -> list[Path]:
    """Source files of ``modules`` and of every ``ssw`` module they import, transitively;
    with ``packages``, the parent packages' ``__init__`` too (what runs when they are
    imported; without: only what the modules' code uses). Sorted.

    Parameters
    ----------
    modules : iterable of str
        Dotted module names.
    packages : bool
        Whether to include the parent packages' ``__init__`` files.

    Returns
    -------
    list of pathlib.Path
        The source files, sorted.
    """
    seen: set[Path] = set()
    todo = list(modules)
    while todo:
        name = todo.pop()
        parts = name.split(".")
        # importing a.b.c runs a and a.b first
        names = [".".join(parts[:i]) for i in range(1, len(parts) + 1)] if packages else [name]
        for n in names:
            p = _module_path(n)
            if p is not None and p not in seen:
                seen.add(p)
                todo.extend(_imports_of(p))
    return sorted(seen)


@functools.lru_cache(maxsize=1024)
def _disk_bytes(path: Path) -> bytes:
    """A source file's bytes on disk, read once per process (the steps' closures share
    most)."""
    return path.read_bytes()


def _source_bytes(path: Path) -> bytes:
    """A source file's bytes as this process loaded it (``ssw.LOADED``), or, for a module
    it has not loaded, as on disk at the first call (what it would load)."""
    loaded = LOADED.get(str(path))
    return loaded[0] if loaded is not None else _disk_bytes(path)


@functools.lru_cache(maxsize=64)
def _source_hash(modules: tuple[str, ...], packages: bool, loaded: int) -> str:
    h = hashlib.sha256()
    for p in module_closure(modules, packages):
        h.update(str(p.relative_to(PACKAGE_DIR)).encode() + b"\0")
        h.update(_source_bytes(p) + b"\0")
    return h.hexdigest()[:DIGEST_HEX]


def source_hash(modules: Iterable[str], packages: bool = True) -> str:
    """Hash of the source of ``modules`` and everything of ssw they import (statically, see
    :func:`module_closure`; ``packages``: with the parent packages' ``__init__``), each file
    as this process loaded it (``ssw.LOADED``: an edit made since does not change it), a
    module it has not loaded as on disk. Data files (schemas, materials, devices) enter
    results through their values, which are inputs, not through this hash.

    Parameters
    ----------
    modules : iterable of str
        Module names (``ssw.contact.operators``).
    packages : bool
        Whether the parent packages' ``__init__`` count (what runs when they are imported).

    Returns
    -------
    str
        :data:`DIGEST_HEX` hex digits of a SHA-256 of the files' paths and bytes.
    """
    # keyed on the number of modules loaded: one loaded since the last call hashes as loaded
    return _source_hash(tuple(sorted(set(modules))), packages, len(LOADED))


def changed_since_loaded() -> str | None:
    """The first module of ssw (its path) whose file differs on disk from what this process
    loaded (modified, replaced or removed since), or None.

    Returns
    -------
    str or None
        The module file's path.
    """
    for path, (_, stat) in sorted(LOADED.items()):
        try:
            st = Path(path).stat()
        except OSError:
            return path
        if (st.st_mtime_ns, st.st_size) != stat:
            return path
    return None


@functools.lru_cache(maxsize=1)
def git_state() -> tuple[str | None, bool | None]:
    """(commit, dirty) of the git checkout holding the package at the first call, or (None,
    None) when the package is not in one (an installed wheel) or git is unavailable.

    ``dirty``: the code that ran is not the commit's: ssw has uncommitted changes, or a
    module this process loaded changed on disk since (:func:`changed_since_loaded`). A warm
    process (``ssw.warmstart``) calls it once its imports are done; its forks inherit it.

    Returns
    -------
    commit : str or None
        The commit's hash.
    dirty : bool or None
        Whether the code that ran differs from the commit.
    """
    root = PACKAGE_DIR.parent
    if not (root / ".git").exists():
        return None, None
    try:
        commit = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"],
                                capture_output=True, text=True, timeout=10, check=True
                                ).stdout.strip()
        status = subprocess.run(["git", "-C", str(root), "status", "--porcelain",
                                 "--untracked-files=no", "--", "ssw"],
                                capture_output=True, text=True, timeout=10, check=True).stdout
    except (OSError, subprocess.SubprocessError):
        return None, None
    return commit or None, bool(status.strip()) or changed_since_loaded() is not None


def current_command() -> str:
    """The running command line, as a shell would read it (``ssw`` for the entry point).

    Returns
    -------
    str
        The command line, shell-quoted.
    """
    argv = list(sys.argv)
    if argv and (argv[0].endswith(("/ssw", "__main__.py")) or argv[0] == "-m"):
        argv[0] = "ssw"
    return shlex.join(argv)


#: What the running command is (set by the command line, :func:`set_context`): the module
#: whose import closure made its results, and the digest of the study inputs it reads when
#: a workflow rule ran it (``ssw --inputs-sha256 ...``).
_CONTEXT: dict[str, Any] = {"modules": None, "inputs_sha256": None}


def set_context(modules: Sequence[str] | None = None, inputs_sha256: str | None = None) -> None:
    """Declare the running command's modules and, for a workflow job, the digest of the
    study inputs it was scheduled with (recorded in every result it writes).

    Parameters
    ----------
    modules : sequence of str or None
        The command's modules (None: the whole package).
    inputs_sha256 : str or None
        The workflow's digest of the job's study inputs (None: not a workflow job).
    """
    _CONTEXT["modules"] = tuple(modules) if modules else None
    _CONTEXT["inputs_sha256"] = inputs_sha256


def all_modules() -> tuple[str, ...]:
    """Every module of the package (the default closure: the whole source).

    Returns
    -------
    tuple of str
        Dotted module names, sorted.
    """
    return tuple(sorted(".".join(("ssw", *p.relative_to(PACKAGE_DIR).with_suffix("").parts))
                        .removesuffix(".__init__") for p in PACKAGE_DIR.rglob("*.py")))


def record(inputs: Any, modules: Sequence[str] | None = None, command: str | None = None
           ) -> dict[str, Any]:
    """The provenance of a result made from ``inputs`` (module docstring).

    ``modules`` default to the running command's (:func:`set_context`), else the whole
    package; ``inputs_sha256`` is the workflow's digest of the job's study inputs when the
    command runs as a workflow job, else the digest of ``inputs``.

    Parameters
    ----------
    inputs : object
        What the result was made from (JSON-able).
    modules : sequence of str or None
        The modules whose source hash is recorded.
    command : str or None
        The command line (None: the running one).

    Returns
    -------
    dict
        ``ssw_version``, ``commit``, ``dirty``, ``source_sha256``, ``inputs_sha256`` and
        ``command``.
    """
    commit, dirty = git_state()
    mods = modules or _CONTEXT["modules"] or all_modules()
    return {
        "ssw_version": __version__,
        "commit": commit,
        "dirty": dirty,
        "source_sha256": source_hash(mods),
        "inputs_sha256": _CONTEXT["inputs_sha256"] or digest(inputs),
        "command": current_command() if command is None else command,
    }


def csv_comment(prov: Mapping[str, Any]) -> str:
    """The first line of a CSV table: ``# ssw <version> commit <c> source <s> inputs <i>
    command: <cmd>`` (readers skip lines starting with ``#``).

    Parameters
    ----------
    prov : Mapping
        A provenance (:func:`record`).

    Returns
    -------
    str
        The comment line, with its newline.
    """
    return (f"# ssw {prov['ssw_version']} commit {prov.get('commit') or 'none'}"
            f"{'+dirty' if prov.get('dirty') else ''} source {prov['source_sha256']} "
            f"inputs {prov['inputs_sha256']} command: {prov.get('command', '')}\n")


def parse_csv_comment(line: str) -> dict[str, Any] | None:
    """The provenance of a CSV table's first line (:func:`csv_comment`), or None.

    Parameters
    ----------
    line : str
        The table's first line.

    Returns
    -------
    dict or None
        ``ssw_version``, ``commit``, ``dirty``, ``source_sha256``, ``inputs_sha256`` and
        ``command`` (those present); None when the line is not ssw's comment.
    """
    if not line.startswith("# ssw "):
        return None
    head, _, command = line.rstrip("\n").partition(" command: ")
    words = head[2:].split()
    out: dict[str, Any] = {"ssw_version": words[1], "command": command}
    for key, name in (("commit", "commit"), ("source", "source_sha256"),
                      ("inputs", "inputs_sha256")):
        if key in words:
            out[name] = words[words.index(key) + 1]
    c = out.get("commit", "none")
    out["dirty"] = c.endswith("+dirty")
    out["commit"] = None if c.startswith("none") else c.removesuffix("+dirty")
    return out


def require_match(what: str, left: tuple[str, Any], right: tuple[str, Any]) -> None:
    """Raise :class:`ProvenanceError` unless two sides agree on ``what``.

    ``left`` and ``right`` are ``(name, value)`` pairs, e.g. ``("calibration c.json",
    "3fa9...")`` and ``("device my.yaml", "77c0...")``; the message names both sides.

    Parameters
    ----------
    what : str
        The quantity compared, e.g. ``"device digest"``.
    left : tuple of (str, object)
        The first side's name and value.
    right : tuple of (str, object)
        The second side's name and value.

    Raises
    ------
    ProvenanceError
        When the two values differ.
    """
    if left[1] != right[1]:
        raise ProvenanceError(
            f"{what} differs: {left[0]} has {left[1]!r}, {right[0]} has {right[1]!r}; "
            "these results were not made from the same inputs")
