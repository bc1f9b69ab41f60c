"""The plate design as an optimization: a bounded search in thickness per material, the
ranking of every candidate evaluated, and the Pareto front of sensitivity against the
sample's yield.

Merit. One number ranks candidates (the smaller the better), lexicographic in effect:

    merit = -S + W_hard (v_plate + v_mass) + W_soft v_soil,

``S`` the worst-case sensitivity, ``v`` the relative excess of each index over its limit
(:attr:`ssw.design.evaluate.Candidate.violations`), ``W_hard`` = :data:`HARD_WEIGHT`
(a plate that yields, or outweighs its limit, loses to any that does not) and ``W_soft`` =
:data:`SOFT_WEIGHT` (a sample that yields beyond its limit loses to one that does not;
when every plate lets it yield, the one that lets it yield least wins). For feasible
candidates the merit is ``-S``: the most sensitive wins.

Search (:func:`search`). Per material (and plate diameter and striker speed, when those are
design variables too) the thickness is continuous: :data:`ssw.design.spec.SCAN_POINTS`
thicknesses log-spaced over the range (evaluated together: one batched chain run) bracket
the best one; a batched refinement then narrows the bracket in ``ln t`` (the best point
evaluated and its two neighbours): each round evaluates :data:`REFINE_POINTS` thicknesses
together (one batched chain run; the scenes are independent, each keeps its own TOF and
tangent), equally spaced inside the bracket, or, when the best point is a bound of the
range (every plate yields and the thinnest least), approaching that bound geometrically
down to :data:`BOUND_SHARE` ``thickness_tol`` from it. The search ends when both of the
best point's neighbours are within ``thickness_tol`` of it: for a merit unimodal in the
bracket (what a bracketing search assumes) the minimizer lies between them, so the best
point is the optimum to ``thickness_tol``, as Brent's bounded method (``fminbound``:
Forsythe, Malcolm & Moler 1977) reaches it; in one to four batched runs instead of its
9-11 sequential evaluations (one round, four plates, when the optimum is on a bound).
The contact operators of each thickness are built once and cached on disk
(:mod:`ssw.contact.operators`), so a repeated design costs the chain and the stresses
only.

Ranking (:func:`rank`). The recommended candidate has the least merit of all candidates
evaluated (scan, search and the device's own plate). The Pareto front is the set of
candidates whose plate stays elastic and light enough (the hard limits) that no other such
candidate beats on both the sensitivity (larger) and the soil yield index (smaller).

References
----------
Forsythe, G. E., Malcolm, M. A. & Moler, C. B. (1977). *Computer Methods for Mathematical
Computations*, Prentice-Hall (fmin, Brent 1973): the bounded search this refinement
replaces, to the same tolerance.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ssw.design.evaluate import Candidate, Evaluator
from ssw.design.spec import DesignSpec

#: Weight of the hard limits' violations (plate yield, mass) in the merit.
HARD_WEIGHT = 1.0e6
#: Weight of the soil limit's violation in the merit.
SOFT_WEIGHT = 10.0
#: Thicknesses evaluated together per round of the search's refinement (inside the
#: bracket, the bracket shrinks by (REFINE_POINTS + 1) / 2 per round).
REFINE_POINTS = 4
#: With the best thickness on a bound of the range, a round's points approach it
#: geometrically, the nearest at this share of ``thickness_tol`` from it (below 1: room for
#: the rounding of thicknesses to the quantum).
BOUND_SHARE = 0.9


def merit(c: Candidate) -> float:
    """The ranking number of a candidate (module docstring); smaller is better.

    Parameters
    ----------
    c : ssw.design.evaluate.Candidate
        The candidate.

    Returns
    -------
    float
        ``-S + HARD_WEIGHT (v_plate + v_mass) + SOFT_WEIGHT v_soil`` (-): ``S`` the
        worst-case sensitivity, ``v`` the relative violations of the limits.
    """
    v = c.violations
    return (-c.sensitivity + HARD_WEIGHT * (v["plate_yield_index"] + v["mass_ratio"])
            + SOFT_WEIGHT * v["soil_yield_index"])


@dataclass(frozen=True)
class Search:
    """The thickness search of one material (plate diameter, striker speed): its best
    candidate, every thickness it evaluated (in order) and scipy's report.

    Parameters
    ----------
    material : str
        The plate material (library key).
    plate_diameter : float
        m, the plate's diameter.
    striker_velocity : float
        m/s, the striker's speed.
    best : ssw.design.evaluate.Candidate
        The candidate of smallest merit.
    evaluated : tuple of float
        m, every thickness evaluated, in order.
    nfev : int
        The number of thicknesses evaluated.
    message : str
        How the refinement ended.
    """

    material: str
    plate_diameter: float
    striker_velocity: float
    best: Candidate
    evaluated: tuple[float, ...]
    nfev: int
    message: str

    def to_dict(self) -> dict[str, Any]:
        """The JSON record of the search.

        Returns
        -------
        dict of str to Any
            Material, plate diameter (m), striker speed (m/s), best thickness (m) and
            merit, the thicknesses evaluated (m), ``nfev`` and ``message``.
        """
        return {"material": self.material, "plate_diameter": self.plate_diameter,
                "striker_velocity": self.striker_velocity,
                "best_thickness": self.best.thickness, "best_merit": merit(self.best),
                "evaluated": list(self.evaluated), "nfev": self.nfev, "message": self.message}


def search(ev: Evaluator, material: str, plate_diameter: float | None = None,
           striker_velocity: float | None = None,
           extra: tuple[tuple[str, float, str], ...] = ()) -> Search:
    """The best thickness of ``material`` (module docstring): a log-spaced scan, then a
    batched grid refinement of the merit in ``ln t`` around the scan's best point.

    Parameters
    ----------
    ev : ssw.design.evaluate.Evaluator
        Evaluates plates (:meth:`ssw.design.evaluate.Evaluator.many`: one batched chain
        run per call).
    material : str
        The plate material (library key).
    plate_diameter : float or None
        m (default: the device's).
    striker_velocity : float or None
        m/s (default: the device's).
    extra : tuple of tuple
        Plates ``(material, thickness m, source)`` of the same diameter and striker speed
        evaluated with the scan (the device's own plate).

    Returns
    -------
    Search
        The best candidate, every thickness evaluated (in order), the number of
        evaluations and how the refinement ended.
    """
    from ssw.design.evaluate import quantize
    from ssw.design.spec import THICKNESS_QUANTUM

    spec = ev.spec
    lo, hi = np.log(spec.thickness[0]), np.log(spec.thickness[1])
    xs = np.linspace(lo, hi, spec.scan_points)
    seen: list[Candidate] = []
    scan = ev.many([(material, float(np.exp(x))) for x in xs]
                   + [(m, t) for m, t, _ in extra], plate_diameter, striker_velocity,
                   ["scan"] * xs.size + [src for _, _, src in extra])[: xs.size]
    seen.extend(scan)
    values = [merit(c) for c in scan]
    # ln of the thicknesses evaluated (rounded to the quantum), sorted with their merits
    x, f = _refine(np.log([c.thickness for c in scan]), np.asarray(values),
                   int(np.argmin(values)))
    tol = spec.thickness_tol
    nfev, rounds = xs.size, 0
    while True:
        b = int(np.argmin(f))
        err = max(x[b] - x[0], x[-1] - x[b])  # the minimizer lies in [x[0], x[-1]]
        if err <= tol:
            message = (f"batched refinement: {rounds} rounds of up to {REFINE_POINTS} "
                       f"thicknesses, the best within {err:.3g} in ln t of its bracket's "
                       f"ends (tolerance {tol:g})")
            break
        width = x[-1] - x[0]
        if b in (0, x.size - 1):  # the best is a bound of the range: geometric toward it
            r = (BOUND_SHARE * tol / width) ** (1.0 / REFINE_POINTS)
            off = width * r ** np.arange(1, REFINE_POINTS + 1)
            grid = x[b] + off if b == 0 else x[b] - off
        else:  # uniform over the bracket
            grid = x[0] + width / (REFINE_POINTS + 1) * np.arange(1, REFINE_POINTS + 1)
        known = {quantize(c.thickness) for c in seen}
        new = []
        for g in grid:  # thicknesses are rounded: one evaluation per rounded thickness
            q = quantize(float(np.exp(g)))
            if q not in known:
                known.add(q)
                new.append(q)
        if not new:
            message = (f"the thicknesses of the next round are those evaluated (rounded to "
                       f"{THICKNESS_QUANTUM:g} m): the best within {err:.3g} in ln t of its "
                       f"bracket's ends (tolerance {tol:g})")
            break
        cands = ev.many([(material, t) for t in new], plate_diameter, striker_velocity,
                        ["search"] * len(new))
        seen.extend(cands)
        nfev += len(new)
        rounds += 1
        pts = np.concatenate([x, np.log([c.thickness for c in cands])])
        vals = np.concatenate([f, [merit(c) for c in cands]])
        order = np.argsort(pts, kind="stable")
        x, f = _refine(pts[order], vals[order], int(np.argmin(vals[order])))
    best = min(seen, key=merit)
    return Search(material, best.plate_diameter, best.striker_velocity, best,
                  tuple(c.thickness for c in seen), nfev, message)


def _refine(x: np.ndarray, f: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The bracket around the best point ``k`` of the sorted points ``x`` (``ln t``) with
    merits ``f``: its neighbours (the point itself at an end of the range) and the best
    point, with their merits."""
    sel = sorted({max(k - 1, 0), k, min(k + 1, x.size - 1)})
    return x[sel], f[sel]


def pareto_front(cands: Iterable[Candidate]) -> list[Candidate]:
    """The candidates meeting the hard limits that no other such candidate dominates
    (larger sensitivity and smaller soil yield index, one of them strictly), sorted by
    soil yield index.

    Parameters
    ----------
    cands : iterable of ssw.design.evaluate.Candidate
        The candidates.

    Returns
    -------
    list of ssw.design.evaluate.Candidate
        The front, by soil yield index then decreasing sensitivity.
    """
    pool = [c for c in cands if c.plate_feasible]
    S = np.array([c.sensitivity for c in pool])
    Y = np.array([c.soil_yield_index for c in pool])
    front = []
    for i, c in enumerate(pool):
        dom = (S >= S[i]) & (Y <= Y[i]) & ((S > S[i]) | (Y < Y[i]))
        if not np.any(dom):
            front.append(c)
    return sorted(front, key=lambda c: (c.soil_yield_index, -c.sensitivity))


@dataclass(frozen=True)
class Ranking:
    """Every candidate (by merit), the recommended one and why, and the Pareto front.

    Parameters
    ----------
    candidates : list of ssw.design.evaluate.Candidate
        One per plate, by merit.
    recommended : ssw.design.evaluate.Candidate
        The first of them.
    reasons : list of str
        Why it won, in words (:func:`reasons`).
    pareto : list of ssw.design.evaluate.Candidate
        The Pareto front (:func:`pareto_front`).
    """

    candidates: list[Candidate]
    recommended: Candidate
    reasons: list[str]
    pareto: list[Candidate]


def rank(cands: Iterable[Candidate], spec: DesignSpec) -> Ranking:
    """Rank candidates by merit; the first is recommended, with the reasons it won.

    Parameters
    ----------
    cands : iterable of ssw.design.evaluate.Candidate
        The candidates (one kept per plate, the ``reference`` label preferred).
    spec : ssw.design.spec.DesignSpec
        The design problem (its limits, for the reasons).

    Returns
    -------
    Ranking
        The candidates by merit, the recommended one, its reasons and the Pareto front.

    Raises
    ------
    ValueError
        When there is no candidate.
    """
    unique: dict[tuple[str, float, float, float], Candidate] = {}
    for c in cands:  # one per plate (the same plate from two jobs: keep the reference label)
        old = unique.get(c.key)
        if old is None or (c.source == "reference" and old.source != "reference"):
            unique[c.key] = c
    pool = sorted(unique.values(), key=merit)
    if not pool:
        raise ValueError("no candidate to rank")
    best = pool[0]
    return Ranking(pool, best, reasons(best, pool, spec), pareto_front(pool))


def reasons(best: Candidate, pool: list[Candidate], spec: DesignSpec) -> list[str]:
    """Why ``best`` won, in words with its numbers.

    Parameters
    ----------
    best : ssw.design.evaluate.Candidate
        The recommended candidate.
    pool : list of ssw.design.evaluate.Candidate
        Every candidate ranked.
    spec : ssw.design.spec.DesignSpec
        The design problem (limits, thickness range, TOF uncertainty).

    Returns
    -------
    list of str
        The reasons, one sentence each.
    """
    feas = [c for c in pool if c.feasible]
    hard = [c for c in pool if c.plate_feasible]
    out = []
    lim = (f"plate yield index {best.plate_yield_index:.3g} (<= 1), soil yield index "
           f"{best.soil_yield_index:.3g} (limit {spec.soil_yield_limit:g}), mass ratio "
           f"{best.mass_ratio:.3g} (<= {spec.max_mass_ratio:g})")
    if best.feasible:
        out.append(f"meets every limit: {lim}")
        rivals = [c for c in feas if c is not best]
        if rivals:
            nxt = max(rivals, key=lambda c: c.sensitivity)
            out.append(f"the most sensitive of {len(feas)} feasible candidates: worst-case "
                       f"sensitivity {best.sensitivity:.4g} against {nxt.sensitivity:.4g} "
                       f"for the next ({_label(nxt)})")
        else:
            out.append(f"the only feasible candidate of {len(pool)}")
    elif best.plate_feasible:
        out.append(f"no candidate keeps the sample within its yield limit "
                   f"{spec.soil_yield_limit:g}; of the {len(hard)} whose plate stays elastic "
                   f"and light, it yields the sample least: {lim}")
        out.append(f"worst-case sensitivity {best.sensitivity:.4g}")
    else:
        out.append(f"no candidate keeps its plate elastic (and within the mass limit); it "
                   f"violates the hard limits least: {lim}")
    lo, hi = spec.thickness
    if best.thickness <= lo * (1 + 1e-3) or best.thickness >= hi * (1 - 1e-3):
        side = "lower" if best.thickness <= lo * (1 + 1e-3) else "upper"
        out.append(f"its thickness is at the {side} bound of the range searched "
                   f"({lo * 1e3:.3g}-{hi * 1e3:.3g} mm): the optimum may lie beyond it")
    out.append(f"worst-case resolution dE/E {best.resolution:.3g} "
               f"(u_TOF {spec.tof_uncertainty:.3g} s)")
    ref = [c for c in pool if c.source == "reference"]
    if ref and ref[0] is not best:
        r = ref[0]
        out.append(f"against the device's plate ({_label(r)}): sensitivity "
                   f"{best.sensitivity / r.sensitivity:.3g} x, soil yield index "
                   f"{best.soil_yield_index / r.soil_yield_index:.3g} x, plate yield index "
                   f"{best.plate_yield_index:.3g} vs {r.plate_yield_index:.3g}")
    return out


def _label(c: Candidate) -> str:
    return f"{c.material} {c.thickness * 1e3:.3g} mm"
