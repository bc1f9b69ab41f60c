"""The dynamic FEM wall: the last bead on plate and soil as an elastodynamic contact problem.

For one scene (soil E, nu, density; plate; bead), :class:`ContactFEM` holds the plate and
soil of :mod:`ssw.dynamics.system` on a mesh of :func:`ssw.contact.mesh.build_mesh` sized
by :mod:`ssw.dynamics.domain`, and the exact sphere-plate contact, unilateral and
frictionless: the candidates are the top-surface nodes with ``r <= r_cand``; the gap of
candidate ``i`` under the bead (rigid sphere shape, centre displaced ``d`` down from first
touch) is

    g_i = R - sqrt(R^2 - r_i^2) - d - w_i + (W_bead lam)_i,

``w_i`` the surface's vertical displacement and ``W_bead`` the bead's own compliance
(:mod:`ssw.dynamics.bead`). Two condensed problems share the candidates:

* **static** (factor ``K + Kb``): the force of a bead held at ``d``, the rest state under
  the chain's weight, and the quasi-static law of the same model (density -> 0);
* **dynamic** (factor ``K_eff`` of :class:`ssw.dynamics.newmark.Newmark`): one step is
  the free motion, one LCP ``g = g0 + (W_eff + W_bead) lam`` at the bead's new position,
  and the update; the wall force is ``sum(lam)``. The candidates' vertical dofs are
  massless (:func:`ssw.dynamics.system.without_mass`, Khenous, Laborde & Renard 2008):
  with their mass, nodes entering contact impact the sphere, and the trapezoidal rule,
  which neither damps nor bounds such jumps, let them grow into a chatter that blew up a
  no-plate run within 400 steps.

:class:`FEMWall` is a *stateful wall* (:class:`ssw.chain.wall.StatefulWall`) over
a list of scenes; :func:`fem_wall` builds it for a chain's scenes; :class:`StaticFEMWall`
is the same scenes' static law as a wall (a static LCP per step). The quasi-static
references of the study are static FEMs in fixed boxes (:mod:`ssw.dynamics.quasistatic`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ssw.contact.contact_lcp import solve_lcp
from ssw.contact.mesh import Mesh, build_mesh
from ssw.contact.petsc_solver import nd_order
from ssw.dynamics.bead import bead_compliance
from ssw.dynamics.domain import DomainSpec, mesh_settings
from ssw.dynamics.newmark import Newmark, State, Static
from ssw.dynamics.system import DynamicSystem, Material, assemble_dynamic, without_mass
from ssw.errors import ConfigError, SolverError

#: LCP gap tolerance relative to the indentation scale.
LCP_TOL = 1e-10
#: How the bead's elasticity enters (:class:`Scene`).
BEAD_MODELS = ("compliance", "scale", "rigid")
#: The FEM sleeps (the soil at rest under the static contact, the force the static one)
#: until the bead has moved this share of the indentation scale from its rest position:
#: the solitary wave's precursor moves it by ~1e-15 m long before the wave arrives.
WAKE = 1e-7


@dataclass(frozen=True)
class WallState:
    """One scene's wall state: the FEM state, whether the dynamics runs (``awake``) and
    the bead's rest indentation ``d`` (m) while it does not.

    Parameters
    ----------
    fem : State
        The FEM state.
    awake : bool
        Whether the dynamics runs.
    d : float
        The bead's rest indentation (m) while dormant.
    """

    fem: State
    awake: bool
    d: float


@dataclass(frozen=True)
class Scene:
    """One dynamic contact scene. SI units.

    ``plate`` is None (and ``plate_thickness`` 0) without a plate. ``bead`` says how the
    bead's own elasticity (``bead_E``, ``bead_nu``) enters: ``compliance`` (its half-space
    compliance in the LCP, :mod:`ssw.dynamics.bead`; the default), ``scale`` (the rigid
    sphere's FEM at the indentation ``d / s``, ``s`` of
    :func:`ssw.chain.wall_base.compliance_scale`: the quasi-static walls' rule, for
    comparisons with them) or ``rigid`` (none).

    Parameters
    ----------
    soil : Material
        The soil (Pa, -, kg/m^3).
    plate : Material or None
        The plate, or None.
    plate_thickness : float
        Plate thickness (m); 0 without a plate.
    plate_radius : float
        Plate radius (m).
    radius : float
        Bead radius (m).
    interface : str
        The plate-soil interface.
    bead_E : float or None
        Bead's Young's modulus (Pa).
    bead_nu : float or None
        Bead's Poisson's ratio.
    bead : str
        How the bead's elasticity enters: ``compliance``, ``scale`` or ``rigid``.
    """

    soil: Material
    plate: Material | None
    plate_thickness: float
    plate_radius: float
    radius: float
    interface: str = "frictionless"
    bead_E: float | None = None
    bead_nu: float | None = None
    bead: str = "compliance"

    def __post_init__(self) -> None:
        if self.bead not in BEAD_MODELS:
            raise ConfigError("dynamics.bead", self.bead, " | ".join(BEAD_MODELS))
        if self.bead != "rigid" and (self.bead_E is None or self.bead_nu is None):
            raise ConfigError("bead_E", self.bead_E, f"the bead's E and nu for bead={self.bead}")
        if self.plate_thickness < 0 or (self.plate_thickness > 0) != (self.plate is not None):
            raise ConfigError("plate", (self.plate, self.plate_thickness),
                              "a plate material with a thickness > 0, or none with 0")
        if not self.radius > 0:
            raise ConfigError("bead_radius", self.radius, "a radius > 0 m")
        for m, name in ((self.soil, "soil"), (self.plate, "plate")):
            if m is None:
                continue
            if not (m.E > 0 and -1.0 < m.nu <= 0.5 and m.density > 0):
                raise ConfigError(name, m, "E > 0 Pa, nu in (-1, 0.5], density > 0 kg/m^3")


def top_candidates(system: DynamicSystem, mesh: Mesh, r_cand: float) -> np.ndarray:
    """Top-surface nodes of the loaded body with ``r <= r_cand``, sorted by radius.

    Parameters
    ----------
    system : DynamicSystem
        The scene's operators.
    mesh : Mesh
        The scene's mesh.
    r_cand : float
        Radius of the candidate zone (m).

    Returns
    -------
    numpy.ndarray
        Node indices, sorted by radius.
    """
    s = system.static
    tol = 1e-9 * mesh.soil_radius
    top_body = 1 if mesh.plate_radius > 0 else 0
    nodes = np.unique(s.tri[s.body == top_body])
    on_top = nodes[np.abs(s.nodes[nodes, 1] - mesh.top) < tol]
    cand = on_top[s.nodes[on_top, 0] <= r_cand]
    return cand[np.argsort(s.nodes[cand, 0])]


class ContactFEM:
    """Static and dynamic sphere contact on one scene's plate and soil (module docstring).

    Parameters
    ----------
    scene : Scene
        The scene (bead, plate, soil).
    spec : ssw.dynamics.domain.DomainSpec
        The domain sizing.
    dt : float or None
        The time step, s (None: static only).
    r_cand : float
        The radius of the candidate zone, m.
    boundary : str
        ``absorbing`` | ``fixed``.
    d_scale : float
        The indentation scale of the LCP tolerance, m.
    """

    def __init__(self, scene: Scene, spec: DomainSpec, dt: float | None, r_cand: float,
                 boundary: str = "absorbing", d_scale: float = 1e-4) -> None:
        self.scene, self.spec, self.dt = scene, spec, dt
        settings = mesh_settings(scene.soil, scene.plate_radius, spec)
        self.mesh = build_mesh(scene.plate_thickness, scene.plate_radius, settings)
        self.system = assemble_dynamic(self.mesh, scene.soil, scene.plate, scene.interface,
                                       boundary, nd_order)
        cand = top_candidates(self.system, self.mesh, r_cand)
        if len(cand) < 4:
            raise ConfigError("dynamics.size_contact", spec.size_contact,
                              "a finer contact mesh: at least 4 nodes in the candidate zone")
        self.r = self.system.static.nodes[cand, 0]
        if np.any(self.r >= scene.radius):
            raise ConfigError("candidate radius", r_cand, f"< the bead radius {scene.radius}")
        self.dofs = self.system.static.udof[cand, 1]
        self.system = without_mass(self.system, self.dofs)
        self.shape = scene.radius - np.sqrt(scene.radius**2 - self.r**2)
        m = len(cand)
        self.W_bead = (bead_compliance(self.r, scene.bead_E, scene.bead_nu)
                       if scene.bead == "compliance" else np.zeros((m, m)))
        # the scale rule: the rigid sphere's indentation is the bead's d / s
        self.d_factor = 1.0
        if scene.bead == "scale":
            c_w = (1.0 - scene.soil.nu**2) / scene.soil.E
            c_b = (1.0 - scene.bead_nu**2) / scene.bead_E
            self.d_factor = (1.0 + c_b / c_w) ** (-2.0 / 3.0)
        self.static = Static(self.system, self.dofs)
        # the two condensed compliances of the LCPs (static, one step) and their factor caches
        self.W_static, self._cache_static = self.static.W + self.W_bead, {}
        self.tol, self.d_scale = LCP_TOL * d_scale, d_scale
        self.newmark = Newmark(self.system, dt, self.dofs) if dt is not None else None
        self.W_step = self.newmark.W + self.W_bead if self.newmark is not None else None
        self._cache_step: dict = {}
        self._active = np.zeros(m, bool)

    @property
    def n_candidates(self) -> int:
        """Number of contact candidate nodes."""
        return len(self.r)

    def _check_zone(self, lam: np.ndarray) -> None:
        if lam[-1] > 0:
            raise SolverError(f"the contact reached the last candidate (r = {self.r[-1]:.4g} m): "
                              "raise the candidate factor")

    # ------------------------------------------------------------------ static
    def static_contact(self, d: float) -> np.ndarray:
        """Contact forces (N) of the bead held at indentation ``d`` (m), at rest.

        Parameters
        ----------
        d : float
            Bead indentation (m).

        Returns
        -------
        numpy.ndarray
            Contact forces (N), one per candidate.
        """
        lam, self._active, _ = solve_lcp(self.W_static, self.shape - self.d_factor * d,
                                         self._active, self.tol, self._cache_static)
        self._check_zone(lam)
        return lam

    def static_force(self, d: np.ndarray) -> np.ndarray:
        """Quasi-static wall force (N) at indentations ``d`` (m), any shape.

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), any shape.

        Returns
        -------
        numpy.ndarray
            Force (N), the shape of ``d``.
        """
        d = np.asarray(d, float)
        return np.array([self.static_contact(x).sum() for x in d.ravel()]).reshape(d.shape)

    def static_indentation(self, F: float) -> float:
        """Indentation (m) at which the static force is ``F`` (N): the root of the monotone
        static law (:func:`ssw.roots.find_root`, the bracket grown from ``[0, 1 um]`` up
        to the bead's radius).

        Parameters
        ----------
        F : float
            Force (N).

        Returns
        -------
        float
            Indentation (m); 0 for ``F <= 0``.
        """
        from ssw.roots import find_root

        if F <= 0:
            return 0.0
        root = find_root(lambda d: self.static_force(d) - F, 0.0, 1e-6, grow=True,
                         limit=self.scene.radius)
        return float(root.x)

    def rest(self, d: float) -> State:
        """The state at rest with the bead held at ``d`` (m).

        Parameters
        ----------
        d : float
            Bead indentation (m).

        Returns
        -------
        State
            The FEM state at rest.
        """
        return self.static.state(self.static_contact(d))

    # ------------------------------------------------------------------ dynamic
    def start(self, d: float) -> WallState:
        """The dormant state at rest with the bead at ``d`` (m).

        Parameters
        ----------
        d : float
            Bead indentation (m).

        Returns
        -------
        WallState
            The dormant state.
        """
        return WallState(self.rest(d), awake=False, d=float(d))

    def advance(self, ws: WallState, d: float) -> tuple[float, WallState]:
        """One step to the bead indentation ``d`` (m), waking the FEM when the bead has moved
        by more than :data:`WAKE` x the indentation scale from its rest position.

        Parameters
        ----------
        ws : WallState
            The state at the step's start.
        d : float
            Bead indentation at the step's end (m).

        Returns
        -------
        F : float
            Wall force (N).
        state : WallState
            The new state.
        """
        if not ws.awake:
            if abs(d - ws.d) <= WAKE * self.d_scale:
                return float(self.static_contact(d).sum()), ws
            ws = WallState(self.rest(ws.d), awake=True, d=ws.d)
        F, st = self.step(ws.fem, d)
        return F, WallState(st, awake=True, d=float(d))

    def step(self, st: State, d: float) -> tuple[float, State]:
        """Advance one step to the bead indentation ``d`` (m): (wall force N, new state).

        Parameters
        ----------
        st : State
            The FEM state at the step's start.
        d : float
            Bead indentation at the step's end (m).

        Returns
        -------
        F : float
            Wall force (N).
        state : State
            The new FEM state.

        Raises
        ------
        SolverError
            If the contact was built without a time step.
        """
        if self.newmark is None:
            raise SolverError("this contact was built without a time step (static only)")
        u_free = self.newmark.free(st)
        g0 = self.shape - self.d_factor * d - u_free[self.dofs]
        lam, self._active, _ = solve_lcp(self.W_step, g0, self._active, self.tol,
                                         self._cache_step)
        self._check_zone(lam)
        return float(lam.sum()), self.newmark.finish(st, u_free, lam)

    def energy(self, st: State) -> tuple[float, float, float]:
        """(kinetic, strain incl. the bead's, radiated) energies (J) of a state.

        Parameters
        ----------
        st : State
            The FEM state.

        Returns
        -------
        tuple of float
            ``(kinetic, strain, radiated)`` (J).
        """
        kin, strain = self.system.energy(st.u, st.v)
        return kin, strain + 0.5 * float(st.lam @ (self.W_bead @ st.lam)), st.radiated

    def destroy(self) -> None:
        """Free the factorizations."""
        self.static.destroy()
        if self.newmark is not None:
            self.newmark.destroy()


class FEMWall:
    """A stateful wall over scenes, each a :class:`ContactFEM`
    (:class:`ssw.chain.wall.StatefulWall`). States are lists of :class:`WallState`.

    Parameters
    ----------
    contacts : list of ContactFEM
        One contact FEM per scene.
    """

    def __init__(self, contacts: list[ContactFEM]) -> None:
        self.contacts = list(contacts)
        dts = {c.dt for c in self.contacts}
        if len(dts) != 1:
            raise ConfigError("dt", sorted(dts, key=str), "one time step for every scene")
        self.dt = dts.pop()

    @property
    def n(self) -> int:
        """Number of scenes."""
        return len(self.contacts)

    def force(self, d: np.ndarray) -> np.ndarray:
        """Quasi-static force (N) at ``d`` (m), one per scene.

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Force (N), (n,).
        """
        return np.array([c.static_force(x) for c, x in zip(self.contacts, d, strict=True)])

    def indentation(self, F: np.ndarray) -> np.ndarray:
        """Static indentation (m) carrying ``F`` (N), one per scene.

        Parameters
        ----------
        F : numpy.ndarray
            Forces (N), scalar or (n,).

        Returns
        -------
        numpy.ndarray
            Indentation (m), (n,).
        """
        F = np.broadcast_to(np.asarray(F, float), (self.n,))
        return np.array([c.static_indentation(x) for c, x in zip(self.contacts, F, strict=True)])

    def hertz_equivalent(self, d_ref: float) -> np.ndarray:
        """``F(d_ref) / d_ref^1.5`` (N/m^1.5), static.

        Parameters
        ----------
        d_ref : float
            Reference indentation (m), > 0.

        Returns
        -------
        numpy.ndarray
            Equivalent Hertz coefficient (N/m^1.5), (n,).
        """
        return self.force(np.full(self.n, d_ref)) / d_ref**1.5

    def start(self, d0: np.ndarray) -> list[WallState]:
        """Dormant rest states with the beads at ``d0`` (m).

        Parameters
        ----------
        d0 : numpy.ndarray
            Initial indentations (m), (n,).

        Returns
        -------
        list of WallState
            One state per scene.
        """
        return [c.start(x) for c, x in zip(self.contacts, d0, strict=True)]

    def advance(self, states: list[WallState], d: np.ndarray, dt: float
                ) -> tuple[np.ndarray, list[WallState]]:
        """Wall forces (N) at the new indentations ``d`` (m) and the new states.

        Parameters
        ----------
        states : list of WallState
            One state per scene.
        d : numpy.ndarray
            Indentations (m), (n,).
        dt : float
            Time step (s); must be the one the FEM was factored for.

        Returns
        -------
        F : numpy.ndarray
            Wall forces (N), (n,).
        states : list of WallState
            The new states.

        Raises
        ------
        ConfigError
            If ``dt`` is not the wall's step.
        """
        if dt != self.dt:
            raise ConfigError("dt", dt, f"the step the FEM wall was factored for ({self.dt} s)")
        out = [c.advance(s, x) for c, s, x in zip(self.contacts, states, d, strict=True)]
        return np.array([f for f, _ in out]), [s for _, s in out]

    def energy(self, states: list[WallState]) -> tuple[np.ndarray, np.ndarray]:
        """Stored (kinetic + strain, J) and radiated (J) energy per scene (a dormant
        scene's: its rest state's).

        Parameters
        ----------
        states : list of WallState
            One state per scene.

        Returns
        -------
        stored : numpy.ndarray
            Kinetic plus strain energy (J), (n,).
        radiated : numpy.ndarray
            Energy radiated through the boundary (J), (n,).
        """
        e = np.array([c.energy(s.fem) for c, s in zip(self.contacts, states, strict=True)])
        return e[:, 0] + e[:, 1], e[:, 2]

    def take(self, idx: np.ndarray) -> FEMWall:
        """The scenes ``idx`` (may repeat).

        Parameters
        ----------
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        FEMWall
            The wall of the selected scenes (the same contacts).
        """
        return FEMWall([self.contacts[i] for i in np.atleast_1d(idx)])

    def take_state(self, states: list[WallState], idx: np.ndarray) -> list[WallState]:
        """The states of the scenes ``idx``.

        Parameters
        ----------
        states : list of WallState
            One state per scene.
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        list of WallState
            The selected states.
        """
        return [states[i] for i in np.atleast_1d(idx)]

    def destroy(self) -> None:
        """Free the contacts' factorizations."""
        for c in self.contacts:
            c.destroy()


def plate_of(params: Any, plate_density: float | None = None) -> Material | None:
    """The chain's plate as a :class:`ssw.dynamics.system.Material` (None without a plate); the
    density comes
    from the materials library by ``params.plate_material`` unless given.

    Parameters
    ----------
    params : ChainParams
        The chain (its plate).
    plate_density : float or None
        Plate density (kg/m^3); None: the materials library's for ``params.plate_material``.

    Returns
    -------
    Material or None
        The plate (Pa, -, kg/m^3), or None.
    """
    if params.plate_thickness <= 0:
        return None
    if plate_density is None:
        from ssw.materials import get_material

        plate_density = get_material(params.plate_material, field="plate.material").density
    return Material(float(params.plate_E), float(params.plate_nu), float(plate_density))


def scenes_of(params: Any, soil_E: Any, soil_nu: Any, soil_density: Any,
              plate_density: float | None = None, bead: str = "compliance") -> list[Scene]:
    """One :class:`Scene` per broadcast (E, nu, density) of the chain ``params``.

    Parameters
    ----------
    params : ChainParams
        The chain.
    soil_E : array_like
        Soil Young's modulus (Pa).
    soil_nu : array_like
        Soil Poisson's ratio.
    soil_density : array_like
        Soil density (kg/m^3).
    plate_density : float or None
        Plate density (kg/m^3); None: the materials library's for ``params.plate_material``.
    bead : str
        How the bead's elasticity enters (:class:`Scene`).

    Returns
    -------
    list of Scene
        One scene per broadcast soil.
    """
    E, nu, rho = (np.ravel(x) for x in np.broadcast_arrays(
        np.asarray(soil_E, float), np.asarray(soil_nu, float), np.asarray(soil_density, float)))
    plate = plate_of(params, plate_density)
    return [Scene(soil=Material(float(e), float(n), float(r)), plate=plate,
                  plate_thickness=float(params.plate_thickness) if plate is not None else 0.0,
                  plate_radius=0.5 * float(params.plate_diameter),
                  radius=float(params.bead_radius), interface=params.plate_interface,
                  bead_E=float(params.bead_E), bead_nu=float(params.bead_nu), bead=bead)
            for e, n, r in zip(E, nu, rho, strict=True)]


#: Candidate zone: CANDIDATE_FACTOR x the Hertz contact radius at the Hertz wall's peak.
CANDIDATE_FACTOR = 1.5


def fem_wall(
    params: Any, soil_E: Any, soil_nu: Any, soil_density: Any, *,
    boundary: str = "absorbing", spec: dict[str, Any] | None = None,
    plate_density: float | None = None, scales: Any = None,
    candidate_factor: float = CANDIDATE_FACTOR, bead: str = "compliance",
) -> tuple[FEMWall, Any]:
    """The dynamic FEM wall of the chain ``params`` on broadcast soils (E Pa, nu, density
    kg/m^3), and the scales it was sized with.

    ``bead``: see :class:`Scene`. ``spec`` overrides fields of
    :class:`ssw.dynamics.domain.DomainSpec` (``window`` and ``f_max`` default to the
    quasi-static run's, per scene). ``scales`` (:class:`ssw.dynamics.scales.ChainScales`;
    default: a Hertz wall run, :func:`ssw.dynamics.scales.chain_scales`) gives the step,
    the window and the candidate zone.

    Parameters
    ----------
    params : ChainParams
        The chain.
    soil_E : array_like
        Soil Young's modulus (Pa).
    soil_nu : array_like
        Soil Poisson's ratio.
    soil_density : array_like
        Soil density (kg/m^3).
    boundary : str
        ``absorbing`` or ``fixed``.
    spec : dict or None
        Fields of :class:`ssw.dynamics.domain.DomainSpec` to override.
    plate_density : float or None
        Plate density (kg/m^3); None: the materials library's for ``params.plate_material``.
    scales : ChainScales or None
        Step (s), window (s) and peak indentations (m); None: from a Hertz wall run.
    candidate_factor : float
        Candidate zone radius in units of ``sqrt(R d_peak)``.
    bead : str
        How the bead's elasticity enters (:class:`Scene`).

    Returns
    -------
    wall : FEMWall
        The dynamic FEM wall.
    scales : ChainScales
        The scales it was sized with.
    """
    from ssw.chain.wall import hertz_wall
    from ssw.dynamics.scales import chain_scales

    scenes = scenes_of(params, soil_E, soil_nu, soil_density, plate_density, bead)
    if scales is None:
        E, nu, _ = np.broadcast_arrays(np.asarray(soil_E, float), np.asarray(soil_nu, float),
                                       np.asarray(soil_density, float))
        scales = chain_scales(params, hertz_wall(params, E.ravel(), nu.ravel()))
    contacts = []
    for k, sc in enumerate(scenes):
        fields = {"window": float(scales.window[k]), "f_max": float(scales.f_max[k]),
                  **(spec or {})}
        r_cand = candidate_factor * np.sqrt(sc.radius * scales.d_peak[k])
        contacts.append(ContactFEM(sc, DomainSpec(**fields), scales.dt, r_cand, boundary,
                                   d_scale=float(scales.d_peak[k])))
    return FEMWall(contacts), scales


class StaticFEMWall(FEMWall):
    """The same scenes' quasi-static law (density -> 0): the static LCP at every step, no
    state (the reference of the quasi-static assumption on the same mesh).

    Parameters
    ----------
    contacts : list of ContactFEM
        One contact FEM per scene.
    """

    def start(self, d0: np.ndarray) -> np.ndarray:
        """The state: the bead indentations ``d0`` (m).

        Parameters
        ----------
        d0 : numpy.ndarray
            Initial indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            A copy of ``d0`` (m).
        """
        return np.asarray(d0, float).copy()

    def advance(self, states: np.ndarray, d: np.ndarray, dt: float
                ) -> tuple[np.ndarray, np.ndarray]:
        """The static force at the new indentations; the state is the indentation.

        Parameters
        ----------
        states : numpy.ndarray
            The bead indentations (m), (n,): the static wall's state.
        d : numpy.ndarray
            Indentations (m), (n,).
        dt : float
            Time step (s); unused.

        Returns
        -------
        F : numpy.ndarray
            Wall forces (N), (n,).
        states : numpy.ndarray
            The new indentations (m), (n,).
        """
        return self.force(d), d.copy()

    def energy(self, states: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Strain energy of the rest states at the indentations; nothing dissipated.

        Parameters
        ----------
        states : numpy.ndarray
            The bead indentations (m), (n,): the static wall's state.

        Returns
        -------
        stored : numpy.ndarray
            Stored energy (J), (n,).
        dissipated : numpy.ndarray
            Zeros (J), (n,).
        """
        e = [c.energy(c.rest(x)) for c, x in zip(self.contacts, states, strict=True)]
        return np.array([k + s for k, s, _ in e]), np.zeros(self.n)

    def take(self, idx: np.ndarray) -> StaticFEMWall:
        """The scenes ``idx`` (may repeat).

        Parameters
        ----------
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        StaticFEMWall
            The wall of the selected scenes.
        """
        return StaticFEMWall([self.contacts[i] for i in np.atleast_1d(idx)])

    def take_state(self, states: np.ndarray, idx: np.ndarray) -> np.ndarray:
        """The state of the scenes ``idx``.

        Parameters
        ----------
        states : numpy.ndarray
            The bead indentations (m), (n,): the static wall's state.
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        numpy.ndarray
            The selected indentations (m).
        """
        return states[idx]
