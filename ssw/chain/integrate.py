"""Batched velocity-Verlet integration of many chains (scenes) at once.

Equations of motion (REFERENCE.md "The chain"; Nesterenko 2001, Daraio et al. 2006), beads
``i = 0..N-1`` from the striker, positions ``u`` down (m)::

    m_i u_i'' = F_{i-1} - F_i + m_i g + P delta_{i1},   F_j = A [u_j - u_{j+1}]_+^(3/2)
    (j = 0..N-2),   F_{N-1} = wall law at [u_{N-1}]_+,   F_{-1} = 0,

with ``P`` the device's preload on bead 1, plus, when ``damping > 0``, the damping of the
device's dissipation law (:mod:`ssw.chain.dissipation`: ``c g(d) d'``, ``g`` 1, ``sqrt(d)``
or the elastic force) in every closed contact, ``d' = v_j - v_{j+1}`` (``v_{N-1}`` at the
wall) evaluated at the new time's velocity, predicted as ``v_{n+1/2} + dt/2 a_n``, which
keeps the scheme second order. The striker
speed, the preload and the masses may differ from scene to scene
(:class:`ssw.chain.params.Batch`: a calibration scan advances many parameter sets in one
run). The last contact is any wall: a law of the indentation (:class:`ssw.chain.wall.Wall`)
or a wall with internal state (:class:`ssw.chain.wall.StatefulWall`: the reduced and the
FEM dynamic walls, the plastic sample), advanced after each drift; every device field acts
the same way whatever the wall.

Method: velocity Verlet (Stormer-Verlet; Hairer, Lubich & Wanner 2006, *Geometric Numerical
Integration*, sec. I.1.4): explicit, second order, one force evaluation per step; near a
contact's opening or closing the Hertz force and the damping's factor are averaged along
the step's relative motion (:mod:`ssw.chain.impulse`), so that the discrete solution is
smooth in its parameters. Its energy error stays small (the rattling beads lose 2e-5 of
the striker's energy over 3 ms at 80 steps per contact, ``tests/test_device.py``) and the
TOF converges as ``dt^2``. The step is a
fixed fraction of the shortest Hertz contact time at the striker speed (Johnson 1985,
eq. 11.24) of two beads and of the last bead on a rigid flat (:func:`time_step`), so that
it depends on the chain alone. Every scene shares the step (the shortest of the batch's
scenes when their striker speeds or masses differ), so a whole sweep advances as
(N, n_scenes) arrays; at the default 80 steps per contact time the TOF is within 8e-5 of
an independent DOP853 solution over the thesis sweep (10 MPa; within 3.4e-5 above it;
``tests/test_chain_order.py``, ``ssw bench chain``).

The sensor signal is what the device's sensor reads (``ChainParams.sensor_reads``): the mean
of the sensor particle's two contact forces, or its upper or lower one. Its dense output and
the TOF on it: :mod:`ssw.chain.dense`.

Forward sensitivities (``derivatives=``, :mod:`ssw.chain.sensitivity`): the derivatives of
``u`` and ``v`` with respect to ``k`` parameters, (N, n, k), advanced by the same step
differentiated line by line, from the derivatives of the initial statics
(:func:`ssw.chain.statics.initial_tangent`); the run keeps the sensor's, ``Run.dsensor``.
They cost nothing when not asked. On request a run also carries the step's own column
(:data:`ssw.chain.sensitivity.STEP`): its derivative with respect to ``dt`` at a fixed
number of steps, for the chain rule through :func:`time_step` (:func:`step_tangent`).

The step's arithmetic (forces, damping, accelerations, kicks, drift, sensitivities, the
sensor's record and the peaks) and the stop rule's are one compiled kernel,
:mod:`ssw.chain.kernel`; this module drives it (:func:`simulate`: the run's set-up, then
its loop of blocks) and keeps what varies by wall and the stop rule's state; the records
are :mod:`ssw.chain.recording`'s. When nothing is done in Python between two steps (the step
evaluates the wall's law, no force or energy record), a block of ``check_every`` steps is
one call of the kernel.

Early stop. Every ``check_every`` steps each scene's record is inspected; a scene stops when
(1) its incident pulse has passed the sensor (the sensor signal fell below 30 % of its peak),
(2) the wall force has peaked and fallen below 35 % of its peak above the static force
(the first wall contact is over: every reflected pulse has left the wall), and (3) the
time since then exceeds 1.5 x the measured sensor-to-wall travel time (incident peak at
the sensor to the wall force's onset, plus one contact time) plus four contact times (the
slower, weaker reflected pulses have passed the sensor). Stopped scenes are removed from
the arrays.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ssw.chain.dissipation import law_of
from ssw.chain.kernel import Stepper, stop_update
from ssw.chain.params import Batch, ChainParams
from ssw.chain.recording import Recorder
from ssw.chain.sensitivity import STEP, Tangent, tangent_of
from ssw.chain.statics import (
    initial_state,
    initial_tangent,
    static_contact_forces,
)
from ssw.chain.wall import Wall, force_and_tangent, is_stateful
from ssw.errors import ConfigError

#: Fall of the sensor signal (share of its peak) that ends the incident pulse.
INCIDENT_END = 0.3
#: Fall of the wall force (share of its peak above the static force) that ends the first
#: wall contact. Soft soils keep the bottom bead pressed after the hit (the chain's weight
#: plus its rebound), so the force does not return to its static value: 0.35 of the peak.
WALL_RELEASE = 0.35
#: Travel-time factor and contact times waited after the wall release.
TRAVEL_FACTOR, TAIL_CONTACTS = 1.5, 4.0
#: Share of the two-bead impact force below which a signal counts as noise for stopping.
NOISE_SHARE = 0.01
#: The rule's constants, in the order of :func:`ssw.chain.kernel.stop_update`.
_RULE = np.array([INCIDENT_END, WALL_RELEASE, TRAVEL_FACTOR, TAIL_CONTACTS])


@dataclass(frozen=True)
class Run:
    """The record of a batched run. SI units; ``n`` scenes, ``k`` parameters.

    Parameters
    ----------
    t : numpy.ndarray
        (n_t,) s.
    sensor : numpy.ndarray
        (n_t, n) N, the sensor signal (``ChainParams.sensor_reads``: the mean of the sensor
        particle's two contact forces, or one of them; static precompression included),
        NaN after a scene stopped.
    wall_force : numpy.ndarray
        (n_t, n) N.
    forces : numpy.ndarray or None
        (n_t, n, N) N: contacts 0..N-2 and the wall.
    energy : numpy.ndarray or None
        (n_t, n) J: kinetic + elastic - the work potential of gravity and the preload +
        what left the chain (a stateful wall's stored and dissipated energy instead of a
        potential; the contacts' damping work): constant up to the integrator's error.
    peak_wall_indentation : numpy.ndarray
        (n,) m, the largest ``u_{N-1}``.
    stop_time : numpy.ndarray
        (n,) s (NaN: ran to the end).
    dt : float
        s, the step.
    energy_wall : numpy.ndarray or None
        (n_t, n) J, what a stateful wall stores (with ``record_energy``).
    dissipated : numpy.ndarray or None
        (n_t, n) J, what left the chain for good: the wall's dissipated or radiated energy
        and the contacts' damping work (with ``record_energy``).
    tangent : Tangent or None
        The parameters of the sensitivities.
    dsensor : numpy.ndarray or None
        (n_t, n, k) N per unit of each parameter: the derivative of ``sensor`` at every
        step (the dense output's, :mod:`ssw.chain.dense`, at any time).
    peak_contact_force : numpy.ndarray or None
        (n,) N, the largest force of any bead-bead contact over the run (the beads' own
        load: the striker's impact, the solitary wave, the waves meeting near the wall).
    """

    t: np.ndarray
    sensor: np.ndarray
    wall_force: np.ndarray
    forces: np.ndarray | None
    energy: np.ndarray | None
    peak_wall_indentation: np.ndarray
    stop_time: np.ndarray
    dt: float
    energy_wall: np.ndarray | None = None
    dissipated: np.ndarray | None = None
    tangent: Tangent | None = None
    dsensor: np.ndarray | None = None
    peak_contact_force: np.ndarray | None = None

    def take(self, idx: np.ndarray) -> Run:
        """The scenes ``idx`` (an index array) of the record.

        Parameters
        ----------
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        Run
            The record of the selected scenes (the time axis unchanged).
        """
        def sel(x: np.ndarray | None, axis: int) -> np.ndarray | None:
            return None if x is None else np.take(x, idx, axis=axis)

        return replace(self, sensor=self.sensor[:, idx], wall_force=self.wall_force[:, idx],
                       forces=sel(self.forces, 1), energy=sel(self.energy, 1),
                       peak_wall_indentation=self.peak_wall_indentation[idx],
                       stop_time=self.stop_time[idx], energy_wall=sel(self.energy_wall, 1),
                       dissipated=sel(self.dissipated, 1), dsensor=sel(self.dsensor, 1),
                       peak_contact_force=sel(self.peak_contact_force, 0))


def impact_scales(params: ChainParams | Batch) -> tuple[np.ndarray, np.ndarray]:
    """Peak overlap and force of the striker meeting bead 1 (Hertz).

    Parameters
    ----------
    params : ChainParams or Batch
        The chain.

    Returns
    -------
    tuple
        ``(d_max, F_max)``: m and N; floats for a ChainParams, (n,) arrays for a Batch.
    """
    b = params if isinstance(params, Batch) else Batch.of(params, 1)
    m0, m1 = b.masses[:, 0], b.masses[:, 1]
    m_eff = m0 * m1 / (m0 + m1)
    A = b.params.bead_coefficient
    d_max = (5.0 * m_eff * b.striker_velocity**2 / (4.0 * A)) ** 0.4
    f = A * d_max**1.5
    if isinstance(params, Batch):
        return d_max, f
    return float(d_max[0]), float(f[0])


def sensor_reading(params: ChainParams, f_upper: np.ndarray, f_lower: np.ndarray
                   ) -> np.ndarray:
    """The sensor's signal from the forces of its upper and lower contacts.

    Parameters
    ----------
    params : ChainParams
        The chain (``sensor_reads``: mean, upper or lower).
    f_upper : numpy.ndarray
        N, the contact between beads ``s - 1`` and ``s``.
    f_lower : numpy.ndarray
        N, the contact between beads ``s`` and ``s + 1``.

    Returns
    -------
    numpy.ndarray
        N.
    """
    if params.sensor_reads == "upper":
        return np.asarray(f_upper, float)
    if params.sensor_reads == "lower":
        return np.asarray(f_lower, float)
    return 0.5 * (np.asarray(f_upper, float) + np.asarray(f_lower, float))


def time_step(params: ChainParams | Batch, wall: Wall) -> float:
    """``min(t_c bead-bead, t_c bead on a rigid flat, t_c bead on the wall) / steps_per_contact``.

    The rigid flat is the stiffest physical wall, so for every physical wall the step
    depends on the chain alone: a scene's TOF does not depend on the batch (chunk, MPI
    rank) it is computed in, as long as the batch's scenes share the striker speed and the
    masses (a Batch takes its shortest scene's step). Only a wall stiffer than rigid at the
    impact's overlap (``hertz_equivalent``) shortens the step further.

    Parameters
    ----------
    params : ChainParams or Batch
        The chain.
    wall : Wall
        The last contact (its ``hertz_equivalent``).

    Returns
    -------
    float
        s.
    """
    from ssw.hertz import contact_time as hertz_time

    b = params if isinstance(params, Batch) else Batch.of(params, 1)
    p = b.params
    d_ref = float(np.min(impact_scales(b)[0]))
    a_rigid = 4.0 / 3.0 * np.sqrt(p.bead_radius) / p.bead_compliance
    a_wall = max(float(np.max(wall.hertz_equivalent(d_ref))), a_rigid)
    t_wall = float(np.min(hertz_time(b.masses[:, -1], a_wall, b.striker_velocity)))
    return min(float(np.min(b.contact_time())), t_wall) / p.steps_per_contact


def _wall_equivalent(b: Batch, wall: Wall, d_ref: np.ndarray, a_rigid: float,
                     with_E: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per scene, the Hertz coefficient of :func:`time_step`'s wall term at the scene's own
    impact overlap ``d_ref`` (the rigid flat's, or the wall's where it is stiffer), its
    slope in ``d_ref`` and in the soil's modulus: ``he = F(d) / d^1.5``, ``dhe/dd = F'(d) /
    d^1.5 - 1.5 he / d``, ``dhe/dE = dF/dE / d^1.5`` (0 for the rigid flat)."""
    he, he_d, he_E = np.full(b.n, a_rigid), np.zeros(b.n), np.zeros(b.n)
    if not float(np.max(wall.hertz_equivalent(float(np.min(d_ref))))) > a_rigid:
        return he, he_d, he_E
    for i in range(b.n):  # a wall stiffer than a rigid flat: no physical wall is
        wi, d = wall.take(np.array([i])), float(d_ref[i])
        h = float(wi.hertz_equivalent(d)[0])
        if h > a_rigid:
            x = np.array([d])
            he[i] = h
            he_d[i] = float(wi.dforce_dd(x)[0]) / d**1.5 - 1.5 * h / d
            if with_E:
                he_E[i] = float(wi.dforce_dE(x)[0]) / d**1.5
    return he, he_d, he_E


def step_tangent(params: ChainParams | Batch, wall: Wall, dt: float,
                 names: tuple[str, ...]) -> np.ndarray:
    """The derivative of the time step (:func:`time_step`) with respect to each parameter,
    per scene: the chain rule's ``d dt / d theta`` for a TOF run at the step its parameters
    give.

    A scene's own step is ``min(t_bb, t_w) / steps_per_contact``, Hertz contact times
    ``t = 2.9432 (5 m / (4 A))^(2/5) v^(-1/5)`` (Johnson 1985, eq. 11.24) of the striker on
    bead 1 (``m = m0 m1 / (m0 + m1)``, ``A`` the beads') and of the last bead on a rigid flat
    (``m`` the last bead's, ``A`` the flat's, or the wall's Hertz equivalent at the impact's
    peak overlap ``d_ref = (5 m v^2 / (4 A))^(2/5)`` where that is stiffer), so ``d ln t =
    2/5 d ln m - 2/5 d ln A - 1/5 d ln v``. A batch takes its shortest step: a scene whose
    own step is the batch's moves it (ties: each scene as if alone, which is what a batch of
    scenes sharing their striker and masses gives), any other scene's step term is 0.

    Parameters
    ----------
    params : ChainParams or Batch
        The chain.
    wall : Wall
        The last contact (its ``hertz_equivalent``; ``dforce_dd``, ``dforce_dE`` for a wall
        stiffer than a rigid flat).
    dt : float
        s, the run's step (:func:`time_step` of the batch).
    names : tuple of str
        Names of :data:`ssw.chain.sensitivity.PARAMETERS`.

    Returns
    -------
    numpy.ndarray
        (n, len(names)) s per unit of each parameter.
    """
    from ssw.hertz import contact_time as hertz_time

    b = params if isinstance(params, Batch) else Batch.of(params, wall.n)
    p = b.params
    m0, m1, v = b.masses[:, 0], b.masses[:, 1], b.striker_velocity
    d_ref = impact_scales(b)[0]
    a_rigid = 4.0 / 3.0 * np.sqrt(p.bead_radius) / p.bead_compliance
    he, he_d, he_E = _wall_equivalent(b, wall, d_ref, a_rigid, "E" in names)
    t_bb = b.contact_time()
    t_w = hertz_time(b.masses[:, -1], he, v)
    own = np.minimum(t_bb, t_w) / p.steps_per_contact
    bb = t_bb <= t_w
    sets = own <= dt * (1.0 + 1e-12)
    s_d = he_d * d_ref / he  # d ln he / d ln d_ref
    # d ln m_eff per unit of m0 and of m1; d ln d_ref = 2/5 d ln m_eff + 4/5 d ln v
    lm0, lm1 = m1 / (m0 * (m0 + m1)), m0 / (m1 * (m0 + m1))
    sensor_is_1 = p.sensor_index == 1 and not p.uniform
    out = np.zeros((b.n, len(names)))
    for j, name in enumerate(names):
        if name == "striker_velocity":
            dln = np.where(bb, -0.2 / v, -0.2 / v - 0.4 * s_d * 0.8 / v)
        elif name == "striker_mass" or (name == "sensor_mass" and sensor_is_1):
            lm = lm0 if name == "striker_mass" else lm1
            dln = np.where(bb, 0.4 * lm, -0.4 * s_d * 0.4 * lm)
        elif name == "E":
            dln = np.where(bb, 0.0, -0.4 * he_E / he)
        else:
            continue
        out[:, j] = np.where(sets, own * dln, 0.0)
    return out


class _StopRule:
    """Per-scene state of the early-stop rule (module docstring), over the active scenes
    (:meth:`keep` drops the stopped ones): ``F`` (9, n) the rows :data:`FLOATS`, ``B``
    (2, n) :data:`FLAGS`, in the layout of :func:`ssw.chain.kernel.stop_update`."""

    FLOATS = ("sensor0", "wall0", "f_noise", "t_c", "inc_max", "t_inc", "t_onset", "w_max",
              "t_rel")
    FLAGS = ("inc_done", "released")

    def __init__(self, n: int, sensor0: np.ndarray, wall0: np.ndarray, f_noise: np.ndarray,
                 t_c: np.ndarray):
        self.F = np.zeros((len(self.FLOATS), n))
        self.F[:4] = sensor0, wall0, f_noise, t_c
        self.F[self.FLOATS.index("t_onset")] = np.nan
        self.B = np.zeros((len(self.FLAGS), n), bool)

    def keep(self, mask: np.ndarray) -> None:
        """Keep the scenes ``mask`` (bool over the active scenes)."""
        self.F = np.ascontiguousarray(self.F[:, mask])
        self.B = np.ascontiguousarray(self.B[:, mask])

    def update(self, times: np.ndarray, S: np.ndarray, W: np.ndarray) -> np.ndarray:
        """Digest a block (k, n_active) of sensor and wall forces; the scenes that may stop.

        With ``Sr = S - sensor0``, ``Wr = W - wall0`` (per scene): the incident peak
        ``inc_max`` (the largest ``Sr`` until the pulse is over) and its time ``t_inc``; the
        pulse is over once ``inc_max > f_noise`` and the block's last ``Sr`` is below
        ``INCIDENT_END inc_max``; ``t_onset``, the first time ``Wr > f_noise``; ``w_max``, the
        largest ``Wr`` until the wall releases: the pulse over, ``w_max > f_noise`` and the
        last ``Wr`` below ``WALL_RELEASE w_max`` (time ``t_rel``); a released scene may stop
        once ``t > t_rel + TRAVEL_FACTOR (t_onset - t_inc + t_c) + TAIL_CONTACTS t_c``
        (``t_onset - t_inc`` 0 without an onset). NaN samples count as the largest, as in
        numpy's ``max``. Evaluated by the step's compiled code
        (:func:`ssw.chain.kernel.stop_update`): one call per block instead of some twenty
        numpy calls, 4-5x less CPU for the few-scene runs of a calibration.
        """
        return stop_update(S, W, np.ascontiguousarray(times, float), _RULE, self.F, self.B)


def simulate(
    params: ChainParams | Batch,
    wall: Any,
    *,
    t_end: float | None = None,
    dt: float | None = None,
    stop_early: bool = True,
    record_forces: bool = False,
    record_energy: bool = False,
    check_every: int = 32,
    initial: tuple[np.ndarray, np.ndarray] | None = None,
    on_progress: Any = None,
    derivatives: Any = None,
) -> Run:
    """Integrate ``wall.n`` chains from the initial state of :mod:`ssw.chain.statics`.

    Parameters
    ----------
    params : ChainParams or Batch
        The chain; a :class:`ssw.chain.params.Batch` of ``wall.n`` scenes for per-scene
        striker speeds, preloads or masses.
    wall : Wall or StatefulWall
        The last-contact law, one per scene (:class:`ssw.chain.wall.Wall`), or a wall with
        internal state (:class:`ssw.chain.wall.StatefulWall`: advanced after each drift).
    t_end : float or None
        s, the end time (default ``params.t_max``).
    dt : float or None
        s, the step (default :func:`time_step`; a stateful wall built for a step, ``wall.dt``,
        must be run with it).
    stop_early : bool
        Stop each scene once its reflected pulses have passed the sensor.
    record_forces : bool
        Also keep every contact force.
    record_energy : bool
        Also keep the energy record (``energy``, ``energy_wall``, ``dissipated``).
    check_every : int
        Steps between stop checks.
    initial : tuple of numpy.ndarray or None
        ``(u, v)`` (m, m/s), shapes (n, N), instead of :func:`ssw.chain.statics.initial_state`.
    on_progress : callable or None
        Called as ``on_progress(k)`` when ``k`` more scenes have finished (a progress bar's
        update; ``ssw.progress``).
    derivatives : Tangent or str or sequence of str or None
        Parameters (:data:`ssw.chain.sensitivity.PARAMETERS`) whose forward sensitivities
        the run carries (``dsensor``), at the run's fixed step, and the step's own column
        (:data:`ssw.chain.sensitivity.STEP`) if named; None: none (no extra cost).

    Returns
    -------
    Run
        The record.

    Raises
    ------
    ConfigError
        Sensitivities asked of a stateful wall without ``advance_tangent`` (the step's
        column: without ``step_tangent``), or with an ``initial`` state, or with a wall
        step other than ``dt``.
    """
    n = wall.n
    b = params if isinstance(params, Batch) else Batch.of(params, n)
    if b.n != n:
        raise ValueError(f"batch of {b.n} scenes for a wall of {n}")
    stateful = is_stateful(wall)
    tg = tangent_of(derivatives)
    dt = _checked_step(b, wall, dt, tg, stateful, initial is not None)
    n_steps = int(np.ceil(float(t_end if t_end is not None else b.params.t_max) / dt - 1e-9))
    rule = _stop_rule(b)
    ch, drive = _start(b, wall, stateful, tg, dt, initial, record_energy)
    if ch.law is None:  # else the step evaluates the wall's law itself
        drive.write_row(ch)
    ch.forces(has_old=False, kick=False)
    rec = Recorder(b, ch, None if tg is None else tg.k, n_steps + 1, check_every,
                   record_forces, record_energy, dt)
    # blocks of check_every steps; when nothing is done in Python between the steps (the
    # step evaluates the wall's law, no force or energy record), a block is one call of the
    # compiled step
    in_c = not (stateful or ch.law is None or record_forces or record_energy)
    n_t, stop_time, peak_u, peak_f = _integrate(ch, drive, rec, rule, dt, n_steps,
                                                check_every, stop_early, in_c, on_progress)
    out = rec.rec.assemble(n_t)
    return Run(
        t=dt * np.arange(n_t), sensor=out["sensor"], wall_force=out["wall"],
        forces=np.moveaxis(out["forces"], 1, 2) if record_forces else None,
        energy=out.get("energy"), peak_wall_indentation=peak_u, stop_time=stop_time,
        dt=dt, energy_wall=out.get("energy_wall") if record_energy and stateful else None,
        dissipated=out.get("dissipated"), tangent=tg,
        dsensor=None if tg is None else np.moveaxis(out["dsensor"], 1, 2),
        peak_contact_force=peak_f,
    )


def _checked_step(b: Batch, wall: Any, dt: float | None, tg: Tangent | None, stateful: bool,
                  given_initial: bool) -> float:
    """The run's step (s): ``dt`` or :func:`time_step`; ConfigError for a stateful wall
    built for another step, or sensitivities the wall or the initial state cannot give
    (:func:`simulate`'s Raises)."""
    dt = float(dt if dt is not None else time_step(b, wall))
    wall_dt = getattr(wall, "dt", None)
    if wall_dt is not None and abs(wall_dt - dt) > 1e-15 * dt:
        raise ConfigError("dt", dt, f"the step the wall was built for ({wall_dt} s)")
    if tg is None:
        return dt
    if stateful and not hasattr(wall, "advance_tangent"):
        raise ConfigError("derivatives", list(tg.names),
                          f"none for the {type(wall).__name__} (no exact tangent: "
                          "differentiate its TOF by central differences, ssw.tof.api)")
    if given_initial:
        raise ConfigError("derivatives", list(tg.names), "none with a given initial state")
    if tg.col(STEP) is not None and stateful and not getattr(wall, "step_tangent", False):
        raise ConfigError("derivatives", list(tg.names),
                          f"none of the step ({STEP}) for the {type(wall).__name__} (its "
                          "advance_tangent does not differentiate the step)")
    return dt


def _stop_rule(b: Batch) -> _StopRule:
    """The early-stop rule's state at the run's start: the static sensor and wall forces,
    the noise level (:data:`NOISE_SHARE` of the two-bead impact force) and the contact
    times of the scenes ``b``."""
    p = b.params
    s = p.sensor_index
    F0 = static_contact_forces(b)  # (n, N)
    _, f_impact = impact_scales(b)
    return _StopRule(b.n, sensor_reading(p, F0[:, s - 1], F0[:, s]), F0[:, -1].copy(),
                     NOISE_SHARE * f_impact, b.contact_time())


class _WallDrive:
    """The last contact of a run's active scenes (:func:`simulate`): its law, or a stateful
    wall's state and force, their sensitivities, and the step's last contact row they
    write. ``u_last`` (n,) m, the last bead's initial position."""

    def __init__(self, wall: Any, stateful: bool, u_last: np.ndarray, tg: Tangent | None
                 ) -> None:
        self.w, self.stateful, self.tg = wall, stateful, tg
        self.c_E = None if tg is None else tg.col("E")
        # a wall with internal state advances it every step from the last bead's new
        # position; its force is then f, not force(u_last)
        self.state = wall.start(u_last.copy()) if stateful else None
        self.f = wall.force(u_last) if stateful else None
        self.tstate: Any = None
        self.df: np.ndarray | None = None
        self.dE_all = self.dE = np.zeros((wall.n, 0 if tg is None else tg.k))
        self.step_opt: dict[str, Any] = {}

    def start_tangent(self, u_last: np.ndarray, D_last: np.ndarray) -> None:
        """The sensitivities' start: ``D_last`` (n, k) the last bead's initial position's
        derivatives (m per unit of each parameter)."""
        tg, wall, c_E = self.tg, self.w, self.c_E
        assert tg is not None
        if c_E is not None:
            self.dE_all[:, c_E] = 1.0
        c_T = tg.col(STEP)
        # the step's column for a stateful wall: d dt / d column
        self.step_opt = {} if c_T is None else {"ddt": np.eye(tg.k)[c_T]}
        if self.stateful:
            self.tstate = wall.start_tangent(self.state, D_last, self.dE)
            self.df = wall.dforce_dd(u_last)[:, None] * D_last
            if c_E is not None:
                self.df[:, c_E] += wall.dforce_dE(u_last)

    def advance(self, ch: Any, dt: float) -> None:
        """A stateful wall's state over the step, to the last bead's new position."""
        u_last = ch.z[0, -1].copy()
        if self.tg is not None:
            self.f, self.df, self.state, self.tstate = self.w.advance_tangent(
                self.state, self.tstate, u_last, ch.ZT[0, -1], dt, self.dE, **self.step_opt)
        else:
            self.f, self.state = self.w.advance(self.state, u_last, dt)

    def write_row(self, ch: Any) -> None:
        """The wall's force (and its sensitivities) into the step's last contact row (not
        called when the step evaluates the wall's law itself)."""
        u_last = ch.z[0, -1]
        if self.f is not None:
            ch.f[-1] = self.f
            if self.tg is not None:
                ch.dF[-1] = self.df
        elif self.tg is None:
            ch.f[-1] = self.w.force(u_last)
        else:
            ch.f[-1], kd, kE = force_and_tangent(self.w, u_last, self.c_E is not None)
            np.multiply(ch.ZT[0, -1], np.asarray(kd)[:, None], out=ch.dF[-1])
            if self.c_E is not None:
                ch.dF[-1, :, self.c_E] += kE

    def keep(self, keep: np.ndarray, active: np.ndarray, in_c: bool) -> None:
        """Keep the scenes ``keep`` (bool over the active scenes; ``active`` the run's
        indices of those kept); the law itself too unless the step holds it (``in_c``)."""
        idx = np.flatnonzero(keep)
        if self.tg is not None:
            self.dE = self.dE_all[active]
            if self.stateful:
                self.df = self.df[keep]
                self.tstate = tuple(x[idx] for x in self.tstate)
        if self.stateful:
            self.state = self.w.take_state(self.state, idx)
            self.f = self.f[keep]
        if not in_c:  # else the step's own law rows were kept (ch.keep)
            self.w = self.w.take(idx)


def _start(b: Batch, wall: Any, stateful: bool, tg: Tangent | None, dt: float,
           initial: tuple[np.ndarray, np.ndarray] | None, record_energy: bool
           ) -> tuple[Stepper, _WallDrive]:
    """The compiled step at the run's initial state (:mod:`ssw.chain.statics`, or
    ``initial``) with its sensitivities, and the wall's drive; a piecewise-linear wall's law
    (``step_law``) or a Hertzian power law (``step_power_law``) goes into the step unless the E
    sensitivity needs what it lacks."""
    p, n = b.params, b.n
    N, s = p.n_beads, p.sensor_index
    damping, law = p.damping, law_of(p.damping_law, "chain.damping_law")
    # internal layout (N, n_scenes): every bead's row is contiguous
    u0, v0 = initial if initial is not None else initial_state(b, wall)
    u_last = np.ascontiguousarray(u0[:, -1])
    drive = _WallDrive(wall, stateful, u_last, tg)

    def col(name: str) -> int:
        """The tangent's column of ``name``; -1 where it carries none."""
        c = None if tg is None else tg.col(name)
        return -1 if c is None else c

    mass_at: list[tuple[int, int]] = []
    if tg is not None:
        # (bead, column) of the masses differentiated: the striker's, the sensor's
        c_ms = None if p.uniform else tg.col("sensor_mass")
        mass_at = [(i, c) for i, c in ((0, tg.col("striker_mass")), (s, c_ms))
                   if c is not None]
        ZT = np.empty((2, N, n, tg.k))
        ZT[0], ZT[1] = initial_tangent(b, wall, u0, tg)
        drive.start_tangent(u_last, ZT[0, -1])
    consts = dict(A=p.bead_coefficient, dt=dt, damping=damping, law=law.code,
                  g=p.g if p.gravity else 0.0, predict=damping > 0.0 or col("damping") >= 0,
                  damped_tangent=tg is not None and damping > 0.0, c_D=col("damping"),
                  c_P=col("preload"), c_E=col("E"), c_T=col(STEP), mass_at=mass_at)
    preload = b.preload.copy()
    ch = Stepper(N, n, 0 if tg is None else tg.k, consts,
                 np.ascontiguousarray((1.0 / b.masses).T),
                 preload if bool(np.any(preload > 0)) else None,
                 record_energy and damping > 0.0)
    ch.z[0], ch.z[1] = u0.T, v0.T
    if tg is not None:
        ch.ZT[...] = ZT
    # a piecewise-linear law or a Hertzian power law is evaluated by the step itself (a
    # block of steps in one call); without its E derivatives, the E sensitivity goes
    # through force_and_tangent, which says so
    step_law = None if stateful else getattr(wall, "step_law", lambda: None)()
    power = None if stateful else getattr(wall, "step_power_law", lambda: None)()
    if step_law is not None and (drive.c_E is None or step_law[3] is not None):
        ch.use_law(step_law)
    elif power is not None and (drive.c_E is None or power[2] is not None):
        ch.use_power_law(*power)
    return ch, drive


def _integrate(ch: Stepper, drive: _WallDrive, rec: Recorder, rule: _StopRule, dt: float,
               n_steps: int, check_every: int, stop_early: bool, in_c: bool,
               on_progress: Any) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """The run's loop: blocks of ``check_every`` steps (steps ``j0 .. step``, in one call of
    the compiled step when ``in_c``), each recorded, then the stop rule, whose stopped
    scenes leave the arrays. Returns the rows of the run, each scene's stop time (s, NaN:
    ran to the end), peak wall indentation (m) and peak bead-bead force (N)."""
    n = ch.z.shape[-1]
    active = np.arange(n)
    peak_u, peak_f, stop_time = np.empty(n), np.empty(n), np.full(n, np.nan)
    rec.row(0, active, ch, drive.w, drive.state, drive.stateful)
    rec.flush(0, 1, active)
    writes_wall = ch.law is None
    step, j0 = 0, 1
    while j0 <= n_steps:
        rows = min(check_every, n_steps - j0 + 1)
        step = j0 + rows - 1
        if in_c:
            ch.advance(rows)
        for k in range(0 if in_c else rows):
            ch.drift()
            if drive.stateful:
                drive.advance(ch, dt)
            if writes_wall:
                drive.write_row(ch)
            ch.forces(has_old=True, kick=True)
            rec.damping_work(ch)
            rec.row(k, active, ch, drive.w, drive.state, drive.stateful)
        got = rec.flush(j0, rows, active)
        times = dt * np.arange(j0, step + 1)
        j0 = step + 1
        if not stop_early:
            continue
        done = rule.update(times, got["sensor"], got["wall"])
        if not np.any(done):
            continue
        if on_progress is not None:
            on_progress(int(np.count_nonzero(done)))
        stop_time[active[done]] = times[-1]
        keep = ~done
        rule.keep(keep)
        peak_u[active[done]] = ch.peak_u[done]
        peak_f[active[done]] = ch.peak_f[:, done].max(axis=0)
        active = active[keep]
        if active.size == 0:
            break
        ch.keep(keep)
        rec.keep(keep)
        drive.keep(keep, active, in_c)
    if active.size:
        peak_u[active] = ch.peak_u
        peak_f[active] = ch.peak_f.max(axis=0)
    return step + 1, stop_time, peak_u, peak_f
