"""The sensor signal between the steps: the integrator's dense output, and the TOF on it.

A sampled peak (the vertex of the parabola through three samples) jumps when the largest
sample moves from one step to the next, so a TOF picked that way is noisy in the run's
parameters. Here the sensor signal between steps ``t_i`` and ``t_i + dt`` is the quintic
Hermite polynomial (``theta = (t - t_i) / dt``)

    H(theta) = S_i p0 + dt S'_i q0 + dt^2 S''_i r0 + S_(i+1) p1 + dt S'_(i+1) q1
               + dt^2 S''_(i+1) r1

(``p0 = 1 - 10 theta^3 + 15 theta^4 - 6 theta^5`` and its companions, :data:`BASIS`; de Boor
2001, *A Practical Guide to Splines*, ch. I) that matches the signal and its first two
time derivatives at both steps. ``S`` are the integrator's samples; ``S'`` and ``S''`` their
sixth-order central differences over seven samples (Fornberg 1988). Velocity Verlet's
samples lie on a smooth trajectory (that of its modified equation; Hairer, Lubich & Wanner
2006, ch. IX) wherever the forces are smooth, so the differences are that trajectory's
derivatives to ``O(dt^6)``: the maximum of ``H`` then does not depend on where the steps
fall (the bead velocities of the step, central differences of second order only, left a
phase-dependent error of 1e-7 of the TOF). Since ``H``, ``H'`` and ``H''`` are continuous at
the steps, the maximum ``t*`` (``H'(t*) = 0``) is a C1 function of the samples and so of the
run's parameters, whichever sample is the largest; its derivative is exact for this discrete
TOF:

    dt*/dp = -dt (dH'/dp)(theta*) / H''(theta*),

``dH'/dp`` the same combination of the samples' forward sensitivities (``Run.dsensor``,
:mod:`ssw.chain.sensitivity`). The peak's height moves as ``dH/dp`` (``H' = 0`` there). The
step's own column (:data:`ssw.chain.sensitivity.STEP`, a run's derivative with respect to
``dt`` at a fixed number of steps) also moves the record's times ``t_i = i dt``: the peak's
``dt*/d dt`` gains ``i + theta*``, and the dense output at a fixed time ``t`` gains ``-(dS/dt)
(t - t_0) / dt`` (its phase ``theta`` moves). With
the contact forces of :mod:`ssw.chain.impulse` (smooth through contact events) the TOF is
smooth in the parameters to ~1e-10 (``ssw bench smooth``).

Which maxima are the incident and the reflected peaks is the rule of
:mod:`ssw.signal.rule`, applied to the samples; the chosen sample's neighbouring interval
where ``H'`` changes sign holds the dense maximum. A peak without one, or too close to the
record's ends or a stop for the differences, keeps its parabolic vertex and says so
(``Peaks.dense`` False, its derivatives NaN).

References
----------
de Boor, C. (2001). *A Practical Guide to Splines*, revised ed. Springer.
Fornberg, B. (1988). Generation of finite difference formulas on arbitrarily spaced grids.
Math. Comp. 51, 699-706.
Hairer, E., Lubich, C. and Wanner, G. (2006). *Geometric Numerical Integration*, 2nd ed.
Springer.
"""

from __future__ import annotations

from dataclasses import fields
from typing import Any

import numpy as np

from ssw.chain.sensitivity import STEP
from ssw.chain.tof import Peaks, check_selection, parabolic
from ssw.signal.rule import RULE, PeakRule, Selection, select

#: Quintic Hermite basis on [0, 1]: row m multiplies the m-th node datum of
#: ``[S_0, dt S'_0, dt^2 S''_0, S_1, dt S'_1, dt^2 S''_1]``; columns are the coefficients
#: of ``theta^0 .. theta^5``.
BASIS = np.array([
    [1.0, 0.0, 0.0, -10.0, 15.0, -6.0],
    [0.0, 1.0, 0.0, -6.0, 8.0, -3.0],
    [0.0, 0.0, 0.5, -1.5, 1.5, -0.5],
    [0.0, 0.0, 0.0, 10.0, -15.0, 6.0],
    [0.0, 0.0, 0.0, -4.0, 7.0, -3.0],
    [0.0, 0.0, 0.0, 0.5, -1.0, 0.5],
])
#: Sixth-order central differences on samples ``-3..3`` (Fornberg 1988): the first
#: derivative times ``dt`` and the second times ``dt^2``.
FIRST = np.array([-1.0, 9.0, -45.0, 0.0, 45.0, -9.0, 1.0]) / 60.0
SECOND = np.array([2.0, -27.0, 270.0, -490.0, 270.0, -27.0, 2.0]) / 180.0
#: Scenes per block of the peak rule (:func:`dense_peaks`): 256 columns of a 6000-step
#: record are 12 MB, the whole record of 1500 scenes 70 MB of new memory.
COLUMNS = 256
#: Samples each side of a node the differences use.
HALF = 3
#: The Hermite data of an interval from its samples ``i - 3 .. i + 4`` (8): rows
#: ``[S_i, dt S'_i, dt^2 S''_i, S_i+1, dt S'_i+1, dt^2 S''_i+1]``.
STENCIL = np.zeros((6, 2 * HALF + 2))
STENCIL[0, HALF] = 1.0
STENCIL[1, :7] = FIRST
STENCIL[2, :7] = SECOND
STENCIL[3, HALF + 1] = 1.0
STENCIL[4, 1:] = FIRST
STENCIL[5, 1:] = SECOND


