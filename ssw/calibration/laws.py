"""The contacts' dissipation laws compared on the references' records (``ssw calibrate
--information features|waveform --compare-laws``).

The same references' records are calibrated under each law of
:data:`ssw.chain.dissipation.LAWS` (:func:`ssw.calibration.waveform.calibrate_records`,
the law's coefficient freed with the other globals the records identify, the global start
in the law's own scale: :func:`ssw.calibration.waveform.start_damping`; for ``waveform``,
from that law's features calibration as :func:`ssw.calibration.records.calibrate_levels`
does). Each law's fit is scored by the Gaussian likelihood of its residuals with the
variances its weights state, the noise's and the law's own model-error floor
(:func:`ssw.calibration.waveform.model_floor`) and the priors' widths::

    -2 ln L = sum_i [ r_i^2 / v_i + ln(2 pi v_i) ],   v_i = sigma_i^2 + phi_k^2 s_i^2

(a law that misses the records needs a larger floor, which its ``ln v_i`` pays for; the
chi^2 alone is brought to its degrees of freedom by the floor and cannot tell the laws
apart), then by Akaike's and Schwarz's criteria::

    AIC = -2 ln L + 2 k,        BIC = -2 ln L + k ln n

with ``k`` the parameters fitted (the freed globals, each hit's three, each non-zero
floor) and ``n`` the records' observations (Burnham & Anderson 2002, sec. 2.2 and 6.4).
The law of least criterion is the one the data prefer among these laws; it is not shown
to be the device's (a real contact follows none of them exactly), and a difference of a
few units is no preference (Burnham & Anderson 2002, sec. 2.6: ``Delta`` < 2 is
substantial support for both). Two caveats stated with the result: the floor is an upper
confidence bound, not the likelihood's maximum (the same estimator for every law, so it
biases each the same way), and a law whose model leaves some of the records'
observations unexplained (a pulse it does not produce) is scored on fewer observations and
is not compared.

References
----------
Akaike, H. (1974). A new look at the statistical model identification. IEEE Trans. Autom.
Control 19, 716-723.
Burnham, K. P. and Anderson, D. R. (2002). Model Selection and Multimodel Inference, 2nd
ed. Springer.
Schwarz, G. (1978). Estimating the dimension of a model. Ann. Stat. 6, 461-464.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np

from ssw.errors import ConfigError

#: A criterion's difference below which two laws are not told apart (Burnham & Anderson
#: 2002, sec. 2.6).
INDISTINCT = 2.0
#: The kinds of observation that are priors, not records (``ssw.calibration.waveform.observe``):
#: they enter the likelihood, not the observations' count ``n``.
PRIORS = ("trigger", "delay")


@dataclass(frozen=True)
class LawScore:
    """One dissipation law's fit of the references' records and its criteria (module
    docstring).

    Parameters
    ----------
    law : str
        The law's name (:data:`ssw.chain.dissipation.LAWS`).
    unit : str
        Its coefficient's unit.
    coefficient : float
        The fitted (or held) coefficient, in ``unit``.
    values : dict
        The globals the fit freed, SI (the coefficient in ``unit``).
    chi2 : float
        The residuals' sum of squares with the fit's weights (noise, floor and priors).
    neg2_log_likelihood : float
        ``-2 ln L`` of the residuals with those variances.
    parameters : int
        ``k``: the parameters fitted, the non-zero floors included.
    observations : int
        ``n``: the records' observations the model explains.
    aic : float
        ``-2 ln L + 2 k``.
    bic : float
        ``-2 ln L + k ln n``.
    floor : dict
        The law's model-error floor per kind of observation (relative).
    converged : bool
        The last fit stopped at a first-order point.
    unexplained : int
        The records' observations the model has no value for (> 0: not compared).
    """

    law: str
    unit: str
    coefficient: float
    values: dict[str, float]
    chi2: float
    neg2_log_likelihood: float
    parameters: int
    observations: int
    aic: float
    bic: float
    floor: dict[str, float]
    converged: bool
    unexplained: int

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (SI; the coefficient in ``unit``).

        Returns
        -------
        dict
            Field name -> value.
        """
        return asdict(self)


