"""The study as the workflow runs it: its jobs, and the inputs each job reads.

Pure functions of a validated config (and one cached view of it, :class:`Study`), used by
the rules of ``workflow/rules/*.smk`` so that the rule files hold only rules and these
helpers are tested like any code.

Exact reruns. Every job declares the slice of the study it reads (:meth:`Study.inputs`):
its part of the config with every reference resolved to values (the device's physics, not
its file name; each material's E, nu, density and strength, not the library's path), and
the hash of the ssw source its command runs (:func:`ssw.provenance.source_hash` of the
command's import closure). The rules pass that slice to Snakemake as a param; Snakemake
stores params with each output and reruns a job whose params changed (its rerun trigger
``params``), so an edit reruns exactly the jobs whose slice it changes, a dry run shows
them, and nothing else reruns. Files a job reads (curves, the calibration, recordings, the
sweep) are its inputs, compared by time as usual.

A job's command reads the whole resolved study config (``results/study_config.yaml``,
written when a run starts, never at parse time: a dry run and a lint write nothing) and
uses only its slice. The slice's digest is passed to the command
(``ssw --inputs-sha256 ...``) and recorded in every result it writes.

Steps and their keys:

* ``contact`` (one job per plate family, :func:`families`: the scenes of one plate
  material and thickness, or of no plate, whatever set lists them: they share a mesh and
  their operators);
* ``fit`` (one job per set); ``calibration``; ``sweep`` (the TOF sweep, in parts:
  ``scattergather``) and ``sweep_figure``; ``validation``; ``survey_point`` (one job per
  point) and ``survey_table``; ``report``.
"""

from __future__ import annotations

import functools
from dataclasses import asdict
from typing import Any

from ssw.config import Scene, all_scenes, device_of, expand_grid, library, scenes
from ssw.errors import ConfigError

#: The results folder of a study, relative to the working folder.
RESULTS = "results"
#: The resolved study config every job reads (written when a run starts).
STUDY_CONFIG = f"{RESULTS}/study_config.yaml"
#: The study's calibration file, relative to the results folder (``ssw calibrate
#: --from-config``); seen from the working folder it is ``ssw.cli._device.STUDY_CALIBRATION``.
CALIBRATION = "calibration/calibration.json"

#: The command module of each step (its import closure is the step's code).
STEP_MODULES: dict[str, tuple[str, ...]] = {
    "contact": ("ssw.cli.contact",),
    "fit": ("ssw.cli.fit",),
    "calibration": ("ssw.cli.calibrate",),
    "sweep": ("ssw.cli.chain",),
    "sweep_figure": ("ssw.cli.chain",),
    "validation": ("ssw.cli.validate",),
    "survey_point": ("ssw.cli.measure",),
    "survey_table": ("ssw.cli.survey",),
    "report": ("ssw.cli.report",),
    "design": ("ssw.cli.design",),
    "design_table": ("ssw.cli.design",),
    "design_device": ("ssw.cli.design",),
    "design_device_table": ("ssw.cli.design",),
}

#: Contact settings that shape a contact curve (every key of the section).
CONTACT_KEYS = ("delta_max", "delta_mode", "reach_energy", "steps", "interface",
                "plate_diameter", "soil_radius", "soil_depth", "mesh_size_contact",
                "mesh_growth", "mesh_size_max", "plate_layers", "candidate_factor",
                "pressure_profiles")
#: Contact settings the chain's ``fem`` wall reads (its mesh and candidate zone; the wall
#: tabulates its own law, so the curves' increments do not matter to it).
FEM_WALL_KEYS = ("soil_radius", "soil_depth", "mesh_size_contact", "mesh_growth",
                 "mesh_size_max", "plate_layers", "candidate_factor")
#: Chain settings of the model (the sweep's grid is the sweep's own).
CHAIN_KEYS = ("damping", "steps_per_contact", "t_max", "gravity", "wall_law",
              "wall_dynamics", "soil_density")


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


