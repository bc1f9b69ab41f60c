"""The device design: scan the device space, refine the best devices by a bounded search,
rank, and place the thesis device.

:func:`run_device_design` is the API of ``ssw design --space device``:

1. the scan (:meth:`ssw.design.space.DeviceSpace.family_points`): every chain of every
   family (bead diameter x plate material; one process each with ``jobs > 1``) at the scan
   points of its continuous variables, evaluated over the soil grid
   (:func:`ssw.design.device_eval.evaluate`, the devices of one chain in one batched run);
2. the bounded search: the ``finalists`` best devices (each of its own chain and plate,
   among the chains and plates the run scans: the base device competes for its own pair's
   start only when its chain is scanned) move their continuous variables (sensor and
   striker mass ratios, drop height, plate thickness, in their logarithm) inside the
   space's ranges by ``scipy.optimize.minimize`` (Powell, bounded; :func:`merit` as the
   objective, ``refine_evaluations`` evaluations);
3. the ranking (:func:`rank`): the feasible device of finest worst-case resolution; when
   none is feasible, the hard-feasible device of finest resolution whose soil yield is
   least in excess, else the smallest weighted violation; the Pareto fronts of the
   hard-feasible devices (resolution against the soil yield index, resolution against the
   mass);
4. the recommended device and the base (thesis) device evaluated again at their own time
   step (the TOF ``ssw tof`` gives for each), with the reasons;
5. with ``plastic_hits`` > 0 (:func:`with_plastic_check`, after the ranking, so after the
   merge of the workflow's family jobs): the ``finalists`` best devices of distinct chains
   and plates and the base device struck that many times on a yielding sample through
   their yielding plate (:func:`ssw.design.hits_check.device_hits_check`): the plate's dent,
   the sample's set and the TOF drift in each one's record (a record, not a constraint:
   the ranking is the elastic one's).
"""

from __future__ import annotations

import resource
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ssw.design.device_eval import HARD, DeviceCandidate, evaluate
from ssw.design.device_spec import DeviceSpec
from ssw.design.space import DevicePoint, DeviceSpace

#: Weight of the hard limits' excess against the soft one's in :func:`merit`.
HARD_WEIGHT = 10.0


def merit(c: DeviceCandidate) -> float:
    """A scalar to minimize: ``ln(dE/E)`` plus ``HARD_WEIGHT`` times the hard limits'
    relative excess and the soft limit's excess (0 for a feasible device). Infinite for a
    device with no TOF somewhere in the soil range. The excesses not computed (a device
    whose stresses were skipped, ``stresses_skipped``: it breaks another hard limit) count
    0, so its merit is a lower bound.

    Parameters
    ----------
    c : ssw.design.device_eval.DeviceCandidate
        The device evaluated.

    Returns
    -------
    float
        ``ln(dE/E) + HARD_WEIGHT sum(v_hard) + v_soil`` (-), ``v`` the relative excesses
        over the limits; inf without a TOF.
    """
    if not np.isfinite(c.resolution):
        return float("inf")
    v = c.violations
    hard = sum(v[k] for k in HARD if not np.isnan(v[k]))
    soil = v["soil_yield_index"]
    return float(np.log(c.resolution) + HARD_WEIGHT * hard + (0.0 if np.isnan(soil) else soil))


def _order(c: DeviceCandidate) -> tuple[int, float, float]:
    """Ranking key: feasible, then hard-feasible (least soil excess), then the rest."""
    if c.feasible:
        return (0, c.resolution, 0.0)
    if c.hard_feasible:
        return (1, c.violations["soil_yield_index"], c.resolution)
    return (2, merit(c), c.resolution)


def dominates(a: DeviceCandidate, b: DeviceCandidate, objectives: tuple[str, ...]) -> bool:
    """``a`` is no worse than ``b`` in every objective (smaller is better) and better in
    one.

    Parameters
    ----------
    a : ssw.design.device_eval.DeviceCandidate
        The first device.
    b : ssw.design.device_eval.DeviceCandidate
        The second device.
    objectives : tuple of str
        Attribute names of the candidates (e.g. ``resolution``, ``mass``), each smaller
        better.

    Returns
    -------
    bool
        Whether ``a`` dominates ``b``.
    """
    va = [float(getattr(a, k)) for k in objectives]
    vb = [float(getattr(b, k)) for k in objectives]
    return all(x <= y for x, y in zip(va, vb, strict=True)) and any(
        x < y for x, y in zip(va, vb, strict=True))


