"""Command-line options shared by every command that runs the chain: the study config, the
device, its calibration, flags overriding single device fields, and the wall law.

Resolution (the same for ``ssw tof``, ``tof-sweep``, ``invert``, ``calibrate``, ``validate``,
``measure`` and ``acquire``, so that a standalone command and the workflow give the same number
for the same inputs):

1. the config: ``--config`` or ``config/config.yaml`` of the working folder, else the
   defaults shipped with ssw;
2. the calibration: ``--calibration FILE``; by default (``auto``, or the environment's
   ``SSW_CALIBRATION``: a file, ``auto`` or ``none``) the study's
   ``results/calibration/calibration.json`` when the config's ``calibration.use`` is true
   and that file exists in the working folder; ``none`` for the uncalibrated device;
3. the device: the calibration's (calibrated) device, else ``--device`` (a YAML file or a
   shipped device's name), else the config's ``device:``; device flags (``--beads``,
   ``--striker-velocity``, ``--preload``, ...) override single fields;
4. numerics and model (time steps, gravity, bead material, uniform sensor, fit law): the
   calibration's, else the config's; flags override. The contacts' dissipation (its law
   and coefficient) is the device's (its ``dissipation:``), replaced by the calibration's,
   else by the config's ``chain.damping`` when not null, then by ``--damping`` and
   ``--damping-law``;
5. the wall law and its dynamics: the calibration's, else ``--law``, else the config's
   ``chain.wall_law`` (and ``chain.wall_dynamics``).

The flags of steps 3-5 are ONE table, :data:`ssw.cli._flags.FLAGS`: under a calibration a
flag that contradicts what it was made with is refused, naming the flag and the calibrated
value (:func:`ssw.cli._flags.contradictions`); one that repeats it is accepted.
"""

from __future__ import annotations

import argparse
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ssw.cli._flags import DEVICE, MODEL, add_flags, contradictions, fields_of
from ssw.errors import ConfigError

DEFAULT_CONTACT_DIR = "results/contact"
#: Environment variable giving the default of ``--calibration`` (a file, auto or none).
CALIBRATION_ENV = "SSW_CALIBRATION"
#: The study's calibration file (rule calibration), relative to the working folder.
STUDY_CALIBRATION = "results/calibration/calibration.json"
WALL_CHOICES = ("rigid", "hertz", "fit", "table", "fem")


def add_device_options(p: argparse.ArgumentParser,
                       walls: tuple[str, ...] = WALL_CHOICES) -> None:
    """Config, device, calibration, device-field and wall options.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser (the options are added to it).
    walls : tuple of str
        The wall laws ``--law`` accepts.
    """
    from ssw.cli._sample import add_sample_options

    add_sample_options(p)
    g = p.add_argument_group("device and calibration")
    g.add_argument("--config", help="study config YAML (default: config/config.yaml of the "
                   "working folder if any, else ssw's defaults)")
    g.add_argument("--device", help="device YAML file or shipped device name (default: the "
                   "config's device, thesis)")
    g.add_argument("--calibration", default=os.environ.get(CALIBRATION_ENV) or "auto",
                   metavar="FILE|auto|none",
                   help=f"calibration file of `ssw calibrate` (default ${CALIBRATION_ENV}, "
                   f"else auto: the study's {STUDY_CALIBRATION} when present and the "
                   "config's calibration.use)")
    add_flags(p, walls)


