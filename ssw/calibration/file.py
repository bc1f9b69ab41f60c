"""The calibration procedure and its file: one source of truth for a calibrated device.

:func:`calibrate` identifies the free parameters (:mod:`ssw.calibration.fit`), evaluates the
calibrated device once more canonically (one plain run, as ``ssw tof --calibration`` would),
and predicts each reference's E from a calibration made without it (leave-one-out: the
honest estimate of the error on an unseen sample).

The file (JSON, ``ssw_kind = "calibration"``, :data:`SCHEMA_VERSION`, checked against
``ssw/data/calibration.schema.yaml`` when read) holds the calibrated device, its nominal
version, the identified values with their standard errors and covariance, the singular
values, the residuals, the leave-one-out predictions, the model-error term where the
references reject the model (``model_error``) and the fit's findings (``warnings``), the
wall law and the numerics it was made with, the materials, and the provenance. Every chain
command takes it (``--calibration FILE``) and runs the calibrated device with that wall law
and numerics.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from ssw.calibration.fit import (
    check_enough,
    fit_warnings,
    identify,
    leave_one_out_sets,
    theta_dict,
)
from ssw.calibration.model import Reference, TofModel
from ssw.chain.params import chain_params
from ssw.device import Device, device_from_dict, parameter
from ssw.errors import ConfigError

KIND = "calibration"
#: The file format's version (2: the model-error term and the fit's findings).
SCHEMA_VERSION = 2
#: The calibration file's JSON Schema (``load_calibration`` checks every file against it).
SCHEMA_PATH = Path(__file__).resolve().parent.parent / "data" / "calibration.schema.yaml"


@dataclass(frozen=True)
class Calibration:
    """A calibrated device and how it was obtained. SI units.

    Parameters
    ----------
    device : ssw.device.Device
        The calibrated device (the identified values in place).
    device_nominal : ssw.device.Device
        The device the calibration started from.
    free : tuple of str
        The identified parameters (:data:`ssw.device.PARAMETERS`).
    parameters : dict
        Identified value per free parameter, in its SI unit.
    parameter_std : dict of str to float or None
        Standard error per parameter of ``covariance_parameters`` (None: no covariance).
    covariance : list of list of float or None
        Covariance of ``covariance_parameters`` (SI units squared), or None.
    singular_values : list of float
        Singular values of the fit's scaled Jacobian.
    unidentified : list of str
        Directions the references do not identify (text).
    references : list of dict
        Per reference: ``id``, ``E`` (Pa), ``nu``, ``tof``, ``tof_std``, ``tof_model``,
        ``residual`` (s), ``residual_pct`` (%), ``source``.
    loo : list of dict
        The leave-one-out predictions, one per reference.
    alternatives : list of dict of str to float
        Other solutions within chi^2 + 1 of the best.
    wall : dict
        The wall law (``law``) and its options.
    numerics : dict
        The chain numerics the calibration was made with.
    material_set : str
        The materials library's set.
    materials_file : str or None
        A materials file replacing the set, or None.
    provenance : dict
        Where the calibration comes from (inputs, versions, time).
    at_bound : dict of str to str
        Parameters a scan bound holds, with the bound.
    device_sha256 : str
        ``device_digest`` of the nominal device and its materials.
    path : str
        The file it was read from ("" when made in memory).
    covariance_parameters : tuple of str
        The parameters the covariance is over (continuous, not at a bound).
    model_error : dict or None
        The TOF model-error term (:class:`ssw.calibration.model_error.ModelError`), or None.
    warnings : list of str
        The fit's findings (:func:`ssw.calibration.fit.fit_warnings`).
    """

    device: Device
    device_nominal: Device
    free: tuple[str, ...]
    parameters: dict[str, Any]
    parameter_std: dict[str, float] | None
    covariance: list[list[float]] | None
    singular_values: list[float]
    unidentified: list[str]
    references: list[dict[str, Any]]
    loo: list[dict[str, Any]]
    alternatives: list[dict[str, float]]
    wall: dict[str, Any]
    numerics: dict[str, Any]
    material_set: str = "realistic"
    materials_file: str | None = None
    provenance: dict[str, Any] = field(default_factory=dict)
    at_bound: dict[str, str] = field(default_factory=dict)
    device_sha256: str = ""
    path: str = ""
    covariance_parameters: tuple[str, ...] = ()
    model_error: dict[str, Any] | None = None
    warnings: list[str] = field(default_factory=list)

    @property
    def residuals(self) -> list[float]:
        """Model minus measured TOF (s) per reference."""
        return [r["residual"] for r in self.references]

    def materials(self) -> dict[str, Any]:
        """The materials library the calibration used.

        Returns
        -------
        dict
            Material key -> :class:`ssw.materials.Material` (SI units).
        """
        from ssw.config import library

        return library({"material_set": self.material_set, "materials_file": self.materials_file})

    def chain_params(self, **numerics: Any) -> Any:
        """ChainParams of the calibrated device with the calibration's numerics (``numerics``
        override them).

        Parameters
        ----------
        **numerics : Any
            Numerics of :func:`ssw.chain.params.chain_params` replacing the calibration's.

        Returns
        -------
        ssw.chain.params.ChainParams
            The calibrated device's chain.
        """
        return chain_params(self.device, self.materials(), **{**self.numerics, **numerics})

    def covariance_array(self) -> np.ndarray | None:
        """The covariance (SI) of ``covariance_parameters``, or None.

        Returns
        -------
        numpy.ndarray or None
            (p, p) covariance, SI units squared.
        """
        return None if self.covariance is None else np.asarray(self.covariance, float)

    def model_term(self) -> Any:
        """The TOF model's error term (:class:`ssw.calibration.model_error.ModelError`), or
        None where the references do not reject the model.

        Returns
        -------
        ssw.calibration.model_error.ModelError or None
            The term.
        """
        from ssw.calibration.model_error import ModelError

        return ModelError.from_dict(self.model_error)

    def continuous(self) -> tuple[str, ...]:
        """The continuous free parameters, in order (the covariance is over those of them
        no bound holds: ``covariance_parameters``).

        Returns
        -------
        tuple of str
            Their names.
        """
        return tuple(n for n in self.free if parameter(n).kind == "continuous")

    def to_dict(self) -> dict[str, Any]:
        """The file's JSON layout (``ssw_kind``, ``SCHEMA_VERSION``, every field; SI).

        Returns
        -------
        dict
            The calibration file's content.
        """
        return {
            "ssw_kind": KIND, "schema_version": SCHEMA_VERSION,
            "device": self.device.to_dict(), "device_nominal": self.device_nominal.to_dict(),
            "free": list(self.free), "parameters": self.parameters,
            "parameter_std": self.parameter_std, "covariance": self.covariance,
            "covariance_parameters": list(self.covariance_parameters),
            "singular_values": self.singular_values, "unidentified": self.unidentified,
            "references": self.references, "residuals": self.residuals, "loo": self.loo,
            "alternatives": self.alternatives, "wall": self.wall, "numerics": self.numerics,
            "material_set": self.material_set, "materials_file": self.materials_file,
            "at_bound": dict(self.at_bound), "device_sha256": self.device_sha256,
            "model_error": self.model_error, "warnings": list(self.warnings),
            "provenance": self.provenance,
        }


def write_calibration(path: str | Path, cal: Calibration) -> None:
    """Write the calibration file atomically.

    Parameters
    ----------
    path : str or Path
        The file (JSON).
    cal : Calibration
        The calibration.

    Raises
    ------
    ValueError
        A value that is not finite (the file would be refused on reading), naming it.
    """
    from ssw.h5io import atomic_write_text, to_json

    d = json.loads(to_json(cal.to_dict()))
    bad = non_finite(d)
    if bad:
        raise ValueError(f"calibration field {bad} is not finite: not written")
    atomic_write_text(path, json.dumps(d) + "\n")


def non_finite(obj: Any, where: str = "") -> str | None:
    """The dotted path of the first number in a JSON document that is NaN or infinite
    (JSON Schema's bounds let them through), or None.

    Parameters
    ----------
    obj : Any
        A JSON document (dicts, lists, numbers, strings).
    where : str
        The dotted path of ``obj`` in the document ("" at the top).

    Returns
    -------
    str or None
        The path of the first NaN or infinite number, or None.
    """
    if isinstance(obj, float) and not np.isfinite(obj):
        return where or "(top level)"
    items = (obj.items() if isinstance(obj, dict) else enumerate(obj)
             if isinstance(obj, list) else ())
    for k, v in items:
        found = non_finite(v, f"{where}.{k}" if where else str(k))
        if found:
            return found
    return None


def load_calibration(path: str | Path) -> Calibration:
    """Read a calibration file written by :func:`write_calibration` (``ssw calibrate``).

    The file is checked against its JSON Schema (``ssw/data/calibration.schema.yaml``,
    through :func:`ssw.schema.first_file_error`), NaN and infinities are refused anywhere,
    and the covariance must be square over its parameters, symmetric and positive definite
    (``check_covariance``); each refusal names the field.

    Parameters
    ----------
    path : str or Path
        The file.

    Returns
    -------
    Calibration
        The calibration.

    Raises
    ------
    ConfigError
        A file that is not a readable calibration of this format, naming the field.
    """
    from ssw.schema import first_file_error, path_of

    p = Path(path)
    try:
        d = json.loads(p.read_text())
    except (OSError, ValueError) as exc:
        raise ConfigError("--calibration", str(p), f"a readable JSON file ({exc})") from exc
    if not isinstance(d, dict) or d.get("ssw_kind") != KIND:
        raise ConfigError("--calibration", str(p),
                          "a calibration file written by `ssw calibrate --output FILE.json`")
    if d.get("schema_version") != SCHEMA_VERSION:
        raise ConfigError(f"{p}: schema_version", d.get("schema_version"),
                          f"calibration schema version {SCHEMA_VERSION}: the file was "
                          "written by an older ssw (version 2 adds the model-error term, "
                          "model_error, and the fit's findings, warnings): recalibrate with "
                          "this ssw (ssw calibrate ... --output FILE.json)")
    bad = non_finite(d)
    if bad:
        raise ConfigError(f"{p}: {bad}", "NaN or infinity", "a finite number")
    err = first_file_error(SCHEMA_PATH, d)
    if err is not None:
        raise ConfigError(f"{p}: {path_of(err)}", err.instance, err.message)
    free = tuple(d["free"])
    cal = Calibration(
        device=device_from_dict(d["device"], f"{p} (device)"),
        device_nominal=device_from_dict(d["device_nominal"], f"{p} (device_nominal)"),
        free=free, parameters=d["parameters"], parameter_std=d["parameter_std"],
        covariance=d["covariance"], singular_values=d["singular_values"],
        unidentified=d["unidentified"], references=d["references"], loo=d["loo"],
        alternatives=d["alternatives"], wall=d["wall"], numerics=d["numerics"],
        material_set=d["material_set"], materials_file=d["materials_file"],
        provenance=d["provenance"], at_bound=dict(d["at_bound"]),
        device_sha256=d["device_sha256"], path=str(p),
        covariance_parameters=tuple(d["covariance_parameters"]),
        model_error=d["model_error"], warnings=list(d["warnings"]),
    )
    check_covariance(cal, str(p))
    return cal


def check_covariance(cal: Calibration, source: str) -> None:
    """ConfigError unless the covariance (if any) is square over its parameters (the
    continuous free ones no bound holds), finite, symmetric and positive definite.

    Parameters
    ----------
    cal : Calibration
        The calibration.
    source : str
        Where it was read from, naming the field in errors.

    Raises
    ------
    ssw.errors.ConfigError
        The covariance's parameters, shape, symmetry or definiteness is wrong.
    """
    field_ = f"{source}: covariance"
    names = cal.covariance_parameters
    cont = cal.continuous()
    if set(names) - set(cont) or set(names) & set(cal.at_bound):
        raise ConfigError(f"{source}: covariance_parameters", list(names),
                          f"continuous free parameters ({', '.join(cont)}) not at a bound "
                          f"({', '.join(cal.at_bound) or 'none'})")
    if cal.covariance is None:
        return
    C = np.asarray(cal.covariance, float)
    if C.shape != (len(names), len(names)):
        raise ConfigError(field_, list(C.shape),
                          f"a {len(names)} x {len(names)} matrix over {', '.join(names)}")
    if not np.all(np.isfinite(C)) or not np.allclose(C, C.T, rtol=1e-9,
                                                      atol=1e-12 * np.abs(C).max()):
        raise ConfigError(field_, C.tolist(), "a finite symmetric matrix")
    if np.any(np.linalg.eigvalsh(C) <= 0):
        raise ConfigError(field_, C.tolist(), "a positive definite matrix (eigenvalues > 0)")


def device_digest(device: Device, materials: dict[str, Any]) -> str:
    """What a calibration was made for: the digest of the device's physics and of the
    values of its materials (``ssw.provenance.digest``); the calibrated parameters are
    part of it at their nominal values.

    Parameters
    ----------
    device : ssw.device.Device
        The (nominal) device.
    materials : dict
        The materials library (its bead and plate materials enter).

    Returns
    -------
    str
        The SHA-256 digest (hex).
    """
    from dataclasses import asdict

    from ssw.provenance import digest

    keys = [device.bead_material] + ([device.plate_material] if device.has_plate else [])
    return digest({"device": device.physics_dict(),
                   "materials": {k: asdict(materials[k]) for k in keys if k in materials}})


def calibrate(
    refs: list[Reference], device: Device, free: list[str] | tuple[str, ...], *,
    materials: dict[str, Any], numerics: dict[str, Any], wall: str,
    wall_options: dict[str, Any] | None = None,
    ranges: dict[str, tuple[float, float]] | None = None, loo: bool = True,
    scan_points: int | None = None, material_set: str = "realistic",
    materials_file: str | None = None, provenance: dict[str, Any] | None = None,
    on_run: Any = None, recorded_wall_options: dict[str, Any] | None = None,
    reference_sample: Any = None,
) -> Calibration:
    """Identify ``free`` device parameters from ``refs`` (see :mod:`ssw.calibration.fit`).

    Where the references reject the model (their chi^2 with the stated TOF uncertainties
    beyond its 95 % quantile) the calibration carries a relative TOF model error in its
    weights, its covariance and every interval made through it (``model_error``,
    :mod:`ssw.calibration.model_error`); a fit that did not converge, leaves a direction
    unidentified (no covariance then) or has no degree of freedom answers with that stated
    (``warnings``, :func:`ssw.calibration.fit.fit_warnings`). Only the input is refused.

    Parameters
    ----------
    refs : list of ssw.calibration.model.Reference
        Reference samples with measured TOFs.
    device : ssw.device.Device
        The nominal device.
    free : list of str
        Names of :data:`ssw.device.PARAMETERS` to identify.
    materials : dict
        The materials library (key -> Material).
    numerics : dict
        Non-device ChainParams fields (steps_per_contact, t_max, gravity, ...).
    wall : str
        The last-contact law's name (:data:`ssw.walls.WALLS`).
    wall_options : dict or None
        The wall builder's options.
    ranges : dict or None
        Scan range ``(lo, hi)`` (SI) per free parameter; None: the defaults of
        :data:`ssw.device.PARAMETERS`.
    loo : bool
        Also calibrate without each reference and predict its E.
    scan_points : int or None
        Grid points per continuous parameter of the global scan; None: automatic.
    material_set : str
        The materials library's set, recorded in the file.
    materials_file : str or None
        The materials library's file, recorded in the file; None: the shipped one.
    provenance : dict or None
        Extra provenance entries recorded in the file.
    on_run : callable or None
        Called after each batched run of the forward model (a progress bar's update).
    recorded_wall_options : dict or None
        The wall options the file records for the calibrated device (default
        ``wall_options``): without the references' sample, which is theirs, not the
        device's (a later measurement names its own).
    reference_sample : ssw.sample.Sample or None
        The references' sample, recorded in the provenance; None: half-spaces.

    Returns
    -------
    Calibration
        The calibrated device, its fit and its findings.

    Raises
    ------
    ConfigError
        No reference, fewer references than parameters freed
        (:func:`ssw.calibration.fit.check_enough`), mixed TOF uncertainties.
    CalibrationError
        A reference TOF the device cannot produce
        (:func:`ssw.calibration.fit.check_producible`).
    """
    if not refs:
        raise ConfigError("--reference", [], "at least one reference sample")
    t0 = time.perf_counter()
    opts = dict(wall_options or {})
    model = TofModel(device, tuple(free), np.array([r.E for r in refs]),
                     np.array([r.nu for r in refs]), materials, dict(numerics), wall, opts,
                     on_run=on_run)
    fit, subs, warnings = _fitted(model, refs, loo, ranges, scan_points)
    merr = None if fit.model_error is None else fit.model_error.to_dict()
    values = theta_dict(model.free, fit.theta)
    cal_device = device.with_(**values)
    references = _reference_rows(refs, chain_params(cal_device, materials, **numerics), wall,
                                 opts)
    std = _parameter_std(fit)
    loo_rows = _loo_predictions(model, refs, subs, materials, numerics, wall, opts) if loo else []
    prov = {**_provenance(refs, model, device, wall, numerics, fit, merr, reference_sample, t0),
            **(provenance or {})}
    return Calibration(
        device=cal_device, device_nominal=device, free=model.free, parameters=values,
        parameter_std=std, covariance=None if fit.covariance is None else fit.covariance.tolist(),
        singular_values=fit.singular_values.tolist(), unidentified=list(fit.unidentified),
        references=references, loo=loo_rows, alternatives=list(fit.alternatives),
        wall={"law": wall, "options": _plain_options(
            opts if recorded_wall_options is None else dict(recorded_wall_options))},
        numerics=dict(numerics), material_set=material_set, materials_file=materials_file,
        provenance=prov, at_bound=dict(fit.at_bound),
        device_sha256=device_digest(device, materials),
        covariance_parameters=fit.covariance_names, model_error=merr, warnings=warnings,
    )


def _fitted(model: TofModel, refs: list[Reference], loo: bool,
            ranges: dict[str, tuple[float, float]] | None,
            scan_points: int | None) -> tuple[Any, list[Any], list[str]]:
    """The fit of a calibration (:func:`ssw.calibration.fit.identify`), its subsets' when
    ``loo``, and its warnings; a covariance no consumer can use dropped.

    Parameters
    ----------
    model : TofModel
        The TOF model of the references.
    refs : list of Reference
        The references.
    loo : bool
        Fit every leave-one-out subset as well.
    ranges : dict or None
        The free parameters' ranges (SI).
    scan_points : int or None
        The start scan's points.

    Returns
    -------
    tuple
        The fit, the subsets' fits and the warnings.

    Raises
    ------
    ConfigError
        Fewer references than free parameters.
    """
    check_enough(len(refs), model.free)
    subsets = leave_one_out_sets(len(refs)) if loo else []
    fit, subs = identify(model, refs, ranges=ranges, subsets=subsets, scan_points=scan_points)
    warnings = fit_warnings(fit)
    if any(w.startswith("the covariance is not") for w in warnings):
        fit = replace(fit, covariance=None, std=None)  # a covariance no consumer can use
    return fit, subs, warnings


def _parameter_std(fit: Any) -> dict[str, float] | None:
    """The fit's standard error of each parameter of its covariance (SI), or None without a
    covariance.

    Parameters
    ----------
    fit : ssw.calibration.fit.Fit
        The calibration's fit.

    Returns
    -------
    dict or None
        Name -> standard error.
    """
    return None if fit.std is None else dict(zip(fit.covariance_names, map(float, fit.std),
                                                 strict=True))


def _reference_rows(refs: list[Reference], params: Any, wall: str,
                    opts: dict[str, Any]) -> list[dict[str, Any]]:
    """The file's rows of the references: each one's measured TOF and the calibrated
    device's (``params``, one plain run on ``wall`` with ``opts``: what users reproduce), s,
    and the residual (s and %)."""
    from ssw.tof import api

    tof_model = np.asarray(api.tof([r.E for r in refs], [r.nu for r in refs], params, wall,
                                   **opts), float)
    return [
        {"id": r.id, "E": r.E, "nu": r.nu, "tof": r.tof, "tof_std": r.tof_std,
         "source": r.source, "tof_model": float(tc), "residual": float(tc - r.tof),
         "residual_pct": float(100.0 * (tc - r.tof) / r.tof)}
        for r, tc in zip(refs, tof_model, strict=True)
    ]


def _provenance(refs: list[Reference], model: TofModel, device: Device, wall: str,
                numerics: dict[str, Any], fit: Any, merr: dict[str, Any] | None,
                reference_sample: Any, t0: float) -> dict[str, Any]:
    """The calibration's provenance: its inputs' record, the fit's cost and findings and
    how its residuals were weighted (with the model-error term where the references reject
    the model); ``t0`` the calibration's start (``time.perf_counter``, s)."""
    from ssw.provenance import record

    if not fit.weights_known:
        weights = "1 % of each TOF, covariance scaled by chi2/(n - q), q its parameters"
    else:
        weights = "given TOF uncertainties" + (
            f" and a relative TOF model error tau = {merr['tau']:.4g} (the references "
            "reject the model)" if merr else "")
    return {**record({"references": [r.__dict__ for r in refs], "free": list(model.free),
                      "device": device.physics_dict(), "wall": wall,
                      "numerics": dict(numerics)}),
            "created_utc": datetime.now(UTC).isoformat(),
            "wall_time_s": time.perf_counter() - t0, "scan_points": fit.scan_points,
            "parameter_sets_evaluated": model.evaluations, "batched_runs": model.runs,
            "converged": fit.converged, "chi2": fit.chi2, "weights": weights,
            "model_error_tau": None if merr is None else merr["tau"],
            "reference_sample": None if reference_sample is None else reference_sample.to_dict()}


def _plain_options(opts: dict[str, Any]) -> dict[str, Any]:
    """Wall options as JSON (paths as text; objects by their type name)."""
    out = {}
    for k, v in opts.items():
        if isinstance(v, str | int | float | bool) or v is None:
            out[k] = v
        elif isinstance(v, Path):
            out[k] = str(v)
        elif isinstance(v, dict):
            out[k] = _plain_options(v)
        else:
            out[k] = f"<{type(v).__name__}>"
    return out


#: A left-out plastic sample's E is sought within this factor of its reference E, on this
#: many moduli (each a plastic FEM tabulation, ~10-25 s; the elastic inverse's 48-point
#: grid over 10-1000 MPa would take an hour).
PLASTIC_LOO_SPAN, PLASTIC_LOO_POINTS = 1.5, 6


def _loo_predictions(model: TofModel, refs: list[Reference], subs: dict, materials: dict,
                     numerics: dict, wall: str, opts: dict) -> list[dict[str, Any]]:
    """E of each reference inverted with the calibration made without it (batched).

    The left-out fits are the other references' least squares in the directions they
    identify, the rest held at the full calibration (:func:`ssw.calibration.fit.
    refine_subsets`); ``identified`` says whether they identify every parameter at the
    fit (else the prediction leans on the full calibration there). No interval is given: the
    left-out problems are strongly nonlinear (without the softest foam the static load
    lies along a curved valley of near-exact fits, where the local singular values swing
    from ~10 to ~0.1), so a linearized covariance is not trustworthy there. The local
    singular values are reported with the fit. A ``plastic`` wall (one model per reference,
    ``opts['soil_model']``) inverts each left-out sample with its own model, within
    :data:`PLASTIC_LOO_SPAN` of its E."""
    from ssw.tof.inverse import invert_batch

    keys = leave_one_out_sets(len(refs))
    cont = model.continuous
    ints = model.integers
    groups: dict[tuple, list[int]] = {}
    for i, key in enumerate(keys):
        sol = subs[key]
        ivals = tuple(round(float(sol.theta[model.free.index(n)])) for n in ints)
        groups.setdefault(ivals, []).append(i)
    E_pred = np.full(len(refs), np.nan)
    reasons = [""] * len(refs)
    for ivals, members in groups.items():
        base = chain_params(model.device.with_(**dict(zip(ints, ivals, strict=True))),
                            materials, **numerics)
        vary = {n: np.array([subs[keys[i]].theta[model.free.index(n)] for i in members])
                for n in cont}
        if wall == "plastic":  # one sample's model each, its law tabulated per modulus
            for j, i in enumerate(members):
                res = invert_batch(
                    [refs[i].tof], [refs[i].nu], base, wall,
                    vary={n: v[j:j + 1] for n, v in vary.items()} or None, strict=False,
                    E_range=(refs[i].E / PLASTIC_LOO_SPAN, refs[i].E * PLASTIC_LOO_SPAN),
                    grid_points=PLASTIC_LOO_POINTS,
                    **{**opts, "soil_model": opts["soil_model"][i]})
                E_pred[i], reasons[i] = res.E[0], res.reason[0]
            continue
        res = invert_batch([refs[i].tof for i in members], [refs[i].nu for i in members],
                           base, wall, vary=vary or None, strict=False, **opts)
        for j, i in enumerate(members):
            E_pred[i] = res.E[j]
            reasons[i] = res.reason[j]
    rows: list[dict[str, Any]] = []
    for i, (key, r) in enumerate(zip(keys, refs, strict=True)):
        sol = subs[key]
        ok = np.isfinite(E_pred[i])
        rows.append({
            "id": r.id, "E": r.E, "nu": r.nu, "tof": r.tof,
            "E_predicted": float(E_pred[i]) if ok else None,
            "error_pct": float(100.0 * (E_pred[i] - r.E) / r.E) if ok else None,
            "parameters": theta_dict(model.free, sol.theta),
            "chi2": float(sol.chi2) if np.isfinite(sol.chi2) else None,
            "singular_values": sol.singular_values.tolist(), "identified": sol.identified,
            "reason": reasons[i], "at_bound": dict(sol.at_bound),
        })
    return rows