def pareto(cands: list[DeviceCandidate], objectives: tuple[str, ...]) -> list[DeviceCandidate]:
    """The non-dominated hard-feasible candidates, by the first objective.

    Parameters
    ----------
    cands : list of ssw.design.device_eval.DeviceCandidate
        The candidates.
    objectives : tuple of str
        Attribute names of the candidates, each smaller better.

    Returns
    -------
    list of ssw.design.device_eval.DeviceCandidate
        The front, sorted by the objectives in order.
    """
    pool = [c for c in cands if c.hard_feasible]
    front = [c for c in pool if not any(dominates(o, c, objectives) for o in pool)]
    return sorted(front, key=lambda c: tuple(getattr(c, k) for k in objectives))


@dataclass(frozen=True)
class Ranking:
    """Every candidate ranked (best first), the recommended one and the fronts.

    Parameters
    ----------
    candidates : list of ssw.design.device_eval.DeviceCandidate
        Every candidate, best first.
    recommended : ssw.design.device_eval.DeviceCandidate
        The first of them.
    front_soil : list of ssw.design.device_eval.DeviceCandidate
        The Pareto front of resolution and soil yield index.
    front_mass : list of ssw.design.device_eval.DeviceCandidate
        The Pareto front of resolution and mass.
    """

    candidates: list[DeviceCandidate]
    recommended: DeviceCandidate
    front_soil: list[DeviceCandidate]
    front_mass: list[DeviceCandidate]


def rank(cands: list[DeviceCandidate]) -> Ranking:
    """The ranking (module docstring); ValueError on no candidate.

    Parameters
    ----------
    cands : list of ssw.design.device_eval.DeviceCandidate
        The candidates.

    Returns
    -------
    Ranking
        Feasible devices by resolution, then hard-feasible ones by soil excess, then the
        rest by :func:`merit`; and the two Pareto fronts.

    Raises
    ------
    ValueError
        When there is no candidate.
    """
    if not cands:
        raise ValueError("no candidate to rank")
    ordered = sorted(cands, key=_order)
    return Ranking(ordered, ordered[0], pareto(ordered, ("resolution", "soil_yield_index")),
                   pareto(ordered, ("resolution", "mass")))


@dataclass(frozen=True)
class _Task:
    space: DeviceSpace
    spec: DeviceSpec
    base: Any
    materials: dict[str, Any]
    contact: dict[str, Any]
    full_scale: float


def _evaluate(task: _Task, points: list[DevicePoint], source: str,
              own_step: bool = False) -> list[DeviceCandidate]:
    items = [(p, p.params(task.base, task.materials)) for p in points]
    # a device at its own step is the base device or the recommended one: stated whole
    return evaluate(items, task.spec, task.materials, task.contact, task.base.bead_radius,
                    task.full_scale, source=source, own_step=own_step, all_stresses=own_step)


def _scan_family(args: tuple[_Task, float, str, int, int]) -> list[DeviceCandidate]:
    task, diameter, plate, part, parts = args
    return _evaluate(task, task.space.family_points(diameter, plate, part, parts), "scan")


def _refine(args: tuple[_Task, DeviceCandidate]) -> tuple[list[DeviceCandidate], dict]:
    """The bounded search of one finalist's continuous variables."""
    from scipy.optimize import minimize

    task, start = args
    seen: dict[tuple[Any, ...], DeviceCandidate] = {}

    def f(x: np.ndarray) -> float:
        pt = start.point.with_continuous(np.exp(x))
        if pt.key not in seen:
            seen[pt.key] = _evaluate(task, [pt], "search")[0]
        return merit(seen[pt.key])

    x0 = np.log(start.point.continuous())
    bounds = task.space.bounds()
    x0 = np.clip(x0, [b[0] for b in bounds], [b[1] for b in bounds])
    res = minimize(f, x0, method="Powell", bounds=bounds,
                   options={"maxfev": task.spec.refine_evaluations,
                            "xtol": task.spec.refine_tol, "ftol": 1e-4})
    return list(seen.values()), {"start": start.point.to_dict(), "merit_start": merit(start),
                                 "merit": float(res.fun), "evaluations": len(seen),
                                 "message": str(res.message)}