@dataclass(frozen=True)
class ChainContext:
    """What a chain command runs: config, device, calibration, ChainParams, wall law.

    Parameters
    ----------
    cfg : dict of str to Any
        The study config.
    device : ssw.device.Device
        The device (the calibration's when there is one).
    calibration : ssw.calibration.Calibration or None
        The calibration applied, or None.
    params : ssw.chain.params.ChainParams
        The chain (SI units).
    wall : str
        The last contact's law (``rigid``, ``hertz``, ``fit``, ``table`` or ``fem``; empty
        for a numerics-only context).
    wall_options : dict of str to Any
        The wall law's options (with the tested sample's contact settings).
    sample : ssw.sample.Sample or None
        The tested sample; None: a half-space.
    device_wall_options : dict of str to Any or None
        The wall options without the sample (what a calibration records).
    """

    cfg: dict[str, Any]
    device: Any
    calibration: Any
    params: Any
    wall: str
    wall_options: dict[str, Any]
    # the tested sample (ssw.sample.Sample; None: a half-space) and the wall options
    # without it (what a calibration records: its sample belongs to its references)
    sample: Any = None
    device_wall_options: dict[str, Any] | None = None

    def inputs(self) -> dict[str, Any]:
        """Provenance for --json and output files.

        Returns
        -------
        dict of str to Any
            The device's name, source and values (SI units), the calibration file, the
            wall and its options (objects named by their type, the curve left out).
        """
        return {
            "device_name": self.device.name, "device_source": self.device.source,
            "device_values": self.device.physics_dict(),
            "calibration_file": None if self.calibration is None else self.calibration.path,
            "wall": self.wall,
            "wall_options": {k: (v if isinstance(v, str | int | float | bool | None)
                                 else str(type(v).__name__)) for k, v in
                             self.wall_options.items() if k != "curve"},
        }


def resolve_calibration(spec: str | None, cfg: dict[str, Any]) -> Any:
    """The calibration of ``--calibration`` (see the module docstring) or None.

    Parameters
    ----------
    spec : str or None
        ``--calibration``: a file, ``auto`` (or None) or ``none``.
    cfg : dict of str to Any
        The study config (its ``calibration.use``).

    Returns
    -------
    ssw.calibration.Calibration or None
        The calibration loaded, or None (``none``; ``auto`` without the study's file or
        with ``calibration.use`` false).
    """
    from ssw.calibration import load_calibration

    if spec is None or spec == "auto":
        if cfg.get("calibration", {}).get("use", True) and Path(STUDY_CALIBRATION).is_file():
            return load_calibration(STUDY_CALIBRATION)
        return None
    if spec == "none":
        return None
    return load_calibration(spec)


def check_device(cal: Any, device: Any, materials: dict[str, Any], spec: str | None) -> None:
    """Refuse a calibration made for another device than the command's.

    Parameters
    ----------
    cal : ssw.calibration.Calibration
        The calibration.
    device : ssw.device.Device
        The command's device: ``--device``, else the config's with ``--calibration auto``,
        else the calibration's own, with the device flags of parameters it did not identify
        applied.
    materials : dict
        The command's materials library (key -> Material).
    spec : str or None
        The ``--calibration`` argument (``auto``: the study's calibration).

    Raises
    ------
    ssw.provenance.ProvenanceError
        Unless the device digests agree (``ssw.provenance.require_match``), naming both
        sides.
    """
    from ssw.calibration.file import device_digest
    from ssw.provenance import require_match

    where = cal.path or "the calibration"
    made_for = cal.device_sha256 or device_digest(cal.device_nominal, cal.materials())
    mine = device_digest(device, materials)
    if made_for != mine:
        diff = {k: (v, device.physics_dict().get(k))
                for k, v in cal.device_nominal.physics_dict().items()
                if device.physics_dict().get(k) != v and k not in cal.free}
        detail = ", ".join(f"{k}: {a!r} there, {b!r} here" for k, a, b in
                           ((k, *ab) for k, ab in diff.items())) or "the materials' values"
        how = ("the study's calibration (--calibration auto)" if spec in (None, "auto")
               else where)
        require_match(f"the device ({detail}); {how} does not apply: --calibration none, or "
                      "recalibrate for this device; the device digest",
                      (f"calibration {where} (device {cal.device_nominal.name})", made_for),
                      (f"this command's device {device.name}", mine))


def check_bead_material(key: str, over: dict[str, Any], materials: dict[str, Any]) -> None:
    """Refuse a bead material named by ``--bead-material`` that the explicit bead values
    (``--bead-density``, ``--bead-E``, ``--bead-nu``) contradict.

    Parameters
    ----------
    key : str
        The material key (``--bead-material``).
    over : dict
        The model flags given (``bead_density`` kg/m^3, ``bead_E`` Pa, ``bead_nu``).
    materials : dict
        The materials library (key -> Material).

    Raises
    ------
    ConfigError
        An unknown key (naming the library's), or a value that differs from the
        material's by more than :data:`ssw.cli._flags.SAME_REL`.
    """
    from ssw.cli._flags import same

    if key not in materials:
        raise ConfigError("--bead-material", key,
                          f"a material of the library: {', '.join(sorted(materials))}")
    m = materials[key]
    for field, flag, mine in (("bead_density", "--bead-density", m.density),
                              ("bead_E", "--bead-E", m.E), ("bead_nu", "--bead-nu", m.nu)):
        if field in over and not same(over[field], mine):
            raise ConfigError(flag, over[field],
                              f"{mine!r}, the value of --bead-material {key} (drop one of "
                              "the two: the material names the beads' values)")


