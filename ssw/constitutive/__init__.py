"""Constitutive models of a sample, by name: the registry, and a model from a config entry
or from a material's strengths (:class:`ssw.materials.Strength`).

Every model follows :mod:`ssw.constitutive.base` (a frozen, hashable parameter object with
a ``key``, ``update`` (return mapping and consistent tangent, vectorized over points) and
``yield_ratio``).
"""

from __future__ import annotations

from dataclasses import fields
from typing import Any

from ssw.constitutive.crushable_foam import CrushableFoam
from ssw.constitutive.drucker_prager import DruckerPrager
from ssw.constitutive.elastic import LinearElastic
from ssw.constitutive.tresca import Tresca
from ssw.constitutive.von_mises import VonMises
from ssw.errors import ConfigError

#: Registry: name -> model class.
MODELS: dict[str, type] = {
    LinearElastic.name: LinearElastic,
    VonMises.name: VonMises,
    DruckerPrager.name: DruckerPrager,
    CrushableFoam.name: CrushableFoam,
    Tresca.name: Tresca,
}


def model_from(spec: dict[str, Any] | None, field: str = "soil_model") -> Any:
    """A model from a config entry.

    Parameters
    ----------
    spec : dict or None
        ``{model: <name>, <parameter>: <value>, ...}`` (SI units and degrees; the config's
        ``sets.*.soil_model`` or ``sets.*.plate_model``).
    field : str
        The entry's name in messages (``soil_model``, ``plate_model``).

    Returns
    -------
    A frozen model of :data:`MODELS`; None for None or ``linear-elastic`` (the exact
    elastic path).

    Raises
    ------
    ConfigError
        Naming ``<field>.<parameter>`` for an unknown model or parameter, or a bad value.
    """
    if spec is None:
        return None
    if not isinstance(spec, dict) or "model" not in spec:
        raise ConfigError(field, spec, "a mapping with 'model': " + " | ".join(MODELS))
    name = spec["model"]
    if name not in MODELS:
        raise ConfigError(f"{field}.model", name, " | ".join(MODELS))
    if name == LinearElastic.name:
        return None
    cls = MODELS[name]
    known = {f.name for f in fields(cls)}
    args = {k: v for k, v in spec.items() if k != "model"}
    unknown = set(args) - known
    if unknown:
        raise ConfigError(f"{field}.{sorted(unknown)[0]}", args[sorted(unknown)[0]],
                          f"parameters of {name}: {', '.join(sorted(known))}")
    try:
        return cls(**{k: (v if isinstance(v, str) or v is None else float(v))
                      for k, v in args.items()})
    except ConfigError as exc:  # the model names its parameter as a soil model's
        if field == "soil_model" or not exc.field.startswith("soil_model."):
            raise
        raise ConfigError(field + exc.field[len("soil_model"):], exc.value,
                          exc.allowed) from None


def model_of_strength(name: str, strength: Any, where: str = "material",
                      field: str = "soil_model") -> Any:
    """A model of ``name`` whose strengths are a material's (not fitted):

    * ``von-mises``: ``Y`` = the yield stress (or the compressive strength), the hardening
      modulus where the library gives one (else perfectly plastic);
    * ``drucker-prager``: the cohesion, friction and dilatancy angles, the tensile strength
      as the cutoff;
    * ``crushable-foam``: ``Y0`` = the compressive strength;
    * ``tresca``: ``k`` = the cohesion (a clay's undrained shear strength ``c_u``; the
      friction angle is not used: undrained, the strength does not depend on the mean
      stress).

    Parameters
    ----------
    name : str
        A plastic model of :data:`MODELS`.
    strength : ssw.materials.Strength
        The material's strengths (Pa, degrees).
    where : str
        The material's place in messages (``materials.<key>``).
    field : str
        The model's entry in messages (``soil_model``, ``plate_model``).

    Returns
    -------
    The frozen model.

    Raises
    ------
    ConfigError
        Naming ``<where>.strength.<field>`` when the model needs a strength the material
        lacks, or ``<field>.model`` for a model that is not plastic.
    """
    def need(value: Any, field: str) -> float:
        if value is None:
            raise ConfigError(f"{where}.strength.{field}", None,
                              f"a value with a source for the {name} model")
        return float(value)

    if name == VonMises.name:
        y = strength.yield_stress if strength.yield_stress is not None else strength.compressive
        return VonMises(need(y, "yield_stress"), float(strength.hardening or 0.0))
    if name == DruckerPrager.name:
        return DruckerPrager(need(strength.cohesion, "cohesion"),
                             need(strength.friction_angle, "friction_angle"),
                             strength.dilatancy_angle, strength.tensile)
    if name == CrushableFoam.name:
        return CrushableFoam(need(strength.compressive, "compressive"))
    if name == Tresca.name:
        return Tresca(need(strength.cohesion, "cohesion"))
    raise ConfigError(f"{field}.model", name,
                      " | ".join(n for n in MODELS if n != LinearElastic.name))


__all__ = ["MODELS", "CrushableFoam", "DruckerPrager", "LinearElastic", "Tresca", "VonMises",
           "model_from", "model_of_strength"]