def map_jobs(fn: Any, tasks: list[Any], jobs: int) -> list[Any]:
    """``[fn(t) for t in tasks]``, in ``jobs`` processes when more than one.

    Parameters
    ----------
    fn : callable
        The function of one task (picklable when ``jobs > 1``).
    tasks : list
        Its arguments, one per call.
    jobs : int
        Processes (1: this process).

    Returns
    -------
    list
        ``fn``'s results in the order of ``tasks``.
    """
    if jobs <= 1 or len(tasks) <= 1:
        return [fn(t) for t in tasks]
    with ProcessPoolExecutor(max_workers=min(jobs, len(tasks))) as ex:
        return list(ex.map(fn, tasks))


@dataclass(frozen=True)
class DeviceDesignResult:
    """The device design's ranking, the base device, the searches and the cost (s).

    Parameters
    ----------
    spec : ssw.design.device_spec.DeviceSpec
        The design problem.
    space : ssw.design.space.DeviceSpace
        The devices searched.
    ranking : Ranking
        The candidates ranked.
    recommended : ssw.design.device_eval.DeviceCandidate
        The recommended device.
    reference : ssw.design.device_eval.DeviceCandidate or None
        The base device evaluated, or None.
    searches : list of dict of str to Any
        Each bounded search's record.
    wall_time : float
        s, the design's wall time.
    cpu_time : float
        s, its CPU time (user + sys, children included).
    plastic : dict of tuple to dict of str to Any
        The plastic check's record of a device, by its key.
    """

    spec: DeviceSpec
    space: DeviceSpace
    ranking: Ranking
    recommended: DeviceCandidate
    reference: DeviceCandidate | None
    searches: list[dict[str, Any]]
    wall_time: float
    cpu_time: float
    plastic: dict[tuple[Any, ...], dict[str, Any]] = field(default_factory=dict)

    def reasons(self) -> list[str]:
        """Why the recommended device (plain sentences with the numbers).

        Returns
        -------
        list of str
            The reasons, one sentence each (resolution, sensitivity, TOF, indices, the base
            device against it).
        """
        r, ref = self.recommended, self.reference
        cands = self.ranking.candidates
        n_ok = sum(c.feasible for c in cands)
        n_hard = sum(c.hard_feasible for c in cands)
        out = []
        if r.feasible:
            out.append(f"finest worst-case resolution dE/E = {r.resolution:.3g} over "
                       f"{self.spec.soil_E[0]:.3g}-{self.spec.soil_E[1]:.3g} Pa among the "
                       f"{n_ok} feasible of {len(cands)} devices evaluated")
        elif r.hard_feasible:
            out.append(f"no device keeps the sample's yield index within "
                       f"{self.spec.soil_yield_limit:g}; of the {n_hard} that meet every hard "
                       f"limit this one yields the sample least ({r.soil_yield_index:.3g})")
        else:
            worst = max(r.violations, key=lambda k: np.nan_to_num(r.violations[k], nan=-1.0))
            out.append(f"no device meets every hard limit; this one breaks them least "
                       f"(worst: {worst} {r.indices[worst]:.3g})")
        out.append(f"its sensitivity |d ln TOF / d ln E| >= {r.sensitivity:.3g}, TOF "
                   f"{np.min(r.tof_E) * 1e3:.3g}-{np.max(r.tof_E) * 1e3:.3g} ms, pulses "
                   f">= {np.nanmin(r.samples_per_pulse_E):.3g} samples wide at "
                   f"{self.spec.sample_rate:g} S/s")
        out.append("indices: " + ", ".join(f"{k} {v:.3g}" for k, v in r.indices.items()))
        if ref is not None:
            better = (ref.resolution / r.resolution if np.isfinite(ref.resolution)
                      and r.resolution > 0 else float("nan"))
            broken = [k for k, v in ref.violations.items() if v > 0]
            n_dom = sum(dominates(c, ref, ("resolution", "soil_yield_index", "mass"))
                        for c in cands if c.feasible)
            out.append(f"the base device ({ref.point.label()}): dE/E {ref.resolution:.3g} "
                       f"({better:.3g} x the recommended's), "
                       + (f"breaks {', '.join(broken)}" if broken else "feasible")
                       + f"; on the resolution-soil front: "
                       f"{'yes' if _on(ref, self.ranking.front_soil) else 'no'}, dominated "
                       f"by {n_dom} feasible devices")
        return out

    def to_dict(self) -> dict[str, Any]:
        """The JSON of ``ssw design --space device``.

        Returns
        -------
        dict of str to Any
            The statement, spec, space, soil grid (Pa), recommended and base devices, the
            Pareto fronts, every candidate, the plastic checks, the searches, counts and
            the wall and CPU times (s).
        """
        rk = self.ranking
        plastic = self.plastic
        return {
            "ssw_kind": "design_device",
            **self.spec.statement(),
            "spec": self.spec.to_dict(),
            "space": self.space.to_dict(),
            "soil_E": self.spec.grid.tolist(),
            "recommended": {**self.recommended.to_dict(), "merit": merit(self.recommended),
                            "label": self.recommended.point.label(),
                            "reasons": self.reasons(),
                            "plastic": plastic.get(self.recommended.key)},
            "reference": None if self.reference is None else {
                **self.reference.to_dict(), "merit": merit(self.reference),
                "label": self.reference.point.label(),
                "plastic": plastic.get(self.reference.key),
                "on_front_soil": _on(self.reference, rk.front_soil),
                "on_front_mass": _on(self.reference, rk.front_mass),
                "rank": 1 + [c.key for c in rk.candidates].index(self.reference.key)
                if self.reference.key in [c.key for c in rk.candidates] else None},
            "pareto_soil": [_brief(c) for c in rk.front_soil],
            "pareto_mass": [_brief(c) for c in rk.front_mass],
            "candidates": [{**c.to_dict(), "merit": merit(c), "plastic": plastic.get(c.key)}
                           for c in rk.candidates],
            "plastic_check": [{"label": c.point.label(), **c.point.to_dict(),
                               "source": c.source, "step": c.step, **plastic[c.key]}
                              for c in rk.candidates if c.key in plastic],
            "searches": self.searches,
            "evaluations": len(rk.candidates),
            "feasible": sum(c.feasible for c in rk.candidates),
            "wall_time": self.wall_time,
            "cpu_time": self.cpu_time,
        }


