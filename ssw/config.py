"""Study configuration: load, validate against the JSON schema, fill defaults, expand grids.

The schema (``ssw/data/config.schema.yaml``, linked as ``workflow/schemas/config.schema.yaml``)
is enforced here for every ``ssw`` command and by ``snakemake.utils.validate`` in the
workflow. :func:`check_config` adds the checks a schema cannot express (material keys that
exist in the library, Poisson's ratios a model supports, non-empty grids) and raises
:class:`ssw.errors.ConfigError` naming the field, the value and what is allowed.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from ssw.errors import ConfigError
from ssw.materials import Material, material_set
from ssw.yamlio import safe_load

SCHEMA_PATH = Path(__file__).resolve().parent / "data" / "config.schema.yaml"
REPO_ROOT = Path(__file__).resolve().parent.parent
DEFAULT_CONFIG = REPO_ROOT / "config" / "config.yaml"


def load_schema() -> dict[str, Any]:
    """The config JSON schema as a dict.

    Returns
    -------
    dict
        The schema read from ``ssw/data/config.schema.yaml``.
    """
    return safe_load(SCHEMA_PATH.read_text())


def _looks_numeric(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


#: Settings of how a study runs, which left the study config for the workflow's profiles:
#: key path -> where it is now.
MOVED_KEYS = {
    ("contact", "jobs_per_group"): "gone: one contact job per plate family (rule "
    "contact_batch); to spread a family, split its set",
    ("chain", "sweep", "chunks"): "the number of sweep jobs is Snakemake's: "
    "--set-scatter sweep=N (or set-scatter in a profile)",
    ("chain", "sweep", "mpi_ranks"): "MPI ranks per sweep job are a resource: "
    "--set-resources tof_sweep:tasks=N (and mpi=srun on a cluster)",
}


def check_moved_keys(cfg: dict[str, Any]) -> None:
    """ConfigError for a setting of how to run (:data:`MOVED_KEYS`) found in a study
    config, naming where it went (a study's config says what to compute, not how).

    Parameters
    ----------
    cfg : dict
        The study config, as read.

    Raises
    ------
    ssw.errors.ConfigError
        When a key of :data:`MOVED_KEYS` is set.
    """
    for path, where in MOVED_KEYS.items():
        node: Any = cfg
        for k in path:
            node = node.get(k) if isinstance(node, dict) else None
            if node is None:
                break
        else:
            raise ConfigError(".".join(path), node, f"not a study setting any more: {where}")


def validate_config(cfg: dict[str, Any]) -> dict[str, Any]:
    """Validate ``cfg`` in place against the schema, fill defaults, and run semantic checks.

    Returns ``cfg``. Raises :class:`.ConfigError` on the first problem (the deepest error of
    the schema, so that the message names the offending field).

    Parameters
    ----------
    cfg : dict
        The study config, as read (changed in place).

    Returns
    -------
    dict
        ``cfg``, validated, its defaults filled.

    Raises
    ------
    ssw.errors.ConfigError
        On the first problem found.
    """
    from ssw.schema import first_file_error, message_of, path_of

    check_moved_keys(cfg)
    err = first_file_error(SCHEMA_PATH, cfg)
    if err is not None:
        hint = ""
        if isinstance(err.instance, str) and _looks_numeric(err.instance):
            hint = " (YAML reads a number like 1.0e6 as text: write 1.0e+6)"
        raise ConfigError(path_of(err), err.instance, message_of(err) + hint)
    check_config(cfg)
    return cfg


def load_config(path: str | Path | None = None, overrides: dict[str, Any] | None = None) -> dict:
    """Read a YAML study config, apply ``overrides`` (top-level keys), validate it.

    Without ``path``: ``config/config.yaml`` of the working folder when there is one (the
    repository), else the schema's defaults alone (a config is optional where it is not
    essential: every default comes with the package).

    Parameters
    ----------
    path : str or pathlib.Path or None
        The YAML file, or None.
    overrides : dict or None
        Top-level keys that replace the file's.

    Returns
    -------
    dict
        The validated config, its defaults filled.

    Raises
    ------
    ssw.errors.ConfigError
        When the file is missing, is not a YAML mapping, or the config is invalid.
    """
    if path is None:
        local = Path("config") / "config.yaml"
        if not local.is_file():
            cfg: dict[str, Any] = {}
            cfg.update(overrides or {})
            return validate_config(cfg)
        path = local
    p = Path(path)
    if not p.is_file():
        raise ConfigError("--config", str(p), "an existing YAML file")
    cfg = safe_load(p.read_text()) or {}
    if not isinstance(cfg, dict):
        raise ConfigError("--config", str(p), "a YAML mapping at the top level")
    cfg.update(overrides or {})
    return validate_config(cfg)


def device_of(cfg: dict[str, Any]) -> Any:
    """The config's device (:class:`ssw.device.Device`): a path (relative to the working
    folder, else to the repository) or the name of a shipped device.

    Parameters
    ----------
    cfg : dict
        The study config (its ``device``, default ``thesis``).

    Returns
    -------
    ssw.device.Device
        The device.
    """
    from ssw.device import load_device

    spec = cfg.get("device", "thesis")
    p = Path(spec)
    if not p.is_file() and not p.is_absolute() and (REPO_ROOT / p).is_file():
        spec = str(REPO_ROOT / p)
    return load_device(spec)


def dump_config(cfg: dict[str, Any]) -> str:
    """YAML text of a validated config, keys in their order; re-loadable by load_config.

    Parameters
    ----------
    cfg : dict
        The validated config.

    Returns
    -------
    str
        The YAML text, after a comment line.
    """
    header = "# Resolved ssw study config (validated, defaults filled). SI units.\n"
    return header + yaml.safe_dump(_plain(cfg), sort_keys=False, default_flow_style=None)


def _plain(obj: Any) -> Any:
    """Plain Python containers (Snakemake's config may hold its own mapping types)."""
    if isinstance(obj, dict):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_plain(v) for v in obj]
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def expand_grid(spec: dict[str, Any], field: str) -> np.ndarray:
    """Values of a grid axis: ``{values: [...]}`` or ``{start, stop, step}`` (stop included).

    Parameters
    ----------
    spec : dict
        The axis: ``values``, or ``start``, ``stop`` and ``step`` (in the axis's unit).
    field : str
        The axis's config path, named in an error.

    Returns
    -------
    numpy.ndarray
        The values, float.

    Raises
    ------
    ssw.errors.ConfigError
        When ``stop - start`` is not a non-negative whole multiple of ``step``.
    """
    if "values" in spec:
        return np.asarray(spec["values"], dtype=float)
    start, stop, step = (float(spec[k]) for k in ("start", "stop", "step"))
    n = (stop - start) / step
    if n < 0 or abs(n - round(n)) > 1e-9 * max(1.0, abs(n)):
        raise ConfigError(
            field, spec, "stop - start must be a non-negative whole multiple of step"
        )
    return start + step * np.arange(round(n) + 1)


