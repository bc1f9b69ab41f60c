"""The reduced dynamic wall: the quasi-static law plus radiation damping and participating mass.

The dynamic FEM wall costs a minute per TOF point; sweeps and inversions need
milliseconds. The reduced wall keeps the quasi-static law ``F_qs(d)`` of any wall of
:mod:`ssw.walls` (Hertz, fit, table, fem) and adds what the soil's inertia does at
the contact's time scale, as the Lysmer analog does for a rigid footing (Lysmer 1965;
Richart, Hall & Woods 1970), with the footing's radius taken from the law itself:

    F = max(0, F_qs(d) + C(d) d' + m(d) d''),
    a(d) = (1 - nu) k_t(d) / (4 G),            k_t = dF_qs/dd (tangent stiffness),
    C(d) = c_r 4 a^2 sqrt(rho G) / (1 - nu),
    m(d) = m_r 4 rho a^3 / (1 - nu) + k_p mu_p pi a^2,

Why the tangent stiffness: an increment of a contact's load spreads like a flat punch's
(the increment of a Hertz pressure is a punch pressure, ``dF/dd = 2 a E*``), so the
incremental dynamic stiffness of the contact is a rigid punch's of the radius ``a`` that
gives the same static tangent stiffness, ``K_s = 4 G a / (1 - nu)``; a punch's impedance is
``K_s (k(a0) + i a0 c(a0))`` with ``k ~ 1 - m_r a0^2`` and ``c ~ c_r`` at the frequencies
of the last contact (``a0 = omega a / c_s <~ 1``). ``c_r = 0.85`` is Lysmer's analog
(3.4 / 4); the defaults :data:`C_R`, :data:`M_R` are the FEM punch's low-frequency values
(``ssw bench dynamic``). The plate (areal density ``mu_p = rho_p t``, kg/m^2) adds its
own inertia, the Rayleigh mass of its quasi-static deflection under the bead: measured on
the static FEM (0.4 mm PLA: 19-27 mg on 10 MPa, 5-7 mg on 100 MPa, 1-2 mg on 1 GPa, the
tangent mode's ``phi M phi``), it is :data:`K_P` ``mu_p pi a^2`` within about 25 %.
``ssw dynamic-study`` measures the reduced wall against the FEM wall.

Time discretization (the stateful wall protocol, :class:`ssw.chain.wall.StatefulWall`): the
force at the new position uses the second-order backward differences

    d'_(n+1) = (3 d_(n+1) - 4 d_n + d_(n-1)) / (2 dt),
    d''_(n+1) ~ (d_(n+1) - 2 d_n + d_(n-1)) / dt^2,

so the state is the last two indentations (and the dissipated energy ``int C d'^2 dt``,
summed with the same velocity).
The dashpot is implicit in the bead's position, stable for any ``C``; the mass term lags
by one step (stable while ``m`` is far below the bead's mass: ``m / m_bead`` ~ 1e-3 here).
As the density tends to 0 (``G`` fixed), ``C`` and ``m`` vanish and the wall is the
quasi-static one exactly.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ssw.errors import ConfigError

#: Normalized radiation dashpot c(a0) of the FEM punch at low a0 (nu = 1/3: 0.80 at
#: a0 = 0.25; Lysmer's analog: 0.85; Veletsos & Verbic: 0.76).
C_R = 0.80
#: Normalized participating mass: 1 - k(a0) ~ M_R a0^2 (the FEM punch, nu = 1/3: 0.09 at
#: a0 = 0.5; Veletsos & Verbic: 0.08).
M_R = 0.09
#: Plate's participating mass in units of its mass over the footing, ``mu_p pi a^2``
#: (static FEM Rayleigh masses of 0.4 mm PLA on 10 MPa-1 GPa soils: 3.2-5.2).
K_P = 4.0
#: Relative step of the tangent stiffness's forward difference (its error ~5e-5 of k_t).
TANGENT_STEP = 1e-4
#: Smallest step (m) of that difference (indentations at or below 0 have no tangent).
MIN_STEP = 1e-15


@dataclass(frozen=True)
class ReducedState:
    """The last two indentations (m), shape (n,), the dissipated energy (J) and the step
    (s) they are apart.

    Parameters
    ----------
    d1 : numpy.ndarray
        Last indentation (m), (n,).
    d0 : numpy.ndarray
        The one before (m), (n,).
    dissipated : numpy.ndarray
        Dissipated energy (J), (n,).
    dt : float
        Step between them (s); 0 at rest.
    """

    d1: np.ndarray
    d0: np.ndarray
    dissipated: np.ndarray
    dt: float = 0.0


@dataclass(frozen=True)
class ReducedWall:
    """``F = F_qs(d) + C(d) d' + m(d) d''`` per scene (module docstring). SI units.

    qs : the quasi-static wall (`ssw.chain.wall.Wall`).  G, nu, rho : (n,) the
    soil's shear modulus (Pa), Poisson's ratio, density (kg/m^3).  mu_p : (n,) the
    plate's areal density (kg/m^2, 0 without a plate).  c_r, m_r, k_p : the normalized
    dashpot, soil mass and plate mass.

    Parameters
    ----------
    qs : Wall
        The quasi-static wall.
    G : numpy.ndarray
        Soil's shear modulus (Pa), (n,).
    nu : numpy.ndarray
        Soil's Poisson's ratio, (n,).
    rho : numpy.ndarray
        Soil's density (kg/m^3), (n,).
    mu_p : numpy.ndarray
        Plate's areal density (kg/m^2), (n,); 0 without a plate.
    c_r : float
        Normalized radiation dashpot.
    m_r : float
        Normalized participating soil mass.
    k_p : float
        Plate's participating mass in units of ``mu_p pi a^2``.
    dt : float or None
        The step the wall was built for (s), or None.
    """

    qs: Any
    G: np.ndarray
    nu: np.ndarray
    rho: np.ndarray
    mu_p: np.ndarray
    c_r: float = C_R
    m_r: float = M_R
    k_p: float = K_P
    dt: float | None = None
    #: :meth:`advance_tangent` differentiates the step too (``ddt``).
    step_tangent: ClassVar[bool] = True

    def __post_init__(self) -> None:
        if np.any(self.rho < 0) or np.any(self.G <= 0):
            raise ConfigError("soil_density", self.rho.tolist(), "densities >= 0 kg/m^3")
        if self.c_r < 0 or self.m_r < 0 or self.k_p < 0 or np.any(self.mu_p < 0):
            raise ConfigError("reduced wall", (self.c_r, self.m_r, self.k_p),
                              "c_r, m_r, k_p and the plate's areal density >= 0")

    @property
    def n(self) -> int:
        """Number of scenes."""
        return self.qs.n

    def tangent(self, d: np.ndarray, F: np.ndarray | None = None) -> np.ndarray:
        """Tangent stiffness ``dF_qs/dd`` (N/m) at ``d`` (m), 0 where ``d <= 0``: a forward
        difference of relative step :data:`TANGENT_STEP` (``F = F_qs(d)`` if known).

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).
        F : numpy.ndarray or None
            Quasi-static forces at ``d`` (N), if known.

        Returns
        -------
        numpy.ndarray
            Tangent stiffness (N/m), (n,).
        """
        d = np.asarray(d, float)
        F = self.qs.force(d) if F is None else F
        h = TANGENT_STEP * np.maximum(d, MIN_STEP)
        return np.where(d > 0, (self.qs.force(d + h) - F) / h, 0.0)

    @functools.cached_property
    def _scale(self) -> np.ndarray:
        """``(1 - nu) / (4 G)`` (m/N): the footing radius per unit tangent stiffness."""
        return (1.0 - self.nu) / (4.0 * self.G)

    @functools.cached_property
    def _factors(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``C = f_c k_t^2``, ``m = (f_m k_t + f_p) k_t^2`` (module docstring)."""
        s2 = self._scale**2
        f_c = self.c_r * 4.0 * np.sqrt(self.rho * self.G) / (1.0 - self.nu) * s2
        f_m = self.m_r * 4.0 * self.rho / (1.0 - self.nu) * s2 * self._scale
        f_p = self.k_p * self.mu_p * np.pi * s2
        return f_c, f_m, f_p

    def radius(self, d: np.ndarray) -> np.ndarray:
        """Equivalent footing radius ``a = (1 - nu) k_t / (4 G)`` (m).

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Footing radius (m), (n,).

        References
        ----------
        Lysmer, J. and Richart, F. E. (1966). Dynamic response of footings to vertical loading.
        *J. Soil Mech. Found. Div.* 92(SM1), 65-91.
        """
        return self._scale * self.tangent(d)

    def coefficients(self, d: np.ndarray, k_t: np.ndarray | None = None
                     ) -> tuple[np.ndarray, np.ndarray]:
        """Dashpot ``C`` (N s/m) and participating mass ``m`` (kg) at ``d`` (m).

        ``C = c_r 4 a^2 sqrt(rho G) / (1 - nu)``, ``m = m_r 4 rho a^3 / (1 - nu) + k_p mu_p pi a^2``
        (module docstring).

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).
        k_t : numpy.ndarray or None
            Tangent stiffness at ``d`` (N/m), if known.

        Returns
        -------
        C : numpy.ndarray
            Dashpot (N s/m), (n,).
        m : numpy.ndarray
            Participating mass (kg), (n,).

        References
        ----------
        Lysmer, J. and Richart, F. E. (1966). Dynamic response of footings to vertical loading.
        *J. Soil Mech. Found. Div.* 92(SM1), 65-91.
        """
        kt = self.tangent(d) if k_t is None else k_t
        f_c, f_m, f_p = self._factors
        k2 = kt * kt
        return f_c * k2, (f_m * kt + f_p) * k2

    # the stateful wall protocol (ssw.chain.wall.StatefulWall) and the Wall protocol
    def force(self, d: np.ndarray) -> np.ndarray:
        """Quasi-static force (N).

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Force (N), (n,).
        """
        return self.qs.force(d)

    def potential(self, d: np.ndarray) -> np.ndarray:
        """Quasi-static stored energy (J).

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Stored energy (J), (n,).
        """
        return potential(self.qs, d)

    def dforce_dd(self, d: np.ndarray) -> np.ndarray:
        """Quasi-static tangent stiffness (N/m), the statics' (the wall at rest).

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Tangent stiffness (N/m), (n,).
        """
        return self.qs.dforce_dd(d)

    def dforce_dE(self, d: np.ndarray) -> np.ndarray:
        """Quasi-static ``dF/dE`` (N/Pa), the statics'.

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            ``dF/dE`` (N/Pa), (n,).
        """
        return self.qs.dforce_dE(d)

    def indentation(self, F: np.ndarray) -> np.ndarray:
        """Quasi-static indentation (m) carrying ``F`` (N).

        Parameters
        ----------
        F : numpy.ndarray
            Forces (N), (n,).

        Returns
        -------
        numpy.ndarray
            Indentation (m), (n,).
        """
        return self.qs.indentation(F)

    def hertz_equivalent(self, d_ref: float) -> np.ndarray:
        """The quasi-static law's ``F(d_ref) / d_ref^1.5`` (N/m^1.5).

        Parameters
        ----------
        d_ref : float
            Reference indentation (m), > 0.

        Returns
        -------
        numpy.ndarray
            Equivalent Hertz coefficient (N/m^1.5), (n,).
        """
        return self.qs.hertz_equivalent(d_ref)

    def start(self, d0: np.ndarray) -> ReducedState:
        """The state at rest with the last beads at ``d0`` (m).

        Parameters
        ----------
        d0 : numpy.ndarray
            Initial indentations (m), (n,).

        Returns
        -------
        ReducedState
            Both past indentations ``d0``, nothing dissipated.
        """
        d0 = np.asarray(d0, float)
        return ReducedState(d0.copy(), d0.copy(), np.zeros(d0.shape))

    def advance(self, st: ReducedState, d: np.ndarray, dt: float
                ) -> tuple[np.ndarray, ReducedState]:
        """Force (N) at the new indentation ``d`` (m) and the new state.

        Parameters
        ----------
        st : ReducedState
            The state.
        d : numpy.ndarray
            Indentations at the step's end (m), (n,).
        dt : float
            Time step (s).

        Returns
        -------
        F : numpy.ndarray
            Force (N), (n,).
        state : ReducedState
            The new state.
        """
        d = np.array(d, float)  # kept in the state: a copy, whatever the caller does to d
        F = self.qs.force(d)
        C, m = self.coefficients(d, self.tangent(d, F))
        v = (3.0 * d - 4.0 * st.d1 + st.d0) / (2.0 * dt)
        F += C * v
        F += m * (d - 2.0 * st.d1 + st.d0) / dt**2
        np.maximum(F, 0.0, out=F)
        diss = st.dissipated + dt * C * v**2 * (F > 0)
        return F, ReducedState(d, st.d1, diss, dt)

    def start_tangent(self, st: ReducedState, D0: np.ndarray, dE: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
        """The derivatives (n, k) of the state at rest: both indentations move as ``D0``.

        Parameters
        ----------
        st : ReducedState
            The state.
        D0 : numpy.ndarray
            Derivatives of the initial indentations (m per parameter unit), (n, k).
        dE : numpy.ndarray
            Derivatives of the soil's modulus (Pa per parameter unit), (n, k); unused.

        Returns
        -------
        tuple of numpy.ndarray
            The derivatives of both past indentations, copies of ``D0``.
        """
        return np.array(D0, float), np.array(D0, float)

    def advance_tangent(self, st: ReducedState, tst: tuple[np.ndarray, np.ndarray],
                        d: np.ndarray, D: np.ndarray, dt: float, dE: np.ndarray,
                        ddt: np.ndarray | None = None
                        ) -> tuple[np.ndarray, np.ndarray, ReducedState, tuple]:
        """:meth:`advance` and its exact derivative.

        Parameters
        ----------
        st : ReducedState
            The state.
        tst : tuple of numpy.ndarray
            ``(D1, D0)`` (n, k): the derivatives of the state's two indentations.
        d : numpy.ndarray
            (n,) m, the new indentation.
        D : numpy.ndarray
            (n, k), its derivatives with respect to the run's ``k`` parameters.
        dt : float
            s.
        dE : numpy.ndarray
            (n, k), the derivatives of the soil's modulus (Pa per unit of each parameter).
        ddt : numpy.ndarray or None
            (k,), the derivatives of the step (s per unit of each parameter; the chain's
            step column, ``ssw.chain.sensitivity.STEP``): the differences' explicit ``dt``,
            ``dv/ddt = -v / dt``, ``dacc/ddt = -2 acc / dt``.

        Returns
        -------
        tuple
            ``(F, dF, state, tstate)``: the force (N), its derivatives (n, k), the new
            state and its derivatives: differentiating every line of :meth:`advance`, the
            tangent stiffness's forward difference included (``k_t = (F_qs(d (1 + e)) -
            F_qs(d)) / (e d)``), and the dashpot's and the masses' dependence on the shear
            modulus (``f_c ~ G^-3/2``, ``f_m ~ G^-3``, ``f_p ~ G^-2``).
        """
        D1, D0 = tst
        d = np.array(d, float)
        F_qs = self.qs.force(d)
        kt = self.tangent(d, F_qs)
        C, m = self.coefficients(d, kt)
        v = (3.0 * d - 4.0 * st.d1 + st.d0) / (2.0 * dt)
        acc = (d - 2.0 * st.d1 + st.d0) / dt**2
        F = F_qs + C * v + m * acc
        on = F > 0
        F = np.maximum(F, 0.0)
        diss = st.dissipated + dt * C * v**2 * on
        # derivatives of F_qs and of the tangent's forward difference
        use_E = bool(np.any(dE))
        pos = d > 0
        up = d * (1.0 + TANGENT_STEP)
        h = TANGENT_STEP * np.maximum(d, MIN_STEP)
        Fd = self.qs.dforce_dd(d)
        dkt_dd = np.where(pos, ((1.0 + TANGENT_STEP) * self.qs.dforce_dd(up) - Fd) / h
                          - kt / np.where(pos, d, 1.0), 0.0)
        dF_qs = Fd[:, None] * D
        dkt = dkt_dd[:, None] * D
        f_c, f_m, f_p = self._factors
        E = 2.0 * (1.0 + self.nu) * self.G
        if use_E:
            FE = self.qs.dforce_dE(d)
            dF_qs += FE[:, None] * dE
            dkt += np.where(pos, (self.qs.dforce_dE(up) - FE) / h, 0.0)[:, None] * dE
        k2 = kt * kt
        dC = (2.0 * f_c * kt)[:, None] * dkt
        dm = (3.0 * f_m * k2 + 2.0 * f_p * kt)[:, None] * dkt
        if use_E:
            dC += (-1.5 * f_c * k2 / E)[:, None] * dE
            dm += ((-3.0 * f_m * kt - 2.0 * f_p) * k2 / E)[:, None] * dE
        dv = (3.0 * D - 4.0 * D1 + D0) / (2.0 * dt)
        dacc = (D - 2.0 * D1 + D0) / dt**2
        if ddt is not None:
            dv = dv - (v / dt)[:, None] * ddt[None, :]
            dacc = dacc - (2.0 * acc / dt)[:, None] * ddt[None, :]
        dF = dF_qs + dC * v[:, None] + C[:, None] * dv + dm * acc[:, None] + m[:, None] * dacc
        dF *= on[:, None]
        return F, dF, ReducedState(d, st.d1, diss, dt), (np.array(D, float), D1)

    def energy(self, st: ReducedState) -> tuple[np.ndarray, np.ndarray]:
        """Stored (the quasi-static potential and the participating mass's kinetic energy,
        J) and dissipated (J) energy.

        Parameters
        ----------
        st : ReducedState
            The state.

        Returns
        -------
        stored : numpy.ndarray
            Stored energy (J), (n,).
        dissipated : numpy.ndarray
            Dissipated energy (J), (n,).
        """
        kinetic = 0.0
        if st.dt > 0:
            _, m = self.coefficients(st.d1)
            kinetic = 0.5 * m * ((st.d1 - st.d0) / st.dt) ** 2
        return potential(self.qs, st.d1) + kinetic, st.dissipated

    def take(self, idx: np.ndarray) -> ReducedWall:
        """The scenes ``idx`` (may repeat).

        Parameters
        ----------
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        ReducedWall
            The wall of the selected scenes.
        """
        return ReducedWall(self.qs.take(idx), self.G[idx], self.nu[idx], self.rho[idx],
                           self.mu_p[idx], self.c_r, self.m_r, self.k_p, self.dt)

    def take_state(self, st: ReducedState, idx: np.ndarray) -> ReducedState:
        """The state of the scenes ``idx``.

        Parameters
        ----------
        st : ReducedState
            The state.
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        ReducedState
            The selected scenes' state.
        """
        return ReducedState(st.d1[idx], st.d0[idx], st.dissipated[idx], st.dt)


#: Gauss-Legendre points of the potential of a wall without ``potential``.
POTENTIAL_POINTS = 32


def potential(wall: Any, d: np.ndarray) -> np.ndarray:
    """``int_0^d F`` (J) of a wall: its ``potential`` or Gauss-Legendre quadrature.

    Parameters
    ----------
    wall : Any
        A wall law.
    d : numpy.ndarray
        Indentations (m), (n,).

    Returns
    -------
    numpy.ndarray
        Stored energy (J), (n,).
    """
    if hasattr(wall, "potential"):
        return wall.potential(d)
    d = np.maximum(np.asarray(d, float), 0.0)
    x, w = np.polynomial.legendre.leggauss(POTENTIAL_POINTS)
    F = np.array([wall.force(0.5 * d * (1.0 + xi)) for xi in x])
    return 0.5 * d * np.einsum("q,qn->n", w, F)


def reduced_wall(qs: Any, soil_E: Any, soil_nu: Any, soil_density: Any, *,
                 plate_areal_density: Any = 0.0, c_r: float = C_R, m_r: float = M_R,
                 k_p: float = K_P) -> ReducedWall:
    """The reduced wall of the quasi-static wall ``qs`` (one scene per broadcast soil E Pa,
    nu, density kg/m^3; ``qs.n`` scenes); ``plate_areal_density`` (kg/m^2) is the plate's
    density times thickness (0: no plate; :func:`plate_areal_density`).

    Parameters
    ----------
    qs : Wall
        The quasi-static wall.
    soil_E : array_like
        Soil Young's modulus (Pa).
    soil_nu : array_like
        Soil Poisson's ratio.
    soil_density : array_like
        Soil density (kg/m^3).
    plate_areal_density : array_like
        Plate density times thickness (kg/m^2); 0: no plate.
    c_r : float
        Normalized radiation dashpot.
    m_r : float
        Normalized participating soil mass.
    k_p : float
        Plate's participating mass in units of ``mu_p pi a^2``.

    Returns
    -------
    ReducedWall
        The reduced wall.

    Raises
    ------
    ConfigError
        If the soils are neither one nor one per scene.
    """
    E, nu, rho = (np.ravel(x).astype(float) for x in np.broadcast_arrays(
        np.asarray(soil_E, float), np.asarray(soil_nu, float),
        np.asarray(soil_density, float)))
    if E.size == 1:
        E, nu, rho = (np.full(qs.n, x[0]) for x in (E, nu, rho))
    if E.size != qs.n:
        raise ConfigError("soil_density", rho.tolist(), f"one value or {qs.n} (one per scene)")
    mu = np.broadcast_to(np.asarray(plate_areal_density, float), (qs.n,)).copy()
    return ReducedWall(qs, E / (2.0 * (1.0 + nu)), nu, rho, mu, c_r, m_r, k_p)


def plate_areal_density(params: Any, plate_density: float | None = None) -> float:
    """``rho_p t`` (kg/m^2) of the chain's plate (0 without one); the density comes from
    the materials library by ``params.plate_material`` unless given.

    Parameters
    ----------
    params : ChainParams
        The chain (its plate).
    plate_density : float or None
        Plate density (kg/m^3); None: the materials library's for ``params.plate_material``.

    Returns
    -------
    float
        Areal density (kg/m^2).
    """
    if params.plate_thickness <= 0:
        return 0.0
    if plate_density is None:
        from ssw.materials import get_material

        plate_density = get_material(params.plate_material, field="plate.material").density
    return float(plate_density) * float(params.plate_thickness)
