"""A design's device as a device file: the recommended (or any ranked) candidate of
``ssw design`` written as a device YAML (``ssw/data/device.schema.yaml``) that every
chain command takes (``--device FILE``).

The written device is the base device of the design (the command's ``--device``, config
or calibration: its DAQ sensor, plate interface, preload, sensor reading and contact
dissipation) with the candidate's design variables: for the device design
(:class:`ssw.design.space.DevicePoint`) the beads (named by material, ``chain.bead_material``,
their values from the materials library), their count and radius, the sensor's index and
mass, the striker's mass and speed (``sqrt(2 g h)`` of the drop height), the plate's
material, thickness and diameter; for the plate design the plate's material, thickness and
diameter and the striker's speed.

The one-hit TOF scatter the design assumed (``repeatability.tof_std``) is carried over,
labelled as the design's assumption (a built device states its own, measured).

The file's header states the candidate, its rank, the TOF the design computed on each soil
modulus, whether that TOF ran at the device's own time step (``step: own``, the TOF ``ssw
tof --device FILE --law fem`` gives on the same config, to round-off) or at its batch's
shared step, and the ``contact:`` lengths its FEM wall used (scaled with the bead radius
for a device design: :func:`ssw.design.device_eval.scaled_contact`).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from ssw.errors import ConfigError

#: Kinds of ``ssw design`` result (the JSON's ``ssw_kind``).
KINDS = ("design", "design_device")


def candidate_at(result: dict[str, Any], rank: int) -> dict[str, Any]:
    """The candidate of rank ``rank`` of a design's JSON (1: the recommended).

    Parameters
    ----------
    result : dict
        The JSON of ``ssw design`` (plate or device space).
    rank : int
        1-based rank in the result's ranked candidates.

    Returns
    -------
    dict
        The candidate's record.

    Raises
    ------
    ConfigError
        ``--output-device-rank`` outside ``1 .. len(candidates)``.
    """
    cands = result["candidates"]
    if not (isinstance(rank, int) and 1 <= rank <= len(cands)):
        raise ConfigError("--output-device-rank", rank,
                          f"a rank 1 .. {len(cands)} (1: the recommended device)")
    return result["recommended"] if rank == 1 else cands[rank - 1]


def device_name(path: str | Path) -> str:
    """A device name (``[A-Za-z0-9_.-]+``) from a file name.

    Parameters
    ----------
    path : str or pathlib.Path
        The device file.

    Returns
    -------
    str
        Its stem, other characters replaced by ``_`` (``designed`` if empty).
    """
    return re.sub(r"[^A-Za-z0-9_.-]", "_", Path(path).stem) or "designed"


def designed_device(result: dict[str, Any], candidate: dict[str, Any], base: Any,
                    materials: dict[str, Any], name: str) -> Any:
    """The :class:`ssw.device.Device` of a design's candidate (module docstring).

    Parameters
    ----------
    result : dict
        The design's JSON (its ``ssw_kind`` and ``spec``).
    candidate : dict
        One of its candidates (:func:`candidate_at`).
    base : ssw.device.Device
        The design's base device.
    materials : dict
        The materials library the design used (key -> Material).
    name : str
        The device's name.

    Returns
    -------
    ssw.device.Device
        The device, with the design's assumed TOF scatter.
    """
    kind = result.get("ssw_kind")
    if kind == "design_device":
        from ssw.design.space import DevicePoint

        dev = DevicePoint.from_dict(candidate).device(base, materials, name=name)
    elif kind == "design":
        dev = base.with_(name=name, plate_material=str(candidate["material"]),
                         plate_thickness=float(candidate["thickness"]),
                         plate_diameter=float(candidate["plate_diameter"]),
                         striker_velocity=float(candidate["striker_velocity"]),
                         description=f"ssw design: {base.name} on "
                         f"{candidate['material']} {candidate['thickness'] * 1e3:.4g} mm",
                         source="")
    else:
        raise ConfigError("--output-device", kind, f"the JSON of ssw design ({', '.join(KINDS)})")
    spec = result["spec"]
    return dev.with_(tof_scatter=float(spec["tof_scatter"]),
                     tof_scatter_source="assumed by ssw design, not measured: "
                     + (spec.get("tof_scatter_source") or "source not stated"))


def header(result: dict[str, Any], candidate: dict[str, Any], rank: int,
           contact: dict[str, Any] | None) -> str:
    """The device file's comment lines (module docstring).

    Parameters
    ----------
    result : dict
        The design's JSON.
    candidate : dict
        The candidate written.
    rank : int
        Its 1-based rank.
    contact : dict or None
        The ``contact:`` settings its fem wall used (lengths in m), or None.

    Returns
    -------
    str
        Comment lines (each starts with a hash and a space).
    """
    space = "device" if result.get("ssw_kind") == "design_device" else "plate"
    lo, hi = result["spec"]["soil_E"]
    label = candidate.get("label") or (
        f"{candidate.get('material')} {candidate.get('thickness', 0.0) * 1e3:.4g} mm")
    step = candidate.get("step", "own")
    lines = [f"Device made by `ssw design --space {space}` (soils {lo:.6g}-{hi:.6g} Pa, nu "
             f"{result['spec']['soil_nu']:g}): rank {rank} of {len(result['candidates'])}"
             + (" (the recommended device)" if rank == 1 else ""),
             f"{label}",
             f"worst-case resolution dE/E {candidate['resolution']:.6g}; feasible "
             f"{candidate['feasible']}",
             f"TOF of the design at its {'own' if step == 'own' else 'batch shared'} time "
             "step (fem wall), s:"]
    lines += [f"  E {e:.9g} Pa: TOF {t!r}" for e, t in zip(candidate["soil_E"],
                                                          candidate["tof_E"], strict=True)]
    if step == "own":
        lines.append("`ssw tof --device FILE --law fem --soil-E E` on the same config and "
                     "calibration gives these to round-off")
    else:
        lines.append("(a shared step: `ssw tof --device FILE` runs the device at its own "
                     "step; the TOFs agree to the integrator's error, not to round-off)")
    if contact:
        lines.append("contact lengths of its fem wall (the config's contact: scaled with "
                     "the bead radius): " + ", ".join(f"{k} {v!r}" for k, v in
                                                      sorted(contact.items())
                                                      if isinstance(v, int | float)))
    return "\n".join("# " + ln for ln in lines)


def write_designed_device(path: str | Path, result: dict[str, Any], rank: int, base: Any,
                          materials: dict[str, Any], contact: dict[str, Any] | None = None,
                          base_radius: float | None = None) -> Any:
    """Write the device of rank ``rank`` of a design (atomically) and return it.

    Parameters
    ----------
    path : str or pathlib.Path
        The device YAML to write.
    result : dict
        The design's JSON.
    rank : int
        1-based rank (1: the recommended device).
    base : ssw.device.Device
        The design's base device.
    materials : dict
        The materials library the design used.
    contact : dict or None
        The config's ``contact:`` settings (stated in the header, scaled with the bead).
    base_radius : float or None
        m, the base device's bead radius (the contact settings' scale).

    Returns
    -------
    ssw.device.Device
        The device written.
    """
    from ssw.device import write_device

    cand = candidate_at(result, rank)
    dev = designed_device(result, cand, base, materials, device_name(path))
    scaled = None
    if contact is not None:
        from ssw.design.device_eval import scaled_contact

        factor = dev.bead_radius / base_radius if base_radius else 1.0
        scaled = scaled_contact(contact, factor)
    write_device(path, dev, header(result, cand, rank, scaled))
    return dev
