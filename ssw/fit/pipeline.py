"""Fits as the study config asks: each curve on its default range, then the tables.

:func:`fit_with_config` fits one curve with one law on the range the config's
``fit.range`` gives for that scene (:mod:`ssw.fit.range`); :func:`fit_files` does it for
many curve files and laws and returns the fits, with the range's provenance attached;
:func:`table_from_files` groups them into :class:`~ssw.fit.table.KTable` s.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import asdict
from pathlib import Path
from typing import Any

from ssw.curve import ForceCurve, read_curve
from ssw.fit.fitting import FitResult, fit_curve, scene_inputs
from ssw.fit.range import FitRange, fit_range, fit_ranges
from ssw.fit.table import KTable, build_tables


def config_laws(cfg: dict[str, Any]) -> list[str]:
    """The laws the config fits: ``fit.compare_laws`` plus ``fit.law``, without repeats.

    Parameters
    ----------
    cfg : dict
        The validated study config.

    Returns
    -------
    list of str
        The laws' names, ``fit.law`` first.
    """
    fc = cfg["fit"]
    return list(dict.fromkeys([fc["law"], *fc["compare_laws"]]))


def fit_with_config(
    curve: ForceCurve, cfg: dict[str, Any], law: str | None = None
) -> tuple[FitResult, FitRange]:
    """Fit ``law`` (default ``fit.law``) on the config's range for this curve's scene.

    Parameters
    ----------
    curve : ForceCurve
        The force-indentation curve (SI).
    cfg : dict
        The validated study config.
    law : str or None
        The law; None: ``fit.law``.

    Returns
    -------
    result : FitResult
        The fit.
    range : FitRange
        The fit range (m).
    """
    sc = scene_inputs(curve)
    rng = fit_range(float(sc["soil_E"]), float(sc["soil_nu"]), float(curve.delta[-1]), cfg,
                    sc.get("plate_E"), sc.get("plate_nu"))
    res = fit_curve(
        curve, law or cfg["fit"]["law"], (rng.lo, rng.hi), weighting=cfg["fit"]["weighting"]
    )
    return res, rng


def fit_files(
    paths: Iterable[str | Path], cfg: dict[str, Any], laws: list[str] | None = None,
    curves: list[Any] | None = None,
) -> list[dict[str, Any]]:
    """For every curve file: ``{"path", "range": FitRange dict, "fits": {law: FitResult}}``.

    The ranges of all files are computed in one batch (one chain run in mode ``chain``).
    ``curves``: the files' curves when already read.

    Parameters
    ----------
    paths : iterable of str or pathlib.Path
        The curve files (HDF5).
    cfg : dict
        The validated study config.
    laws : list of str or None
        The laws to fit; None: :func:`config_laws`.
    curves : list or None
        The files' curves when already read, in the order of ``paths``.

    Returns
    -------
    list of dict
        One record per file.
    """
    paths = [str(p) for p in paths]
    curves = [read_curve(p, extras=False) for p in paths] if curves is None else list(curves)
    scs = [scene_inputs(c) for c in curves]
    ranges = fit_ranges(
        [float(s["soil_E"]) for s in scs],
        [float(s["soil_nu"]) for s in scs],
        [float(c.delta[-1]) for c in curves],
        cfg,
        [s.get("plate_E") for s in scs],
        [s.get("plate_nu") for s in scs],
    )
    out = []
    for p, c, rng in zip(paths, curves, ranges, strict=True):
        fits = {
            law: fit_curve(c, law, (rng.lo, rng.hi), weighting=cfg["fit"]["weighting"])
            for law in laws or config_laws(cfg)
        }
        out.append({"path": p, "range": asdict(rng), "fits": fits})
    return out


def table_from_files(
    paths: Iterable[str | Path], cfg: dict[str, Any], laws: list[str] | None = None,
    curves: list[Any] | None = None,
) -> tuple[list[KTable], list[dict[str, Any]]]:
    """Fit every file (``curves``: already read) and build the tables; also return the
    per-file records.

    Parameters
    ----------
    paths : iterable of str or pathlib.Path
        The curve files (HDF5).
    cfg : dict
        The validated study config.
    laws : list of str or None
        The laws to fit; None: :func:`config_laws`.
    curves : list or None
        The files' curves when already read, in the order of ``paths``.

    Returns
    -------
    tables : list of KTable
        One table per plate.
    records : list of dict
        The per-file records of :func:`fit_files`.
    """
    records = fit_files(paths, cfg, laws, curves)
    return build_tables(fr for r in records for fr in r["fits"].values()), records
