"""The TOF of a device on a sample: the chain run against a last-contact law named in
:data:`ssw.walls.WALLS` (the public entry points of docs/CONTRACTS.md).

* :func:`tof` (s): TOF for broadcast arrays of soil E (Pa) and nu, one batched run;
* :func:`peaks`: the peaks and the run behind them;
* :func:`tof_derivatives`: the TOF with its derivatives with respect to the soil's modulus
  and the device's parameters (:data:`ssw.chain.sensitivity.PARAMETERS`);
* :func:`sensor_signal` (s, N): the sensor force vs time;
* :func:`sensor_derivatives`: the sensor force and its derivatives at given times (a
  recording's samples);
* :func:`run_chain`: every contact force vs time (the ``ssw chain`` command).

``wall`` names a law of :data:`ssw.walls.WALLS` (``rigid``, ``hertz``, ``fit``, ``table``,
``fem``, ``plastic``); ``wall_options`` are its builder's keywords (``K=``, ``power=``,
``k_table=`` for ``fit``; ``curve=`` for ``table``; ``contact=`` for ``fem``; ``dynamics=``,
``soil_density=`` for the soil's inertia). The chain itself (:mod:`ssw.chain`) knows only the
wall protocol: :func:`ssw.chain.run.run_peaks` runs walls already built.

Derivatives. A TOF is the discrete scheme's, at the time step its parameters give
(:func:`ssw.chain.integrate.time_step`, a fixed fraction of a Hertz contact time at the
striker's speed): a derivative is that of the TOF a run at the perturbed parameters gives,
its step's dependence on the striker's speed and masses included (the chain rule through
the step, :func:`ssw.chain.integrate.step_tangent`; 1-3e-4 of the striker speed's
derivative on the thesis device). Given a step (``dt=``), the step is held fixed. Two
methods, named in every result:

* ``forward``: forward sensitivities carried by the integrator
  (:mod:`ssw.chain.sensitivity`, the step's own column among them) and the dense peak's
  implicit derivative (:mod:`ssw.chain.dense`): exact for the discrete TOF. Every wall
  whose law states its derivatives: ``rigid``, ``hertz``, ``fit`` (through the K table's
  interpolant), ``fem`` (implicit differentiation of the condensed contact problem; not
  with the unilateral interface, for E), the reduced dynamic wall;
* ``central``: fourth-order differences of TOFs at the same step
  (:func:`ssw.chain.sensitivity.stencil`: central, one-sided at a bound, a preload or a
  dissipation of 0), relative step :data:`ssw.chain.sensitivity.CENTRAL_STEP`, every
  perturbation in one batched run, plus the step's share: the same differences of the
  TOF in the step times the step's analytic derivative: the walls without a tangent
  (``plastic``, a ``table`` wall's E) and on request (``method="central"``). A wall built
  for one step (the elastodynamic FEM wall, ``wall.dt``) holds its step: its derivatives
  are at that step.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ssw.chain.integrate import Run, simulate, step_tangent, time_step
from ssw.chain.params import Batch, ChainParams
from ssw.chain.run import chain_step, run_peaks, step_derivatives
from ssw.chain.sensitivity import (
    CENTRAL_STEP,
    MOVES_STEP,
    PARAMETERS,
    STEP,
    stencil,
    tangent_of,
    units,
)
from ssw.chain.tof import Peaks
from ssw.errors import ConfigError
from ssw.walls import build_wall

#: Methods of :func:`tof_derivatives`.
METHODS = ("auto", "forward", "central")


def _shape(soil_E: Any, soil_nu: Any, vary: dict[str, Any] | None = None) -> tuple[int, ...]:
    extra = [np.shape(v) for v in (vary or {}).values() if v is not None]
    return np.broadcast_shapes(np.shape(soil_E), np.shape(soil_nu), *extra)


def _broadcast(soil_E: Any, soil_nu: Any, vary: dict[str, Any] | None
               ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray] | None]:
    """E, nu and the varied fields broadcast to one shape, flattened."""
    shape = _shape(soil_E, soil_nu, vary)
    E = np.broadcast_to(np.asarray(soil_E, float), shape).ravel()
    nu = np.broadcast_to(np.asarray(soil_nu, float), shape).ravel()
    flat = None if not vary else {
        k: np.broadcast_to(np.asarray(v, float), shape).ravel()
        for k, v in vary.items() if v is not None}
    return E, nu, flat


def peaks(
    soil_E: Any, soil_nu: Any, params: ChainParams, wall: str = "hertz", *,
    vary: dict[str, Any] | None = None, strict: bool = True, on_progress: Any = None,
    derivatives: Any = None, dt: float | None = None, **wall_options: Any,
) -> tuple[Peaks, Run]:
    """Peaks on the dense output (flat, one per scene) and the run.

    Parameters
    ----------
    soil_E : array_like
        Pa, broadcast with ``soil_nu`` and ``vary``.
    soil_nu : array_like
        -.
    params : ChainParams
        The chain.
    wall : str
        A law of :data:`ssw.walls.WALLS`.
    vary : dict or None
        Per-scene fields (:data:`ssw.chain.params.VARYING` -> values).
    strict : bool
        Raise on a truncated record or a signal without two peaks (else NaN).
    on_progress : callable or None
        Told ``on_progress(k)`` when ``k`` scenes finish.
    derivatives : sequence of str or None
        Forward sensitivities to carry (:func:`ssw.chain.run.run_peaks`); the wall must
        have them (:func:`tof_derivatives` chooses).
    dt : float or None
        s, the time step (default: :func:`ssw.chain.integrate.time_step` of the batch, and
        the derivatives include its dependence on the parameters; given, it is held
        fixed).
    **wall_options
        The wall builder's keywords.

    Returns
    -------
    tuple
        ``(Peaks, Run)``.
    """
    E, nu, flat = _broadcast(soil_E, soil_nu, vary)
    w = build_wall(wall, params, E, nu, **wall_options)
    b = Batch.of(params, w.n, flat) if flat else params
    return run_peaks(b, w, strict=strict, on_progress=on_progress, derivatives=derivatives,
                     dt=dt)


def tof(
    soil_E: Any, soil_nu: Any, params: ChainParams, wall: str = "hertz", *,
    vary: dict[str, Any] | None = None, **wall_options: Any,
) -> np.ndarray:
    """TOF (s) between the incident and reflected peaks at the sensor, vectorized.

    Parameters
    ----------
    soil_E : array_like
        Pa, broadcast with ``soil_nu`` and the arrays of ``vary``.
    soil_nu : array_like
        -.
    params : ChainParams
        The chain.
    wall : str
        A last-contact law of :data:`ssw.walls.WALLS`.
    vary : dict or None
        Per-scene striker speed, preload, masses.
    **wall_options
        The law's options.

    Returns
    -------
    numpy.ndarray
        s, the broadcast shape.

    Raises
    ------
    SolverError
        A scene's record is truncated (its reflected wave had not passed the sensor at
        ``params.t_max``).
    """
    pk, _ = peaks(soil_E, soil_nu, params, wall, vary=vary, **wall_options)
    return pk.tof.reshape(_shape(soil_E, soil_nu, vary))


@dataclass(frozen=True)
class TofDerivatives:
    """A TOF with its derivatives (:func:`tof_derivatives`). SI units.

    Parameters
    ----------
    tof : numpy.ndarray
        s, the broadcast shape of the inputs.
    dtof : dict
        Parameter name -> s per SI unit of the parameter (same shape), the step's
        dependence on it included (module docstring).
    method : dict
        Parameter name -> ``forward`` or ``central`` (module docstring).
    step : dict
        Parameter name -> the central differences' step (SI unit of the parameter; 0 for
        ``forward``).
    peaks : Peaks
        The base run's peaks (flat), with ``dt_*``/``df_*`` for the forward parameters.
    run : Run
        The base run; its ``dsensor`` holds the sensor signal's forward sensitivities at
        its step (``run.tangent``'s columns: the step's own last where a parameter moves
        it).
    dt : float
        s, the fixed step of every run.
    units : dict
        Parameter name -> its SI unit (the dissipation coefficient's is its law's).
    """

    tof: np.ndarray
    dtof: dict[str, np.ndarray]
    method: dict[str, str]
    step: dict[str, float]
    peaks: Peaks
    run: Run
    dt: float
    #: parameter name -> its SI unit (the dissipation coefficient's is its law's)
    units: dict[str, str] = field(default_factory=lambda: dict(PARAMETERS))

    def as_dict(self, index: int = 0) -> dict[str, Any]:
        """Scene ``index``'s values for a JSON record: ``tof``, ``dtof_d<name>``,
        ``derivative_method`` and ``derivative_units`` (s per unit).

        Parameters
        ----------
        index : int
            The scene.

        Returns
        -------
        dict
            The record (s and s per parameter unit).
        """
        out: dict[str, Any] = {"tof": float(np.ravel(self.tof)[index])}
        for name, d in self.dtof.items():
            out[f"dtof_d{name}"] = float(np.ravel(d)[index])
        out["derivative_method"] = dict(self.method)
        out["derivative_units"] = {f"dtof_d{k}": f"s/({self.units[k]})" for k in self.dtof}
        out["derivative_step"] = {k: v for k, v in self.step.items() if v}
        return out


def forward_ok(w: Any, names: tuple[str, ...]) -> dict[str, bool]:
    """Which parameters the wall ``w`` can carry forward sensitivities for.

    Parameters
    ----------
    w : Wall
        A built wall (:func:`ssw.walls.build_wall`).
    names : tuple of str
        Names of :data:`ssw.chain.sensitivity.PARAMETERS`.

    Returns
    -------
    dict
        Name -> True where the wall states the tangent the forward sensitivity needs (a
        stateful wall its ``advance_tangent``, and for a parameter that moves the step its
        ``step_tangent``; ``E`` its ``dforce_dE``).
    """
    stateful = hasattr(w, "advance")
    tangent = not stateful or hasattr(w, "advance_tangent")
    ok = {name: tangent for name in names}
    if stateful and tangent and not getattr(w, "step_tangent", False):
        for name in set(names) & set(MOVES_STEP):
            ok[name] = name == "E"  # E moves no physical wall's step
    if "E" in names and tangent:
        try:
            w.dforce_dE(np.zeros(w.n))
        except (ConfigError, AttributeError):
            ok["E"] = False
    return ok


def central_differences(
    soil_E: np.ndarray, soil_nu: np.ndarray, params: ChainParams, wall: str,
    names: tuple[str, ...], *, dt: float, vary: dict[str, np.ndarray] | None = None,
    step: float = CENTRAL_STEP, strict: bool = True, moving_step: bool = True,
    **wall_options: Any,
) -> tuple[dict[str, np.ndarray], dict[str, float]]:
    """Central differences of TOFs at the fixed step ``dt``, every perturbation of ``E``
    and of the per-scene fields in one batched run (the dissipation, one ChainParams field,
    in its own runs); with ``moving_step``, plus the step's share of each parameter that
    moves it: the same differences of the TOF in the step, times the step's analytic
    derivative (:func:`ssw.chain.integrate.step_tangent`).

    Parameters
    ----------
    soil_E : numpy.ndarray
        (n,) Pa.
    soil_nu : numpy.ndarray
        (n,) -.
    params : ChainParams
        The chain.
    wall : str
        A law of :data:`ssw.walls.WALLS`.
    names : tuple of str
        Parameters of :data:`ssw.chain.sensitivity.PARAMETERS`.
    dt : float
        s, the step of the base run.
    vary : dict or None
        The base run's per-scene fields, (n,) each.
    step : float
        Relative step (:data:`ssw.chain.sensitivity.CENTRAL_STEP`).
    strict : bool
        As :func:`peaks`.
    moving_step : bool
        ``dt`` is the parameters' own step (:func:`ssw.chain.integrate.time_step`), which
        moves with them; False: held fixed.
    **wall_options
        The law's options.

    Returns
    -------
    tuple of dict
        Name -> (n,) s per unit, and name -> the step used (SI, the first scene's).
    """
    n = soil_E.size
    base = Batch.of(params, n, vary)
    values = {"E": soil_E, "striker_velocity": base.striker_velocity,
              "preload": base.preload, "striker_mass": base.masses[:, 0],
              "sensor_mass": base.masses[:, params.sensor_index],
              "damping": np.full(n, params.damping)}
    per_scene = {"striker_velocity": base.striker_velocity, "preload": base.preload,
                 "striker_mass": base.masses[:, 0],
                 "sensor_mass": base.masses[:, params.sensor_index]}
    Es, fs, plan = [], {k: [] for k in per_scene}, []
    out, used = {}, {}
    for name in names:
        st = stencil(name, values[name], step)
        h = st.h
        used[name] = float(h[0])
        if name == "damping":
            tofs = [peaks(soil_E, soil_nu, params.with_(damping=float(params.damping
                                                                      + o * h[0])),
                          wall, vary=vary, strict=strict, dt=dt, **wall_options)[0].tof
                    for o in st.offsets]
            out[name] = st.derivative(tofs)
            continue
        for o in st.offsets:
            Es.append(soil_E + o * h if name == "E" else soil_E)
            for k, v in per_scene.items():
                fs[k].append(v + o * h if k == name else v)
            plan.append(name)
    if Es:
        E_all = np.concatenate(Es)
        nu_all = np.tile(soil_nu, len(Es))
        w = build_wall(wall, params, E_all, nu_all, **wall_options)
        b = Batch.of(params, w.n, {k: np.concatenate(v) for k, v in fs.items()})
        pk, _ = run_peaks(b, w, strict=strict, dt=dt)
        blocks = pk.tof.reshape(len(Es), n)
        j = 0
        for name in dict.fromkeys(plan):
            st = stencil(name, values[name], step)
            out[name] = st.derivative(list(blocks[j: j + st.offsets.size]))
            j += st.offsets.size
    movers = tuple(k for k in names if k in MOVES_STEP)
    if moving_step and movers:
        w = build_wall(wall, params, soil_E, soil_nu, **wall_options)
        ddt = step_tangent(base, w, dt, movers)
        if getattr(w, "dt", None) is None and np.any(ddt):  # else the wall holds its step
            st = stencil(STEP, np.array([dt]), step)
            tofs = [run_peaks(base, w, strict=strict, dt=dt + o * float(st.h[0]))[0].tof
                    for o in st.offsets]
            dT = st.derivative(tofs)
            for j, name in enumerate(movers):
                out[name] = out[name] + dT * ddt[:, j]
    return out, used


def tof_derivatives(
    soil_E: Any, soil_nu: Any, params: ChainParams, wall: str = "hertz", *,
    derivatives: Any = tuple(PARAMETERS), vary: dict[str, Any] | None = None,
    method: str = "auto", step: float = CENTRAL_STEP, strict: bool = True,
    **wall_options: Any,
) -> TofDerivatives:
    """The TOF and its derivatives with respect to the soil's modulus and the device's
    parameters (module docstring).

    Parameters
    ----------
    soil_E : array_like
        Pa, broadcast with ``soil_nu`` and ``vary``.
    soil_nu : array_like
        -.
    params : ChainParams
        The chain.
    wall : str
        A law of :data:`ssw.walls.WALLS`.
    derivatives : sequence of str or str
        Names of :data:`ssw.chain.sensitivity.PARAMETERS` (default all: ``E``,
        ``striker_velocity``, ``preload``, ``sensor_mass``, ``striker_mass``, ``damping``).
    vary : dict or None
        Per-scene striker speed, preload, masses.
    method : str
        ``auto`` (forward where the wall states its derivatives, else central),
        ``forward`` (ConfigError where it cannot) or ``central``.
    step : float
        Relative step of the central differences.
    strict : bool
        As :func:`peaks`.
    **wall_options
        The law's options (``with_dE`` is set for the ``fem`` wall when E is asked).

    Returns
    -------
    TofDerivatives
        TOF, derivatives, the method of each, the base run and peaks.

    Raises
    ------
    ConfigError
        An unknown parameter or method, or ``forward`` where the wall has no tangent.
    """
    if method not in METHODS:
        raise ConfigError("derivative method", method, " | ".join(METHODS))
    tg = tangent_of(derivatives)
    names = tg.names
    shape = _shape(soil_E, soil_nu, vary)
    E, nu, flat = _broadcast(soil_E, soil_nu, vary)
    opts = dict(wall_options)
    if wall == "fem" and "E" in names and method != "central":
        opts["with_dE"] = True
    w = build_wall(wall, params, E, nu, **opts)
    b = Batch.of(params, w.n, flat) if flat else params
    dt = time_step(b, w)
    ok = forward_ok(w, names) if method != "central" else dict.fromkeys(names, False)
    if method == "forward" and not all(ok.values()):
        bad = [k for k, v in ok.items() if not v]
        raise ConfigError("derivatives", bad, f"parameters the {wall} wall has forward "
                          "sensitivities for (or method auto/central)")
    forward = tuple(k for k in names if ok[k])
    # the step is the parameters' own (dt None: run_peaks differentiates it too)
    pk, run = run_peaks(b, w, strict=strict, derivatives=forward or None)
    dtof: dict[str, np.ndarray] = {}
    meth: dict[str, str] = {}
    steps: dict[str, float] = {}
    for j, name in enumerate(forward):
        dtof[name] = pk.dtof[:, j]
        meth[name], steps[name] = "forward", 0.0
    central = tuple(k for k in names if not ok[k])
    if central:
        got, used = central_differences(E, nu, params, wall, central, dt=dt, vary=flat,
                                        step=step, strict=strict, **wall_options)
        for name in central:
            dtof[name] = got[name]
            meth[name], steps[name] = "central", used[name]
    order = {k: dtof[k].reshape(shape) for k in names}
    return TofDerivatives(pk.tof.reshape(shape), order, {k: meth[k] for k in names},
                          {k: steps[k] for k in names}, pk, run, dt,
                          units(params.damping_law))


def sensor_signal(
    soil_E: Any,
    soil_nu: Any,
    params: ChainParams,
    wall: str = "hertz",
    *,
    t_end: float | None = None,
    **wall_options: Any,
) -> tuple[np.ndarray, np.ndarray]:
    """The sensor particle's force vs time.

    Parameters
    ----------
    soil_E : array_like
        Pa, broadcast with ``soil_nu``.
    soil_nu : array_like
        -.
    params : ChainParams
        The chain.
    wall : str
        A law of :data:`ssw.walls.WALLS`.
    t_end : float or None
        s: run exactly that long; None: until the reflected wave has passed the sensor
        (the latest scene's stop time).
    **wall_options
        The law's options.

    Returns
    -------
    tuple of numpy.ndarray
        ``(t, F)``: ``t`` (n_t,) s from the striker's first contact, ``F`` N, what the
        sensor reads (``params.sensor_reads``), static precompression included; shape
        (n_t,) for scalar ``soil_E``/``soil_nu``, else ``n_t`` followed by their
        broadcast shape.
    """
    w = build_wall(wall, params, soil_E, soil_nu, **wall_options)
    if t_end is None:
        run = simulate(params, w)
        stop = run.stop_time
        n_t = run.t.size if np.any(np.isnan(stop)) else int(np.rint(stop.max() / run.dt)) + 1
        F = _hold_last(run.sensor[:n_t])
        t = run.t[:n_t]
    else:
        run = simulate(params, w, t_end=t_end, stop_early=False)
        t, F = run.t, run.sensor
    return t, F.reshape((t.size, *_shape(soil_E, soil_nu)))


@dataclass(frozen=True)
class SensorDerivatives:
    """The sensor signal at given times and its forward sensitivities. SI units.

    Parameters
    ----------
    t : numpy.ndarray
        (m,) s from the striker's first contact.
    sensor : numpy.ndarray
        (m, n) N, the dense output (:func:`ssw.chain.dense.evaluate`).
    dsensor : numpy.ndarray
        (m, n, k) N per SI unit of each parameter (at the parameters' own step, its
        dependence on them included, unless the step was given).
    names : tuple of str
        The parameters (the last axis of ``dsensor``).
    run : Run
        The run (its samples and their sensitivities at every step, ``run.dsensor``, at
        its fixed step: ``run.tangent``'s columns, the step's own last where a parameter
        moves it).
    rate : numpy.ndarray or None
        (m, n) N/s, the time derivative of ``sensor`` (with ``rate=True``).
    """

    t: np.ndarray
    sensor: np.ndarray
    dsensor: np.ndarray
    names: tuple[str, ...]
    run: Run
    rate: np.ndarray | None = None


def sensor_derivatives(
    soil_E: Any, soil_nu: Any, params: ChainParams, wall: str = "hertz", *,
    times: Any = None, derivatives: Any = tuple(PARAMETERS), t_end: float | None = None,
    vary: dict[str, Any] | None = None, rate: bool = False, dt: float | None = None,
    **wall_options: Any,
) -> SensorDerivatives:
    """The sensor signal and its exact derivatives (forward sensitivities of the discrete
    scheme, on its dense output) at ``times`` (a recording's samples; default: the run's
    steps), for a waveform inversion.

    Parameters
    ----------
    soil_E : array_like
        Pa, broadcast with ``soil_nu`` and ``vary``: one scene each.
    soil_nu : array_like
        -.
    params : ChainParams
        The chain.
    wall : str
        A law of :data:`ssw.walls.WALLS` with forward sensitivities (module docstring).
    times : array_like or None
        (m,) s, or (m, n) one column per scene (a recording's samples per hit); None:
        every step.
    derivatives : sequence of str or str
        Names of :data:`ssw.chain.sensitivity.PARAMETERS`.
    t_end : float or None
        s, the run's length (default: until every scene's reflected wave has passed).
    vary : dict or None
        Per-scene striker speed, preload, masses.
    rate : bool
        Also the signal's time derivative (``SensorDerivatives.rate``, N/s): what a shift
        in time (a trigger's offset) changes.
    dt : float or None
        s, the time step (default :func:`ssw.chain.integrate.time_step` of the batch, and
        the derivatives include its dependence on the parameters through the run's step
        column and :func:`ssw.chain.integrate.step_tangent`; a fit fixes it, so that its
        runs compare one discretization, and the derivatives are at that step).
    **wall_options
        The law's options.

    Returns
    -------
    SensorDerivatives
        Signal (N) and derivatives per SI unit.
    """
    from ssw.chain.dense import evaluate

    tg = tangent_of(derivatives)
    E, nu, flat = _broadcast(soil_E, soil_nu, vary)
    opts = dict(wall_options)
    if wall == "fem" and "E" in tg.names:
        opts["with_dE"] = True
    w = build_wall(wall, params, E, nu, **opts)
    b = Batch.of(params, w.n, flat) if flat else params
    ddt = step_derivatives(b, w, tg) if dt is None else None
    run = simulate(b, w, derivatives=tg if ddt is None else tg.with_step(), t_end=t_end,
                   stop_early=t_end is None, dt=dt)
    t = run.t if times is None else np.asarray(times, float)
    out = evaluate(run, t, tangent=True, rate=rate)
    dS = out[1] if ddt is None else chain_step(out[1], ddt)
    return SensorDerivatives(t, out[0], dS, tg.names, run, out[2] if rate else None)


def sensor_force(
    soil_E: float, soil_nu: float, params: ChainParams, wall: str = "hertz", *,
    t_end: float | None = None, **wall_options: Any,
) -> tuple[Any, float]:
    """One scene's sensor force as a function of time: the dense output
    (:func:`ssw.chain.dense.evaluate`) minus the static value, 0 before the wave, the last
    value after the run (what a measurement model samples, :mod:`ssw.daq.model`).

    Parameters
    ----------
    soil_E : float
        Pa.
    soil_nu : float
        -.
    params : ChainParams
        The chain.
    wall : str
        A law of :data:`ssw.walls.WALLS`.
    t_end : float or None
        s, the run's length (None: twice the time the reflected wave needs to pass the
        sensor).
    **wall_options
        The law's options.

    Returns
    -------
    tuple
        ``force(s) -> F`` (any shape of times ``s``, s; N) and the run's last time, s.
    """
    from ssw.chain.dense import evaluate

    w = build_wall(wall, params, soil_E, soil_nu, **wall_options)
    run = simulate(params, w, t_end=t_end, stop_early=t_end is None)
    if t_end is None and np.isfinite(run.stop_time[0]):
        # on to twice that time: the secondary reflection and the rattle after it are in
        # a record's window too
        run = simulate(params, w, t_end=2.0 * float(run.stop_time[0]), stop_early=False)
    stop = float(run.stop_time[0]) if np.isfinite(run.stop_time[0]) else float(run.t[-1])
    last = stop - 5 * run.dt
    base = float(run.sensor[0, 0])
    tail = float(evaluate(run, np.array([last]))[0][0, 0]) - base

    def force(s: np.ndarray) -> np.ndarray:
        s = np.asarray(s, float)
        inside = (s > 4 * run.dt) & (s < last)
        got = evaluate(run, np.clip(s, 4 * run.dt, last).ravel())[0][:, 0].reshape(s.shape)
        return np.where(inside, got - base, np.where(s >= last, tail, 0.0))

    return force, last


def _hold_last(F: np.ndarray) -> np.ndarray:
    """Fill each column's NaN tail (stopped scene) with its last value."""
    out = F.copy()
    valid = ~np.isnan(out)
    last = np.maximum.accumulate(np.where(valid, np.arange(out.shape[0])[:, None], 0), axis=0)
    return out[last, np.arange(out.shape[1])]


def run_chain(
    params: ChainParams,
    soil_E: float,
    soil_nu: float,
    wall: str = "hertz",
    *,
    t_end: float,
    **wall_options: Any,
) -> Run:
    """One scene run to ``t_end`` recording every contact force and the energy.

    Parameters
    ----------
    params : ChainParams
        The chain.
    soil_E : float
        Pa.
    soil_nu : float
        -.
    wall : str
        A law of :data:`ssw.walls.WALLS`.
    t_end : float
        s.
    **wall_options
        The law's options.

    Returns
    -------
    Run
        With ``forces`` and ``energy``.
    """
    w = build_wall(wall, params, soil_E, soil_nu, **wall_options)
    return simulate(params, w, t_end=t_end, stop_early=False, record_forces=True,
                    record_energy=True)
