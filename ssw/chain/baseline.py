"""Reference solution of the chain: the same equations, solved with scipy's DOP853.

The yardstick of ``ssw bench chain`` and of the integrator's order test
(``tests/test_chain_order.py``): an independent solve of the model of
:mod:`ssw.chain.integrate` (same equations, a different method)::

    m_i u_i'' = F_{i-1} - F_i + m_i g + P delta_{i1},   F_j = A [u_j - u_{j+1}]_+^(3/2)
    (+ c g_j (v_j - v_{j+1}) while closed),   F_{N-1} = C_w [u_{N-1}]_+^n_w (+ c g v_{N-1}),

``P`` the preload on bead 1, ``c g d'`` the contacts' damping by the device's law
(:mod:`ssw.chain.dissipation`: ``g`` 1, ``sqrt(d)`` or the contact's elastic force, at its
point value); the sensor reads the mean of its
two contact forces, or its upper (``F_{s-1}``) or lower (``F_s``) one. It is
self-contained where sharing code could hide an error in :mod:`ssw.chain` (a wrong
precompression or a peak-location bias shared by both sides would cancel in a
comparison):

* **equations** from the raw parameters: masses ``4/3 pi R^3 rho`` (striker and sensor
  overrides), the bead-bead Hertz coefficient ``A = E sqrt(2R) / (3 (1 - nu^2))`` (two
  equal spheres: ``R_eff = R/2``, ``E* = E / (2 (1 - nu^2))``; Johnson 1985, eq. 4.22-4.23),
  and :func:`hertz_wall` for the bead on an elastic half-space
  ``A_w = 4/3 sqrt(R) / ((1 - nu_b^2)/E_b + (1 - nu^2)/E)``; a wall may also be given as
  ``(coef, exponent)`` arrays or any object with ``coef``/``exponent`` (a
  `ssw.chain.wall.PowerWall`): then only the law's two numbers come from ssw;
* **initial state** (:func:`static_state`): its own static equilibrium (contact ``j >= 1``
  carries ``P + g sum_{k=1..j} m_k``, the wall ``P + g sum_{k=1..N-1} m_k``, ``P`` the
  preload on bead 1), checked against the right-hand side (beads 1..N-1 at rest);
* **time of flight** (:func:`tof_rule`): the sensor force and its exact time derivative
  ``dF_j/dt = 3/2 A sqrt(d_j) (v_j - v_{j+1})`` (+ ``c (g' d'^2 + g (a_j - a_{j+1}))``) are
  sampled
  from DOP853's dense output, and each peak is located as the root of the cubic Hermite
  interpolant's derivative between the two samples where ``dF/dt`` changes sign (no
  parabola through three force samples, nor the quintic dense output of
  :mod:`ssw.chain.dense`). The rule that chooses the peaks is :mod:`ssw.signal.rule`'s
  (its thresholds are read from there: the rule is the TOF's definition, not a
  computation), applied here to the continuous maxima.

Nothing of :mod:`ssw.chain.integrate`, :mod:`ssw.chain.statics`, :mod:`ssw.chain.tof`,
:mod:`ssw.chain.dense`, :mod:`ssw.walls` or :mod:`ssw.hertz` is used. What remains shared
is the :class:`ssw.chain.params.ChainParams` record (its numbers), the peak rule's three
thresholds and, when a ``PowerWall`` is passed, the wall's coefficient and exponent (the
model's input).

The method: the adaptive explicit Runge-Kutta 8(5,3) of Dormand & Prince (Hairer, Norsett &
Wanner 1993, *Solving ODEs I*, sec. II.10), ``scipy.integrate.DOP853`` stepped by hand so
that only the sensor samples are kept (a whole sweep can be one batched system). State
``y = [u, v]``, bead-major ``(N, n_scenes)`` blocks. Error control per component:
``|err| <= atol + rtol |y|``; the default ``atol`` is ``rtol`` times the impact scales
(the two-bead peak overlap for ``u``, the striker speed for ``v``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ssw.chain.params import ChainParams
from ssw.errors import ConfigError, RecordingError, SolverError
from ssw.signal.rule import RULE

#: Largest static acceleration (share of g, or of the preload's) the initial state may
#: leave on beads 1..N-1: the equilibrium is exact up to rounding.
STATIC_TOL = 1e-8


@dataclass(frozen=True)
class ChainModel:
    """The equations of motion, as numbers. SI units; ``n`` scenes share the chain.

    Parameters
    ----------
    masses : numpy.ndarray
        (N,) kg.
    A : float
        N/m^1.5, bead-bead.
    wall_coef : numpy.ndarray
        (n,) N/m^wall_exp.
    wall_exp : numpy.ndarray
        (n,) -.
    g : float
        m/s^2 (0 without gravity).
    preload : float
        N on bead 1.
    damping : float
        The dissipation coefficient (the law's unit).
    sensor : int
        The sensor's index.
    reads : str
        ``mean|upper|lower``.
    v0 : float
        m/s, the striker's speed.
    law : str
        The dissipation law (``dashpot``, ``kuwabara_kono``, ``hunt_crossley``).
    """

    masses: np.ndarray
    A: float
    wall_coef: np.ndarray
    wall_exp: np.ndarray
    g: float
    preload: float
    damping: float
    sensor: int
    reads: str
    v0: float
    law: str = "dashpot"

    @property
    def n(self) -> int:
        """Number of scenes (the wall laws' count)."""
        return int(self.wall_coef.size)

    @property
    def hertzian(self) -> bool:
        """Every wall exponent is 1.5 (``d sqrt(d)`` instead of a power)."""
        return bool(np.all(self.wall_exp == 1.5))

    @property
    def inv_masses(self) -> np.ndarray:
        """Inverse masses (1/kg), one per bead."""
        return 1.0 / self.masses

    @property
    def N(self) -> int:
        """Number of beads (the striker included)."""
        return int(self.masses.size)


@dataclass(frozen=True)
class BaselineResult:
    """The reference's peaks and work.

    Parameters
    ----------
    tof : numpy.ndarray
        (n,) s.
    t_incident : numpy.ndarray
        (n,) s.
    t_reflected : numpy.ndarray
        (n,) s.
    t : numpy.ndarray
        (n_t,) s, the sample times.
    sensor : numpy.ndarray
        (n_t, n) N, the sensor force (NaN after a scene's own ``t_end``).
    nfev : int
        Right-hand-side evaluations.
    steps : int
        Accepted steps.
    """

    tof: np.ndarray
    t_incident: np.ndarray
    t_reflected: np.ndarray
    t: np.ndarray
    sensor: np.ndarray
    nfev: int
    steps: int


def hertz_wall(params: ChainParams, soil_E: Any, soil_nu: Any) -> tuple[np.ndarray, np.ndarray]:
    """Bead on an elastic half-space, ``F = A_w d^1.5`` (Johnson 1985, eq. 4.23).

    ``A_w = 4/3 sqrt(R) E*``, ``1/E* = (1 - nu_b^2)/E_b + (1 - nu^2)/E``.

    Parameters
    ----------
    params : ChainParams
        The chain (its bead's numbers).
    soil_E : array_like
        Pa, broadcast with ``soil_nu``, flattened.
    soil_nu : array_like
        -.

    Returns
    -------
    tuple of numpy.ndarray
        ``(A_w, 1.5)``: (n,) N/m^1.5 and (n,) -.
    """
    E, nu = np.broadcast_arrays(np.asarray(soil_E, float), np.asarray(soil_nu, float))
    inv = (1.0 - params.bead_nu**2) / params.bead_E + (1.0 - nu.ravel() ** 2) / E.ravel()
    coef = 4.0 / 3.0 * np.sqrt(params.bead_radius) / inv
    return coef, np.full(coef.size, 1.5)


def chain_model(params: ChainParams, wall: Any) -> ChainModel:
    """The model of ``params`` with ``wall``.

    Parameters
    ----------
    params : ChainParams
        The chain (its numbers only).
    wall : tuple or object
        ``(coef, exponent)`` (n,) arrays or an object with them (a PowerWall).

    Returns
    -------
    ChainModel
        The equations, as numbers.
    """
    if isinstance(wall, tuple):
        coef, expo = wall
    elif hasattr(wall, "coef") and hasattr(wall, "exponent"):
        coef, expo = wall.coef, wall.exponent
    else:
        raise ConfigError("wall", type(wall).__name__,
                          "a power law (coef, exponent) or a PowerWall (rigid, hertz, fit)")
    coef = np.atleast_1d(np.asarray(coef, float))
    expo = np.broadcast_to(np.asarray(expo, float), coef.shape).copy()
    R, rho = params.bead_radius, params.bead_density
    m = np.full(params.n_beads, 4.0 / 3.0 * np.pi * R**3 * rho)
    if params.striker_mass is not None:
        m[0] = params.striker_mass
    if params.sensor_mass is not None and not params.uniform:
        m[params.sensor_index] = params.sensor_mass
    A = params.bead_E * np.sqrt(2.0 * R) / (3.0 * (1.0 - params.bead_nu**2))
    return ChainModel(
        masses=m, A=float(A), wall_coef=coef, wall_exp=expo,
        g=params.g if params.gravity else 0.0, preload=float(getattr(params, "preload", 0.0)),
        damping=float(params.damping), sensor=params.sensor_index,
        reads=str(getattr(params, "sensor_reads", "mean")), v0=params.striker_velocity,
        law=str(getattr(params, "damping_law", "dashpot")),
    )


def _factor(law: str, d: np.ndarray, f_el: np.ndarray) -> tuple[Any, Any]:
    """The law's damping factor ``g`` of closed contacts (overlap ``d > 0``, elastic force
    ``f_el``) and its slope ``dg/dd`` per unit of ``df_el/dd``'s factor (``hunt_crossley``:
    the caller's ``df_el/dd``): ``(1, 0)``, ``(sqrt(d), 1 / (2 sqrt(d)))``, ``(f_el, 1)``."""
    if law == "kuwabara_kono":
        sq = np.sqrt(d)
        return sq, 0.5 / np.where(sq > 0, sq, np.inf)
    if law == "hunt_crossley":
        return f_el, 1.0
    return 1.0, 0.0


def _forces(mod: ChainModel, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Contact forces (N), contacts 0..N-2 and the wall (row N-1); ``u, v`` (N, ...)."""
    f = np.empty_like(u)
    d = np.subtract(u[:-1], u[1:], out=f[:-1])
    np.maximum(d, 0.0, out=d)
    if mod.damping:
        closed = d > 0
        overlap = d.copy() if mod.law == "kuwabara_kono" else None
    d *= np.sqrt(d)
    d *= mod.A
    w = np.maximum(u[-1], 0.0)
    shape = (-1,) + (1,) * (u.ndim - 2)
    coef = mod.wall_coef.reshape(shape)
    f[-1] = coef * w * np.sqrt(w) if mod.hertzian else coef * w ** mod.wall_exp.reshape(shape)
    if mod.damping:
        g_c = _factor(mod.law, overlap, f[:-1])[0] if mod.law != "dashpot" else 1.0
        g_w = _factor(mod.law, w, f[-1])[0] if mod.law != "dashpot" else 1.0
        f[:-1] += mod.damping * g_c * (v[:-1] - v[1:]) * closed
        f[-1] += mod.damping * g_w * v[-1] * (w > 0)
    return f


def _acceleration(mod: ChainModel, u: np.ndarray, v: np.ndarray,
                  out: np.ndarray | None = None) -> np.ndarray:
    """``a_i = (F_{i-1} - F_i + P delta_{i1}) / m_i + g`` (m/s^2), shape of ``u``."""
    f = _forces(mod, u, v)
    net = np.negative(f, out=out)
    net[1:] += f[:-1]
    net[1] += mod.preload
    net *= mod.inv_masses.reshape((-1,) + (1,) * (u.ndim - 1))
    net += mod.g
    return net


def static_state(mod: ChainModel) -> tuple[np.ndarray, np.ndarray]:
    """Beads 1..N-1 in static equilibrium under gravity and the preload, the striker
    touching bead 1 at the striker speed.

    Parameters
    ----------
    mod : ChainModel
        The equations.

    Returns
    -------
    tuple of numpy.ndarray
        Initial ``u`` (m) and ``v`` (m/s), shapes (N, n).

    Raises
    ------
    SolverError
        The state leaves beads 1..N-1 accelerating (a defect of this function).
    """
    N, n = mod.N, mod.n
    load = mod.preload + mod.g * np.cumsum(mod.masses[1:])  # contacts 1..N-2, then the wall
    u = np.zeros((N, n))
    u[-1] = (load[-1] / mod.wall_coef) ** (1.0 / mod.wall_exp)
    for j in range(N - 2, 0, -1):  # contact j joins beads j, j+1
        u[j] = u[j + 1] + (load[j - 1] / mod.A) ** (2.0 / 3.0)
    u[0] = u[1]
    v = np.zeros((N, n))
    v[0] = mod.v0
    a = _acceleration(mod, u, np.zeros_like(v))
    scale = mod.g + mod.preload / mod.masses[1]
    if scale > 0 and np.max(np.abs(a[1:])) > STATIC_TOL * scale:
        raise SolverError(f"static state not in equilibrium: |a| = {np.max(np.abs(a[1:])):.3e}")
    return u, v


def _sensor(mod: ChainModel, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sensor force (N) and its time derivative (N/s) for states ``u, v`` (N, n, m).

    A contact's force is ``A d^1.5`` plus, with damping, ``c g (v_j - v_{j+1})`` while
    closed (what a force sensor in the contact feels); its rate ``3/2 A sqrt(d) d'`` plus
    ``c (g' d'^2 + g (a_j - a_{j+1}))``.
    """
    s = mod.sensor
    acc = _acceleration(mod, u, v) if mod.damping else None

    def contact(j: int) -> tuple[np.ndarray, np.ndarray]:
        d = np.maximum(u[j] - u[j + 1], 0.0)
        dv = v[j] - v[j + 1]
        f, r = mod.A * d**1.5, 1.5 * mod.A * np.sqrt(d) * dv
        if acc is not None:
            g, g1 = _factor(mod.law, d, f)
            if mod.law == "hunt_crossley":
                g1 = 1.5 * mod.A * np.sqrt(d)
            closed = d > 0
            r = r + mod.damping * (g1 * dv * dv + g * (acc[j] - acc[j + 1])) * closed
            f = f + mod.damping * g * dv * closed
        return f, r

    (fu, ru), (fl, rl) = contact(s - 1), contact(s)
    if mod.reads == "upper":
        return fu, ru
    if mod.reads == "lower":
        return fl, rl
    return 0.5 * (fu + fl), 0.5 * (ru + rl)


def _hermite_peak(s0, s1, r0, r1, h):
    """Maximum of the cubic Hermite interpolant on ``[0, h]`` with values ``s0, s1`` and
    slopes ``r0 > 0 >= r1``: (offset in s, value).

    Its derivative in ``th = t / h`` is the quadratic ``m0 + 2 c2 th + 3 c3 th^2``, positive
    at 0 and ``m1 <= 0`` at 1: the maximum is its first root in ``(0, 1]``, in closed form
    (the cancellation-free pair ``q / a``, ``c / q``; Press et al. 2007, sec. 5.6)."""
    m0, m1, dl = h * r0, h * r1, s1 - s0
    c2, c3 = 3.0 * dl - 2.0 * m0 - m1, m0 + m1 - 2.0 * dl
    a, b = 3.0 * c3, 2.0 * c2
    q = -0.5 * (b + np.copysign(np.sqrt(np.maximum(b * b - 4.0 * a * m0, 0.0)), b))
    with np.errstate(divide="ignore", invalid="ignore"):
        roots = np.stack([m0 / q, q / a])
    roots = np.where((roots > 0) & (roots <= 1), roots, np.inf)
    th = np.minimum(np.min(roots, axis=0), 1.0)
    return th * h, s0 + m0 * th + c2 * th**2 + c3 * th**3


def tof_rule(h: float, S: np.ndarray, R: np.ndarray) -> tuple[float, float]:
    """Incident and reflected peak times (s) of one sensor record.

    Parameters
    ----------
    h : float
        s, the sample step (sample ``k`` at ``k h``).
    S : numpy.ndarray
        (n_t,) N, the sensor force, ``S[0]`` the static baseline.
    R : numpy.ndarray
        (n_t,) N/s, its exact time derivative.

    Returns
    -------
    tuple of float
        The incident and reflected peak times (s).

    Raises
    ------
    RecordingError
        No incident or no reflected peak.
    """
    s = S - S[0]
    k = np.flatnonzero((R[:-1] > 0) & (R[1:] <= 0))  # a maximum inside [t_k, t_k+1]
    if k.size == 0:
        raise RecordingError("reference: the sensor force has no maximum")
    off, val = _hermite_peak(s[k], s[k + 1], R[k], R[k + 1], h)
    t_pk = k * h + off
    top = max(float(s.max()), float(val.max()))
    inc = np.flatnonzero(val >= RULE.incident_fraction * top)
    if top <= 0 or inc.size == 0:
        raise RecordingError("reference: no incident peak")
    i = inc[0]
    below = np.flatnonzero((np.arange(s.size) > k[i]) & (s < RULE.gap_fraction * val[i]))
    if below.size == 0:
        raise RecordingError("reference: the incident pulse does not end")
    kg = below[0]
    after = k >= kg
    wmax = max(float(s[kg:].max()), float(val[after].max()) if after.any() else -np.inf)
    ref = np.flatnonzero(after & (val >= RULE.split_fraction * wmax))
    if wmax <= 0 or ref.size == 0:
        raise RecordingError("reference: no reflected peak")
    return float(t_pk[i]), float(t_pk[ref[0]])


def solve_dop853(
    params: ChainParams,
    wall: Any,
    *,
    t_end: Any,
    rtol: float = 1e-9,
    atol: Any = None,
    sample_dt: float = 1e-6,
) -> BaselineResult:
    """Solve ``n`` scenes (one batched system) with DOP853 and pick their TOF.

    Parameters
    ----------
    params : ChainParams
        The chain (its numbers only).
    wall : tuple or object
        ``(coef, exponent)`` (n,) arrays, or an object with ``coef``/``exponent`` (a
        PowerWall): ``F = coef [d]_+^exponent`` (N, m).
    t_end : float or numpy.ndarray
        s, scalar or (n,): each scene's record ends there (the system runs to the largest).
    rtol : float
        Relative tolerance.
    atol : float or numpy.ndarray or None
        Absolute tolerance, scalar or (2 N n,) (m for ``u``, m/s for ``v``); default
        ``rtol`` x (peak two-bead overlap, striker speed).
    sample_dt : float
        s, the sensor's sample step.

    Returns
    -------
    BaselineResult
        Peaks, TOF, record and work.

    Raises
    ------
    SolverError
        DOP853 failed.
    RecordingError
        A record without its peaks.
    """
    from scipy.integrate import DOP853

    mod = chain_model(params, wall)
    N, n = mod.N, mod.n
    t_ends = np.broadcast_to(np.asarray(t_end, float), (n,))
    if not (np.all(t_ends > 0) and np.isfinite(t_ends).all()):
        raise ConfigError("t_end", t_end, "times > 0 s")
    if not (0 < rtol < 1) or not (0 < sample_dt < t_ends.min()):
        raise ConfigError("rtol/sample_dt", (rtol, sample_dt), "0 < rtol < 1, 0 < dt < t_end")
    if atol is None:
        m_eff = mod.masses[0] * mod.masses[1] / (mod.masses[0] + mod.masses[1])
        d_imp = (5.0 * m_eff * mod.v0**2 / (4.0 * mod.A)) ** 0.4  # Johnson eq. 11.22
        atol = rtol * np.concatenate([np.full(N * n, d_imp), np.full(N * n, mod.v0)])
    u0, v0 = static_state(mod)

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        dy = np.empty_like(y)
        dy[: N * n] = y[N * n :]
        u, v = y[: N * n].reshape(N, n), y[N * n :].reshape(N, n)
        _acceleration(mod, u, v, out=dy[N * n :].reshape(N, n))
        return dy

    t_stop = float(t_ends.max())
    n_t = int(np.floor(t_stop / sample_dt + 1e-9)) + 1
    S = np.empty((n_t, n))
    R = np.empty((n_t, n))
    S[0], R[0] = _sensor(mod, u0, v0)
    solver = DOP853(rhs, 0.0, np.concatenate([u0.ravel(), v0.ravel()]), t_stop,
                    rtol=rtol, atol=atol)
    k, steps = 1, 0
    while solver.status == "running":
        msg = solver.step()
        steps += 1
        if solver.status == "failed":
            raise SolverError(f"DOP853 failed at t = {solver.t:.6e} s: {msg}")
        k_hi = n_t if solver.status == "finished" else min(
            n_t, int(np.floor(solver.t / sample_dt + 1e-9)) + 1)
        if k_hi > k:
            ts = sample_dt * np.arange(k, k_hi)
            Y = solver.dense_output()(ts)  # (2 N n, m)
            u = Y[: N * n].reshape(N, n, -1)
            v = Y[N * n :].reshape(N, n, -1)
            f, r = _sensor(mod, u, v)
            S[k:k_hi], R[k:k_hi] = f.T, r.T
            k = k_hi
    t = sample_dt * np.arange(n_t)
    t_inc, t_ref = np.empty(n), np.empty(n)
    for j in range(n):
        m = int(np.floor(t_ends[j] / sample_dt + 1e-9)) + 1
        t_inc[j], t_ref[j] = tof_rule(sample_dt, S[:m, j], R[:m, j])
        S[m:, j] = np.nan
    return BaselineResult(tof=t_ref - t_inc, t_incident=t_inc, t_reflected=t_ref, t=t,
                          sensor=S, nfev=int(solver.nfev), steps=steps)
