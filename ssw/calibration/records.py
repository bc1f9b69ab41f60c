"""A calibration refined by the references' records, level by level (``ssw calibrate
--information features|waveform``).

The TOF calibration (:func:`ssw.calibration.file.calibrate`) always answers: where its
references reject its model it carries the model's error (:mod:`ssw.calibration.model_error`)
instead of refusing, so the records' levels never wait on its chi^2. Each level then stands
on its own records:

* ``features``: from the TOF calibration's device, the start the records point to (a grid
  of the sensor's mass and the contact dashpot, each point's hits fitted, refined around
  the best: :func:`ssw.calibration.waveform.global_start`,
  :func:`ssw.calibration.waveform.refine_start`), then every global the features identify
  freed, with the model-error floor their residuals call for
  (:func:`ssw.calibration.waveform.calibrate_records`);
* ``waveform``: from the features' calibration (its globals and DAQ gain; each hit's
  parameters fitted to the samples and the floor they leave estimated before the globals
  are freed), every global the samples identify freed with the samples' own floor. The
  samples' chi^2 is far sharper in the device than the features' (``ssw identify``: 1e3
  times narrower marginal uncertainties), so a grid over the waveform's chi^2 would need
  a far finer spacing; the features' optimum lies within its basin.

Model error at these levels. The floor of each kind of observation (the features, a
record's samples: :func:`ssw.calibration.waveform.model_floor`) weighs the observations; it
assumes the model's errors independent from one observation to the next, and they are not
(a chain that does not have the device's sensor contacts or dissipation law misses a pulse's
shape, sample after sample), and the part of them along E's own signature is absorbed into
a sample's E where no residual shows it. What E's interval lacks is therefore measured on E
itself, where E is known: each reference is left out, the level's globals refitted on the
others from the calibration (:func:`leave_one_out`), and its E fitted through them as an
unseen sample's is (:func:`fit_modulus`, :func:`modulus_budget`); the relative error
``u`` that those predictions' intervals lack is the upper confidence bound of
:func:`ssw.calibration.model_error.floor_bound` (the estimator of every level) on their
errors in ``ln E``, with each prediction's own standard uncertainty as the noise and the
references' count as the degrees of freedom (the predictions are fitted to nothing). It
enters every interval at that level (``model ({level} leave-one-out)``).

The records' fit of each level is stored in the calibration's ``provenance["information"]``
(:func:`ssw.calibration.waveform.with_fit`; ``from``: the level it started from; ``loo``
and ``model_loo``: the leave-one-out predictions and their term) and its floor and
findings in ``warnings``.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from ssw.errors import ConfigError


def calibrate_levels(cal: Any, samples: list[Any], acq: Any, level: str, *,
                     trigger_level: float, tof_scatter: float, wall: str,
                     wall_options: dict[str, Any] | None = None,
                     start_grid: tuple[tuple[float, ...], tuple[float, ...]] | None = None,
                     refine_levels: int | None = None, loo: bool = True,
                     prior: dict[str, Any] | None = None) -> dict[str, Any]:
    """The TOF calibration ``cal`` refined by its references' records up to ``level``
    (module docstring): every level's calibration, in order.

    Parameters
    ----------
    cal : ssw.calibration.Calibration
        The TOF calibration of the same references.
    samples : list of ssw.calibration.waveform.Hits
        The references' records, each with its E.
    acq : ssw.daq.model.Acquisition
        The measurement model.
    level : str
        ``features`` or ``waveform``.
    trigger_level : float
        N, the records' trigger level.
    tof_scatter : float
        s, a hit's TOF scatter (the prior of each hit's reflected-wave delay).
    wall : str
        The wall law.
    wall_options : dict or None
        Its options.
    start_grid : tuple or None
        The features' global start grid (sensor masses, multiples of the device's; contact
        dissipation coefficients in the unit of the device's law, N s/m for the dashpot);
        None: the default one (:func:`ssw.calibration.waveform.start_damping`).
    refine_levels : int or None
        Refinements of that start; None: the default.
    loo : bool
        Each level's references' leave-one-out predictions and the model term they call for
        (:func:`with_loo`); False: none, and a warning says the intervals at these levels
        lack that check.
    prior : dict or None
        The measured globals' priors, global -> (mean, standard deviation), SI
        (:func:`ssw.calibration.hits.device_priors` of a device file that states its
        striker's uncertainty); None: the device's values with
        :data:`ssw.calibration.hits.GLOBAL_PRIORS`' widths. Every level keeps them.

    Returns
    -------
    dict
        ``{"features": Calibration[, "waveform": Calibration]}``.

    Raises
    ------
    ConfigError
        ``level`` is not ``features`` or ``waveform``.
    """
    from ssw.calibration.waveform import REFINE_LEVELS, calibrate_records, with_fit

    if level not in ("features", "waveform"):
        raise ConfigError("--information", level, "features | waveform for a fit of records")
    opts = dict(wall_options or {})
    f = calibrate_records(samples, cal.chain_params(), wall, opts, acq, "features",
                          trigger_level, tof_scatter, start_grid=start_grid,
                          refine_levels=REFINE_LEVELS if refine_levels is None
                          else refine_levels, prior=prior)
    kw = {"trigger_level": trigger_level, "tof_scatter": tof_scatter, "wall": wall,
          "wall_options": opts}

    def checked(c: Any) -> Any:
        if loo:
            return with_loo(c, samples, acq, **kw)
        level_ = c.provenance["information"]["level"]
        return replace(c, warnings=[*c.warnings, (
            f"RECORDS ({level_}): no leave-one-out check (--no-loo): the intervals at this "
            "level lack the model term it would measure on E")])

    out = {"features": checked(with_fit(cal, f, "features"))}
    if level == "waveform":
        feat = out["features"]
        info = feat.provenance["information"]
        w = calibrate_records(samples, feat.chain_params(), wall, opts, acq, "waveform",
                              trigger_level, tof_scatter, scan=False,
                              gain=float(info["gain"]), prior=info.get("prior"))
        out["waveform"] = checked(with_fit(feat, w, "waveform"))
    return out


def with_loo(cal: Any, samples: list[Any], acq: Any, **kw: Any) -> Any:
    """``cal`` (a calibration of records, :func:`ssw.calibration.waveform.with_fit`) with its
    references' leave-one-out predictions and the model-error term in ``ln E`` they call for
    (module docstring) in ``provenance["information"]`` (``loo``, ``model_loo``) and its
    ``warnings``.

    Parameters
    ----------
    cal : ssw.calibration.Calibration
        The calibration at a records' level.
    samples : list of ssw.calibration.waveform.Hits
        Its references' records.
    acq : ssw.daq.model.Acquisition
        The measurement model.
    **kw
        ``trigger_level``, ``tof_scatter``, ``wall``, ``wall_options``
        (:func:`leave_one_out`).

    Returns
    -------
    ssw.calibration.Calibration
        The calibration with the term.
    """
    from ssw.calibration.model_error import floor_bound

    info = dict(cal.provenance["information"])
    rows = leave_one_out(cal, samples, acq, **kw)
    ok = [r for r in rows if r["E_predicted"] is not None]
    d = np.array([np.log(r["E_predicted"] / r["E"]) for r in ok])
    u = np.array([r["u"] for r in ok])
    term = floor_bound(d, u, np.ones(d.size), float(d.size)) if ok else None
    info.update(loo=rows, model_loo=term)
    level = info["level"]
    said = ", ".join(f"{r['id']} {r['error_pct']:+.3g} %" if r["error_pct"] is not None
                     else f"{r['id']} none" for r in rows)
    verdict = ("" if term is None else "; inside their intervals" if not term else
               f"; their intervals lack a model term of {100 * term:.3g} % in E (95 % upper "
               "bound), in every interval at this level")
    warnings = [*cal.warnings,
                f"RECORDS ({level}): the references' leave-one-out E {said}{verdict}"]
    return replace(cal, provenance={**cal.provenance, "information": info},
                   warnings=warnings)


def leave_one_out(cal: Any, samples: list[Any], acq: Any, *, trigger_level: float,
                  tof_scatter: float, wall: str, wall_options: dict[str, Any] | None = None
                  ) -> list[dict[str, Any]]:
    """Each reference's E predicted as an unseen sample's, through the level's globals
    refitted without it (module docstring).

    The globals the calibration freed are refitted on the other references from the
    calibration's values (:func:`ssw.calibration.waveform.calibrate_records` without the
    global start, with their own floor). Where the calibration corrects the model by its
    discrepancy (:mod:`ssw.calibration.discrepancy`), the globals are held at its values
    and the discrepancy and the floor refitted on the others, their hits from the
    calibration's fit of them (:func:`ssw.calibration.waveform.refit_discrepancy`): what
    is left out is the correction's own extrapolation. Refitted on two of the honesty
    study's three references, the globals leave the basin of all three, and so do the
    hits' parameters fitted again from their first guess (the TOF's correction then 15 %
    and 74 % per unit of the wall's scale, against -1.1 % and +1.0 % with all three). The
    left-out reference's records are then fitted
    with E free (:func:`fit_modulus`) and given the budget a measurement at this level has
    (:func:`modulus_budget`: the fit, the model's share of it, the refitted globals'
    covariance).

    Parameters
    ----------
    cal : ssw.calibration.Calibration
        The calibration at a records' level (``provenance["information"]``).
    samples : list of ssw.calibration.waveform.Hits
        Its references' records (each with its E).
    acq : ssw.daq.model.Acquisition
        The measurement model.
    trigger_level : float
        N.
    tof_scatter : float
        s, a hit's TOF scatter.
    wall : str
        The wall law.
    wall_options : dict or None
        Its options.

    Returns
    -------
    list of dict
        Per reference: ``id``, ``E`` and ``E_predicted`` (Pa; None where the fit failed),
        ``error_pct``, ``u`` (the prediction's standard uncertainty in ``ln E``),
        ``flagged``.
    """
    from ssw.calibration.waveform import (
        calibrate_records,
        global_covariance,
        refit_discrepancy,
    )
    from ssw.errors import RecordingError, SolverError

    info = cal.provenance["information"]
    level, opts = info["level"], dict(wall_options or {})
    rows: list[dict[str, Any]] = []
    for i, smp in enumerate(samples):
        others = [s for j, s in enumerate(samples) if j != i]
        row: dict[str, Any] = {"id": smp.id, "E": float(smp.E), "E_predicted": None,
                               "error_pct": None, "u": None, "flagged": None}
        try:
            g = (refit_discrepancy(others, cal.chain_params(), wall, opts, acq,
                                   trigger_level, tof_scatter, _hits_state(cal, samples, i))
                 if info.get("discrepancy") else
                 calibrate_records(others, cal.chain_params(), wall, opts, acq, level,
                                   trigger_level, tof_scatter,
                                   free_globals=tuple(info["freed"]), scan=False,
                                   gain=float(info["gain"]), prior=info.get("prior")))
            names, C = global_covariance(g, hits=sum(s.n for s in others) / len(others))
            params = cal.chain_params().with_(**{
                k: float(g.state.globals[k]) for k in ("preload", "sensor_mass",
                                                       "striker_mass", "damping")})
            f, setup = fit_modulus(replace(smp, E=None), params, wall, opts, acq, level,
                                   trigger_level=trigger_level, tof_scatter=tof_scatter,
                                   gain=float(g.state.globals["gain"]), floor=g.floor,
                                   E0=float(smp.E), discrepancy=g.discrepancy)
        except (RecordingError, SolverError) as exc:
            rows.append({**row, "reason": str(exc)})
            continue
        terms = modulus_budget(setup, f, level, g.floor,
                               {"names": names, "matrix": C.tolist()})
        E = float(f.state.E[0])
        rows.append({**row, "E_predicted": E, "error_pct": 100.0 * (E / smp.E - 1.0),
                     "u": float(np.sqrt(sum(v**2 for v in terms.values()))),
                     "flagged": bool(f.flagged)})
    return rows


def _hits_state(cal: Any, samples: list[Any], left: int) -> Any:
    """The state of the references but ``left``: their E, their hits' parameters as the
    calibration ``cal`` fitted them (``provenance["information"]``), its globals."""
    from ssw.calibration.waveform import State, device_globals

    info = cal.provenance["information"]
    starts = np.concatenate([[0], np.cumsum([s.n for s in samples])])
    keep = np.concatenate([np.arange(starts[j], starts[j + 1])
                           for j in range(len(samples)) if j != left])
    per_hit = [np.asarray(info[k], float)[keep] for k in
               ("striker_velocity_per_hit", "time_offset_per_hit", "delay_per_hit")]
    E = np.array([s.E for j, s in enumerate(samples) if j != left], float)
    return State(E, *per_hit, device_globals(cal.chain_params(), float(info["gain"])))


def fit_modulus(hits: Any, params: Any, wall: str, wall_options: dict[str, Any] | None,
                acq: Any, level: str, *, trigger_level: float, tof_scatter: float,
                gain: float = 1.0, floor: dict[str, float] | None = None, E0: float,
                discrepancy: Any = None) -> tuple[Any, Any]:
    """A sample's E from its records at a level, the device held: E, each hit's striker
    speed, trigger time offset and reflected-wave delay fitted
    (:func:`ssw.calibration.waveform.fit`) from ``E0``, the weights the noise's with the
    calibration's model-error ``floor``.

    Parameters
    ----------
    hits : ssw.calibration.waveform.Hits
        The sample's records (its ``E`` None: fitted).
    params : ssw.chain.params.ChainParams
        The (calibrated) device's chain.
    wall : str
        The wall law.
    wall_options : dict or None
        Its options.
    acq : ssw.daq.model.Acquisition
        The measurement model.
    level : str
        ``features`` or ``waveform``.
    trigger_level : float
        N, the records' trigger level.
    tof_scatter : float
        s, a hit's TOF scatter (the delays' prior).
    gain : float
        The DAQ gain.
    floor : dict or None
        The model-error floor of the weights (None: the noise alone).
    E0 : float
        Pa, E's start (the TOF measurement's).
    discrepancy : Discrepancy or dict or None
        The calibration's model discrepancy at the features level
        (:class:`ssw.calibration.discrepancy.Discrepancy` or its JSON form; None: none).

    Returns
    -------
    tuple
        The :class:`ssw.calibration.waveform.Fit` and its
        :class:`ssw.calibration.waveform.Setup`.
    """
    from ssw.calibration.discrepancy import Discrepancy
    from ssw.calibration.waveform import (
        PER_HIT,
        Column,
        Setup,
        State,
        device_globals,
        fit,
        initial_state,
    )

    if isinstance(discrepancy, dict):
        discrepancy = Discrepancy.from_dict(discrepancy)
    setup = Setup(params, wall, dict(wall_options or {}), acq, level, [hits],
                  trigger_level, tof_scatter=tof_scatter, floor=dict(floor or {}),
                  discrepancy=discrepancy if level == "features" else None)
    glob = device_globals(params, gain)
    v0 = float(params.striker_velocity)
    setup.fix_step(State(np.array([E0]), np.full(hits.n, 1.5 * v0), np.zeros(hits.n),
                         np.zeros(hits.n), glob))
    state = initial_state(setup, glob, [E0], v0)
    free = [Column("E", 0)] + [Column(name, h) for name in PER_HIT for h in range(hits.n)]
    return fit(setup, state, free), setup


def modulus_budget(setup: Any, f: Any, level: str, floor: dict[str, float] | None,
                   covariance: dict[str, Any] | None) -> dict[str, float]:
    """The terms of E's budget (standard uncertainties of ``ln E``) a fit of a sample's
    records gives (:func:`fit_modulus`): ``{level} fit``, the fit's standard error, scaled
    by ``sqrt(chi2 / dof)`` where the model does not reach the noise (Press et al. 2007,
    sec. 15.1) and, with a model-error floor, by the square root of the hits (the model's
    error is common to a sample's hits: it does not average down over them), split then
    into the noise's share (:func:`ssw.calibration.waveform.noise_std`) and the model's,
    ``model ({level})``; ``calibration ({level})``, the calibration's globals' covariance
    propagated through the fit (:func:`ssw.calibration.waveform.propagated`), except through
    a model corrected by its discrepancy (:mod:`ssw.calibration.discrepancy`): the
    correction is fitted given the globals, and refitted it takes up the change a global
    makes that is a line in the wall's scale (a sensor's or a striker's mass moves a
    feature by a factor nearly the same on every sample: the correction's ``a_k``), which
    the propagation with the correction held counts as E's (on the honesty study's device,
    2-5 % of E at 1 sigma); what the line does not take up, the features' cross-validated
    floors and the leave-one-out term on E carry.

    Parameters
    ----------
    setup : ssw.calibration.waveform.Setup
        The fit's model and records.
    f : ssw.calibration.waveform.Fit
        The fit (E the first free parameter).
    level : str
        Its level.
    floor : dict or None
        The model-error floor of its weights.
    covariance : dict or None
        ``names`` and ``matrix``: the calibration's globals' covariance in their scaled
        coordinates (:func:`ssw.calibration.waveform.global_covariance`).

    Returns
    -------
    dict
        Term name -> standard uncertainty of ``ln E``.
    """
    from ssw.calibration.waveform import Column, noise_std, propagated

    col = Column("E", 0)
    out: dict[str, float] = {}
    u_fit = f.std(col)
    if any((floor or {}).values()):
        u_fit *= float(np.sqrt(setup.samples[0].n))
        u_noise = min(noise_std(setup, f, col), u_fit)
        out[f"{level} fit"] = u_noise
        out[f"model ({level})"] = float(np.sqrt(u_fit**2 - u_noise**2))
    else:
        out[f"{level} fit"] = u_fit
    if covariance and covariance.get("names") and setup.discrepancy is None:
        C = propagated(setup, f, list(covariance["names"]), np.asarray(covariance["matrix"]))
        out[f"calibration ({level})"] = float(np.sqrt(max(C[0, 0], 0.0)))
    return out