def score(setup: Any, f: Any, law: str) -> LawScore:
    """The likelihood and the criteria of a fit ``f`` of the records under the law
    ``law`` (module docstring).

    Parameters
    ----------
    setup : ssw.calibration.waveform.Setup
        The fit's model and records (its chain under ``law``).
    f : ssw.calibration.waveform.Fit
        The fit, its ``floor`` the model-error floor of its weights.
    law : str
        The dissipation law of ``setup``'s chain.

    Returns
    -------
    LawScore
        The law's score.
    """
    from ssw.calibration.waveform import observe
    from ssw.chain.dissipation import law_of

    run = replace(setup, floor=dict(f.floor), runs=0)
    obs = observe(run, f.state, set())
    setup.runs += run.runs
    r = (obs.model - obs.data) / obs.sigma
    ok = np.isfinite(r)
    chi2 = float(np.sum(r[ok] ** 2))
    n2ll = chi2 + float(np.sum(np.log(2.0 * np.pi * obs.sigma[ok] ** 2)))
    n = int(np.count_nonzero(ok & ~np.isin(obs.kind, PRIORS)))
    k = len(f.free) + sum(1 for v in f.floor.values() if v > 0)
    values = {c.name: float(f.state.globals[c.name]) for c in f.free if c.index < 0}
    return LawScore(law, law_of(law).unit, float(f.state.globals["damping"]), values, chi2,
                    n2ll, k, n, n2ll + 2.0 * k, n2ll + k * float(np.log(max(n, 1))),
                    dict(f.floor), bool(f.converged), int(f.unexplained))


def law_fit(samples: list[Any], params: Any, law: str, wall: str,
            wall_options: dict[str, Any] | None, acq: Any, level: str, *,
            trigger_level: float, tof_scatter: float,
            start_grid: tuple[tuple[float, ...], tuple[float, ...]] | None = None,
            refine_levels: int | None = None,
            prior: dict[str, Any] | None = None) -> LawScore:
    """The references' records calibrated under the dissipation ``law`` at ``level`` and
    scored (:func:`score`): ``features`` from the global start in the law's scale; then,
    for ``waveform``, from the features' fit with its DAQ gain (as
    :func:`ssw.calibration.records.calibrate_levels`).

    Parameters
    ----------
    samples : list of ssw.calibration.waveform.Hits
        The references' records, each with its E.
    params : ssw.chain.params.ChainParams
        The device's chain (its law replaced by ``law``, its coefficient by the start's).
    law : str
        The dissipation law.
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
        s, a hit's TOF scatter.
    start_grid : tuple or None
        The features' start grid (sensor masses, multiples of the device's; coefficients
        in the law's unit); None: the default (:func:`ssw.calibration.waveform.start_damping`).
    refine_levels : int or None
        Refinements of the start (None: the default).
    prior : dict or None
        The measured globals' priors (:func:`ssw.calibration.hits.device_priors`; None:
        the device's values with :data:`ssw.calibration.hits.GLOBAL_PRIORS`' widths), kept
        by both levels.

    Returns
    -------
    LawScore
        The law's fit at ``level``, scored.
    """
    from ssw.calibration.hits import device_priors
    from ssw.calibration.waveform import (
        REFINE_LEVELS,
        Setup,
        State,
        calibrate_records,
        device_globals,
    )
    from ssw.chain.dissipation import law_of

    law_of(law, "--compare-laws")
    opts = dict(wall_options or {})
    p = params.with_(damping_law=law, damping=law_of(law).scale)
    kw = {"trigger_level": trigger_level, "tof_scatter": tof_scatter}
    gain = 1.0
    prior = device_priors(p) if prior is None else prior  # the file's, at both levels
    f = calibrate_records(samples, p, wall, opts, acq, "features", start_grid=start_grid,
                          refine_levels=REFINE_LEVELS if refine_levels is None
                          else refine_levels, prior=prior, **kw)
    if level == "waveform":
        g = f.state.globals
        p = p.with_(**{k: float(g[k]) for k in ("preload", "sensor_mass", "striker_mass",
                                                 "damping")},
                    striker_velocity=float(np.mean(f.state.striker_velocity)))
        gain = float(g["gain"])
        f = calibrate_records(samples, p, wall, opts, acq, "waveform", scan=False,
                              gain=gain, prior=prior, **kw)
    # the fit's own model: its chain's step fixed as calibrate_records fixed it
    setup = Setup(p, wall, opts, acq, level, samples, trigger_level,
                  tof_scatter=tof_scatter)
    n_h, v0 = setup.n_hits, float(p.striker_velocity)
    setup.fix_step(State(np.array([s.E for s in samples], float), np.full(n_h, 1.5 * v0),
                         np.zeros(n_h), np.zeros(n_h), device_globals(p, gain)))
    return score(setup, f, law)


