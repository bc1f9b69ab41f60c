"""The study's jobs as the rules name them: its results' layout, the sets and plate
families, the files each job reads, the ``ssw`` flags that name them, the survey's points.

Pure functions of a validated config (:mod:`ssw.workflow`). SI units where a value has one;
paths are relative to the working folder unless a ``root`` is given.
"""

from __future__ import annotations

from typing import Any

from ssw.config import Scene, all_scenes, device_of, expand_grid, scenes
from ssw.errors import ConfigError

#: The results folder of a study, relative to the working folder.
RESULTS = "results"
#: The resolved study config every job reads (written when a run starts).
STUDY_CONFIG = f"{RESULTS}/study_config.yaml"
#: The study's calibration file, relative to the results folder (``ssw calibrate
#: --from-config``); seen from the working folder it is ``ssw.cli._device.STUDY_CALIBRATION``.
CALIBRATION = "calibration/calibration.json"



def family_of(scene: Scene) -> str:
    """The plate family of a scene: ``<plate>-t<thickness>um`` (the scene id's start), or
    ``noplate``; the scenes of a family share their mesh and their plate's operators.

    Parameters
    ----------
    scene : ssw.config.Scene
        The contact scene.

    Returns
    -------
    str
        The family name.
    """
    if scene.plate_thickness <= 0:
        return "noplate"
    return scene.scene_id.split("-E", 1)[0]


def families(cfg: dict[str, Any]) -> dict[str, list[str]]:
    """Plate family -> its scene ids (sorted by Poisson's ratio, then E), every scene of
    every set once. One contact job computes one family.

    Parameters
    ----------
    cfg : dict
        The study config.

    Returns
    -------
    dict of str to list of str
        Family name -> its scene ids.
    """
    out: dict[str, list[Scene]] = {}
    for sc in all_scenes(cfg).values():
        out.setdefault(family_of(sc), []).append(sc)
    return {f: [s.scene_id for s in sorted(v, key=lambda s: (s.soil_nu, s.soil_E,
                                                               s.scene_id))]
            for f, v in sorted(out.items())}


def contact_file(scene_id: str, results: str = RESULTS) -> str:
    """The curve file of a scene: ``<results>/contact/<family>/<scene_id>.h5``.

    Parameters
    ----------
    scene_id : str
        The scene's id.
    results : str
        The results folder.

    Returns
    -------
    str
        The path of the scene's curve file.
    """
    return scene_file(f"{results}/contact", scene_id)


def scene_file(contact_dir: str, scene_id: str) -> str:
    """The curve file of a scene in a contact folder: ``<dir>/<family>/<scene_id>.h5``.

    Parameters
    ----------
    contact_dir : str
        The contact folder.
    scene_id : str
        The scene's id.

    Returns
    -------
    str
        The path of the scene's curve file.
    """
    family = "noplate" if scene_id.startswith("noplate") else scene_id.split("-E", 1)[0]
    return f"{contact_dir}/{family}/{scene_id}.h5"


def k_table_file(cfg: dict[str, Any], results: str = RESULTS) -> str:
    """The K table of the config's ``fit.set`` (the chain's ``fit`` wall).

    Parameters
    ----------
    cfg : dict
        The study config.
    results : str
        The results folder.

    Returns
    -------
    str
        ``<results>/fit/sets/<set>/k_table.h5``.

    Raises
    ------
    ssw.errors.ConfigError
        When ``fit.set`` is not set.
    """
    if cfg["fit"].get("set") is None:
        raise ConfigError("fit.set", None, "a set whose K table feeds the fit wall")
    return f"{results}/fit/sets/{cfg['fit']['set']}/k_table.h5"


def one_soil_sets(cfg: dict[str, Any]) -> list[str]:
    """Sets with one soil (the thesis's Sets 1 and 2: deviation from Hertz per plate).

    Parameters
    ----------
    cfg : dict
        The study config.

    Returns
    -------
    list of str
        The names of the sets with one soil.
    """
    return [s for s in cfg["sets"] if _n_soils(cfg, s) == 1]


def grid_sets(cfg: dict[str, Any]) -> list[str]:
    """Sets with several soils (the thesis's Set 3: K(E, nu) tables).

    Parameters
    ----------
    cfg : dict
        The study config.

    Returns
    -------
    list of str
        The names of the sets with more than one soil.
    """
    return [s for s in cfg["sets"] if _n_soils(cfg, s) > 1]


def _n_soils(cfg: dict[str, Any], set_name: str) -> int:
    s = cfg["sets"][set_name]
    return int(expand_grid(s["soil_E"], f"sets.{set_name}.soil_E").size
               * expand_grid(s["soil_nu"], f"sets.{set_name}.soil_nu").size)