def library(cfg: dict[str, Any]) -> dict[str, Material]:
    """The materials of the config's library and set.

    Parameters
    ----------
    cfg : dict
        The study config (``material_set``, ``materials_file``).

    Returns
    -------
    dict of str to ssw.materials.Material
        Material key -> material (SI units).
    """
    return material_set(cfg.get("material_set", "realistic"), _materials_path(cfg))


def _materials_path(cfg: dict[str, Any]) -> Path:
    """The config's materials library: ``materials_file`` (relative to the working folder,
    else to the repository), or the library shipped with ssw when it is null."""
    from ssw.materials import DEFAULT_LIBRARY

    name = cfg.get("materials_file")
    if name is None:
        return DEFAULT_LIBRARY
    p = Path(name)
    return p if p.is_absolute() or p.exists() else REPO_ROOT / p


def check_config(cfg: dict[str, Any]) -> None:
    """Checks the schema cannot express. Raises :class:`.ConfigError` naming the field.

    Parameters
    ----------
    cfg : dict
        The study config, schema-valid, its defaults filled.

    Raises
    ------
    ssw.errors.ConfigError
        On the first problem: an unknown material, a thickness < 0 m, a modulus <= 0 Pa, a
        Poisson's ratio outside (-1, 0.5], settings that contradict each other.
    """
    mats = library(cfg)
    known = ", ".join(sorted(mats))

    def need_material(field: str, key: str) -> None:
        if key not in mats:
            raise ConfigError(field, key, f"a material of the library: {known}")

    for name, s in cfg["sets"].items():
        for i, m in enumerate(s["plate_material"]):
            need_material(f"sets.{name}.plate_material[{i}]", m)
        t = expand_grid(s["plate_thickness"], f"sets.{name}.plate_thickness")
        if np.any(t < 0) or not np.all(np.isfinite(t)):
            raise ConfigError(f"sets.{name}.plate_thickness", t.tolist(), "thicknesses >= 0 m")
        E = expand_grid(s["soil_E"], f"sets.{name}.soil_E")
        if np.any(E <= 0) or not np.all(np.isfinite(E)):
            raise ConfigError(f"sets.{name}.soil_E", E.tolist(), "moduli > 0 Pa")
        nu = expand_grid(s["soil_nu"], f"sets.{name}.soil_nu")
        if np.any(nu <= -1) or np.any(nu > 0.5):
            raise ConfigError(
                f"sets.{name}.soil_nu", nu.tolist(),
                "Poisson's ratios in (-1, 0.5] (0.5 is solved with the mixed u-p element)",
            )
    ch = cfg.get("chain", {})
    dev = device_of(cfg)
    need_material("device: chain.bead_material", dev.bead_material)
    if dev.has_plate:
        need_material("device: plate.material", dev.plate_material)
    cal = cfg.get("calibration", {})
    if cal.get("use", False) and ch.get("wall_law") == "table":
        raise ConfigError(
            "calibration.use", True,
            "false with chain.wall_law table (the calibration needs a law defined at any E: "
            "fem, hertz or fit)",
        )
    for name, rng in cal.get("ranges", {}).items():
        if name not in cal.get("free", []):
            raise ConfigError(f"calibration.ranges.{name}", rng, "a range of a free parameter")
    if ch.get("wall_law") == "fit" and cfg.get("fit", {}).get("set") is None:
        raise ConfigError("chain.wall_law", "fit", "a K table: set fit.set, or use fem")
    sw = ch.get("sweep", {})
    if "soil_E" in sw:
        E = expand_grid(sw["soil_E"], "chain.sweep.soil_E")
        if np.any(E <= 0):
            raise ConfigError("chain.sweep.soil_E", E.tolist(), "moduli > 0 Pa")
    if "soil_nu" in sw:
        nu = expand_grid(sw["soil_nu"], "chain.sweep.soil_nu")
        if np.any(nu <= -1) or np.any(nu > 0.5):
            raise ConfigError("chain.sweep.soil_nu", nu.tolist(), "Poisson's ratios in (-1, 0.5]")
    fit = cfg.get("fit", {})
    if fit.get("set") is not None and fit["set"] not in cfg["sets"]:
        raise ConfigError("fit.set", fit["set"], f"one of the sets: {', '.join(cfg['sets'])}")
    points = cfg.get("survey", {}).get("points", [])
    if points:
        check_points(points)
    for i, smp in enumerate(cfg.get("validation", {}).get("samples", [])):
        need_material(f"validation.samples[{i}].material", smp["material"])
        rng = smp.get("soil_nu_range")
        if rng is not None and not -1.0 < rng[0] <= rng[1] <= 0.5:
            raise ConfigError(f"validation.samples[{i}].soil_nu_range", rng,
                              "[lo, hi] with -1 < lo <= hi <= 0.5")


