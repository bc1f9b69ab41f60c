"""Command-line options of the sample under the plate (:mod:`ssw.sample`): a finite block
instead of the half-space, for ``ssw contact`` and every chain command (its ``fem`` wall)."""

from __future__ import annotations

import argparse

from ssw.errors import ConfigError
from ssw.sample import BASES, LATERALS, Sample, equivalent_radius


def add_sample_options(p: argparse.ArgumentParser) -> None:
    """``--sample-thickness``, ``--sample-radius`` or ``--sample-box``, ``--sample-base``,
    ``--sample-lateral`` (default: none of them, the half-space)."""
    g = p.add_argument_group("sample (default: a half-space)")
    g.add_argument("--sample-thickness", type=float, metavar="H",
                   help="a finite sample block of this thickness, m")
    g.add_argument("--sample-radius", type=float, metavar="R",
                   help="the block's radius, m (cylinder)")
    g.add_argument("--sample-box", metavar="A,B",
                   help="or its sides, m: a box taken as the cylinder of the same footprint "
                   "area, radius sqrt(A B / pi)")
    g.add_argument("--sample-base", choices=BASES, default=None,
                   help="on a rigid base, bonded (u = 0, default) or sliding (frictionless)")
    g.add_argument("--sample-lateral", choices=LATERALS, default=None,
                   help="its side free (default) or in a rigid frictionless mould")


def sample_of(args: argparse.Namespace) -> Sample | None:
    """The :class:`Sample` of the flags, or None (the half-space) when none is given."""
    thickness = getattr(args, "sample_thickness", None)
    radius = getattr(args, "sample_radius", None)
    box = getattr(args, "sample_box", None)
    others = [getattr(args, k, None) for k in ("sample_base", "sample_lateral")]
    if thickness is None:
        if radius is not None or box is not None or any(o is not None for o in others):
            raise ConfigError("--sample-thickness", None,
                              "a thickness (m) with the other --sample-* flags")
        return None
    if (radius is None) == (box is None):
        raise ConfigError("--sample-radius", radius, "a radius (m) or --sample-box A,B, one")
    size = ""
    if box is not None:
        try:
            a, b = (float(x) for x in box.split(","))
        except ValueError as exc:
            raise ConfigError("--sample-box", box, "two sides A,B in m") from exc
        radius = equivalent_radius(a, b)
        size = f"box {a:g} x {b:g} m -> radius sqrt(a b / pi)"
    return Sample(float(thickness), float(radius), others[0] or "bonded",
                  others[1] or "free", size)
