"""The plastic sample's model from command-line flags (``ssw contact``, ``ssw tof --hits``):
``--soil-model`` with its strengths, or a library material's (``--soil-material``: its E,
nu and strengths, not fitted)."""

from __future__ import annotations

import argparse
from typing import Any

from ssw.errors import ConfigError

#: ``--soil-model`` choices: the plastic models of :data:`ssw.constitutive.MODELS`.
PLASTIC_MODELS = ("von-mises", "drucker-prager", "crushable-foam", "tresca")


def add_soil_model_options(p: Any) -> None:
    """The flags of a plastic sample's model (``ssw contact``, ``ssw tof --hits``), on a
    parser or an argument group: read by :func:`soil_model_of`.

    Parameters
    ----------
    p : argparse.ArgumentParser or argparse._ArgumentGroup
        The command's parser or one of its argument groups (the options are added to it).
    """
    p.add_argument("--soil-model", choices=PLASTIC_MODELS,
                   help="constitutive model of the sample beyond elasticity (the "
                   "elasto-plastic contact, ssw.contact.plastic; through the plate if any)")
    p.add_argument("--soil-yield-stress", type=float,
                   help="von Mises yield stress Y, or the foam's compressive strength, Pa")
    p.add_argument("--soil-hardening", type=float, default=0.0,
                   help="linear hardening modulus, Pa (default 0: perfectly plastic)")
    p.add_argument("--soil-cohesion", type=float,
                   help="Drucker-Prager cohesion c, or Tresca's shear strength k (the "
                   "undrained cohesion c_u), Pa")
    p.add_argument("--soil-friction-angle", type=float,
                   help="Drucker-Prager friction angle phi, degrees")
    p.add_argument("--soil-dilatancy-angle", type=float,
                   help="Drucker-Prager dilatancy angle psi, degrees (default phi)")
    p.add_argument("--soil-material",
                   help="a material key of the library: its E, nu and strengths (with "
                   "--soil-model; the strengths are the library's, not fitted)")


def soil_material_of(args: argparse.Namespace, cfg: dict[str, Any]) -> Any:
    """The library material of ``--soil-material`` (None without it); fills
    ``args.soil_E``/``soil_nu`` from it when they are not given. ConfigError naming the
    flag for a key the library lacks.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (``--soil-material``, ``--soil-E``, ``--soil-nu``).
    cfg : dict of str to Any
        The study config (its materials library).

    Returns
    -------
    ssw.materials.Material or None
        The material, or None without the flag.

    Raises
    ------
    ssw.errors.ConfigError
        When the library has no such material.
    """
    if args.soil_material is None:
        return None
    from ssw.config import library

    mats = library(cfg)
    if args.soil_material not in mats:
        raise ConfigError("--soil-material", args.soil_material,
                          f"a material of the library: {', '.join(sorted(mats))}")
    mat = mats[args.soil_material]
    args.soil_E = mat.E if args.soil_E is None else args.soil_E
    args.soil_nu = mat.nu if args.soil_nu is None else args.soil_nu
    return mat