class Study:
    """A validated config seen as workflow jobs: what each job reads (module docstring).

    The device and the materials library are read once; every method is a pure function
    of the config.

    Parameters
    ----------
    cfg : dict
        The validated study config.

    Attributes
    ----------
    cfg : dict
        The study config.
    """

    def __init__(self, cfg: dict[str, Any]) -> None:
        self.cfg = cfg

    # ------------------------------------------------------------------ resolved data
    @functools.cached_property
    def device(self) -> Any:
        """The study's device (:class:`ssw.device.Device`)."""
        return device_of(self.cfg)

    @functools.cached_property
    def materials(self) -> dict[str, Any]:
        """The study's materials (key -> :class:`ssw.materials.Material`)."""
        return library(self.cfg)

    @functools.cached_property
    def families(self) -> dict[str, list[str]]:
        """Plate family -> scene ids (:func:`families`)."""
        return families(self.cfg)

    @functools.cached_property
    def scenes(self) -> dict[str, Scene]:
        """Scene id -> scene, every set."""
        return all_scenes(self.cfg)

    def material_values(self, keys: Any) -> dict[str, Any]:
        """``{key: every field of the material}`` for the material keys given.

        Parameters
        ----------
        keys : iterable of str
            Material keys (``none`` is skipped).

        Returns
        -------
        dict
            Material key -> its fields (:func:`dataclasses.asdict`; SI units).

        Raises
        ------
        ssw.errors.ConfigError
            When a key is not in the materials library.
        """
        out = {}
        for k in sorted(set(keys)):
            if k == "none":
                continue
            if k not in self.materials:
                raise ConfigError("material", k, f"a material of the library: "
                                  f"{', '.join(sorted(self.materials))}")
            out[k] = asdict(self.materials[k])
        return out

    def _device_part(self) -> dict[str, Any]:
        """The device's physics and the materials of its beads and plate."""
        dev = self.device
        return {"device": dev.physics_dict(),
                "device_materials": self.material_values(
                    [dev.bead_material, dev.plate_material if dev.has_plate else "none"])}

    def _chain_part(self) -> dict[str, Any]:
        """What a chain command reads: device, chain model, wall law and its inputs."""
        cfg = self.cfg
        part: dict[str, Any] = {**self._device_part(),
                                "chain": {k: cfg["chain"].get(k) for k in CHAIN_KEYS},
                                "fit_law": cfg["fit"].get("law")}
        law = wall_law(cfg)
        if law == "fem":
            part["fem_wall"] = {k: cfg["contact"].get(k) for k in FEM_WALL_KEYS}
        if law in ("fit", "table"):
            part["fit_set"] = cfg["fit"].get("set")
        return part

    def _sample_materials(self, samples: list[dict[str, Any]]) -> dict[str, Any]:
        return self.material_values([s["material"] for s in samples if s.get("material")])

    # ------------------------------------------------------------------ step inputs
    def inputs(self, step: str, key: str | None = None) -> dict[str, Any]:
        """The slice of the study the job ``step`` (``key``: its wildcard) reads, with the
        ssw version and the hash of its code (module docstring).

        Parameters
        ----------
        step : str
            The job's step, a key of ``STEP_MODULES``.
        key : str or None
            The job's wildcard (e.g. a contact family), or None.

        Returns
        -------
        dict
            ``step``, ``key``, ``ssw_version``, ``code`` (the hash of the step's modules) and
            ``config`` (the slice of the config the step reads).

        Raises
        ------
        ssw.errors.ConfigError
            When ``step`` is unknown, or ``key`` names no contact family, set, survey point or
        design soil range of the study.
        """
        from ssw import __version__
        from ssw.provenance import source_hash

        if step not in STEP_MODULES:
            raise ConfigError("step", step, f"one of {', '.join(STEP_MODULES)}")
        part = getattr(self, f"_{step}")(key)
        return {"step": step, "key": key, "ssw_version": __version__,
                "code": source_hash(STEP_MODULES[step]), "config": part}

    def _contact(self, family: str | None) -> dict[str, Any]:
        cfg = self.cfg
        if family not in self.families:
            raise ConfigError("contact family", family, f"one of {', '.join(self.families)}")
        ids = self.families[family]
        plates = {self.scenes[i].plate_material for i in ids}
        part: dict[str, Any] = {
            "contact": {k: cfg["contact"].get(k) for k in CONTACT_KEYS},
            "indenter": cfg["indenter"], "material_set": cfg.get("material_set"),
            "plates": self.material_values(plates), "scenes": ids,
            "samples": sorted({repr(self.scenes[i].sample) for i in ids}),
            "soil_models": sorted({repr(self.scenes[i].soil_model) for i in ids}),
        }
        if cfg["contact"].get("delta_mode") == "chain":  # the reach is the chain's
            part.update(self._chain_part(), fit_range=cfg["fit"]["range"])
        return part

    def _fit(self, set_name: str | None) -> dict[str, Any]:
        cfg = self.cfg
        if set_name not in cfg["sets"]:
            raise ConfigError("set", set_name, f"one of the sets: {', '.join(cfg['sets'])}")
        spec = cfg["sets"][set_name]
        ids = [s.scene_id for s in scenes(cfg, set_name)]
        part: dict[str, Any] = {
            "set_name": set_name, "set": spec, "scenes": ids, "fit": cfg["fit"],
            "material_set": cfg.get("material_set"), "indenter": cfg["indenter"],
            "plates": self.material_values(spec["plate_material"]),
        }
        if cfg["fit"]["range"].get("mode") == "chain" or _n_soils(cfg, set_name) > 1:
            # the fit range is the chain's reach; a grid set's TOF cost runs the chain
            part.update(self._chain_part(), contact=cfg["contact"])
        return part

    def _calibration(self, key: str | None = None) -> dict[str, Any]:
        cfg = self.cfg
        val = cfg.get("validation", {})
        samples = val.get("samples", [])
        return {**self._chain_part(), "calibration": cfg.get("calibration", {}),
                "samples": samples, "sample_materials": self._sample_materials(samples),
                "lowpass": val.get("lowpass"), "min_hits": val.get("min_hits")}

    def _sweep(self, key: str | None = None) -> dict[str, Any]:
        sw = self.cfg["chain"]["sweep"]
        return {**self._chain_part(), "calibration_use": uses_calibration(self.cfg),
                "sweep": {"soil_E": sw["soil_E"], "soil_nu": sw["soil_nu"]}}

    def _sweep_figure(self, key: str | None = None) -> dict[str, Any]:
        return {"study": self.cfg.get("study")}

    def _validation(self, key: str | None = None) -> dict[str, Any]:
        cfg = self.cfg
        val = cfg.get("validation", {})
        return {**self._chain_part(), "calibration_use": uses_calibration(cfg),
                "validation": val,
                "sample_materials": self._sample_materials(val.get("samples", [])),
                "daq": cfg.get("daq"), "study": cfg.get("study")}

    def _survey_point(self, point: str | None) -> dict[str, Any]:
        cfg = self.cfg
        points = {p["id"]: p for p in cfg.get("survey", {}).get("points", [])}
        if point not in points:
            raise ConfigError("survey point", point, f"one of {', '.join(points)}")
        val = cfg.get("validation", {})
        return {**self._chain_part(), "calibration_use": uses_calibration(cfg),
                "point": points[point], "lowpass": val.get("lowpass"),
                "min_hits": val.get("min_hits"), "daq": cfg.get("daq")}

    def _survey_table(self, key: str | None = None) -> dict[str, Any]:
        sv = self.cfg.get("survey", {})
        return {"survey": sv, "study": self.cfg.get("study")}

    def _design(self, soil: str | None) -> dict[str, Any]:
        """A design job (one soil range, one material): the design section, the device,
        the chain model and the fem wall's mesh (the design always runs the fem wall)."""
        cfg = self.cfg
        design = cfg.get("design", {})
        if soil not in design.get("soils", {}):
            raise ConfigError("design soil range", soil,
                              f"one of {', '.join(design.get('soils', {})) or '(none)'}")
        return {**self._device_part(),
                "chain": {k: cfg["chain"].get(k) for k in CHAIN_KEYS},
                "fem_wall": {k: cfg["contact"].get(k) for k in FEM_WALL_KEYS},
                "calibration_use": uses_calibration(cfg),
                "design": {k: v for k, v in design.items() if k != "soils"},
                "soil": design["soils"][soil],
                "plates": self.material_values(design.get("materials", [])),
                "sample_rate": cfg.get("daq", {}).get("sample_rate")}

    def _design_table(self, soil: str | None) -> dict[str, Any]:
        return {"design": self._design(soil), "study": self.cfg.get("study")}

    def _design_device(self, soil: str | None) -> dict[str, Any]:
        """A device design job (one soil range, one family): the plate design's inputs,
        the device space's bead and plate materials and the DAQ (rate and noise)."""
        dev = self.cfg.get("design", {}).get("device") or {}
        mats = [*dev.get("bead_materials", []), *dev.get("plate_materials", [])]
        return {**self._design(soil), "device_materials": self.material_values(mats),
                "daq": self.cfg.get("daq", {})}

    def device_families(self) -> dict[str, str]:
        """The device design's jobs when ``design.device.study`` is on: ``{name: D:MAT}``
        (``name`` = bead diameter in um and plate material, a wildcard value; ``D:MAT`` the
        ``--family`` flag), one per bead diameter and plate material; else none.

        Returns
        -------
        dict of str to str
            Job name -> its ``--family`` flag.
        """
        dev = self.cfg.get("design", {}).get("device") or {}
        if not dev.get("study"):
            return {}
        return {f"{round(float(d) * 1e6)}um_{m}": f"{float(d)!r}:{m}"
                for d in dev.get("bead_diameters", []) for m in dev.get("plate_materials", [])}

    def _design_device_table(self, soil: str | None) -> dict[str, Any]:
        return {"design": self._design_device(soil), "study": self.cfg.get("study")}

    def _report(self, key: str | None = None) -> dict[str, Any]:
        return {"study": self.cfg.get("study")}

    def param(self, step: str, key: str | None = None) -> str:
        """:meth:`inputs` as canonical JSON: the value a rule's params hold.

        Parameters
        ----------
        step : str
            The job's step.
        key : str or None
            The job's wildcard, or None.

        Returns
        -------
        str
            The canonical JSON text.
        """
        from ssw.provenance import canonical_json

        return canonical_json(self.inputs(step, key))

    def digest(self, step: str, key: str | None = None) -> str:
        """The digest of :meth:`inputs` (passed to the job's command as
        ``--inputs-sha256``).

        Parameters
        ----------
        step : str
            The job's step.
        key : str or None
            The job's wildcard, or None.

        Returns
        -------
        str
            The SHA-256 hex digest (:func:`ssw.provenance.digest`).
        """
        from ssw.provenance import digest

        return digest(self.inputs(step, key))


