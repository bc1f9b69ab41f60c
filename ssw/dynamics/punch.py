"""Vertical dynamic stiffness of a rigid circular punch on the FEM half-space, and its references.

The verification of the dynamic FEM's operators (mass, stiffness, boundary, time stepping)
against the classical impedance of a massless rigid disk of radius ``a`` on an elastic
half-space, relaxed (frictionless) contact (Veletsos & Verbic 1973; Luco & Westmann 1971):

    K(omega) = K_s [k(a0) + i a0 c(a0)],   K_s = 4 G a / (1 - nu),   a0 = omega a / c_s.

Method (time domain, as the wall runs): every surface node with ``r <= a`` is moved
down by the same Gaussian pulse ``delta(t) = delta_0 exp(-(t - t_0)^2 / (2 s^2))``
(bilateral constraint, ``u_r`` free: relaxed contact), the punch force ``P(t)`` is the sum
of the constraint forces (condensed like the contact), and ``K(omega) = P(omega) /
delta(omega)`` from the Fourier transforms over a window that ends before any wave the
boundary reflects comes back (:mod:`ssw.dynamics.domain` sizes the domain for it), by
which time the force has returned to zero. The punch of a node-conforming mesh has an
effective radius between its last constrained and first free node (``growth a`` apart):
it is defined by the FEM's own static stiffness, ``a_eff = K_static (1 - nu) / (4 G)``, and
``k``, ``c`` are normalized by ``K_static`` at ``a0 = omega a_eff / c_s``. Use the
``absorbing`` boundary: its springs approximate the half-space's static far field (a fixed
box of radius ``L`` is stiffer by ``~(3 - 2 nu) a / (pi (1 - nu) L)``, Steinbrenner's
estimate: 2.8 % at ``L = 40 a``, nu = 1/3, which the measured fixed/absorbing ratio
1.028 matches), while the dynamic window itself never sees the truncation.

References (:func:`veletsos_verbic`, :func:`lysmer_analog`):

* Veletsos & Verbic (1973): ``k = 1 - g1 (g2 a0)^2 / (1 + (g2 a0)^2) - g3 a0^2``,
  ``c = g4 + g1 g2 (g2 a0)^2 / (1 + (g2 a0)^2)``, fitted to the exact solutions for
  ``a0 <= 1.5``. Only the nu = 1/3 row, (g1, g2, g3, g4) = (0.35, 0.80, 0, 0.75), is used:
  it reproduces the values tabulated from it elsewhere (k = 0.9517, 0.8634, 0.7934 and
  c = 0.7886, 0.8593, 0.9152 at a0 = 0.5, 1, 1.5); the rows of other Poisson's ratios
  could not be confirmed here.
* Lysmer's analog (Lysmer 1965; Richart, Hall & Woods 1970; REFERENCE.md): a constant
  spring ``K_s`` and dashpot ``3.4 a^2 sqrt(rho G) / (1 - nu)``, i.e. ``k = 1``,
  ``c = 0.85``.

References
----------
Veletsos, A. S. & Verbic, B. (1973). Vibration of viscoelastic foundations. Earthquake
Eng. Struct. Dyn. 2, 87-102.
Luco, J. E. & Westmann, R. A. (1971). Dynamic response of circular footings. J. Eng. Mech.
Div. ASCE 97(EM5), 1381-1395.
Lysmer, J. (1965). Vertical motion of rigid footings. Contract report 3-115, U.S. Army
Engineer Waterways Experiment Station.
Richart, F. E., Hall, J. R. & Woods, R. D. (1970). Vibrations of Soils and Foundations.
Prentice-Hall.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ssw.contact.mesh import build_mesh
from ssw.contact.petsc_solver import nd_order
from ssw.dynamics.domain import DomainSpec, mesh_settings
from ssw.dynamics.fem_wall import top_candidates
from ssw.dynamics.newmark import Newmark, State, Static
from ssw.dynamics.system import Material, assemble_dynamic
from ssw.errors import ConfigError

#: Veletsos & Verbic (1973) vertical coefficients (g1, g2, g3, g4) by Poisson's ratio.
VV_COEFFICIENTS = {1.0 / 3.0: (0.35, 0.80, 0.0, 0.75)}
#: Lysmer's analog dashpot coefficient 3.4 / 4 (c of the normalized impedance).
LYSMER_C = 0.85
#: Pulse width (in a / c_s), its centre (in widths) and the tail after it (in a / c_s).
PULSE_WIDTH, PULSE_CENTRE, TAIL = 2.5, 6.0, 10.0
#: Time steps per a / c_s.
STEPS_PER_TRANSIT = 40
#: Zero padding of the Fourier transform (times the record).
PADDING = 8


def veletsos_verbic(a0: np.ndarray, nu: float) -> tuple[np.ndarray, np.ndarray]:
    """Normalized vertical impedance ``(k, c)`` of Veletsos & Verbic (1973) at ``a0``.

    Only the tabulated Poisson's ratios (:data:`VV_COEFFICIENTS`) are accepted.

    Parameters
    ----------
    a0 : numpy.ndarray
        Dimensionless frequency ``omega r0 / c_s``.
    nu : float
        Poisson's ratio (a tabulated one).

    Returns
    -------
    k : numpy.ndarray
        Normalized stiffness.
    c : numpy.ndarray
        Normalized damping.

    Raises
    ------
    ConfigError
        If ``nu`` is not tabulated.

    References
    ----------
    Veletsos, A. S. and Verbic, B. (1973). Vibration of viscoelastic foundations.
    *Earthquake Eng. Struct. Dyn.* 2, 87-102.
    """
    key = next((x for x in VV_COEFFICIENTS if abs(x - nu) < 1e-9), None)
    if key is None:
        raise ConfigError("nu", nu, f"one of {sorted(VV_COEFFICIENTS)} (Veletsos & Verbic)")
    g1, g2, g3, g4 = VV_COEFFICIENTS[key]
    a0 = np.asarray(a0, float)
    x = (g2 * a0) ** 2
    return 1.0 - g1 * x / (1.0 + x) - g3 * a0**2, g4 + g1 * g2 * x / (1.0 + x)


def lysmer_analog(a0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lysmer's analog: ``k = 1``, ``c = 0.85`` at every ``a0``.

    Parameters
    ----------
    a0 : numpy.ndarray
        Dimensionless frequency ``omega r0 / c_s``.

    Returns
    -------
    k : numpy.ndarray
        Normalized stiffness, ones.
    c : numpy.ndarray
        Normalized damping, 0.85.

    References
    ----------
    Lysmer, J. and Richart, F. E. (1966). Dynamic response of footings to vertical loading.
    *J. Soil Mech. Found. Div.* 92(SM1), 65-91.
    """
    a0 = np.asarray(a0, float)
    return np.ones_like(a0), np.full_like(a0, LYSMER_C)


