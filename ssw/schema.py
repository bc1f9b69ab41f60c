"""JSON Schema validation with defaults, shared by the data layer (study configs, devices).

:func:`validator` is a JSON Schema 2020-12 validator (Snakemake 9's draft) that also fills
in every ``default`` of the schema, as ``snakemake.utils.validate`` does, so that a command
and the workflow see the same config, and that refuses NaN and infinities wherever the
schema accepts a number (JSON has neither; YAML's ``.nan`` and ``.inf`` would pass every
bound: NaN compares false with any limit). A subschema with ``allowNonFinite: true``
accepts them. :func:`first_error` turns the deepest error into (field, value, message) for
:class:`ssw.errors.ConfigError`, a non-finite number first.

Every job of a study validates the same study config and device again (a command cannot
know that the workflow did). :func:`first_file_error` remembers the filled instance of every
valid (schema file, instance) pair under the disk cache (``$SSW_CACHE_DIR/schema``, default
``~/.cache/ssw``, :func:`ssw.h5io.cache_root`; ``SSW_CACHE_DIR=none`` turns it off), named
by the SHA-256 of the schema file's bytes, of this module's source (the validator's own
rules) and of the instance's JSON, keys in their order: the filled instance comes back
exactly, order included. An instance that JSON does not carry exactly (integer keys, dates,
NaN) is not remembered, and nothing is written where the cache folder does not exist yet,
nor by a process that turned writing off (:func:`set_memo_writes`: the workflow's own, so
that parsing the Snakefile, in a dry run or a lint, writes nothing; its jobs remember).
A remembered instance is validated again when it is read: it must hold the instance it
stands for (every value of the instance, at its place) and pass the schema with nothing
left to fill; one that does not is discarded with a :class:`MemoWarning` and the instance
is validated as if nothing were remembered.
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import os
from pathlib import Path
from typing import Any

#: Whether :func:`first_file_error` writes the pairs it validates (it reads them regardless).
_MEMO_WRITES = True
#: The schema keyword that lets a number be NaN or infinite (default false).
ALLOW_NON_FINITE = "allowNonFinite"
#: The ``validator`` of a non-finite number's error (:func:`first_error` reports it first).
NON_FINITE = "finite"
#: Parsed schemas by the SHA-256 of their file's bytes (a process parses each once).
_SCHEMAS: dict[str, dict[str, Any]] = {}


class MemoWarning(UserWarning):
    """A remembered validation did not hold when read again; it was discarded."""


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
    """A JSON Schema 2020-12 validator of ``schema`` that fills in ``default`` values and
    refuses non-finite numbers.

    Parameters
    ----------
    schema : dict
        The JSON schema.

    Returns
    -------
    jsonschema.protocols.Validator
        Draft 2020-12 with two keywords extended: ``properties`` fills the defaults of
        absent properties into the instance (in place); ``type`` refuses a NaN or an
        infinity where it accepts ``number``, unless the subschema says
        ``allowNonFinite: true``.
    """
    import jsonschema

    base = jsonschema.Draft202012Validator
    validate_props = base.VALIDATORS["properties"]
    validate_type = base.VALIDATORS["type"]

    def set_defaults(validator: Any, properties: Any, instance: Any, schema: Any) -> Any:
        if isinstance(instance, dict):
            for prop, sub in properties.items():
                if "default" in sub and prop not in instance:
                    instance[prop] = copy.deepcopy(sub["default"])
        yield from validate_props(validator, properties, instance, schema)

    def finite_type(validator: Any, types: Any, instance: Any, schema: Any) -> Any:
        errors = list(validate_type(validator, types, instance, schema))
        yield from errors
        if (not errors and isinstance(instance, float) and not math.isfinite(instance)
                and not schema.get(ALLOW_NON_FINITE, False)):
            yield jsonschema.ValidationError(
                "not a finite number: NaN and infinities are refused (YAML's .nan and .inf "
                "pass every bound); write the value itself", validator=NON_FINITE)

    return jsonschema.validators.extend(
        base, {"properties": set_defaults, "type": finite_type})(schema)


def path_of(error: Any) -> str:
    """The dotted path of a validation error's instance (``(top level)`` for the root).

    Parameters
    ----------
    error : jsonschema.ValidationError
        The validation error.

    Returns
    -------
    str
        The path, e.g. ``sets.set1.soil_E``.
    """
    parts = [str(p) for p in error.absolute_path]
    return ".".join(parts) if parts else "(top level)"


def message_of(error: Any) -> str:
    """What ``error`` allows, in words: a ``pattern`` error gives its subschema's
    ``description`` (the characters a name may hold) when it has one, else jsonschema's
    message.

    Parameters
    ----------
    error : jsonschema.ValidationError
        An error of :func:`first_error`.

    Returns
    -------
    str
        The text for :class:`ssw.errors.ConfigError`'s ``allowed``.
    """
    schema = error.schema if isinstance(error.schema, dict) else {}
    if error.validator == "pattern" and schema.get("description"):
        return f"{schema['description']} (pattern {error.validator_value})"
    return str(error.message)


def _non_finite(errors: Any) -> Any | None:
    """The first non-finite number's error among ``errors`` and the errors of their
    alternatives (``oneOf``/``anyOf`` branches), or None."""
    for e in errors:
        if e.validator == NON_FINITE:
            return e
        inner = _non_finite(e.context)
        if inner is not None:
            return inner
    return None


def first_error(schema: dict[str, Any], instance: Any) -> Any | None:
    """Validate ``instance`` in place (defaults filled); its first error, or None.

    Parameters
    ----------
    schema : dict
        The JSON schema.
    instance : Any
        The document; defaults are filled in place.

    Returns
    -------
    jsonschema.ValidationError or None
        A non-finite number's error when there is one, even inside one branch of a
        ``oneOf`` (a NaN in a grid's values), else the deepest error (so that the message
        names the offending field); None when ``instance`` is valid.
    """
    errors = sorted(validator(schema).iter_errors(instance), key=lambda e: -len(e.absolute_path))
    if not errors:
        return None
    return _non_finite(errors) or errors[0]


def _memo_path(schema_bytes: bytes, instance: Any) -> Path | None:
    """Where the filled ``instance`` of a valid pair is kept; None without a disk cache or
    when JSON does not carry ``instance`` exactly."""
    from ssw.h5io import cache_root

    root = cache_root()
    text = _exact_json(instance)
    if root is None or text is None:
        return None
    rules = hashlib.sha256(Path(__file__).read_bytes()).digest()
    digest = hashlib.sha256(hashlib.sha256(schema_bytes).digest() + rules
                            + text.encode()).hexdigest()
    return root / "schema" / f"{digest[:32]}.json"


def _exact_json(obj: Any) -> str | None:
    """``obj`` as JSON when it reads back equal (plain dicts with str keys, lists, str,
    numbers, bools, None; no NaN), else None."""
    try:
        text = json.dumps(obj, allow_nan=False)
    except (TypeError, ValueError):
        return None
    return text if json.loads(text) == obj else None


def _holds(filled: Any, instance: Any) -> bool:
    """Whether ``filled`` is ``instance`` with defaults added: every key of a mapping there
    with its value held, lists of the same length item by item, other values equal and of
    the same type."""
    if isinstance(instance, dict):
        return isinstance(filled, dict) and all(
            k in filled and _holds(filled[k], v) for k, v in instance.items())
    if isinstance(instance, list):
        return (isinstance(filled, list) and len(filled) == len(instance)
                and all(_holds(a, b) for a, b in zip(filled, instance, strict=True)))
    return type(filled) is type(instance) and filled == instance


def _recall(memo: Path, schema: dict[str, Any], instance: dict[str, Any]) -> dict | None:
    """The remembered filled instance at ``memo`` when it validates again (module
    docstring), else None: an unreadable file is skipped, one that does not hold is
    discarded with a :class:`MemoWarning`."""
    import warnings

    try:
        text = memo.read_text()
        filled = json.loads(text)
    except (OSError, ValueError):
        return None
    reason = None
    if not isinstance(filled, dict) or not _holds(filled, instance):
        reason = "it does not hold the document it was remembered for"
    else:
        err = first_error(schema, filled)
        if err is not None:
            reason = f"{path_of(err)}: {err.message}"
        elif _exact_json(filled) != text:
            reason = "the schema fills defaults it lacks"
    if reason is None:
        return filled
    warnings.warn(f"discarding the remembered validation {memo}: its document fails the "
                  f"schema again ({reason}); validating the document itself",
                  MemoWarning, stacklevel=3)
    try:
        memo.unlink()
    except OSError:
        pass
    return None


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
        The first error (:func:`first_error`), or None when ``instance`` is valid.
    """
    from ssw.h5io import atomic_write_text
    from ssw.yamlio import safe_load

    schema_bytes = Path(schema_path).read_bytes()
    key = hashlib.sha256(schema_bytes).hexdigest()
    schema = _SCHEMAS.get(key)
    if schema is None:
        schema = _SCHEMAS[key] = safe_load(schema_bytes.decode())
    memo = _memo_path(schema_bytes, instance)
    if memo is not None and memo.is_file():
        filled = _recall(memo, schema, instance)
        if filled is not None:
            instance.clear()
            instance.update(filled)
            return None
    err = first_error(schema, instance)
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
