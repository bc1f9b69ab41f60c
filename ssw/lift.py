"""A compacted lift on a subgrade, read as a half-space: how wrong is E?

A field test point is a lift of thickness ``h`` and modulus ``E1`` on a subgrade of
``E2``; an inversion that takes the ground for a half-space of one modulus returns an
apparent ``E_app`` between the two. :func:`lift_errors` computes ``E_app / E1 - 1`` with
the device's chain on exact contact laws of the layered oracle (:mod:`ssw.contact.layered`,
Burmister's layered elastic solution by Hankel transforms, with the device's plate as its
top layer, frictionless on the lift, the lift bonded to the subgrade): the TOF of the
layered ground, inverted through the TOFs of half-spaces computed the same way (so that
the oracle's own discretization error cancels). Both curves reach the indentation at which
a Hertz half-space of the softer medium stores ``reach_energy`` (the study's
``contact.reach_energy``), beyond the chain's own reach.

The error falls as ``1/h`` (the contact's stress bulb is a few contact radii deep): the
thickness below which it exceeds a tolerance is :func:`warning_thickness`.

References
----------
Burmister, D. M. (1945). The general theory of stresses and displacements in layered
systems. J. Appl. Phys. 16, 89-94.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ssw.errors import ConfigError

#: Increments of each oracle curve (uniform to the energy reach), and the reach's margin.
CURVE_STEPS = 400
REACH_MARGIN = 1.2


@dataclass(frozen=True)
class LiftErrors:
    """Apparent-modulus errors of a half-space reading: ``error[i, j]`` (relative) for
    ``ratios[i]`` = E2 / E1 and ``thicknesses[j]`` (m); the lift's ``E1`` (Pa), ``nu``.

    Parameters
    ----------
    E1 : float
        Young's modulus of the lift (Pa).
    nu : float
        Poisson's ratio of the lift.
    subgrade_nu : float
        Poisson's ratio of the subgrade.
    ratios : numpy.ndarray
        Subgrade moduli over ``E1``, (n_ratios,).
    thicknesses : numpy.ndarray
        Lift thicknesses (m), (n_thicknesses,).
    error : numpy.ndarray
        Relative error of the apparent modulus, (n_ratios, n_thicknesses).
    tof : numpy.ndarray
        Layered TOFs (s), (n_ratios, n_thicknesses).
    """

    E1: float
    nu: float
    subgrade_nu: float
    ratios: np.ndarray
    thicknesses: np.ndarray
    error: np.ndarray
    tof: np.ndarray  # (n_ratios, n_thicknesses) s

    def to_dict(self) -> dict[str, Any]:
        """The result as plain lists and numbers (SI), with each ratio's warning thickness.

        Returns
        -------
        dict
            ``E1`` (Pa), ``nu``, ``subgrade_nu``, ``ratios``, ``thicknesses`` (m), ``error``,
            ``tof`` (s) and ``warning_thickness`` (m or None, by ratio).
        """
        return {"E1": self.E1, "nu": self.nu, "subgrade_nu": self.subgrade_nu,
                "ratios": self.ratios.tolist(), "thicknesses": self.thicknesses.tolist(),
                "error": self.error.tolist(), "tof": self.tof.tolist(),
                "warning_thickness": {f"{r:g}": warning_thickness(self, r)
                                      for r in self.ratios}}


def _stack(params: Any, E1: float, nu: float, lift: tuple[float, float, float] | None) -> Any:
    from ssw.contact.layered_kernel import Layer, Stack

    layers, ifaces = [], []
    if params.plate_thickness > 0:
        layers.append(Layer(float(params.plate_E), float(params.plate_nu),
                            float(params.plate_thickness)))
        ifaces.append("frictionless")
    if lift is None:
        return Stack(tuple(layers), tuple(ifaces), float(E1), float(nu))
    h, E2, nu2 = lift
    layers.append(Layer(float(E1), float(nu), float(h)))
    ifaces.append("bonded")
    return Stack(tuple(layers), tuple(ifaces), float(E2), float(nu2))


def _curve(params: Any, E1: float, nu: float, lift: tuple[float, float, float] | None,
           energy: float) -> Any:
    from ssw.contact.layered import LayeredSettings, solve_stack
    from ssw.fit.range import energy_reach

    soft = min(E1, lift[1]) if lift is not None else E1
    reach = REACH_MARGIN * float(energy_reach(soft, nu, None, None, params.bead_radius,
                                              energy)[0])
    d = np.linspace(reach / CURVE_STEPS, reach, CURVE_STEPS)
    return solve_stack(_stack(params, E1, nu, lift), params.bead_radius, d,
                       LayeredSettings())[0]


def lift_errors(params: Any, E1: float, nu: float, ratios: Any, thicknesses: Any, *,
                subgrade_nu: float | None = None, energy: float = 0.01,
                E_grid: Any = None) -> LiftErrors:
    """``E_app / E1 - 1`` of a lift (E1 Pa, nu; ``thicknesses`` m) on subgrades of
    ``ratios`` x E1 (``subgrade_nu``, default ``nu``), read through the device's chain
    ``params`` as a half-space (module docstring): the layered TOFs inverted by
    :func:`ssw.tof.inverse.invert_batch` on the half-spaces' TOFs (``E_grid``, Pa: the
    half-spaces; default 41 moduli over E1/5..5 E1, log-spaced).

    Parameters
    ----------
    params : Any
        The device's chain parameters (:class:`ssw.chain.params.ChainParams`).
    E1 : float
        Young's modulus of the lift (Pa), > 0.
    nu : float
        Poisson's ratio of the lift.
    ratios : array_like
        Subgrade moduli as multiples of ``E1``, > 0.
    thicknesses : array_like
        Lift thicknesses (m), > 0.
    subgrade_nu : float or None
        Poisson's ratio of the subgrade; None: ``nu``.
    energy : float
        Impact energy of the contact curves' reach (J).
    E_grid : array_like or None
        Half-space moduli of the inversion (Pa); None: 41 log-spaced over E1/5..5 E1.

    Returns
    -------
    LiftErrors
        Relative errors of the apparent modulus and the layered TOFs (s).

    Raises
    ------
    ConfigError
        If a modulus, ratio or thickness is not > 0, or the half-spaces' TOFs do not
        bracket every layered TOF.
    """
    from ssw.tof import api
    from ssw.tof.inverse import ForwardGrid, invert_batch

    ratios = np.atleast_1d(np.asarray(ratios, float))
    hs = np.atleast_1d(np.asarray(thicknesses, float))
    if not (E1 > 0 and np.all(ratios > 0) and np.all(hs > 0)):
        raise ConfigError("lift", {"E1": E1, "ratios": ratios.tolist(),
                                   "thicknesses": hs.tolist()},
                          "a modulus > 0 Pa, ratios > 0 and thicknesses > 0 m")
    nu2 = float(nu if subgrade_nu is None else subgrade_nu)
    grid = (np.geomspace(E1 / 5.0, E1 * 5.0, 41) if E_grid is None
            else np.asarray(E_grid, float))
    half = [_curve(params, float(E), nu, None, energy) for E in grid]
    tof_half = np.asarray(api.tof(grid, np.full(grid.size, nu), params, "table", curve=half))
    curves = [_curve(params, E1, nu, (h, r * E1, nu2), energy) for r in ratios for h in hs]
    tof = np.asarray(api.tof(np.full(len(curves), E1), np.full(len(curves), nu), params,
                             "table", curve=curves)).reshape(ratios.size, hs.size)
    # the one TOF inversion (its guards, its interpolation) on the half-spaces' grid
    half_grid = ForwardGrid(grid, tof_half[None, :], np.array([float(nu)]), {})
    inv = invert_batch(tof.ravel(), float(nu), params, "table", grid=half_grid, refine=0,
                       strict=False)
    bad = [r for r in inv.reason if r]
    if bad:
        raise ConfigError("E_grid", [grid[0], grid[-1]],
                          "half-space moduli whose TOFs fall strictly and bracket every "
                          f"layered TOF ({bad[0]})")
    E_app = inv.E.reshape(tof.shape)
    return LiftErrors(float(E1), float(nu), nu2, ratios, hs, E_app / E1 - 1.0, tof)


def warning_thickness(res: LiftErrors, ratio: float, tolerance: float = 0.02) -> float | None:
    """The lift thickness (m) below which a half-space reading errs by more than
    ``tolerance`` on the subgrade ``ratio`` x E1: the error ~ c / h interpolated in
    ``ln h`` between the computed thicknesses; None when it stays within the tolerance
    over them (or never does).

    Parameters
    ----------
    res : LiftErrors
        The computed errors.
    ratio : float
        The subgrade ratio (the nearest computed one is used).
    tolerance : float
        Largest accepted relative error.

    Returns
    -------
    float or None
        Thickness (m), or None.
    """
    i = int(np.argmin(np.abs(res.ratios - ratio)))
    e = np.abs(res.error[i])
    h = res.thicknesses
    above = e > tolerance
    if not above.any() or above.all():
        return None
    j = int(np.flatnonzero(above)[-1])
    if j + 1 >= h.size:
        return None
    t = (np.log(e[j]) - np.log(tolerance)) / (np.log(e[j]) - np.log(e[j + 1]))
    return float(np.exp(np.log(h[j]) + t * (np.log(h[j + 1]) - np.log(h[j]))))


def plot_lift(res: LiftErrors, path: str) -> None:
    """The errors against lift thickness, one line per subgrade ratio (PNG, atomic).

    Parameters
    ----------
    res : LiftErrors
        The computed errors.
    path : str
        The PNG file to write.
    """
    from ssw.plotting import pyplot, save_png

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.0, 4.0))
    for i, r in enumerate(res.ratios):
        ax.plot(res.thicknesses * 1e3, res.error[i] * 100, marker="o",
                label=f"subgrade E2 = {r:g} E1")
    ax.axhline(0.0, color="0.5", lw=0.8)
    for tol in (-2.0, 2.0):
        ax.axhline(tol, color="0.7", lw=0.8, ls="--")
    ax.set_xscale("log")
    ax.set_xticks(res.thicknesses * 1e3, [f"{h * 1e3:g}" for h in res.thicknesses])
    ax.minorticks_off()
    ax.set_xlabel("lift thickness h (mm)")
    ax.set_ylabel("E read as a half-space / E1 - 1 (%)")
    ax.set_title(f"lift E1 = {res.E1 / 1e6:g} MPa, nu {res.nu:g}: half-space reading")
    ax.legend(fontsize=8)
    save_png(fig, path)


def half_space_departure(params: Any, E: Any, nu: Any, tof: Any,
                         half_space_options: dict[str, Any]) -> np.ndarray:
    """The relative error of E a half-space reading makes on a stated finite sample: the
    sample's TOF ``tof`` (s) at ``E`` (Pa), ``nu`` read through the fem wall of the
    half-space (``half_space_options``: the device's ``contact`` settings without the
    sample), to first order ``ln(tof / TOF_half) / (d ln TOF_half / d ln E)`` (the exact
    forward sensitivity, :func:`ssw.tof.api.tof_derivatives`; the ``finite_sample`` check of
    :mod:`ssw.validity`).

    Parameters
    ----------
    params : ssw.chain.params.ChainParams
        The chain.
    E : array_like
        Pa, broadcast with ``nu`` and ``tof``.
    nu : array_like
        -.
    tof : array_like
        s, the TOFs on the sample.
    half_space_options : dict
        The fem wall's options of the half-space (its ``contact``, ``operators``).

    Returns
    -------
    numpy.ndarray
        (n,) relative error of E (signed; > 0: the half-space reading is too stiff).
    """
    from ssw.tof.api import tof_derivatives

    E, nu = (np.atleast_1d(np.asarray(x, float)) for x in np.broadcast_arrays(E, nu))
    opts = {k: v for k, v in half_space_options.items() if k in ("contact", "operators")}
    res = tof_derivatives(E, nu, params, "fem", derivatives=("E",), strict=False, **opts)
    half = np.asarray(res.tof, float)
    slope = E * np.asarray(res.dtof["E"], float) / half
    return np.log(np.asarray(tof, float) / half) / slope