def chain_context(args: argparse.Namespace, E: Any = 1.0e8, nu: Any = 0.3,
                  numerics_only: bool = False) -> ChainContext:
    """Resolve config, calibration, device, params and wall (module docstring).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (the options of :func:`add_device_options`).
    E : float or numpy.ndarray
        Pa, the soil moduli the ``table`` wall needs curves of.
    nu : float or numpy.ndarray
        The soils' Poisson's ratios (-), likewise.
    numerics_only : bool
        Resolve config, calibration, device and params only (no wall, no sample).

    Returns
    -------
    ChainContext
        What the command runs.

    Raises
    ------
    ssw.errors.ConfigError
        On contradicting flags (``--drop-height`` with ``--striker-velocity``, a flag
        against the calibration, ``--bead-material`` against bead values), a thickness
        range where one thickness is needed, a sample without the fem wall, or wall
        dynamics without the soil's density.
    ssw.provenance.ProvenanceError
        When the calibration was made for another device.
    """
    from ssw.chain.params import chain_params, numerics_of
    from ssw.cli._sample import sample_of, thickness_range
    from ssw.config import device_of, library, load_config
    from ssw.device import load_device

    cfg = load_config(getattr(args, "config", None))
    spec = getattr(args, "calibration", "auto")
    cal = resolve_calibration(spec, cfg)
    named = load_device(args.device) if getattr(args, "device", None) else None
    changes = fields_of(args, DEVICE)
    if "drop_height" in changes and "striker_velocity" in changes:
        raise ConfigError("--drop-height", changes["drop_height"], "not with --striker-velocity")
    over = fields_of(args, MODEL)
    if cal is not None:
        contradictions(args, cal)
        base = named if named is not None else (device_of(cfg) if spec in (None, "auto")
                                                else cal.device_nominal)
        # the flags agree with the calibration (above); those of parameters it did not
        # identify also say which device the command means
        fixed = {k: v for k, v in changes.items()
                 if ("striker_velocity" if k == "drop_height" else k) not in cal.free}
        check_device(cal, base.with_(**fixed) if fixed else base,
                     library(cfg) if named is not None or spec in (None, "auto")
                     else cal.materials(), spec)
        device = cal.device
    else:
        device = named if named is not None else device_of(cfg)
        if changes:
            device = device.with_(**changes)
    numerics = dict(cal.numerics) if cal is not None else numerics_of(cfg)
    numerics.update(over)
    mats = cal.materials() if cal is not None else library(cfg)
    if "bead_material" in changes:
        check_bead_material(changes["bead_material"], over, mats)
    params = chain_params(device, mats, **numerics)
    if numerics_only:
        return ChainContext(cfg, device, cal, params, "", {})
    wall, opts = wall_law(args, cfg, cal, params, E, nu)
    plain = dict(opts)
    if thickness_range(args) is not None and not getattr(args, "thickness_range_ok", False):
        raise ConfigError("--sample-thickness", args.sample_thickness,
                          "one thickness H, m (a range LO:HI is ssw measure's budget term)")
    sample = sample_of(args)
    if sample is not None:  # the tested block, not the device: any calibration applies
        if wall != "fem":
            raise ConfigError("--sample-thickness", sample.thickness,
                              f"the fem wall (--law fem; this command's wall is {wall})")
        opts = {**opts, "contact": sample.contact_settings(opts.get("contact") or
                                                           dict(cfg.get("contact", {})))}
    # a calibration's wall dynamics, else the config's (a contradicting flag is refused)
    dyn = getattr(args, "wall_dynamics", None) or opts.pop("dynamics", None) or (
        "quasi-static" if cal is not None
        else cfg.get("chain", {}).get("wall_dynamics", "quasi-static"))
    rho = getattr(args, "soil_density", None)
    rho = rho if rho is not None else opts.pop("soil_density", None)
    rho = rho if rho is not None else cfg.get("chain", {}).get("soil_density")
    if dyn == "reduced":
        if rho is None:
            raise ConfigError("--soil-density", None,
                              "the tested medium's density (kg/m^3) for --wall-dynamics reduced")
        opts = {**opts, "dynamics": "reduced", "soil_density": float(rho)}
        plain = {**plain, "dynamics": "reduced", "soil_density": float(rho)}
    elif dyn == "fem":
        if rho is None:
            raise ConfigError("--soil-density", None,
                              "the tested medium's density (kg/m^3) for --wall-dynamics fem")
        opts = {**opts, "dynamics": "fem", "soil_density": float(rho)}
        plain = {**plain, "dynamics": "fem", "soil_density": float(rho)}
    return ChainContext(cfg, device, cal, params, wall, opts, sample, plain)


