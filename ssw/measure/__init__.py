"""From recordings of hits on one test point to its modulus, with an honest interval.

:func:`measure` takes the recordings of one test point (sessions of hits: HDF5, CSV, MAT,
TDMS, :func:`ssw.daq.importers.read_any`), picks every hit's TOF with the rejection rule of
:mod:`ssw.signal.tof` (per session), pools the accepted hits, and inverts their mean TOF
through the device (calibrated or not) with the uncertainty budget of
:func:`ssw.modulus.estimate_moduli`: the standard error of the mean TOF, the calibration's
covariance, the Poisson's ratio range, the wall law's and the integrator's errors, and the
TOF's sampling uncertainty (below).

Scatter. The TOF's standard error is the accepted hits' sample standard deviation over the
square root of their number; with fewer than ``MIN_HITS_FOR_SCATTER`` accepted hits the
scatter is not estimable: the device's stated scatter (``repeatability.tof_std`` of its
file) is used instead and the term is labelled ``tof (stated scatter)``; without one, the
term is missing from the interval, which says so (``missing_terms``), and a survey verdict
on it is inconclusive.

Yield. When the sample's strength is known (:func:`uniaxial_strength` of a library
material, or stated), :func:`yield_check` reports how close the measured hit came to
yielding it: the chain at the measured E gives the wall's peak indentation, the contact
FEM's elastic field at that state (:func:`ssw.contact.stress.contact_stresses`: through the
plate, with the bead's compliance) the sample's peak von Mises stress, and the yield index
is that stress over the strength. At 1 or above the sample has started to yield under the
bead (Johnson 1985, sec. 6.1: a sphere on a half-space first yields below the surface, at
``p0 = 1.61 Y`` for nu 0.3): the TOF then carries plastic work as well as E, and the
measurement says so.

Sampling. A peak time read from a record sampled at ``f_s`` carries a systematic error (the
module's anti-alias filter reshaping the pulses, the sub-sample interpolation) that the mean
over hits does not average away. It enters as a TOF uncertainty
:func:`sampling_uncertainty`, the largest bias measured by ``ssw bench tof`` from simulated
NI 9234 records of known TOF (x16 band-limited interpolation before the parabolic vertex):
0.72 us at 51.2 kS/s (PCF 08, the broadest reflected pulse: 0.04 sample), and 2 to 5 us at
25.6 kS/s and below, where the module's filter cuts into the pulse (0.13 sample).

Records. :func:`measure_information` (:mod:`ssw.measure.records`) refines the TOF
measurement by the records' features or whole waveforms.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ssw.errors import RecordingError
from ssw.measure.records import measure_information  # noqa: F401
from ssw.signal.tof import MIN_HITS_FOR_SCATTER

#: Systematic TOF uncertainty of the peak picking, in sample periods (1 sigma): the largest
#: bias measured against records of known TOF (``ssw bench tof``, README Stage III), at the
#: NI 9234's full rate and below half of it.
SAMPLING_FRACTION_FULL_RATE = 0.04
SAMPLING_FRACTION = 0.13
#: The NI 9234's full rate, S/s (REFERENCE.md: 13.1072 MHz / 256).
FULL_RATE = 51200.0



def sampling_uncertainty(rate: float) -> float:
    """TOF uncertainty (s) of the peak picking at sample rate ``rate`` (S/s).

    Parameters
    ----------
    rate : float
        S/s, the record's sample rate.

    Returns
    -------
    float
        s, one standard uncertainty: ``SAMPLING_FRACTION_FULL_RATE`` (at the NI 9234's
        full rate) or ``SAMPLING_FRACTION`` sample periods, ``frac / rate``.
    """
    frac = SAMPLING_FRACTION_FULL_RATE if rate >= 0.99 * FULL_RATE else SAMPLING_FRACTION
    return frac / rate


@dataclass(frozen=True)
class Measurement:
    """The modulus of one test point and how it was obtained. SI units.

    Parameters
    ----------
    E : float
        Pa, the Young's modulus of the test point.
    E_low : float
        Pa, lower end of the 95 % interval, ``E exp(-1.96 u)``.
    E_high : float
        Pa, upper end of the 95 % interval, ``E exp(+1.96 u)``.
    u : float
        -, standard uncertainty of ln E: the quadrature sum of ``contributions``.
    contributions : dict of str to float
        -, standard uncertainty of ln E per source.
    notes : tuple of str
        Remarks on the measurement (text).
    tof_mean : float
        s, mean TOF of the accepted hits.
    tof_sem : float
        s, its standard error (NaN: not estimable).
    tof_std : float
        s, sample standard deviation of the accepted hits' TOF (NaN: too few hits).
    n_hits : int
        Hits found in the recordings.
    n_accepted : int
        Hits the rejection rule accepted.
    tof_per_hit : list of float or None
        s, each hit's TOF (None: none picked).
    accepted : list of bool
        Whether each hit was accepted.
    rejections : list of str
        Why hits were rejected or dropped, by file.
    files : list of str
        The recordings' paths.
    sample_rate : float
        S/s, the lowest sample rate of the recordings.
    nu : float
        -, the Poisson's ratio of the inversion.
    nu_range : tuple of float or None
        -, the stated Poisson's ratio range, or None.
    synthetic : bool
        Whether any recording is synthetic.
    missing : dict of str to str
        Budget terms left out of the interval, each with the reason.
    extra : dict
        Further entries of :meth:`to_dict` (sensitivity, checks, yield index).
    """

    E: float
    E_low: float
    E_high: float
    u: float
    contributions: dict[str, float]
    notes: tuple[str, ...]
    tof_mean: float
    tof_sem: float
    tof_std: float
    n_hits: int
    n_accepted: int
    tof_per_hit: list[float | None]
    accepted: list[bool]
    rejections: list[str]
    files: list[str]
    sample_rate: float
    nu: float
    nu_range: tuple[float, float] | None
    synthetic: bool
    missing: dict[str, str] = field(default_factory=dict)
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def complete(self) -> bool:
        """Whether every term of the uncertainty budget is in the interval."""
        return not self.missing

    def to_dict(self) -> dict[str, Any]:
        """The measurement as a JSON-ready mapping (SI units; percentages marked ``_pct``).

        Returns
        -------
        dict
            E, its interval and budget (in %), the TOF statistics, the hits and ``extra``.
        """
        return {
            "E": self.E, "E_low": self.E_low, "E_high": self.E_high, "coverage": 0.95,
            "E_u_pct": 100.0 * self.u,
            "contributions_pct": {k: 100.0 * v for k, v in self.contributions.items()},
            "missing_terms": dict(self.missing), "interval_complete": self.complete,
            "notes": list(self.notes), "tof_mean": self.tof_mean,
            "tof_sem": None if np.isnan(self.tof_sem) else self.tof_sem,
            "tof_std": None if np.isnan(self.tof_std) else self.tof_std,
            "n_hits": self.n_hits, "n_accepted": self.n_accepted,
            "tof_per_hit": self.tof_per_hit, "accepted": self.accepted,
            "rejections": self.rejections, "files": self.files,
            "sample_rate": self.sample_rate, "nu": self.nu,
            "nu_range": None if self.nu_range is None else list(self.nu_range),
            "synthetic": self.synthetic, **self.extra,
        }


def uniaxial_strength(strength: Any) -> float | None:
    """The uniaxial strength (Pa) a sample's von Mises stress is compared with, from a
    :class:`ssw.materials.Strength`: the yield stress, else the compressive strength (foams:
    the crushing plateau), else the unconfined compressive strength of Mohr-Coulomb
    ``q_u = 2 c cos(phi) / (1 - sin(phi))``; None when none is known.

    Parameters
    ----------
    strength : ssw.materials.Strength or None
        The sample material's strengths (Pa; friction angle in degrees).

    Returns
    -------
    float or None
        Pa, the uniaxial strength, or None.

    Notes
    -----
    ``q_u = 2 c cos(phi) / (1 - sin(phi)) = 2 c tan(45 deg + phi / 2)`` is the uniaxial
    compressive strength of the Mohr-Coulomb criterion (its unconfined compression circle).
    """
    if strength is None:
        return None
    if strength.yield_stress is not None:
        return float(strength.yield_stress)
    if strength.compressive is not None:
        return float(strength.compressive)
    if strength.cohesion is not None and strength.friction_angle is not None:
        phi = np.radians(float(strength.friction_angle))
        return float(2.0 * strength.cohesion * np.cos(phi) / (1.0 - np.sin(phi)))
    return None


def yield_check(E: float, nu: float, params: Any, wall_options: dict[str, Any] | None,
                strength: float) -> dict[str, Any]:
    """How close a hit on a sample of modulus ``E`` (Pa), ``nu`` came to yielding it (module
    docstring): ``{"sample_peak_von_mises": Pa, "sample_strength": Pa, "yield_index": -,
    "sample_yielded": bool, "peak_wall_force": N}``, from the device's chain ``params`` on
    its exact FEM wall (``wall_options``: its ``contact`` settings and operators).

    Parameters
    ----------
    E : float
        Pa, the sample's Young's modulus.
    nu : float
        -, its Poisson's ratio.
    params : ssw.chain.params.ChainParams
        The device's chain.
    wall_options : dict or None
        The wall builder's options (only ``contact`` and ``operators`` are used).
    strength : float
        Pa, the sample's uniaxial strength (:func:`uniaxial_strength`).

    Returns
    -------
    dict
        ``sample_peak_von_mises`` (Pa), ``sample_strength`` (Pa), ``yield_index`` (-, their
        ratio), ``sample_yielded`` (bool), ``peak_wall_force`` (N).

    Raises
    ------
    ssw.errors.ConfigError
        ``strength`` is not a finite value > 0 Pa.
    """
    from ssw.errors import ConfigError
    from ssw.tof.api import peaks
    from ssw.walls.fem import peak_stresses

    if not (np.isfinite(strength) and strength > 0):
        raise ConfigError("sample strength", strength, "a strength > 0 Pa")
    opts = {k: v for k, v in (wall_options or {}).items() if k in ("contact", "operators")}
    _, run = peaks(E, nu, params, "fem", **opts)
    st = peak_stresses(params, E, nu, run.peak_wall_indentation[:1], **opts)
    peak = float(st.soil.peak[0])
    return {"sample_peak_von_mises": peak, "sample_strength": float(strength),
            "yield_index": peak / float(strength), "sample_yielded": bool(peak >= strength),
            "peak_wall_force": float(st.force[0])}


def pooled_tof(recordings: list[Any], tof_options: Any = None) -> dict[str, Any]:
    """Per-hit TOFs of every recording (the rejection rule applied per session), pooled:
    the accepted hits' mean, sample std and standard error of the mean (s).

    Parameters
    ----------
    recordings : list of ssw.daq.recording.Recording
        The sessions of one test point.
    tof_options : ssw.signal.tof.TofOptions or None
        Options of the TOF picking and the rejection rule (None: the defaults).

    Returns
    -------
    dict
        ``tof_mean``, ``tof_std`` (NaN below :data:`ssw.signal.tof.MIN_HITS_FOR_SCATTER`
        hits), ``tof_sem`` (s); ``n_accepted``, ``n_hits``, ``tof_per_hit``, ``accepted``,
        ``rejections``, ``sample_rate`` (S/s, the lowest) and ``n_dropped``.

    Raises
    ------
    ssw.errors.RecordingError
        No hit was accepted.
    """
    from ssw.signal.tof import recording_tof

    per_hit: list[float | None] = []
    accepted: list[bool] = []
    reasons: list[str] = []
    rates = set()
    for rec in recordings:
        res = recording_tof(rec, tof_options)
        per_hit += [None if not np.isfinite(v) else float(v) for v in res.tof]
        accepted += res.accepted.tolist()
        reasons += [f"{Path(rec.path).name}: {r}" for r in (*res.reasons, *rec.dropped)]
        rates.add(float(res.sample_rate))
    dropped = sum(len(rec.dropped) for rec in recordings)  # on reading (NaN, clipped)
    t = np.array([v for v, a in zip(per_hit, accepted, strict=True) if a], float)
    if t.size == 0:
        raise RecordingError("no accepted hit in " + ", ".join(r.path for r in recordings))
    # NaN: not estimable from these hits (module docstring, MIN_HITS_FOR_SCATTER)
    std = float(np.std(t, ddof=1)) if t.size >= MIN_HITS_FOR_SCATTER else float("nan")
    return {"tof_mean": float(np.mean(t)), "tof_std": std,
            "tof_sem": std / np.sqrt(t.size), "n_accepted": int(t.size),
            "n_hits": len(per_hit), "tof_per_hit": per_hit, "accepted": accepted,
            "rejections": reasons, "sample_rate": min(rates), "n_dropped": dropped}


def measure(
    recordings: list[Any], nu: float | tuple[float, float], params: Any, wall: str,
    wall_options: dict[str, Any] | None = None, *, calibration: Any = None,
    tof_options: Any = None, device: Any = None, strength: float | None = None,
    sample_range: list[dict[str, Any]] | None = None, strengths: Any = None,
    stresses: str = "fem",
) -> Measurement:
    """E with its 95 % interval from the recordings of one test point (module docstring).

    Parameters
    ----------
    recordings : list of ssw.daq.recording.Recording
        The sessions of the test point (one or more).
    nu : float or tuple of float
        The medium's Poisson's ratio, or a range ``(lo, hi)``.
    params : ssw.chain.params.ChainParams
        The (calibrated) device's chain.
    wall : str
        The wall law's name (:data:`ssw.walls.WALLS`).
    wall_options : dict or None
        The wall builder's options (its plate, sample and contact settings).
    calibration : ssw.calibration.Calibration or None
        The calibration whose covariance enters the interval.
    tof_options : ssw.signal.tof.TofOptions or None
        Options of the TOF picking and the rejection rule (:func:`pooled_tof`).
    device : ssw.device.Device or None
        The device (its stated TOF scatter, when there are too few hits to estimate one).
    strength : float or None
        The sample's uniaxial strength, Pa (:func:`uniaxial_strength`), or None: with it,
        the measurement reports its yield index (:func:`yield_check`) and warns when the
        sample yielded.
    sample_range : list of dict or None
        The wall options of the thinnest and the thickest sample of a stated range of
        sample thickness (``ssw measure --sample-thickness LO:HI``; the central E is the
        middle one's, ``wall_options``): the spread of E between them enters the
        budget as a uniform term, ``|ln(E_hi / E_lo)| / (2 sqrt 3)`` (``sample``).
    strengths : ssw.validity.Strengths or None
        The strengths of the beads and the plate (:func:`ssw.validity.strengths_of`): with
        them, the measurement carries its checks (``validity``: :func:`ssw.validity.assess`
        of the chain at the measured E), the sample's yield against
        ``strength`` when given, else against ``ssw design``'s stated assumption, named in
        the entry.
    stresses : str
        The checks' stress mode (:data:`ssw.validity.STRESS_MODES`).

    Returns
    -------
    Measurement
        E with its 95 % interval ``E exp(+-1.96 u)`` and the budget.

    Raises
    ------
    ssw.errors.RecordingError
        No recording, or no accepted hit.
    """
    from ssw.modulus import estimate_moduli

    if not recordings:
        raise RecordingError("no recording to measure")
    pool = pooled_tof(recordings, tof_options)
    n = pool["n_accepted"]
    notes = _stated_scatter(pool, device)
    nu_arg = np.array([nu[0], nu[1]], float) if isinstance(nu, tuple | list) else float(nu)
    est = estimate_moduli([pool["tof_mean"]], [pool["tof_sem"]], nu_arg, params, wall,
                          wall_options, calibration=calibration)[0]
    missing = _missing(est, n)
    contrib = dict(est.contributions)
    if notes and "tof" in contrib:
        contrib["tof (stated scatter)"] = contrib.pop("tof")
    if sample_range is not None:  # a stated range of sample thickness: uniform in ln E
        contrib["sample"], note = _sample_range_term(pool["tof_mean"], nu_arg, params, wall,
                                                     sample_range)
        notes.append(note)
    # sampling: a systematic TOF uncertainty of the peak picking at the record's rate
    u_samp = sampling_uncertainty(pool["sample_rate"]) / (
        pool["tof_mean"] * abs(est.dlnTOF_dlnE))
    contrib["sampling"] = float(u_samp)
    u = float(np.sqrt(sum(v**2 for v in contrib.values())))
    from ssw.modulus import COVERAGE_Z

    notes = [*est.notes, *notes]
    extra: dict[str, Any] = {"dlnTOF_dlnE": est.dlnTOF_dlnE,
                             "wall_extrapolated": est.extrapolated,
                             "n_dropped": pool["n_dropped"]}
    if strengths is not None:
        extra.update(_checks(est, params, wall, wall_options, strengths, strength, stresses,
                             notes))
    if strength is not None:
        extra.update(_yield(est, params, wall_options, strength, notes))
    return Measurement(
        E=est.E, E_low=est.E * float(np.exp(-COVERAGE_Z * u)),
        E_high=est.E * float(np.exp(COVERAGE_Z * u)), u=u, contributions=contrib,
        notes=tuple(notes), tof_mean=pool["tof_mean"], tof_sem=pool["tof_sem"],
        tof_std=pool["tof_std"], n_hits=pool["n_hits"], n_accepted=pool["n_accepted"],
        tof_per_hit=pool["tof_per_hit"], accepted=pool["accepted"],
        rejections=pool["rejections"], files=[r.path for r in recordings],
        sample_rate=pool["sample_rate"], nu=est.nu, nu_range=est.nu_range,
        synthetic=any(bool(r.meta.get("synthetic", False)) for r in recordings),
        missing=missing, extra=extra,
    )


def _missing(est: Any, n: int) -> dict[str, str]:
    """The budget's terms the estimate could not give, the TOF's saying why (too few hits
    and no stated scatter) and the way on.

    Parameters
    ----------
    est : ssw.modulus.ModulusEstimate
        The estimate (its ``missing`` terms).
    n : int
        The accepted hits.

    Returns
    -------
    dict
        Each missing term's reason.
    """
    missing = dict(est.missing)
    if "tof" in missing:
        missing["tof"] = (f"{n} accepted hit(s), fewer than {MIN_HITS_FOR_SCATTER}: the TOF's "
                          "scatter is not estimable and the device file states none "
                          "(record more hits, or state repeatability.tof_std)")
    return missing


def _stated_scatter(pool: dict[str, Any], device: Any) -> list[str]:
    """The TOF's standard error from the device's stated scatter where the hits are too few
    to estimate one (``pool["tof_sem"]`` NaN; set in place), and the note saying so.

    Parameters
    ----------
    pool : dict
        The pooled TOF (:func:`pooled_tof`; s).
    device : ssw.device.Device or None
        The device (its ``tof_scatter``, s per hit, and its source).

    Returns
    -------
    list of str
        The note, or none.
    """
    n = pool["n_accepted"]
    stated = getattr(device, "tof_scatter", None)
    if np.isnan(pool["tof_sem"]) and stated is not None:
        pool["tof_sem"] = float(stated) / np.sqrt(n)
        return [f"{n} accepted hit(s), fewer than {MIN_HITS_FOR_SCATTER}: the TOF term "
                f"uses the device's stated scatter, {stated:.3g} s per hit "
                f"({device.tof_scatter_source or 'source not given'})"]
    return []


def _sample_range_term(tof_mean: float, nu: Any, params: Any, wall: str,
                       sample_range: list[dict[str, Any]]) -> tuple[float, str]:
    """The budget's term of a stated range of sample thickness: E on the thinnest and the
    thickest sample, uniform in ``ln E``: ``|ln(E_hi / E_lo)| / (2 sqrt 3)``.

    Parameters
    ----------
    tof_mean : float
        s, the pooled TOF.
    nu : float or numpy.ndarray
        The medium's Poisson's ratio, or its range.
    params : ssw.chain.params.ChainParams
        The device's chain.
    wall : str
        The wall law's name.
    sample_range : list of dict
        The wall options of the thinnest and the thickest sample.

    Returns
    -------
    tuple
        The term (relative standard uncertainty of E) and its note.
    """
    from ssw.modulus import estimate_moduli

    ends = [estimate_moduli([tof_mean], [float("nan")], nu, params, wall, o,
                            calibration=None)[0].E for o in sample_range]
    term = float(abs(np.log(ends[1] / ends[0])) / (2.0 * np.sqrt(3.0)))
    return term, (f"sample thickness stated as a range: E {ends[0] / 1e6:.4g} MPa on the "
                  f"thinnest, {ends[1] / 1e6:.4g} MPa on the thickest (a uniform term)")


def _yield(est: Any, params: Any, wall_options: dict[str, Any] | None, strength: float,
           notes: list[str]) -> dict[str, Any]:
    """The sample's yield check at the measured E (:func:`yield_check`), with a note
    appended to ``notes`` when the sample yielded.

    Parameters
    ----------
    est : ssw.modulus.ModulusEstimate
        The estimate (E, Pa; nu).
    params : ssw.chain.params.ChainParams
        The device's chain.
    wall_options : dict or None
        The wall builder's options.
    strength : float
        Pa, the sample's uniaxial strength.
    notes : list of str
        The measurement's notes (appended to).

    Returns
    -------
    dict
        The yield check's entries.
    """
    yc = yield_check(est.E, est.nu, params, wall_options, strength)
    if yc["sample_yielded"]:
        notes.append(
            f"the sample yielded under the bead: peak von Mises stress "
            f"{yc['sample_peak_von_mises'] / 1e6:.3g} MPa is {yc['yield_index']:.2f} x its "
            f"strength {strength / 1e6:.3g} MPa (elastic field at the hit's peak force "
            f"{yc['peak_wall_force']:.3g} N): the TOF carries plastic work as well as E; "
            "a lower striker speed or a thicker plate keeps it elastic (ssw design)")
    return yc


def _checks(est: Any, params: Any, wall: str, wall_options: dict[str, Any] | None,
            strengths: Any, strength: float | None, stresses: str, notes: list[str]
            ) -> dict[str, Any]:
    """The checks of a measurement at its E (the chain run there,
    :func:`ssw.tof.sweep.run_sweep`, and :func:`ssw.validity.assess`), the sample's
    ``strength`` (Pa) when known; a note when the sample may have yielded under an assumed
    strength."""
    from dataclasses import replace as _replace

    from ssw.tof.sweep import run_sweep

    if strength is not None:
        strengths = _replace(strengths, sample=float(strength),
                             sample_source=strengths.sample_source or "stated")
    v = run_sweep(params, np.array([est.E]), np.array([est.nu]), wall, strengths=strengths,
                  stresses=stresses, **dict(wall_options or {})).validity
    if "sample_yield" in v.values and "sample_yield" in v.assumed \
            and not v.holds("sample_yield")[0]:
        notes.append(f"the sample may have yielded under the bead: its yield index is "
                     f"{v.values['sample_yield'][0]:.3g} against the assumed strength "
                     f"({v.assumed['sample_yield']}): state its strength to decide")
    return v.to_dict(0)


def parse_nu(text: str | float) -> float | tuple[float, float]:
    """``NU`` or ``LO:HI`` (a Poisson's ratio range) from the command line.

    Parameters
    ----------
    text : str or float
        ``NU`` or ``LO:HI``, with ``-1 < LO <= HI <= 0.5``.

    Returns
    -------
    float or tuple of float
        The Poisson's ratio, or the range ``(lo, hi)``.

    Raises
    ------
    ssw.errors.ConfigError
        Not a ratio or range in bounds (``--soil-nu``).
    """
    from ssw.errors import ConfigError

    s = str(text).strip()
    try:
        if ":" in s:
            lo, hi = (float(x) for x in s.split(":", 1))
            if not -1.0 < lo <= hi <= 0.5:
                raise ValueError
            return (lo, hi)
        v = float(s)
        if not -1.0 < v <= 0.5:
            raise ValueError
        return v
    except ValueError as exc:
        raise ConfigError("--soil-nu", text, "a Poisson's ratio NU or a range LO:HI with "
                          "-1 < LO <= HI <= 0.5") from exc
