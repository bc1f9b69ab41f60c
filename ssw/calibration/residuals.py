"""What a calibration fits, and the derivatives of its model: residuals and Jacobians.

A calibration compares **observations** (measured values with their standard uncertainties,
each belonging to one reference sample: today each reference's mean TOF; a waveform
calibration appends other kinds, its samples or features) with the model's values for
parameter sets ``theta`` of the free device parameters. Everything the least squares needs
comes from ONE function, the model's **derivatives**::

    derivatives(theta) -> (values, jacobian)
    theta (m, len(free)) SI;  values (m, n) in the observations' order;
    jacobian (m, n, len(continuous)): d value / d theta_j per SI unit of each continuous
    free parameter (integers, the bead count, are scanned, not differentiated).

:func:`model_derivatives` chooses it: a model whose walls carry the chain's exact forward
sensitivities (:mod:`ssw.chain.sensitivity`) gives it from the runs of its values (one
batched run for the ``m`` rows, exact for the discrete TOF); otherwise
:func:`central_differences` builds it from the model's values alone (one batched run for
every row's ``1 + 2 p`` points). The least squares works in scaled coordinates ``x``
(``ln theta`` for a log-scaled parameter, ``theta / scale`` otherwise:
:data:`ssw.device.PARAMETERS`), where the Jacobian is ``jacobian * d theta / d x``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ssw.device import parameter

#: Step of the central differences in the scaled coordinates (1e-3 relative for a log
#: parameter, 1e-3 of its scale otherwise): the TOF's own noise (the sub-step interpolation
#: of its peaks, ~1e-8 relative) stays far below the step's change, and its O(h^2) error
#: (~1e-6 relative) far below the data's uncertainties.
FD_STEP = 1e-3

#: ``derivatives(theta) -> (values, jacobian)`` (module docstring).
Derivatives = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


# --------------------------------------------------------------------- coordinates
def to_x(theta: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """Scaled coordinates of parameter values (last axis in ``names`` order).

    Parameters
    ----------
    theta : numpy.ndarray
        (..., p) parameter values, SI.
    names : tuple of str
        The parameters (:data:`ssw.device.PARAMETERS`), the last axis's order.

    Returns
    -------
    numpy.ndarray
        (..., p) ``x = ln(theta)`` for a log-scanned parameter, ``theta / scale`` otherwise.
    """
    th = np.asarray(theta, float)
    out = np.empty_like(th)
    for j, n in enumerate(names):
        p = parameter(n)
        out[..., j] = np.log(th[..., j]) if p.log else th[..., j] / p.scale
    return out


def from_x(x: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """Parameter values (SI) of scaled coordinates (last axis in ``names`` order).

    Parameters
    ----------
    x : numpy.ndarray
        (..., p) scaled coordinates.
    names : tuple of str
        The parameters (:data:`ssw.device.PARAMETERS`), the last axis's order.

    Returns
    -------
    numpy.ndarray
        (..., p) ``theta = exp(x)`` for a log-scanned parameter, ``x scale`` otherwise, SI.
    """
    xx = np.asarray(x, float)
    out = np.empty_like(xx)
    for j, n in enumerate(names):
        p = parameter(n)
        out[..., j] = np.exp(xx[..., j]) if p.log else xx[..., j] * p.scale
    return out


def dtheta_dx(theta: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """``d theta / d x`` per parameter (theta for log coordinates, scale otherwise), same
    shape as ``theta`` (last axis in ``names`` order).

    Parameters
    ----------
    theta : numpy.ndarray
        (..., p) parameter values, SI.
    names : tuple of str
        The parameters (:data:`ssw.device.PARAMETERS`), the last axis's order.

    Returns
    -------
    numpy.ndarray
        (..., p) ``d theta / d x``, SI per scaled unit.
    """
    th = np.asarray(theta, float)
    return np.stack([th[..., j] if parameter(n).log else np.full(th.shape[:-1],
                                                                  parameter(n).scale)
                     for j, n in enumerate(names)], axis=-1)


def bounds_x(names: tuple[str, ...], ranges: dict[str, tuple[float, float]]
             ) -> tuple[np.ndarray, np.ndarray]:
    """The scaled coordinates' bounds of the parameter ranges (SI).

    Parameters
    ----------
    names : tuple of str
        The parameters (:data:`ssw.device.PARAMETERS`), the last axis's order.
    ranges : dict of str to tuple of float
        ``(lo, hi)`` per parameter, SI.

    Returns
    -------
    tuple of numpy.ndarray
        (p,) lower and (p,) upper bounds in scaled coordinates.
    """
    lo = np.array([ranges[n][0] for n in names], float)
    hi = np.array([ranges[n][1] for n in names], float)
    return to_x(lo, names), to_x(hi, names)


def fd_pair(x: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two points of a central difference of step :data:`FD_STEP` per scaled
    coordinate, ``x -+ FD_STEP``, shifted (same spacing) to stay inside ``[lo, hi]``: a
    point on a bound (a preload of 0 N) is differentiated one-sidedly instead of at an
    inadmissible value.

    Parameters
    ----------
    x : numpy.ndarray
        Scaled coordinates.
    lo : numpy.ndarray
        Their lower bounds (broadcast against ``x``).
    hi : numpy.ndarray
        Their upper bounds.

    Returns
    -------
    tuple of numpy.ndarray
        The lower and upper points, ``2 FD_STEP`` apart, inside ``[lo, hi]``.
    """
    a = np.asarray(x, float) - FD_STEP
    b = np.asarray(x, float) + FD_STEP
    below, above = a < lo, b > hi
    a = np.where(below, lo, np.where(above, hi - 2 * FD_STEP, a))
    b = np.where(below, lo + 2 * FD_STEP, np.where(above, hi, b))
    return a, b