# ---------------------------------------------------------------------- rule helpers
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


#: Memory (MB) and wall time (min) a job asks of a cluster: (base, per unit of size), the
#: size being a contact family's scene count (0 for the other steps). Measured on the
#: thesis study (``results/benchmarks``: max_rss and s): a 300-scene family 320 MB and 7 s,
#: the calibration 250 MB and 8 s, the sweep 200 MB and 3 s, a fit 350 MB and 7 s; the
#: figures leave room (x4 memory, x40 time for slower nodes and finer meshes), and a retry
#: doubles them (Snakemake's ``attempt``).
RESOURCES: dict[str, tuple[float, float, float, float]] = {
    #                mem base, mem per unit, min base, min per unit
    "contact": (1000.0, 2.0, 5.0, 1.0 / 60.0),
    "fit": (1500.0, 0.0, 10.0, 0.0),
    "calibration": (1500.0, 0.0, 15.0, 0.0),
    "sweep": (1500.0, 0.0, 15.0, 0.0),
    "validation": (1500.0, 0.0, 15.0, 0.0),
    "survey_point": (1000.0, 0.0, 10.0, 0.0),
    "design": (2000.0, 0.0, 20.0, 0.0),
    "design_device": (3000.0, 0.0, 60.0, 0.0),
}