def _on(c: DeviceCandidate, front: list[DeviceCandidate]) -> bool:
    return any(o.key == c.key for o in front)


def _brief(c: DeviceCandidate) -> dict[str, Any]:
    return {"label": c.point.label(), **c.point.to_dict(), "resolution": c.resolution,
            "soil_yield_index": c.soil_yield_index, "mass": c.mass}


def run_device_design(space: DeviceSpace, spec: DeviceSpec, base: Any,
                      materials: dict[str, Any], contact: dict[str, Any], full_scale: float,
                      reference: DevicePoint | None = None, *, jobs: int = 1,
                      families: list[tuple[float, str]] | None = None,
                      parts: tuple[int, int] | None = None) -> DeviceDesignResult:
    """Scan, search and rank the device space (module docstring).

    Parameters
    ----------
    space : ssw.design.space.DeviceSpace
        The devices searched.
    spec : ssw.design.device_spec.DeviceSpec
        The question: soils, limits, DAQ.
    base : ssw.chain.params.ChainParams
        The base device's chain (numerics, interface, preload; its bead radius is the
        scale of the ``contact`` settings).
    materials : dict
        The materials library.
    contact : dict
        The study's ``contact:`` settings.
    full_scale : float
        N, the sensor's and DAQ's full scale.
    reference : DevicePoint or None
        The base device as a point (evaluated at its own step and ranked with the others).
    jobs : int
        Processes (one family each; the searches one finalist each).
    families : list of tuple or None
        Only these (bead diameter, plate material) families (default: the space's).
    parts : tuple of int or None
        ``(part, parts)``: of each family only the chains of that part
        (:meth:`ssw.design.space.DeviceSpace.family_points`; the workflow's scatter).

    Returns
    -------
    DeviceDesignResult
        The ranking, the recommended and base devices, the searches, the cost.
    """
    t0, c0 = time.perf_counter(), cpu_time()
    task = _Task(space, spec, base, materials, contact, full_scale)
    fams = families if families is not None else space.families()
    part, n_parts = parts if parts is not None else (0, 1)
    scanned = [c for found in map_jobs(_scan_family, [(task, d, m, part, n_parts)
                                                      for d, m in fams], jobs)
               for c in found]
    seen = {c.key: c for c in scanned}
    ref = None
    if reference is not None:
        ref = _evaluate(task, [reference], "reference", own_step=True)[0]
        seen[ref.key] = ref
    # the searches start from the chains and plates this run scans (the base device competes
    # for its own pair's start there): a part of a family (--part) searches its own pairs,
    # never another part's, so the parts together search what one run does
    mine = {(c.point.chain, c.point.plate_material) for c in scanned}
    finalists = best_of_pairs(sorted((c for c in seen.values()
                                      if (c.point.chain, c.point.plate_material) in mine),
                                     key=_order), spec.finalists)
    searches = []
    if spec.refine_evaluations > 0 and finalists:
        for found, info in map_jobs(_refine, [(task, c) for c in finalists], jobs):
            for c in found:
                seen.setdefault(c.key, c)
            searches.append(info)
    ranking = rank(list(seen.values()))
    best = ranking.recommended
    rec = best if best.step == "own" else _evaluate(task, [best.point], best.source,
                                                   own_step=True)[0]
    seen[rec.key] = rec
    ranking = rank(list(seen.values()))
    return DeviceDesignResult(spec, space, ranking, ranking.recommended, ref, searches,
                              time.perf_counter() - t0, cpu_time() - c0)


