"""Materials library: named materials with E (Pa), nu, density (kg/m^3) and a source.

The library is a YAML file (shipped as ``ssw/data/materials.yaml``, linked from the
repository's ``config/materials.yaml``) with named sets. ``realistic`` is
complete; other sets (``as_printed``, the thesis's Table 1 moduli as printed) override
fields of some materials and inherit the rest from ``realistic``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from ssw.errors import ConfigError

#: The library shipped with ssw (package data; ``config/materials.yaml`` links to it).
DEFAULT_LIBRARY = Path(__file__).resolve().parent / "data" / "materials.yaml"
BASE_SET = "realistic"


@dataclass(frozen=True)
class Material:
    """An isotropic linear-elastic material. SI units."""

    key: str
    name: str
    E: float  # Young's modulus, Pa
    nu: float  # Poisson's ratio, -
    density: float  # kg/m^3
    source: str

    def __post_init__(self) -> None:
        if not self.E > 0:
            raise ConfigError(f"materials.{self.key}.E", self.E, "Young's modulus must be > 0 Pa")
        if not -1.0 < self.nu <= 0.5:
            raise ConfigError(f"materials.{self.key}.nu", self.nu, "must lie in (-1, 0.5]")
        if not self.density > 0:
            raise ConfigError(f"materials.{self.key}.density", self.density, "must be > 0 kg/m^3")


def load_library(path: str | Path | None = None) -> dict[str, dict[str, Any]]:
    """Raw library: set name -> material key -> fields."""
    p = Path(path) if path is not None else DEFAULT_LIBRARY
    if not p.is_file():
        raise ConfigError("materials_file", str(p), "an existing YAML materials library")
    data = yaml.safe_load(p.read_text())
    if not isinstance(data, dict) or BASE_SET not in data:
        raise ConfigError("materials_file", str(p), f"a mapping with a '{BASE_SET}' set")
    return data


def material_set(name: str = BASE_SET, path: str | Path | None = None) -> dict[str, Material]:
    """All materials of set ``name`` (fields not in the set come from ``realistic``)."""
    lib = load_library(path)
    if name not in lib:
        raise ConfigError("material_set", name, f"one of {sorted(lib)}")
    out = {}
    for key, base in lib[BASE_SET].items():
        fields = {**base, **(lib[name].get(key, {}) if name != BASE_SET else {})}
        out[key] = Material(
            key=key,
            name=str(fields["name"]),
            E=float(fields["E"]),
            nu=float(fields["nu"]),
            density=float(fields["density"]),
            source=str(fields["source"]),
        )
    unknown = set(lib[name]) - set(out)
    if unknown:
        raise ConfigError(f"materials.{name}", sorted(unknown), "materials also in 'realistic'")
    return out


def get_material(
    key: str, set_name: str = BASE_SET, path: str | Path | None = None, field: str = "material"
) -> Material:
    """Material ``key`` of set ``set_name``; ``field`` names the setting for error messages."""
    mats = material_set(set_name, path)
    if key not in mats:
        raise ConfigError(field, key, f"a material of the library: {', '.join(sorted(mats))}")
    return mats[key]