def mem_mb(step: str, size: int) -> int:
    """MB of memory a job of ``step`` of ``size`` asks for (:data:`RESOURCES`).

    Parameters
    ----------
    step : str
        The job's step (a key of :data:`RESOURCES`).
    size : int
        The job's size (a family's scene count; 0 for other steps).

    Returns
    -------
    int
        Memory, MB.
    """
    base, per, _, _ = RESOURCES[step]
    return round(base + per * size)


def runtime_min(step: str, size: int) -> int:
    """Minutes of wall time a job of ``step`` of ``size`` asks for (:data:`RESOURCES`).

    Parameters
    ----------
    step : str
        The job's step (a key of :data:`RESOURCES`).
    size : int
        The job's size (a family's scene count; 0 for other steps).

    Returns
    -------
    int
        Wall time, min (rounded up).
    """
    _, _, base, per = RESOURCES[step]
    return int(-(-(base + per * size) // 1))


def mpi_launch(resources: Any) -> list[str]:
    """The MPI launcher of a job with resources ``tasks`` > 1, else nothing.

    Parameters
    ----------
    resources : snakemake.io.Resources
        The job's resources: ``tasks`` (ranks) and ``mpi`` (the launcher's command line,
        default ``mpiexec``; e.g. ``srun`` or ``srun --mpi=pmi2`` on a cluster).

    Returns
    -------
    list of str
        ``[*launcher words, "-n", tasks]``, one argument each (a rule quotes each); empty
        for one task.
    """
    import shlex

    tasks = int(getattr(resources, "tasks", 1) or 1)
    if tasks <= 1:
        return []
    launcher = getattr(resources, "mpi", None) or "mpiexec"
    return [*shlex.split(str(launcher)), "-n", str(tasks)]


def mpi_flag(resources: Any) -> list[str]:
    """``--mpi`` for a job with resources ``tasks`` > 1 (its command splits its work over
    the ranks), else nothing.

    Parameters
    ----------
    resources : snakemake.io.Resources
        The job's resources.

    Returns
    -------
    list of str
        ``["--mpi"]`` or ``[]``.
    """
    return ["--mpi"] if int(getattr(resources, "tasks", 1) or 1) > 1 else []


def end_of_run() -> int:
    """Cancel the job scheduler's pending timers once a run is over (the workflow's
    ``onsuccess`` and ``onerror``).

    Snakemake's scheduler arms a ``threading.Timer`` at every scheduling round (its job-rate
    limit, ``--max-jobs-per-timespan``, 1 s by default) to look again for jobs to start.
    The timers are not daemon threads: the process waits for the last one before it exits,
    a second after its last job (measured: 1.3 s from "Complete log" to the exit of a
    two-job workflow, 0.3-0.4 s without the timers). After the last job no timer has anything
    left to do.

    Returns
    -------
    int
        How many timers were cancelled.
    """
    import threading

    timers = [t for t in threading.enumerate() if isinstance(t, threading.Timer)]
    for t in timers:
        t.cancel()
    return len(timers)


def submits_to_slurm(workflow: Any) -> bool:
    """Whether a Snakemake run submits its jobs to Slurm (the ``slurm`` executor).

    Parameters
    ----------
    workflow : snakemake.workflow.Workflow
        The running workflow.

    Returns
    -------
    bool
        True when its executor plugin is ``slurm``.
    """
    plugin = getattr(workflow, "executor_plugin", None)
    return plugin is not None and getattr(plugin, "name", "") == "slurm"


def check_cluster_fit(workflow: Any) -> None:
    """ConfigError naming every job of the run that asks for more than the largest node
    has (:func:`ssw.cluster.check_jobs_fit`), before anything is submitted.

    Parameters
    ----------
    workflow : snakemake.workflow.Workflow
        The running workflow (its DAG's jobs to run, local jobs left out).

    Raises
    ------
    ssw.errors.ConfigError
        When a job asks for more cores, memory or time than any node has.
    """
    from ssw.cluster import check_jobs_fit

    jobs = [(j.rule.name, int(j.threads), dict(j.resources.items()))
            for j in workflow.dag.needrun_jobs() if not j.is_local]
    check_jobs_fit(jobs)


def _job_name(job: Any) -> str:
    """A Snakemake job as ``rule[wildcard=value,...]`` (a group job: its group)."""
    rule = getattr(job, "rule", None)
    if rule is None:
        return str(job)
    wildcards = getattr(job, "wildcards_dict", None) or {}
    return rule.name + (f"[{','.join(f'{k}={v}' for k, v in wildcards.items())}]"
                        if wildcards else "")


def cap_status_pause(executor: Any, pause_s: float) -> None:
    """Hold the executor plugin's pause between two status queries at ``pause_s`` at most.

    The Slurm plugin (2.8.0, ``Executor.check_active_jobs``) sets the pause before the next
    query at the end of each query: back to ``--slurm-init-seconds-before-status-checks``
    when a job ended, else 10 s longer, up to 180 s. Each query is wrapped here, and the
    pause it leaves is clipped to ``pause_s`` (:func:`ssw.cluster.slurm_timing`), so
    that a job is seen to end at most ``pause_s`` after it ends.

    Parameters
    ----------
    executor : snakemake_interface_executor_plugins.executors.remote.RemoteExecutor
        The run's executor (``next_seconds_between_status_checks``, ``check_active_jobs``
        an async generator of the jobs still active).
    pause_s : float
        s, the longest pause.
    """
    query = executor.check_active_jobs

    async def capped(active_jobs: list[Any]) -> Any:
        async for job in query(active_jobs):
            yield job
        if executor.next_seconds_between_status_checks > pause_s:
            executor.next_seconds_between_status_checks = pause_s

    executor.check_active_jobs = capped


#: The executors whose spawned jobs' command lines name the interpreter unquoted
#: (snakemake-interface-executor-plugins 9.4, ``format_job_exec``): (module, class).
_SPAWNING_EXECUTORS = (
    ("snakemake_interface_executor_plugins.executors.remote", "RemoteExecutor"),
    ("snakemake_executor_plugin_slurm_jobstep", "Executor"),
    ("snakemake.executors.local", "Executor"),
)


def quote_job_python() -> list[str]:
    """Quote the interpreter in the command lines of the jobs Snakemake spawns.

    An executor that runs a job as ``python -m snakemake ...`` (the Slurm submission's, the
    Slurm job step's inside each job, the local one's for a ``run:`` rule) puts
    ``sys.executable`` into the command line unquoted, its other arguments quoted: a venv
    under a folder whose name holds a space (``~/My Projects/ssw/.venv``) makes every such
    job fail with ``/home/me/My: not found`` (snakemake issue 3211). Each executor class of
    ``_SPAWNING_EXECUTORS`` already imported (Snakemake loads the run's executor
    plugin before it reads the Snakefile; none is imported here) gets a
    ``get_python_executable`` whose answer is shell-quoted (unchanged for a path without
    special characters). Idempotent.

    Returns
    -------
    list of str
        The classes changed by this call, ``module.Class``.
    """
    import shlex
    import sys

    changed = []
    for module, name in _SPAWNING_EXECUTORS:
        cls = getattr(sys.modules.get(module), name, None)
        plain = getattr(cls, "get_python_executable", None)
        if cls is None or plain is None or getattr(plain, "ssw_quoted", False):
            continue

        def quoted(self: Any, _plain: Any = plain) -> str:
            return shlex.quote(str(_plain(self)))

        quoted.ssw_quoted = True  # type: ignore[attr-defined]
        cls.get_python_executable = quoted
        changed.append(f"{module}.{name}")
    return changed


def prepare_slurm_run(workflow: Any) -> list[str]:
    """Make a Snakemake run on Slurm see its jobs end, before anything is submitted.

    On a cluster without accounting storage the run's status command becomes ``squeue``
    (:func:`ssw.cluster.status_command`; or a ConfigError naming the flag), every job must
    fit a node (:func:`check_cluster_fit`), the pause between two status queries stops
    growing at the run's limit (:func:`ssw.cluster.slurm_timing`, :func:`cap_status_pause`),
    and a watch stops the run with a message when its jobs are lost, and when a job pends
    beyond its limit stops the run or reports the job, as its resources ``ssw_pending_s``
    and ``ssw_on_pending`` say (:func:`ssw.cluster.watch_lost_jobs`, with a ``squeue``
    query of the run's jobs by the run's job name, as the executor plugin's own, and
    Slurm's reason for each state).

    Parameters
    ----------
    workflow : snakemake.workflow.Workflow
        The run (the ``workflow`` of a Snakefile's ``onstart``; its executor is ``slurm``).

    Returns
    -------
    list[str]
        What changed or may go wrong, one line each, for the run's log.

    Raises
    ------
    ConfigError
        A job no node can hold, or a cluster on which the plugin cannot see jobs end.
    """
    import os
    import shutil

    from ssw import cluster
    from ssw.pending import pending_limit

    notes = []
    settings = workflow.executor_settings
    info = cluster.slurm_config()
    sacct = shutil.which("sacct") is not None
    init_s = int(settings.init_seconds_before_status_checks)
    wanted = cluster.status_command(info, settings.status_command, init_s, sacct)
    if wanted != settings.status_command:
        notes.append(f"this Slurm keeps no job accounting (AccountingStorageType = "
                     f"{info.accounting_storage}): job states come from {wanted}, as with "
                     f"--slurm-status-command {wanted}")
        settings.status_command = wanted
    used = cluster.effective_status_command(wanted, info.min_job_age_s, init_s, sacct)
    timing = cluster.slurm_timing(os.environ)
    pause_s = timing.status_pause_s
    warning = cluster.short_job_age(info, used, pause_s)
    if warning:
        notes.append(warning)
    check_cluster_fit(workflow)

    scheduler = workflow.scheduler
    executor = getattr(scheduler, "_executor", None)
    if executor is not None:
        cap_status_pause(executor, pause_s)
    run_id = getattr(executor, "run_uuid", None)
    if run_id is None:
        notes.append("the lost-jobs watch is off: the Slurm executor has no run ID")
        return notes
    # The controller's view of the run's jobs (squeue, by the run's job name, as the plugin's
    # own query, with Slurm's reason for each state): with squeue as the status command a
    # job it no longer lists is lost to the run after the short grace; with sacct (history
    # kept in slurmdbd, which may lag) only after the longest patience. A job pending beyond
    # its limit (its resources ssw_pending_s, ssw_on_pending) stops the run or is reported.
    command = cluster.squeue_command(run_id)

    def waiting() -> list[str]:
        return sorted(_job_name(j) for j in list(scheduler.running) if not j.is_local)

    known: dict[str, tuple[str, Any]] = {}

    def limits() -> dict[str, tuple[str, Any]]:
        # the jobs submitted so far (the plugin empties its list while a status query runs:
        # what was known stays known)
        known.update({str(info.external_jobid): (_job_name(info.job),
                                                 pending_limit(info.job.resources))
                      for info in list(getattr(executor, "active_jobs", ()))
                      if info.external_jobid is not None and str(info.external_jobid)
                      not in known})
        return known

    def lost(message: str) -> None:
        from snakemake_interface_common.exceptions import WorkflowError

        scheduler.executor_error_callback(WorkflowError(message))

    def note(message: str) -> None:
        from snakemake.logging import logger

        logger.warning(f"ssw cluster check: {message}")

    stall_s = pause_s + timing.vanish_s + float(workflow.execution_settings.latency_wait)
    vanish_s = timing.vanish_s if used == "squeue" else stall_s
    cluster.watch_lost_jobs(lambda: cluster.query_jobs(command), waiting, lost, stall_s,
                            vanish_s, timing.poll_s, limits, note)
    return notes


#: The study's stages in the report's order: results sub-folder -> the title of its category
#: (workflow/report/workflow.rst describes each title).
REPORT_STAGES: dict[str, str] = {
    "contact": "Contact (Stage I)",
    "fit": "Fits (Stage I)",
    "chain": "Chain (Stage II)",
    "validation": "Validation (Stage III)",
    "survey": "Survey",
    "design": "Plate design",
}


def report_stages(cfg: dict[str, Any]) -> list[str]:
    """The stages whose figures and tables a study's report shows, in report order.

    Parameters
    ----------
    cfg : dict[str, Any]
        The validated study config.

    Returns
    -------
    list[str]
        Keys of :data:`REPORT_STAGES`: ``contact`` when a set has one soil (its contact
        figure, rule ``fit_set``), ``fit`` when there are sets, ``chain`` and ``validation``
        always, ``survey`` when it has points, ``design`` when it has soil ranges.
    """
    shown = {
        "contact": bool(one_soil_sets(cfg)),
        "fit": bool(cfg.get("sets")),
        "chain": True,
        "validation": True,
        "survey": bool(survey_points(cfg)),
        "design": bool(cfg.get("design", {}).get("soils")),
    }
    return [stage for stage in REPORT_STAGES if shown[stage]]


def report_categories(cfg: dict[str, Any]) -> dict[str, str]:
    """Stage -> its category in the study's report: the stages the report shows numbered
    1, 2, ... in order (:func:`report_stages`); a stage it does not show keeps its bare
    title (no file of it reaches the report).

    Parameters
    ----------
    cfg : dict[str, Any]
        The validated study config.

    Returns
    -------
    dict[str, str]
        Every key of :data:`REPORT_STAGES`, e.g. ``{"design": "5. Plate design", ...}``.
    """
    numbered = {st: f"{i}. {REPORT_STAGES[st]}"
                for i, st in enumerate(report_stages(cfg), start=1)}
    return {st: numbered.get(st, title) for st, title in REPORT_STAGES.items()}


def report_tables(targets: list[Any], categories: dict[str, str], results: str = RESULTS
                  ) -> dict[str, list[str]]:
    """Stage -> its CSV tables among ``targets`` (a stage is a results sub-folder).

    Parameters
    ----------
    targets : list
        The report job's input files.
    categories : dict of str to str
        Stage -> its report category (only the keys are read).
    results : str
        The results folder.

    Returns
    -------
    dict of str to list of str
        Stage -> its CSV tables, in ``targets``' order, each once; stages with none left out.
    """
    out: dict[str, list[str]] = {}
    for stage in categories:
        tables = list(dict.fromkeys(str(t) for t in targets
                                    if str(t).startswith(f"{results}/{stage}/")
                                    and str(t).endswith(".csv")))
        if tables:
            out[stage] = tables
    return out


def report_page_args(output: Any, tables: dict[str, list[str]], categories: dict[str, str]
                     ) -> list[str]:
    """``ssw report`` arguments ``--page OUTPUT TITLE CSV...`` for every stage's tables
    page.

    Parameters
    ----------
    output : snakemake.io.OutputFiles
        The job's outputs, one per stage.
    tables : dict
        Stage -> its CSV tables (:func:`report_tables`).
    categories : dict
        Stage -> its report category (:func:`report_categories`).

    Returns
    -------
    list of str
        One argument per item (a rule quotes each: ``{params.pages:q}``).
    """
    return [a for st, ts in tables.items()
            for a in ("--page", str(getattr(output, st)), f"{categories[st]}: tables", *ts)]


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
