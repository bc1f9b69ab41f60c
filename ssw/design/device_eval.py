"""Devices evaluated over the soil range: resolution, pulses, yield, mass and length.

For each device of a list (:class:`ssw.design.space.DevicePoint` with its
:class:`ssw.chain.params.ChainParams`) and the soil moduli ``E_k`` of the design
(:attr:`ssw.design.device_spec.DeviceSpec.grid`):

1. the chain on the exact FEM law of the device's bead on its plate (the ``fem`` wall,
   :mod:`ssw.walls.fem`, on a mesh scaled with the bead: every length of the study's
   ``contact:`` settings times the bead radius over the base device's, so that a device
   scaled in every length has the same mesh in its own units), the devices of one chain
   (bead material, diameter, count, sensor index) in one batched run: their strikers,
   sensors and plates differ from scene to scene (:class:`ssw.chain.params.Batch`, the
   plates' walls side by side, :func:`ssw.walls.fem.concatenate`). The run's step is its
   shortest scene's (:func:`ssw.chain.integrate.time_step`): with ``own_step`` the devices
   are grouped by striker so that each runs at its own step, the TOF ``ssw tof`` gives;
2. ``TOF_k`` and ``S_k = |E dTOF/dE| / TOF`` from the exact forward sensitivity of the
   dense TOF (:func:`ssw.chain.run.run_peaks`);
3. the DAQ's reading (:mod:`ssw.design.sampling`): the sampled peaks' bias and spread over
   the clock phase, the noise's TOF scatter, the pulses' width in samples; with one hit's
   stated scatter, ``u_TOF`` and the resolution ``dE/E = u_TOF / (TOF S)``
   (:mod:`ssw.design.device_spec`);
4. the pulses at the sensor, on the record of the dense output's steps: the valley between
   the incident and the reflected peak over the peak rule's gap share
   (:data:`ssw.signal.rule.RULE`) of the smaller peak (``overlap_index``; > 1: the pulses
   merge, the window between them is not a TOF window); the rule's noise floor over the
   reflected peak (``detection_index``); the largest reading over the full scale
   (``range_index``);
5. stresses at the hit's peak (:func:`ssw.walls.fem.peak_stresses`: the plate's and the
   soil's peak von Mises stress under the elastic bead) and the yield indices; the beads'
   index at the largest bead contact force the run shows (the striker's impact,
   :func:`ssw.chain.integrate.impact_scales`, the sensor's reading, or the wall's force
   next to the last bead-bead contact), Hertz's peak pressure of two beads
   (:func:`ssw.constitutive.yield_index.hertz_peak_pressure`) over their first-yield
   pressure ``k(nu) Y`` (Johnson 1985, sec. 6.1; ``Y`` the library's yield stress, or its
   compressive strength for a brittle bead);
6. mass (the beads, sensor, striker and plate) and length (the bead column, the drop and
   the plate).

The indices of a device are its worst over the soils.
"""

from __future__ import annotations

import time
from dataclasses import astuple, dataclass, field, fields
from typing import Any

import numpy as np

from ssw.design.device_spec import DeviceSpec
from ssw.design.space import DevicePoint
from ssw.errors import ConfigError

#: The ``contact:`` settings that are lengths (m): scaled with the bead radius.
CONTACT_LENGTHS = ("delta_max", "soil_radius", "soil_depth", "mesh_size_contact",
                   "mesh_size_max", "delta_reach")
#: Per-soil arrays of a candidate (SI units), in its JSON record.
ARRAYS = ("soil_E", "tof_E", "dtof_dE_E", "sensitivity_E", "u_tof_E", "resolution_E",
          "noise_E", "bias_E", "spread_E", "samples_per_pulse_E", "overlap_E", "detection_E",
          "round_trip_E", "sensor_peak_E", "wall_force_E", "plate_von_mises_E", "soil_von_mises_E",
          "plate_yield_E", "soil_yield_E")
#: Limited indices: hard (a device that breaks one is not built) and soft.
HARD = ("overlap_index", "round_trip_index", "detection_index", "range_index",
        "bead_yield_index", "plate_yield_index", "plate_mass_ratio", "mass", "length")
SOFT = ("soil_yield_index",)