@dataclass(frozen=True)
class PunchImpedance:
    """The FEM punch's impedance. SI units.

    a0 : (n,) -.  k, c : (n,) normalized by ``K_static``.  K_static : N/m, the static
    stiffness of the discrete punch on the dynamic mesh with its truncation boundary.
    a_eff : m.
    t, delta, force : the record (s, m, N).  dofs : size of the system.  domain : m.

    Parameters
    ----------
    a0 : numpy.ndarray
        Dimensionless frequencies, (n,).
    k : numpy.ndarray
        Normalized stiffness, (n,).
    c : numpy.ndarray
        Normalized damping, (n,).
    K_static : float
        Static stiffness of the discrete punch (N/m).
    a_eff : float
        Effective punch radius (m).
    t : numpy.ndarray
        Times of the record (s).
    delta : numpy.ndarray
        Punch displacement of the record (m).
    force : numpy.ndarray
        Punch force of the record (N).
    dofs : int
        Size of the system.
    domain : float
        Domain radius = depth (m).
    """

    a0: np.ndarray
    k: np.ndarray
    c: np.ndarray
    K_static: float
    a_eff: float
    t: np.ndarray
    delta: np.ndarray
    force: np.ndarray
    dofs: int
    domain: float


def punch_impedance(
    soil: Material, radius: float, a0: np.ndarray, *, boundary: str = "absorbing",
    size_contact: float | None = None, growth: float = 0.1, wave_elements: float = 4.0,
) -> PunchImpedance:
    """Vertical impedance of a rigid punch of ``radius`` (m) on the FEM half-space ``soil``.

    Parameters
    ----------
    soil : ssw.dynamics.system.Material
        The half-space's material.
    radius : float
        The punch's radius, m.
    a0 : numpy.ndarray
        The dimensionless frequencies ``omega radius / c_s``.
    boundary : str
        The truncation boundary (``absorbing`` | ``fixed``; the window excludes its
        reflections either way).
    size_contact : float or None
        The element size under the punch, m (default: radius / 50).
    growth : float
        Element size over distance from the punch's edge (the mesh's grading).
    wave_elements : float
        Elements per shear wavelength at the pulse's highest frequency (the far field's
        element size).

    Returns
    -------
    PunchImpedance
        Normalized impedance (``k``, ``c``), static stiffness (N/m) and the record.
    """
    cs = soil.c_s
    s = PULSE_WIDTH * radius / cs
    t0 = PULSE_CENTRE * s
    T = t0 + PULSE_CENTRE * s + TAIL * radius / cs
    spec = DomainSpec(window=T, f_max=5.0 / (2.0 * np.pi * s), wave_elements=wave_elements,
                      size_contact=size_contact or radius / 50.0, growth=growth,
                      max_domain=np.inf)
    settings = mesh_settings(soil, 0.0, spec)
    mesh = build_mesh(0.0, 0.0, settings)
    system = assemble_dynamic(mesh, soil, None, "frictionless", boundary, nd_order)
    nodes = top_candidates(system, mesh, radius * (1.0 + 1e-9))
    dofs = system.static.udof[nodes, 1]
    K_static = static_stiffness(system, dofs)
    dt = radius / cs / STEPS_PER_TRANSIT
    nm = Newmark(system, dt, dofs)
    n_steps = int(np.ceil(T / dt))
    t = dt * np.arange(n_steps + 1)
    delta = radius * 1e-4 * np.exp(-0.5 * ((t - t0) / s) ** 2)
    from scipy.linalg import cho_factor, cho_solve

    cf = cho_factor(nm.W)
    n = system.ndof
    force = np.zeros(n_steps + 1)
    delta -= delta[0]  # starts at rest (the Gaussian's start is exp(-18) of its peak)
    st = State(u=np.zeros(n), v=np.zeros(n), a=np.zeros(n), lam=np.zeros(len(dofs)))
    for j in range(1, n_steps + 1):
        u_free = nm.free(st)
        lam = cho_solve(cf, u_free[dofs] + delta[j])
        st = nm.finish(st, u_free, lam)
        force[j] = lam.sum()
    nm.destroy()
    G = soil.G
    a_eff = K_static * (1.0 - soil.nu) / (4.0 * G)
    nfft = PADDING * t.size
    w = 2.0 * np.pi * np.fft.rfftfreq(nfft, dt)
    K = np.fft.rfft(force, nfft) / np.fft.rfft(delta, nfft)
    omega = np.asarray(a0, float) * cs / a_eff
    Kw = np.interp(omega, w, K.real) + 1j * np.interp(omega, w, K.imag)
    a0 = np.asarray(a0, float)
    return PunchImpedance(a0=a0, k=Kw.real / K_static, c=Kw.imag / (a0 * K_static),
                          K_static=K_static, a_eff=a_eff, t=t, delta=delta, force=force,
                          dofs=n, domain=mesh.soil_radius)


def static_stiffness(system, dofs: np.ndarray) -> float:
    """Static force per unit uniform displacement of the nodes ``dofs`` (N/m).

    Parameters
    ----------
    system : DynamicSystem
        The operators.
    dofs : numpy.ndarray
        The loaded dofs.

    Returns
    -------
    float
        Stiffness (N/m).
    """
    static = Static(system, dofs)
    one = np.ones(len(dofs))
    K = float(one @ np.linalg.solve(static.W, one))
    static.destroy()
    return K

