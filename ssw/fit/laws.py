"""Registry of the force-indentation laws fitted to contact curves.

Every law maps an indentation ``delta`` (m) to a force ``F`` (N). The reference Hertz
coefficient of the scene, ``A_H = 4/3 E* sqrt(R)`` (N m^-3/2), is passed to every law so
that dimensionless parameters (K) can be defined against it. In ssw the FEM indenter is
rigid, so ``E* = E_soil / (1 - nu_soil^2)`` and ``R`` is the indenter radius.

Laws (``LAWS[name]``):

* ``k_hertz``: ``F = K A_H delta^(3/2)``, the thesis's modified Hertz law (Torres
  Constante 2024, Stage II). One linear parameter: exact linear least squares.
* ``power``: ``F = C delta^n`` (C in N m^-n). Nonlinear in n: a least-squares line in
  log-log space (exact for data that follow the law), refined on the weighted force
  residuals by Levenberg-Marquardt (``scipy.optimize.least_squares``, MINPACK's damped
  Gauss-Newton: an undamped step overshoots where the data are far from a power law).
* ``two_term``: ``F = k1 delta + k2 delta^(3/2)`` (k1 in N/m, k2 in N m^-3/2): a linear
  spring (the plate's bending on the soil, Selvadurai 1979 ch. 5) in parallel with a
  Hertz-like term. Exact linear least squares.

Weightings: ``absolute`` minimizes ``sum (F_fit - F)^2`` (ordinary least squares on the
force, the thesis's choice); ``relative`` minimizes ``sum ((F_fit - F) / F)^2``, which
weights small indentations equally.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ssw.errors import ConfigError, SolverError

FloatArray = NDArray[np.float64]

WEIGHTINGS = ("absolute", "relative")
#: Tolerances of the power law's Levenberg-Marquardt (relative step, relative cost
#: reduction, gradient): machine precision, so that it stops at the round-off of the cost.
LM_TOL = float(np.finfo(float).eps)


@dataclass(frozen=True)
class Law:
    """A fit law: names of its parameters (with units), a fitter and an evaluator.

    Parameters
    ----------
    name : str
        The registry name.
    params : tuple
        Names of its parameters.
    units : tuple
        Their units.
    formula : str
        The law's formula, as text.
    fit : callable
        ``fit(delta, force, hertz_coefficient, weighting) -> params``.
    evaluate : callable
        ``evaluate(params, delta, hertz_coefficient) -> force`` (N).
    """

    name: str
    params: tuple[str, ...]
    units: tuple[str, ...]
    formula: str
    fit: Callable[[FloatArray, FloatArray, float, str], dict[str, float]]
    evaluate: Callable[[dict[str, float], FloatArray, float], FloatArray]


def _weights(force: FloatArray, weighting: str) -> FloatArray:
    if weighting == "absolute":
        return np.ones_like(force)
    if weighting == "relative":
        return 1.0 / force
    raise ConfigError("fit.weighting", weighting, f"one of {', '.join(WEIGHTINGS)}")


def linear_lstsq(columns: list[FloatArray], force: FloatArray, weights: FloatArray) -> FloatArray:
    """Weighted linear least squares ``min sum (w (X c - F))^2`` with column scaling.

    Columns are scaled to unit norm before the QR-based solve, so coefficients of very
    different magnitudes (N/m next to N m^-3/2) are found to near machine precision.

    Parameters
    ----------
    columns : list of numpy.ndarray
        The design matrix's columns, (m,) each.
    force : numpy.ndarray
        Forces (N), (m,).
    weights : numpy.ndarray
        Weights, (m,).

    Returns
    -------
    numpy.ndarray
        The coefficients, one per column (N per the column's unit).

    Raises
    ------
    SolverError
        If a column is identically zero.
    """
    X = np.column_stack(columns) * weights[:, None]
    scale = np.linalg.norm(X, axis=0)
    if np.any(scale == 0):
        raise SolverError("a fit column is identically zero on the fit range")
    coef, *_ = np.linalg.lstsq(X / scale, force * weights, rcond=None)
    return coef / scale


# -- k_hertz ------------------------------------------------------------------------------


def _fit_k_hertz(delta: FloatArray, force: FloatArray, A_H: float, weighting: str) -> dict:
    """``K = sum(w^2 F H) / sum(w^2 H^2)`` with ``H = A_H delta^1.5``: the normal equation."""
    H = A_H * delta**1.5
    w2 = _weights(force, weighting) ** 2
    return {"K": float(np.sum(w2 * force * H) / np.sum(w2 * H * H))}


def _eval_k_hertz(p: dict[str, float], delta: FloatArray, A_H: float) -> FloatArray:
    return p["K"] * A_H * np.clip(delta, 0.0, None) ** 1.5


# -- power --------------------------------------------------------------------------------


def _fit_power(delta: FloatArray, force: FloatArray, A_H: float, weighting: str) -> dict:
    """Log-log line, then Levenberg-Marquardt on ``w (F_fit - F)`` in ``(ln F_ref, n)``.

    The model is written about the geometric-mean indentation ``d_ref``:
    ``F = exp(b) (delta/d_ref)^n`` so that the two Jacobian columns ``F`` and
    ``F ln(delta/d_ref)`` are nearly orthogonal; ``C = exp(b) d_ref^(-n)``. The damped
    steps (Moré 1978, MINPACK's ``lmder``) reach the least-squares optimum where the
    undamped Gauss-Newton steps overshoot and oscillate (a force far from a power law:
    ``tests/test_fit_laws.py``).
    """
    from scipy.optimize import least_squares

    if np.any(force <= 0):
        raise SolverError("the power law needs forces > 0 on the fit range")
    x_ref = float(np.mean(np.log(delta)))
    x = np.log(delta) - x_ref
    n, b = np.polyfit(x, np.log(force), 1)
    w = _weights(force, weighting)

    def residual(p: FloatArray) -> FloatArray:
        return (np.exp(p[0] + p[1] * x) - force) * w

    def jacobian(p: FloatArray) -> FloatArray:
        Ff = np.exp(p[0] + p[1] * x) * w
        return np.column_stack([Ff, Ff * x])

    res = least_squares(residual, np.array([b, n]), jac=jacobian, method="lm",
                        xtol=LM_TOL, ftol=LM_TOL, gtol=LM_TOL)
    if res.status <= 0 or not np.all(np.isfinite(res.x)):
        raise SolverError(f"the power-law least squares did not converge ({res.message})")
    b, n = res.x
    return {"C": float(np.exp(b - n * x_ref)), "n": float(n)}


def _eval_power(p: dict[str, float], delta: FloatArray, A_H: float) -> FloatArray:
    return p["C"] * np.clip(delta, 0.0, None) ** p["n"]


# -- two_term -----------------------------------------------------------------------------


def _fit_two_term(delta: FloatArray, force: FloatArray, A_H: float, weighting: str) -> dict:
    k1, k2 = linear_lstsq([delta, delta**1.5], force, _weights(force, weighting))
    return {"k1": float(k1), "k2": float(k2)}


def _eval_two_term(p: dict[str, float], delta: FloatArray, A_H: float) -> FloatArray:
    d = np.clip(delta, 0.0, None)
    return p["k1"] * d + p["k2"] * d**1.5


LAWS: dict[str, Law] = {
    "k_hertz": Law(
        "k_hertz", ("K",), ("1",), "F = K * 4/3 E* sqrt(R) delta^1.5", _fit_k_hertz, _eval_k_hertz
    ),
    "power": Law("power", ("C", "n"), ("N m^-n", "1"), "F = C delta^n", _fit_power, _eval_power),
    "two_term": Law(
        "two_term",
        ("k1", "k2"),
        ("N/m", "N m^-1.5"),
        "F = k1 delta + k2 delta^1.5",
        _fit_two_term,
        _eval_two_term,
    ),
}


def get_law(name: str, field: str = "fit.law") -> Law:
    """The law called ``name``; ``field`` names the setting for the error message.

    Parameters
    ----------
    name : str
        The law's registry name.
    field : str
        The setting's name, for the error message.

    Returns
    -------
    Law
        The law.

    Raises
    ------
    ConfigError
        If no law has that name.
    """
    if name not in LAWS:
        raise ConfigError(field, name, f"one of {', '.join(LAWS)}")
    return LAWS[name]