def soil_model_of(args: argparse.Namespace, cfg: dict[str, Any]) -> Any:
    """The :mod:`ssw.constitutive` model of the flags; fills ``args.soil_E``/``soil_nu``
    from ``--soil-material`` when they are not given. ConfigError naming the flag that is
    missing or wrong.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (the options of :func:`add_soil_model_options`).
    cfg : dict of str to Any
        The study config (its materials library).

    Returns
    -------
    Any
        The plastic model (:func:`ssw.constitutive.model_from`, or the material's
        strengths through :func:`ssw.constitutive.model_of_strength`; stresses in Pa).

    Raises
    ------
    ssw.errors.ConfigError
        When ``--soil-model``, the soil's E or nu, or a strength the model needs is
        missing, or the model is no plastic one.
    """
    from ssw.constitutive import model_from, model_of_strength

    if args.soil_model is None:
        raise ConfigError("--soil-model", None, " | ".join(PLASTIC_MODELS))
    mat = soil_material_of(args, cfg)
    for name in ("soil_E", "soil_nu"):
        if getattr(args, name) is None:
            raise ConfigError(f"--{name.replace('_', '-')}", None, "a value (or --soil-material)")
    if mat is not None and args.soil_yield_stress is None and args.soil_cohesion is None:
        return model_of_strength(args.soil_model, mat.strength, f"materials.{args.soil_material}")
    spec: dict[str, Any] = {"model": args.soil_model}
    if args.soil_model in ("von-mises", "crushable-foam"):
        if args.soil_yield_stress is None:
            raise ConfigError("--soil-yield-stress", None, "a stress > 0 Pa")
        key = "yield_stress" if args.soil_model == "von-mises" else "compressive_strength"
        spec.update({key: args.soil_yield_stress, "hardening": args.soil_hardening})
    elif args.soil_model == "tresca":
        if args.soil_cohesion is None:
            raise ConfigError("--soil-cohesion", None,
                              "the shear strength k (the undrained cohesion c_u), Pa")
        spec.update(cohesion=args.soil_cohesion, hardening=args.soil_hardening)
    else:
        if args.soil_cohesion is None or args.soil_friction_angle is None:
            raise ConfigError("--soil-cohesion", args.soil_cohesion,
                              "a cohesion (Pa) and --soil-friction-angle (degrees)")
        spec.update(cohesion=args.soil_cohesion, friction_angle=args.soil_friction_angle,
                    dilatancy_angle=args.soil_dilatancy_angle)
    model = model_from(spec)
    if model is None:
        raise ConfigError("--soil-model", args.soil_model, "a plastic model (von-mises)")
    return model


#: ``--plate-model`` choices: a plate yields as a metal or a polymer does (von Mises).
PLATE_MODELS = ("von-mises",)


def add_plate_model_options(p: Any) -> None:
    """The flags of a yielding plate (``ssw contact``, ``ssw tof --hits``), on a parser or
    an argument group: read by :func:`plate_model_of`.

    Parameters
    ----------
    p : argparse.ArgumentParser or argparse._ArgumentGroup
        The command's parser or one of its argument groups (the options are added to it).
    """
    p.add_argument("--plate-model", choices=PLATE_MODELS,
                   help="constitutive model of the plate beyond elasticity (default: elastic); "
                   "its yield stress and hardening are the plate material's in the library "
                   "unless given")
    p.add_argument("--plate-yield-stress", type=float,
                   help="the plate's von Mises yield stress Y, Pa (default: the library's)")
    p.add_argument("--plate-hardening", type=float,
                   help="the plate's linear hardening modulus, Pa (default: the library's, "
                   "else 0: perfectly plastic)")


def plate_model_of(args: argparse.Namespace, materials: dict[str, Any], plate_key: str
                   ) -> Any:
    """The plate's :mod:`ssw.constitutive` model of the flags (None without
    ``--plate-model``): the plate material ``plate_key``'s library strengths, overridden by
    ``--plate-yield-stress`` and ``--plate-hardening``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed flags.
    materials : dict
        The material library (key -> :class:`ssw.materials.Material`).
    plate_key : str
        The plate's material key (``none``: no plate).

    Returns
    -------
    The plate's model, or None (an elastic plate).

    Raises
    ------
    ConfigError
        Naming the flag: a plate flag without ``--plate-model``, a model without a plate,
        or a material without a yield stress and no ``--plate-yield-stress``.
    """
    from ssw.constitutive import model_from

    name = getattr(args, "plate_model", None)
    if name is None:
        for flag in ("plate_yield_stress", "plate_hardening"):
            if getattr(args, flag, None) is not None:
                raise ConfigError(f"--{flag.replace('_', '-')}", getattr(args, flag),
                                  "with --plate-model")
        return None
    if plate_key == "none":
        raise ConfigError("--plate-model", name, "a plate (--plate-thickness > 0)")
    strength = materials[plate_key].strength if plate_key in materials else None
    Y = args.plate_yield_stress
    if Y is None and strength is not None:
        Y = strength.yield_stress
    if Y is None:
        raise ConfigError("--plate-yield-stress", None,
                          f"a stress > 0 Pa (materials.{plate_key} has no yield_stress)")
    H = args.plate_hardening
    if H is None:
        H = strength.hardening if strength is not None and strength.hardening else 0.0
    return model_from({"model": name, "yield_stress": Y, "hardening": H}, "plate_model")