def wall_law(cfg: dict[str, Any]) -> str:
    """The chain's last-contact law (``chain.wall_law``).

    Parameters
    ----------
    cfg : dict
        The study config.

    Returns
    -------
    str
        The law's name (default ``fem``).
    """
    return str(cfg["chain"].get("wall_law", "fem"))


def uses_calibration(cfg: dict[str, Any]) -> bool:
    """Whether the sweep, the validation and the survey use the calibrated device.

    Parameters
    ----------
    cfg : dict
        The study config.

    Returns
    -------
    bool
        ``calibration.use`` (default true).
    """
    return bool(cfg.get("calibration", {}).get("use", True))


def recordings(cfg: dict[str, Any], root: str) -> list[str]:
    """The validation samples' recordings (paths from ``root``, the repository).

    Parameters
    ----------
    cfg : dict
        The study config.
    root : str
        The repository's folder.

    Returns
    -------
    list of str
        One path per validation sample that names recordings.
    """
    import os

    return [os.path.join(root, s["recordings"]) for s in
            cfg.get("validation", {}).get("samples", []) if s.get("recordings")]


def wall_inputs(cfg: dict[str, Any], results: str = RESULTS) -> dict[str, Any]:
    """The files the wall law reads: the K table (``fit``) or the sweep points' curves
    (``table``); none for ``fem`` and ``hertz`` (the ``fem`` wall builds its own law).

    Parameters
    ----------
    cfg : dict
        The study config.
    results : str
        The results folder.

    Returns
    -------
    dict
        ``{"k_table": path}``, ``{"curves": [path, ...]}`` or ``{}``.
    """
    law = wall_law(cfg)
    if law == "fit":
        return {"k_table": k_table_file(cfg, results)}
    if law == "table":
        return {"curves": [contact_file(i, results) for i in sweep_scene_ids(cfg)]}
    return {}


def calibrated_inputs(cfg: dict[str, Any], results: str = RESULTS) -> dict[str, Any]:
    """The wall law's inputs plus, with ``calibration.use``, the calibration file.

    Parameters
    ----------
    cfg : dict
        The study config.
    results : str
        The results folder.

    Returns
    -------
    dict
        :func:`wall_inputs` plus ``"calibration"``: the calibration file's path.
    """
    inputs = wall_inputs(cfg, results)
    if uses_calibration(cfg):
        inputs["calibration"] = f"{results}/{CALIBRATION}"
    return inputs


def wall_flags(cfg: dict[str, Any], inputs: Any, results: str = RESULTS) -> list[str]:
    """``ssw`` arguments naming the wall law and its inputs.

    Parameters
    ----------
    cfg : dict
        The study config.
    inputs : snakemake.io.InputFiles
        The job's inputs (``k_table`` or ``curves`` when the law reads them).
    results : str
        The results folder.

    Returns
    -------
    list of str
        One argument per item (a rule quotes each: ``{params.wall:q}``), e.g.
        ``["--law", "fit", "--k-table", "results/fit/sets/set3_soil/k_table.h5"]``.
    """
    args = ["--law", wall_law(cfg)]
    keys = set(inputs.keys())
    if "k_table" in keys:
        args += ["--k-table", str(inputs.k_table)]
    if "curves" in keys:
        args += ["--contact-dir", f"{results}/contact"]
    return args


def calibration_flag(inputs: Any) -> list[str]:
    """``--calibration FILE`` when the job's inputs hold the calibration, else ``none``
    (a job never picks up a calibration its rule does not depend on).

    Parameters
    ----------
    inputs : snakemake.io.InputFiles
        The job's inputs.

    Returns
    -------
    list of str
        The flag and its value, one argument each (a rule quotes each).
    """
    if "calibration" in inputs.keys():
        return ["--calibration", str(inputs.calibration)]
    return ["--calibration", "none"]


def sweep_scene_ids(cfg: dict[str, Any]) -> list[str]:
    """Contact scene ids of the sweep points (the ``table`` wall reads their curves).

    Raises ConfigError when a sweep point is in no contact set.

    Parameters
    ----------
    cfg : dict
        The study config.

    Returns
    -------
    list of str
        One scene id per sweep point (Poisson's ratio outer, E inner).

    Raises
    ------
    ssw.errors.ConfigError
        When a sweep point is in no contact set.
    """
    ch = cfg["chain"]
    dev = device_of(cfg)
    E = expand_grid(ch["sweep"]["soil_E"], "chain.sweep.soil_E")
    nu = expand_grid(ch["sweep"]["soil_nu"], "chain.sweep.soil_nu")
    plate = dev.plate_material if dev.has_plate else "none"
    ids = [Scene(plate, float(dev.plate_thickness), float(e), float(n)).scene_id
           for n in nu for e in E]
    known = all_scenes(cfg)
    missing = [i for i in ids if i not in known]
    if missing:
        raise ConfigError("chain.wall_law", "table",
                          f"a contact scene for every sweep point; {len(missing)} are in no "
                          f"set (e.g. {missing[0]}): add them to a set")
    return ids

