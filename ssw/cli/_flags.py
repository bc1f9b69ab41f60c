"""The device, model and wall-law flags of every chain command, in ONE table.

``ssw calibrate`` and every command that reads a calibration (``tof``, ``tof-sweep``,
``invert``, ``chain``, ``validate``, ``measure``, ``acquire``, ``tof-recording``, ``lift``,
``design``; the workflow's rules call them) take the same flags, defined here once
(:data:`FLAGS`): each flag's option, the field it sets (a :class:`ssw.device.Device` field,
a :class:`ssw.chain.params.ChainParams` field, or an option of the wall law), and whether
it is part of what a calibration is made with (``calibrated``).

* ``ssw calibrate`` applies every flag it accepts to the model it calibrates and records it
  (the device, the ChainParams ``numerics`` and the wall law in the calibration file), and
  refuses by name a flag it cannot honour (:func:`refuse_for_calibration`);
* a command given a calibration runs the calibrated model: a flag it is given must agree
  with what the calibration was made with when the flag is ``calibrated``; otherwise it is
  refused, naming the flag and the calibrated value (:func:`contradictions`). A flag that
  repeats the calibration's value is accepted (the same flags work for ``calibrate`` and
  its consumers). Flags not ``calibrated`` (the time step, the tested medium's density)
  change freely.

The tested sample's flags (``--sample-*``, :mod:`ssw.cli._sample`) describe the block under
the plate, not the device: any calibration applies to any sample.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ssw.chain.dissipation import LAWS as DISSIPATION_LAWS
from ssw.errors import ConfigError

#: Where a flag's value goes.
DEVICE, MODEL, WALL = "device", "model", "wall"
#: Relative difference beyond which two values of a float flag contradict each other (a
#: value the calibration file printed with its 17 digits and typed back is the same value).
SAME_REL = 1e-9
GROUPS = {DEVICE: "device fields (override the device's)", MODEL: "numerics and model",
          WALL: "wall law (the last contact)"}


@dataclass(frozen=True)
class Flag:
    """One command-line flag of the chain commands.

    Parameters
    ----------
    option : str
        The flag (``--bead-E``).
    target : str
        ``device`` (a :class:`ssw.device.Device` field), ``model`` (a
        :class:`ssw.chain.params.ChainParams` field beyond the device's) or ``wall`` (the
        wall law and its options).
    field : str
        The field or wall option it sets (``drop_height`` sets the striker speed).
    calibrated : bool
        Part of what a calibration is made with: recorded in it, and a consumer of the
        calibration refuses another value.
    help : str
        The flag's help text.
    type : callable or None
        argparse's ``type`` (None: text).
    choices : tuple or None
        The allowed values.
    const : object
        For a flag without a value (``--uniform``, ``--no-gravity``): the field's value
        when it is given (None: the flag takes a value).
    metavar : str or None
        argparse's ``metavar``.
    """

    option: str
    target: str
    field: str
    calibrated: bool
    help: str
    type: Callable[[str], Any] | None = None
    choices: tuple[str, ...] | None = None
    const: Any = None
    metavar: str | None = None

    @property
    def dest(self) -> str:
        """The argparse attribute (``--bead-E`` -> ``bead_E``; ``--law`` -> ``wall``)."""
        return "wall" if self.option == "--law" else self.option[2:].replace("-", "_")

    def value(self, args: argparse.Namespace) -> Any:
        """The field's value the flag gives in ``args``, or None when it is not given.

        Parameters
        ----------
        args : argparse.Namespace
            The parsed command line.

        Returns
        -------
        Any
            The field's value (SI units), or None.
        """
        v = getattr(args, self.dest, None)
        if self.const is not None:
            return self.const if v else None
        return v


#: Every device, model and wall flag of the chain's commands (module docstring).
FLAGS: tuple[Flag, ...] = (
    # ---- device fields
    Flag("--beads", DEVICE, "beads", True, "beads including the striker (bead 0); keeps the "
         "beads below the sensor unless --sensor-index is given", int),
    Flag("--sensor-index", DEVICE, "sensor_index", True,
         "0-based index of the sensor particle", int),
    Flag("--sensor-mass", DEVICE, "sensor_mass", True, "sensor particle mass, kg", float),
    Flag("--sensor-reads", DEVICE, "sensor_reads", True,
         "force the sensor reads: mean of its two contacts, upper or lower",
         choices=("mean", "upper", "lower")),
    Flag("--striker-mass", DEVICE, "striker_mass", True, "striker mass, kg", float),
    Flag("--striker-velocity", DEVICE, "striker_velocity", True,
         "striker speed at contact, m/s", float),
    Flag("--drop-height", DEVICE, "drop_height", True,
         "striker dropped from this height, m (speed sqrt(2 g h))", float),
    Flag("--preload", DEVICE, "preload", True, "constant force on bead 1, N", float),
    Flag("--bead-radius", DEVICE, "bead_radius", True, "bead radius, m", float),
    Flag("--bead-material", DEVICE, "bead_material", True,
         "bead material key (materials library: its density, E and nu; --bead-density, "
         "--bead-E, --bead-nu must agree with it)"),
    Flag("--plate-material", DEVICE, "plate_material", True,
         "plate material key (materials library)"),
    Flag("--plate-thickness", DEVICE, "plate_thickness", True,
         "plate thickness, m (0: no plate)", float),
    Flag("--plate-diameter", DEVICE, "plate_diameter", True, "plate diameter, m", float),
    Flag("--plate-interface", DEVICE, "plate_interface", True,
         "how the plate sits on the medium", choices=("frictionless", "bonded", "unilateral")),
    # ---- ChainParams beyond the device
    Flag("--uniform", MODEL, "uniform", True,
         "the sensor is a plain bead (its mass is ignored)", const=True),
    Flag("--no-gravity", MODEL, "gravity", True, "no gravity, no precompression",
         const=False),
    Flag("--bead-density", MODEL, "bead_density", True, "bead density, kg/m^3", float),
    Flag("--bead-E", MODEL, "bead_E", True, "bead Young's modulus, Pa", float),
    Flag("--bead-nu", MODEL, "bead_nu", True, "bead Poisson's ratio", float),
    Flag("--damping", MODEL, "damping", True, "the contacts' dissipation coefficient, in "
         "the unit of the law (--damping-law: dashpot N s/m, kuwabara_kono N s/m^1.5, "
         "hunt_crossley s/m); default: the device's (dissipation: in its file), else the "
         "config's chain.damping", float),
    Flag("--damping-law", MODEL, "damping_law", True, "the contacts' dissipation law: "
         "dashpot c d', kuwabara_kono c sqrt(d) d', hunt_crossley c F_el(d) d' (default: the "
         "device's)", choices=tuple(DISSIPATION_LAWS)),
    Flag("--steps-per-contact", MODEL, "steps_per_contact", False,
         "time steps per Hertz contact time (the discretization: a calibration's consumer "
         "may refine it)", int),
    # ---- the wall law
    Flag("--law", WALL, "law", True, "last-contact law (default: the calibration's, else the "
         "config's chain.wall_law)"),
    Flag("--K", WALL, "K", True, "fit wall: a constant K instead of --k-table", float),
    Flag("--fit-law", MODEL, "fit_law", True,
         "fit wall: the law read from the K table (default: config fit.law)",
         choices=("k_hertz", "power")),
    Flag("--k-table", WALL, "k_table", False, "fit wall: K table HDF5 (default "
         "results/fit/sets/<fit.set>/k_table.h5; under a calibration: where its table is "
         "found, e.g. a workflow job's input)"),
    Flag("--curve", WALL, "curve", True,
         "table wall: one FEM contact curve HDF5 for every scene"),
    Flag("--contact-dir", WALL, "contact_dir", True, "table wall without --curve: the "
         "contact curves' folder (<family>/<scene_id>.h5, as the workflow writes them; "
         "default results/contact)"),
    Flag("--wall-dynamics", WALL, "dynamics", True,
         "the tested medium's inertia: quasi-static (the static law, default: the config's "
         "chain.wall_dynamics), reduced (plus its radiation damping and participating mass, "
         "ssw.dynamics.reduced), fem (the elastodynamic FEM wall: ssw tof only, about a "
         "minute per point)", choices=("quasi-static", "reduced", "fem")),
    Flag("--soil-density", WALL, "soil_density", False, "density of the tested medium, "
         "kg/m^3 (reduced or fem dynamics; default: the config's chain.soil_density)", float),
)
BY_OPTION = {f.option: f for f in FLAGS}


def add_flags(p: argparse.ArgumentParser, walls: tuple[str, ...]) -> None:
    """Every flag of :data:`FLAGS` in its group (``--law`` choosing among ``walls``).

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser (the flags are added to it).
    walls : tuple of str
        The wall laws ``--law`` accepts.
    """
    groups = {t: p.add_argument_group(title) for t, title in GROUPS.items()}
    for f in FLAGS:
        g = groups[f.target if f.field != "fit_law" else WALL]
        names = [f.option] + (["--wall"] if f.option == "--law" else [])
        if f.const is not None:
            g.add_argument(*names, dest=f.dest, action="store_true", default=None, help=f.help)
            continue
        choices = list(walls) if f.option == "--law" else f.choices
        g.add_argument(*names, dest=f.dest, type=f.type, choices=choices, metavar=f.metavar,
                       help=f.help)


def given(args: argparse.Namespace, target: str | None = None) -> dict[Flag, Any]:
    """The flags given in ``args`` (of ``target`` only, if given) and their field values.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    target : str or None
        ``device``, ``model`` or ``wall``; None: every flag.

    Returns
    -------
    dict of Flag to Any
        Each flag given and its field's value (SI units).
    """
    out = {}
    for f in FLAGS:
        v = f.value(args)
        if v is not None and (target is None or f.target == target):
            out[f] = v
    return out


def fields_of(args: argparse.Namespace, target: str) -> dict[str, Any]:
    """``{field: value}`` of the ``target``'s flags given in ``args``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    target : str
        ``device``, ``model`` or ``wall``.

    Returns
    -------
    dict of str to Any
        Field name to value (SI units).
    """
    return {f.field: v for f, v in given(args, target).items()}


def same(a: Any, b: Any) -> bool:
    """Two values of a flag agree (floats within :data:`SAME_REL`).

    Parameters
    ----------
    a : Any
        One value.
    b : Any
        The other.

    Returns
    -------
    bool
        Whether they agree: numbers within the relative :data:`SAME_REL`, others equal.
    """
    if isinstance(a, bool) or isinstance(b, bool) or a is None or b is None:
        return a == b
    if isinstance(a, int | float | np.floating) and isinstance(b, int | float | np.floating):
        return bool(np.isclose(float(a), float(b), rtol=SAME_REL, atol=0.0))
    return a == b


def calibrated_value(flag: Flag, cal: Any) -> Any:
    """What the calibration ``cal`` was made with for ``flag``'s field (the calibrated
    device's field, its ChainParams' field, its wall law or a wall option; the striker
    speed for ``--drop-height``).

    Parameters
    ----------
    flag : Flag
        The flag.
    cal : ssw.calibration.Calibration
        The calibration.

    Returns
    -------
    Any
        The calibrated value (SI units; m/s for ``--drop-height``), or None for a wall
        option it does not state.
    """
    if flag.target == DEVICE:
        return getattr(cal.device, "striker_velocity" if flag.field == "drop_height"
                       else flag.field)
    if flag.target == MODEL:
        return getattr(cal.chain_params(), flag.field)
    if flag.field == "law":
        return cal.wall["law"]
    opts = cal.wall.get("options", {})
    if flag.field == "dynamics":
        return opts.get("dynamics") or "quasi-static"
    return opts.get(flag.field)


def contradictions(args: argparse.Namespace, cal: Any) -> None:
    """ConfigError naming the first flag of ``args`` that contradicts the calibration
    ``cal`` (a ``calibrated`` flag whose value differs from the calibration's), with the
    calibrated value; none when every flag agrees with it.

    Parameters
    ----------
    args : argparse.Namespace
        The command's parsed flags.
    cal : ssw.calibration.Calibration
        The calibration the command reads.

    Raises
    ------
    ConfigError
        Naming the flag, its value, the calibrated value and the way out.
    """
    from ssw.device import STANDARD_GRAVITY

    where = cal.path or "the calibration"
    for f, v in given(args).items():
        if not f.calibrated:
            continue
        mine = float(np.sqrt(2.0 * STANDARD_GRAVITY * v)) if f.field == "drop_height" else v
        theirs = calibrated_value(f, cal)
        if same(mine, theirs):
            continue
        name = "striker_velocity" if f.field == "drop_height" else f.field
        if name in cal.free:
            raise ConfigError(f.option, v, f"{where} identified {name} = {theirs:.6g}: "
                              "--calibration none to set it")
        flag = f.option if f.const is not None else f"{f.option} {v}"
        raise ConfigError(f.option, True if f.const is not None else v,
                          f"{where} was made with {name} = {theirs!r}: --calibration none "
                          f"to change it, or recalibrate with {flag}")


def refuse_for_calibration(args: argparse.Namespace, free: tuple[str, ...]) -> None:
    """ConfigError for a flag ``ssw calibrate`` cannot honour: one that sets a parameter it
    identifies (``free``), ``--uniform`` with the sensor's mass free, the dynamic FEM wall
    (``ssw tof`` alone runs it), or a table wall's curves (a calibration needs a law at any
    modulus).

    Parameters
    ----------
    args : argparse.Namespace
        ``ssw calibrate``'s parsed flags.
    free : tuple of str
        The parameters it identifies.

    Raises
    ------
    ConfigError
        Naming the flag.
    """
    for f, v in given(args).items():
        name = "striker_velocity" if f.field == "drop_height" else f.field
        if f.target == DEVICE and name in free:
            raise ConfigError(f.option, v, f"none with --free {name}: the calibration "
                              f"identifies it (the device file's value is the scan's "
                              f"tie-break; --range {name}=LO:HI bounds its search)")
        if f.field in ("curve", "contact_dir"):
            raise ConfigError(f.option, v, "none: a calibration needs a law at any modulus "
                              "(--law fem | hertz | fit | rigid), not the table wall's curves")
        if f.field == "dynamics" and v == "fem":
            raise ConfigError(f.option, v, "quasi-static | reduced for a calibration (the "
                              "dynamic FEM wall runs in ssw tof alone)")
    if "sensor_mass" in free and BY_OPTION["--uniform"].value(args):
        raise ConfigError("--free", "sensor_mass", "not with --uniform (the sensor is then a "
                          "plain bead: its mass has no effect)")
