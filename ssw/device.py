"""The SSW device as a first-class object: one instrument, described in one YAML file.

A device holds everything physical about one instrument (schema
``ssw/data/device.schema.yaml``): the chain (bead count, material, radius, any preload on its
top), the sensor particle (position, mass, which force it reads), the striker (mass, speed or
drop height), the plate under the last bead (material, thickness, diameter, interface), the
DAQ force sensor (model, sensitivity, range) and the dissipation of its contacts (a law and
its coefficient: the source of truth of the chain's ``damping``; a study config's
``chain.damping`` or the ``--damping`` flag replaces the coefficient, ``--damping-law`` the
law). The thesis's device is the default
(``ssw/data/devices/thesis.yaml``, linked from ``config/devices/``).

Devices are found by path, or by name among the shipped devices. Study configs name one
(``device:``); the command line takes ``--device FILE`` and individual flags override its
fields (:meth:`Device.with_`). The device is data: :func:`ssw.chain.params.chain_params`
turns a device and the numerics of a study into the ``ChainParams`` the integrator runs.

Calibratable parameters (:data:`PARAMETERS`) are device fields that ``ssw calibrate`` may
identify from measured TOFs: continuous ones (striker speed, preload, masses) and integer
ones (the bead count, scanned).
"""

from __future__ import annotations

import copy
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from ssw.errors import ConfigError
from ssw.yamlio import safe_load

DATA = Path(__file__).resolve().parent / "data"
SCHEMA_PATH = DATA / "device.schema.yaml"
DEVICES_DIR = DATA / "devices"
#: The device a command uses when none is named.
DEFAULT_DEVICE = "thesis"
#: Standard gravity, m/s^2 (CGPM 1901), for the drop height.
STANDARD_GRAVITY = 9.80665
#: V, the input range of the DAQ module (NI 9234: +-5 V; REFERENCE.md).
DAQ_RANGE_V = 5.0
#: The contacts' dissipation laws a device may state (the chain implements each:
#: :data:`ssw.chain.dissipation.LAWS`, which holds their units and formulas).
DISSIPATION_LAWS = ("dashpot", "kuwabara_kono", "hunt_crossley")


