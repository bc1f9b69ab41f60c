"""The validation rule: simulated vs measured TOF and the modulus inverted from it.

For each sample of config ``validation.samples`` (thesis defaults PCF 08, 15, 30):

* ``tof_sim``: the chain model's TOF at the manufacturer's E and nu
  (:func:`ssw.tof.sweep.run_sweep`, the config's wall law), with the checks of that run's
  assumptions (``validity``, ``checks_failed``: :mod:`ssw.validity`);
* ``tof_measured``: the mean TOF of the sample's recording (:mod:`ssw.signal.tof`, with its
  hit rejection rule) when ``recordings`` is given, else the thesis's published mean
  (``tof_published``, Table 2);
* ``tof_diff_pct = 100 |tof_measured - tof_sim| / tof_sim`` (Table 2 prints the absolute
  difference; the signed one is kept as ``tof_diff_signed_pct``);
* ``E_measured``: E inverted from the measured mean TOF at the sample's nu, with its 95 %
  interval ``E_low``..``E_high`` and the uncertainty budget (:func:`ssw.modulus.estimate_moduli`:
  the TOF's standard error, the calibration's covariance, a Poisson's ratio range, the wall
  law's and the integrator's errors). With a recording every accepted hit is also inverted
  and ``E_cov_pct`` is their COV (Table 3's "COV measured E"); with the published mean
  only, ``E_cov_pct = None`` (the hit data are not published; the thesis's COV is reported
  as ``E_cov_published``) and the TOF's standard error is the one the calibration uses
  (:mod:`ssw.calibration.references`);
* ``E_loo``: the sample's E predicted by the calibration made WITHOUT it (the calibration's
  leave-one-out; None without a calibration or when the sample was not a reference);
* ``E_diff_pct = 100 |E_measured - E_manufacturer| / E_manufacturer`` (Table 3; this
  reproduces its printed 3 / 1 / 1 % from 39/38, 122/123, 442/445 MPa).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ssw.errors import ConfigError


@dataclass(frozen=True)
class SampleResult:
    """One validation row (SI units; percentages in %).

    Parameters
    ----------
    sample : str
        The sample's id.
    material : str
        Its materials-library key.
    E_manufacturer : float
        Pa, the manufacturer's Young's modulus.
    nu : float
        -, the sample's Poisson's ratio.
    tof_sim : float
        s, the chain model's TOF at ``E_manufacturer`` and ``nu``.
    tof_measured : float
        s, the measured mean TOF (the recording's, else the published one).
    tof_measured_std : float or None
        s, standard deviation of the accepted hits' TOF.
    tof_source : str
        Where ``tof_measured`` comes from (recording or published).
    tof_diff_pct : float
        %, ``100 |tof_measured - tof_sim| / tof_sim``.
    tof_diff_signed_pct : float
        %, ``100 (tof_measured - tof_sim) / tof_sim``.
    E_measured : float
        Pa, E inverted from ``tof_measured``.
    E_cov_pct : float or None
        %, COV of the per-hit E (None without a recording).
    E_diff_pct : float
        %, ``100 |E_measured - E_manufacturer| / E_manufacturer``.
    E_low : float or None
        Pa, lower end of the 95 % interval of ``E_measured``.
    E_high : float or None
        Pa, upper end of the 95 % interval of ``E_measured``.
    E_u_pct : float or None
        %, standard uncertainty of ln E (x 100).
    E_contributions_pct : dict of str to float
        %, the budget's terms by source.
    E_notes : list of str
        Remarks on the estimate.
    E_missing_terms : dict of str to str
        Budget terms left out, with the reason.
    E_loo : float or None
        Pa, E from the calibration made without this sample.
    E_loo_diff_pct : float or None
        %, ``100 (E_loo - E_manufacturer) / E_manufacturer``.
    tof_sem : float or None
        s, standard error of ``tof_measured``.
    n_hits : int or None
        Hits in the recording.
    n_accepted : int or None
        Hits the rejection rule accepted.
    recording : str or None
        Path of the sample's recording.
    synthetic : bool or None
        Whether the recording is synthetic.
    tof_per_hit : list of float
        s, each hit's TOF.
    E_per_hit : list of float
        Pa, E inverted from each accepted hit.
    rejections : list of str
        Why hits were rejected.
    tof_published : float or None
        s, the thesis's measured mean TOF (Table 2).
    tof_sim_published : float or None
        s, the thesis's simulated TOF (Table 2).
    E_published : float or None
        Pa, the thesis's measured E (Table 3).
    E_cov_published : float or None
        %, the thesis's COV of measured E (Table 3).
    validity : list of dict
        The checks of the ``tof_sim`` run (:mod:`ssw.validity`).
    checks_failed : list of str
        Names of the checks that fail.
    """

    sample: str
    material: str
    E_manufacturer: float
    nu: float
    tof_sim: float
    tof_measured: float
    tof_measured_std: float | None
    tof_source: str
    tof_diff_pct: float
    tof_diff_signed_pct: float
    E_measured: float
    E_cov_pct: float | None
    E_diff_pct: float
    E_low: float | None = None
    E_high: float | None = None
    E_u_pct: float | None = None
    E_contributions_pct: dict[str, float] = field(default_factory=dict)
    E_notes: list[str] = field(default_factory=list)
    E_missing_terms: dict[str, str] = field(default_factory=dict)
    E_loo: float | None = None
    E_loo_diff_pct: float | None = None
    tof_sem: float | None = None
    n_hits: int | None = None
    n_accepted: int | None = None
    recording: str | None = None
    synthetic: bool | None = None
    tof_per_hit: list[float] = field(default_factory=list)
    E_per_hit: list[float] = field(default_factory=list)
    rejections: list[str] = field(default_factory=list)
    tof_published: float | None = None
    tof_sim_published: float | None = None
    E_published: float | None = None
    E_cov_published: float | None = None
    validity: list[dict[str, Any]] = field(default_factory=list)
    checks_failed: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """The row as a mapping of its fields (SI units; percentages in %).

        Returns
        -------
        dict
            Field name -> value.
        """
        return asdict(self)


def pct(a: float, b: float) -> float:
    """``100 (a - b) / b``.

    Parameters
    ----------
    a : float
        The value compared.
    b : float
        The reference (same unit, nonzero).

    Returns
    -------
    float
        %, the signed relative difference.
    """
    return 100.0 * (a - b) / b


def cov_pct(x: np.ndarray) -> float | None:
    """Sample COV ``100 std(x, ddof=1) / mean(x)``, None for fewer than two values.

    Parameters
    ----------
    x : numpy.ndarray
        The values (any unit).

    Returns
    -------
    float or None
        %, the coefficient of variation.
    """
    return float(100.0 * np.std(x, ddof=1) / np.mean(x)) if x.size > 1 else None


def inverse_range(wall: str, wall_options: dict[str, Any], params: Any) -> tuple[float, float]:
    """E range (Pa) of the inverse: the thesis's 10..1000 MPa, cut to a K table's soils.

    With the ``fit`` wall and a K table, the forward model only exists over the table's
    soil moduli (the table does not extrapolate).

    Parameters
    ----------
    wall : str
        The wall law's name.
    wall_options : dict
        The wall builder's options (``k_table`` read for the ``fit`` wall).
    params : ssw.chain.params.ChainParams
        The device's chain (to load the K table).

    Returns
    -------
    tuple of float
        Pa, ``(lo, hi)`` of the inversion's search.
    """
    from ssw.tof.inverse import E_RANGE
    from ssw.walls import load_k_table

    if wall != "fit" or wall_options.get("k_table") is None:
        return E_RANGE
    table = load_k_table(wall_options["k_table"], params)
    return (max(E_RANGE[0], float(table.soil_E.min())), min(E_RANGE[1], float(table.soil_E.max())))


def validate_samples(
    cfg: dict[str, Any], params: Any, wall: str, wall_options: dict[str, Any], *,
    root: str | Path = ".", tof_options: Any = None, calibration: Any = None,
    full_scale: float | None = None, strengths: Any = None, stresses: str = "bound",
) -> list[SampleResult]:
    """Compute the validation rows of every sample in ``cfg['validation']['samples']``.

    ``params`` is the (calibrated) device's :class:`ssw.chain.params.ChainParams`;
    ``wall``/``wall_options`` the last-contact law; ``root`` the folder relative recording
    paths start from; ``calibration`` the :class:`ssw.calibration.Calibration` (its
    covariance enters the E intervals, its leave-one-out rows the E_loo column);
    ``full_scale`` (N) the device's largest unclipped force, the recordings' hits are
    checked against; ``strengths`` (:class:`ssw.validity.Strengths`: the beads' and the
    plate's) gives each row the checks of the chain's run at its manufacturer's E (the run
    of ``tof_sim``; its sample's yield against its library strength,
    :func:`sample_strengths`), with the stress mode ``stresses``
    (:data:`ssw.validity.STRESS_MODES`).

    Parameters
    ----------
    cfg : dict
        The study config (``validation.samples`` and the materials read).
    params : ssw.chain.params.ChainParams
        The (calibrated) device's chain.
    wall : str
        The last contact's wall law.
    wall_options : dict
        The wall builder's options.
    root : str or Path
        Folder relative recording paths start from.
    tof_options : ssw.signal.tof.TofOptions or None
        Options of the TOF picking and rejection rule.
    calibration : ssw.calibration.Calibration or None
        Its covariance enters the E intervals, its leave-one-out rows ``E_loo``.
    full_scale : float or None
        N, the device's largest unclipped force, the hits are checked against.
    strengths : ssw.validity.Strengths or None
        The beads' and the plate's strengths; with them each row carries its checks.
    stresses : str
        The checks' stress mode (:data:`ssw.validity.STRESS_MODES`).

    Returns
    -------
    list of SampleResult
        One row per sample, in the config's order.

    Raises
    ------
    ssw.errors.ConfigError
        No sample in ``validation.samples``.
    """
    from ssw.calibration.references import from_config
    from ssw.config import library
    from ssw.modulus import estimate_moduli
    from ssw.tof.sweep import run_sweep

    samples = cfg.get("validation", {}).get("samples", [])
    if not samples:
        raise ConfigError("validation.samples", samples, "at least one sample")
    wall_options = dict(wall_options)
    E_range = inverse_range(wall, wall_options, params)
    mats = library(cfg)
    E_man = np.array([mats[s["material"]].E for s in samples])
    nus = np.array([mats[s["material"]].nu for s in samples])
    # the model's TOF at the manufacturer's E; its run's checks (ssw.validity) are the row's
    sim = run_sweep(params, E_man, nus, wall, **wall_options,
                    **({} if strengths is None else
                       {"strengths": sample_strengths(samples, mats, strengths),
                        "stresses": stresses}))
    tof_sim = np.asarray(sim.tof, dtype=float)
    checks = sim.validity
    # measured TOFs and their standard errors: what the calibration uses
    refs = {r.id: r for r in from_config(cfg, params, wall, wall_options, root=root,
                                         tof_options=tof_options, require_std=False,
                                         full_scale=full_scale)}
    extras = [_recording_extra(smp, root, tof_options, full_scale) for smp in samples]
    T = np.array([refs[s["id"]].tof for s in samples])
    # an unknown TOF uncertainty is NaN: the interval then lists its tof term as missing
    S = np.array([np.nan if refs[s["id"]].tof_std is None else refs[s["id"]].tof_std
                  for s in samples])
    nu_arg = np.array([s.get("soil_nu_range") or [nus[i], nus[i]]
                       for i, s in enumerate(samples)], float)
    est = estimate_moduli(T, S, nu_arg, params, wall, wall_options, calibration=calibration,
                          E_range=E_range)
    _per_hit_moduli(extras, [e.nu for e in est], params, wall, E_range, wall_options)
    loo = {row["id"]: row for row in (calibration.loo if calibration is not None else [])}
    return [_row(smp, est[i], extras[i], float(E_man[i]), float(tof_sim[i]), float(T[i]),
                 float(S[i]), loo.get(smp["id"], {}).get("E_predicted"),
                 None if checks is None else (checks.entries(i), checks.failed(i)))
            for i, smp in enumerate(samples)]


def _recording_extra(smp: dict[str, Any], root: str | Path, tof_options: Any,
                     full_scale: float | None) -> dict[str, Any]:
    """A sample's columns from its recording (none without one): its hits, the accepted
    hits' TOFs (s), the rejections and the TOF's standard deviation (s) (``tof_measured_std``,
    taken out again by :func:`_row`)."""
    from ssw.daq.importers import read_any
    from ssw.signal.tof import recording_tof

    if not smp.get("recordings"):
        return {}
    p = Path(smp["recordings"])
    p = p if p.is_absolute() else Path(root) / p
    rec = read_any(p, clipped="drop", full_scale=full_scale)
    res = recording_tof(rec, tof_options)
    t_hits = res.tof[res.accepted]
    return dict(n_hits=int(res.tof.size), n_accepted=res.n_accepted,
                recording=str(smp["recordings"]),
                synthetic=bool(rec.meta.get("synthetic", False)),
                tof_per_hit=t_hits.tolist(),
                rejections=list(res.reasons) + list(rec.dropped),
                tof_measured_std=res.std)


def _per_hit_moduli(extras: list[dict[str, Any]], nus: list[float], params: Any, wall: str,
                    E_range: tuple[float, float], wall_options: dict[str, Any]) -> None:
    """Each recorded hit's E (Pa; Table 3's COV) into ``extras`` (``E_per_hit``), every hit
    of every sample in one batched inversion at its sample's Poisson's ratio ``nus``."""
    from ssw.tof.inverse import invert_batch

    hit_T = [np.asarray(x.get("tof_per_hit", []), float) for x in extras]
    if not any(h.size for h in hit_T):
        return
    allT = np.concatenate(hit_T)
    allnu = np.concatenate([np.full(h.size, nus[i]) for i, h in enumerate(hit_T)])
    inv = invert_batch(allT, allnu, params, wall, E_range=E_range, strict=False,
                       **wall_options)
    k = 0
    for i, h in enumerate(hit_T):
        extras[i]["E_per_hit"] = inv.E[k:k + h.size].tolist()
        k += h.size


def _row(smp: dict[str, Any], e: Any, extra: dict[str, Any], E_man: float, tof_sim: float,
         T: float, S: float, lo: float | None,
         checks: tuple[list[dict[str, Any]], list[str]] | None) -> SampleResult:
    """One sample's row from its estimate ``e`` (:class:`ssw.modulus.ModulusEstimate`), its
    recording's columns ``extra``, its manufacturer's E (Pa), simulated and measured TOF and
    the TOF's standard error (s; NaN: unknown), its leave-one-out E (Pa) and its checks
    (entries, failing names)."""
    E_hits = np.asarray(extra.get("E_per_hit", []), float)
    E_hits = E_hits[np.isfinite(E_hits)]
    source = "recording" if smp.get("recordings") else "published"
    std = extra.pop("tof_measured_std", None)
    return SampleResult(
        sample=smp["id"], material=smp["material"], E_manufacturer=E_man,
        nu=e.nu, tof_sim=tof_sim, tof_measured=T,
        tof_measured_std=std, tof_source=source,
        tof_diff_pct=abs(pct(T, tof_sim)), tof_diff_signed_pct=pct(T, tof_sim),
        E_measured=e.E, E_cov_pct=cov_pct(E_hits) if E_hits.size else None,
        E_diff_pct=abs(pct(e.E, E_man)), E_low=e.E_low, E_high=e.E_high,
        E_u_pct=100.0 * e.u,
        E_contributions_pct={k_: 100.0 * v for k_, v in e.contributions.items()},
        E_notes=list(e.notes), E_missing_terms=dict(e.missing), E_loo=lo,
        E_loo_diff_pct=None if lo is None else pct(lo, E_man),
        tof_sem=None if np.isnan(S) else S,
        tof_published=smp.get("tof_published"),
        tof_sim_published=smp.get("tof_sim_published"),
        E_published=smp.get("E_published"), E_cov_published=smp.get("E_cov_published"),
        validity=[] if checks is None else checks[0],
        checks_failed=[] if checks is None else checks[1],
        **extra,
    )


def sample_strengths(samples: list[dict[str, Any]], mats: dict[str, Any],
                     strengths: Any) -> Any:
    """``strengths`` (:class:`ssw.validity.Strengths`: the beads' and the plate's) with each
    sample's own: its library material's uniaxial strength
    (:func:`ssw.measure.uniaxial_strength`), NaN (the stated assumption) where it has
    none.

    Parameters
    ----------
    samples : list of dict
        The config's samples (``id``, ``material``).
    mats : dict
        The materials library by key.
    strengths : ssw.validity.Strengths
        The beads' and the plate's strengths.

    Returns
    -------
    ssw.validity.Strengths
        A copy with ``sample`` (Pa per sample, NaN: none stated) and its source.
    """
    from dataclasses import replace

    from ssw.measure import uniaxial_strength

    Y = [uniaxial_strength(getattr(mats[s["material"]], "strength", None)) for s in samples]
    src = "; ".join(f"{s['id']}: the library's {s['material']} "
                    f"({'none stated' if y is None else f'{y:.4g} Pa'})"
                    for s, y in zip(samples, Y, strict=True))
    return replace(strengths, sample=np.array([np.nan if y is None else y for y in Y], float),
                   sample_source=src)