def scaled_contact(contact: dict[str, Any], factor: float) -> dict[str, Any]:
    """The ``contact:`` settings with every length times ``factor`` (the mesh of a bead
    ``factor`` times the base device's).

    Parameters
    ----------
    contact : dict of str to Any
        The ``contact:`` settings (lengths in m).
    factor : float
        The scale of every length (-): the bead radius over the base device's.

    Returns
    -------
    dict of str to Any
        The settings, the :data:`CONTACT_LENGTHS` (m) scaled, the others as given.
    """
    return {k: (float(v) * factor if k in CONTACT_LENGTHS and v is not None else v)
            for k, v in contact.items()}


@dataclass(frozen=True)
class DeviceCandidate:
    """One device evaluated over the soil range (module docstring). SI units; the arrays
    (n,) over ``soil_E``.

    ``source``: how it was chosen (``reference``: the base device; ``scan``; ``search``);
    ``step``: ``own`` (its own time step: the TOF of ``ssw tof``) or ``shared`` (the
    shortest of its chain's batch).

    Parameters
    ----------
    point : ssw.design.space.DevicePoint
        The device.
    soil_E : numpy.ndarray
        (n,) Pa, the soil moduli.
    tof_E : numpy.ndarray
        (n,) s, the dense TOF.
    dtof_dE_E : numpy.ndarray
        (n,) s/Pa, its exact forward sensitivity ``dTOF/dE``.
    sensitivity_E : numpy.ndarray
        (n,) ``S = |E dTOF/dE| / TOF`` (-).
    u_tof_E : numpy.ndarray
        (n,) s, the mean TOF's standard uncertainty of one measurement:
        ``u^2 = scatter^2 / hits + (noise^2 + spread^2) / hits + bias^2``.
    resolution_E : numpy.ndarray
        (n,) the relative resolution ``dE/E = u_TOF / (TOF S)`` (-; inf: no TOF).
    noise_E : numpy.ndarray
        (n,) s, one hit's TOF standard deviation from the DAQ's white noise.
    bias_E : numpy.ndarray
        (n,) s, the sampled TOF's mean error over the clock phases.
    spread_E : numpy.ndarray
        (n,) s, its standard deviation over the phases.
    samples_per_pulse_E : numpy.ndarray
        (n,) the narrower pulse's width at half height, in samples.
    overlap_E : numpy.ndarray
        (n,) the valley between the pulses over the peak rule's gap share of the smaller
        (-; > 1: the pulses merge).
    detection_E : numpy.ndarray
        (n,) the peak rule's noise floor over the reflected peak (-).
    round_trip_E : numpy.ndarray
        (n,) the shortest physical round trip sensor -> wall -> sensor over the TOF (-).
    sensor_peak_E : numpy.ndarray
        (n,) N, the sensor's largest reading.
    wall_force_E : numpy.ndarray
        (n,) N, the wall's force at the peak indentation.
    plate_von_mises_E : numpy.ndarray
        (n,) Pa, the plate's peak von Mises stress.
    soil_von_mises_E : numpy.ndarray
        (n,) Pa, the soil's peak von Mises stress (elastic field).
    plate_yield_E : numpy.ndarray
        (n,) the plate's peak von Mises stress over its yield stress (-).
    soil_yield_E : numpy.ndarray
        (n,) the soil's peak von Mises stress over its yield stress (-).
    bead_force : float
        N, the largest bead contact force of the device's batched run.
    bead_yield_index : float
        Hertz peak pressure of two beads at ``bead_force`` over their first-yield pressure
        ``k(nu) Y`` (-; Johnson 1985, sec. 6.1).
    range_index : float
        The sensor's largest reading over the full scale (-).
    mass : float
        kg, beads, sensor, striker and plate.
    length : float
        m, bead column, drop height and plate thickness.
    plate_mass_ratio : float
        The plate's mass over a bead's (-).
    source : str
        How it was chosen: ``reference``, ``scan`` or ``search``.
    step : str
        ``own`` or ``shared`` time step.
    wall_time : float
        s, its share of the evaluation's wall time.
    limits : dict of str to float
        Each index's limit (:attr:`ssw.design.device_spec.DeviceSpec.limits`; 1 if absent).
    checks_E : dict of str to numpy.ndarray
        (n,) each validity check's ratio over the soils.
    checks_assumed : dict of str to str
        The assumption behind a check, by check name.
    stresses_skipped : str
        Empty when the plate's and soil's stresses were computed; else why not (the hard
        limits known without them that the device breaks, :func:`evaluate`): its stress
        arrays NaN, its yield indices and their violations NaN (not computed).
    """

    point: DevicePoint
    soil_E: np.ndarray
    tof_E: np.ndarray
    dtof_dE_E: np.ndarray
    sensitivity_E: np.ndarray
    u_tof_E: np.ndarray
    resolution_E: np.ndarray
    noise_E: np.ndarray
    bias_E: np.ndarray
    spread_E: np.ndarray
    samples_per_pulse_E: np.ndarray
    overlap_E: np.ndarray
    detection_E: np.ndarray
    round_trip_E: np.ndarray
    sensor_peak_E: np.ndarray
    wall_force_E: np.ndarray
    plate_von_mises_E: np.ndarray
    soil_von_mises_E: np.ndarray
    plate_yield_E: np.ndarray
    soil_yield_E: np.ndarray
    bead_force: float
    bead_yield_index: float
    range_index: float
    mass: float
    length: float
    plate_mass_ratio: float
    source: str = "scan"
    step: str = "shared"
    wall_time: float = 0.0
    limits: dict[str, float] = field(default_factory=dict, compare=False)
    checks_E: dict[str, np.ndarray] = field(default_factory=dict, compare=False)
    checks_assumed: dict[str, str] = field(default_factory=dict, compare=False)
    stresses_skipped: str = ""

    def validity(self) -> Any:
        """The checks over the soils (:class:`ssw.validity.Validity`, one scene per E).

        Returns
        -------
        ssw.validity.Validity
            The checks ``checks_E`` and their assumptions ``checks_assumed``.
        """
        from ssw.validity import Validity

        skipped = {} if not self.stresses_skipped else {
            k: f"stresses not computed: the device {self.stresses_skipped}"
            for k in ("sample_yield", "plate_yield")}
        return Validity(dict(self.checks_E), dict(self.checks_assumed), skipped=skipped)

    # ------------------------------------------------------------------ indices
    @property
    def resolution(self) -> float:
        """The worst (coarsest) relative resolution dE/E over the soils (inf: no TOF)."""
        r = self.resolution_E
        return float(np.max(r)) if np.all(np.isfinite(r)) else float("inf")

    @property
    def sensitivity(self) -> float:
        """The smallest ``|d ln TOF / d ln E|`` over the soils."""
        return float(np.min(self.sensitivity_E))

    def _worst(self, x: np.ndarray) -> float:
        return float(np.max(x)) if np.all(np.isfinite(x)) else float("inf")

    @property
    def overlap_index(self) -> float:
        """The worst pulse overlap over the soils (-; inf: not evaluable)."""
        return self._worst(self.overlap_E)

    @property
    def detection_index(self) -> float:
        """The worst noise floor over the reflected peak over the soils (-; inf: none)."""
        return self._worst(self.detection_E)

    @property
    def round_trip_index(self) -> float:
        """The worst shortest round trip over the TOF over the soils (-; inf: none)."""
        return self._worst(self.round_trip_E)

    @property
    def plate_yield_index(self) -> float:
        """The plate's largest peak von Mises stress over its yield stress (-; NaN: not
        computed, ``stresses_skipped``)."""
        return float("nan") if self.stresses_skipped else self._worst(self.plate_yield_E)

    @property
    def soil_yield_index(self) -> float:
        """The soil's largest peak von Mises stress over its yield stress (-; NaN: not
        computed, ``stresses_skipped``)."""
        return float("nan") if self.stresses_skipped else self._worst(self.soil_yield_E)

    @property
    def indices(self) -> dict[str, float]:
        """Every limited index (``HARD``, ``SOFT``)."""
        return {k: float(getattr(self, k)) for k in (*HARD, *SOFT)}

    @property
    def violations(self) -> dict[str, float]:
        """Relative excess of each index over its limit (0: met; inf: not evaluable; NaN:
        not computed, ``stresses_skipped``)."""
        out = {}
        for k, v in self.indices.items():
            lim = self.limits.get(k, 1.0)
            out[k] = (max(0.0, v / lim - 1.0) if np.isfinite(v)
                      else float("nan") if np.isnan(v) else float("inf"))
        return out

    @property
    def hard_feasible(self) -> bool:
        """Every hard limit met (the Pareto fronts' pool)."""
        v = self.violations
        return all(v[k] == 0.0 for k in HARD) and np.isfinite(self.resolution)

    @property
    def feasible(self) -> bool:
        """Every hard and soft limit met."""
        return self.hard_feasible and self.violations["soil_yield_index"] == 0.0

    @property
    def key(self) -> tuple[Any, ...]:
        """The device's key (:attr:`ssw.design.space.DevicePoint.key`)."""
        return self.point.key

    def to_dict(self, arrays: bool = True) -> dict[str, Any]:
        """The JSON record (``arrays``: with the per-soil arrays).

        Parameters
        ----------
        arrays : bool
            Whether the per-soil arrays (:data:`ARRAYS`) and checks are included.

        Returns
        -------
        dict of str to Any
            The point's variables, source, step, resolution, sensitivity, indices,
            feasibility, violations and (when checked) the worst validity (SI units).
        """
        d: dict[str, Any] = {
            **self.point.to_dict(), "source": self.source, "step": self.step,
            "resolution": self.resolution, "sensitivity": self.sensitivity,
            **self.indices, "bead_force": self.bead_force,
            "feasible": self.feasible, "hard_feasible": self.hard_feasible,
            "violations": self.violations, "wall_time": self.wall_time,
            "stresses_skipped": self.stresses_skipped}
        if arrays:
            d.update({k: getattr(self, k).tolist() for k in ARRAYS})
        if self.checks_E:  # the worst over the soils, and (with arrays) every soil's
            worst = self.validity().worst()
            d.update(validity=worst.entries(0), checks_failed=worst.failed(0),
                     checks_assumed=dict(self.checks_assumed))
            if arrays:
                d["checks_E"] = {k: v.tolist() for k, v in self.checks_E.items()}
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any], limits: dict[str, float]) -> DeviceCandidate:
        """A candidate from its JSON record (:meth:`to_dict` with arrays).

        Parameters
        ----------
        d : dict of str to Any
            The record, with the per-soil arrays (SI units).
        limits : dict of str to float
            Each index's limit.

        Returns
        -------
        DeviceCandidate
            The candidate.
        """
        arr = {k: np.asarray(d[k], float) for k in ARRAYS}
        scalars = {k: float(d[k]) for k in ("bead_force", "bead_yield_index", "range_index",
                                            "mass", "length", "plate_mass_ratio")}
        return cls(point=DevicePoint.from_dict(d), **arr, **scalars, source=d["source"],
                   step=d["step"], wall_time=float(d.get("wall_time", 0.0)),
                   limits=dict(limits),
                   checks_E={k: np.asarray(v, float) for k, v in
                             d.get("checks_E", {}).items()},
                   checks_assumed=dict(d.get("checks_assumed", {})),
                   stresses_skipped=str(d.get("stresses_skipped", "")))