# --------------------------------------------------------------------- derivatives
def central_differences(values: Callable[[np.ndarray], np.ndarray], free: tuple[str, ...],
                        ranges: dict[str, tuple[float, float]]) -> Derivatives:
    """The model's derivatives (module docstring) by central differences of its values.

    Parameters
    ----------
    values : callable
        ``values(theta) -> (m, n)``: the model's values for parameter sets ``theta``
        (m, len(free)) SI, NaN where the model gives none (one batched run per call).
    free : tuple of str
        The free parameters, the columns of ``theta`` (:data:`ssw.device.PARAMETERS`).
    ranges : dict
        The admissible range (SI) of each continuous free parameter: the difference points
        stay inside it (:func:`fd_pair`).

    Returns
    -------
    callable
        ``derivatives(theta) -> (values (m, n), jacobian (m, n, p))``, ``p`` the continuous
        free parameters in ``free`` order, per SI unit; every row's ``1 + 2 p`` points in ONE
        call of ``values``.
    """
    cont = tuple(n for n in free if parameter(n).kind == "continuous")
    idx = [free.index(n) for n in cont]
    lo, hi = bounds_x(cont, ranges)

    def derivatives(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        th = np.atleast_2d(np.asarray(theta, float))
        m, p = th.shape[0], len(cont)
        x = to_x(th[:, idx], cont)
        a, b = fd_pair(x, lo, hi)
        rows = [th]
        for j in range(p):
            for end in (b, a):
                pt = th.copy()
                pt[:, idx[j]] = from_x(end[:, j:j + 1], cont[j:j + 1])[:, 0]
                rows.append(pt)
        out = np.asarray(values(np.concatenate(rows)), float)
        f0 = out[:m]
        jac = np.empty((m, f0.shape[1], p))
        scale = dtheta_dx(th[:, idx], cont) if p else np.zeros((m, 0))
        for j in range(p):
            up, dn = out[(1 + 2 * j) * m:(2 + 2 * j) * m], out[(2 + 2 * j) * m:(3 + 2 * j) * m]
            jac[:, :, j] = (up - dn) / (b[:, j] - a[:, j])[:, None] / scale[:, j, None]
        return f0, jac

    return derivatives


def model_derivatives(model: Any, ranges: dict[str, tuple[float, float]]) -> Derivatives:
    """The model's derivatives (module docstring): exact where it has them, central
    differences otherwise.

    Parameters
    ----------
    model : ssw.calibration.model.TofModel
        The model: callable on ``theta`` (its values), with ``free`` (the parameter names),
        ``forward()`` (whether its walls carry the forward sensitivities) and
        ``derivatives(theta)``.
    ranges : dict
        The admissible range (SI) of each continuous free parameter (the central
        differences' points stay inside it).

    Returns
    -------
    callable
        ``derivatives(theta) -> (values (m, n), jacobian (m, n, p))``.
    """
    if model.forward():
        return model.derivatives
    return central_differences(model, model.free, ranges)


# --------------------------------------------------------------------- observations
@dataclass(frozen=True)
class Observations:
    """Measured values a calibration fits, their standard uncertainties and references.

    Parameters
    ----------
    values : numpy.ndarray
        (n,) the measured values (SI; today each reference's mean TOF, s).
    std : numpy.ndarray
        (n,) their standard uncertainties (same units), > 0.
    reference : numpy.ndarray
        (n,) ints: the reference sample each value belongs to (a subset fit, leave-one-out,
        keeps the values of its references).
    kind : tuple of str
        (n,) what each value is (``tof``; a waveform calibration adds its own kinds).
    """

    values: np.ndarray
    std: np.ndarray
    reference: np.ndarray
    kind: tuple[str, ...]

    @classmethod
    def tof(cls, tof: np.ndarray, std: np.ndarray) -> Observations:
        """One mean TOF (s) per reference with its standard uncertainty (s).

        Parameters
        ----------
        tof : numpy.ndarray
            (n,) s, the references' mean TOFs.
        std : numpy.ndarray
            (n,) s, their standard uncertainties (> 0).

        Returns
        -------
        Observations
            Value ``j`` belonging to reference ``j``, of kind ``tof``.
        """
        T = np.asarray(tof, float).ravel()
        return cls(T, np.asarray(std, float).ravel(), np.arange(T.size), ("tof",) * T.size)

    def columns(self, refs: tuple[int, ...] | np.ndarray) -> np.ndarray:
        """Indices of the values that belong to the references ``refs``.

        Parameters
        ----------
        refs : tuple of int or numpy.ndarray
            Reference indices.

        Returns
        -------
        numpy.ndarray
            The indices into ``values``, ascending.
        """
        return np.flatnonzero(np.isin(self.reference, np.asarray(refs, int)))

    def weighted(self, values: np.ndarray, jacobian: np.ndarray, cols: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, float]:
        """Weighted residuals, Jacobian and chi^2 of one parameter set on the ``cols``.

        Parameters
        ----------
        values : numpy.ndarray
            (n,) the model's values.
        jacobian : numpy.ndarray
            (n, p) their derivatives (any coordinates: the result is in the same ones).
        cols : numpy.ndarray
            The observations fitted (:meth:`columns`).

        Returns
        -------
        tuple
            ``r = (model - measured) / std`` on ``cols``, ``J / std``, ``r . r`` (inf where
            the model gives no value; ``J`` is then zeros).
        """
        s = self.std[cols]
        r = (values[cols] - self.values[cols]) / s
        J = jacobian[cols] / s[:, None]
        if not (np.all(np.isfinite(r)) and np.all(np.isfinite(J))):
            return r, np.zeros_like(J), np.inf
        return r, J, float(r @ r)

    def chi2(self, values: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """chi^2 (m,) of the model's values (m, n) on ``cols`` (inf where one is missing).

        Parameters
        ----------
        values : numpy.ndarray
            (m, n) the model's values per parameter set.
        cols : numpy.ndarray
            The observations compared (:meth:`columns`).

        Returns
        -------
        numpy.ndarray
            (m,) -, ``sum(((model - measured) / std)^2)`` over ``cols``.
        """
        r = (values[:, cols] - self.values[cols]) / self.std[cols]
        return np.where(np.all(np.isfinite(r), axis=1), np.sum(r**2, axis=1), np.inf)
