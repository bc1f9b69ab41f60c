"""The sample under the plate: a half-space, or a finite block on a base, free or in a mould.

Every contact scene stands on a soil. By default it is the FEM's wide box
(``contact.soil_radius`` x ``contact.soil_depth``, 1 m x 1 m: rollers on its side, its bottom
fixed), which stands for a half-space (within 0.7 % of the layered half-space oracle, README).
A real sample is often not one: a foam reference is a block a few centimetres thick on a
bench, a compacted soil sits in a Proctor mould (101.6 mm diameter, 116.4 mm high) or a CBR
mould (152.4 mm), a field lift is a layer on a subgrade. A :class:`Sample` says which:

* ``thickness`` (m) and ``radius`` (m) of the block (axisymmetric); a box of sides ``a x b``
  is taken as the cylinder of the same footprint area, ``radius = sqrt(a b / pi)``
  (:func:`equivalent_radius`; stated in the sample's ``lateral_size``);
* ``base``: ``bonded`` (glued to a rigid base: ``u = 0``) or ``sliding`` (on a rigid,
  frictionless base: ``u_z = 0``, ``u_r`` free);
* ``lateral``: ``free`` (traction-free side) or ``mould`` (a rigid, frictionless mould:
  ``u_r = 0``).

The FEM meshes the block itself (its radius and thickness replace the box's) with these
boundary conditions (:meth:`Sample.contact_settings`); the substructured fast path is kept
(the block is condensed per geometry and Poisson's ratio like the box). An elastic subgrade
under a layer and multi-layer field profiles are not modelled by the FEM (the layered
oracle, ``ssw contact --engine layered``, computes a layer on a rigid base).

Data layer: no heavy imports.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from ssw.errors import ConfigError

BASES = ("bonded", "sliding")
LATERALS = ("free", "mould")


@dataclass(frozen=True)
class Sample:
    """A finite cylindrical sample (module docstring). Lengths in m."""

    thickness: float
    radius: float
    base: str = "bonded"
    lateral: str = "free"
    lateral_size: str = ""  # how the radius was obtained (a box's sides), for the record

    def __post_init__(self) -> None:
        for name in ("thickness", "radius"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise ConfigError(f"sample.{name}", v, "a length > 0 m")
        if self.base not in BASES:
            raise ConfigError("sample.base", self.base, " | ".join(BASES))
        if self.lateral not in LATERALS:
            raise ConfigError("sample.lateral", self.lateral, " | ".join(LATERALS))

    @property
    def key(self) -> str:
        """Short file-name-safe text for scene ids, e.g. ``h40mm-r50mm-bonded-free``
        (lengths to 1 um; two samples of a config closer than that share an id, which the
        config refuses: :func:`ssw.config.scenes`)."""
        def mm(x: float) -> str:
            return f"{round(x * 1e6) / 1e3:g}mm"

        return f"h{mm(self.thickness)}-r{mm(self.radius)}-{self.base}-{self.lateral}"

    def contact_settings(self, contact: dict[str, Any]) -> dict[str, Any]:
        """The ``contact`` settings of a scene on this sample: the FEM's soil domain is the
        block (its radius and thickness) with the block's base and side conditions."""
        return {**contact, "soil_radius": float(self.radius),
                "soil_depth": float(self.thickness), "soil_base": self.base,
                "soil_lateral": self.lateral}

    def to_dict(self) -> dict[str, Any]:
        out = {"thickness": self.thickness, "radius": self.radius, "base": self.base,
               "lateral": self.lateral}
        if self.lateral_size:
            out["lateral_size"] = self.lateral_size
        return out


def equivalent_radius(side_a: float, side_b: float) -> float:
    """Radius (m) of the cylinder with the footprint area of an ``a x b`` box (m):
    ``sqrt(a b / pi)``."""
    if not (side_a > 0 and side_b > 0):
        raise ConfigError("sample.box", [side_a, side_b], "two sides > 0 m")
    return math.sqrt(side_a * side_b / math.pi)


def sample_from_dict(d: dict[str, Any] | None, field: str = "sample") -> Sample | None:
    """A :class:`Sample` from a config mapping ``{thickness, radius | box: [a, b], base,
    lateral}`` (SI), or None for none (the half-space)."""
    if d is None:
        return None
    if not isinstance(d, dict):
        raise ConfigError(field, d, "a mapping {thickness, radius or box, base, lateral}")
    unknown = set(d) - {"thickness", "radius", "box", "base", "lateral"}
    if unknown:
        raise ConfigError(f"{field}.{sorted(unknown)[0]}", d[sorted(unknown)[0]],
                          "one of thickness, radius, box, base, lateral")
    if ("radius" in d) == ("box" in d):
        raise ConfigError(f"{field}.radius", d.get("radius"),
                          "a radius (m) or a box [a, b] (m), one of them")
    size = ""
    if "box" in d:
        box = d["box"]
        if not (isinstance(box, list | tuple) and len(box) == 2):
            raise ConfigError(f"{field}.box", box, "two sides [a, b], m")
        radius = equivalent_radius(float(box[0]), float(box[1]))
        size = f"box {float(box[0]):g} x {float(box[1]):g} m -> radius sqrt(a b / pi)"
    else:
        radius = d["radius"]
    try:
        return Sample(float(d.get("thickness", float("nan"))), float(radius),
                      d.get("base", "bonded"), d.get("lateral", "free"), size)
    except (TypeError, ValueError) as exc:
        raise ConfigError(field, d, f"numbers in m ({exc})") from exc