def _bead_strength(material: Any) -> float:
    """A bead material's yield stress, or its compressive strength (brittle); ConfigError
    naming the library's field when it has neither."""
    st = material.strength
    y = st.yield_stress if st.yield_stress is not None else st.compressive
    if y is None:
        raise ConfigError(f"materials.{material.key}.strength.yield_stress", None,
                          "a yield stress (or a compressive strength) with its source: the "
                          "beads are designed against it")
    return float(y)


def _group_key(params: Any) -> tuple[Any, ...]:
    """What the scenes of one batched run share: every ChainParams field but those a
    Batch varies per scene and the plate's (the walls carry the plate)."""
    from ssw.chain.params import VARYING

    skip = set(VARYING) | {f.name for f in fields(params) if f.name.startswith("plate_")}
    return tuple(v for f, v in zip(fields(params), astuple(params), strict=True)
                 if f.name not in skip)


@dataclass
class _Scenes:
    """The dynamics of one device over the soils (before the stresses)."""

    point: DevicePoint
    params: Any
    E: np.ndarray
    tof: np.ndarray
    dtof: np.ndarray
    d_peak: np.ndarray
    wall_force: np.ndarray
    sensor_peak: np.ndarray
    bead_force: float
    overlap: np.ndarray
    detection: np.ndarray
    round_trip: np.ndarray
    sampled: Any
    step: str
    wall_time: float
    checks: dict[str, np.ndarray] = field(default_factory=dict)