def compare_laws(samples: list[Any], params: Any, wall: str,
                 wall_options: dict[str, Any] | None, acq: Any, level: str, *,
                 trigger_level: float, tof_scatter: float, laws: tuple[str, ...] | None = None,
                 start_grid: tuple[tuple[float, ...], tuple[float, ...]] | None = None,
                 refine_levels: int | None = None,
                 prior: dict[str, Any] | None = None) -> dict[str, Any]:
    """The references' records fitted under each dissipation law and compared by AIC and
    BIC (module docstring).

    Parameters
    ----------
    samples : list of ssw.calibration.waveform.Hits
        The references' records, each with its E.
    params : ssw.chain.params.ChainParams
        The device's chain (the start of every law's fit but for the dissipation).
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
        s, a hit's TOF scatter.
    laws : tuple of str or None
        The laws compared (None: every law of :data:`ssw.chain.dissipation.LAWS`).
    start_grid : tuple or None
        The start grid's sensor masses (multiples of the device's); its coefficients are
        each law's own (:func:`ssw.calibration.waveform.start_damping`) unless given, then
        as dashpots (N s/m) scaled to each law likewise.
    refine_levels : int or None
        Refinements of each law's start (None: the default).
    prior : dict or None
        The measured globals' priors (:func:`law_fit`).

    Returns
    -------
    dict
        ``level``; ``laws``: each law's :meth:`LawScore.to_dict` with ``delta_aic`` and
        ``delta_bic`` (from the least among the compared); ``preferred``: ``{"aic": law,
        "bic": law}`` (None where no law is compared), ``distinct``: whether the preferred
        law's criterion is at least :data:`INDISTINCT` below every other's;
        ``not_compared``: the laws leaving observations unexplained; ``statement``: the
        finding in words (what the data prefer, never the device's law).

    Raises
    ------
    ConfigError
        ``level`` is not a records' level, or an unknown law.
    """
    from ssw.calibration.start import START_DAMPING
    from ssw.chain.dissipation import DEFAULT_LAW, LAWS

    if level not in ("features", "waveform"):
        raise ConfigError("--information", level, "features | waveform with --compare-laws "
                          "(the records identify the contacts' dissipation; TOFs do not)")
    names = tuple(LAWS) if laws is None else tuple(laws)
    scores = []
    for law in names:
        grid = None
        if start_grid is not None:
            ratio = LAWS[law].scale / LAWS[DEFAULT_LAW].scale if law in LAWS else 1.0
            grid = (start_grid[0], tuple(c * ratio for c in (start_grid[1] or START_DAMPING)))
        scores.append(law_fit(samples, params, law, wall, wall_options, acq, level,
                              trigger_level=trigger_level, tof_scatter=tof_scatter,
                              start_grid=grid, refine_levels=refine_levels, prior=prior))
    return summarize(scores, level)


def summarize(scores: list[LawScore], level: str) -> dict[str, Any]:
    """The comparison of laws' scores (:func:`compare_laws`'s result).

    Parameters
    ----------
    scores : list of LawScore
        Each law's score at ``level``.
    level : str
        The records' level of the fits.

    Returns
    -------
    dict
        As :func:`compare_laws` returns.
    """
    compared = [s for s in scores if s.unexplained == 0]
    rows, preferred, distinct = [], {}, {}
    for crit in ("aic", "bic"):
        vals = {s.law: getattr(s, crit) for s in compared}
        if not vals:
            preferred[crit], distinct[crit] = None, False
            continue
        best = min(vals, key=vals.__getitem__)
        preferred[crit] = best
        distinct[crit] = all(v - vals[best] >= INDISTINCT for k, v in vals.items()
                             if k != best)
    for s in scores:
        row = s.to_dict()
        for crit in ("aic", "bic"):
            ref = min((getattr(c, crit) for c in compared), default=np.nan)
            row[f"delta_{crit}"] = (float(getattr(s, crit) - ref) if s.unexplained == 0
                                    else None)
        rows.append(row)
    best = preferred["bic"]
    if best is None:
        text = "no law explains every observation of the records: none compared"
    elif distinct["bic"] and distinct["aic"] and preferred["aic"] == best:
        text = (f"the records prefer {best} among {', '.join(s.law for s in compared)} "
                f"(BIC and AIC at least {INDISTINCT:g} below every other law's); the "
                "preferred law of these, not shown to be the device's")
    else:
        text = (f"the records do not tell {', '.join(s.law for s in compared)} apart "
                f"(criteria within {INDISTINCT:g} of the least, or AIC and BIC disagree)")
    return {"level": level, "laws": rows, "preferred": preferred, "distinct": distinct,
            "not_compared": [s.law for s in scores if s.unexplained > 0],
            "statement": text}