def _lossless(x: float, scale: float, formats: tuple[str, ...] = ("g",)) -> str:
    """Text of ``x`` in units of ``scale`` (a power of ten: 1e6 for MPa, 1e-6 for um) that
    reads back to ``x`` exactly: the first of ``formats`` that does, else the shortest
    round-trip text of the scaled value, else ``x`` itself in base units followed by ``!``
    (so that it cannot be read as scaled)."""
    x = float(x)
    inverse = scale < 1.0
    k = float(round(1.0 / scale)) if inverse else float(scale)
    shown = x * k if inverse else x / k

    def back(text: str) -> float:
        return float(text) / k if inverse else float(text) * k

    for text in (*(format(shown, f) for f in formats), repr(shown)):
        if back(text) == x:
            return text
    return f"{x!r}!"


@dataclass(frozen=True)
class Scene:
    """One contact scene: a plate (or none) on a soil, indented by the rigid sphere. SI.

    ``sample`` (the soil's geometry: a finite block, a layer on a base; None: the default
    half-space), ``soil_model`` (the soil's constitutive law beyond elasticity; None:
    linear elastic) and ``plate_model`` (the plate's; None: elastic) are frozen, hashable
    objects with a ``key``: a short file-name-safe text that tells them apart (it enters
    the scene id).

    Parameters
    ----------
    plate_material : str
        The plate's material key; ``"none"`` when ``plate_thickness`` is 0.
    plate_thickness : float
        The plate's thickness, m (0: no plate).
    soil_E : float
        The soil's Young's modulus, Pa.
    soil_nu : float
        The soil's Poisson's ratio, dimensionless.
    sample : object or None
        The soil's geometry (None: half-space).
    soil_model : object or None
        The soil's constitutive model (None: linear elastic).
    plate_model : object or None
        The plate's constitutive model (None: elastic).
    """

    plate_material: str  # material key; "none" when plate_thickness == 0
    plate_thickness: float  # m
    soil_E: float  # Pa
    soil_nu: float  # -
    sample: Any = None
    soil_model: Any = None
    plate_model: Any = None

    @property
    def scene_id(self) -> str:
        """File-name-safe identifier, e.g. ``pla-t400um-E10MPa-nu0.300``; lossless: two
        scenes have the same id only when they are equal (every number reads back to its
        value exactly), so two grid points never share a curve."""
        plate = (
            "noplate"
            if self.plate_thickness == 0
            else f"{self.plate_material}-t{_lossless(self.plate_thickness, 1e-6)}um"
        )
        text = (f"{plate}-E{_lossless(self.soil_E, 1e6)}MPa-"
                f"nu{_lossless(self.soil_nu, 1.0, ('.3f', 'g'))}")
        for part in (self.sample, self.soil_model):
            if part is not None:
                text += f"-{part.key}"
        if self.plate_model is not None and self.plate_thickness > 0:
            text += f"-plate-{self.plate_model.key}"
        return text