def _samples(x: np.ndarray, i: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """``x[i - 3 .. i + 4, ..., cols]`` for a record ``x`` (n_t, ..., n): (m, 8, ...); NaN
    beyond the record's ends."""
    n_t = x.shape[0]
    rows = i[:, None] + np.arange(-HALF, HALF + 2)  # (m, 8)
    inside = (rows >= 0) & (rows < n_t)
    got = x[np.clip(rows, 0, n_t - 1), ..., cols[:, None]]  # (m, 8, ...)
    mask = inside.reshape(inside.shape + (1,) * (got.ndim - 2))
    return np.where(mask, got, np.nan)


def hermite_data(run: Any, i: np.ndarray, cols: np.ndarray, tangent: bool = False
                 ) -> tuple[np.ndarray, np.ndarray | None]:
    """Node data of the intervals ``[t_i, t_i + dt]`` of the scenes ``cols``.

    Parameters
    ----------
    run : Run
        The record (``sensor``; ``dsensor`` for the derivatives).
    i : numpy.ndarray
        (m,) interval (step) indices.
    cols : numpy.ndarray
        (m,) scene indices.
    tangent : bool
        Also the derivatives with respect to the run's parameters.

    Returns
    -------
    tuple
        ``Y`` (m, 6): ``[S_i, dt S'_i, dt^2 S''_i, S_i+1, dt S'_i+1, dt^2 S''_i+1]`` (N;
        NaN where the samples do not reach), and ``dY`` (m, 6, k) or None.
    """
    Y = _stencil(_samples(run.sensor, i, cols), pairwise=True)
    if not tangent:
        return Y, None
    dS = _samples(np.moveaxis(run.dsensor, 2, 1), i, cols)  # (m, 8, k)
    return Y, _stencil(dS, pairwise=dS.shape[-1] == 1)


def _stencil(S: np.ndarray, pairwise: bool) -> np.ndarray:
    """``STENCIL`` applied to the 8 samples of each interval: ``S`` (m, 8, ...) to (m, 6, ...).

    The eight products are summed in a fixed order, elementwise (not a matrix product: a
    scene's numbers do not depend on the scenes around it): pairwise, ``((p0 + p1) + (p2 +
    p3)) + ((p4 + p5) + (p6 + p7))``, or from left to right. These are the orders numpy's
    ``sum`` over that axis took before (pairwise along a contiguous axis: the sensor and a
    single derivative; left to right across one: several derivatives), so the record's
    numbers are those it gave, bit for bit, at a third of the time on 20 000 intervals and
    8 derivatives (0.077 s against 0.22 s, ``time.perf_counter``, 2 cores, 2026-11-29): no
    (m, 6, 8, k) temporary.

    Parameters
    ----------
    S : numpy.ndarray
        (m, 8, ...) the samples ``x[i - 3 .. i + 4]`` (:func:`_samples`).
    pairwise : bool
        The pairwise order (else left to right).

    Returns
    -------
    numpy.ndarray
        (m, 6, ...) the node data.
    """
    shape = (1, 6) + (1,) * (S.ndim - 2)
    p = [STENCIL[:, j].reshape(shape) * S[:, None, j] for j in range(8)]
    if pairwise:
        return ((p[0] + p[1]) + (p[2] + p[3])) + ((p[4] + p[5]) + (p[6] + p[7]))
    out = p[0] + p[1]
    for term in p[2:]:
        out += term
    return out


def _poly(Y: np.ndarray) -> np.ndarray:
    """Monomial coefficients (m, 6) of the Hermite polynomials of the node data Y (m, 6)."""
    return (Y[:, :, None] * BASIS[None]).sum(axis=1)


def _basis_at(powers: np.ndarray) -> np.ndarray:
    """The six basis functions (or their derivatives) from the powers of theta (m, 6):
    ``powers @ BASIS.T`` in a fixed order, (m, 6)."""
    return (powers[:, None, :] * BASIS[None]).sum(axis=2)


def _eval(c: np.ndarray, x: np.ndarray, order: int) -> np.ndarray:
    """``d^order/dtheta^order`` of the polynomials ``c`` (m, 6) at ``x`` (m,)."""
    out = np.zeros(x.shape)
    for j in range(5, order - 1, -1):
        f = 1.0
        for r in range(order):
            f *= j - r
        out = out * x + f * c[:, j]
    return out


def _root(c: np.ndarray) -> np.ndarray:
    """The root in [0, 1] of ``H'`` (``H'(0) > 0 >= H'(1)``), vectorized, to a few ulp: the
    one bracketed root finder (:func:`ssw.roots.find_root`) on the non-decreasing ``-H'``."""
    from ssw.roots import find_root

    m = c.shape[0]
    return find_root(lambda x: -_eval(c, x, 1), np.zeros(m), np.ones(m)).x


def _refine(run: Any, k: np.ndarray, cols: np.ndarray) -> tuple[np.ndarray, ...]:
    """Dense maxima next to the samples ``k`` (m,) of the scenes ``cols``: the interval
    index ``i``, ``theta``, the height ``H`` (N, baseline included), ``H''`` (N per unit
    theta^2) and ``ok``, False where no interval next to ``k`` brackets a maximum of ``H``
    (or its samples do not reach)."""
    n_t = run.sensor.shape[0]
    kk = np.clip(k, 1, n_t - 2)
    Yl, _ = hermite_data(run, kk - 1, cols)  # [k-1, k]
    Yr, _ = hermite_data(run, kk, cols)  # [k, k+1]
    # H' at the nodes k-1, k, k+1 (times dt)
    g0, g1, g2 = Yl[:, 1], Yr[:, 1], Yr[:, 4]
    up = (g1 > 0) & (g2 <= 0)  # the maximum in [k, k+1]
    down = (g0 > 0) & (g1 <= 0)  # in [k-1, k] (exclusive of up: the sign of S'_k)
    i = np.where(up, kk, kk - 1)
    Y = np.where(up[:, None], Yr, Yl)
    ok = (up | down) & np.all(np.isfinite(Y), axis=1)
    c = _poly(np.where(ok[:, None], Y, 0.0))
    theta = np.where(ok, _root(c), 0.0)
    return i, theta, _eval(c, theta, 0), _eval(c, theta, 2), ok


def dense_peaks(run: Any, *, rule: PeakRule = RULE, strict: bool = True) -> Peaks:
    """Incident and reflected peaks of the run's sensor signal on its dense output (module
    docstring), with their derivatives when the run carries sensitivities.

    Parameters
    ----------
    run : Run
        The record (:func:`ssw.chain.integrate.simulate`).
    rule : PeakRule
        The peak rule (:data:`ssw.signal.rule.RULE`).
    strict : bool
        Raise on a scene without two peaks (else its values are NaN).

    Returns
    -------
    Peaks
        Times (s), heights above the static baseline (N), and with ``run.tangent`` their
        derivatives ``dt_incident``, ``dt_reflected``, ``df_incident``, ``df_reflected``
        (n, k) per unit of each parameter; ``dense`` (n,) False where a peak kept its
        parabolic vertex (its derivatives NaN).

    Raises
    ------
    RecordingError
        (strict) a scene has no incident or no reflected peak.
    """
    y = run.sensor
    n_t, n = y.shape
    # the rule on blocks of COLUMNS scenes (its operations are per column): the baseline-
    # removed signal (NaN read as 0) is never made for the whole record at once
    parts = []
    for c0 in range(0, max(n, 1), COLUMNS):
        s = y[:, c0 : c0 + COLUMNS] - y[0, c0 : c0 + COLUMNS]
        s[np.isnan(s)] = 0.0
        parts.append(select(s, rule))
    sel = Selection(*(np.concatenate([getattr(q, f.name) for q in parts])
                      for f in fields(Selection)))
    bad = check_selection(sel, strict)
    cols = np.arange(n)
    base = y[0]
    out: dict[str, np.ndarray] = {}
    derivs = run.tangent is not None
    dense = ~bad
    for name, k in (("incident", sel.k_incident), ("reflected", sel.k_reflected)):
        i, theta, H, H2, ok = _refine(run, k, cols)
        ok &= ~bad
        dense &= ok
        # a peak without a dense maximum keeps the parabolic vertex of its samples (the
        # baseline-removed signal at kk - 1 .. kk + 1)
        kk = np.clip(k, 1, n_t - 2)
        s3 = y[kk + np.arange(-1, 2)[:, None], cols] - base
        s3[np.isnan(s3)] = 0.0
        off, h_par = parabolic(s3, kk, cols, near=True)
        out[f"t_{name}"] = np.where(ok, run.t[0] + (i + theta) * run.dt,
                                    run.t[0] + (kk + off) * run.dt)
        out[f"f_{name}"] = np.where(ok, H - base, h_par)
        if derivs:
            _, dY = hermite_data(run, i, cols, tangent=True)
            # dH/dp and dH'/dp at theta*: the basis (and its derivative) at theta* times dY
            pw = theta[:, None] ** np.arange(6)
            dpw = np.concatenate([np.zeros((n, 1)), np.arange(1, 6) * pw[:, :5]], axis=1)
            b0 = _basis_at(pw)  # (n, 6): the basis functions at theta*
            b1 = _basis_at(dpw)
            dH = (b0[:, :, None] * dY).sum(axis=1)
            dH1 = (b1[:, :, None] * dY).sum(axis=1)
            dtheta = -dH1 / np.where(ok, H2, -1.0)[:, None]
            nan = np.where(ok, 0.0, np.nan)[:, None]
            out[f"dt_{name}"] = run.dt * dtheta + nan
            if (c_T := run.tangent.col(STEP)) is not None:  # the record's times n dt
                out[f"dt_{name}"][:, c_T] += i + theta
            out[f"df_{name}"] = dH - run.dsensor[0] + nan
    nan = np.where(bad, np.nan, 0.0)
    return Peaks(
        t_incident=out["t_incident"] + nan, t_reflected=out["t_reflected"] + nan,
        f_incident=out["f_incident"] + nan, f_reflected=out["f_reflected"] + nan,
        dt_incident=out.get("dt_incident"), dt_reflected=out.get("dt_reflected"),
        df_incident=out.get("df_incident"), df_reflected=out.get("df_reflected"),
        dense=dense, tangent=run.tangent,
    )


def evaluate(run: Any, t: np.ndarray, *, tangent: bool = False, rate: bool = False
             ) -> tuple[np.ndarray, ...]:
    """The dense output (module docstring) of every scene at times ``t`` (s, from the
    striker's first contact, e.g. a recording's sample times), with its derivatives.

    Parameters
    ----------
    run : Run
        The record (``dsensor`` for the derivatives).
    t : numpy.ndarray
        (m,) s, the same times for every scene, or (m, n) one column of times per scene,
        inside the record (NaN where a scene's samples do not reach: before ``3 dt``, after
        its stop).
    tangent : bool
        Also the derivatives with respect to the run's parameters (``run.tangent``).
    rate : bool
        Also the time derivative ``dS/dt`` (N/s) of the dense output (the quintic's own
        derivative: what a shift of the signal in time changes).

    Returns
    -------
    tuple
        ``S`` (m, n) N and ``dS`` (m, n, k) N per unit of each parameter (None without
        ``tangent``; the step's column, :data:`ssw.chain.sensitivity.STEP`, at the fixed
        times ``t``); with ``rate`` a third item, ``dS/dt`` (m, n) N/s.
    """
    t = np.asarray(t, float)
    n = run.sensor.shape[1]
    tt = np.broadcast_to(t.reshape(-1, 1) if t.ndim <= 1 else t, (t.size if t.ndim <= 1
                                                                    else t.shape[0], n))
    m = tt.shape[0]
    pos = (tt - run.t[0]) / run.dt
    i = np.clip(np.floor(pos).astype(np.int64), 0, run.sensor.shape[0] - 2)
    theta = (pos - i).ravel()
    ii = i.ravel()
    cols = np.tile(np.arange(n), m)
    Y, dY = hermite_data(run, ii, cols, tangent=tangent and run.tangent is not None)
    powers = theta[:, None] ** np.arange(6)
    b0 = _basis_at(powers)  # (m n, 6)
    S = (b0 * Y).sum(axis=1).reshape(m, n)
    dS = None if dY is None else (b0[:, :, None] * dY).sum(axis=1).reshape(m, n, -1)
    c_T = None if dS is None else run.tangent.col(STEP)
    if not rate and c_T is None:
        return S, dS
    dpw = np.concatenate([np.zeros((theta.size, 1)), np.arange(1, 6) * powers[:, :5]], axis=1)
    S1 = (_basis_at(dpw) * Y).sum(axis=1).reshape(m, n) / run.dt
    if c_T is not None:  # at a fixed time the phase moves with the step: -(i + theta) dS/dt
        dS[:, :, c_T] -= S1 * (ii + theta).reshape(m, n)
    return (S, dS, S1) if rate else (S, dS)
