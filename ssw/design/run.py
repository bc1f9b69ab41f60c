"""A whole plate design: every material's search, the device's own plate, the ranking.

:func:`run_design` is the API of ``ssw design``: it evaluates the device's own plate (the
reference, when its material is among the design's), searches the thickness of every
material (and plate diameter and striker speed, when given) with
:func:`ssw.design.optimize.search`, optionally in parallel processes (one per search), and
ranks every candidate (:func:`ssw.design.optimize.rank`). :func:`merge_results` ranks the
candidates of several runs together (the workflow runs one job per material).
"""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass
from typing import Any

from ssw.chain.params import ChainParams
from ssw.design.evaluate import Candidate, Evaluator
from ssw.design.optimize import Ranking, Search, merit, rank, search
from ssw.design.spec import DesignSpec
from ssw.errors import ConfigError
from ssw.materials import Material


@dataclass(frozen=True)
class DesignResult:
    """The design's ranking, its searches and what it cost (s).

    Parameters
    ----------
    spec : ssw.design.spec.DesignSpec
        The design problem.
    ranking : ssw.design.optimize.Ranking
        The candidates ranked.
    searches : list of dict of str to Any
        Each thickness search's record (:meth:`ssw.design.optimize.Search.to_dict`).
    wall_time : float
        s, the design's wall time.
    """

    spec: DesignSpec
    ranking: Ranking
    searches: list[dict[str, Any]]
    wall_time: float

    def to_dict(self) -> dict[str, Any]:
        """The JSON of ``ssw design`` (module docstring of :mod:`ssw.cli.design`).

        Returns
        -------
        dict of str to Any
            The statement, spec, soil grid (Pa), recommended candidate and its reasons,
            every candidate with its merit, the Pareto front, the device's own plate, the
            searches, the evaluation count and the wall time (s).
        """
        r = self.ranking
        rec = r.recommended.to_dict()
        return {
            "ssw_kind": "design",
            **self.spec.statement(),
            "spec": self.spec.to_dict(),
            "soil_E": self.spec.grid.tolist(),
            "recommended": {**rec, "merit": merit(r.recommended), "reasons": r.reasons},
            "candidates": [{**c.to_dict(), "merit": merit(c)} for c in r.candidates],
            "pareto": [{"material": c.material, "thickness": c.thickness,
                        "plate_diameter": c.plate_diameter,
                        "striker_velocity": c.striker_velocity,
                        "sensitivity": c.sensitivity,
                        "soil_yield_index": c.soil_yield_index} for c in r.pareto],
            "reference": next(({**c.to_dict(), "merit": merit(c)} for c in r.candidates
                               if c.source == "reference"), None),
            "searches": self.searches,
            "evaluations": len(r.candidates),
            "wall_time": self.wall_time,
        }


def _combos(spec: DesignSpec) -> list[tuple[str, float | None, float | None]]:
    return list(itertools.product(spec.materials, spec.plate_diameters or (None,),
                                  spec.striker_velocities or (None,)))


def _search_task(args: tuple[Any, ...]) -> tuple[Search, list[Candidate]]:
    spec, params, materials, contact, combo, bead_material = args
    ev = Evaluator(spec, params, materials, contact, bead_material=bead_material)
    s = search(ev, *combo)
    return s, list(ev.seen.values())


def run_design(spec: DesignSpec, params: ChainParams, materials: dict[str, Material],
               contact: dict[str, Any] | None = None, *, reference: bool = True,
               jobs: int = 1, store: Any = None, bead_material: str | None = None
               ) -> DesignResult:
    """Search every material (module docstring) and rank the candidates.

    Parameters
    ----------
    spec : ssw.design.spec.DesignSpec
        The design.
    params : ssw.chain.params.ChainParams
        The device's chain (its plate is the reference).
    materials : dict
        The materials library (key -> Material).
    contact : dict or None
        The fem wall's ``contact`` settings.
    reference : bool
        Evaluate the device's own plate when its material is among the design's.
    jobs : int
        Processes (one search each; 1: this process).
    store : ssw.contact.operators.OperatorStore or None
        The contact operators of this process (default: the process's).
    bead_material : str or None
        The beads' material key (the device's): the candidates' bead check.

    Returns
    -------
    DesignResult
        The ranking of every candidate evaluated, the searches and the wall time (s).

    Raises
    ------
    ssw.errors.ConfigError
        When a design material is not in the library.
    """
    t0 = time.perf_counter()
    for key in spec.materials:
        if key not in materials:
            raise ConfigError("--materials", key,
                              f"materials of the library: {', '.join(sorted(materials))}")
    ev = Evaluator(spec, params, materials, contact, store, bead_material=bead_material)
    cands: list[Candidate] = []
    combos = _combos(spec)
    ref: tuple[tuple[str, float, str], ...] = ()
    if reference and params.plate_thickness > 0 and params.plate_material in spec.materials:
        ref = ((params.plate_material, params.plate_thickness, "reference"),)
        if (jobs > 1 and len(combos) > 1) or combos[0][1:] != (None, None):
            # not with the first search's scan (another process, or another plate diameter
            # or striker speed than the device's)
            cands.append(ev(params.plate_material, params.plate_thickness, source="reference"))
            ref = ()
    if jobs > 1 and len(combos) > 1:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(max_workers=min(jobs, len(combos))) as pool:
            out = list(pool.map(_search_task, [(spec, params, materials, contact, c,
                                                bead_material) for c in combos]))
    else:
        # the device's plate is evaluated with the first search's scan (one chain run)
        out = [(search(ev, *c, extra=ref if i == 0 else ()), [])
               for i, c in enumerate(combos)]
        cands = list(ev.seen.values())
    searches = [s.to_dict() for s, _ in out]
    for _, cs in out:
        cands.extend(cs)
    return DesignResult(spec, rank(cands, spec), searches, time.perf_counter() - t0)


def merge_results(results: list[dict[str, Any]]) -> DesignResult:
    """Rank together the candidates of several ``ssw design`` results (JSON dicts) of the
    same design question (soils, limits, device): ConfigError naming the field that
    differs otherwise.

    Parameters
    ----------
    results : list of dict of str to Any
        The JSON of each ``ssw design`` result.

    Returns
    -------
    DesignResult
        Their candidates ranked together; wall time the sum of theirs (s).

    Raises
    ------
    ssw.errors.ConfigError
        When there is no result, or a spec field differs between them.
    """
    if not results:
        raise ConfigError("design results", [], "at least one result of ssw design")
    base = results[0]["spec"]
    same = ("soil_E", "soil_nu", "thickness", "moduli", "log_step", "soil_strength",
            "soil_strength_ratio", "soil_yield_limit", "max_mass_ratio", "hits",
            "tof_scatter", "tof_sampling")
    for r in results[1:]:
        for k in same:
            if r["spec"].get(k) != base.get(k):
                raise ConfigError(f"design spec {k}", (base.get(k), r["spec"].get(k)),
                                  "the same in every result merged")
    fields = {k: (tuple(v) if isinstance(v, list) else v) for k, v in base.items()
              if k != "soil_E_grid"}
    fields["materials"] = tuple(dict.fromkeys(m for r in results for m in r["spec"]["materials"]))
    spec = DesignSpec(**fields)
    limits = {"soil_yield_limit": spec.soil_yield_limit, "max_mass_ratio": spec.max_mass_ratio}
    cands = [Candidate.from_dict(c, limits) for r in results for c in r["candidates"]]
    searches = [s for r in results for s in r.get("searches", [])]
    wall = float(sum(r.get("wall_time", 0.0) for r in results))
    return DesignResult(spec, rank(cands, spec), searches, wall)