def _dynamics(members: list[tuple[DevicePoint, Any]], spec: DeviceSpec, contact: Any,
              store: Any, step: str) -> list[_Scenes]:
    """One batched run of the devices ``members`` (one chain) over the soil grid."""
    from ssw.chain.params import Batch
    from ssw.chain.run import run_peaks
    from ssw.design.sampling import sampled_tof
    from ssw.signal.rule import RULE
    from ssw.signal.tof import shortest_round_trip
    from ssw.validity import (
        contact_radius_ratio,
        plate_deflection_ratio,
        pulse_overlap,
        reach_ratio,
    )
    from ssw.walls.fem import concatenate, fem_wall

    t0 = time.perf_counter()
    E = spec.grid
    n_E = E.size
    base = members[0][1]
    walls = [fem_wall(p, E, np.full(n_E, spec.soil_nu), contact=contact(p), operators=store,
                      with_dE=True) for _, p in members]
    wall = concatenate(walls)
    rep = lambda f: np.repeat([f(p) for _, p in members], n_E)  # noqa: E731
    vary = {"striker_velocity": rep(lambda p: p.striker_velocity),
            "striker_mass": rep(lambda p: p.masses[0]),
            "sensor_mass": rep(lambda p: p.masses[p.sensor_index])}
    b = Batch.of(base, wall.n, vary)
    pk, run = run_peaks(b, wall, strict=False, derivatives=("E",))
    # the valley between the pulses over the rule's gap share of the smaller (infinite
    # where the reflected peak is not on the record: a scene run again for longer keeps
    # its first record)
    overlap = pulse_overlap(run, pk)
    seen = np.isfinite(pk.tof) & (pk.t_reflected <= run.t[-1])
    with np.errstate(divide="ignore", invalid="ignore"):
        detection = np.where(pk.f_reflected > 0,
                             RULE.noise_k * spec.noise_rms / pk.f_reflected, np.inf)
        # the shortest physical round trip at the incident pulse's force over the TOF:
        # above 1, the "reflected" peak came back too soon to be one (a striker's train)
        t_min = np.array([
            shortest_round_trip(p.n_beads - 1 - p.sensor_index, p.bead_radius, p.bead_E,
                                p.bead_nu, p.bead_density, float(f), float(w0))
            if np.isfinite(f) and f > 0 else np.inf
            for (_, p), f, w0 in zip([m for m in members for _ in range(n_E)],
                                     pk.f_incident, run.wall_force[0], strict=True)])
        round_trip = np.where(seen, t_min / pk.tof, np.inf)
    sampled = sampled_tof(run, pk, spec.sample_rate, spec.noise_rms, spec.phases)
    sensor_peak = np.nanmax(run.sensor, axis=0)
    d_peak = run.peak_wall_indentation
    f_wall = wall.force(d_peak)
    reach = reach_ratio(wall, d_peak)
    wall_time = (time.perf_counter() - t0) / len(members)
    out = []
    for j, (point, p) in enumerate(members):
        sl = slice(j * n_E, (j + 1) * n_E)
        sub = type(sampled)(*(getattr(sampled, f.name)[sl] for f in fields(sampled)))
        checks = {"contact_strain": contact_radius_ratio(d_peak[sl], p.bead_radius),
                  "plate_deflection": plate_deflection_ratio(d_peak[sl], p.plate_thickness)}
        if reach is not None:
            checks["wall_reach"] = reach[sl]
        out.append(_Scenes(point, p, E, pk.tof[sl], pk.dtof[sl, 0], d_peak[sl], f_wall[sl],
                           sensor_peak[sl], float(np.nanmax(run.peak_contact_force[sl])),
                           overlap[sl], detection[sl], round_trip[sl], sub, step,
                           wall_time, checks))
    return out