def device_parts(cfg: dict[str, Any]) -> int:
    """The device design's parts per family.

    Parameters
    ----------
    cfg : dict
        The study config.

    Returns
    -------
    int
        ``design.device.parts`` (default 1): the workflow's scattergather ``device`` (a
        part with no chain is refused by the family job,
        :meth:`ssw.design.space.DeviceSpace.family_points`).
    """
    dev = cfg.get("design", {}).get("device") or {}
    return int(dev.get("parts") or 1)


def scatter_part(item: str) -> str:
    """The ``--part`` flag of a scatter item.

    Parameters
    ----------
    item : str
        Snakemake's scatter item ``i-of-n`` (1-based).

    Returns
    -------
    str
        ``i-1/n`` (0-based part of n).
    """
    i, _, n = item.partition("-of-")
    return f"{int(i) - 1}/{int(n)}"


def alternatives(names: Any) -> str:
    """A wildcard regex matching exactly ``names`` (none: a regex that matches nothing).

    Parameters
    ----------
    names : iterable of str
        The values the wildcard may take.

    Returns
    -------
    str
        The escaped names joined by ``|``, or ``(?!)``.
    """
    import re

    names = list(names)
    return "|".join(re.escape(n) for n in names) if names else "(?!)"


def set_families(cfg: dict[str, Any], set_name: str, results: str = RESULTS) -> list[str]:
    """The contact family folders that hold the scenes of a set.

    Parameters
    ----------
    cfg : dict
        The study config.
    set_name : str
        The set's name (a key of ``sets``).
    results : str
        The results folder.

    Returns
    -------
    list of str
        The folders ``<results>/contact/<family>``, sorted.
    """
    return sorted({f"{results}/contact/{family_of(s)}" for s in scenes(cfg, set_name)})


def write_study_config(cfg: dict[str, Any], path: str = STUDY_CONFIG) -> bool:
    """Write the resolved study config (``ssw.config.dump_config``) for the jobs, only when
    its text changed (a run that changes nothing rewrites nothing). Returns whether it
    wrote.

    Parameters
    ----------
    cfg : dict
        The resolved study config.
    path : str
        The file to write.

    Returns
    -------
    bool
        True when the file was written.
    """
    from pathlib import Path

    from ssw.config import dump_config
    from ssw.h5io import atomic_write_text

    p = Path(path)
    text = dump_config(cfg)
    if p.is_file() and p.read_text() == text:
        return False
    atomic_write_text(p, text)
    return True


def survey_points(cfg: dict[str, Any]) -> list[str]:
    """The ids of the config's survey points.

    Parameters
    ----------
    cfg : dict
        The study config.

    Returns
    -------
    list of str
        The ``survey.points`` ids, in the config's order.
    """
    return [p["id"] for p in cfg.get("survey", {}).get("points", [])]


def _point(cfg: dict[str, Any], point: str) -> dict[str, Any]:
    pts = {p["id"]: p for p in cfg.get("survey", {}).get("points", [])}
    if point not in pts:
        raise ConfigError("survey point", point, f"one of {', '.join(pts)}")
    return pts[point]


def point_recordings(cfg: dict[str, Any], point: str, root: str) -> list[str]:
    """A survey point's recordings (paths from ``root``, the repository).

    Parameters
    ----------
    cfg : dict
        The study config.
    point : str
        The survey point's id.
    root : str
        The repository's folder.

    Returns
    -------
    list of str
        The recording paths.

    Raises
    ------
    ssw.errors.ConfigError
        When ``point`` is not a survey point of the config.
    """
    import os

    return [os.path.join(root, r) for r in _point(cfg, point)["recordings"]]


def survey_nu(cfg: dict[str, Any], point: str) -> str:
    """The point's ``--soil-nu`` argument (``NU`` or ``LO:HI``).

    Parameters
    ----------
    cfg : dict
        The study config.
    point : str
        The survey point's id.

    Returns
    -------
    str
        The point's soil Poisson's ratio (:func:`ssw.config.nu_text`).

    Raises
    ------
    ssw.errors.ConfigError
        When ``point`` is not a survey point of the config.
    """
    from ssw.config import nu_text

    return nu_text(_point(cfg, point)["soil_nu"])


def survey_has_coordinates(cfg: dict[str, Any]) -> bool:
    """Whether any survey point has plan or geographic coordinates (a map is drawn).

    Parameters
    ----------
    cfg : dict
        The study config.

    Returns
    -------
    bool
        True when a point has ``x`` or ``latitude``.
    """
    return any(p.get("x") is not None or p.get("latitude") is not None
               for p in cfg.get("survey", {}).get("points", []))
