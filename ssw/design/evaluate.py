"""One plate candidate: its sensitivity, resolution, stresses and mass over the soil range.

For a plate (material, thickness, diameter) and striker speed, over the soil moduli ``E_k``
of the design (:attr:`ssw.design.spec.DesignSpec.grid`):

1. TOF: the device's chain with the exact FEM law of that plate as its wall (the ``fem``
   wall, :mod:`ssw.walls.fem`), in one batched run over the ``E_k`` carrying the forward
   sensitivity ``dTOF/dE`` (the chain's forward sensitivity, :func:`ssw.chain.run.run_peaks`;
   several candidates evaluated together, :meth:`Evaluator.many`, share that run, each
   scene's numbers being those of its own run; with the unilateral interface, whose law has
   no E tangent, :func:`ssw.tof.api.tof_derivatives`' central differences of TOFs at the
   same step);
2. sensitivity ``S_k = |d ln TOF / d ln E| = |E_k dTOF/dE / TOF_k|``, exact for the
   discrete TOF at the run's fixed step (no difference quotient, hence no quotient of two
   TOFs' rounding: the curve is smooth in E; ``tests/test_design_cli.py`` compares it with
   central differences of ``ssw tof``'s TOFs);
3. resolution ``dE/E = u_TOF / (TOF_k S_k)``: the relative change of E that moves the
   mean TOF of one measurement by its standard uncertainty
   (:attr:`ssw.design.spec.DesignSpec.tof_uncertainty`);
4. stresses at the hit's peak: the chain's largest wall indentation ``d_k`` is, in the
   rigid sphere's coordinates of the FEM, ``d_k / s_k`` (the bead's compliance,
   :func:`ssw.chain.wall_base.compliance_scale`), the force the wall carries there; at that
   force the contact's elastic field under the bead's Hertz-equivalent rigid sphere
   (:func:`ssw.contact.stress.equivalent_radius`: the elastic steel bead's pressure, not a
   rigid one's) gives the plate's and the soil's peak von Mises stresses
   (:func:`ssw.contact.stress.contact_stresses`, from the wall's force at ``d_k``: the
   rigid sphere's path is not traced again), and with the plate's yield stress and the
   soil's the yield indices;
5. mass: ``rho pi D^2 t / 4`` against a bead's;
6. the checks of its assumptions over the soils (:mod:`ssw.validity`, from what 1-4
   computed: the contact's and the plate's small strain at ``d_k``, the wall law's reach,
   the pulses' separation at the sensor, the beads', the plate's and the soil's yield, the
   soil's at the design's strength or its stated assumption): ``checks_E``, and in its
   record the worst over the soils (``validity``, ``checks_failed``).

The indices of the candidate are the worst over the soils: the smallest sensitivity, the
coarsest resolution, the largest yield indices.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ssw.chain.params import ChainParams
from ssw.design.spec import THICKNESS_QUANTUM, DesignSpec
from ssw.errors import ConfigError
from ssw.materials import Material


@dataclass(frozen=True)
class Candidate:
    """One plate evaluated over the soil range (module docstring). SI units; arrays (n,)
    over ``soil_E``.

    ``source``: how it was chosen (``reference``: the device's own plate; ``scan``; ``search``).

    Parameters
    ----------
    material : str
        The plate's material key.
    thickness : float
        m, the plate's thickness.
    plate_diameter : float
        m, the plate's diameter.
    striker_velocity : float
        m/s, the striker's speed.
    soil_E : numpy.ndarray
        (n,) Pa, the soil moduli.
    tof_E : numpy.ndarray
        (n,) s, the TOF.
    sensitivity_E : numpy.ndarray
        (n,) ``S = |E dTOF/dE / TOF|`` (-).
    resolution_E : numpy.ndarray
        (n,) ``dE/E = u_TOF / (TOF S)`` (-).
    peak_force_E : numpy.ndarray
        (n,) N, the wall's force at the largest indentation.
    peak_indentation_E : numpy.ndarray
        (n,) m, the chain's largest wall indentation.
    plate_von_mises_E : numpy.ndarray
        (n,) Pa, the plate's peak von Mises stress.
    soil_von_mises_E : numpy.ndarray
        (n,) Pa, the soil's peak von Mises stress.
    plate_yield_E : numpy.ndarray
        (n,) the plate's peak von Mises stress over its yield stress (-).
    soil_yield_E : numpy.ndarray
        (n,) the soil's peak von Mises stress over its yield stress (-).
    plate_yield_stress : float
        Pa, the plate material's yield stress.
    mass : float
        kg, the plate's mass ``rho pi D^2 t / 4``.
    mass_ratio : float
        The plate's mass over a bead's (-).
    source : str
        How it was chosen: ``reference``, ``scan`` or ``search``.
    wall_time : float
        s, its share of the evaluation's wall time.
    limits : dict of str to float
        ``soil_yield_limit`` and ``max_mass_ratio`` (-; 1 if absent).
    checks_E : dict of str to numpy.ndarray
        (n,) each validity check's ratio over the soils.
    checks_assumed : dict of str to str
        The assumption behind a check, by check name.
    """

    material: str
    thickness: float
    plate_diameter: float
    striker_velocity: float
    soil_E: np.ndarray
    tof_E: np.ndarray
    sensitivity_E: np.ndarray
    resolution_E: np.ndarray
    peak_force_E: np.ndarray
    peak_indentation_E: np.ndarray
    plate_von_mises_E: np.ndarray
    soil_von_mises_E: np.ndarray
    plate_yield_E: np.ndarray
    soil_yield_E: np.ndarray
    plate_yield_stress: float
    mass: float
    mass_ratio: float
    source: str = "search"
    wall_time: float = 0.0
    limits: dict[str, float] = field(default_factory=dict, compare=False)
    checks_E: dict[str, np.ndarray] = field(default_factory=dict, compare=False)
    checks_assumed: dict[str, str] = field(default_factory=dict, compare=False)

    def validity(self) -> Any:
        """The checks over the soils (:class:`ssw.validity.Validity`, one scene per E).

        Returns
        -------
        ssw.validity.Validity
            The checks ``checks_E`` and their assumptions ``checks_assumed``.
        """
        from ssw.validity import Validity

        return Validity(dict(self.checks_E), dict(self.checks_assumed))

    # ------------------------------------------------------------------ indices
    @property
    def sensitivity(self) -> float:
        """The worst (smallest) sensitivity over the soils."""
        return float(np.min(self.sensitivity_E))

    @property
    def resolution(self) -> float:
        """The worst (coarsest) relative resolution dE/E over the soils."""
        return float(np.max(self.resolution_E))

    @property
    def plate_yield_index(self) -> float:
        """The plate's largest peak von Mises stress over its yield stress (-)."""
        return float(np.max(self.plate_yield_E))

    @property
    def soil_yield_index(self) -> float:
        """The soil's largest peak von Mises stress over its yield stress (-)."""
        return float(np.max(self.soil_yield_E))

    @property
    def soil_peak_strain(self) -> float:
        """max over E of the soil's peak von Mises stress over E (free of any strength)."""
        return float(np.max(self.soil_von_mises_E / self.soil_E))

    @property
    def violations(self) -> dict[str, float]:
        """Relative excess of each index over its limit (0: met)."""
        lim = self.limits
        return {
            "plate_yield_index": max(0.0, self.plate_yield_index - 1.0),
            "soil_yield_index": max(0.0, self.soil_yield_index
                                    / lim.get("soil_yield_limit", 1.0) - 1.0),
            "mass_ratio": max(0.0, self.mass_ratio / lim.get("max_mass_ratio", 1.0) - 1.0),
        }

    @property
    def feasible(self) -> bool:
        """Every limit met (plate elastic, soil yield index, mass ratio)."""
        return all(v == 0.0 for v in self.violations.values())

    @property
    def plate_feasible(self) -> bool:
        """The hard limits met (plate elastic, mass): what the Pareto front considers."""
        v = self.violations
        return v["plate_yield_index"] == 0.0 and v["mass_ratio"] == 0.0

    @property
    def key(self) -> tuple[str, float, float, float]:
        """Material, thickness (m), plate diameter (m) and striker speed (m/s)."""
        return (self.material, self.thickness, self.plate_diameter, self.striker_velocity)

    def to_dict(self) -> dict[str, Any]:
        """The JSON record (the fields of ``ssw design --json``'s ``candidates``).

        Returns
        -------
        dict of str to Any
            The fields, indices, feasibility, violations, per-soil arrays and checks (SI
            units).
        """
        return {
            "material": self.material, "thickness": self.thickness,
            "plate_diameter": self.plate_diameter, "striker_velocity": self.striker_velocity,
            "source": self.source,
            "sensitivity": self.sensitivity, "resolution": self.resolution,
            "plate_yield_index": self.plate_yield_index,
            "soil_yield_index": self.soil_yield_index,
            "soil_peak_strain": self.soil_peak_strain,
            "mass": self.mass, "mass_ratio": self.mass_ratio,
            "feasible": self.feasible, "violations": self.violations,
            "plate_yield_stress": self.plate_yield_stress,
            "soil_E": self.soil_E.tolist(),
            "sensitivity_E": self.sensitivity_E.tolist(),
            "resolution_E": self.resolution_E.tolist(),
            "tof_E": self.tof_E.tolist(),
            "peak_force_E": self.peak_force_E.tolist(),
            "peak_indentation_E": self.peak_indentation_E.tolist(),
            "plate_von_mises_E": self.plate_von_mises_E.tolist(),
            "soil_von_mises_E": self.soil_von_mises_E.tolist(),
            "plate_yield_E": self.plate_yield_E.tolist(),
            "soil_yield_E": self.soil_yield_E.tolist(),
            "wall_time": self.wall_time,
            **self._checks_record(),
        }

    def _checks_record(self) -> dict[str, Any]:
        """The record's checks: the worst over the soils (``validity``, ``checks_failed``),
        every soil's values (``checks_E``) and what they assumed (``checks_assumed``)."""
        if not self.checks_E:
            return {}
        worst = self.validity().worst()
        return {"validity": worst.entries(0), "checks_failed": worst.failed(0),
                "checks_E": {k: v.tolist() for k, v in self.checks_E.items()},
                "checks_assumed": dict(self.checks_assumed)}

    @classmethod
    def from_dict(cls, d: dict[str, Any], limits: dict[str, float]) -> Candidate:
        """A candidate from its JSON record (:meth:`to_dict`).

        Parameters
        ----------
        d : dict of str to Any
            The record (SI units).
        limits : dict of str to float
            ``soil_yield_limit`` and ``max_mass_ratio`` (-).

        Returns
        -------
        Candidate
            The candidate.
        """
        arr = {k: np.asarray(d[k], float) for k in (
            "soil_E", "tof_E", "sensitivity_E", "resolution_E", "peak_force_E",
            "peak_indentation_E", "plate_von_mises_E", "soil_von_mises_E", "plate_yield_E",
            "soil_yield_E")}
        return cls(material=d["material"], thickness=float(d["thickness"]),
                   plate_diameter=float(d["plate_diameter"]),
                   striker_velocity=float(d["striker_velocity"]), **arr,
                   plate_yield_stress=float(d["plate_yield_stress"]), mass=float(d["mass"]),
                   mass_ratio=float(d["mass_ratio"]), source=d.get("source", "search"),
                   wall_time=float(d.get("wall_time", 0.0)), limits=dict(limits),
                   checks_E={k: np.asarray(v, float) for k, v in
                             d.get("checks_E", {}).items()},
                   checks_assumed=dict(d.get("checks_assumed", {})))


def quantize(thickness: float) -> float:
    """The thickness rounded to :data:`ssw.design.spec.THICKNESS_QUANTUM` (m).

    Parameters
    ----------
    thickness : float
        m.

    Returns
    -------
    float
        m, the nearest multiple of the quantum.
    """
    return float(np.round(thickness / THICKNESS_QUANTUM) * THICKNESS_QUANTUM)


def candidate_params(params: ChainParams, material: Material, thickness: float,
                     plate_diameter: float, striker_velocity: float) -> ChainParams:
    """The device's chain ``params`` with a candidate's plate (``material``, ``thickness``
    m, ``plate_diameter`` m) and striker speed (m/s).

    Parameters
    ----------
    params : ssw.chain.params.ChainParams
        The device's chain.
    material : ssw.materials.Material
        The plate's material (E, Pa; nu, -).
    thickness : float
        m, the plate's thickness.
    plate_diameter : float
        m, the plate's diameter.
    striker_velocity : float
        m/s, the striker's speed.

    Returns
    -------
    ssw.chain.params.ChainParams
        The chain with that plate and striker speed.
    """
    return params.with_(plate_material=material.key, plate_thickness=float(thickness),
                        plate_E=material.E, plate_nu=material.nu,
                        plate_diameter=float(plate_diameter),
                        striker_velocity=float(striker_velocity))


def plate_yield_stress(material: Material) -> float:
    """The plate material's yield stress (Pa); ConfigError when the library has none.

    Parameters
    ----------
    material : ssw.materials.Material
        The plate's material.

    Returns
    -------
    float
        Pa, its yield stress.

    Raises
    ------
    ssw.errors.ConfigError
        When the library states no yield stress for it.
    """
    y = material.strength.yield_stress
    if y is None:
        raise ConfigError(f"materials.{material.key}.strength.yield_stress", None,
                          "a yield stress (Pa) with its source: a plate is designed against it")
    return float(y)


class Evaluator:
    """Evaluates candidates of one design (remembering each: a search revisits none).

    Parameters
    ----------
    spec : ssw.design.spec.DesignSpec
        The design.
    params : ssw.chain.params.ChainParams
        The device's chain (its plate is replaced per candidate).
    materials : dict
        The materials library (key -> Material).
    contact : dict or None
        The ``contact`` settings of the fem wall (mesh, zone).
    store : ssw.contact.operators.OperatorStore or None
        The contact operators (default: the process's, disk-cached).
    bead_material : str or None
        The beads' material key (the device's): its strength for the beads' check.
    """

    def __init__(self, spec: DesignSpec, params: ChainParams, materials: dict[str, Material],
                 contact: dict[str, Any] | None = None, store: Any = None,
                 bead_material: str | None = None) -> None:
        self.spec, self.params, self.materials = spec, params, materials
        self.bead_material = bead_material
        self.contact = {**(contact or {}), "interface": params.plate_interface}
        self.store = store
        self.seen: dict[tuple[str, float, float, float], Candidate] = {}
        self.limits = {"soil_yield_limit": spec.soil_yield_limit,
                       "max_mass_ratio": spec.max_mass_ratio}

    def __call__(self, material: str, thickness: float, plate_diameter: float | None = None,
                 striker_velocity: float | None = None, source: str = "search") -> Candidate:
        return self.many([(material, thickness)], plate_diameter, striker_velocity,
                         [source])[0]

    def many(self, plates: list[tuple[str, float]], plate_diameter: float | None = None,
             striker_velocity: float | None = None, sources: list[str] | None = None
             ) -> list[Candidate]:
        """Evaluate several plates at once: the chains of those not seen yet advance in one
        batched run (every scene's TOF and its tangent are those of its own run: the
        integrator's scenes are independent and share the chain's step).

        Parameters
        ----------
        plates : list of tuple
            ``(material, thickness)`` pairs (key, m).
        plate_diameter : float or None
            m (default: the device's).
        striker_velocity : float or None
            m/s (default: the device's).
        sources : list of str or None
            How each was chosen (``Candidate.source``; default ``search``).

        Returns
        -------
        list of Candidate
            One per plate, in order.
        """
        D = float(plate_diameter if plate_diameter is not None else self.params.plate_diameter)
        v = float(striker_velocity if striker_velocity is not None
                  else self.params.striker_velocity)
        sources = list(sources) if sources is not None else ["search"] * len(plates)
        keys = [(m, quantize(t), D, v) for m, t in plates]
        todo: dict[tuple[str, float, float, float], str] = {}
        for key, src in zip(keys, sources, strict=True):
            if key not in self.seen and (key not in todo or src == "reference"):
                todo[key] = src  # the same plate twice: the device's own keeps its label
        if todo:
            for c in self._evaluate(list(todo), list(todo.values())):
                self.seen[c.key] = c
        return [self.seen[k] for k in keys]

    def _evaluate(self, keys: list[tuple[str, float, float, float]], sources: list[str]
                  ) -> list[Candidate]:
        """The candidates ``keys`` ((material, thickness, diameter, speed)): one fem wall
        each, their chains in one run (grouped by time step), then each one's stresses."""
        from ssw.contact.operators import keeping_factors
        from ssw.walls.fem import fem_wall

        t0 = time.perf_counter()
        spec = self.spec
        E = spec.grid
        nu = np.full(E.size, float(spec.soil_nu))
        ps = []
        for material, t, D, v in keys:
            if material not in self.materials:
                raise ConfigError("--materials", material,
                                  f"materials of the library: {', '.join(sorted(self.materials))}")
            if t <= 0:
                raise ConfigError("thickness", t, "a plate thickness > 0 m")
            plate_yield_stress(self.materials[material])  # designed against it: known first
            ps.append(candidate_params(self.params, self.materials[material], t, D, v))
        with keeping_factors(2 * len(ps)):  # the stresses below reuse the bodies' LU
            walls = [fem_wall(p, E, nu, contact=self.contact, operators=self.store,
                              with_dE=True) for p in ps]
            return self._finish(keys, sources, ps, walls, t0)

    def _finish(self, keys: list[tuple[str, float, float, float]], sources: list[str],
                ps: list[ChainParams], walls: list[Any], t0: float) -> list[Candidate]:
        """The chains of the candidates' walls in one run per time step, then each one's
        stresses (:meth:`_candidate`)."""
        from ssw.chain.integrate import time_step
        from ssw.chain.run import run_peaks
        from ssw.tof.api import forward_ok, tof_derivatives
        from ssw.validity import pulse_overlap
        from ssw.walls.fem import concatenate

        spec = self.spec
        E = spec.grid
        n = len(keys)
        tof: list[np.ndarray] = [np.empty(0)] * n
        dtof: list[np.ndarray] = [np.empty(0)] * n
        d_chain: list[np.ndarray] = [np.empty(0)] * n
        pulses: list[tuple[np.ndarray, np.ndarray]] = [(np.empty(0), np.empty(0))] * n
        if all(forward_ok(w, ("E",))["E"] for w in walls):
            # one run per time step (the step depends on the chain alone unless a wall is
            # stiffer than a rigid flat): the same step, hence the same TOF, as alone
            groups: dict[float, list[int]] = {}
            for i, (p, w) in enumerate(zip(ps, walls, strict=True)):
                groups.setdefault(time_step(p, w), []).append(i)
            for dt, idx in groups.items():
                pk, run = run_peaks(ps[idx[0]], concatenate([walls[i] for i in idx]), dt=dt,
                                    derivatives=("E",))
                overlap = pulse_overlap(run, pk)
                for j, i in enumerate(idx):
                    sl = slice(j * E.size, (j + 1) * E.size)
                    tof[i], dtof[i] = pk.tof[sl], pk.dtof[sl, 0]
                    d_chain[i] = run.peak_wall_indentation[sl]
                    pulses[i] = (overlap[sl], run.peak_contact_force[sl])
        else:  # a law without dF/dE (the unilateral interface): central differences
            for i, p in enumerate(ps):
                res = tof_derivatives(E, spec.soil_nu, p, "fem", derivatives=("E",),
                                      contact=self.contact, operators=self.store)
                tof[i], dtof[i] = np.asarray(res.tof, float), res.dtof["E"]
                d_chain[i] = res.run.peak_wall_indentation
                pulses[i] = (pulse_overlap(res.run, res.peaks), res.run.peak_contact_force)
        share = (time.perf_counter() - t0) / n
        return [self._candidate(*key, src, ps[i], walls[i], tof[i], dtof[i], d_chain[i], share,
                                pulses[i])
                for i, (key, src) in enumerate(zip(keys, sources, strict=True))]

    def _candidate(self, material: str, t: float, D: float, v: float, source: str,
                   p: ChainParams, wall: Any, tof: np.ndarray, dtof: np.ndarray,
                   d_chain: np.ndarray, shared: float,
                   pulses: tuple[np.ndarray, np.ndarray] | None = None) -> Candidate:
        """A candidate from its chain's TOF, ``dTOF/dE`` and peak wall indentation: its
        stresses at the wall's force there (the path of the rigid sphere not traced again);
        ``shared`` (s) its share of the batch's time; ``pulses`` the run's pulse overlap
        and largest bead-bead force per soil (:meth:`_checks`)."""
        from ssw.walls.fem import peak_stresses

        t0 = time.perf_counter()
        spec = self.spec
        E = spec.grid
        m = self.materials[material]
        Y = plate_yield_stress(m)
        sens = np.abs(E * dtof / tof)
        st = peak_stresses(p, E, spec.soil_nu, d_chain, contact=self.contact,
                           operators=self.store, force=wall.force(d_chain))
        mass = m.density * np.pi * 0.25 * D * D * t
        plate_yield, soil_yield = st.plate.peak / Y, st.soil.peak / spec.soil_yield_stress(E)
        checks, assumed = self._checks(p, wall, d_chain, pulses, plate_yield, soil_yield)
        return Candidate(
            material=material, thickness=t, plate_diameter=D, striker_velocity=v,
            soil_E=E, tof_E=tof, sensitivity_E=sens,
            resolution_E=spec.tof_uncertainty / (tof * sens),
            peak_force_E=st.force, peak_indentation_E=d_chain,
            plate_von_mises_E=st.plate.peak, soil_von_mises_E=st.soil.peak,
            plate_yield_E=plate_yield, soil_yield_E=soil_yield,
            plate_yield_stress=Y, mass=float(mass), mass_ratio=float(mass / p.bead_mass),
            source=source, wall_time=shared + time.perf_counter() - t0, limits=self.limits,
            checks_E=checks, checks_assumed=assumed)

    def _checks(self, p: ChainParams, wall: Any, d: np.ndarray,
                pulses: tuple[np.ndarray, np.ndarray] | None, plate_yield: np.ndarray,
                soil_yield: np.ndarray) -> tuple[dict[str, np.ndarray], dict[str, str]]:
        """The candidate's checks per soil (:mod:`ssw.validity`) from what its evaluation
        computed, and the assumption its soil's yield rests on."""
        from ssw.validity import (
            contact_radius_ratio,
            first_yield_index,
            plate_deflection_ratio,
            reach_ratio,
        )

        vals = {"contact_strain": contact_radius_ratio(d, p.bead_radius),
                "plate_deflection": plate_deflection_ratio(d, p.plate_thickness)}
        reach = reach_ratio(wall, d)
        if reach is not None:
            vals["wall_reach"] = reach
        bead = self.materials.get(self.bead_material) if self.bead_material else None
        bead_st = getattr(bead, "strength", None)
        bead_y = None if bead_st is None else (bead_st.yield_stress or bead_st.compressive)
        if pulses is not None:
            vals["pulse_separation"] = pulses[0]
            if bead_y is not None:
                vals["bead_yield"] = first_yield_index(pulses[1], p.bead_E, p.bead_nu,
                                                       p.bead_radius, bead_y)
        vals["sample_yield"], vals["plate_yield"] = soil_yield, plate_yield
        spec = self.spec
        assumed = {} if spec.soil_strength is not None else {
            "sample_yield": f"Y_soil = {spec.soil_strength_ratio:g} E (ssw design's stated "
                            "assumption: --soil-strength states one)"}
        return {k: np.asarray(v, float) for k, v in vals.items()}, assumed