def scenes(cfg: dict[str, Any], set_name: str) -> list[Scene]:
    """Scenes of set ``set_name``: the product of its axes, no-plate scenes deduplicated.

    Parameters
    ----------
    cfg : dict
        The study config.
    set_name : str
        The set's name (a key of ``sets``).

    Returns
    -------
    list of Scene
        The scenes, plate material outer, then thickness, E and Poisson's ratio.

    Raises
    ------
    ssw.errors.ConfigError
        When the set is unknown, its sample, soil or plate model is invalid, or two scenes
        share an id.
    """
    if set_name not in cfg["sets"]:
        raise ConfigError("set", set_name, f"one of the sets: {', '.join(cfg['sets'])}")
    s = cfg["sets"][set_name]
    from ssw.constitutive import model_from
    from ssw.sample import sample_from_dict

    model = model_from(s.get("soil_model"))
    sample = sample_from_dict(s.get("sample"), f"sets.{set_name}.sample")
    out: dict[str, Scene] = {}
    for m in s["plate_material"]:
        for t in expand_grid(s["plate_thickness"], f"sets.{set_name}.plate_thickness"):
            for E in expand_grid(s["soil_E"], f"sets.{set_name}.soil_E"):
                for nu in expand_grid(s["soil_nu"], f"sets.{set_name}.soil_nu"):
                    sc = Scene("none" if t == 0 else m, float(t), float(E), float(nu),
                               sample=sample, soil_model=model,
                               plate_model=_plate_model(cfg, set_name, m) if t > 0 else None)
                    other = out.setdefault(sc.scene_id, sc)
                    if other != sc:
                        raise ConfigError(f"sets.{set_name}", sc.scene_id,
                                          f"scenes that can be told apart: {sc} and {other} "
                                          "share one id")
    return list(out.values())


