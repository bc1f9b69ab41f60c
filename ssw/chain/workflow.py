"""Input helpers of the chain stage's Snakemake rules (``workflow/rules/chain.smk``).

Pure functions of the validated config, so the ``.smk`` file holds only rules (and the
helpers get tested like any code).
"""

from __future__ import annotations

from typing import Any

from ssw.config import Scene, all_scenes, device_of, expand_grid


def wall_law(config: dict[str, Any]) -> str:
    """The sweep's last-contact law (``chain.wall_law``)."""
    return str(config["chain"].get("wall_law", "fit"))


def sweep_scene_ids(config: dict[str, Any]) -> list[str]:
    """Contact scene ids of the sweep points (the table wall reads their curves).

    Raises ``ValueError`` when a sweep point is in no contact set.
    """
    ch = config["chain"]
    dev = device_of(config)
    E = expand_grid(ch["sweep"]["soil_E"], "chain.sweep.soil_E")
    nu = expand_grid(ch["sweep"]["soil_nu"], "chain.sweep.soil_nu")
    plate = dev.plate_material if dev.has_plate else "none"
    ids = [
        Scene(plate, float(dev.plate_thickness), float(e), float(n)).scene_id
        for n in nu
        for e in E
    ]
    known = all_scenes(config)
    missing = [i for i in ids if i not in known]
    if missing:
        raise ValueError(
            f"chain.wall_law = table needs a contact scene for every sweep point; "
            f"{len(missing)} are in no set (e.g. {missing[0]}): add them to a set"
        )
    return ids


#: The study's calibration file, relative to the results folder (``ssw calibrate
#: --from-config``; ``ssw.cli._device.STUDY_CALIBRATION`` is the same file seen from the
#: working folder).
CALIBRATION = "calibration/calibration.json"


def uses_calibration(config: dict[str, Any]) -> bool:
    """Whether the sweep, the validation and the inverse use the calibrated device."""
    return bool(config.get("calibration", {}).get("use", True))


def calibrated_inputs(config: dict[str, Any], results: str) -> dict[str, Any]:
    """The wall law's inputs plus, with calibration.use, the calibration file."""
    inputs = wall_inputs(config, results)
    if uses_calibration(config):
        inputs["calibration"] = f"{results}/{CALIBRATION}"
    return inputs


def calibration_flag(inputs: Any) -> str:
    """``--calibration FILE`` when the job's inputs hold the calibration, else ``none``
    (a job never picks up a calibration its rule does not depend on)."""
    if "calibration" in inputs.keys():
        return f"--calibration {inputs.calibration}"
    return "--calibration none"


def recordings(config: dict[str, Any], root: str) -> list[str]:
    """The validation samples' recordings (paths from ``root``, the repository)."""
    import os

    return [os.path.join(root, s["recordings"]) for s in
            config.get("validation", {}).get("samples", []) if s.get("recordings")]


def wall_inputs(config: dict[str, Any], results: str) -> dict[str, Any]:
    """The K table (fit wall) or the sweep points' contact curves (table wall)."""
    law = wall_law(config)
    if law == "fit":
        return {"k_table": f"{results}/fit/k_table.h5"}
    if law == "table":
        return {"curves": [f"{results}/contact/{i}.h5" for i in sweep_scene_ids(config)]}
    return {}


def wall_flags(config: dict[str, Any], inputs: Any, results: str) -> str:
    """``ssw`` flags naming the wall law and its inputs."""
    flags = f"--law {wall_law(config)}"
    keys = set(inputs.keys())
    if "k_table" in keys:
        flags += f" --k-table {inputs.k_table}"
    if "curves" in keys:
        flags += f" --contact-dir {results}/contact"
    return flags