def merge_device_results(results: list[dict[str, Any]]) -> DeviceDesignResult:
    """The candidates of several device designs of one question (the workflow's family
    jobs' JSON) ranked together. Each family's best was evaluated at its own step, so the
    best of all is too; the costs add up. ConfigError when the questions differ.

    Parameters
    ----------
    results : list of dict of str to Any
        The JSON of each ``ssw design --space device`` result.

    Returns
    -------
    DeviceDesignResult
        Their candidates ranked together; wall and CPU times the sums of theirs (s).

    Raises
    ------
    ssw.errors.ConfigError
        When there is no result, or their questions differ.
    """
    from ssw.design.space import space_from_dict
    from ssw.errors import ConfigError

    if not results:
        raise ConfigError("--merge", [], "at least one ssw design --space device JSON")
    spec = DeviceSpec.from_dict(results[0]["spec"])
    for r in results[1:]:
        if DeviceSpec.from_dict(r["spec"]) != spec:
            raise ConfigError("--merge", r["spec"], "results of one question (the same spec)")
    space_d = results[0]["space"]
    space = space_from_dict(space_d, space_d["plate_diameter_ratio"])
    seen: dict[tuple[Any, ...], DeviceCandidate] = {}
    plastic: dict[tuple[Any, ...], dict[str, Any]] = {}
    for r in results:
        for d in r["candidates"]:
            c = DeviceCandidate.from_dict(d, spec.limits)
            if c.key not in seen or c.step == "own":
                seen[c.key] = c
            if d.get("plastic") is not None:
                plastic[c.key] = d["plastic"]
    ranking = rank(list(seen.values()))
    ref_d = next((r["reference"] for r in results if r.get("reference")), None)
    ref = None if ref_d is None else DeviceCandidate.from_dict(ref_d, spec.limits)
    return DeviceDesignResult(spec, space, ranking, ranking.recommended, ref,
                              [s for r in results for s in r["searches"]],
                              sum(r["wall_time"] for r in results),
                              sum(r["cpu_time"] for r in results), plastic)


#: Share of a sized design's evaluations its scan may take (:func:`sized`); the rest go to
#: the bounded searches from the best devices.
SCAN_SHARE = 0.75


