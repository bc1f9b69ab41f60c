"""The predicted measurement of a designed device: the 95 % interval of E that ``ssw
measure`` would report, per hit and per point of ``hits`` hits, at the TOF and the
features levels.

For each soil modulus ``E`` (the ends and the middle of the design's grid) the information
of one hit (:func:`ssw.calibration.information.identifiability`, the machinery of ``ssw
identify``: the chain on the design's fem wall, the DAQ's acquisition of the config, its
noise ``noise_rms``) gives the Fisher matrix ``F = V diag(s^2) V^T`` over the scaled
parameters (``ln E``, the device's). A measurement holds the device at its calibrated
values and estimates E alone, so in ``ln E``

* the hits' noise: ``var_n = 1 / (m F_EE)`` over ``m`` hits (the ``device_known`` view of
  ``ssw identify``);
* the calibration's uncertainty (systematic: one calibration for every hit): the
  estimator's shift ``g = -F_Ec / F_EE`` per unit error of the calibrated parameters ``c``,
  ``var_c = g^T C g``, ``C`` the calibration's covariance in the scaled coordinates (a
  log-scaled parameter's relative); the estimator of a parameter held at a wrong value
  (Bard 1974, sec. 7-5);
* at the TOF level, the sampled peaks' bias ``b`` (s, :mod:`ssw.design.sampling`) and a
  calibration's stated model error ``sigma_m`` (relative to the TOF; the hook
  ``model_error``), both systematic: ``((b / T)^2 + sigma_m^2) / S^2``,
  ``S = |d ln TOF / d ln E|`` (``T S = sigma_T sqrt(F_EE)`` of the TOF level).

At the TOF level one hit's TOF scatters by the device's stated scatter and the DAQ's noise
and sampling spread through the peak picker, in quadrature (the design's ``u_TOF``
terms). The interval is ``E exp(+-1.96 sigma)`` (``sigma`` the standard deviation of
``ln E``, the sum of the variances).

References
----------
Bard, Y. (1974). *Nonlinear Parameter Estimation*. Academic Press, ch. 7.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

#: Two-sided 95 % quantile of the standard normal.
Z95 = 1.959963984540054
#: Levels predicted (``ssw identify``'s, without the whole waveform: ``ssw measure``'s).
LEVELS = ("tof", "features")


@dataclass(frozen=True)
class LevelPrediction:
    """One level's predicted uncertainty of ``ln E`` over the soils. Arrays (k,).

    Parameters
    ----------
    noise_hit : numpy.ndarray
        Standard deviation of ``ln E`` from one hit's noise.
    calibration : numpy.ndarray
        From the calibration's covariance (0: none stated).
    systematic : numpy.ndarray
        From the sampled peaks' bias and the model error (TOF level; 0 otherwise).
    """

    noise_hit: np.ndarray
    calibration: np.ndarray
    systematic: np.ndarray

    def sigma(self, hits: int) -> np.ndarray:
        """Standard deviation of ``ln E`` of a point.

        Parameters
        ----------
        hits : int
            Hits of the point (the noise averages over them, the other terms do not).

        Returns
        -------
        numpy.ndarray
            (k,) over the soils.
        """
        return np.sqrt(self.noise_hit**2 / hits + self.calibration**2 + self.systematic**2)


def calibration_shift_variance(info: Any, cov: np.ndarray | None,
                               names: tuple[str, ...]) -> tuple[float, float]:
    """``var_n`` of one hit and ``var_c`` (module docstring) from one level's information.

    Parameters
    ----------
    info : ssw.calibration.information.Information
        One hit's information over ``info.names`` (``E`` first), every parameter free.
    cov : numpy.ndarray or None
        The calibration's covariance over ``names`` in the scaled coordinates, or None.
    names : tuple of str
        Its parameters (those not in ``info.names`` are left out).

    Returns
    -------
    tuple of float
        ``(var_n, var_c)`` in ``(ln E)^2``; ``var_n`` infinite when one hit does not see E.
    """
    F = (info.vectors * info.singular_values**2) @ info.vectors.T
    e = info.names.index("E")
    F_EE = float(F[e, e])
    if not F_EE > 0:
        return float("inf"), 0.0
    if cov is None or not names:
        return 1.0 / F_EE, 0.0
    keep = [i for i, n in enumerate(names) if n in info.names]
    g = -np.array([F[e, info.names.index(names[i])] for i in keep]) / F_EE
    C = np.asarray(cov, float)[np.ix_(keep, keep)]
    return 1.0 / F_EE, float(g @ C @ g)


def scaled_covariance(cal: Any, values: dict[str, float], damping_law: str
                      ) -> tuple[np.ndarray | None, tuple[str, ...]]:
    """A calibration's covariance (SI) in the scaled coordinates of ``ssw identify``.

    Parameters
    ----------
    cal : ssw.calibration.Calibration or None
        The calibration (None: no covariance).
    values : dict
        The parameters' values, SI (a log-scaled one's covariance is divided by them).
    damping_law : str
        The contacts' dissipation law (the scale of ``damping``).

    Returns
    -------
    tuple
        ``(C, names)``; ``(None, ())`` without a covariance.
    """
    from ssw.calibration.waveform import parameter

    C = None if cal is None else cal.covariance_array()
    if C is None:
        return None, ()
    names = tuple(cal.covariance_parameters)
    s = np.array([values[n] if parameter(n, damping_law).log else
                  parameter(n, damping_law).scale for n in names], float)
    return C / np.outer(s, s), names


def predict(params: Any, wall_options: dict[str, Any], soil_E: np.ndarray, soil_nu: float,
            settings: Any, *, tof: np.ndarray, tof_scatter: np.ndarray, noise_rms: float,
            bias: np.ndarray, calibration: Any = None,
            model_error: float | None = None) -> dict[str, LevelPrediction]:
    """The predicted uncertainty of ``ln E`` of one device over ``soil_E`` (module docstring).

    Parameters
    ----------
    params : ssw.chain.params.ChainParams
        The device's chain.
    wall_options : dict
        The fem wall's options (its ``contact``).
    soil_E : numpy.ndarray
        (k,) Pa, the soils.
    soil_nu : float
        Their Poisson's ratio.
    settings : ssw.daq.settings.DaqSettings
        The acquisition.
    tof : numpy.ndarray
        (k,) s, the device's TOF at each soil (the model error's scale).
    tof_scatter : numpy.ndarray
        (k,) s, one hit's TOF standard deviation at each soil (random per hit).
    noise_rms : float
        N, the DAQ's white noise.
    bias : numpy.ndarray
        (k,) s, the sampled peaks' TOF bias (systematic).
    calibration : ssw.calibration.Calibration or None
        Its covariance enters as ``var_c``.
    model_error : float or None
        The calibration's stated TOF model error (relative, one standard deviation;
        systematic), or None.

    Returns
    -------
    dict
        Level (:data:`LEVELS`) -> :class:`LevelPrediction`.
    """
    from ssw.calibration.information import identifiability

    soil_E = np.asarray(soil_E, float)
    k = soil_E.size
    out = {lv: {"n": np.zeros(k), "c": np.zeros(k), "s": np.zeros(k)} for lv in LEVELS}
    for i, E in enumerate(soil_E):
        res = identifiability(params, "fem", wall_options, float(E), soil_nu, settings,
                              hits=1, tof_scatter=float(tof_scatter[i]), noise=noise_rms)
        C, names = scaled_covariance(calibration, res.values, res.damping_law)
        for lv in LEVELS:
            var_n, var_c = calibration_shift_variance(res.levels[lv], C, names)
            out[lv]["n"][i], out[lv]["c"][i] = np.sqrt(var_n), np.sqrt(var_c)
        # the TOF level's systematic terms over |dTOF / d ln E| = sigma_TOF sqrt(F_EE)
        n_tof = out["tof"]["n"][i]
        slope = float(tof_scatter[i]) / n_tof if np.isfinite(n_tof) else 0.0
        shift = np.hypot(float(bias[i]), (model_error or 0.0) * float(tof[i]))
        out["tof"]["s"][i] = shift / slope if slope > 0 else np.inf
    return {lv: LevelPrediction(d["n"], d["c"], d["s"]) for lv, d in out.items()}


def model_error_of(calibration: Any) -> float | None:
    """The relative TOF model error a calibration states: the hook of :func:`predict`'s
    ``model_error``.

    Parameters
    ----------
    calibration : ssw.calibration.Calibration or None
        The calibration.

    Returns
    -------
    float or None
        Its ``model_term().tau`` where its file has a model term, else None.
    """
    term = getattr(calibration, "model_term", None)
    if not callable(term):
        return None
    t = term()
    return None if t is None else float(t.tau)


def soil_indices(n: int) -> list[int]:
    """The soils predicted of a grid: its ends and its middle.

    Parameters
    ----------
    n : int
        Soils of the grid.

    Returns
    -------
    list of int
        Their indices, sorted, distinct.
    """
    return sorted({0, (n - 1) // 2, n - 1})


def interval_record(E: np.ndarray, sigma: np.ndarray) -> dict[str, list[float]]:
    """The 95 % interval ``E exp(+-1.96 sigma)`` and its relative half-width
    ``sinh(1.96 sigma)``.

    Parameters
    ----------
    E : numpy.ndarray
        (k,) Pa, the moduli.
    sigma : numpy.ndarray
        (k,) standard deviations of ``ln E``.

    Returns
    -------
    dict
        ``lo``, ``hi`` (Pa), ``half_width``, ``sigma_lnE``: JSON lists, None where E is
        not identified.
    """
    def lst(x: np.ndarray) -> list[float | None]:
        return [float(v) if np.isfinite(v) else None for v in x]

    return {"lo": lst(E * np.exp(-Z95 * sigma)), "hi": lst(E * np.exp(Z95 * sigma)),
            "half_width": lst(np.sinh(Z95 * sigma)), "sigma_lnE": lst(sigma)}


def predicted_measurement(result: dict[str, Any], base: Any, materials: dict[str, Any],
                          contact: dict[str, Any], settings: Any, *, point_hits: int = 5,
                          calibration: Any = None, model_error: float | None = None
                          ) -> dict[str, Any]:
    """The predicted measurement of the recommended and the base device of a device
    design's JSON (module docstring), for its JSON's ``prediction``.

    Parameters
    ----------
    result : dict
        The JSON of ``ssw design --space device``.
    base : ssw.chain.params.ChainParams
        The base device's chain (numerics; its bead radius the scale of ``contact``).
    materials : dict
        The materials library the design used.
    contact : dict
        The ``contact:`` settings for the base device's bead.
    settings : ssw.daq.settings.DaqSettings
        The acquisition.
    point_hits : int
        Hits of one measured point.
    calibration : ssw.calibration.Calibration or None
        Its covariance (scaled: relative for a log-scaled parameter) applied to each
        device.
    model_error : float or None
        The relative TOF model error (:func:`model_error_of`), or None.

    Returns
    -------
    dict
        ``statement``, ``point_hits``, ``soil_E`` and per device (``recommended``,
        ``reference``) per level the interval per hit and per point and the terms.
    """

    spec = result["spec"]
    out: dict[str, Any] = {
        "statement": (
            "95 % interval of E that ssw measure reports with the device held at its "
            "calibrated values: E exp(+-1.96 sigma), sigma^2 = var(noise of the hits, "
            "ssw identify's Fisher information of one hit over the hits) + var(the "
            "calibration's covariance through the estimator) + at the TOF level the "
            "sampled peaks' bias and the model error over |dTOF/dlnE| (ssw.design.predict)"),
        "point_hits": int(point_hits),
        "calibration": None if calibration is None else (
            getattr(calibration, "path", None) or "given") + (
            "" if calibration.covariance_array() is not None else " (no covariance)"),
        "model_error": model_error, "devices": {}}
    for name in ("recommended", "reference"):
        c = result.get(name)
        if c is not None:
            out["devices"][name] = device_prediction(
                c, spec, base, materials, contact, settings, point_hits=point_hits,
                calibration=calibration, model_error=model_error)
    return out


def device_prediction(c: dict[str, Any], spec: dict[str, Any], base: Any,
                      materials: dict[str, Any], contact: dict[str, Any], settings: Any, *,
                      point_hits: int = 5, calibration: Any = None,
                      model_error: float | None = None) -> dict[str, Any]:
    """The predicted intervals of one candidate of a device design at the ends and the
    middle of its soils.

    Parameters
    ----------
    c : dict
        The candidate's JSON record (its point and per-soil arrays).
    spec : dict
        The design's JSON ``spec`` (TOF scatter s, noise N, nu).
    base : ssw.chain.params.ChainParams
        The base device's chain.
    materials : dict
        The materials library.
    contact : dict
        The ``contact:`` settings for the base device's bead.
    settings : ssw.daq.settings.DaqSettings
        The acquisition.
    point_hits : int
        Hits of one measured point.
    calibration : ssw.calibration.Calibration or None
        Its covariance enters.
    model_error : float or None
        The relative TOF model error.

    Returns
    -------
    dict
        ``label``, ``soil_E``, ``tof_scatter_hit`` and per level the interval per hit and
        per point and the terms.
    """
    from ssw.design.device_eval import scaled_contact
    from ssw.design.space import DevicePoint

    point = DevicePoint.from_dict(c)
    p = point.params(base, materials)
    wall = {"contact": scaled_contact({**contact, "interface": p.plate_interface},
                                      p.bead_radius / base.bead_radius)}
    idx = soil_indices(len(c["soil_E"]))
    E = np.asarray(c["soil_E"], float)[idx]
    arr = {k: np.asarray(c[k], float)[idx] for k in ("tof_E", "noise_E", "spread_E",
                                                     "bias_E")}
    scatter = np.sqrt(spec["tof_scatter"]**2 + arr["noise_E"]**2 + arr["spread_E"]**2)
    levels = predict(p, wall, E, float(spec["soil_nu"]), settings, tof=arr["tof_E"],
                     tof_scatter=scatter, noise_rms=float(spec["noise_rms"]),
                     bias=arr["bias_E"], calibration=calibration, model_error=model_error)
    return {"label": c.get("label") or point.label(), "soil_E": E.tolist(),
            "tof_scatter_hit": scatter.tolist(),
            **{lv: {"hit": interval_record(E, lp.sigma(1)),
                    "point": interval_record(E, lp.sigma(point_hits)),
                    "terms_sigma_lnE": {"noise_hit": lp.noise_hit.tolist(),
                                        "calibration": lp.calibration.tolist(),
                                        "systematic": lp.systematic.tolist()}}
               for lv, lp in levels.items()}}


def rank_by_level(result: dict[str, Any], level: str, pool: int, predictor: Any
                  ) -> dict[str, Any]:
    """``--objective features``: the first ``pool`` feasible candidates of the design's
    ranking (its resolution's; hard-feasible ones when none is feasible) ranked by the
    largest predicted 95 % half-width of E per point over the soils at ``level``; the best
    becomes the recommended device.

    Parameters
    ----------
    result : dict
        The device design's JSON (changed in place: ``recommended``, ``objective``).
    level : str
        ``tof`` or ``features``.
    pool : int
        Candidates predicted.
    predictor : callable
        Candidate record -> :func:`device_prediction`'s record.

    Returns
    -------
    dict
        ``result``.
    """
    cands = result["candidates"]
    ok = [c for c in cands if c["feasible"]] or [c for c in cands if c["hard_feasible"]] \
        or cands
    scored = []
    for c in ok[:pool]:
        d = predictor(c)
        hw = d[level]["point"]["half_width"]
        worst = float("inf") if any(v is None for v in hw) else float(max(hw))
        scored.append((worst, c, d))
    scored.sort(key=lambda t: t[0])
    worst, best, _ = scored[0]
    old = result["recommended"]
    from ssw.design.space import DevicePoint

    label = DevicePoint.from_dict(best).label()
    reasons = [f"the smallest worst-case predicted 95 % half-width of E per point at the "
               f"{level} level, {100 * worst:.3g} %, among the {len(scored)} best devices "
               "of the resolution's ranking (--objective " + level + ")"]
    same = DevicePoint.from_dict(old).key == DevicePoint.from_dict(best).key
    reasons += old.get("reasons", []) if same else [
        f"the resolution's recommended device: {old.get('label')} (dE/E "
        f"{old['resolution']:.3g}; this one {best['resolution']:.3g})"]
    result["recommended"] = {**best, "label": label, "reasons": reasons,
                             "plastic": best.get("plastic")}
    result["objective_ranking"] = {
        "level": level, "pool": len(scored),
        "candidates": [{"label": DevicePoint.from_dict(c).label(), "resolution":
                        c["resolution"], "worst_half_width": w} for w, c, _ in scored]}
    return result


def worst_half_width(pred: dict[str, Any], device: str, level: str, per: str = "point"
                     ) -> float:
    """The largest relative half-width over the soils of one device's interval.

    Parameters
    ----------
    pred : dict
        :func:`predicted_measurement`'s record.
    device : str
        ``recommended`` or ``reference``.
    level : str
        ``tof`` or ``features``.
    per : str
        ``hit`` or ``point``.

    Returns
    -------
    float
        The half-width (inf where E is not identified).
    """
    hw = pred["devices"][device][level][per]["half_width"]
    return float("inf") if any(v is None for v in hw) else float(max(hw))


def human_lines(pred: dict[str, Any]) -> list[str]:
    """The predicted intervals as lines of text.

    Parameters
    ----------
    pred : dict
        :func:`predicted_measurement`'s record.

    Returns
    -------
    list of str
        Relative half-widths in %, per hit / per point, per device and level.
    """
    lines = [f"predicted 95 % interval of E (+-, relative), per hit and per "
             f"{pred['point_hits']}-hit point"
             + (f"; calibration {pred['calibration']}" if pred["calibration"] else
                "; device known (no calibration)")
             + (f"; model error {pred['model_error']:.3g}" if pred["model_error"] else "")]
    for name, d in pred["devices"].items():
        lines.append(f"  {name}: {d['label']}")
        for lv in LEVELS:
            cells = []
            for i, E in enumerate(d["soil_E"]):
                h, p = d[lv]["hit"]["half_width"][i], d[lv]["point"]["half_width"][i]
                fmt = lambda v: "n.i." if v is None else f"{100 * v:.3g} %"  # noqa: E731
                cells.append(f"E {E / 1e6:.4g} MPa: {fmt(h)} / {fmt(p)}")
            lines.append(f"    {lv:9s} " + "; ".join(cells))
    return lines
