"""Exact reruns: the slice of the study each job reads (:class:`Study`).

Every job declares the slice of the study it reads (:meth:`Study.inputs`): its part of the
config with every reference resolved to values (the device's physics, not its file name;
each material's E, nu, density and strength, not the library's path), and the hash of the
ssw source its command runs (:func:`ssw.provenance.source_hash` of the command's import
closure, the modules :data:`STEP_MODULES` names). The rules pass that slice to Snakemake as
a param (:meth:`Study.param`), and its digest to the command (:meth:`Study.digest`).
"""

from __future__ import annotations

import functools
from dataclasses import asdict
from typing import Any

from ssw.config import Scene, all_scenes, device_of, library, scenes
from ssw.errors import ConfigError
from ssw.workflow.jobs import _n_soils, families, uses_calibration, wall_law

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
        """Plate family -> scene ids (:func:`ssw.workflow.families`)."""
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

