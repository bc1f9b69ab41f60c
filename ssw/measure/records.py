"""A measurement of records (``ssw measure --information features|waveform``): E fitted to
the accepted hits' features or whole waveforms, starting from the TOF measurement of the
same recordings (:func:`ssw.measure.measure`), its budget, notes and identified parameters.
:func:`measure_information` is importable from :mod:`ssw.measure` as well.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from ssw.errors import RecordingError
from ssw.modulus import MODEL_TERM

if TYPE_CHECKING:
    from ssw.measure import Measurement


#: Terms of the TOF budget that a fit of the records replaces (the scatter of the hits and
#: the peak picking's sampling error are in the fit's own residuals; the TOF model's error,
#: :func:`ssw.modulus.model_term`, by the records' own: their calibration's floor and the
#: fit's ``sqrt(chi2 / dof)``).
_FIT_REPLACES = ("tof", "tof (stated scatter)", "sampling", MODEL_TERM)


def measure_information(m: Measurement, recordings: list[Any], level: str, params: Any,
                        wall: str, wall_options: dict[str, Any] | None, *, acquisition: Any,
                        trigger_level: float, tof_scatter: float,
                        full_scale: float | None = None, gain: float = 1.0,
                        floor: dict[str, float] | None = None,
                        covariance: dict[str, Any] | None = None,
                        model_loo: float | None = None,
                        discrepancy: dict[str, Any] | None = None) -> Measurement:
    """E from the records' features or whole waveforms (``ssw measure --information``),
    starting from the TOF measurement ``m`` of the same recordings.

    The sample's E, each accepted hit's striker speed, trigger time offset and delay are
    fitted (:func:`ssw.calibration.waveform.fit`) with the device at its (calibrated)
    values, the weights the noise's with the calibration's model-error ``floor`` (stated in
    the notes). E's standard error in ``ln E`` is the fit's, scaled by ``sqrt(chi2 / dof)``
    when the model does not reach the noise (a model-discrepancy term, stated), and with
    a floor by the square root of the hits (the model's error is common to a sample's
    hits and does not average down over them); with a floor the budget names its two
    shares, ``{level} fit`` (the noise's weights alone at the optimum,
    :func:`ssw.calibration.waveform.noise_std`) and ``model ({level})`` (the rest: the
    model-error floor and the misfit, :mod:`ssw.calibration.model_error`). These
    replace the TOF's scatter, sampling and model-error terms of ``m``'s budget, whose other
    terms (calibration, Poisson's ratio, wall, integrator) stay. ``chi2`` and its quantile flag
    a recording the model does not explain (a clipped hit, a yielding sample, a time
    offset the trigger does not explain): beyond
    :data:`ssw.calibration.waveform_fit.FLAG_QUANTILE` the measurement says so in its notes and
    ``flagged``.

    Parameters
    ----------
    m : Measurement
        The TOF measurement of the recordings (its E the start, its accepted hits used).
    recordings : list of ssw.daq.recording.Recording
        The sessions.
    level : str
        ``features`` or ``waveform``.
    params : ssw.chain.params.ChainParams
        The (calibrated) device's chain.
    wall : str
        The wall law.
    wall_options : dict or None
        Its options.
    acquisition : ssw.daq.model.Acquisition
        The measurement model (rate, sensitivity, coupling).
    trigger_level : float
        N, the recordings' trigger level.
    tof_scatter : float
        s, one hit's TOF scatter (the prior of each hit's delay).
    full_scale : float or None
        N, the rails (samples at them are left out).
    gain : float
        The DAQ gain (a waveform calibration's, :func:`ssw.calibration.waveform.with_fit`).
    floor : dict or None
        The model-error floor of the weights (``floor`` of :class:`ssw.calibration.waveform.Setup`:
        a calibration's, estimated from its references' residuals,
        :func:`ssw.calibration.waveform.model_floor`); None: the noise alone.
    covariance : dict or None
        A calibration of records' globals: ``names`` and ``matrix``, their covariance in
        the scaled coordinates (:func:`ssw.calibration.waveform.global_covariance`). Given,
        it replaces the TOF calibration's term of the budget by its own, propagated
        through the fit (:func:`ssw.calibration.waveform.propagated`), since the fit
        replaces what the TOF calibration fitted (the striker speed) by each hit's own.
    model_loo : float or None
        The calibration's model-error term in ``ln E`` at this level, from its references'
        leave-one-out predictions (:func:`ssw.calibration.records.with_loo`); it enters
        the budget as ``model ({level} leave-one-out)``.
    discrepancy : dict or None
        The calibration's model discrepancy at the features level (the JSON form of
        :class:`ssw.calibration.discrepancy.Discrepancy`): the model's features corrected
        by it (stated in the notes); None: uncorrected.

    Returns
    -------
    Measurement
        ``m`` with E, its interval and budget from the fit, and in ``extra``:
        ``information``, ``identified`` (value and standard error of every fitted parameter
        the records identify), ``chi2``, ``chi2_dof``, ``chi2_quantile``, ``flagged``,
        ``fit_runs``.
    """
    from ssw.calibration.records import fit_modulus
    from ssw.modulus import COVERAGE_Z

    hits = _accepted_hits(m, recordings, full_scale)
    f, setup = fit_modulus(hits, params, wall, wall_options, acquisition, level,
                           trigger_level=trigger_level, tof_scatter=tof_scatter, gain=gain,
                           floor=floor, E0=m.E, discrepancy=discrepancy)
    E = float(f.state.E[0])
    contrib = _information_budget(m, f, setup, level, floor, covariance, model_loo)
    u = float(np.sqrt(sum(v**2 for v in contrib.values())))
    notes = _information_notes(m, f, setup, level, floor, model_loo)
    extra = {**m.extra, "information": level, "identified": _identified(f, setup),
             "chi2": f.chi2, "chi2_dof": f.dof, "chi2_quantile": f.quantile,
             "flagged": f.flagged, "unexplained": f.unexplained,
             "fit_converged": f.converged, "fit_runs": f.runs,
             "E_tof": m.E, "E_tof_low": m.E_low, "E_tof_high": m.E_high}
    return replace(m, E=E, E_low=E * float(np.exp(-COVERAGE_Z * u)),
                   E_high=E * float(np.exp(COVERAGE_Z * u)), u=u, contributions=contrib,
                   notes=tuple(notes), extra=extra)


def _accepted_hits(m: Measurement, recordings: list[Any], full_scale: float | None) -> Any:
    """The accepted hits of the recordings as one sample's records (E unknown), each cut
    to the shortest record.

    Parameters
    ----------
    m : Measurement
        The TOF measurement (its accepted hits, sample rate and nu).
    recordings : list of ssw.daq.recording.Recording
        The sessions.
    full_scale : float or None
        N, the rails.

    Returns
    -------
    ssw.calibration.hits.Hits
        The records.

    Raises
    ------
    ssw.errors.RecordingError
        No accepted hit.
    """
    from ssw.calibration.hits import Hits

    forces, kt = [], []
    for rec in recordings:
        for h in rec.hits:
            forces.append(h.force)
            kt.append(h.trigger_index)
    keep = [i for i, a in enumerate(m.accepted) if a]
    if not keep:
        raise RecordingError("no accepted hit to fit")
    n = min(len(f) for f in forces)
    return Hits.of(np.stack([forces[i][:n] for i in keep]), [kt[i] for i in keep],
                   m.sample_rate, E=None, nu=m.nu, full_scale=full_scale)


def _information_budget(m: Measurement, f: Any, setup: Any, level: str,
                        floor: dict[str, float] | None, covariance: dict[str, Any] | None,
                        model_loo: float | None) -> dict[str, float]:
    """The budget of a measurement of records: ``m``'s terms but those the fit replaces
    (:data:`_FIT_REPLACES`; the TOF calibration's where the records' calibration replaces
    it), with the fit's (:func:`ssw.calibration.records.modulus_budget`) and the
    calibration's leave-one-out model term.

    Parameters
    ----------
    m : Measurement
        The TOF measurement.
    f : ssw.calibration.waveform_fit.Fit
        The fit of the records.
    setup : ssw.calibration.observation.Setup
        Its model.
    level : str
        ``features`` or ``waveform``.
    floor : dict or None
        The model-error floor of the weights.
    covariance : dict or None
        The calibration of records' globals' covariance.
    model_loo : float or None
        The calibration's model-error term in ``ln E``.

    Returns
    -------
    dict
        Each term's relative standard uncertainty of E.
    """
    from ssw.calibration.records import modulus_budget

    contrib = {k: v for k, v in m.contributions.items() if k not in _FIT_REPLACES}
    terms = modulus_budget(setup, f, level, floor, covariance)
    if f"calibration ({level})" in terms or setup.discrepancy is not None:
        contrib.pop("calibration", None)  # the records' calibration replaces the TOF's
    contrib.update(terms)
    if model_loo:
        contrib[f"model ({level} leave-one-out)"] = float(model_loo)
    return contrib


def _information_notes(m: Measurement, f: Any, setup: Any, level: str,
                       floor: dict[str, float] | None, model_loo: float | None) -> list[str]:
    """The notes of a measurement of records: ``m``'s but the TOF's scatter and model
    terms, then the floor, the discrepancy, the leave-one-out term, the misfit and the
    flags the fit calls for.

    Parameters
    ----------
    m : Measurement
        The TOF measurement.
    f : ssw.calibration.waveform_fit.Fit
        The fit of the records.
    setup : ssw.calibration.observation.Setup
        Its model (its discrepancy).
    level : str
        ``features`` or ``waveform``.
    floor : dict or None
        The model-error floor of the weights.
    model_loo : float or None
        The calibration's model-error term in ``ln E``.

    Returns
    -------
    list of str
        The notes.
    """
    from ssw.calibration.waveform_fit import FLAG_QUANTILE

    notes = [x for x in m.notes if "TOF term" not in x and MODEL_TERM not in x]
    if any(floor.values() if floor else ()):
        notes.append("the weights carry the calibration's model-error floor (relative "
                     "standard deviation added to the noise's, estimated from its references' "
                     "residuals; common to the hits, so E's fit error is scaled by the square "
                     "root of their number): "
                     + ", ".join(f"{k} {v:.2g}" for k, v in floor.items()))
    if setup.discrepancy is not None:
        notes.append("the model's features are corrected by the calibration's model "
                     "discrepancy, a line in (E / E_0)^(-2/5) fitted on its references: "
                     + setup.discrepancy.describe())
    if model_loo:
        notes.append(f"the calibration's references, each predicted as an unseen sample at "
                     f"this level, call for a model term of {100 * model_loo:.3g} % in E "
                     f"(95 % upper bound): 'model ({level} leave-one-out)'")
    if f.misfit > 1.0:
        notes.append(f"the model leaves chi2/dof = {f.misfit:.3g} of the records unexplained: "
                     f"E's fit error is scaled by sqrt({f.misfit:.3g}) (a model-discrepancy "
                     "term)")
    if f.unexplained:
        notes.append(f"FLAGGED: {f.unexplained} observation(s) of the records have no value in "
                     "the model (a pulse or a trigger crossing it does not produce)")
    elif f.flagged:
        notes.append(f"FLAGGED: the model does not explain these records (chi2 {f.chi2:.4g} "
                     f"on {f.dof} degrees of freedom, quantile {f.quantile:.6f} > "
                     f"{FLAG_QUANTILE}): a clipped hit, a yielding sample or a time "
                     "offset the trigger did not remove; E is not to be trusted as is")
    if not f.converged:
        notes.append("the fit did not converge: E is its last iterate")
    return notes


def _identified(f: Any, setup: Any) -> dict[str, dict[str, float]]:
    """Value and standard error (SI) of every fitted parameter the records identify (its
    standard error in the scaled coordinate at most
    :data:`ssw.calibration.information.IDENTIFIED_U`).

    Parameters
    ----------
    f : ssw.calibration.waveform_fit.Fit
        The fit of the records.
    setup : ssw.calibration.observation.Setup
        Its model (the scaled coordinates).

    Returns
    -------
    dict
        Per parameter's label, its ``value`` and ``std``.
    """
    from ssw.calibration.information import IDENTIFIED_U
    from ssw.calibration.observation import coordinate

    identified: dict[str, dict[str, float]] = {}
    for c, v in zip(f.free, f.values, strict=True):
        s = f.std(c)
        if s <= IDENTIFIED_U:
            log = c.name in ("E", "striker_velocity")
            identified[c.label] = {"value": float(v),
                                   "std": float(s * v if log else s * coordinate(setup, c)[1])}
    return identified
