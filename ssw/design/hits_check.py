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

The device design's finalists (:func:`device_hits_check`) are struck the same way, on the
same sample, and through a plate that yields too: von Mises with the plate material's
library yield stress and hardening (:func:`ssw.constitutive.model_of_strength`; the
``plastic`` wall's yielding plate). Per device: the plate's permanent dent on the axis (its
thinning, ``plate_thinning`` (:class:`ssw.walls.hits.Hits`)) and the sample's permanent set
(the plate-sample interface's depth, ``interface_set``) after the last hit, and the TOF's
drift from the first hit to the last, beside the device's one-measurement TOF uncertainty
there. A device the plastic contact cannot strike (a plate without a yield stress, an
interface it does not model, a solve that fails) keeps the reason in its record, not a
silent gap. """

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
    over the hits after the first (``tof_std_seated``), and the elastic index it checks.

    Parameters
    ----------
    spec : ssw.design.spec.DesignSpec
        The design (the soil's Poisson's ratio and yield stress, Pa).
    params : ssw.chain.params.ChainParams
        The device's chain.
    materials : dict of str to ssw.materials.Material
        The materials library.
    candidate : ssw.design.evaluate.Candidate or dict of str to Any
        The plate (or its JSON record); the soil of its largest soil yield index is struck.
    hits : int
        Consecutive hits, at least 2.

    Returns
    -------
    dict of str to Any
        The plate, the soil, the hits' records, the TOF drift (s) and standard deviations
        (s), the elastic soil yield index and the static set (m).

    Raises
    ------
    ssw.errors.ConfigError
        When ``hits`` is no integer >= 2.
    """
    from ssw.errors import ConfigError

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
    res = strike(p, E, spec.soil_nu, Y, hits)
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


def strike(params: ChainParams, soil_E: float, soil_nu: float, yield_stress: float,
           hits: int, plate_model: Any = None) -> Any:
    """``hits`` hits of the chain ``params`` on a virgin von Mises sample.

    Parameters
    ----------
    params : ChainParams
        The device's chain and plate.
    soil_E : float
        Pa, the sample's Young's modulus.
    soil_nu : float
        The sample's Poisson's ratio.
    yield_stress : float
        Pa, the sample's von Mises yield stress (perfectly plastic).
    hits : int
        Hits, >= 1.
    plate_model : model of :mod:`ssw.constitutive` or None
        The plate's law (None: an elastic plate).

    Returns
    -------
    ssw.walls.hits.Hits
        Per hit TOF, forces, sets, dissipated energy and the plate's dent.
    """
    from ssw.constitutive import VonMises
    from ssw.walls.hits import run_hits
    from ssw.walls.plastic import plastic_wall

    wall = plastic_wall(params, soil_E, soil_nu, soil_model=VonMises(yield_stress),
                        plate_model=plate_model)
    return run_hits(params, wall, hits)


def plate_model_of(materials: dict[str, Material], key: str) -> Any:
    """The yielding plate of a material.

    Parameters
    ----------
    materials : dict
        The materials library.
    key : str
        The plate material's key.

    Returns
    -------
    ssw.constitutive.VonMises
        Von Mises with the library's yield stress and hardening
        (:func:`ssw.constitutive.model_of_strength`).

    Raises
    ------
    ConfigError
        Naming ``materials.<key>.strength`` when the library gives no strength.
    """
    from ssw.constitutive import model_of_strength
    from ssw.errors import ConfigError

    strength = materials[key].strength
    if strength is None:
        raise ConfigError(f"materials.{key}.strength", None,
                          "a yield_stress (the plate's von Mises model)")
    return model_of_strength("von-mises", strength, f"materials.{key}", field="plate_model")


def device_hits_check(spec: Any, base: ChainParams, materials: dict[str, Material],
                      candidate: Any, hits: int) -> dict[str, Any]:
    """``hits`` hits of a device of the device design on a virgin von Mises sample, through
    its plate yielding as von Mises (module docstring).

    Parameters
    ----------
    spec : ssw.design.device_spec.DeviceSpec
        The design's question (the soil's strength and Poisson's ratio).
    base : ChainParams
        The base device's chain (numerics, interface, preload).
    materials : dict
        The materials library.
    candidate : ssw.design.device_eval.DeviceCandidate
        The device, evaluated over the soil range.
    hits : int
        Hits, >= 2 (a drift needs two).

    Returns
    -------
    dict
        ``soil_E`` (Pa, the soil of the largest elastic soil yield index), ``soil_nu``,
        ``soil_yield_stress`` (Pa), ``plate_model`` (its parameters), the elastic indices
        there, per hit ``rows`` (:meth:`ssw.walls.hits.Hits.rows`), ``plate_dent`` and
        ``soil_set`` (m, after the last hit), ``tof_drift`` (s, last hit's TOF less the
        first's), ``drift_over_u_tof`` (its size over the device's TOF uncertainty there),
        and ``error`` (None, or why the device could not be struck).

    Raises
    ------
    ConfigError
        For ``hits`` < 2.
    """
    from ssw.errors import ConfigError, SswError

    if not (isinstance(hits, int | np.integer) and hits >= 2):
        raise ConfigError("design.device.plastic_hits", hits,
                          "an integer >= 2 (a drift needs two hits; 0: no check)")
    k = int(np.argmax(candidate.soil_yield_E))
    E = float(candidate.soil_E[k])
    Y = float(spec.soil_yield_stress(np.array([E]))[0])
    out: dict[str, Any] = {
        "hits": int(hits), "soil_E": E, "soil_nu": spec.soil_nu, "soil_model": "von-mises",
        "soil_yield_stress": Y, "plate_model": None,
        "elastic_soil_yield_index": float(candidate.soil_yield_E[k]),
        "elastic_plate_yield_index": float(candidate.plate_yield_E[k]),
        "rows": [], "plate_dent": None, "soil_set": None, "tof_drift": None,
        "drift_over_u_tof": None, "error": None}
    try:
        plate = plate_model_of(materials, candidate.point.plate_material)
        out["plate_model"] = plate.params()
        res = strike(candidate.point.params(base, materials), E, spec.soil_nu, Y, hits,
                     plate)
    except SswError as exc:  # the reason kept in the record (module docstring)
        out["error"] = f"{type(exc).__name__}: {exc}"
        return out
    tof = res.tof[:, 0]
    drift = float(tof[-1] - tof[0])
    out.update({"rows": res.rows(), "plate_dent": float(res.plate_thinning[-1, 0]),
                "soil_set": float(res.interface_set[-1, 0]),
                "permanent_set": float(res.permanent_set[-1, 0]), "tof_drift": drift,
                "drift_over_u_tof": abs(drift) / float(candidate.u_tof_E[k]),
                "beyond_exact_reach": bool(res.wall.d_max0[0] > res.wall.exact_reach[0])})
    return out