def sized(space: DeviceSpace, spec: DeviceSpec, n: int) -> tuple[DeviceSpace, DeviceSpec]:
    """The space and spec of a design of about ``n`` evaluations (``--size N``).

    The scan of each continuous variable in turn (the order of
    :data:`ssw.design.space.CONTINUOUS`) triples its points while it holds at most
    :data:`SCAN_SHARE` of ``n``: the centres of ``3 k`` equal cells hold those of ``k``
    (:meth:`ssw.design.space.Interval.scan_values`), so the grown scan holds every device
    of the space's own. The rest goes to the bounded searches, which start from the best
    devices of distinct chains and plate materials (the front's neighbourhood):
    ``finalists`` = the rest over ``refine_evaluations`` (at least the spec's), each search
    the rest over the finalists (at least the spec's ``refine_evaluations``). A space whose
    scan alone exceeds ``n`` is kept.

    Parameters
    ----------
    space : ssw.design.space.DeviceSpace
        The devices searched.
    spec : ssw.design.device_spec.DeviceSpec
        The question (its ``finalists`` and ``refine_evaluations``).
    n : int
        Evaluations wanted (>= 1).

    Returns
    -------
    tuple
        The grown space and the spec with its search budget.

    Raises
    ------
    ConfigError
        ``n`` < 1.
    """
    from ssw.design.space import CONTINUOUS
    from ssw.errors import ConfigError

    if not (isinstance(n, int) and n >= 1):
        raise ConfigError("--size", n, "a number of evaluations >= 1")
    k = 0
    while True:
        name = CONTINUOUS[k % len(CONTINUOUS)]
        iv = getattr(space, name)
        grown = replace(space, **{name: replace(iv, scan=3 * iv.scan)})
        if grown.size > SCAN_SHARE * n:
            break
        space, k = grown, k + 1
    rest = n - space.size
    if rest <= 0 or spec.refine_evaluations == 0:
        return space, spec
    pairs = sum(len(space.chains(d)) for d in space.bead_diameters) * len(
        space.plate_materials)
    finalists = int(min(pairs, max(spec.finalists, rest // spec.refine_evaluations)))
    return space, replace(spec, finalists=finalists, refine_evaluations=max(
        spec.refine_evaluations, rest // finalists))


def best_of_pairs(ordered: list[DeviceCandidate], n: int) -> list[DeviceCandidate]:
    """The finalists: the first ``n`` devices of distinct chains and plate materials.

    Parameters
    ----------
    ordered : list of DeviceCandidate
        Devices, best first.
    n : int
        Devices wanted.

    Returns
    -------
    list of DeviceCandidate
        At most ``n`` devices of ``ordered`` (its order), each of a finite :func:`merit`
        and of a chain and plate material no earlier one has.
    """
    out: list[DeviceCandidate] = []
    pairs: set[tuple[Any, ...]] = set()
    for c in ordered:
        pair = (c.point.chain, c.point.plate_material)
        if pair not in pairs and np.isfinite(merit(c)):
            pairs.add(pair)
            out.append(c)
        if len(out) >= n:
            break
    return out


def struck(result: DeviceDesignResult) -> list[DeviceCandidate]:
    """The devices of the plastic check.

    Parameters
    ----------
    result : DeviceDesignResult
        A ranked device design.

    Returns
    -------
    list of DeviceCandidate
        The ``spec.finalists`` finalists of the ranking (:func:`best_of_pairs`, the
        recommended first), and the base device when it is not one of them.
    """
    out = best_of_pairs(result.ranking.candidates, result.spec.finalists)
    ref = result.reference
    if ref is not None and all(c.key != ref.key for c in out):
        out.append(ref)
    return out


def _strike(args: tuple[Any, ...]) -> dict[str, Any]:
    from ssw.design.hits_check import device_hits_check

    return device_hits_check(*args)


def with_plastic_check(result: DeviceDesignResult, base: Any, materials: dict[str, Any],
                       jobs: int = 1) -> DeviceDesignResult:
    """The result with the plastic check of its :func:`struck` devices (module docstring,
    step 5); unchanged when ``spec.plastic_hits`` is 0.

    Parameters
    ----------
    result : DeviceDesignResult
        A ranked device design (one run's or merged).
    base : ssw.chain.params.ChainParams
        The base device's chain (numerics, interface, preload).
    materials : dict
        The materials library.
    jobs : int
        Processes (one device each).

    Returns
    -------
    DeviceDesignResult
        With ``plastic``: the record of each struck device by its key
        (:func:`ssw.design.hits_check.device_hits_check`); its CPU and wall time added.
    """
    hits = result.spec.plastic_hits
    if hits == 0:
        return result
    t0, c0 = time.perf_counter(), cpu_time()
    chosen = struck(result)
    records = map_jobs(_strike, [(result.spec, base, materials, c, hits) for c in chosen],
                       jobs)
    return replace(result, plastic={**result.plastic, **{
        c.key: r for c, r in zip(chosen, records, strict=True)}},
        wall_time=result.wall_time + time.perf_counter() - t0,
        cpu_time=result.cpu_time + cpu_time() - c0)


def cpu_time() -> float:
    """s, this process's CPU time and its finished children's (user + sys).

    Returns
    -------
    float
        s, ``time.process_time()`` plus the children's user and system time.
    """
    ch = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + ch.ru_utime + ch.ru_stime
