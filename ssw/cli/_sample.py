"""Command-line options of the sample under the plate (:mod:`ssw.sample`): a finite block
instead of the half-space, for ``ssw contact`` and every chain command (its ``fem`` wall)."""

from __future__ import annotations

import argparse

from ssw.errors import ConfigError
from ssw.sample import BASES, LATERALS, Sample, equivalent_radius


def add_sample_options(p: argparse.ArgumentParser) -> None:
    """``--sample-thickness``, ``--sample-radius`` or ``--sample-box``, ``--sample-base``,
    ``--sample-lateral`` (default: none of them, the half-space).

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser (the options are added to it).
    """
    g = p.add_argument_group("sample (default: a half-space)")
    g.add_argument("--sample-thickness", metavar="H|LO:HI",
                   help="a finite sample block of this thickness, m; a range LO:HI (ssw "
                   "measure) adds the spread of E over it to the uncertainty budget")
    g.add_argument("--sample-radius", type=float, metavar="R",
                   help="the block's radius, m (cylinder)")
    g.add_argument("--sample-box", metavar="A,B",
                   help="or its sides, m: a box taken as the cylinder of the same footprint "
                   "area, radius sqrt(A B / pi)")
    g.add_argument("--sample-base", choices=BASES, default=None,
                   help="on a rigid base, bonded (u = 0, default) or sliding (frictionless), "
                   "or elastic: a lift on a subgrade (--base-E, --base-nu; ssw contact only)")
    g.add_argument("--base-E", type=float, metavar="PA", help="the subgrade's modulus, Pa")
    g.add_argument("--base-nu", type=float, metavar="NU",
                   help="the subgrade's Poisson's ratio")
    g.add_argument("--sample-lateral", choices=LATERALS, default=None,
                   help="its side free (default) or in a rigid frictionless mould")


def thickness_range(args: argparse.Namespace) -> tuple[float, float] | None:
    """``(lo, hi)`` m of ``--sample-thickness LO:HI``; None for one thickness or none.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    tuple of (float, float) or None
        ``(lo, hi)``, m, or None.

    Raises
    ------
    ssw.errors.ConfigError
        When the range is not two numbers with ``0 < LO < HI``.
    """
    text = getattr(args, "sample_thickness", None)
    if text is None or ":" not in str(text):
        return None
    try:
        lo, hi = (float(x) for x in str(text).split(":"))
    except ValueError as exc:
        raise ConfigError("--sample-thickness", text, "H or LO:HI, m") from exc
    if not 0 < lo < hi:
        raise ConfigError("--sample-thickness", text, "0 < LO < HI, m")
    return lo, hi


def sample_of(args: argparse.Namespace, thickness: float | None = None) -> Sample | None:
    """The :class:`~ssw.sample.Sample` of the flags, or None (the half-space) when none is given; a
    thickness range gives its middle (or ``thickness``, m).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (the options of :func:`add_sample_options`).
    thickness : float or None
        m, the block's thickness instead of the flag's (None: the flag's).

    Returns
    -------
    ssw.sample.Sample or None
        The block (lengths in m), or None for the half-space.

    Raises
    ------
    ssw.errors.ConfigError
        On a malformed thickness or box, sample flags without a thickness, a radius and a
        box (or neither), a radius with an elastic base, or base values without one.
    """
    text = getattr(args, "sample_thickness", None)
    rng = thickness_range(args)
    if thickness is None and text is not None:
        try:
            thickness = 0.5 * (rng[0] + rng[1]) if rng else float(text)
        except ValueError as exc:
            raise ConfigError("--sample-thickness", text, "H or LO:HI, m") from exc
    radius = getattr(args, "sample_radius", None)
    box = getattr(args, "sample_box", None)
    others = [getattr(args, k, None) for k in ("sample_base", "sample_lateral", "base_E",
                                               "base_nu")]
    if thickness is None:
        if radius is not None or box is not None or any(o is not None for o in others):
            raise ConfigError("--sample-thickness", None,
                              "a thickness (m) with the other --sample-* flags")
        return None
    if others[0] == "elastic":
        if radius is not None or box is not None:
            raise ConfigError("--sample-radius", radius if box is None else box,
                              "none with --sample-base elastic (the lift spans the soil box)")
        return Sample(float(thickness), None, "elastic", others[1] or "free", "",
                      others[2], others[3])
    if others[2] is not None or others[3] is not None:
        raise ConfigError("--base-E", others[2], "only with --sample-base elastic")
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