#: Hard limits known before the stresses: a device that breaks one of them is not built
#: whatever its stresses, so its stresses are not computed (:func:`evaluate`).
BEFORE_STRESSES = tuple(k for k in HARD if k != "plate_yield_index")


def _stress_groups(scenes: list[_Scenes], needed: list[int]) -> list[list[int]]:
    """The scenes ``needed`` grouped by bead and plate (one stress call each)."""
    plates: dict[tuple[Any, ...], list[int]] = {}
    for i in needed:
        p = scenes[i].params
        plates.setdefault((p.bead_radius, p.bead_E, p.bead_nu, p.plate_E, p.plate_nu,
                           p.plate_thickness, p.plate_diameter, p.plate_interface), []).append(i)
    return [[i for i in idx if np.all(np.isfinite(scenes[i].d_peak))]
            for idx in plates.values()]


def _stresses(scenes: list[_Scenes], needed: list[int], spec: DeviceSpec, contact_of: Any,
              store: Any) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Pa, the plate's and the soil's peak von Mises stress (n_E,) of each scene (NaN where
    not ``needed`` or without a peak): the states of one bead on one plate in one call
    (:func:`ssw.walls.fem.peak_stresses`, one state per modulus)."""
    from ssw.walls.fem import peak_stresses

    plate_vm = [np.full(spec.moduli, np.nan) for _ in scenes]
    soil_vm = [np.full(spec.moduli, np.nan) for _ in scenes]
    for ok in _stress_groups(scenes, needed):
        if not ok:
            continue
        p = scenes[ok[0]].params
        t0 = time.perf_counter()
        st = peak_stresses(p, np.concatenate([scenes[i].E for i in ok]), spec.soil_nu,
                           np.concatenate([scenes[i].d_peak for i in ok]),
                           contact=contact_of(p), operators=store,
                           force=np.concatenate([scenes[i].wall_force for i in ok]))
        share = (time.perf_counter() - t0) / len(ok)
        for j, i in enumerate(ok):
            sl = slice(j * spec.moduli, (j + 1) * spec.moduli)
            soil_vm[i] = st.soil.peak[sl]
            plate_vm[i] = st.plate.peak[sl] if st.plate is not None else np.zeros(spec.moduli)
            scenes[i].wall_time += share
    return plate_vm, soil_vm


def _candidate(sc: _Scenes, plate_vm: np.ndarray, soil_vm: np.ndarray, spec: DeviceSpec,
               materials: dict[str, Any], full_scale: float, source: str,
               skipped: str = "") -> DeviceCandidate:
    """The candidate of one device's dynamics and stresses (module docstring, 3-6)."""
    from ssw.constitutive.yield_index import first_yield_ratio, hertz_peak_pressure
    from ssw.design.evaluate import plate_yield_stress

    point, p = sc.point, sc.params
    plate_mat = materials[point.plate_material]
    Y_plate = plate_yield_stress(plate_mat)
    p0 = float(hertz_peak_pressure(np.array([sc.bead_force]), p.bead_E, p.bead_nu,
                                   p.bead_radius)[0])
    bead_index = p0 / (first_yield_ratio(p.bead_nu)
                       * _bead_strength(materials[point.bead_material]))
    with np.errstate(divide="ignore", invalid="ignore"):
        sens = np.abs(sc.E * sc.dtof) / sc.tof
        u = np.sqrt(spec.tof_scatter**2 / spec.hits
                    + (sc.sampled.noise**2 + sc.sampled.spread**2) / spec.hits
                    + sc.sampled.bias**2)
        res = u / (sc.tof * sens)
    plate_mass = plate_mat.density * np.pi * 0.25 * p.plate_diameter**2 * p.plate_thickness
    checks = {**sc.checks, "pulse_separation": sc.overlap,
              "bead_yield": np.full(sc.E.size, float(bead_index))}
    if not skipped:
        checks.update(sample_yield=soil_vm / spec.soil_yield_stress(sc.E),
                      plate_yield=plate_vm / Y_plate)
    return DeviceCandidate(
        point=point, soil_E=sc.E, tof_E=sc.tof, dtof_dE_E=sc.dtof, sensitivity_E=sens,
        u_tof_E=u, resolution_E=np.where(np.isfinite(res), res, np.inf),
        noise_E=sc.sampled.noise, bias_E=sc.sampled.bias, spread_E=sc.sampled.spread,
        samples_per_pulse_E=sc.sampled.samples_per_pulse, overlap_E=sc.overlap,
        detection_E=sc.detection, round_trip_E=sc.round_trip, sensor_peak_E=sc.sensor_peak,
        wall_force_E=sc.wall_force, plate_von_mises_E=plate_vm, soil_von_mises_E=soil_vm,
        plate_yield_E=plate_vm / Y_plate, soil_yield_E=soil_vm / spec.soil_yield_stress(sc.E),
        bead_force=sc.bead_force, bead_yield_index=float(bead_index),
        range_index=float(np.nanmax(sc.sensor_peak) / full_scale),
        mass=float(np.sum(p.masses) + plate_mass),
        length=float(p.n_beads * 2.0 * p.bead_radius + point.drop_height + p.plate_thickness),
        plate_mass_ratio=float(plate_mass / p.bead_mass), source=source, step=sc.step,
        wall_time=sc.wall_time, limits=spec.limits, checks_E=checks,
        checks_assumed={} if spec.soil_strength is not None else {
            "sample_yield": f"Y_soil = {spec.soil_strength_ratio:g} E (ssw design's "
                            "stated assumption: --soil-strength states one)"},
        stresses_skipped=skipped)


