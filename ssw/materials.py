"""Materials library: named materials with E (Pa), nu, density (kg/m^3), a source and, where
known, strengths (:class:`Strength`, each with its own source).

The library is a YAML file (shipped as ``ssw/data/materials.yaml``, linked from the
repository's ``config/materials.yaml``) with named sets. ``realistic`` is
complete; other sets (``as_printed``, the thesis's Table 1 moduli as printed) override
fields of some materials and inherit the rest from ``realistic``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

from ssw.errors import ConfigError
from ssw.yamlio import safe_load

#: The library shipped with ssw (package data; ``config/materials.yaml`` links to it).
DEFAULT_LIBRARY = Path(__file__).resolve().parent / "data" / "materials.yaml"
BASE_SET = "realistic"
#: A material key: letters, digits and underscores (keys enter scene ids, file names,
#: wildcards and commands; the study config's ``$defs/name``).
KEY_PATTERN = r"[A-Za-z0-9_]+"


@dataclass(frozen=True)
class Strength:
    """What a material withstands before it yields or fails. SI units; None: not known.

    Parameters
    ----------
    yield_stress : float or None
        Uniaxial (tensile) yield stress (Pa), the von Mises ``Y`` (metals, plates).
    compressive : float or None
        Uniaxial compressive strength (Pa) (foams: the plateau or yield stress in
        compression; soils: unconfined compressive strength).
    tensile : float or None
        Uniaxial tensile strength (Pa).
    cohesion : float or None
        Mohr-Coulomb cohesion ``c`` (Pa).
    friction_angle : float or None
        Mohr-Coulomb angle of internal friction ``phi`` (degrees).
    dilatancy_angle : float or None
        Dilatancy angle ``psi`` (degrees; non-associated flow).
    hardening : float or None
        Linear isotropic hardening modulus ``dY / d kappa`` of the von Mises ``Y`` (Pa;
        ``kappa`` the equivalent plastic strain; 0: perfectly plastic).
    source : str
        Where the values come from.
    """

    yield_stress: float | None = None
    compressive: float | None = None
    tensile: float | None = None
    cohesion: float | None = None
    friction_angle: float | None = None
    dilatancy_angle: float | None = None
    hardening: float | None = None
    source: str = ""

    def check(self, key: str) -> None:
        """ConfigError naming ``materials.<key>.strength.<field>`` for a bad value.

        Parameters
        ----------
        key : str
            The material's key in the library.

        Raises
        ------
        ConfigError
            If a strength is not finite or out of range, an angle lies outside
            [0, 90) degrees, or strengths come without a source.
        """
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name == "source" or v is None:
                continue
            if f.name in ("friction_angle", "dilatancy_angle"):
                if not (math.isfinite(v) and 0.0 <= v < 90.0):
                    raise ConfigError(f"materials.{key}.strength.{f.name}", v,
                                      "an angle in [0, 90) degrees")
            elif not (math.isfinite(v) and v >= 0.0 if f.name in ("cohesion", "hardening")
                      else math.isfinite(v) and v > 0.0):
                raise ConfigError(f"materials.{key}.strength.{f.name}", v,
                                  "a stress >= 0 Pa" if f.name in ("cohesion", "hardening")
                                  else "a stress > 0 Pa")
        if any(getattr(self, f.name) is not None for f in fields(self) if f.name != "source") \
                and not self.source.strip():
            raise ConfigError(f"materials.{key}.strength.source", self.source,
                              "a source for the strengths (a catalogue, a handbook, a paper)")

    @classmethod
    def from_dict(cls, key: str, data: Any) -> Strength:
        """A strength from the library's ``strength:`` mapping (checked).

        Parameters
        ----------
        key : str
            The material's key in the library.
        data : Any
            The ``strength:`` mapping (Pa, degrees, ``source``).

        Returns
        -------
        Strength
            The checked strengths.

        Raises
        ------
        ConfigError
            If ``data`` is not a mapping, has unknown fields or bad values.
        """
        if not isinstance(data, dict):
            raise ConfigError(f"materials.{key}.strength", data, "a mapping of strengths")
        known = {f.name for f in fields(cls)}
        unknown = set(data) - known
        if unknown:
            raise ConfigError(f"materials.{key}.strength", sorted(unknown),
                              f"fields of {', '.join(sorted(known))}")
        st = cls(**{k: (str(v) if k == "source" else None if v is None
                        else number(f"materials.{key}.strength.{k}", v))
                    for k, v in data.items()})
        st.check(key)
        return st


@dataclass(frozen=True)
class Material:
    """An isotropic linear-elastic material, with its strengths where known. SI units.

    Parameters
    ----------
    key : str
        Its key in the library: letters, digits and underscores (:data:`KEY_PATTERN`).
    name : str
        What it is.
    E : float
        Young's modulus, Pa (finite, > 0).
    nu : float
        Poisson's ratio (finite, in (-1, 0.5]).
    density : float
        kg/m^3 (finite, > 0).
    source : str
        Where the values come from.
    strength : Strength
        Its strengths, where known.

    Raises
    ------
    ConfigError
        Naming ``materials.<key>.<field>`` and the value, for a key or a value outside
        these bounds (NaN and infinities included).
    """

    key: str
    name: str
    E: float  # Young's modulus, Pa
    nu: float  # Poisson's ratio, -
    density: float  # kg/m^3
    source: str
    strength: Strength = Strength()

    def __post_init__(self) -> None:
        if not (isinstance(self.key, str) and re.fullmatch(KEY_PATTERN, self.key)):
            raise ConfigError(f"materials.{self.key}", self.key,
                              "a key of letters, digits and underscores (it enters file names "
                              "and commands)")
        for name in ("E", "nu", "density"):
            v = getattr(self, name)
            if not math.isfinite(v):
                raise ConfigError(f"materials.{self.key}.{name}", v,
                                  "a finite number (NaN and infinities are refused)")
        if not self.E > 0:
            raise ConfigError(f"materials.{self.key}.E", self.E, "Young's modulus must be > 0 Pa")
        if not -1.0 < self.nu <= 0.5:
            raise ConfigError(f"materials.{self.key}.nu", self.nu, "must lie in (-1, 0.5]")
        if not self.density > 0:
            raise ConfigError(f"materials.{self.key}.density", self.density, "must be > 0 kg/m^3")


def number(field: str, value: Any) -> float:
    """``value`` as a float, or :class:`.ConfigError` naming ``field`` when it is not a
    number (text, a list, a bool).

    Parameters
    ----------
    field : str
        The library field, e.g. ``materials.pla.E``.
    value : Any
        The value read from the library.

    Returns
    -------
    float
        The number (its finiteness and range are the caller's checks).
    """
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ConfigError(field, value, "a number in SI units (YAML reads 1.0e6 as text: "
                          "write 1.0e+6)")
    return float(value)


def load_library(path: str | Path | None = None) -> dict[str, dict[str, Any]]:
    """Raw library: set name -> material key -> fields.

    Parameters
    ----------
    path : str or pathlib.Path or None
        The YAML materials library; None: the packaged one.

    Returns
    -------
    dict
        Set name -> material key -> fields, as in the YAML file.

    Raises
    ------
    ConfigError
        If the file does not exist or lacks the base set.
    """
    p = Path(path) if path is not None else DEFAULT_LIBRARY
    if not p.is_file():
        raise ConfigError("materials_file", str(p), "an existing YAML materials library")
    data = safe_load(p.read_text())
    if not isinstance(data, dict) or BASE_SET not in data:
        raise ConfigError("materials_file", str(p), f"a mapping with a '{BASE_SET}' set")
    return data


def material_set(name: str = BASE_SET, path: str | Path | None = None) -> dict[str, Material]:
    """All materials of set ``name`` (fields not in the set come from ``realistic``).

    Parameters
    ----------
    name : str
        The set's name.
    path : str or pathlib.Path or None
        The YAML materials library; None: the packaged one.

    Returns
    -------
    dict
        Material key -> :class:`Material` (SI).

    Raises
    ------
    ConfigError
        If the set is unknown or names materials not in the base set.
    """
    lib = load_library(path)
    if name not in lib:
        raise ConfigError("material_set", name, f"one of {sorted(lib)}")
    out = {}
    for key, base in lib[BASE_SET].items():
        vals = {**base, **(lib[name].get(key, {}) if name != BASE_SET else {})}
        out[key] = Material(
            key=key,
            name=str(vals["name"]),
            E=number(f"materials.{key}.E", vals["E"]),
            nu=number(f"materials.{key}.nu", vals["nu"]),
            density=number(f"materials.{key}.density", vals["density"]),
            source=str(vals["source"]),
            strength=Strength.from_dict(key, vals["strength"]) if vals.get("strength")
            else Strength(),
        )
    unknown = set(lib[name]) - set(out)
    if unknown:
        raise ConfigError(f"materials.{name}", sorted(unknown), "materials also in 'realistic'")
    return out


def get_material(
    key: str, set_name: str = BASE_SET, path: str | Path | None = None, field: str = "material"
) -> Material:
    """Material ``key`` of set ``set_name``; ``field`` names the setting for error messages.

    Parameters
    ----------
    key : str
        The material's key.
    set_name : str
        The set's name.
    path : str or pathlib.Path or None
        The YAML materials library; None: the packaged one.
    field : str
        The setting's name, for error messages.

    Returns
    -------
    Material
        The material (SI).

    Raises
    ------
    ConfigError
        If ``key`` is not a material of the set.
    """
    mats = material_set(set_name, path)
    if key not in mats:
        raise ConfigError(field, key, f"a material of the library: {', '.join(sorted(mats))}")
    return mats[key]
