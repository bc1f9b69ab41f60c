"""Consecutive hits of the chain on one plastic sample (:mod:`ssw.walls.plastic`).

The chain is placed on the virgin sample (its weight and preload indent it statically,
along the virgin curve: the sample's history starts there), then struck ``hits`` times.
Each hit starts from the chain at rest in static equilibrium on the sample as the previous
hits left it (on the unloading curve of the largest indentation reached: the chain was
lifted and set down again, or came to rest between hits), the striker at the device's
speed. After each hit the sample's history is the largest indentation reached so far.

Per hit: the TOF (:func:`ssw.chain.run.run_peaks`), the peak wall force, the peak
indentation, the permanent set (the residual indentation once unloaded), its increment,
the energy the sample absorbed irrecoverably (the growth of the wall's dissipated energy:
the area of the hit's hysteresis loop), and under a plate the split of the permanent set
into the depth the plate-sample interface keeps on the axis (the sample's own set, and
with a yielding plate on an elastic sample the plate's permanent bending) and the plate's
permanent thinning there (zero for an elastic plate).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ssw.chain.params import ChainParams
from ssw.errors import ConfigError


@dataclass(frozen=True)
class Hits:
    """Per hit (rows) and scene (columns), SI: ``tof`` s, ``peak_force`` N,
    ``peak_indentation`` m, ``permanent_set`` m (after the hit), ``set_increment`` m,
    ``dissipated`` J (in the hit), ``interface_set`` m (the permanent depth of the
    plate-sample interface on the axis; without a plate the permanent set) and
    ``plate_thinning`` m (the rest: the plate's permanent thinning there). ``static_set`` (n,) m and
    ``static_dissipated`` (n,) J: what placing the chain did. ``wall``: the sample after
    the last hit.

    Parameters
    ----------
    tof : numpy.ndarray
        TOF (s), (hits, n).
    peak_force : numpy.ndarray
        Peak wall force (N), (hits, n).
    peak_indentation : numpy.ndarray
        Peak indentation (m), (hits, n).
    permanent_set : numpy.ndarray
        Permanent set after the hit (m), (hits, n).
    set_increment : numpy.ndarray
        Permanent set added by the hit (m), (hits, n).
    dissipated : numpy.ndarray
        Energy dissipated in the hit (J), (hits, n).
    interface_set : numpy.ndarray
        Permanent depth of the plate-sample interface on the axis (m), (hits, n).
    plate_thinning : numpy.ndarray
        The plate's permanent thinning there (m), (hits, n).
    static_set : numpy.ndarray
        Permanent set of placing the chain (m), (n,).
    static_dissipated : numpy.ndarray
        Energy dissipated placing the chain (J), (n,).
    wall : PlasticWall
        The sample after the last hit.
    """

    tof: np.ndarray
    peak_force: np.ndarray
    peak_indentation: np.ndarray
    permanent_set: np.ndarray
    set_increment: np.ndarray
    dissipated: np.ndarray
    interface_set: np.ndarray
    plate_thinning: np.ndarray
    static_set: np.ndarray
    static_dissipated: np.ndarray
    wall: Any

    def rows(self) -> list[dict[str, Any]]:
        """One mapping per hit (first scene).

        Returns
        -------
        list of dict
            ``hit`` and each per-hit quantity of the first scene (SI).
        """
        keys = ("tof", "peak_force", "peak_indentation", "permanent_set", "set_increment",
                "dissipated", "interface_set", "plate_thinning")
        return [{"hit": i + 1, **{k: float(getattr(self, k)[i, 0]) for k in keys}}
                for i in range(self.tof.shape[0])]


def dissipated(wall: Any, d_max: np.ndarray) -> np.ndarray:
    """(n,) J: the energy the sample lost since virgin, at the history ``d_max`` (m).

    Parameters
    ----------
    wall : PlasticWall
        The sample.
    d_max : numpy.ndarray
        Largest indentations of the history (m), (n,).

    Returns
    -------
    numpy.ndarray
        Dissipated energy (J), (n,).
    """
    return wall.energies(np.zeros(wall.n), d_max)[1]


def run_hits(params: ChainParams, wall: Any, hits: int) -> Hits:
    """``hits`` consecutive hits of the chain ``params`` on the virgin sample ``wall`` (a
    :class:`ssw.walls.plastic.PlasticWall`).

    Parameters
    ----------
    params : ChainParams
        The chain.
    wall : PlasticWall
        The virgin sample.
    hits : int
        Number of hits, >= 1.

    Returns
    -------
    Hits
        Each hit's TOF (s), peaks, permanent sets (m) and dissipated energies (J).

    Raises
    ------
    ConfigError
        If ``hits`` is not an integer >= 1.
    """
    from ssw.chain.run import run_peaks
    from ssw.chain.statics import static_contact_forces

    if not (isinstance(hits, int | np.integer) and hits >= 1):
        raise ConfigError("--hits", hits, "an integer >= 1")
    F0 = np.full(wall.n, float(static_contact_forces(params)[-1]))
    placed = wall.with_history(wall.indentation(F0))
    static_set = placed.residual_indentation()
    lost = dissipated(placed, placed.d_max0)
    static_lost = lost.copy()
    w = placed
    out: dict[str, list[np.ndarray]] = {k: [] for k in (
        "tof", "peak_force", "peak_indentation", "permanent_set", "set_increment",
        "dissipated", "interface_set", "plate_thinning")}
    for _ in range(hits):
        set_before = w.residual_indentation()
        pk, run = run_peaks(params, w)
        peak = run.peak_wall_indentation
        w = w.with_history(peak)
        now = dissipated(w, w.d_max0)
        out["tof"].append(np.asarray(pk.tof, float))
        out["peak_force"].append(np.nanmax(run.wall_force, axis=0))
        out["peak_indentation"].append(peak)
        out["permanent_set"].append(w.residual_indentation())
        out["set_increment"].append(w.residual_indentation() - set_before)
        out["dissipated"].append(now - lost)
        under = w.interface_residual_indentation()
        out["interface_set"].append(under)
        out["plate_thinning"].append(w.residual_indentation() - under)
        lost = now
    return Hits(**{k: np.array(v) for k, v in out.items()}, static_set=static_set,
                static_dissipated=static_lost, wall=w)