def _broken_before_stresses(c: DeviceCandidate) -> list[str]:
    """The limits of :data:`BEFORE_STRESSES` a candidate breaks (or all: no TOF)."""
    if not np.isfinite(c.resolution):
        return ["resolution (no TOF on some soil)"]
    v = c.violations
    return [k for k in BEFORE_STRESSES if not v[k] == 0.0]


def evaluate(items: list[tuple[DevicePoint, Any]], spec: DeviceSpec,
             materials: dict[str, Any], contact: dict[str, Any], base_radius: float,
             full_scale: float, *, store: Any = None, source: str = "scan",
             own_step: bool = False, all_stresses: bool = False) -> list[DeviceCandidate]:
    """Evaluate devices over the soil grid (module docstring).

    The stresses (step 5, the costliest per plate) are computed only for the devices that
    meet every hard limit known without them (:data:`BEFORE_STRESSES`), unless
    ``all_stresses``: those the ranking's feasible and hard-feasible classes and the Pareto
    fronts can hold. A device that breaks one is ranked among the infeasible ones by
    :func:`merit <ssw.design.device_search.merit>` without its yield terms (a lower bound),
    its plate and soil stresses NaN and ``stresses_skipped`` naming the broken limits.

    Parameters
    ----------
    items : list of tuple
        ``(DevicePoint, ChainParams)`` pairs: each device and the chain that runs it.
    spec : ssw.design.device_spec.DeviceSpec
        The design question.
    materials : dict
        The materials library (key -> Material).
    contact : dict
        The study's ``contact:`` settings (for a bead of ``base_radius``).
    base_radius : float
        m, the base device's bead radius (the contact settings' scale).
    full_scale : float
        N, the largest reading of the sensor and the DAQ.
    store : ssw.contact.operators.OperatorStore or None
        The contact operators (default: the process's).
    source : str
        The candidates' label (``scan``, ``search``, ``reference``).
    own_step : bool
        Group the devices by striker so that each runs at its own time step.
    all_stresses : bool
        The stresses of every device (the base device's and the recommended one's: each
        stated whole), not only of those that meet the hard limits known without them.

    Returns
    -------
    list of DeviceCandidate
        In the order of ``items``.
    """
    def contact_of(p: Any) -> dict[str, Any]:
        return scaled_contact({**contact, "interface": p.plate_interface},
                              p.bead_radius / base_radius)

    groups: dict[tuple[Any, ...], list[int]] = {}
    for i, (_, p) in enumerate(items):
        key = _group_key(p) + ((p.striker_velocity, p.masses[0]) if own_step else ())
        groups.setdefault(key, []).append(i)
    scenes: list[Any] = [None] * len(items)
    for idx in groups.values():
        for i, sc in zip(idx, _dynamics([items[i] for i in idx], spec, contact_of, store,
                                        "own" if own_step else "shared"), strict=True):
            scenes[i] = sc
    nan = np.full(spec.moduli, np.nan)
    broken = [_broken_before_stresses(_candidate(sc, nan, nan, spec, materials, full_scale,
                                                 source, "?")) for sc in scenes]
    if all_stresses:
        broken = [[] for _ in scenes]
    needed = [i for i, b in enumerate(broken) if not b]
    plate_vm, soil_vm = _stresses(scenes, needed, spec, contact_of, store)
    return [_candidate(sc, plate_vm[i], soil_vm[i], spec, materials, full_scale, source,
                       "" if not broken[i] else "breaks " + ", ".join(broken[i]))
            for i, sc in enumerate(scenes)]
