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
* ``base``: ``bonded`` (glued to a rigid base: ``u = 0``), ``sliding`` (on a rigid,
  frictionless base: ``u_z = 0``, ``u_r`` free) or ``elastic``: a lift bonded to a subgrade
  of ``base_E`` (Pa) and ``base_nu`` that fills the rest of the FEM's soil box (a field
  lift; laterally the box, so ``radius`` is not given);
* ``lateral``: ``free`` (traction-free side) or ``mould`` (a rigid, frictionless mould:
  ``u_r = 0``).

The FEM meshes the block itself (its radius and thickness replace the box's) with these
boundary conditions (:meth:`Sample.contact_settings`); the substructured fast path is kept
(the block is condensed per geometry and Poisson's ratio like the box). A lift on an
elastic subgrade is the box in two regions; the soil is then condensed per ratio of the
moduli (one operator per subgrade-to-lift ratio, not one per Poisson's ratio), so the
chain's ``fem`` wall, which shares one operator among all soil moduli, takes samples on a
rigid base only. Multi-layer profiles are the layered oracle's (``ssw.lift``).

Data layer: no heavy imports.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from ssw.errors import ConfigError

BASES = ("bonded", "sliding", "elastic")
LATERALS = ("free", "mould")


@dataclass(frozen=True)
class Sample:
    """A finite cylindrical sample (module docstring). Lengths in m.

    Parameters
    ----------
    thickness : float
        Thickness (m).
    radius : float or None
        Radius (m); None with an elastic base.
    base : str
        Bottom condition: ``bonded``, ``sliding`` or ``elastic``.
    lateral : str
        Lateral condition: ``mould`` or ``free``.
    lateral_size : str
        How the radius was obtained (a box's sides), for the record.
    base_E : float or None
        Young's modulus of an elastic base (Pa).
    base_nu : float or None
        Poisson's ratio of an elastic base.
    """

    thickness: float
    radius: float | None
    base: str = "bonded"
    lateral: str = "free"
    lateral_size: str = ""  # how the radius was obtained (a box's sides), for the record
    base_E: float | None = None  # Pa, the subgrade's (base elastic)
    base_nu: float | None = None

    def __post_init__(self) -> None:
        if self.base not in BASES:
            raise ConfigError("sample.base", self.base, " | ".join(BASES))
        elastic = self.base == "elastic"
        for name in ("thickness", "radius"):
            v = getattr(self, name)
            if name == "radius" and elastic:
                if v is not None:
                    raise ConfigError("sample.radius", v, "none for a lift on an elastic "
                                      "base (it spans the FEM's soil box)")
                continue
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise ConfigError(f"sample.{name}", v, "a length > 0 m")
        if self.lateral not in LATERALS:
            raise ConfigError("sample.lateral", self.lateral, " | ".join(LATERALS))
        if elastic:
            if not (isinstance(self.base_E, int | float) and self.base_E > 0):
                raise ConfigError("sample.base_E", self.base_E, "the subgrade's E > 0 Pa")
            if not (isinstance(self.base_nu, int | float) and -1.0 < self.base_nu <= 0.5):
                raise ConfigError("sample.base_nu", self.base_nu, "a Poisson's ratio in "
                                  "(-1, 0.5]")
        elif self.base_E is not None or self.base_nu is not None:
            raise ConfigError("sample.base_E", self.base_E, "only with base elastic")

    @property
    def key(self) -> str:
        """Short file-name-safe text for scene ids, e.g. ``h40mm-r50mm-bonded-free``
        (lengths to 1 um; two samples of a config closer than that share an id, which the
        config refuses: :func:`ssw.config.scenes`)."""
        def mm(x: float) -> str:
            return f"{round(x * 1e6) / 1e3:g}mm"

        if self.base == "elastic":
            return (f"h{mm(self.thickness)}-on-E{round(self.base_E / 1e3) / 1e3:g}MPa"
                    f"-nu{self.base_nu:g}")
        return f"h{mm(self.thickness)}-r{mm(self.radius)}-{self.base}-{self.lateral}"

    def contact_settings(self, contact: dict[str, Any]) -> dict[str, Any]:
        """The ``contact`` settings of a scene on this sample: the FEM's soil domain is the
        block (its radius and thickness) with the block's base and side conditions.

        Parameters
        ----------
        contact : dict
            The scene's ``contact`` settings.

        Returns
        -------
        dict
            A copy with the sample's domain (m, Pa) and boundary conditions.
        """
        if self.base == "elastic":  # the box, in two regions: the lift and its subgrade
            return {**contact, "subgrade_depth": float(self.thickness),
                    "subgrade_E": float(self.base_E), "subgrade_nu": float(self.base_nu)}
        return {**contact, "soil_radius": float(self.radius),
                "soil_depth": float(self.thickness), "soil_base": self.base,
                "soil_lateral": self.lateral}

    def to_dict(self) -> dict[str, Any]:
        """The sample as a plain mapping (SI), the form :func:`sample_from_dict` reads.

        Returns
        -------
        dict
            ``thickness``, ``radius`` (m), ``base``, ``lateral`` and, where they apply,
            ``base_E`` (Pa), ``base_nu`` and ``lateral_size``.
        """
        out = {"thickness": self.thickness, "radius": self.radius, "base": self.base,
               "lateral": self.lateral}
        if self.base == "elastic":
            out.update(base_E=self.base_E, base_nu=self.base_nu)
        if self.lateral_size:
            out["lateral_size"] = self.lateral_size
        return out


def equivalent_radius(side_a: float, side_b: float) -> float:
    """Radius (m) of the cylinder with the footprint area of an ``a x b`` box (m):
    ``sqrt(a b / pi)``.

    Parameters
    ----------
    side_a : float
        First side of the box (m).
    side_b : float
        Second side of the box (m).

    Returns
    -------
    float
        Equivalent radius (m).

    Raises
    ------
    ConfigError
        If a side is not > 0.
    """
    if not (side_a > 0 and side_b > 0):
        raise ConfigError("sample.box", [side_a, side_b], "two sides > 0 m")
    return math.sqrt(side_a * side_b / math.pi)


def sample_from_dict(d: dict[str, Any] | None, field: str = "sample") -> Sample | None:
    """A :class:`Sample` from a config mapping ``{thickness, radius | box: [a, b], base,
    lateral}`` (SI), or None for none (the half-space).

    Parameters
    ----------
    d : dict or None
        The config mapping (SI), or None.
    field : str
        The setting's name, for error messages.

    Returns
    -------
    Sample or None
        The sample, or None for the half-space.

    Raises
    ------
    ConfigError
        If the mapping is malformed or a value is out of range.
    """
    if d is None:
        return None
    if not isinstance(d, dict):
        raise ConfigError(field, d, "a mapping {thickness, radius or box, base, lateral}")
    unknown = set(d) - {"thickness", "radius", "box", "base", "lateral", "base_E", "base_nu"}
    if unknown:
        raise ConfigError(f"{field}.{sorted(unknown)[0]}", d[sorted(unknown)[0]],
                          "one of thickness, radius, box, base, lateral, base_E, base_nu")
    if d.get("base") == "elastic":
        try:
            return Sample(float(d.get("thickness", float("nan"))), d.get("radius"), "elastic",
                          d.get("lateral", "free"), "", d.get("base_E"), d.get("base_nu"))
        except (TypeError, ValueError) as exc:
            raise ConfigError(field, d, f"numbers in m and Pa ({exc})") from exc
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
