"""Entry points: the TOF of a scene with a dynamic wall, and with its quasi-static twin.

* :func:`fem_tof`: the dynamic FEM wall and the same scene's quasi-static laws, all run
  through the chain's one integrator (:func:`ssw.chain.integrate.simulate`, which honours
  every device field: the sensor's reading, the contact dashpot, the preload, gravity,
  the masses) over the same record length. The
  quasi-static references are static FEMs of the same contact mesh in fixed boxes
  (:data:`ssw.dynamics.quasistatic.STATIC_BOXES`): the 1 m box of the quasi-static study
  (``ssw contact``) and the half-space, extrapolated from the 1 and 3 m boxes in ``1 / L``.
  Not the dynamic mesh's own static law: its truncation boundary is statically
  approximate (its springs were measured ~1 % soft for a punch), while the dynamic window
  never sees it (fixed and absorbing boundaries give the same dynamic TOF to 1e-9);
* :func:`reduced_tof`: the reduced dynamic wall (:mod:`ssw.dynamics.reduced`) and its
  quasi-static law, batched over scenes.

TOFs are the peaks of the runs' dense output (:func:`ssw.chain.dense.dense_peaks`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ssw.chain.dense import dense_peaks
from ssw.chain.integrate import Run, simulate
from ssw.chain.sensitivity import CENTRAL_STEP, PARAMETERS

#: The static curves kept reach this multiple of the Hertz wall's peak indentation.
CURVE_REACH = 1.5


@dataclass(frozen=True)
class DynamicTof:
    """TOFs of a dynamic wall and of its quasi-static laws, and what it took.

    ``error`` is ``tof_half_space / tof_dynamic - 1``, the relative error the quasi-static
    assumption makes in the TOF; ``error_box`` the same against the 1 m box the study's
    curves use (static box effect included).

    Parameters
    ----------
    tof_dynamic : numpy.ndarray
        (n,) s, the dynamic wall's.
    tof_static : numpy.ndarray
        (n,) s, the quasi-static FEM's law (1 m box).
    tof_half_space : numpy.ndarray
        (n,) s, the half-space's static law.
    stats : list of dict
        Per scene: dofs, candidates, domain (m), wall times (s), energy balance (J).
    runs : tuple or None
        (dynamic, 1 m static) records when kept.
    curves : list or None
        Per scene, the static boxes' laws ``{L: (d, F)}`` (m, N; the bead's compliance
        included) when kept.
    """

    tof_dynamic: np.ndarray
    tof_static: np.ndarray
    tof_half_space: np.ndarray
    stats: list[dict[str, Any]] = field(default_factory=list)
    runs: tuple[Run, Run] | None = None
    curves: list[dict[float, tuple[np.ndarray, np.ndarray]]] | None = None

    @property
    def error(self) -> np.ndarray:
        """Relative TOF error of the quasi-static half-space law, ``tof_half_space / tof_dynamic -
        1``.
        """
        return self.tof_half_space / self.tof_dynamic - 1.0

    @property
    def error_box(self) -> np.ndarray:
        """Relative TOF error of the static box law, ``tof_static / tof_dynamic - 1``."""
        return self.tof_static / self.tof_dynamic - 1.0


def fem_tof(
    params: Any, soil_E: Any, soil_nu: Any, soil_density: Any, *, keep_runs: bool = False,
    keep_curves: bool = False, record_energy: bool = True, **options: Any,
) -> DynamicTof:
    """TOF of the chain ``params`` with the dynamic FEM wall and with its static law,
    every run through the chain's one integrator (every device field honoured).

    Parameters
    ----------
    params : ChainParams
        The chain.
    soil_E : array_like
        Pa, broadcast with ``soil_nu`` and ``soil_density``: one scene each.
    soil_nu : array_like
        -.
    soil_density : array_like
        kg/m^3.
    keep_runs : bool
        Keep the records.
    keep_curves : bool
        Keep the static boxes' laws (to :data:`CURVE_REACH` x the Hertz wall's peak
        indentation).
    record_energy : bool
        Record the energies (the balance).
    **options
        Keywords of :func:`ssw.dynamics.fem_wall.fem_wall` (``boundary``, ``spec``,
        ``plate_density``, ``bead``, ``candidate_factor``, ``scales``).

    Returns
    -------
    DynamicTof
        TOFs and statistics, one per scene.
    """
    from ssw.dynamics.fem_wall import StaticFEMWall, fem_wall
    from ssw.dynamics.quasistatic import STATIC_BOXES, static_box, static_curve

    t0 = time.perf_counter()
    wall, scales = fem_wall(params, soil_E, soil_nu, soil_density, **options)
    t_build = time.perf_counter() - t0
    tof_d, tof_s, tof_h, stats, runs, curves = [], [], [], [], None, []
    try:
        for k in range(wall.n):
            w = wall.take(np.array([k]))
            t_end = float(scales.t_end[k])
            t1 = time.perf_counter()
            boxes = []
            for L in STATIC_BOXES:
                box = static_box(w.contacts[0], L)
                r_s = simulate(params, StaticFEMWall([box]), t_end=t_end, dt=scales.dt,
                               stop_early=False)
                boxes.append((L, float(dense_peaks(r_s).tof[0]), r_s))
                if keep_curves:
                    if not boxes[1:]:
                        curves.append({})
                    curves[-1][L] = static_curve(box, CURVE_REACH * float(scales.d_peak[k]))
                box.destroy()
            (L1, T1, r_box), (L2, T2, _) = boxes
            t2 = time.perf_counter()
            r_d = simulate(params, w, t_end=t_end, dt=scales.dt, record_energy=record_energy,
                           stop_early=False)
            t3 = time.perf_counter()
            tof_s.append(T1)
            tof_h.append(T2 + (T2 - T1) * (1.0 / L2) / (1.0 / L1 - 1.0 / L2))
            tof_d.append(float(dense_peaks(r_d).tof[0]))
            c = w.contacts[0]
            st = {"dofs": c.system.ndof, "candidates": c.n_candidates,
                  "domain": c.mesh.soil_radius, "elements": len(c.mesh.tri),
                  "steps": r_d.t.size - 1, "dt": scales.dt, "t_end": t_end,
                  "window": float(scales.window[k]),
                  "f_max": float(scales.f_max[k]), "wall_build": t_build / wall.n,
                  "wall_static_runs": t2 - t1, "wall_dynamic_run": t3 - t2}
            if record_energy:
                tot = r_d.energy[:, 0]
                chain = tot - r_d.energy_wall[:, 0] - r_d.dissipated[:, 0]
                st.update({"energy_input": float(chain[0] - chain.min()),
                           "energy_drift": float(np.max(np.abs(tot - tot[0]))),
                           "energy_radiated": float(r_d.dissipated[-1, 0])})
            stats.append(st)
            if keep_runs:
                runs = (r_d, r_box)
    finally:
        wall.destroy()
    return DynamicTof(np.array(tof_d), np.array(tof_s), np.array(tof_h), stats, runs,
                      curves if keep_curves else None)


def fem_tof_derivatives(
    params: Any, soil_E: Any, soil_nu: Any, soil_density: Any, *,
    derivatives: Any = tuple(PARAMETERS), step: float = CENTRAL_STEP, order: int = 2,
    **options: Any,
) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, float]]:
    """The dynamic FEM wall's TOF and its derivatives by central differences (the wall
    has no tangent), one scene at a time.

    Every perturbed run keeps the base run's step and length and, for the device's
    parameters, its FEM wall (one mesh, one factorization); for ``E`` the wall is rebuilt
    on the same mesh (the base scene's domain and largest element, its scales: only the
    soil's modulus changes). Derivatives of the discrete TOF at that step and mesh, by the
    stencils of :func:`ssw.chain.sensitivity.stencil` (``order`` 2: two FEM runs per
    parameter, truncation ~1e-4 relative at the default step; 4: four runs).

    Parameters
    ----------
    params : ChainParams
        The chain.
    soil_E : array_like
        Pa, broadcast with ``soil_nu`` and ``soil_density``: one FEM per scene.
    soil_nu : array_like
        -.
    soil_density : array_like
        kg/m^3.
    derivatives : sequence of str or str
        Names of :data:`ssw.chain.sensitivity.PARAMETERS`.
    step : float
        Relative step.
    order : int
        2 or 4, the stencils' order.
    **options
        Keywords of :func:`ssw.dynamics.fem_wall.fem_wall`.

    Returns
    -------
    tuple
        ``(tof, dtof, steps)``: (n,) s, name -> (n,) s per SI unit, name -> the first
        scene's step (SI).
    """
    from ssw.chain.params import Batch
    from ssw.chain.sensitivity import stencil, tangent_of
    from ssw.dynamics.fem_wall import fem_wall

    names = tangent_of(derivatives).names
    E, nu, rho = (np.ravel(x).astype(float) for x in np.broadcast_arrays(
        np.asarray(soil_E, float), np.asarray(soil_nu, float),
        np.asarray(soil_density, float)))
    wall, scales = fem_wall(params, E, nu, rho, **options)
    tof = np.empty(E.size)
    dtof = {k: np.empty(E.size) for k in names}
    used: dict[str, float] = {}
    try:
        for i in range(wall.n):
            w = wall.take(np.array([i]))
            t_end = float(scales.t_end[i])

            def run_tof(chain: Any, wl: Any, t_end: float = t_end) -> float:
                r = simulate(chain, wl, t_end=t_end, dt=scales.dt, stop_early=False)
                return float(dense_peaks(r).tof[0])

            tof[i] = run_tof(params, w)
            b0 = Batch.of(params, 1)
            values = {"E": E[i:i + 1], "striker_velocity": b0.striker_velocity,
                      "preload": b0.preload, "striker_mass": b0.masses[:, 0],
                      "sensor_mass": b0.masses[:, params.sensor_index],
                      "damping": np.array([params.damping])}
            c = w.contacts[0]
            fixed = {**options.get("spec", {}), "domain": float(c.mesh.soil_radius),
                     "size_max": _largest_element(c)}
            for name in names:
                st = stencil(name, values[name], step, order)
                h = float(st.h[0])
                used.setdefault(name, h)
                got = []
                for o in st.offsets:
                    x = float(values[name][0] + o * h)
                    if name == "E":
                        opts = {**options, "spec": fixed, "scales": _scene_scales(scales, i)}
                        we, _ = fem_wall(params, x, nu[i], rho[i], **opts)
                        try:
                            got.append(run_tof(params, we))
                        finally:
                            we.destroy()
                    elif name == "damping":
                        got.append(run_tof(params.with_(damping=x), w))
                    else:
                        got.append(run_tof(Batch.of(params, 1, {name: x}), w))
                dtof[name][i] = float(st.derivative([np.array([g]) for g in got])[0])
    finally:
        wall.destroy()
    return tof, dtof, used


def _largest_element(contact: Any) -> float:
    """The largest element (m) of a scene's mesh settings (the wave rule's, when the spec
    leaves it free)."""
    from ssw.dynamics.domain import mesh_settings

    return float(mesh_settings(contact.scene.soil, contact.scene.plate_radius,
                               contact.spec).size_max)


def _scene_scales(scales: Any, i: int) -> Any:
    """The scales of scene ``i`` alone."""
    from dataclasses import replace as dc_replace

    one = slice(i, i + 1)
    return dc_replace(scales, t_end=scales.t_end[one], window=scales.window[one],
                      f_max=scales.f_max[one], d_peak=scales.d_peak[one],
                      t_onset=scales.t_onset[one])


def static_laws(params: Any, soil_E: Any, soil_nu: Any, soil_density: Any, scales: Any,
                **options: Any) -> list[dict[float, tuple[np.ndarray, np.ndarray]]]:
    """Per scene, the static FEM laws of the quasi-static boxes
    (:data:`ssw.dynamics.quasistatic.STATIC_BOXES`), up to :data:`CURVE_REACH` x the Hertz
    wall's peak indentation.

    Parameters
    ----------
    params : ChainParams
        The chain.
    soil_E : array_like
        Pa, broadcast with ``soil_nu`` and ``soil_density``: one scene each.
    soil_nu : array_like
        -.
    soil_density : array_like
        kg/m^3.
    scales : ChainScales
        The scenes' scales (:func:`ssw.dynamics.scales.chain_scales`).
    **options
        ``plate_density``, ``bead``, ``spec`` (mesh), ``candidate_factor``.

    Returns
    -------
    list of dict
        Per scene ``{L: (d, F)}`` (m, N).
    """
    from ssw.dynamics.domain import DomainSpec
    from ssw.dynamics.fem_wall import CANDIDATE_FACTOR, ContactFEM, scenes_of
    from ssw.dynamics.quasistatic import STATIC_BOXES, STATIC_SIZE_MAX, static_curve

    scenes = scenes_of(params, soil_E, soil_nu, soil_density, options.get("plate_density"),
                       options.get("bead", "compliance"))
    factor = options.get("candidate_factor", CANDIDATE_FACTOR)
    out = []
    for k, sc in enumerate(scenes):
        d_peak = float(scales.d_peak[k])
        laws = {}
        for L in STATIC_BOXES:
            spec = DomainSpec(**{"window": float(scales.window[k]), **options.get("spec", {}),
                                 "domain": L, "size_max": STATIC_SIZE_MAX})
            c = ContactFEM(sc, spec, None, factor * np.sqrt(sc.radius * d_peak), "fixed",
                           d_scale=d_peak)
            laws[L] = static_curve(c, CURVE_REACH * d_peak)
            c.destroy()
        out.append(laws)
    return out


def reduced_tof(params: Any, soil_E: Any, soil_nu: Any, soil_density: Any, *,
                laws: list[dict[float, tuple[np.ndarray, np.ndarray]]] | None = None,
                **options: Any) -> DynamicTof:
    """TOF of the chain with the reduced dynamic wall on the static FEM laws of the
    quasi-static boxes, batched over the scenes.

    ``tof_dynamic`` is the reduced wall's on the half-space law (``1 / L`` extrapolation
    of its TOFs on the 1 and 3 m boxes, as the quasi-static ``tof_half_space``);
    ``tof_static`` the 1 m box's quasi-static TOF.

    Parameters
    ----------
    params : ChainParams
        The chain.
    soil_E : array_like
        Pa, broadcast with ``soil_nu`` and ``soil_density``: one scene each.
    soil_nu : array_like
        -.
    soil_density : array_like
        kg/m^3.
    laws : list or None
        The static laws when already known (:func:`static_laws`).
    **options
        Those of :func:`static_laws` and ``c_r``, ``m_r``, ``k_p``.

    Returns
    -------
    DynamicTof
        TOFs, one per scene.
    """
    from types import SimpleNamespace

    from ssw.chain.wall import compliance_scale, hertz_wall, table_wall
    from ssw.dynamics.quasistatic import STATIC_BOXES
    from ssw.dynamics.reduced import plate_areal_density, reduced_wall
    from ssw.dynamics.scales import chain_scales

    E, nu, rho = (np.ravel(x).astype(float) for x in np.broadcast_arrays(
        np.asarray(soil_E, float), np.asarray(soil_nu, float),
        np.asarray(soil_density, float)))
    t0 = time.perf_counter()
    scales = chain_scales(params, hertz_wall(params, E, nu))
    coef = {k: options.pop(k) for k in ("c_r", "m_r", "k_p") if k in options}
    if laws is None:
        laws = static_laws(params, E, nu, rho, scales, **options)
    t1 = time.perf_counter()
    s = compliance_scale(params, E, nu)
    t_end = float(np.max(scales.t_end))
    tof: dict[tuple[str, float], np.ndarray] = {}
    for L in STATIC_BOXES:
        curves = [SimpleNamespace(delta=law[L][0] / sk, force=law[L][1])
                  for law, sk in zip(laws, s, strict=True)]
        tw = table_wall(params, E, nu, curve=curves)
        rw = reduced_wall(tw, E, nu, rho, plate_areal_density=plate_areal_density(
            params, options.get("plate_density")), **coef)
        for name, w in (("static", tw), ("reduced", rw)):
            run = simulate(params, w, t_end=t_end, dt=scales.dt, stop_early=False)
            tof[(name, L)] = dense_peaks(run).tof
    L1, L2 = STATIC_BOXES
    w2 = (1.0 / L2) / (1.0 / L1 - 1.0 / L2)

    def half_space(name: str) -> np.ndarray:
        return tof[(name, L2)] + (tof[(name, L2)] - tof[(name, L1)]) * w2

    t2 = time.perf_counter()
    stats = [{"dt": scales.dt, "t_end": t_end, "wall_static_laws": (t1 - t0) / E.size,
              "wall_runs": (t2 - t1) / E.size} for _ in range(E.size)]
    return DynamicTof(half_space("reduced"), tof[("static", L1)], half_space("static"),
                      stats, None, laws)