@dataclass(frozen=True)
class Device:
    """One SSW instrument. SI units; the YAML layout is nested (:meth:`to_dict`).

    Parameters
    ----------
    name : str
        The device's name (identification only).
    beads : int
        Beads including the striker (bead 0) and the bead on the plate (>= 3).
    bead_material : str
        Material key of the beads (materials library).
    bead_radius : float
        m, radius of every bead.
    preload : float
        N, constant downward force on bead 1 (top of the resting column), >= 0.
    sensor_index : int
        0-based index of the sensor particle from the striker, 1 .. ``beads - 2``.
    sensor_mass : float or None
        kg, mass of the sensor particle; ``None``: a bead's mass.
    sensor_reads : str
        Which force the sensor reads: ``mean`` | ``upper`` | ``lower``.
    striker_mass : float or None
        kg, mass of the striker; ``None``: a bead's mass.
    striker_velocity : float
        m/s, the striker's speed at first contact.
    plate_material : str
        Material key of the plate under the last bead, or ``none``.
    plate_thickness : float
        m, thickness of the plate (0: no plate).
    plate_diameter : float
        m, diameter of the plate.
    plate_interface : str
        How the plate meets the sample: ``frictionless`` | ``bonded`` | ``unilateral``.
    sensor_model : str
        The DAQ force sensor's model (text).
    sensitivity : float
        V/N, the force sensor's sensitivity.
    sensor_range : float
        N, the force sensor's measuring range.
    dissipation_law : str
        The contacts' dissipation law (:data:`DISSIPATION_LAWS`): ``dashpot`` ``c d'``,
        ``kuwabara_kono`` ``c sqrt(d) d'``, ``hunt_crossley`` ``c F_el(d) d'``.
    dissipation : float
        Its coefficient ``c`` >= 0 in the law's unit (N s/m, N s/m^1.5, s/m; 0:
        conservative).
    tof_scatter : float or None
        s, the stated standard deviation of one hit's TOF on a uniform sample (None: not
        stated).
    tof_scatter_source : str
        Where ``tof_scatter`` comes from.
    striker_mass_std : float or None
        kg, the stated standard uncertainty of the striker's mass as weighed (the prior of
        calibrations of records, :func:`ssw.calibration.hits.device_priors`; None: not
        stated, 5 % of the mass).
    description : str
        Free text describing the device.
    source : str
        Where the device was read from (not part of its physics).

    Raises
    ------
    ssw.errors.ConfigError
        A field out of its allowed range, naming its place in the YAML layout.
    """

    name: str
    beads: int
    bead_material: str
    bead_radius: float
    preload: float
    sensor_index: int
    sensor_mass: float | None
    sensor_reads: str
    striker_mass: float | None
    striker_velocity: float
    plate_material: str
    plate_thickness: float
    plate_diameter: float
    plate_interface: str
    sensor_model: str
    sensitivity: float
    sensor_range: float
    dissipation_law: str = "dashpot"
    dissipation: float = 0.0
    tof_scatter: float | None = None
    tof_scatter_source: str = ""
    striker_mass_std: float | None = None
    description: str = ""
    source: str = ""

    def __post_init__(self) -> None:
        if not self.beads >= 3:
            raise ConfigError("chain.beads", self.beads, "at least 3 (striker, sensor, last)")
        if not 1 <= self.sensor_index <= self.beads - 2:
            raise ConfigError("sensor.index", self.sensor_index,
                              f"an index between 1 and beads - 2 = {self.beads - 2}")
        for name in ("bead_radius", "striker_velocity", "plate_diameter", "sensitivity",
                     "sensor_range"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ConfigError(_yaml_field(name), v, "a finite value > 0")
        for name in ("sensor_mass", "striker_mass"):
            v = getattr(self, name)
            if v is not None and not (np.isfinite(v) and v > 0):
                raise ConfigError(_yaml_field(name), v, "a mass > 0 kg, or null (a bead's)")
        u = self.striker_mass_std
        if u is not None and not (np.isfinite(u) and u > 0):
            raise ConfigError("striker.mass_std", u,
                              "a standard uncertainty > 0 kg, or null (5 % of the mass)")
        if not (np.isfinite(self.preload) and self.preload >= 0):
            raise ConfigError("chain.preload", self.preload, "a force >= 0 N")
        if not (np.isfinite(self.plate_thickness) and self.plate_thickness >= 0):
            raise ConfigError("plate.thickness", self.plate_thickness, ">= 0 m (0: no plate)")
        if self.plate_thickness > 0 and self.plate_material == "none":
            raise ConfigError("plate.material", "none", "a material key when thickness > 0")
        if self.sensor_reads not in ("mean", "upper", "lower"):
            raise ConfigError("sensor.reads", self.sensor_reads, "mean | upper | lower")
        if self.plate_interface not in ("frictionless", "bonded", "unilateral"):
            raise ConfigError("plate.interface", self.plate_interface,
                              "frictionless | bonded | unilateral")
        if self.dissipation_law not in DISSIPATION_LAWS:
            raise ConfigError("dissipation.law", self.dissipation_law,
                              " | ".join(DISSIPATION_LAWS) + " (or --damping-law)")
        if not (np.isfinite(self.dissipation) and self.dissipation >= 0):
            raise ConfigError("dissipation.coefficient", self.dissipation,
                              "a coefficient >= 0 in the law's unit (0: conservative)")

    # ------------------------------------------------------------------ derived
    @property
    def drop_height(self) -> float:
        """Free-fall height (m) giving the striker speed, ``v^2 / (2 g)``."""
        return self.striker_velocity**2 / (2.0 * STANDARD_GRAVITY)

    @property
    def beads_below_sensor(self) -> int:
        """Beads between the sensor particle and the plate, the last bead included."""
        return self.beads - 1 - self.sensor_index

    @property
    def has_plate(self) -> bool:
        """Whether the device has a plate under the last bead (thickness > 0 m)."""
        return self.plate_thickness > 0

    @property
    def full_scale_force(self) -> float:
        """N, the largest force a recording of this device holds unclipped: the sensor's
        range, or the NI 9234's +-5 V over the sensor's sensitivity if that is less
        (REFERENCE.md: 445 N x 11.24 mV/N ~ 5 V)."""
        return min(self.sensor_range, DAQ_RANGE_V / self.sensitivity)

    def with_(self, **changes: Any) -> Device:
        """A copy with ``changes`` (field names; ``drop_height`` sets the striker speed).

        Changing ``beads`` without ``sensor_index`` keeps the beads below the sensor (the
        sensor stays at the same height above the plate: what a longer or shorter column
        above it means physically).

        Parameters
        ----------
        **changes : Any
            New values by field name (SI units); ``drop_height`` (m) sets
            ``striker_velocity = sqrt(2 g h)``.

        Returns
        -------
        Device
            The changed copy (validated again).

        Raises
        ------
        ssw.errors.ConfigError
            An unknown field, a drop height with a velocity, or a value out of range.
        """
        ch = dict(changes)
        if "drop_height" in ch:
            h = ch.pop("drop_height")
            if "striker_velocity" in ch:
                raise ConfigError("striker.drop_height", h, "not together with a velocity")
            if not (np.isfinite(h) and h > 0):
                raise ConfigError("striker.drop_height", h, "a height > 0 m")
            ch["striker_velocity"] = float(np.sqrt(2.0 * STANDARD_GRAVITY * h))
        if "beads" in ch and "sensor_index" not in ch:
            ch["sensor_index"] = int(ch["beads"]) - 1 - self.beads_below_sensor
        unknown = set(ch) - {f.name for f in fields(self)}
        if unknown:
            raise ConfigError("device field", sorted(unknown),
                              f"fields of a device: {', '.join(f.name for f in fields(self))}")
        if "beads" in ch:
            ch["beads"] = int(ch["beads"])
            ch["sensor_index"] = int(ch["sensor_index"])
        return replace(self, **ch)

    # ------------------------------------------------------------------ I/O
    def to_dict(self) -> dict[str, Any]:
        """The nested YAML/JSON layout of the schema (SI units).

        Returns
        -------
        dict
            The device by schema section (``chain``, ``sensor``, ``striker``, ``plate``,
            ``daq_sensor``, ``dissipation``, ``repeatability``), SI units.
        """
        return {
            "name": self.name,
            "description": self.description,
            "chain": {"beads": self.beads, "bead_material": self.bead_material,
                      "bead_radius": self.bead_radius, "preload": self.preload},
            "sensor": {"index": self.sensor_index, "mass": self.sensor_mass,
                       "reads": self.sensor_reads},
            "striker": {"mass": self.striker_mass, "mass_std": self.striker_mass_std,
                        "velocity": self.striker_velocity, "drop_height": None},
            "plate": {"material": self.plate_material, "thickness": self.plate_thickness,
                      "diameter": self.plate_diameter, "interface": self.plate_interface},
            "daq_sensor": {"model": self.sensor_model, "sensitivity": self.sensitivity,
                           "range": self.sensor_range},
            "dissipation": {"law": self.dissipation_law, "coefficient": self.dissipation},
            "repeatability": {"tof_std": self.tof_scatter, "source": self.tof_scatter_source},
        }

    def physics_dict(self) -> dict[str, Any]:
        """Every physical field, flat (no name, description, sources, nor the stated TOF
        scatter and striker mass uncertainty: measured properties of the device, not part
        of its model). A device
        without dissipation (coefficient 0, whatever the law's name) leaves the dissipation
        out: its physics, and the digest a calibration records of it, are those of a
        device file that states none.

        Returns
        -------
        dict
            Field name -> value (SI units) of the physical fields.
        """
        d = asdict(self)
        for k in ("name", "description", "source", "tof_scatter", "tof_scatter_source",
                  "striker_mass_std"):
            d.pop(k)
        if self.dissipation == 0:
            d.pop("dissipation_law")
            d.pop("dissipation")
        return d


#: Flat field -> its place in the YAML layout (for error messages).
_YAML_FIELDS = {
    "beads": "chain.beads", "bead_material": "chain.bead_material",
    "bead_radius": "chain.bead_radius", "preload": "chain.preload",
    "sensor_index": "sensor.index", "sensor_mass": "sensor.mass", "sensor_reads": "sensor.reads",
    "striker_mass": "striker.mass", "striker_mass_std": "striker.mass_std",
    "striker_velocity": "striker.velocity",
    "plate_material": "plate.material", "plate_thickness": "plate.thickness",
    "plate_diameter": "plate.diameter", "plate_interface": "plate.interface",
    "sensor_model": "daq_sensor.model", "sensitivity": "daq_sensor.sensitivity",
    "sensor_range": "daq_sensor.range", "dissipation_law": "dissipation.law",
    "dissipation": "dissipation.coefficient",
}


def _yaml_field(name: str) -> str:
    return _YAML_FIELDS.get(name, name)


def device_from_dict(data: dict[str, Any], source: str = "") -> Device:
    """A device from its nested layout: schema-validated, defaults filled.

    Parameters
    ----------
    data : dict
        The device in the nested layout of ``ssw/data/device.schema.yaml`` (SI units).
    source : str
        Where it was read from, for error messages and ``Device.source``.

    Returns
    -------
    Device
        The validated device.

    Raises
    ------
    ssw.errors.ConfigError
        Naming the field (``device.<path>``), the value and what is allowed.
    """
    from ssw.schema import first_file_error, path_of

    if not isinstance(data, dict):
        raise ConfigError("device", source or type(data).__name__, "a YAML mapping")
    d = copy.deepcopy(data)
    err = first_file_error(SCHEMA_PATH, d)
    if err is not None:
        raise ConfigError(f"device {source}: {path_of(err)}".strip(), err.instance, err.message)
    st = d["striker"]
    if (st.get("velocity") is None) == (st.get("drop_height") is None):
        raise ConfigError(f"device {source}: striker".strip(),
                          {"velocity": st.get("velocity"), "drop_height": st.get("drop_height")},
                          "exactly one of velocity (m/s) and drop_height (m)")
    v = st["velocity"]
    if v is None:
        v = float(np.sqrt(2.0 * STANDARD_GRAVITY * st["drop_height"]))
    ch, se, pl, daq = d["chain"], d["sensor"], d["plate"], d["daq_sensor"]
    dis = d["dissipation"]
    return Device(
        name=d["name"], description=str(d.get("description", "")).strip(),
        beads=int(ch["beads"]), bead_material=ch["bead_material"],
        bead_radius=float(ch["bead_radius"]), preload=float(ch["preload"]),
        sensor_index=int(se["index"]),
        sensor_mass=None if se["mass"] is None else float(se["mass"]),
        sensor_reads=se["reads"],
        striker_mass=None if st["mass"] is None else float(st["mass"]),
        striker_velocity=float(v),
        plate_material=pl["material"], plate_thickness=float(pl["thickness"]),
        plate_diameter=float(pl["diameter"]), plate_interface=pl["interface"],
        sensor_model=daq["model"], sensitivity=float(daq["sensitivity"]),
        sensor_range=float(daq["range"]),
        dissipation_law=dis["law"], dissipation=float(dis["coefficient"]),
        tof_scatter=None if d["repeatability"].get("tof_std") is None
        else float(d["repeatability"]["tof_std"]),
        tof_scatter_source=str(d["repeatability"].get("source", "")), source=source,
        striker_mass_std=None if st.get("mass_std") is None else float(st["mass_std"]),
    )


def available_devices() -> list[str]:
    """Names of the devices shipped with ssw.

    Returns
    -------
    list of str
        The shipped devices' names, sorted.
    """
    return sorted(p.stem for p in DEVICES_DIR.glob("*.yaml"))


def device_path(spec: str | Path) -> Path:
    """The YAML file of ``spec``: an existing path, or the name of a shipped device.

    Parameters
    ----------
    spec : str or Path
        A path to a device YAML file, or the name of a shipped device.

    Returns
    -------
    Path
        The device's YAML file.

    Raises
    ------
    ssw.errors.ConfigError
        Neither a file nor a shipped device (``--device``), listing the shipped ones.
    """
    p = Path(spec)
    if p.is_file():
        return p
    shipped = DEVICES_DIR / f"{spec}.yaml"
    if shipped.is_file():
        return shipped
    raise ConfigError("--device", str(spec),
                      f"a device YAML file or one of the shipped devices: "
                      f"{', '.join(available_devices())}")


def load_device(spec: str | Path | dict[str, Any] | Device | None = None) -> Device:
    """A device from a path, a shipped device's name, a mapping, or the default (thesis).

    Parameters
    ----------
    spec : str, Path, dict, Device or None
        A device file, a shipped device's name, a nested mapping, a device (returned as
        is), or None for :data:`DEFAULT_DEVICE`.

    Returns
    -------
    Device
        The validated device.

    Raises
    ------
    ssw.errors.ConfigError
        An unknown device, an unreadable file, or an invalid field.
    """
    if isinstance(spec, Device):
        return spec
    if isinstance(spec, dict):
        return device_from_dict(spec, "(mapping)")
    p = device_path(DEFAULT_DEVICE if spec is None else spec)
    try:
        data = safe_load(p.read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise ConfigError("--device", str(p), f"a readable YAML device file ({exc})") from exc
    return device_from_dict(data, str(p))


def write_device(path: str | Path, device: Device, header: str = "") -> None:
    """Write a device YAML file atomically (re-loadable by :func:`load_device`).

    Parameters
    ----------
    path : str or Path
        The YAML file to write.
    device : Device
        The device to write (its :meth:`Device.to_dict` layout).
    header : str
        Text put before the YAML (e.g. comment lines); none by default.
    """
    from ssw.h5io import atomic_write_text

    text = (header + "\n" if header else "") + yaml.safe_dump(
        device.to_dict(), sort_keys=False, default_flow_style=False)
    atomic_write_text(path, text)


# ---------------------------------------------------------------------- calibratable
@dataclass(frozen=True)
class Parameter:
    """A device field ``ssw calibrate`` may identify.

    ``kind`` is ``continuous`` (refined by least squares) or ``integer`` (scanned);
    ``lower``/``upper`` bound the global scan (SI); ``log`` scans and steps it in log
    space; ``scale`` (SI) makes Jacobian columns comparable when a value may be 0.

    Parameters
    ----------
    name : str
        The device field's name.
    unit : str
        Its SI unit (``1``: dimensionless).
    kind : str
        ``continuous`` or ``integer``.
    lower : float
        Lower end of the global scan, in ``unit``.
    upper : float
        Upper end of the global scan, in ``unit``.
    log : bool
        Scan and step in log space.
    scale : float
        Typical size in ``unit``, scaling its Jacobian column.
    description : str
        What the parameter is (text).
    """

    name: str
    unit: str
    kind: str
    lower: float
    upper: float
    log: bool
    scale: float
    description: str


#: Calibratable device parameters by name.
PARAMETERS: dict[str, Parameter] = {p.name: p for p in (
    Parameter("striker_velocity", "m/s", "continuous", 0.1, 2.0, True, 0.5,
              "striker speed at first contact (drop heights 0.5 mm .. 0.2 m)"),
    Parameter("preload", "N", "continuous", 0.0, 60.0, False, 5.0,
              "constant force on bead 1 (0 .. 10x the weight of a 20-bead chain)"),
    Parameter("sensor_mass", "kg", "continuous", 0.005, 0.2, True, 0.03,
              "mass of the sensor particle"),
    Parameter("striker_mass", "kg", "continuous", 0.005, 0.5, True, 0.03,
              "mass of the striker"),
    Parameter("beads", "1", "integer", 8, 40, False, 1.0,
              "bead count (the beads below the sensor are kept)"),
)}


def parameter(name: str) -> Parameter:
    """The calibratable parameter ``name`` (ConfigError listing them otherwise).

    Parameters
    ----------
    name : str
        A key of :data:`PARAMETERS`.

    Returns
    -------
    Parameter
        Its description.

    Raises
    ------
    ssw.errors.ConfigError
        ``name`` is not calibratable (``--free``).
    """
    if name not in PARAMETERS:
        raise ConfigError("--free", name, f"one of {', '.join(PARAMETERS)}")
    return PARAMETERS[name]


def parameter_value(device: Device, name: str) -> float:
    """The device's value of a calibratable parameter (a None mass is a bead's mass).

    Parameters
    ----------
    device : Device
        The device.
    name : str
        A key of :data:`PARAMETERS`.

    Returns
    -------
    float
        The value in the parameter's SI unit; a None mass is ``4/3 pi R^3 rho`` of a bead
        (kg).

    Raises
    ------
    ssw.errors.ConfigError
        ``name`` is not calibratable.
    """
    parameter(name)
    v = getattr(device, name)
    if v is None:  # a mass given as "a bead's"
        from ssw.materials import material_set

        rho = material_set()[device.bead_material].density
        v = 4.0 / 3.0 * np.pi * device.bead_radius**3 * rho
    return float(v)
