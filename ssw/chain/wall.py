"""The chain's last contact: the wall protocol and the laws made of the chain's numbers.

A wall law gives the force ``F(d)`` (N) at the last bead's indentation ``d = u_{N-1}`` (m,
``[d]_+``: no tension), batched over scenes (one law per scene). The chain knows only the
protocol (:class:`Wall`); the laws that need the contact FEM, the fitted tables or the
soil's dynamics, and the registry of every law by name, live above the chain in
:mod:`ssw.walls`. The laws here:

* ``rigid``: the bead on a rigid flat, ``F = 4/3 sqrt(R) E_b/(1-nu_b^2) d^1.5`` (only the
  bead deforms). It is the mirror image of a bead-bead contact (``2^1.5 A``), which the
  tests use as an exact check;
* ``hertz``: the bead on the elastic half-space, ``F = A_w d^1.5``,
  ``A_w = 4/3 sqrt(R) / ((1-nu_b^2)/E_b + (1-nu_w^2)/E_w)`` (REFERENCE.md, Johnson 1985);
* ``fit``: the thesis's modified Hertz law ``F = K(E, nu) A_w d^1.5`` (``fit_law=k_hertz``)
  or the power law ``F = C (d/s)^n`` (``fit_law=power``) per scene, from explicit ``K=`` /
  ``power=(C, n)`` values or a table object with ``.K(E, nu)`` and ``.power(E, nu)``
  (``ssw.walls`` reads a K table file into one);
* ``table``: the FEM force-indentation curve itself (``curve=``: one
  :class:`ssw.curve.ForceCurve` or a path, or one per scene), interpolated (no fit error).

Bead compliance. The thesis's K and the FEM curves come from a *rigid* sphere, law
``F_R(d)``. The chain's bead is steel, so we add its compliance the way Hertz does
(``1/E* = c_w + c_b``, ``c = (1-nu^2)/E``): ``F(d) = F_R(d / s)`` with
``s = (1 + c_b/c_w)^(2/3)``. This is exact for a Hertz-shaped ``F_R`` and turns the
rigid-sphere law ``K 4/3 E_w/(1-nu_w^2) sqrt(R) d^1.5`` into exactly the thesis's
``K A_w d^1.5``; for the plate's non-Hertzian curves it is an approximation of relative
size ``c_b/c_w`` (2e-4 at 38 MPa, 5e-3 at 1000 MPa).

Table extension. Beyond the curve's last point ``(d_L, F_L)`` the force continues as the
power law ``F = F_L (d/d_L)^n_L`` whose exponent is the curve's log-log slope over its last
10 % of indentation (clipped to [1, 2]): C^0 and slope-continuous in the mean. The chain's
peak wall indentation (:func:`ssw.chain.run.peak_wall_indentation`) tells how far a
sweep reaches beyond the FEM range.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from ssw.chain.params import ChainParams
from ssw.errors import ConfigError, SswError
from ssw.hertz import effective_modulus, hertz_coefficient
from ssw.roots import find_root

#: Cells of the uniform indentation grid a FEM curve is resampled on.
TABLE_CELLS = 400
#: Share of the curve's indentation range used for the extension's exponent.
TABLE_TAIL = 0.1


def force_indentation(force: Any, F: Any, start: np.ndarray) -> np.ndarray:
    """Indentations (m) at which the non-decreasing laws ``force(d)`` carry ``F``.

    The bracket ``[0, start]`` is grown until it holds ``F``, then the roots are found by
    :func:`ssw.roots.find_root` to its default relative tolerance (a few ulp), vectorized
    over the scenes.

    Parameters
    ----------
    force : callable
        ``force(d) -> F``: the laws' forces (N) at the indentations ``d`` (m), one per
        scene.
    F : array_like
        Forces to carry (N), one per scene; a negative one is read as 0.
    start : array_like
        First upper end of each bracket (m, > 0).

    Returns
    -------
    ndarray
        Indentations (m), the broadcast shape of ``start`` and ``F``.
    """
    hi, target = np.broadcast_arrays(np.asarray(start, float), np.asarray(F, float))
    target = np.maximum(target, 0.0)
    return find_root(lambda d: force(d) - target, np.zeros(hi.shape), hi, grow=True).x


@dataclass(frozen=True)
class PowerWall:
    """``F = coef [d]_+^n`` per scene; shapes (n_scenes,).

    Parameters
    ----------
    coef : numpy.ndarray
        (n,) N/m^n.
    exponent : numpy.ndarray
        (n,) -.
    force_error : float or None
        Stated relative (1 sigma) error of the law's force; None when not known.
    dcoef_dE : numpy.ndarray or None
        (n,) N/m^n/Pa, the coefficient's derivative with respect to the soil's modulus
        (None: the law's E-dependence is not known, :meth:`dforce_dE` raises).
    dexponent_dE : numpy.ndarray or None
        (n,) 1/Pa, the exponent's (None: constant).
    """

    coef: np.ndarray
    exponent: np.ndarray
    hertzian: bool = field(init=False)  # every exponent is 1.5 (a faster path)
    force_error: float | None = None
    dcoef_dE: np.ndarray | None = None
    dexponent_dE: np.ndarray | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "hertzian", bool(np.all(self.exponent == 1.5)))

    @property
    def n(self) -> int:
        """Number of scenes."""
        return self.coef.shape[0]

    def force(self, d: np.ndarray) -> np.ndarray:
        """Wall force (N) at indentation ``d`` (m), shape (n_scenes,).

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Force (N), (n,); 0 for ``d <= 0``.
        """
        dp = np.maximum(d, 0.0)
        if self.hertzian:
            return self.coef * dp * np.sqrt(dp)
        return self.coef * dp**self.exponent

    def dforce_dd(self, d: np.ndarray) -> np.ndarray:
        """Tangent stiffness ``n coef d^(n-1)`` (N/m) at ``d`` (m); 0 for ``d <= 0``.

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Tangent stiffness (N/m), (n,).
        """
        dp = np.maximum(d, 0.0)
        if self.hertzian:
            return 1.5 * self.coef * np.sqrt(dp)
        return np.where(dp > 0, self.exponent * self.coef * dp ** (self.exponent - 1.0), 0.0)

    def dforce_dE(self, d: np.ndarray) -> np.ndarray:
        """``dF/dE`` (N/Pa) at fixed indentation ``d`` (m): ``dcoef/dE d^n + coef d^n ln(d)
        dn/dE``; ConfigError when the builder did not state the law's E-dependence.

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
            If the law was built without its E-dependence (``dcoef_dE`` is None).
        """
        if self.dcoef_dE is None:
            raise ConfigError("wall", "a power law without its E-dependence",
                              "a law built by hertz_wall, fit_wall or rigid_wall")
        dp = np.maximum(d, 0.0)
        dn = dp * np.sqrt(dp) if self.hertzian else dp ** self.exponent
        out = self.dcoef_dE * dn
        if self.dexponent_dE is not None:
            out = out + self.coef * dn * np.log(np.where(dp > 0, dp, 1.0)) * self.dexponent_dE
        return out

    def potential(self, d: np.ndarray) -> np.ndarray:
        """Stored energy ``coef d^(n+1) / (n+1)`` (J).

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Stored energy (J), (n,); 0 for ``d <= 0``.
        """
        dp = np.maximum(d, 0.0)
        return self.coef * dp ** (self.exponent + 1.0) / (self.exponent + 1.0)

    def indentation(self, F: np.ndarray) -> np.ndarray:
        """Indentation (m) carrying force ``F`` (N), the inverse of :meth:`force`.

        Parameters
        ----------
        F : numpy.ndarray
            Forces (N), (n,); values <= 0 give 0.

        Returns
        -------
        numpy.ndarray
            Indentation (m), (n,).
        """
        return (np.maximum(F, 0.0) / self.coef) ** (1.0 / self.exponent)

    def take(self, idx: np.ndarray) -> PowerWall:
        """The scenes ``idx`` (may repeat).

        Parameters
        ----------
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        PowerWall
            The law of the selected scenes.
        """
        return PowerWall(self.coef[idx], self.exponent[idx], force_error=self.force_error,
                         dcoef_dE=None if self.dcoef_dE is None else self.dcoef_dE[idx],
                         dexponent_dE=None if self.dexponent_dE is None
                         else self.dexponent_dE[idx])

    def hertz_equivalent(self, d_ref: float) -> np.ndarray:
        """``F(d_ref) / d_ref^1.5`` (N/m^1.5): a Hertz coefficient for time-step choice.

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


@dataclass(frozen=True)
class TableWall:
    """Tabulated ``F(d)`` per scene on a uniform grid, with a power-law extension.

    ``g[k] = F(k h) / (k h)^1.5`` is interpolated linearly (exact for Hertz at any grid);
    beyond ``d_last = TABLE_CELLS h`` the force is ``F_last (d/d_last)^n_ext``.

    Parameters
    ----------
    h : numpy.ndarray
        Grid step per scene (m), (n,).
    g : numpy.ndarray
        ``F(k h) / (k h)^1.5`` per scene (N/m^1.5), (n, TABLE_CELLS + 1).
    f_last : numpy.ndarray
        Force at the table's last indentation (N), (n,).
    n_ext : numpy.ndarray
        Exponent of the power-law extension, (n,).
    """

    h: np.ndarray  # m, grid step per scene, (n,)
    g: np.ndarray  # N/m^1.5, (n, TABLE_CELLS + 1)
    f_last: np.ndarray  # N
    n_ext: np.ndarray  # -

    @property
    def n(self) -> int:
        """Number of scenes."""
        return self.h.shape[0]

    @property
    def exact_reach(self) -> np.ndarray:
        """(n,) m: the last indentation of each scene's curve; beyond it the law is the
        power-law extension (:func:`beyond_exact_reach` flags a run that goes there)."""
        return self.h * (self.g.shape[1] - 1)

    def force(self, d: np.ndarray) -> np.ndarray:
        """Wall force (N) at indentation ``d`` (m): the interpolated table inside it, the
        power-law extension beyond ``d_last``.

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Force (N), (n,); 0 for ``d <= 0``.
        """
        dp = np.maximum(d, 0.0)
        cells = self.g.shape[1] - 1
        x = dp / self.h
        k = np.minimum(x.astype(np.int64), cells - 1)
        frac = np.minimum(x - k, 1.0)
        rows = np.arange(self.n) * (cells + 1)
        flat = self.g.ravel()
        gk = flat[rows + k]
        gval = gk + frac * (flat[rows + k + 1] - gk)
        inside = gval * dp * np.sqrt(dp)
        d_last = cells * self.h
        outside = self.f_last * (np.maximum(dp, d_last) / d_last) ** self.n_ext
        return np.where(x <= cells, inside, outside)

    def dforce_dd(self, d: np.ndarray) -> np.ndarray:
        """Tangent stiffness (N/m) of the tabulated law at ``d`` (m): ``g' d^1.5 + 1.5 g
        d^0.5`` inside the table (``g`` linear in each cell), the extension's beyond.

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Tangent stiffness (N/m), (n,).
        """
        dp = np.maximum(d, 0.0)
        cells = self.g.shape[1] - 1
        x = dp / self.h
        k = np.minimum(x.astype(np.int64), cells - 1)
        frac = np.minimum(x - k, 1.0)
        r = np.arange(self.n)
        g0, g1 = self.g[r, k], self.g[r, k + 1]
        sq = np.sqrt(dp)
        inside = (g1 - g0) / self.h * dp * sq + 1.5 * (g0 + frac * (g1 - g0)) * sq
        d_last = cells * self.h
        outside = (self.n_ext * self.f_last / d_last
                   * (np.maximum(dp, d_last) / d_last) ** (self.n_ext - 1.0))
        return np.where(x <= cells, inside, outside)

    def dforce_dE(self, d: np.ndarray) -> np.ndarray:
        """Not available: a table is one FEM curve per scene, data for one modulus (the
        ``fem`` wall is the same law as a function of E).

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Raises
        ------
        ConfigError
            Always: a table holds no E-dependence.
        """
        raise ConfigError("wall", "table", "a law with its E-dependence for dF/dE: fem, fit, "
                          "hertz (a table wall's curve is data for one modulus)")

    def indentation(self, F: np.ndarray) -> np.ndarray:
        """Indentation carrying ``F`` (N): the root of the monotone law
        (:func:`force_indentation`).

        Parameters
        ----------
        F : numpy.ndarray
            Forces (N), (n,); values <= 0 give 0.

        Returns
        -------
        numpy.ndarray
            Indentation (m), (n,).
        """
        return force_indentation(self.force, F, self.h * (self.g.shape[1] - 1))

    def take(self, idx: np.ndarray) -> TableWall:
        """The scenes ``idx`` (may repeat).

        Parameters
        ----------
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        TableWall
            The tables of the selected scenes.
        """
        return TableWall(self.h[idx], self.g[idx], self.f_last[idx], self.n_ext[idx])

    def hertz_equivalent(self, d_ref: float) -> np.ndarray:
        """``F(d_ref) / d_ref^1.5`` (N/m^1.5).

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


def beyond_exact_reach(wall: Any, peak_indentation: np.ndarray) -> np.ndarray:
    """The scenes whose last bead went deeper than the wall's exact law reaches.

    Parameters
    ----------
    wall : Wall
        The last contact (its ``exact_reach``, m: a tabulated FEM curve's end, the FEM
        law's computed range; none for a law defined at any depth).
    peak_indentation : numpy.ndarray
        (n,) m, the run's largest indentations.

    Returns
    -------
    numpy.ndarray
        (n,) bool: where the force was an extension, not the model.
    """
    reach = getattr(wall, "exact_reach", None)
    peak = np.asarray(peak_indentation, float)
    if reach is None:
        return np.zeros(peak.shape, bool)
    return peak > np.asarray(reach, float) * (1.0 + 1e-9)


class Wall(Protocol):
    """What the integrator needs of a last-contact law (one law per scene, ``n`` scenes).

    Every method is vectorized over the scenes: arrays of shape (n,), SI units.
    ``take(idx)`` selects scenes by index; ``idx`` may repeat one (a calibration scan
    tiles the walls of a few references over many parameter sets).

    Parameters
    ----------
    *args : Any
        Unused: a protocol is not instantiated.
    **kwargs : Any
        Unused: a protocol is not instantiated.
    """

    @property
    def n(self) -> int:
        """Number of scenes."""
        ...

    def force(self, d: np.ndarray) -> np.ndarray:
        """Wall force (N) at indentation ``d`` (m); 0 for ``d <= 0``.

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Force (N), (n,).
        """

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

    def indentation(self, F: np.ndarray) -> np.ndarray:
        """Indentation (m) carrying the force ``F >= 0`` (N): the inverse of :meth:`force`.

        Parameters
        ----------
        F : numpy.ndarray
            Forces (N), (n,), >= 0.

        Returns
        -------
        numpy.ndarray
            Indentation (m), (n,).
        """

    def take(self, idx: np.ndarray) -> Wall:
        """The scenes ``idx`` (may repeat).

        Parameters
        ----------
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        Wall
            The law of the selected scenes.
        """
        ...

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


def force_and_tangent(wall: Wall, d: np.ndarray, with_E: bool
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """A displacement wall's force, its tangent stiffness and (with ``with_E``) ``dF/dE`` at
    ``d``: the wall's own fused evaluation where it has one (``force_and_tangent``, e.g.
    :meth:`ssw.walls.fem.PiecewiseLinearWall.force_and_tangent`: one search of its pieces
    for the three), else its ``force``, ``dforce_dd`` and ``dforce_dE``.

    Parameters
    ----------
    wall : Wall
        The law, with ``dforce_dd`` (and ``dforce_dE`` for ``with_E``).
    d : numpy.ndarray
        Indentations (m), (n,).
    with_E : bool
        Whether ``dF/dE`` is wanted.

    Returns
    -------
    tuple
        ``(F, dF/dd, dF/dE)``: N, N/m and N/Pa, (n,) each; ``dF/dE`` None without
        ``with_E``.
    """
    fused = getattr(wall, "force_and_tangent", None)
    if fused is not None:
        return fused(d, with_E)
    w: Any = wall
    return w.force(d), w.dforce_dd(d), (w.dforce_dE(d) if with_E else None)


class StatefulWall(Protocol):
    """A last contact with internal state (the soil's motion, a sample's history).

    The integrator (:func:`ssw.chain.integrate.simulate`) keeps Verlet's structure
    (Hairer, Lubich & Wanner 2006, sec. I.1.4): each step drifts the positions, then
    evaluates the forces at the new positions, here

        F_wall(n+1), state(n+1) = wall.advance(state(n), u_last(n+1), dt),

    the wall integrating its own state over the step (implicitly if it likes: stiff
    internal dynamics cost nothing in step size) from the bead's new position only, so that
    the scheme stays explicit for the chain. Besides :class:`Wall`'s ``n``,
    ``indentation`` (the statics of the initial state), ``hertz_equivalent`` (the step)
    and ``take``, such a wall has (vectorized over ``n`` scenes, SI):

    * ``force(d)``: the force of the state at rest at ``d`` (the first step's);
    * ``start(d0) -> state``: the state at rest with the last beads at ``d0`` (m);
    * ``advance(state, d, dt) -> (F, state)``;
    * ``energy(state) -> (stored, dissipated)`` (J, (n,)): what the wall holds and what it
      radiated or dissipated so far (the run's energy record uses it instead of
      ``potential``);
    * ``take_state(state, idx)``: select scenes;
    * optionally ``dt`` (s): the step the wall was built for (a FEM's factorization).

    Exact forward sensitivities (:mod:`ssw.chain.sensitivity`) need two more methods:
    ``start_tangent(state, D0, dE) -> tstate`` and ``advance_tangent(state, tstate, d, D,
    dt, dE) -> (F, dF, state, tstate)``, ``D`` (n, k) the derivatives of the indentation
    with respect to the ``k`` parameters, ``dE`` (n, k) those of the soil's modulus, ``dF``
    (n, k) the force's; a wall without them is differentiated by central differences of
    its TOF (:mod:`ssw.tof.api`).

    Parameters
    ----------
    *args : Any
        Unused: a protocol is not instantiated.
    **kwargs : Any
        Unused: a protocol is not instantiated.
    """

    @property
    def n(self) -> int:
        """Number of scenes."""
        ...

    def force(self, d: np.ndarray) -> np.ndarray:
        """Force (N) of the state at rest at indentation ``d`` (the first step's).

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Force (N), (n,).
        """
        ...

    def indentation(self, F: np.ndarray) -> np.ndarray:
        """Indentation (m) at rest under force ``F`` (the initial state's statics).

        Parameters
        ----------
        F : numpy.ndarray
            Forces (N), (n,), >= 0.

        Returns
        -------
        numpy.ndarray
            Indentation (m), (n,).
        """
        ...

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
        ...

    def start(self, d0: np.ndarray) -> Any:
        """The state at rest with the last beads at ``d0``.

        Parameters
        ----------
        d0 : numpy.ndarray
            Initial indentations (m), (n,).

        Returns
        -------
        Any
            The wall's state.
        """
        ...

    def advance(self, state: Any, d: np.ndarray, dt: float) -> tuple[np.ndarray, Any]:
        """Integrate the wall's state over one step to the bead's new position.

        Parameters
        ----------
        state : Any
            The state at the step's start.
        d : numpy.ndarray
            Indentations (m) at the step's end, (n,).
        dt : float
            Time step (s).

        Returns
        -------
        tuple
            ``(F, state)``: the force (N), (n,), and the state at the step's end.
        """
        ...

    def energy(self, state: Any) -> tuple[np.ndarray, np.ndarray]:
        """Energy the wall holds and the energy it radiated or dissipated so far.

        Parameters
        ----------
        state : Any
            The wall's state.

        Returns
        -------
        tuple
            ``(stored, dissipated)``: J, (n,) each.
        """
        ...

    def take(self, idx: np.ndarray) -> StatefulWall:
        """The scenes ``idx`` (may repeat).

        Parameters
        ----------
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        StatefulWall
            The wall of the selected scenes.
        """
        ...

    def take_state(self, state: Any, idx: np.ndarray) -> Any:
        """The state of the scenes ``idx``.

        Parameters
        ----------
        state : Any
            The wall's state.
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        Any
            The state of the selected scenes.
        """
        ...


def is_stateful(wall: Any) -> bool:
    """Whether ``wall`` has internal state (:class:`StatefulWall`).

    Parameters
    ----------
    wall : Any
        A last-contact law.

    Returns
    -------
    bool
        True if it has an ``advance`` method.
    """
    return hasattr(wall, "advance")


def compliance_scale(params: ChainParams, soil_E: np.ndarray, soil_nu: np.ndarray) -> np.ndarray:
    """``s = (1 + c_b/c_w)^(2/3)``: rigid-sphere law ``F_R(d)`` -> steel bead ``F_R(d/s)``.

    Parameters
    ----------
    params : ChainParams
        The chain (its bead's compliance ``c_b``).
    soil_E : numpy.ndarray
        Pa.
    soil_nu : numpy.ndarray
        -.

    Returns
    -------
    numpy.ndarray
        -, broadcast.
    """
    c_w = (1.0 - np.asarray(soil_nu, float) ** 2) / np.asarray(soil_E, float)
    return (1.0 + params.bead_compliance / c_w) ** (2.0 / 3.0)


def compliance_scale_dE(params: ChainParams, soil_E: np.ndarray, soil_nu: np.ndarray
                        ) -> np.ndarray:
    """``ds/dE`` of :func:`compliance_scale`: with ``x = c_b E / (1 - nu^2)``,
    ``s = (1 + x)^(2/3)`` and ``ds/dE = 2/3 (1 + x)^(-1/3) c_b / (1 - nu^2)``.

    Parameters
    ----------
    params : ChainParams
        The chain.
    soil_E : numpy.ndarray
        Pa.
    soil_nu : numpy.ndarray
        -.

    Returns
    -------
    numpy.ndarray
        1/Pa, broadcast.
    """
    k = params.bead_compliance / (1.0 - np.asarray(soil_nu, float) ** 2)
    return 2.0 / 3.0 * (1.0 + k * np.asarray(soil_E, float)) ** (-1.0 / 3.0) * k


def scene_arrays(soil_E: Any, soil_nu: Any) -> tuple[np.ndarray, np.ndarray]:
    """Soil moduli and Poisson's ratios broadcast together and flattened, one per scene.

    Parameters
    ----------
    soil_E : array_like
        Pa, broadcast with ``soil_nu``: one scene each.
    soil_nu : array_like
        -.

    Returns
    -------
    tuple of numpy.ndarray
        (n,) Pa and (n,) -.

    Raises
    ------
    ConfigError
        E <= 0 or nu outside (-1, 0.5].
    """
    E, nu = np.broadcast_arrays(np.asarray(soil_E, float), np.asarray(soil_nu, float))
    E, nu = E.ravel(), nu.ravel()
    if np.any(~(E > 0)):
        raise ConfigError("soil_E", E[~(E > 0)].tolist(), "moduli > 0 Pa")
    if np.any((nu <= -1) | (nu > 0.5)):
        raise ConfigError("soil_nu", nu.tolist(), "Poisson's ratios in (-1, 0.5]")
    return E, nu


def rigid_wall(params: ChainParams, soil_E: Any, soil_nu: Any) -> PowerWall:
    """Rigid flat: ``F = 4/3 sqrt(R) E_b/(1-nu_b^2) d^1.5`` (only the bead deforms).

    Parameters
    ----------
    params : ChainParams
        The chain.
    soil_E : array_like
        Pa, broadcast with ``soil_nu``: they only set the count of scenes.
    soil_nu : array_like
        -.

    Returns
    -------
    PowerWall
        One law per scene (no E-dependence).
    """
    E, _ = scene_arrays(soil_E, soil_nu)
    coef = hertz_coefficient(effective_modulus(params.bead_E, params.bead_nu), params.bead_radius)
    return PowerWall(np.full(E.size, coef), np.full(E.size, 1.5), dcoef_dE=np.zeros(E.size))


def hertz_wall(params: ChainParams, soil_E: Any, soil_nu: Any) -> PowerWall:
    """Elastic half-space: ``F = A_w d^1.5`` (REFERENCE.md; Johnson 1985 ch. 4).

    Parameters
    ----------
    params : ChainParams
        The chain.
    soil_E : array_like
        Pa, broadcast with ``soil_nu``: one scene each.
    soil_nu : array_like
        -.

    Returns
    -------
    PowerWall
        One law per scene, with ``dA_w/dE``.
    """
    E, nu = scene_arrays(soil_E, soil_nu)
    return PowerWall(params.wall_coefficient(E, nu), np.full(E.size, 1.5),
                     dcoef_dE=params.wall_coefficient_dE(E, nu))


def fit_wall(
    params: ChainParams,
    soil_E: Any,
    soil_nu: Any,
    *,
    K: Any = None,
    power: tuple[Any, Any] | None = None,
    k_table: Any = None,
) -> PowerWall:
    """Modified Hertz: ``F = K A_w d^1.5`` (k_hertz) or ``F = C (d/s)^n`` (power).

    Parameters
    ----------
    params : ChainParams
        The chain (``fit_law`` picks the table's law).
    soil_E : array_like
        Pa, broadcast with ``soil_nu``: one scene each.
    soil_nu : array_like
        -.
    K : array_like or None
        Constant K (-), broadcast to the scenes.
    power : tuple or None
        ``(C, n)``: the rigid-sphere law ``F = C delta^n`` (N/m^n, -), constants.
    k_table : object or None
        A table with ``.K(E, nu)`` and ``.power(E, nu)`` (``ssw.fit.table.KTable``); its
        ``dK_dE`` and ``dpower_dE``, when it has them, give the law's E-dependence.

    Returns
    -------
    PowerWall
        With ``dcoef_dE`` (and ``dexponent_dE`` for the power law): explicit ``K`` or
        ``(C, n)`` are constants in E (the Hertz coefficient and the bead's compliance
        scale carry it); a table's are its interpolant's derivatives (None if it has none).

    Raises
    ------
    ConfigError
        Not exactly one of ``K``, ``power``, ``k_table``; values out of range.
    """
    E, nu = scene_arrays(soil_E, soil_nu)
    dK: Any = 0.0
    dC: Any = 0.0
    dn: Any = 0.0
    given = [x is not None for x in (K, power, k_table)]
    if sum(given) != 1:
        raise ConfigError(
            "fit wall", {"K": K, "power": power, "k_table": k_table},
            "exactly one of K, power=(C, n) or k_table",
        )
    force_error = None
    if k_table is not None:
        if not hasattr(k_table, "K"):
            raise ConfigError("k_table", k_table, "a table with .K(E, nu) and .power(E, nu) "
                              "(ssw.walls.build_wall reads a K table file)")
        table = k_table
        # the table's stated leave-one-out interpolation bound (ssw.fit.table.interp_error),
        # taken as the law's force error: conservative as a 1-sigma figure, and it leaves
        # out the fitted shape's own misfit to the FEM curve (rule fit_tof_impact)
        stated = table.interp_error() if hasattr(table, "interp_error") else {}
        if params.fit_law == "k_hertz":
            K = table.K(E, nu)
            force_error = stated.get("K")
            dK = table.dK_dE(E, nu) if hasattr(table, "dK_dE") else None
        else:
            power = table.power(E, nu)
            force_error = stated.get("power")
            dC, dn = table.dpower_dE(E, nu) if hasattr(table, "dpower_dE") else (None, None)
        force_error = None if force_error is None or not np.isfinite(force_error) else float(
            force_error)
    if K is not None:
        Kv = np.broadcast_to(np.asarray(K, float), E.shape).copy()
        if np.any(~(Kv > 0)):
            raise ConfigError("K", Kv.tolist(), "K > 0")
        A_w = params.wall_coefficient(E, nu)
        dcoef = None if dK is None else (dK * A_w + Kv * params.wall_coefficient_dE(E, nu))
        return PowerWall(Kv * A_w, np.full(E.size, 1.5), force_error=force_error,
                         dcoef_dE=None if dcoef is None else np.broadcast_to(
                             dcoef, E.shape).copy())
    C, n = (np.broadcast_to(np.asarray(x, float), E.shape).copy() for x in power)  # type: ignore[union-attr]
    if np.any(~(C > 0)) or np.any(~((n >= 1.0) & (n <= 3.0))):
        raise ConfigError("power", (C.tolist(), n.tolist()), "C > 0 and 1 <= n <= 3")
    s = compliance_scale(params, E, nu)
    coef = C / s**n
    if dC is None:
        return PowerWall(coef, n, force_error=force_error)
    # coef = C s^-n: dcoef/dE = coef (C'/C - n s'/s - ln(s) n')
    ds = compliance_scale_dE(params, E, nu)
    dcoef = coef * (dC / C - n * ds / s - np.log(s) * dn)
    return PowerWall(coef, n, force_error=force_error,
                     dcoef_dE=np.broadcast_to(dcoef, E.shape).copy(),
                     dexponent_dE=np.broadcast_to(np.asarray(dn, float), E.shape).copy())


def table_wall(
    params: ChainParams, soil_E: Any, soil_nu: Any, *, curve: Any = None
) -> TableWall:
    """The FEM curve(s) themselves, interpolated (module docstring).

    Parameters
    ----------
    params : ChainParams
        The chain (the bead's compliance).
    soil_E : array_like
        Pa, broadcast with ``soil_nu``: one scene each.
    soil_nu : array_like
        -.
    curve : ForceCurve or str or sequence
        One curve (:class:`ssw.curve.ForceCurve` or HDF5 path) for every scene, or a
        sequence with one per scene.

    Returns
    -------
    TableWall
        One table per scene (data for one modulus each: no E-dependence).

    Raises
    ------
    ConfigError
        No curve, or not one per scene.
    """
    E, nu = scene_arrays(soil_E, soil_nu)
    if curve is None:
        raise ConfigError("curve", None, "a contact curve (ForceCurve or results/contact/*.h5)")
    curves = list(curve) if isinstance(curve, Sequence) and not isinstance(curve, str) else [
        curve
    ] * E.size
    if len(curves) != E.size:
        raise ConfigError("curve", f"{len(curves)} curves", f"one per scene ({E.size})")
    s = compliance_scale(params, E, nu)
    rows = [_resample(_as_curve(c), si) for c, si in zip(curves, s, strict=True)]
    h, g, fl, ne = (np.array(x) for x in zip(*rows, strict=True))
    return TableWall(h, g, fl, ne)


def _as_curve(c: Any) -> Any:
    if hasattr(c, "delta") and hasattr(c, "force"):
        return c
    from ssw.curve import read_curve

    return read_curve(c, extras=False)


def _resample(curve: Any, scale: float) -> tuple[float, np.ndarray, float, float]:
    """Grid step, ``g = F/d^1.5`` on the grid, last force and extension exponent."""
    d = np.asarray(curve.delta, float) * scale
    F = np.asarray(curve.force, float)
    if d[0] > 0:  # the curve starts at contact: F(0) = 0
        d, F = np.concatenate([[0.0], d]), np.concatenate([[0.0], F])
    if np.any(np.diff(F) < 0) or not F[-1] > 0:
        raise SswError("a contact curve for the table wall must be non-decreasing and end > 0 N")
    d_last = d[-1]
    h = d_last / TABLE_CELLS
    grid = h * np.arange(TABLE_CELLS + 1)
    pos = d > 0
    g = np.interp(grid, d[pos], F[pos] / d[pos] ** 1.5)  # F/d^1.5 is what is interpolated
    tail = d >= (1.0 - TABLE_TAIL) * d_last
    sel = tail & (d > 0) & (F > 0)
    if np.count_nonzero(sel) >= 2:
        n_ext = float(np.polyfit(np.log(d[sel]), np.log(F[sel]), 1)[0])
    else:
        n_ext = 1.5
    return h, g, float(F[-1]), float(np.clip(n_ext, 1.0, 2.0))
