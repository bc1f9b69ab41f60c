"""The validation rule: simulated vs measured TOF and the modulus inverted from it.

For each sample of config ``validation.samples`` (thesis defaults PCF 08, 15, 30):

* ``tof_sim``: the chain model's TOF at the manufacturer's E and nu
  (:func:`ssw.chain.api.tof`, the config's wall law);
* ``tof_measured``: the mean TOF of the sample's recording (:mod:`ssw.signal.tof`, with its
  hit rejection rule) when ``recordings`` is given, else the thesis's published mean
  (``tof_published``, Table 2);
* ``tof_diff_pct = 100 |tof_measured - tof_sim| / tof_sim`` (Table 2 prints the absolute
  difference; the signed one is kept as ``tof_diff_signed_pct``);
* ``E_measured``: E inverted from the measured TOF at the sample's nu
  (:func:`ssw.chain.inverse.invert`). With a recording every accepted hit is inverted and
  ``E_measured`` is their mean, ``E_cov_pct`` their COV (Table 3's "COV measured E"); with
  the published mean only, one inversion and ``E_cov_pct = None`` (the hit data are not
  published; the thesis's COV is reported as ``E_cov_published``);
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
    """One validation row (SI units; percentages in %)."""

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

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def pct(a: float, b: float) -> float:
    """``100 (a - b) / b``."""
    return 100.0 * (a - b) / b


def cov_pct(x: np.ndarray) -> float | None:
    """Sample COV ``100 std(x, ddof=1) / mean(x)``, None for fewer than two values."""
    return float(100.0 * np.std(x, ddof=1) / np.mean(x)) if x.size > 1 else None


def inverse_range(wall: str, wall_options: dict[str, Any], params: Any) -> tuple[float, float]:
    """E range (Pa) of the inverse: the thesis's 10..1000 MPa, cut to a K table's soils.

    With the ``fit`` wall and a K table, the forward model only exists over the table's
    soil moduli (the table does not extrapolate).
    """
    from ssw.chain.inverse import E_RANGE
    from ssw.chain.walls import load_k_table

    if wall != "fit" or wall_options.get("k_table") is None:
        return E_RANGE
    table = load_k_table(wall_options["k_table"], params)
    return (max(E_RANGE[0], float(table.soil_E.min())), min(E_RANGE[1], float(table.soil_E.max())))


def validate_samples(
    cfg: dict[str, Any], params: Any, wall: str, wall_options: dict[str, Any], *,
    root: str | Path = ".", tof_options: Any = None,
) -> list[SampleResult]:
    """Compute the validation rows of every sample in ``cfg['validation']['samples']``.

    ``params`` is a :class:`ssw.chain.params.ChainParams`; ``wall``/``wall_options`` the
    last-contact law; ``root`` the folder relative recording paths start from.
    """
    from ssw.chain import api
    from ssw.chain.inverse import invert
    from ssw.config import library
    from ssw.daq.importers import read_any
    from ssw.signal.tof import recording_tof

    samples = cfg.get("validation", {}).get("samples", [])
    if not samples:
        raise ConfigError("validation.samples", samples, "at least one sample")
    wall_options = dict(wall_options)
    E_range = inverse_range(wall, wall_options, params)
    mats = library(cfg)
    E_man = np.array([mats[s["material"]].E for s in samples])
    nus = np.array([mats[s["material"]].nu for s in samples])
    tof_sim = np.asarray(api.tof(E_man, nus, params, wall, **wall_options), dtype=float)
    rows = []
    for i, smp in enumerate(samples):
        rec_path = smp.get("recordings")
        extra: dict[str, Any] = {}
        if rec_path:
            p = Path(rec_path)
            p = p if p.is_absolute() else Path(root) / p
            rec = read_any(p, clipped="drop")
            res = recording_tof(rec, tof_options)
            t_hits = res.tof[res.accepted]
            inv = invert(t_hits, nus[i], params, wall, E_range=E_range, **wall_options)
            E_hits = np.atleast_1d(inv.E)
            t_meas, t_std = res.mean, res.std
            E_meas, E_cov = float(np.mean(E_hits)), cov_pct(E_hits)
            extra = dict(n_hits=int(res.tof.size), n_accepted=res.n_accepted,
                         recording=str(rec_path), synthetic=bool(rec.meta.get("synthetic", False)),
                         tof_per_hit=t_hits.tolist(), E_per_hit=E_hits.tolist(),
                         rejections=list(res.reasons) + list(rec.dropped))
            source = "recording"
        elif "tof_published" in smp:
            t_meas, t_std = float(smp["tof_published"]), None
            E_meas = float(invert(t_meas, nus[i], params, wall, E_range=E_range,
                                  **wall_options).E)
            E_cov = None
            source = "published"
        else:
            raise ConfigError(f"validation.samples[{i}]", smp["id"],
                              "a sample with recordings or tof_published")
        rows.append(SampleResult(
            sample=smp["id"], material=smp["material"], E_manufacturer=float(E_man[i]),
            nu=float(nus[i]), tof_sim=float(tof_sim[i]), tof_measured=float(t_meas),
            tof_measured_std=t_std, tof_source=source,
            tof_diff_pct=abs(pct(t_meas, tof_sim[i])), tof_diff_signed_pct=pct(t_meas, tof_sim[i]),
            E_measured=E_meas, E_cov_pct=E_cov, E_diff_pct=abs(pct(E_meas, E_man[i])),
            tof_published=smp.get("tof_published"),
            tof_sim_published=smp.get("tof_sim_published"),
            E_published=smp.get("E_published"), E_cov_published=smp.get("E_cov_published"),
            **extra,
        ))
    return rows
