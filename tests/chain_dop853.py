"""An independent chain for the calibration tests: the equations alone, solved by scipy's DOP853.

REFERENCE.md "The chain": ``N`` steel spheres under gravity, counted from the striker (bead 0),
precompressed to static equilibrium (with a preload ``P`` on bead 1), the striker arriving at
bead 1 with speed ``v``; Hertz contacts ``F_j = A d_j^1.5`` (``A = E sqrt(2R) / (3 (1 -
nu^2))``, two identical spheres), the wall a Hertz sphere on the half-space ``A_w d^1.5``
(``A_w = 4/3 E* sqrt(R)``). Solved with ``solve_ivp(DOP853)`` at rtol 1e-10 (Hairer, Norsett
& Wanner 1993, II.10); the sensor signal (mean of the sensor particle's two contact forces)
sampled every 0.2 us, the TOF between its first peak and the first peak after the signal
fell below a quarter of it, each refined by a parabola. Nothing of ssw's chain code is used.

A real device departs from ssw's model in ways the keywords of :func:`sensor_signal` make
(a device "as built"): the sensor particle's own mass, and its two contacts softer than a
bead's (``sensor_stiffness``: a bead cut in two around a piezoelectric disc is more
compliant than a solid one); the striker's own mass; dissipation in every closed contact by
one of the laws of :data:`LAWS`, with the wall's contact dissipating by its own law and
coefficient. In closed contacts (``d > 0``) the force is the elastic one plus

* ``dashpot``: ``c d'`` (``c`` N s/m; a linear viscous dashpot);
* ``kuwabara_kono``: ``c sqrt(d) d'`` (``c`` N s/m^1.5; the viscoelastic sphere, Kuwabara &
  Kono 1987, Brilliantov et al. 1996: ``F = A (d^1.5 + 1.5 tau sqrt(d) d')``, ``c = 1.5 A
  tau``);
* ``hunt_crossley``: ``c F_el(d) d'`` (``c`` s/m; Hunt & Crossley 1975: the damping in
  proportion to the elastic force);
* ``tsuji``: ``c d^(1/4) d'`` (``c`` N s/m^1.25; Tsuji, Tanaka & Ishida 1992, their
  non-linear spring-dashpot for Hertz contacts);

(``d'`` the rate of overlap; no clamp: a contact closing fast may pull, as in ssw's dashpot).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.integrate import solve_ivp

G = 9.80665
R = 9.525e-3  # m, 3/4 in beads
E_B, NU_B, RHO = 200.0e9, 0.28, 7810.0  # chrome steel, the library's chrome_steel
N_BEADS, SENSOR = 20, 10
BEAD_MASS = 4.0 / 3.0 * np.pi * R**3 * RHO  # kg
#: Sampling of the sensor signal, s (and the record's length).
SAMPLE, T_END = 0.2e-6, 4.5e-3

#: The dissipation laws (module docstring): name -> the damping coefficient's factor of the
#: overlap ``d > 0`` (m) and the contact's elastic force ``F_el`` (N), so that the damping
#: force is ``c * factor(d, F_el) * d'``.
LAWS: dict[str, Callable[[np.ndarray, np.ndarray], np.ndarray]] = {
    "dashpot": lambda d, f: np.ones_like(d),
    "kuwabara_kono": lambda d, f: np.sqrt(d),
    "hunt_crossley": lambda d, f: f,
    "tsuji": lambda d, f: np.sqrt(np.sqrt(d)),
}


def sensor_signal(E: float, nu: float, v: float, *, sensor_mass: float = BEAD_MASS,
                  damping: float = 0.0, preload: float = 0.0, law: str = "dashpot",
                  striker_mass: float = BEAD_MASS, sensor_stiffness: float = 1.0,
                  wall_damping: float | None = None, wall_law: str | None = None,
                  t_end: float = T_END) -> tuple[np.ndarray, np.ndarray]:
    """The sensor signal of the chain of the module docstring on a half-space of modulus
    ``E`` (Pa) and Poisson's ratio ``nu``, minus its static value.

    Parameters
    ----------
    E : float
        The half-space's Young's modulus, Pa.
    nu : float
        Its Poisson's ratio.
    v : float
        The striker's speed when it touches bead 1, m/s.
    sensor_mass : float
        The sensor particle's mass, kg (default: a bead's).
    damping : float
        The dissipation coefficient of every closed bead-bead contact, in the units of
        ``law`` (default 0: conservative).
    preload : float
        A constant downward force on bead 1, N.
    law : str
        The bead-bead contacts' dissipation law, a key of :data:`LAWS`.
    striker_mass : float
        The striker's mass, kg (default: a bead's).
    sensor_stiffness : float
        The factor on the Hertz coefficient of the sensor particle's two contacts (1: a
        bead's).
    wall_damping : float or None
        The wall contact's dissipation coefficient (None: ``damping``).
    wall_law : str or None
        The wall contact's law (None: ``law``).
    t_end : float
        s, the record's length.

    Returns
    -------
    tuple of numpy.ndarray
        Times (s, every :data:`SAMPLE` from the striker's contact) and the signal (N).
    """
    n = N_BEADS
    m = np.full(n, BEAD_MASS)
    m[SENSOR] = sensor_mass
    m[0] = striker_mass
    A = E_B * np.sqrt(2 * R) / (3 * (1 - NU_B**2))  # two identical spheres
    Es = 1.0 / ((1 - NU_B**2) / E_B + (1 - nu**2) / E)
    Aw = 4.0 / 3.0 * Es * np.sqrt(R)  # sphere on the half-space
    stiff = np.append(np.full(n - 1, A), Aw)
    stiff[SENSOR - 1: SENSOR + 1] *= sensor_stiffness
    coef = np.append(np.full(n - 1, damping),
                     damping if wall_damping is None else wall_damping)
    laws = [LAWS[law]] * (n - 1) + [LAWS[law if wall_law is None else wall_law]]
    # static equilibrium of beads 1..n-1: contact j >= 1 carries the weights above it and
    # the preload
    F = preload + G * np.cumsum(m[1:])  # contacts 1..n-2, then the wall
    u = np.zeros(n)
    u[-1] = (F[-1] / stiff[-1]) ** (2 / 3)
    for j in range(n - 2, 0, -1):  # u_j = u_{j+1} + overlap_j
        u[j] = u[j + 1] + (F[j - 1] / stiff[j]) ** (2 / 3)
    u[0] = u[1]
    v0 = np.zeros(n)
    v0[0] = v
    load = G * m
    load[1] += preload
    damped = bool(np.any(coef))

    def forces(x: np.ndarray, w: np.ndarray) -> np.ndarray:
        """Contact forces (n, ...) of positions and velocities (n, ...): the n - 1 bead
        pairs, then the wall."""
        d = x.copy()
        d[:-1] -= x[1:]
        dp = np.maximum(d, 0.0)
        shape = (n,) + (1,) * (x.ndim - 1)
        f = stiff.reshape(shape) * dp * np.sqrt(dp)
        if damped:
            rate = w.copy()
            rate[:-1] -= w[1:]
            # each contact's law: the bead pairs' (rows :-1) and the wall's (row -1)
            fac = np.concatenate([laws[0](dp[:-1], f[:-1]), laws[-1](dp[-1:], f[-1:])])
            f = f + coef.reshape(shape) * fac * rate * (d > 0)
        return f

    # the step's right-hand side, called some 10^5 times a record: the arithmetic of
    # forces() element by element (the same values to the bit), in fewer numpy calls
    law_b, law_w = laws[0], laws[-1]
    out = np.empty(2 * n)
    d = np.empty(n)
    rate = np.empty(n)
    fac = np.empty(n)

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        x, w = y[:n], y[n:]
        np.subtract(x[:-1], x[1:], out=d[:-1])
        d[-1] = x[-1]
        dp = np.maximum(d, 0.0)
        f = stiff * dp * np.sqrt(dp)
        if damped:
            np.subtract(w[:-1], w[1:], out=rate[:-1])
            rate[-1] = w[-1]
            fac[:-1] = law_b(dp[:-1], f[:-1])
            fac[-1:] = law_w(dp[-1:], f[-1:])
            f = f + coef * fac * rate * (d > 0)
        out[:n] = w
        acc = load - f
        acc[1:] += f[:-1]
        np.divide(acc, m, out=out[n:])
        return out.copy()

    t = np.arange(0.0, t_end, SAMPLE)
    sol = solve_ivp(rhs, (0.0, t[-1]), np.concatenate([u, v0]), method="DOP853",
                    rtol=1e-10, atol=1e-16, t_eval=t)
    assert sol.success, sol.message
    f = forces(sol.y[:n], sol.y[n:])
    s = 0.5 * (f[SENSOR - 1] + f[SENSOR])
    return t, s - s[0]


def chain_tof(E: float, nu: float, v: float, **device: float | str | None) -> float:
    """TOF (s) of the chain of the module docstring on a half-space of modulus ``E`` (Pa) and
    Poisson's ratio ``nu`` (:func:`sensor_signal`'s arguments): between its incident and
    reflected peaks.

    Parameters
    ----------
    E : float
        Pa.
    nu : float
        -.
    v : float
        The striker's speed, m/s.
    **device
        The keywords of :func:`sensor_signal` (the device as built).

    Returns
    -------
    float
        s.
    """
    t, s = sensor_signal(E, nu, v, **device)

    def vertex(k: int) -> float:
        ym, y0, yp = s[k - 1], s[k], s[k + 1]
        return t[k] + 0.5 * (ym - yp) / (ym - 2 * y0 + yp) * (t[1] - t[0])

    k1 = int(np.argmax(s > 0.5 * s.max()))
    while s[k1 + 1] > s[k1]:
        k1 += 1
    gap = k1 + int(np.argmax(s[k1:] < 0.25 * s[k1]))
    k2 = gap + int(np.argmax(s[gap:]))  # the reflected pulse: its first local maximum
    k2 = gap + int(np.flatnonzero((s[gap + 1:-1] > s[gap:-2]) & (s[gap + 1:-1] >= s[gap + 2:])
                                  & (s[gap + 1:-1] > 0.2 * s[k2]))[0]) + 1
    return float(vertex(k2) - vertex(k1))
