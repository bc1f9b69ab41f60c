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


def model_from(spec: dict[str, Any] | None) -> Any:
    """A model from a mapping ``{model: <name>, <parameter>: <value>, ...}`` (SI units; the
    config's ``sets.*.soil_model``); None or ``linear-elastic``: None (today's elastic
    path)."""
    if spec is None:
        return None
    if not isinstance(spec, dict) or "model" not in spec:
        raise ConfigError("soil_model", spec, "a mapping with 'model': "
                          + " | ".join(MODELS))
    name = spec["model"]
    if name not in MODELS:
        raise ConfigError("soil_model.model", name, " | ".join(MODELS))
    if name == LinearElastic.name:
        return None
    cls = MODELS[name]
    known = {f.name for f in fields(cls)}
    args = {k: v for k, v in spec.items() if k != "model"}
    unknown = set(args) - known
    if unknown:
        raise ConfigError(f"soil_model.{sorted(unknown)[0]}", args[sorted(unknown)[0]],
                          f"parameters of {name}: {', '.join(sorted(known))}")
    return cls(**{k: (v if isinstance(v, str) or v is None else float(v))
                  for k, v in args.items()})


def model_of_strength(name: str, strength: Any, where: str = "material") -> Any:
    """A model of ``name`` whose strengths are a material's (not fitted):

    * ``von-mises``: ``Y`` = the yield stress (or the compressive strength);
    * ``drucker-prager``: the cohesion, friction and dilatancy angles, the tensile strength
      as the cutoff;
    * ``crushable-foam``: ``Y0`` = the compressive strength;
    * ``tresca``: ``k`` = the cohesion (a clay's undrained shear strength ``c_u``; the
      friction angle is not used: undrained, the strength does not depend on the mean
      stress).
    """
    def need(value: Any, field: str) -> float:
        if value is None:
            raise ConfigError(f"{where}.strength.{field}", None,
                              f"a value with a source for the {name} model")
        return float(value)

    if name == VonMises.name:
        y = strength.yield_stress if strength.yield_stress is not None else strength.compressive
        return VonMises(need(y, "yield_stress"))
    if name == DruckerPrager.name:
        return DruckerPrager(need(strength.cohesion, "cohesion"),
                             need(strength.friction_angle, "friction_angle"),
                             strength.dilatancy_angle, strength.tensile)
    if name == CrushableFoam.name:
        return CrushableFoam(need(strength.compressive, "compressive"))
    if name == Tresca.name:
        return Tresca(need(strength.cohesion, "cohesion"))
    raise ConfigError("soil_model.model", name,
                      " | ".join(n for n in MODELS if n != LinearElastic.name))


__all__ = ["MODELS", "CrushableFoam", "DruckerPrager", "LinearElastic", "Tresca", "VonMises",
           "model_from", "model_of_strength"]
