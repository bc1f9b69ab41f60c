"""An independent chain for the calibration tests: the equations alone, solved by scipy's DOP853.

REFERENCE.md "The chain": ``N`` steel spheres under gravity, counted from the striker (bead 0),
precompressed to static equilibrium (with a preload ``P`` on bead 1), the striker arriving at
bead 1 with speed ``v``; Hertz contacts ``F_j = A d_j^1.5`` (``A = E sqrt(2R) / (3 (1 -
nu^2))``, two identical spheres) with, optionally, a viscous dashpot ``c (v_j - v_{j+1})`` in
every closed contact, the wall a Hertz sphere on the half-space ``A_w d^1.5`` (``A_w = 4/3
E* sqrt(R)``) with the same dashpot; the sensor particle may have its own mass. Solved with
``solve_ivp(DOP853)`` at rtol 1e-10 (Hairer, Norsett & Wanner 1993, II.10); the sensor
signal (mean of the sensor particle's two contact forces) sampled every 0.2 us, the TOF
between its first peak and the first peak after the signal fell below a quarter of it, each
refined by a parabola. Nothing of ssw's chain code is used.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

G = 9.80665
R = 9.525e-3  # m, 3/4 in beads
E_B, NU_B, RHO = 200.0e9, 0.28, 7810.0  # chrome steel, the library's chrome_steel
N_BEADS, SENSOR = 20, 10
BEAD_MASS = 4.0 / 3.0 * np.pi * R**3 * RHO  # kg
#: Sampling of the sensor signal, s (and the record's length).
SAMPLE, T_END = 0.2e-6, 4.5e-3


def chain_tof(E: float, nu: float, v: float, *, sensor_mass: float = BEAD_MASS,
              damping: float = 0.0, preload: float = 0.0) -> float:
    """TOF (s) of the chain of the module docstring on a half-space of modulus ``E`` (Pa) and
    Poisson's ratio ``nu``.

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
        The dashpot of every closed contact, N s/m (default 0: conservative).
    preload : float
        A constant downward force on bead 1, N.

    Returns
    -------
    float
        The TOF between the incident and the reflected peak of the sensor signal, s.
    """
    n = N_BEADS
    m = np.full(n, BEAD_MASS)
    m[SENSOR] = sensor_mass
    A = E_B * np.sqrt(2 * R) / (3 * (1 - NU_B**2))  # two identical spheres
    Es = 1.0 / ((1 - NU_B**2) / E_B + (1 - nu**2) / E)
    Aw = 4.0 / 3.0 * Es * np.sqrt(R)  # sphere on the half-space
    # static equilibrium of beads 1..n-1: contact j >= 1 carries the weights above it and
    # the preload
    F = preload + G * np.cumsum(m[1:])  # contacts 1..n-2, then the wall
    u = np.zeros(n)
    u[-1] = (F[-1] / Aw) ** (2 / 3)
    for j in range(n - 2, 0, -1):  # u_j = u_{j+1} + overlap_j
        u[j] = u[j + 1] + (F[j - 1] / A) ** (2 / 3)
    u[0] = u[1]
    v0 = np.zeros(n)
    v0[0] = v
    load = G * m
    load[1] += preload

    stiff = np.append(np.full(n - 1, A), Aw)

    def forces(x: np.ndarray, w: np.ndarray) -> np.ndarray:
        """Contact forces (n, ...) of positions and velocities (n, ...): the n - 1 bead
        pairs, then the wall."""
        d = x.copy()
        d[:-1] -= x[1:]
        dp = np.maximum(d, 0.0)
        f = stiff.reshape((n,) + (1,) * (x.ndim - 1)) * dp * np.sqrt(dp)
        if damping:
            rate = w.copy()
            rate[:-1] -= w[1:]
            f += damping * rate * (d > 0)
        return f

    out = np.empty(2 * n)

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        f = forces(y[:n], y[n:])
        out[:n] = y[n:]
        out[n:] = load - f
        out[n + 1:] += f[:-1]
        out[n:] /= m
        return out.copy()

    t = np.arange(0.0, T_END, SAMPLE)
    sol = solve_ivp(rhs, (0.0, t[-1]), np.concatenate([u, v0]), method="DOP853",
                    rtol=1e-10, atol=1e-16, t_eval=t)
    assert sol.success, sol.message
    f = forces(sol.y[:n], sol.y[n:])
    s = 0.5 * (f[SENSOR - 1] + f[SENSOR])
    s = s - s[0]

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
