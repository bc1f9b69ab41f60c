"""Reference samples for a calibration: from the command line, recordings, or a study config.

The TOF of a reference is always a MEASURED one: a recording's mean over its accepted hits
(uncertainty: the standard error of that mean, ``std / sqrt(n)``), or a published measured
mean (``validation.samples[].tof_published``, the thesis's Table 2 experimental column).

A published mean's uncertainty, when the config does not give it (``tof_std``), is derived
from what the thesis publishes: the COV of the moduli it inverted hit by hit (Table 3,
``E_cov_published``) and the number of hits (``hits_published``; the thesis: "three
consecutive tests"). Each hit's E and TOF are tied by the local slope
``k = d ln TOF / d ln E`` of the TOF-E relation, so the TOF's COV is ``|k| COV_E`` and the
mean's standard error ``|k| COV_E TOF / sqrt(n)``. ``k`` is evaluated with the device's
model at the sample (about -0.2: ``TOF ~ E^(-1/5)`` for a Hertz wall); it converts the
thesis's own numbers back to the TOF scatter that produced them, so it needs only to be
roughly right.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ssw.calibration.model import Reference
from ssw.errors import ConfigError

#: Relative step of E for the local slope d ln TOF / d ln E.
SLOPE_STEP = 0.02


def tof_slope(E: np.ndarray, nu: np.ndarray, params: Any, wall: str,
              wall_options: dict[str, Any]) -> np.ndarray:
    """``d ln TOF / d ln E`` (central difference, one batched run) at each (E, nu).

    Parameters
    ----------
    E : numpy.ndarray
        Pa, the moduli.
    nu : numpy.ndarray
        -, the Poisson's ratios (same shape).
    params : ssw.chain.params.ChainParams
        The device's chain.
    wall : str
        The wall law's name.
    wall_options : dict
        The wall builder's options.

    Returns
    -------
    numpy.ndarray
        -, ``ln(TOF(E (1 + h)) / TOF(E (1 - h))) / ln((1 + h) / (1 - h))`` with
        ``h = SLOPE_STEP``.
    """
    from ssw.tof import api

    E = np.asarray(E, float)
    nu = np.asarray(nu, float)
    T = api.tof(np.concatenate([E * (1 + SLOPE_STEP), E * (1 - SLOPE_STEP)]),
                np.concatenate([nu, nu]), params, wall, **wall_options)
    up, dn = T[: E.size], T[E.size:]
    return np.log(up / dn) / np.log((1 + SLOPE_STEP) / (1 - SLOPE_STEP))


def recording_reference(path: str | Path, E: float, nu: float, *, id: str = "",
                        tof_options: Any = None, **read_options: Any) -> Reference:
    """A reference from a recording of a sample of known E (Pa) and nu: the mean TOF of its
    accepted hits, with the standard error of that mean.

    Parameters
    ----------
    path : str or Path
        The recording (any format :func:`ssw.daq.importers.read_any` reads).
    E : float
        Pa, the sample's known Young's modulus.
    nu : float
        -, its Poisson's ratio.
    id : str
        The reference's name (default the file's stem).
    tof_options : ssw.signal.tof.TofOptions or None
        Options of the TOF picking and rejection rule.
    **read_options : Any
        Options of :func:`ssw.daq.importers.read_any` (``full_scale`` N, ...).

    Returns
    -------
    Reference
        The mean TOF (s) and its standard error ``std / sqrt(n)`` (s).

    Raises
    ------
    ssw.errors.ConfigError
        Fewer accepted hits than :data:`ssw.signal.tof.MIN_HITS_FOR_SCATTER`.
    """
    from ssw.daq.importers import read_any
    from ssw.signal.tof import MIN_HITS_FOR_SCATTER, recording_tof

    rec = read_any(path, clipped="drop", **read_options)
    res = recording_tof(rec, tof_options)
    n = res.n_accepted
    if n < MIN_HITS_FOR_SCATTER:
        raise ConfigError("reference recording", str(path),
                          f"at least {MIN_HITS_FOR_SCATTER} accepted hits for a TOF "
                          f"uncertainty (found {n})")
    return Reference(E, nu, res.mean, res.std / np.sqrt(n), id=id or Path(path).stem,
                     source=f"recording {path} ({n} hits)")


def from_config(cfg: dict[str, Any], params: Any, wall: str, wall_options: dict[str, Any],
                *, root: str | Path = ".", tof_options: Any = None,
                require_std: bool = True, full_scale: float | None = None
                ) -> list[Reference]:
    """The config's validation samples as references (manufacturer E and nu, measured TOF).

    Recordings (``recordings``, relative to ``root``) are used when given, else the
    published measured mean with ``tof_std`` or the uncertainty derived from the published
    E COV (module docstring); without either, a ConfigError (``require_std``) or no
    uncertainty (None).

    Parameters
    ----------
    cfg : dict
        The study config (``validation.samples`` and the materials).
    params : ssw.chain.params.ChainParams
        The device's chain (the TOF slope of a derived uncertainty).
    wall : str
        The wall law's name.
    wall_options : dict
        The wall builder's options.
    root : str or Path
        Folder relative recording paths start from.
    tof_options : ssw.signal.tof.TofOptions or None
        Options of the TOF picking and rejection rule.
    require_std : bool
        Refuse a sample without a TOF uncertainty (else its ``tof_std`` is None).
    full_scale : float or None
        N, the device's largest unclipped force, the recordings are read with.

    Returns
    -------
    list of Reference
        One per sample, in the config's order.

    Raises
    ------
    ssw.errors.ConfigError
        No sample, a sample without a measured TOF, or without an uncertainty when
        ``require_std``.
    """
    from ssw.config import library

    samples = cfg.get("validation", {}).get("samples", [])
    if not samples:
        raise ConfigError("validation.samples", samples, "reference samples with measured TOFs")
    mats = library(cfg)
    refs: list[Reference | None] = [None] * len(samples)
    derive = []
    for i, smp in enumerate(samples):
        m = mats[smp["material"]]
        if smp.get("recordings"):
            p = Path(smp["recordings"])
            p = p if p.is_absolute() else Path(root) / p
            refs[i] = recording_reference(p, m.E, m.nu, id=smp["id"], tof_options=tof_options,
                                          full_scale=full_scale)
        elif "tof_published" in smp:
            if smp.get("tof_std") is not None:
                refs[i] = Reference(m.E, m.nu, float(smp["tof_published"]),
                                    float(smp["tof_std"]), id=smp["id"],
                                    source="published mean, tof_std given")
            else:
                derive.append(i)
        else:
            raise ConfigError(f"validation.samples[{i}]", smp["id"],
                              "a sample with recordings or tof_published (a measured TOF)")
    if derive:
        E = np.array([mats[samples[i]["material"]].E for i in derive])
        nu = np.array([mats[samples[i]["material"]].nu for i in derive])
        k = tof_slope(E, nu, params, wall, wall_options)
        for j, i in enumerate(derive):
            smp = samples[i]
            cov = smp.get("E_cov_published")
            if cov is None:
                if not require_std:
                    refs[i] = Reference(float(E[j]), float(nu[j]), float(smp["tof_published"]),
                                        None, id=smp["id"], source="published mean")
                    continue
                raise ConfigError(f"validation.samples[{i}].tof_std", None,
                                  "a TOF uncertainty (s), or E_cov_published to derive it")
            n = int(smp.get("hits_published", 3))
            tof = float(smp["tof_published"])
            std = abs(float(k[j])) * float(cov) / 100.0 * tof / np.sqrt(n)
            refs[i] = Reference(float(E[j]), float(nu[j]), tof, std, id=smp["id"],
                                source=f"published mean; std from COV(E) {cov} %, "
                                f"{n} hits, dlnTOF/dlnE {float(k[j]):.3f}")
    return [r for r in refs if r is not None]
