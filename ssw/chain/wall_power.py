"""The power laws of the last contact, ``F = coef [d]_+^n`` per scene (:class:`PowerWall`),
and the laws built as one:

* ``rigid``: the bead on a rigid flat, ``F = 4/3 sqrt(R) E_b/(1-nu_b^2) d^1.5`` (only the
  bead deforms). It is the mirror image of a bead-bead contact (``2^1.5 A``), which the
  tests use as an exact check;
* ``hertz``: the bead on the elastic half-space, ``F = A_w d^1.5``,
  ``A_w = 4/3 sqrt(R) / ((1-nu_b^2)/E_b + (1-nu_w^2)/E_w)`` (REFERENCE.md, Johnson 1985);
* ``fit``: the thesis's modified Hertz law ``F = K(E, nu) A_w d^1.5`` (``fit_law=k_hertz``)
  or the power law ``F = C (d/s)^n`` (``fit_law=power``) per scene, from explicit ``K=`` /
  ``power=(C, n)`` values or a table object with ``.K(E, nu)`` and ``.power(E, nu)``
  (``ssw.walls`` reads a K table file into one); ``s`` is the bead's compliance scale
  (:func:`ssw.chain.wall_base.compliance_scale`).

Each law carries its derivative in the soil's modulus where it is known (``dcoef_dE``,
``dexponent_dE``), for the exact forward sensitivities of :mod:`ssw.chain.sensitivity`.

A Hertzian law (every exponent 1.5, constant in E: ``rigid``, ``hertz``, ``fit`` with
``k_hertz``) is evaluated inside a run by the compiled step
(:meth:`PowerWall.step_power_law`, :func:`ssw.chain.kernel.power_law`), in the IEEE
operations of :meth:`PowerWall.force`, :meth:`PowerWall.dforce_dd` and
:meth:`PowerWall.dforce_dE` and their order (products and a square root, each correctly
rounded): the same bits as the run's Python loop on the law's own methods. Any other law
stays on that loop: numpy's ``power`` and ``log`` are not libm's on every CPU (with
AVX-512 numpy takes its own SIMD versions, which differ from glibc's ``pow`` in the last
bit of about 5 % of the values), so the step's ``pow`` would not reproduce the law's
numbers bit for bit.

References
----------
K. L. Johnson, *Contact Mechanics*, Cambridge University Press, 1985, ch. 4.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ssw.chain.params import ChainParams
from ssw.chain.wall_base import compliance_scale, compliance_scale_dE, scene_arrays
from ssw.errors import ConfigError
from ssw.hertz import effective_modulus, hertz_coefficient


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

    def step_power_law(self) -> tuple | None:
        """The law's rows for the compiled step, which then evaluates the wall's force
        itself (:meth:`ssw.chain.kernel.Stepper.use_power_law`), when the law is Hertzian
        (module docstring).

        Returns
        -------
        tuple or None
            ``(coef, exponent, dcoef_dE, dexponent_dE)``: (n,) float arrays (N/m^n, -,
            N/m^n/Pa, 1/Pa; the last two None where the law has none); None for a law with
            an exponent other than 1.5, or whose exponent moves with E (its ``dF/dE``
            takes a logarithm): the run evaluates it in Python.
        """
        de = self.dexponent_dE
        if not self.hertzian or (de is not None and np.any(de != 0.0)):
            return None
        return tuple(None if x is None else np.ascontiguousarray(x, float)
                     for x in (self.coef, self.exponent, self.dcoef_dE, self.dexponent_dE))

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
