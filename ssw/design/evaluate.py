"""One plate candidate: its sensitivity, resolution, stresses and mass over the soil range.

For a plate (material, thickness, diameter) and striker speed, over the soil moduli ``E_k``
of the design (:attr:`ssw.design.spec.DesignSpec.grid`):

1. TOF: the device's chain with the exact FEM law of that plate as its wall (the ``fem``
   wall, :mod:`ssw.walls.fem`), in one batched run over ``E_k e^-h``, ``E_k``,
   ``E_k e^h`` (``h`` = ``log_step``);
2. sensitivity ``S_k = |ln TOF(E_k e^h) - ln TOF(E_k e^-h)| / (2 h)``, the central
   difference of ``ln TOF`` in ``ln E`` (error ``O(h^2)``: the third derivative of a curve
   that bends slowly; ``tests/test_design_cli.py`` compares it with ``ssw tof``);
3. resolution ``dE/E = u_TOF / (TOF_k S_k)``: the relative change of E that moves the
   mean TOF of one measurement by its standard uncertainty
   (:attr:`ssw.design.spec.DesignSpec.tof_uncertainty`);
4. stresses at the hit's peak: the chain's largest wall indentation ``d_k`` is, in the
   rigid sphere's coordinates of the FEM, ``d_k / s_k`` (the bead's compliance,
   :func:`ssw.chain.wall.compliance_scale`), the force the wall carries there; at that
   force the contact's elastic field under the bead's Hertz-equivalent rigid sphere
   (:func:`ssw.contact.stress.equivalent_radius`: the elastic steel bead's pressure, not a
   rigid one's) gives the plate's and the soil's peak von Mises stresses
   (:func:`ssw.contact.stress.contact_stresses`), and with the plate's yield stress and
   the soil's the yield indices;
5. mass: ``rho pi D^2 t / 4`` against a bead's.

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
        return float(np.max(self.plate_yield_E))

    @property
    def soil_yield_index(self) -> float:
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
        return all(v == 0.0 for v in self.violations.values())

    @property
    def plate_feasible(self) -> bool:
        """The hard limits met (plate elastic, mass): what the Pareto front considers."""
        v = self.violations
        return v["plate_yield_index"] == 0.0 and v["mass_ratio"] == 0.0

    @property
    def key(self) -> tuple[str, float, float, float]:
        return (self.material, self.thickness, self.plate_diameter, self.striker_velocity)

    def to_dict(self) -> dict[str, Any]:
        """The JSON record (the fields of ``ssw design --json``'s ``candidates``)."""
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
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any], limits: dict[str, float]) -> Candidate:
        """A candidate from its JSON record (:meth:`to_dict`)."""
        arr = {k: np.asarray(d[k], float) for k in (
            "soil_E", "tof_E", "sensitivity_E", "resolution_E", "peak_force_E",
            "peak_indentation_E", "plate_von_mises_E", "soil_von_mises_E", "plate_yield_E",
            "soil_yield_E")}
        return cls(material=d["material"], thickness=float(d["thickness"]),
                   plate_diameter=float(d["plate_diameter"]),
                   striker_velocity=float(d["striker_velocity"]), **arr,
                   plate_yield_stress=float(d["plate_yield_stress"]), mass=float(d["mass"]),
                   mass_ratio=float(d["mass_ratio"]), source=d.get("source", "search"),
                   wall_time=float(d.get("wall_time", 0.0)), limits=dict(limits))


def quantize(thickness: float) -> float:
    """The thickness rounded to :data:`ssw.design.spec.THICKNESS_QUANTUM` (m)."""
    return float(np.round(thickness / THICKNESS_QUANTUM) * THICKNESS_QUANTUM)


def candidate_params(params: ChainParams, material: Material, thickness: float,
                     plate_diameter: float, striker_velocity: float) -> ChainParams:
    """The device's chain ``params`` with a candidate's plate (``material``, ``thickness``
    m, ``plate_diameter`` m) and striker speed (m/s)."""
    return params.with_(plate_material=material.key, plate_thickness=float(thickness),
                        plate_E=material.E, plate_nu=material.nu,
                        plate_diameter=float(plate_diameter),
                        striker_velocity=float(striker_velocity))


def plate_yield_stress(material: Material) -> float:
    """The plate material's yield stress (Pa); ConfigError when the library has none."""
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
    """

    def __init__(self, spec: DesignSpec, params: ChainParams, materials: dict[str, Material],
                 contact: dict[str, Any] | None = None, store: Any = None) -> None:
        self.spec, self.params, self.materials = spec, params, materials
        self.contact = {**(contact or {}), "interface": params.plate_interface}
        self.store = store
        self.seen: dict[tuple[str, float, float, float], Candidate] = {}
        self.limits = {"soil_yield_limit": spec.soil_yield_limit,
                       "max_mass_ratio": spec.max_mass_ratio}

    def __call__(self, material: str, thickness: float, plate_diameter: float | None = None,
                 striker_velocity: float | None = None, source: str = "search") -> Candidate:
        D = float(plate_diameter if plate_diameter is not None else self.params.plate_diameter)
        v = float(striker_velocity if striker_velocity is not None
                  else self.params.striker_velocity)
        key = (material, quantize(thickness), D, v)
        if key not in self.seen:
            self.seen[key] = self._evaluate(*key, source)
        return self.seen[key]

    def _evaluate(self, material: str, t: float, D: float, v: float, source: str
                  ) -> Candidate:
        from ssw.tof.api import peaks
        from ssw.walls.fem import peak_stresses

        t0 = time.perf_counter()
        if material not in self.materials:
            raise ConfigError("--materials", material,
                              f"materials of the library: {', '.join(sorted(self.materials))}")
        if t <= 0:
            raise ConfigError("thickness", t, "a plate thickness > 0 m")
        m = self.materials[material]
        Y = plate_yield_stress(m)
        spec = self.spec
        p = candidate_params(self.params, m, t, D, v)
        E = spec.grid
        n = E.size
        h = spec.log_step
        E3 = np.concatenate([E * np.exp(-h), E, E * np.exp(h)])
        pk, run = peaks(E3, spec.soil_nu, p, "fem", contact=self.contact,
                        operators=self.store)
        tof = pk.tof.reshape(3, n)
        sens = np.abs(np.log(tof[2]) - np.log(tof[0])) / (2.0 * h)
        d_chain = run.peak_wall_indentation[n:2 * n]
        st = peak_stresses(p, E, spec.soil_nu, d_chain, contact=self.contact,
                           operators=self.store)
        mass = m.density * np.pi * 0.25 * D * D * t
        return Candidate(
            material=material, thickness=t, plate_diameter=D, striker_velocity=v,
            soil_E=E, tof_E=tof[1], sensitivity_E=sens,
            resolution_E=spec.tof_uncertainty / (tof[1] * sens),
            peak_force_E=st.force, peak_indentation_E=d_chain,
            plate_von_mises_E=st.plate.peak, soil_von_mises_E=st.soil.peak,
            plate_yield_E=st.plate.peak / Y,
            soil_yield_E=st.soil.peak / spec.soil_yield_stress(E),
            plate_yield_stress=Y, mass=float(mass), mass_ratio=float(mass / p.bead_mass),
            source=source, wall_time=time.perf_counter() - t0, limits=self.limits)
