"""The designed plate on a yielding sample: consecutive hits through the plastic FEM.

A design ranks plates by first yield in the elastic field (:mod:`ssw.design.evaluate`:
``soil_yield_index``, the soil's peak von Mises stress at the hit's peak over its strength).
Past first yield that index says nothing of what the yielding does to the measurement. This
check strikes a virgin sample ``hits`` times through a plate (:mod:`ssw.walls.hits`, the
``plastic`` wall: the plastic contact FEM through the elastic plate, history carried from
hit to hit) and reports per hit the TOF, the permanent set and the energy dissipated, and
the TOF's drift over the hits against the device's one-hit scatter.

The sample: von Mises with the design's soil strength, ``Y = Y_soil(E)``
(:meth:`ssw.design.spec.DesignSpec.soil_yield_stress`, the same assumption as the elastic
index), at the soil of the design range where the candidate's elastic soil yield index is
largest (the soil the design's constraint is about). Von Mises is the simplest law that
yields at the design's stated strength; a user with a soil's c and phi runs ``ssw tof
--hits`` with ``--soil-model drucker-prager``.

Cost: one plastic wall per plate (its loading and unloading tables, ~5-25 s on one core).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ssw.chain.params import ChainParams
from ssw.design.evaluate import Candidate, candidate_params
from ssw.design.spec import DesignSpec
from ssw.materials import Material


def hits_check(spec: DesignSpec, params: ChainParams, materials: dict[str, Material],
               candidate: Candidate | dict[str, Any], hits: int = 3) -> dict[str, Any]:
    """``hits`` consecutive hits through ``candidate``'s plate on a virgin von Mises sample
    of the design's strength at its worst soil (module docstring). SI units.

    Returns the plate, the soil (``soil_E``, ``soil_nu``, ``yield_stress``), per hit
    (``tof`` s, ``peak_force`` N, ``permanent_set`` m, ``dissipated`` J), the TOF's
    ``drift`` (s, hit to hit), its standard deviation over the hits (``tof_std``, s) and
    over the hits after the first (``tof_std_seated``), and the elastic index it checks."""
    from ssw.constitutive import VonMises
    from ssw.errors import ConfigError
    from ssw.walls.hits import run_hits
    from ssw.walls.plastic import plastic_wall

    c = candidate.to_dict() if isinstance(candidate, Candidate) else candidate
    if not (isinstance(hits, int) and hits >= 2):
        raise ConfigError("--plastic-hits", hits, "an integer >= 2 (a drift needs two hits)")
    m = materials[c["material"]]
    yield_E = np.asarray(c["soil_yield_E"], float)
    k = int(np.argmax(yield_E))
    E = float(np.asarray(c["soil_E"], float)[k])
    Y = float(spec.soil_yield_stress(np.array([E]))[0])
    p = candidate_params(params, m, c["thickness"], c["plate_diameter"],
                         c["striker_velocity"])
    wall = plastic_wall(p, E, spec.soil_nu, soil_model=VonMises(Y))
    res = run_hits(p, wall, hits)
    tof = res.tof[:, 0]
    return {
        "material": c["material"], "thickness": float(c["thickness"]),
        "plate_diameter": float(c["plate_diameter"]), "source": c.get("source"),
        "soil_E": E, "soil_nu": spec.soil_nu, "soil_model": "von-mises", "yield_stress": Y,
        "elastic_soil_yield_index": float(yield_E[k]),
        "hits": res.rows(), "drift": np.diff(tof).tolist(),
        "tof_std": float(np.std(tof, ddof=1)),
        "tof_std_seated": float(np.std(tof[1:], ddof=1)) if hits > 2 else None,
        "static_set": float(res.static_set[0]),
    }
