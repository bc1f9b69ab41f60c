"""The ``fem`` wall: the FEM force-indentation law itself, computed when the chain needs it.

For each scene (soil E, nu) under the chain's plate (``ChainParams.plate_*``; thickness 0:
none), the law of a rigid sphere of the bead's radius pressed into the plate on that soil
is the exact solution path of the condensed FEM contact problem
(:mod:`ssw.contact.operators`, :mod:`ssw.contact.parametric`): piecewise linear in the
indentation between breakpoints (a candidate node entering or leaving the contact). No fit,
no interpolation across E, no extrapolation inside its range. Once the operators of the
plate and of the soil's nu exist (built on demand, cached on disk), a scene costs a dense
condensation and a path trace: milliseconds.

Range. The law is traced to the indentation ``d_exact`` at which the wall would store
:data:`ENERGY_MARGIN` times the striker's kinetic energy plus the work of the chain's weight
and preload, ``U(d) = k 1/2 m_s v^2 + (M g + P) d`` (the bound of
:func:`ssw.fit.range.energy_bound_indentation` with the wall's own potential instead of
Hertz's, and ``k`` = :data:`ENERGY_MARGIN` for striker speeds up to twice the nominal one,
as a calibration scan tries). Beyond it the last piece continues linearly (never reached
by a chain the bound holds for: tests/test_fem_wall.py).

Bead compliance. The FEM's sphere is rigid; the bead's compliance is added as for the other
FEM-based walls (:func:`ssw.chain.wall_base.compliance_scale`): ``F(d) = F_R(d / s)``.

Representation. The exact law is kept as it is: per scene its breakpoints and the
coefficients ``F = a + b d`` of each piece, evaluated by one binary search per call over all
scenes' breakpoints at once (:class:`PiecewiseLinearWall`). Its TOF is the exact law's;
``ssw bench contact --wall`` measures the cost against a 400-cell table of the same law.

Force error. Against the exact sphere on a half-space (Sneddon 1965) the FEM law has two
errors: the mesh's, which falls as the mesh growth squared (node-to-surface contact,
``tests/test_contact.py::test_mesh_convergence_rate``; rms ``FORCE_ERROR_COEF * growth^2``
over 1e-6..1e-4 m in a 3 m domain, ``ssw bench contact``), and the finite soil sample's,
which stiffens the contact by about ``DOMAIN_ERROR_COEF * a / L`` (``a`` the contact radius,
``L`` the domain radius = depth; measured: +0.23 % at a = 2.9 mm in the 1 m domain, 0.03 %
in a 3 m one). ``force_error`` (1 sigma) is their quadratic sum at the largest contact
radius the chain reaches among the scenes (the nominal energy bound), a conservative figure
(measured rms over the law's range: 1.1e-3 at 20 MPa, 1.0e-3 at 300 MPa, against 1.9e-3 and
1.0e-3 stated; tests/test_fem_wall.py). Plate curves converge under refinement faster than
the bare soil's (the slow test of ``tests/test_contact.py``).
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ssw.chain.kernel import piecewise
from ssw.chain.params import ChainParams
from ssw.errors import ConfigError, SolverError

#: Energy the law's range must hold, as a multiple of the striker's kinetic energy (module
#: docstring): 4 = twice the nominal striker speed.
ENERGY_MARGIN = 4.0
#: ``force_error = FORCE_ERROR_COEF * mesh_growth^2``: rms relative force error of the
#: no-plate curve against Sneddon over 1e-6..1e-4 m, 1000 increments, 3 m domain, measured
#: by ``ssw bench contact`` at growth 0.1 (5.3e-4) and 0.2 (1.9e-3) (module docstring).
FORCE_ERROR_COEF = 0.053
#: Relative stiffening of the contact by a finite domain per unit ``a / L`` (module
#: docstring; ssw bench contact --domain-study, tests/test_fem_wall.py).
DOMAIN_ERROR_COEF = 0.9


@dataclass(frozen=True)
class PiecewiseLinearWall:
    """``F(d)`` piecewise linear per scene: ``F = a_j + b_j d`` on ``[d_j, d_{j+1}]``.

    Arrays (n, K + 1): ``d`` breakpoints (m, increasing, ``d[:, 0] = 0``, rows padded with
    their last value), ``a`` (N), ``b`` (N/m) of the piece that starts at each breakpoint
    (the last real piece repeated at the end and in the padding: the linear continuation),
    ``U`` (J) the potential at the breakpoints. ``d_exact`` (n,) m: where the exact law
    ends. ``force_error``: relative 1-sigma force error of each scene's law, (n,) (None:
    unknown). ``da_dE``, ``db_dE`` (n, K + 1), N/Pa and N/m/Pa, or None: the pieces'
    coefficients' derivatives with respect to the soil's modulus (:func:`fem_wall`).

    Parameters
    ----------
    d : numpy.ndarray
        Breakpoints (m), (n, K + 1), increasing from 0.
    a : numpy.ndarray
        Intercepts of the pieces (N), (n, K + 1).
    b : numpy.ndarray
        Slopes of the pieces (N/m), (n, K + 1).
    U : numpy.ndarray
        Potential at the breakpoints (J), (n, K + 1).
    d_exact : numpy.ndarray
        Where the exact law ends (m), (n,).
    force_error : numpy.ndarray or None
        Relative 1-sigma force error per scene, (n,); None: unknown.
    da_dE : numpy.ndarray or None
        ``da/dE`` (N/Pa), (n, K + 1), or None.
    db_dE : numpy.ndarray or None
        ``db/dE`` (N/m/Pa), (n, K + 1), or None.
    """

    d: np.ndarray
    a: np.ndarray
    b: np.ndarray
    U: np.ndarray
    d_exact: np.ndarray
    force_error: np.ndarray | None = None
    da_dE: np.ndarray | None = None
    db_dE: np.ndarray | None = None
    _fkeys: np.ndarray = field(init=False, repr=False)
    _fend: np.ndarray = field(init=False, repr=False)
    _off: np.ndarray = field(init=False, repr=False)  # 2 x row: each row's key offset
    _law: tuple = field(init=False, repr=False)  # the arrays, C-contiguous (step_law)

    def __post_init__(self) -> None:
        n = self.d.shape[0]
        rows = 2.0 * np.arange(n)[:, None]
        F = self.a + self.b * self.d
        fend = F[:, -1]
        object.__setattr__(self, "_fend", fend)
        object.__setattr__(self, "_fkeys", (rows + F / fend[:, None]).ravel())
        object.__setattr__(self, "_off", rows.ravel().copy())
        object.__setattr__(self, "_law", tuple(
            None if x is None else np.ascontiguousarray(x, float)
            for x in (self.d, self.a, self.b, self.da_dE, self.db_dE)))

    @property
    def n(self) -> int:
        """Number of scenes."""
        return self.d.shape[0]

    @property
    def exact_reach(self) -> np.ndarray:
        """(n,) m: where each scene's exact law ends (beyond it: its linear continuation)."""
        return self.d_exact

    def _piece(self, x: np.ndarray, keys: np.ndarray) -> np.ndarray:
        """Flat index of the piece holding the normalized values ``x`` (n,) in [0, 1] (the
        forces, for :meth:`indentation`; the law's own search is the step's,
        :func:`ssw.chain.kernel.piecewise`).

        Row ``i``'s keys lie in ``[2 i, 2 i + 1]`` with its first key ``2 i``, so for ``x``
        in [0, 1] the search lands inside the row: no clipping needed."""
        return np.searchsorted(keys, x + self._off, side="right") - 1

    def step_law(self) -> tuple:
        """The law's arrays as the chain's step evaluates them itself
        (:func:`ssw.chain.kernel.piecewise`): ``(d, a, b, da_dE, db_dE)``.

        Returns
        -------
        tuple
            (n, K + 1) arrays, C-contiguous (the derivatives None when unknown).
        """
        return self._law

    def force(self, d: np.ndarray) -> np.ndarray:
        """Wall force (N) at indentation ``d`` (m), shape (n,); 0 for ``d <= 0``.

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Force (N), (n,).
        """
        return piecewise(self._law, d)[0]

    def dforce_dd(self, d: np.ndarray) -> np.ndarray:
        """Tangent stiffness (N/m): the slope ``b`` of the piece holding ``d`` (m); 0 for
        ``d <= 0``.

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Tangent stiffness (N/m), (n,).
        """
        return piecewise(self._law, d, tangent=True)[1]

    def dforce_dE(self, d: np.ndarray) -> np.ndarray:
        """``dF/dE`` (N/Pa) at fixed indentation ``d`` (m): ``da/dE + db/dE d`` of the piece
        holding ``d`` (the law is continuous at the breakpoints, which move with E, so
        their motion adds nothing); ConfigError without the pieces' derivatives.

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            ``dF/dE`` (N/Pa), (n,).

        Raises
        ------
        ConfigError
            If the wall was built without the pieces' E-derivatives.
        """
        self._check_dE()
        return piecewise(self._law, d, with_E=True)[2]

    def _check_dE(self) -> None:
        if self.da_dE is None or self.db_dE is None:
            raise ConfigError("wall", "fem (unilateral interface)",
                              "a frictionless or bonded plate, or none, for dF/dE")

    def force_and_tangent(self, d: np.ndarray, with_E: bool
                          ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """``(F, dF/dd, dF/dE)`` at indentations ``d`` (m) from one search of the pieces:
        :meth:`force`, :meth:`dforce_dd` and, with ``with_E``, :meth:`dforce_dE` (else
        None) (:func:`ssw.chain.wall.force_and_tangent`); ConfigError for ``with_E``
        without the pieces' derivatives.

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).
        with_E : bool
            Whether ``dF/dE`` is wanted.

        Returns
        -------
        tuple
            ``(F, dF/dd, dF/dE)``: N, N/m and N/Pa, (n,) each; ``dF/dE`` None without
            ``with_E``.

        Raises
        ------
        ConfigError
            If the wall was built without the pieces' E-derivatives.
        """
        if with_E:
            self._check_dE()
        return piecewise(self._law, d, tangent=True, with_E=with_E)[:3]

    def potential(self, d: np.ndarray) -> np.ndarray:
        """Stored energy ``int_0^d F`` (J).

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Stored energy (J), (n,).
        """
        dp = np.maximum(np.asarray(d, float), 0.0)
        j = np.arange(self.n) * self.d.shape[1] + piecewise(self._law, dp, piece=True)[3]
        dj, aj, bj = self.d.ravel()[j], self.a.ravel()[j], self.b.ravel()[j]
        return self.U.ravel()[j] + (dp - dj) * (aj + 0.5 * bj * (dp + dj))

    def indentation(self, F: np.ndarray) -> np.ndarray:
        """Indentation (m) carrying the force ``F >= 0`` (N): the inverse of :meth:`force`.

        Parameters
        ----------
        F : numpy.ndarray
            Forces (N), scalar or (n,).

        Returns
        -------
        numpy.ndarray
            Indentation (m), (n,).
        """
        Fp = np.maximum(np.broadcast_to(np.asarray(F, float), (self.n,)), 0.0)
        j = self._piece(np.minimum(Fp / self._fend, 1.0), self._fkeys)
        aj, bj = self.a.ravel()[j], self.b.ravel()[j]
        return np.where(Fp > 0, (Fp - aj) / bj, 0.0)

    def take(self, idx: np.ndarray) -> PiecewiseLinearWall:
        """The scenes ``idx`` (may repeat).

        Parameters
        ----------
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        PiecewiseLinearWall
            The law of the selected scenes.
        """
        def sel(x: np.ndarray | None) -> np.ndarray | None:
            return None if x is None else np.asarray(x)[idx]

        return PiecewiseLinearWall(self.d[idx], self.a[idx], self.b[idx], self.U[idx],
                                   self.d_exact[idx], sel(self.force_error), sel(self.da_dE),
                                   sel(self.db_dE))

    def hertz_equivalent(self, d_ref: float) -> np.ndarray:
        """``F(d_ref) / d_ref^1.5`` (N/m^1.5), for the time-step choice.

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


def chain_energy(params: ChainParams) -> tuple[float, float]:
    """``(W0, Wg)``: the striker's kinetic energy ``1/2 m_s v^2`` (J) and the static load
    ``M g + P`` (N) on the wall's indentation (``M`` the chain's mass with gravity on, ``P``
    the preload).

    Parameters
    ----------
    params : ChainParams
        The chain.

    Returns
    -------
    W0 : float
        Striker's kinetic energy (J), at the largest striker speed.
    Wg : float
        Static load on the wall (N), at the largest preload.
    """
    m = params.masses
    W0 = 0.5 * float(m[0]) * float(np.max(params.striker_velocity)) ** 2
    Wg = (float(np.sum(m)) * params.g if params.gravity else 0.0) + float(
        np.max(params.preload))
    return W0, Wg


def energy_bound(d: np.ndarray, F: np.ndarray, W: float, Wg: float) -> tuple[float, np.ndarray]:
    """Smallest indentation ``x`` (m) with ``U(x) - Wg x = W``, ``U = int_0^x F``, for the
    piecewise-linear force through ``(d_j, F_j)`` (inf if the range holds none), and the
    potential ``U`` (J) at the breakpoints.

    ``U - Wg x`` is convex (the force is non-decreasing), so the first breakpoint past the
    level brackets the root; on that piece ``U`` is an exact quadratic, solved in closed form
    (the cancellation-free root).

    Parameters
    ----------
    d : numpy.ndarray
        Breakpoint indentations (m), increasing, from 0.
    F : numpy.ndarray
        Forces at the breakpoints (N), non-decreasing.
    W : float
        Energy brought (J).
    Wg : float
        Constant load (N).

    Returns
    -------
    x : float
        The indentation (m), inf if the range holds none.
    U : numpy.ndarray
        Potential at the breakpoints (J).
    """
    U = np.concatenate([[0.0], np.cumsum(0.5 * (F[1:] + F[:-1]) * np.diff(d))])
    g = U - Wg * d - W
    k = np.flatnonzero(g >= 0)
    if k.size == 0:
        return np.inf, U
    j = int(k[0])
    if j == 0:
        return float(d[0]), U
    x0, x1 = float(d[j - 1]), float(d[j])
    slope = (F[j] - F[j - 1]) / (x1 - x0)
    c = float(g[j - 1])  # < 0
    bq = float(F[j - 1]) - Wg
    y = -2.0 * c / (bq + np.sqrt(bq * bq - 2.0 * slope * c))
    return float(min(x0 + y, x1)), U


def fem_wall(
    params: ChainParams, soil_E: Any, soil_nu: Any, *, contact: dict[str, Any] | None = None,
    operators: Any = None, with_dE: bool = False,
) -> PiecewiseLinearWall:
    """The exact FEM law of each scene (module docstring).

    Parameters
    ----------
    params : ChainParams
        The chain; its ``bead_radius`` (the indenter), ``plate_*`` (the plate; thickness 0:
        none), striker, masses, gravity and preload (the range).
    soil_E : array_like
        Pa, broadcast with ``soil_nu``: one scene each.
    soil_nu : array_like
        -.
    contact : dict or None
        The ``contact`` settings (mesh, zone); defaults :data:`ssw.contact.scene.DEFAULTS`; the
        plate's interface and diameter are the device's (``params``), not these.
    operators : OperatorStore or None
        :class:`ssw.contact.operators.OperatorStore` (default: the process's).
    with_dE : bool
        Also the pieces' derivatives with respect to the soil's modulus
        (``_pieces_dE``: implicit differentiation of the condensed contact problem at
        each piece's active set; frictionless or bonded plates, or none), for
        ``dforce_dE``; they cost about half a build more.

    Returns
    -------
    PiecewiseLinearWall
        One law per scene.

    Raises
    ------
    SolverError
        The range does not hold the chain's energy within the contact zone.
    """
    from ssw.chain.wall import compliance_scale, compliance_scale_dE, scene_arrays
    from ssw.contact.operators import default_store, geometry_of, scene_lcp
    from ssw.contact.parametric import prefix_path
    from ssw.contact.scene import settings_of
    from ssw.hertz import effective_modulus, energy_indentation, hertz_coefficient

    E, nu = scene_arrays(soil_E, soil_nu)
    # the plate is the device's: its interface and diameter, whatever the contact settings say
    cfg = settings_of({**(contact or {}), "interface": params.plate_interface,
                       "plate_diameter": params.plate_diameter})
    store = operators if operators is not None else default_store()
    R, t = float(params.bead_radius), float(params.plate_thickness)
    has_plate = t > 0
    plate = (float(params.plate_E), float(params.plate_nu))
    W0, Wg = chain_energy(params)
    W = ENERGY_MARGIN * W0
    s = compliance_scale(params, E, nu)
    ds = compliance_scale_dE(params, E, nu)
    # a first guess of the range (rigid-sphere coordinates): the Hertz bound of the softer
    # half-space, where (2/5) A d^2.5 = W + Wg d (a plate stiffer than the soil only lowers
    # the real one); it sets the candidate zone, the trace goes on as far as needed
    Eh = np.minimum(E, plate[0]) if has_plate else E
    A = hertz_coefficient(effective_modulus(Eh, nu), R)
    # the margined energy's reach (the guess) and the nominal one's (the zone, the error
    # model below) in one call of the elementwise root finder (each root its own iteration)
    guess, reach = energy_indentation(A, np.stack([np.broadcast_to(W, A.shape),
                                                   np.broadcast_to(W0, A.shape)]), Wg)
    # the zone: as the study's curves (the nominal energy's reach), so that the wall shares
    # their operators; a deeper contact is caught (the last candidate must stay open)
    geom = geometry_of(cfg, t, R, float(np.max(reach)), cfg["interface"])
    layout = store.layout(geom)
    plate_op = store.body(geom, "plate", plate[1]) if has_plate else None
    rows = []
    for i in range(E.size):
        key = _law_key(geom, plate if has_plate else None, float(E[i]), float(nu[i]), R,
                       cfg["interface"])
        law = _LAWS.get(key)
        if law is not None and (law.df0 is not None or not with_dE):
            _LAWS.move_to_end(key)
            row = _chain_row(law, s[i], float(ds[i]), W, Wg, with_dE)
            if row is not None:
                rows.append(row)
                continue
        soil_op = store.body(geom, "soil", float(nu[i]))
        lcp = scene_lcp(layout, plate_op, soil_op, float(E[i]),
                        plate[0] if has_plate else None, cfg["interface"], R)
        ms = lcp.n_sphere
        path = prefix_path(lcp.W, lcp.q0, lcp.q1) if lcp.tie is None else None
        if path is not None and ms == lcp.q0.size:
            # the whole path of a disk-shaped contact: kept in rigid coordinates (a scene's
            # law for every chain on it), mapped to this chain's range and compliance
            law = _rigid_law(lcp, path, ms, with_dE)
            _keep(key, law)
            row = _chain_row(law, s[i], float(ds[i]), W, Wg, with_dE)
            if row is None:
                raise _beyond_zone(float(layout.r[-1]), float(E[i]))
            rows.append(row)
            continue
        rows.append(_traced_row(lcp, path, s[i], float(ds[i]), float(guess[i]), W, Wg, R,
                                float(E[i]), with_dE))
    return _assemble(rows, _force_error(cfg, R, reach))


def _force_error(cfg: dict[str, Any], R: float, reach: np.ndarray) -> np.ndarray:
    """The stated relative force error of each scene's law: the mesh's error and the finite
    domain's stiffening at the scene's own contact radius ``sqrt(R reach)`` (m; a soft
    soil's is larger), from the contact settings ``cfg`` (m)."""
    a_peak = np.sqrt(R * reach)
    L = min(float(cfg["soil_radius"]), float(cfg["soil_depth"]))
    return np.hypot(FORCE_ERROR_COEF * float(cfg["mesh_growth"]) ** 2,
                    DOMAIN_ERROR_COEF * a_peak / L)


def _beyond_zone(zone: float, soil_E: float) -> SolverError:
    """The error of a range that does not hold the chain's energy within the contact zone
    (``zone``, m, the last candidate's radius; ``soil_E``, Pa)."""
    return SolverError(f"the fem wall's range does not hold the chain's energy within its "
                       f"contact zone (r <= {zone:.4g} m; soil E {soil_E:.4g} Pa)")


def _traced_row(lcp: Any, path: Any, s: float, ds: float, end: float, W: float, Wg: float,
                R: float, soil_E: float, with_dE: bool) -> tuple[Any, ...]:
    """One scene's law (a row of :func:`_assemble`) from its contact path as far as the
    chain's energy reaches: ``path`` the whole path when the problem has one in closed
    form, else None and the path is traced from ``end`` (m, rigid coordinates; doubled
    until the energy bound is finite, :func:`energy_bound`). ``s``, ``ds`` the bead's
    compliance scale and its derivative in E (1/Pa); ``W``, ``Wg`` the chain's energy (J)
    and weight (N); ``R`` the bead radius (m); ``soil_E`` (Pa) for the messages."""
    from ssw.contact.parametric import Tracer

    ms = lcp.n_sphere
    zone = float(lcp.r[-1])
    tracer = None if path is not None else Tracer(lcp.W, lcp.q0, lcp.q1)
    while True:
        if tracer is not None:
            tracer.advance(end)
            path = tracer.path()
        dR = path.breaks
        F = np.concatenate([path.lam0[:, :ms].sum(1) + dR[:-1] * path.lam1[:, :ms].sum(1),
                            [path.lam0[-1, :ms].sum() + dR[-1] * path.lam1[-1, :ms].sum()]])
        d = s * dR
        bound, U = energy_bound(d, F, W, Wg)
        if np.isfinite(bound):
            break
        if tracer is None or end > 0.5 * R:
            raise _beyond_zone(zone, soil_E)
        end *= 2.0
    if np.any(path.active[:, ms - 1]):
        raise SolverError(
            f"the contact zone of the fem wall reached its last candidate (r = "
            f"{zone:.4g} m); soil E {soil_E:.4g} Pa")
    keep = d <= bound * (1 + 1e-12)
    j_end = int(np.count_nonzero(keep))  # breakpoints up to the bound, plus the next
    j_end = min(j_end + 1, d.size)
    row = _pieces(d[:j_end], path, ms, s, U[:j_end])
    deriv = None
    if with_dE and lcp.dW_dE is not None and lcp.tie is None:
        df0, df1 = _pieces_dE(lcp.W, lcp.dW_dE, path, ms, j_end - 1)
        deriv = _chain_dE(df0, df1, path.lam1[:j_end - 1, :ms].sum(axis=1), s, ds)
    return (*row, *(deriv if deriv is not None else (None, None)))


def _pieces(d: np.ndarray, path: Any, ms: int, s: float, U: np.ndarray
            ) -> tuple[np.ndarray, ...]:
    """Breakpoints, piece coefficients (chain coordinates) and potential of one scene."""
    k = d.size - 1  # pieces
    f0 = path.lam0[:k, :ms].sum(axis=1)
    f1 = path.lam1[:k, :ms].sum(axis=1) / s  # F = f0 + f1_R (d / s)
    a = np.concatenate([f0, f0[-1:]])
    b = np.concatenate([f1, f1[-1:]])
    return d, a, b, U


#: Scene laws kept in memory (``_rigid_law``: a few kB each), least recently used out.
LAWS_KEPT = 20_000
_LAWS: OrderedDict[tuple[Any, ...], RigidLaw] = OrderedDict()


@dataclass(frozen=True)
class RigidLaw:
    """The exact law of the rigid sphere on one scene, in its own coordinates: the pieces of
    the whole prefix path (every candidate of the zone), ``F = f0 + f1 delta`` on
    ``[breaks[j], breaks[j + 1]]`` (m, N, N/m), and ``df0``, ``df1`` their derivatives with
    respect to the soil's modulus (N/Pa, N/m/Pa; None: not computed). What a chain adds is
    its own: the bead's compliance and the range its energy needs (``_chain_row``).

    Parameters
    ----------
    breaks : numpy.ndarray
        Piece breakpoints (m).
    f0 : numpy.ndarray
        Intercepts (N).
    f1 : numpy.ndarray
        Slopes (N/m).
    df0 : numpy.ndarray or None
        ``df0/dE`` (N/Pa), or None.
    df1 : numpy.ndarray or None
        ``df1/dE`` (N/m/Pa), or None.
    """

    breaks: np.ndarray
    f0: np.ndarray
    f1: np.ndarray
    df0: np.ndarray | None = None
    df1: np.ndarray | None = None


def _law_key(geom: Any, plate: tuple[float, float] | None, E: float, nu: float, R: float,
             interface: str) -> tuple[Any, ...]:
    """What a scene's rigid law depends on: the geometry (mesh, zone), the plate's
    ``(E, nu)``, the soil's, the sphere's radius and the interface."""
    return (geom.key(), plate, E, nu, R, interface)


def _keep(key: tuple[Any, ...], law: RigidLaw) -> None:
    _LAWS[key] = law
    _LAWS.move_to_end(key)
    while len(_LAWS) > LAWS_KEPT:
        _LAWS.popitem(last=False)


def _rigid_law(lcp: Any, path: Any, ms: int, with_dE: bool) -> RigidLaw:
    """The :class:`RigidLaw` of a whole prefix path (and its E derivatives when asked and
    the LCP has them)."""
    k = path.pieces
    f0 = path.lam0[:, :ms].sum(axis=1)
    f1 = path.lam1[:, :ms].sum(axis=1)
    if with_dE and lcp.dW_dE is not None:
        df0, df1 = _pieces_dE(lcp.W, lcp.dW_dE, path, ms, k)
        return RigidLaw(path.breaks.copy(), f0, f1, df0, df1)
    return RigidLaw(path.breaks.copy(), f0, f1)


def _chain_row(law: RigidLaw, s: float, ds: float, W: float, Wg: float, with_dE: bool
               ) -> tuple[Any, ...] | None:
    """One scene's pieces in the chain's coordinates (``d = s delta``) up to the energy
    bound of ``W`` (J) with the static load ``Wg`` (N), plus the next breakpoint, as
    :func:`fem_wall` builds them; None when the law's range does not hold the energy."""
    dR = law.breaks
    F = np.concatenate([law.f0 + dR[:-1] * law.f1, [law.f0[-1] + dR[-1] * law.f1[-1]]])
    d = s * dR
    bound, U = energy_bound(d, F, W, Wg)
    if not np.isfinite(bound):
        return None
    j_end = min(int(np.count_nonzero(d <= bound * (1 + 1e-12))) + 1, d.size)
    k = j_end - 1
    a = np.concatenate([law.f0[:k], law.f0[k - 1:k]])
    b = np.concatenate([law.f1[:k], law.f1[k - 1:k]]) / s
    if not with_dE or law.df0 is None or law.df1 is None:
        return d[:j_end], a, b, U[:j_end], None, None
    da, db = _chain_dE(law.df0[:k], law.df1[:k], law.f1[:k], s, ds)
    return d[:j_end], a, b, U[:j_end], da, db


def _pieces_dE(W: np.ndarray, dW: np.ndarray, path: Any, ms: int, k: int
               ) -> tuple[np.ndarray, np.ndarray]:
    """``df0/dE`` and ``df1/dE`` of the first ``k`` pieces in the rigid sphere's
    coordinates (N/Pa, N/m/Pa; :func:`_chain_dE` maps them to the chain's).

    On piece ``j`` with active set ``A`` the path is ``lam_A = alpha + delta beta``,
    ``W_AA alpha = -q0_A``, ``W_AA beta = -q1_A`` (:mod:`ssw.contact.parametric`); the gaps'
    data do not depend on E, so implicit differentiation gives ``W_AA dalpha = -dW_AA alpha``
    and the same for ``beta`` (exact for the piecewise-linear law at its active sets). With
    ``f0 = sum alpha``, ``f1 = sum beta`` over the sphere's candidates, the chain's law is
    ``a = f0``, ``b = f1 / s`` (``s`` the bead's compliance scale, ``ds = ds/dE``).
    """
    from scipy.linalg import cho_factor, cho_solve, solve_triangular

    m = W.shape[0]
    act = path.active[:k]  # (k, m)
    # the right-hand sides -dW_AA lam_A (lam is 0 off A), both parts: (m, 2k)
    lam = np.concatenate([path.lam0[:k], path.lam1[:k]], axis=0)
    mask = np.concatenate([act, act], axis=0).T
    rhs = -(dW @ lam.T) * mask
    sol = np.zeros_like(rhs)
    size = act.sum(axis=1)
    prefix = np.concatenate([np.all(act[:, None, :] == (np.arange(m) < size[:, None])[:, None, :],
                                    axis=2)[:, 0]] * 2)
    if np.any(prefix):
        # a prefix active set {0..p-1}: W_pp^-1 = Z_pp^T Z_pp with Z = L^-1 (W = L L^T):
        # masked products with the whole triangular Z give every piece at once
        L = np.linalg.cholesky(W)
        Z = solve_triangular(L, np.eye(m), lower=True, check_finite=False)
        y = (Z @ rhs[:, prefix]) * mask[:, prefix]
        sol[:, prefix] = (Z.T @ y) * mask[:, prefix]
    for j in np.flatnonzero(~prefix):
        a_j = np.flatnonzero(mask[:, j])
        if a_j.size:
            sol[a_j, j] = cho_solve(cho_factor(W[np.ix_(a_j, a_j)], lower=True), rhs[a_j, j])
    return sol[:ms, :k].sum(axis=0), sol[:ms, k:].sum(axis=0)


def _chain_dE(df0: np.ndarray, df1: np.ndarray, f1: np.ndarray, s: float, ds: float
              ) -> tuple[np.ndarray, np.ndarray]:
    """``da/dE`` and ``db/dE`` of the chain's pieces ``a = f0``, ``b = f1 / s`` (``s`` the
    bead's compliance scale, ``ds = ds/dE``), the last one repeated as :func:`_pieces`
    does."""
    da = np.concatenate([df0, df0[-1:]])
    db = df1 / s - f1 * ds / s**2
    return da, np.concatenate([db, db[-1:]])


def concatenate(walls: list[PiecewiseLinearWall]) -> PiecewiseLinearWall:
    """The scenes of several walls as one (each row padded with its last value, as
    :func:`fem_wall` pads its scenes; the derivatives kept only if every wall has them):
    the walls of several plates or chains' ranges advanced in one batched run.

    Parameters
    ----------
    walls : list of PiecewiseLinearWall
        The walls.

    Returns
    -------
    PiecewiseLinearWall
        One wall of all their scenes, in order.
    """
    width = max(w.d.shape[1] for w in walls)

    def stack(name: str) -> np.ndarray:
        parts = []
        for w in walls:
            x = getattr(w, name)
            parts.append(np.concatenate([x, np.repeat(x[:, -1:], width - x.shape[1], axis=1)],
                                        axis=1))
        return np.concatenate(parts, axis=0)

    deriv = all(w.da_dE is not None and w.db_dE is not None for w in walls)
    errors = [w.force_error for w in walls]
    error = (np.concatenate([np.broadcast_to(e, (w.n,)) for e, w in zip(errors, walls,
                                                                         strict=True)])
             if all(e is not None for e in errors) else None)
    return PiecewiseLinearWall(stack("d"), stack("a"), stack("b"), stack("U"),
                               np.concatenate([w.d_exact for w in walls]), error,
                               stack("da_dE") if deriv else None,
                               stack("db_dE") if deriv else None)


def _assemble(rows: list[tuple[Any, ...]], force_error: np.ndarray) -> PiecewiseLinearWall:
    """Pad the scenes' pieces to one width (the derivatives only if every scene has them)."""
    width = max(r[0].size for r in rows)
    deriv = all(r[4] is not None for r in rows)
    out = []
    for col in range(6 if deriv else 4):
        arr = np.empty((len(rows), width))
        for i, r in enumerate(rows):
            v = r[col]
            arr[i, : v.size] = v
            arr[i, v.size:] = v[-1]
        out.append(arr)
    d, a, b, U = out[:4]
    da, db = out[4:] if deriv else (None, None)
    return PiecewiseLinearWall(d, a, b, U, d[:, -1].copy(), force_error, da, db)


def peak_stresses(params: ChainParams, soil_E: Any, soil_nu: float, d_wall: Any, *,
                  contact: dict[str, Any] | None = None, operators: Any = None,
                  force: Any = None) -> Any:
    """The contact's elastic stresses at the chain's peak wall indentations ``d_wall`` (m,
    one per soil modulus ``soil_E``, Pa; one ``soil_nu``): the indentation moved into the
    rigid sphere's coordinates of the FEM (the bead's compliance out,
    :func:`ssw.chain.wall_base.compliance_scale`) and the device's plate (its material,
    thickness, diameter and interface, as :func:`fem_wall` has them) with the elastic bead
    (:func:`ssw.contact.stress.contact_stresses`; ``force``, N, the wall's force there when
    known). Returns its ``ContactStress``.

    Parameters
    ----------
    params : ChainParams
        The chain.
    soil_E : array_like
        Soil Young's moduli (Pa).
    soil_nu : float
        Soil Poisson's ratio.
    d_wall : array_like
        Peak wall indentations (m), one per modulus.
    contact : dict or None
        The contact FEM settings; None: the defaults.
    operators : Any
        A store of the FEM's operators to reuse, or None.
    force : array_like or None
        The wall's forces at ``d_wall`` (N), when known.

    Returns
    -------
    ContactStress
        The contact's elastic stresses (Pa).
    """
    from ssw.chain.wall import compliance_scale
    from ssw.contact.stress import contact_stresses

    E = np.atleast_1d(np.asarray(soil_E, float))
    delta = np.asarray(d_wall, float) / compliance_scale(params, E, np.full(E.size, soil_nu))
    has_plate = params.plate_thickness > 0
    cfg = {**(contact or {}), "interface": params.plate_interface,
           "plate_diameter": params.plate_diameter}
    return contact_stresses(E, soil_nu, (params.plate_E, params.plate_nu) if has_plate
                            else None, params.plate_thickness, params.bead_radius, delta,
                            cfg, store=operators, bead=(params.bead_E, params.bead_nu),
                            force=force)