def _plate_model(cfg: dict[str, Any], set_name: str, material: str) -> Any:
    """The plate model of set ``set_name`` for the plate ``material`` (None: elastic): the
    set's ``plate_model``, its yield stress and hardening the material's library strengths
    unless the set gives them."""
    from ssw.constitutive import model_from

    spec = cfg["sets"][set_name].get("plate_model")
    field = f"sets.{set_name}.plate_model"
    if spec is None or not isinstance(spec, dict) or spec.get("model") == "linear-elastic":
        return model_from(spec, field)
    spec = dict(spec)
    if "yield_stress" not in spec:
        st = library(cfg)[material].strength
        if st.yield_stress is None:
            raise ConfigError(f"{field}.yield_stress", None,
                              f"a stress > 0 Pa (materials.{material} has no yield_stress)")
        spec["yield_stress"] = st.yield_stress
        spec.setdefault("hardening", st.hardening or 0.0)
    return model_from(spec, field)


def all_scenes(cfg: dict[str, Any]) -> dict[str, Scene]:
    """Every scene of every set, by scene id (a scene shared by two sets appears once).

    Raises ConfigError if two different scenes had one id (ids are lossless: a guard).

    Parameters
    ----------
    cfg : dict
        The study config.

    Returns
    -------
    dict of str to Scene
        Scene id -> scene.

    Raises
    ------
    ssw.errors.ConfigError
        When two different scenes share an id.
    """
    out: dict[str, Scene] = {}
    for name in cfg["sets"]:
        for sc in scenes(cfg, name):
            other = out.setdefault(sc.scene_id, sc)
            if other != sc:
                raise ConfigError(f"sets.{name}", sc.scene_id,
                                  f"scenes that can be told apart: {sc} and {other} share "
                                  "one id")
    return out


# ---------------------------------------------------------------------- survey points
def check_points(points: list[dict[str, Any]], field: str = "survey.points") -> None:
    """Ids unique and file-name safe, one kind of target, coordinates in pairs.

    Parameters
    ----------
    points : list of dict
        The survey points (schema-valid).
    field : str
        Their config path, named in an error.

    Raises
    ------
    ssw.errors.ConfigError
        On the first point that breaks a rule.
    """
    import re

    seen = set()
    for i, pt in enumerate(points):
        pid = pt["id"]
        if not re.fullmatch(r"[A-Za-z0-9_][A-Za-z0-9_.-]*", pid):
            raise ConfigError(f"{field}[{i}].id", pid,
                              "letters, digits, _ . - (not starting with . or -), as the "
                              "schema's $defs/id")
        if pid in seen:
            raise ConfigError(f"{field}[{i}].id", pid, "an id used once")
        seen.add(pid)
        if pt.get("target_E") is not None and pt.get("reference_E") is not None:
            raise ConfigError(f"{field}[{i}]", pid, "target_E or reference_E, not both")
        for a, b in (("x", "y"), ("latitude", "longitude")):
            if (pt.get(a) is None) != (pt.get(b) is None):
                raise ConfigError(f"{field}[{i}].{a}/{b}", [pt.get(a), pt.get(b)],
                                  "both coordinates or neither")
        nu = pt["soil_nu"]
        if isinstance(nu, list) and not (len(nu) == 2 and -1 < nu[0] <= nu[1] <= 0.5):
            raise ConfigError(f"{field}[{i}].soil_nu", nu, "NU or [LO, HI], -1 < LO <= HI <= 0.5")


def nu_text(nu: Any) -> str:
    """The ``--soil-nu`` argument of a point's Poisson's ratio (``NU`` or ``LO:HI``).

    Parameters
    ----------
    nu : float or list of float
        The Poisson's ratio, or its range ``[lo, hi]``; dimensionless.

    Returns
    -------
    str
        ``NU`` or ``LO:HI`` (``%g``).
    """
    if isinstance(nu, list | tuple):
        return f"{float(nu[0]):g}:{float(nu[1]):g}"
    return f"{float(nu):g}"
