"""JSON Schema validation with defaults, shared by the data layer (study configs, devices).

:func:`validator` is a JSON Schema 2020-12 validator (Snakemake 9's draft) that also fills
in every ``default`` of the schema, as ``snakemake.utils.validate`` does, so that a command
and the workflow see the same config. :func:`first_error` turns the deepest error into
(field, value, message) for :class:`ssw.errors.ConfigError`.
"""

from __future__ import annotations

import copy
from typing import Any


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
