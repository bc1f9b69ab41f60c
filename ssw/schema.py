"""JSON Schema validation with defaults, shared by the data layer (study configs, devices).

:func:`validator` is a JSON Schema 2020-12 validator (Snakemake 9's draft) that also fills
in every ``default`` of the schema, as ``snakemake.utils.validate`` does, so that a command
and the workflow see the same config. :func:`first_error` turns the deepest error into
(field, value, message) for :class:`ssw.errors.ConfigError`.

Every job of a study validates the same study config and device again (a command cannot
know that the workflow did). :func:`first_file_error` remembers the filled instance of every
valid (schema file, instance) pair under the disk cache (``$SSW_CACHE_DIR/schema``, default
``~/.cache/ssw``, :func:`ssw.h5io.cache_root`; ``SSW_CACHE_DIR=none`` turns it off), named
by the SHA-256 of the schema file's bytes and of the instance's JSON, keys in their order: the
filled instance comes back exactly, order included. An instance that JSON does not carry
exactly (integer keys, dates, NaN) is not remembered, and nothing is written where the cache
folder does not exist yet, nor by a process that turned writing off (:func:`set_memo_writes`:
the workflow's own, so that parsing the Snakefile, in a dry run or a lint, writes nothing;
its jobs remember). A job that finds its pair takes the filled
instance without importing ``jsonschema`` (85 ms of each job's start, with the 13 ms of
parsing the schema, measured on a 2-core machine).
"""

from __future__ import annotations

import copy
import hashlib
import json
import os
from pathlib import Path
from typing import Any

#: Whether :func:`first_file_error` writes the pairs it validates (it reads them regardless).
_MEMO_WRITES = True


def set_memo_writes(enabled: bool) -> None:
    """Let this process write the validated pairs of :func:`first_file_error`, or not.

    Parameters
    ----------
    enabled : bool
        False: read the remembered pairs, write none.
    """
    global _MEMO_WRITES
    _MEMO_WRITES = bool(enabled)


def validator(schema: dict[str, Any]) -> Any:
    """A JSON Schema 2020-12 validator of ``schema`` that fills in ``default`` values."""
    import jsonschema

    base = jsonschema.Draft202012Validator
    validate_props = base.VALIDATORS["properties"]

    def set_defaults(validator: Any, properties: Any, instance: Any, schema: Any) -> Any:
        if isinstance(instance, dict):
            for prop, sub in properties.items():
                if "default" in sub and prop not in instance:
                    instance[prop] = copy.deepcopy(sub["default"])
        yield from validate_props(validator, properties, instance, schema)

    return jsonschema.validators.extend(base, {"properties": set_defaults})(schema)


def path_of(error: Any) -> str:
    """The dotted path of a validation error's instance (``(top level)`` for the root)."""
    parts = [str(p) for p in error.absolute_path]
    return ".".join(parts) if parts else "(top level)"


def first_error(schema: dict[str, Any], instance: Any) -> Any | None:
    """Validate ``instance`` in place (defaults filled); the deepest error, or None."""
    errors = sorted(validator(schema).iter_errors(instance), key=lambda e: -len(e.absolute_path))
    return errors[0] if errors else None


def _memo_path(schema_bytes: bytes, instance: Any) -> Path | None:
    """Where the filled ``instance`` of a valid pair is kept; None without a disk cache or
    when JSON does not carry ``instance`` exactly."""
    from ssw.h5io import cache_root

    root = cache_root()
    text = _exact_json(instance)
    if root is None or text is None:
        return None
    digest = hashlib.sha256(hashlib.sha256(schema_bytes).digest() + text.encode()).hexdigest()
    return root / "schema" / f"{digest[:32]}.json"


def _exact_json(obj: Any) -> str | None:
    """``obj`` as JSON when it reads back equal (plain dicts with str keys, lists, str,
    numbers, bools, None; no NaN), else None."""
    try:
        text = json.dumps(obj, allow_nan=False)
    except (TypeError, ValueError):
        return None
    return text if json.loads(text) == obj else None


def first_file_error(schema_path: str | os.PathLike[str], instance: dict[str, Any]) -> Any | None:
    """:func:`first_error` against the YAML schema at ``schema_path``, remembered on disk
    for the valid pairs (module docstring).

    Parameters
    ----------
    schema_path : str or os.PathLike
        The JSON schema, as a YAML file.
    instance : dict
        The document; validated in place (defaults filled).

    Returns
    -------
    jsonschema.ValidationError or None
        The deepest error, or None when ``instance`` is valid.
    """
    from ssw.h5io import atomic_write_text
    from ssw.yamlio import safe_load

    schema_bytes = Path(schema_path).read_bytes()
    memo = _memo_path(schema_bytes, instance)
    if memo is not None and memo.is_file():
        try:
            filled = json.loads(memo.read_text())
        except (OSError, ValueError):
            filled = None
        if isinstance(filled, dict):
            instance.clear()
            instance.update(filled)
            return None
    err = first_error(safe_load(schema_bytes.decode()), instance)
    keep = (err is None and _MEMO_WRITES and memo is not None
            and memo.parent.parent.is_dir())
    filled_text = _exact_json(instance) if keep else None
    if filled_text is not None:
        try:
            memo.parent.mkdir(parents=True, exist_ok=True)
            atomic_write_text(memo, filled_text)
        except OSError:
            pass  # a cache that cannot be written costs a validation next time
    return err