def contact_for_bead(cfg: dict[str, Any], bead_radius: float) -> dict[str, Any]:
    """The config's ``contact:`` settings for a bead of radius ``bead_radius`` (m): their
    lengths (:data:`ssw.design.device_eval.CONTACT_LENGTHS`) are those of the config's
    device's bead, scaled by ``bead_radius`` over its radius, so that a device scaled in
    every length meshes alike in its own units (the device design's meshes:
    :func:`ssw.design.device_eval.scaled_contact`). The config's own device: unchanged.

    Parameters
    ----------
    cfg : dict
        The study config.
    bead_radius : float
        m, the command's bead radius.

    Returns
    -------
    dict
        The settings (a copy).
    """
    from ssw.config import device_of
    from ssw.design.device_eval import scaled_contact

    contact = dict(cfg.get("contact", {}))
    own = device_of(cfg).bead_radius
    return contact if bead_radius == own else scaled_contact(contact, bead_radius / own)


def wall_law(args: argparse.Namespace, cfg: dict[str, Any], cal: Any, params: Any,
             E: Any, nu: Any) -> tuple[str, dict[str, Any]]:
    """The last-contact law and its options (module docstring, step 5).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (``--law``, ``--K``, ``--k-table``, ``--curve``,
        ``--contact-dir``).
    cfg : dict of str to Any
        The study config.
    cal : ssw.calibration.Calibration or None
        The calibration, whose law and options win.
    params : ssw.chain.params.ChainParams
        The chain (its bead radius, m, and plate).
    E : float or numpy.ndarray
        Pa, the soil moduli whose curves the ``table`` law reads.
    nu : float or numpy.ndarray
        The soils' Poisson's ratios (-), likewise.

    Returns
    -------
    tuple of (str, dict of str to Any)
        The law's name and its options.
    """
    given = getattr(args, "wall", None)
    if cal is not None:  # its law and options (a contradicting flag is refused before)
        law = cal.wall["law"]
        opts = {k: v for k, v in cal.wall.get("options", {}).items()}
        if law == "fit" and "k_table" in opts and args.k_table:
            opts["k_table"] = args.k_table
        return law, opts
    law = given or cfg.get("chain", {}).get("wall_law", "hertz")
    if law == "fit":
        if args.K is not None:
            return law, {"K": args.K}
        from ssw.workflow import k_table_file

        return law, {"k_table": args.k_table or k_table_file(cfg)}
    if law == "fem":
        return law, {"contact": contact_for_bead(cfg, params.bead_radius)}
    if law == "table":
        if args.curve:
            return law, {"curve": args.curve}
        from ssw.config import Scene
        from ssw.workflow import scene_file

        Eb, nub = np.broadcast_arrays(np.asarray(E, float), np.asarray(nu, float))
        folder = args.contact_dir or DEFAULT_CONTACT_DIR
        paths = [scene_file(folder, Scene(params.plate_material, params.plate_thickness,
                                          float(e), float(n)).scene_id)
                 for e, n in zip(Eb.ravel(), nub.ravel(), strict=True)]
        return law, {"curve": paths}
    return law, {}
