"""The substructured engine and the parametric LCP against independent second methods.

* Substructured (plate and soil condensed separately at unit E, a dense system per scene,
  the LCP's exact path) vs monolithic (one PETSc LU of the whole u-p matrix, the candidates
  condensed by solves, an active-set LCP at every increment): the same curve to round-off
  on every interface law and without a plate.
* The parametric path vs the per-increment LCP (``solve_lcp``) on the same compliance,
  including the degenerate start of the unilateral interface (every plate-soil gap zero at
  ``delta = 0``); the prefix fast path vs the general tracer.
* A body's condensed stiffness vs the Schur complement formed from pivoted solves; an
  unstable pivot-free factorization is caught by its backward error.

Round-off: the compliances' condition numbers are ~1e4 (frictionless, bonded, no plate)
and ~2e7 (unilateral: the plate held on the axis only), so agreement is asserted at
1e-9 and 1e-6 relative (measured 8e-11 and 7e-9).
"""

from __future__ import annotations

import numpy as np
import pytest

from ssw.contact import solve_curve
from ssw.contact.contact_lcp import solve_lcp
from ssw.contact.operators import CacheWarning, OperatorStore, sphere_gap0
from ssw.contact.parametric import Tracer, prefix_path, trace
from ssw.contact.scene import indentation_steps

R = 9.53e-3  # m
PLA = (3.5e9, 0.36)
SOIL = (50e6, 0.3)
#: A cheaper mesh (growth 0.2, ~0.4 % force error): the engines must agree on any mesh.
COARSE = {"mesh_growth": 0.2, "mesh_size_contact": 1e-5, "steps": 100}


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    """Operators of this module (a fresh disk cache: the test builds them)."""
    return OperatorStore(tmp_path_factory.mktemp("operators"))


def _pair(soil, plate, t, store, **cfg):
    c = {**COARSE, **cfg}
    sub, s_state = solve_curve(soil, plate, t, R, c, store)
    mono, m_state = solve_curve(soil, plate, t, R, c, engine="monolithic")
    m_state["solver"].destroy()
    return sub, mono, s_state, m_state


@pytest.mark.parametrize(("interface", "rtol"), [
    ("frictionless", 1e-9), ("bonded", 1e-9), ("unilateral", 1e-6), ("none", 1e-9)])
def test_substructured_equals_monolithic(interface, rtol, store):
    """Force, contact radius and pressure of the two engines agree to round-off."""
    plate, t = (None, 0.0) if interface == "none" else (PLA, 0.4e-3)
    itf = "frictionless" if interface == "none" else interface
    sub, mono, _, _ = _pair(SOIL, plate, t, store, interface=itf)
    assert np.array_equal(sub.delta, mono.delta)
    assert np.max(np.abs(sub.force / mono.force - 1)) < rtol
    # the edge estimate extrapolates gap^(2/3) of near-zero gaps: 100x more sensitive
    assert np.max(np.abs(sub.contact_radius / mono.contact_radius - 1)) < 100 * rtol
    ps, pm = sub.pressure["p"], mono.pressure["p"]
    n = pm.shape[1]  # the substructured engine has more (idle) candidates
    assert np.allclose(ps[:, :n], pm, rtol=0, atol=100 * rtol * np.max(pm))
    assert np.all(ps[:, n:] == 0)


def test_unilateral_axis_tie_is_compressed(store):
    """The plate is tied to the soil on the axis only: that tie must push, never pull
    (a pull would mean the plate lifts off under the load, which the tie forbids)."""
    for plate, t in ((PLA, 0.4e-3), ((200e9, 0.26), 0.1e-3)):
        curve, _ = solve_curve((10e6, 0.3), plate, t, R, {**COARSE, "interface": "unilateral"},
                               store)
        assert curve.stats["tie_force_max"] <= 0.0


def test_unilateral_path_equals_per_increment_lcp(store):
    """Degenerate start: at delta = 0 every plate-soil pair touches with zero gap. The
    traced path must equal an LCP solved afresh (cold start) at every increment."""
    curve, state = solve_curve(SOIL, PLA, 0.4e-3, R, {**COARSE, "interface": "unilateral"},
                               store)
    lcp, path = state["lcp"], state["path"]
    assert path.active[0, lcp.n_sphere:].any()  # the interface is in contact from the start
    lam = path.forces(curve.delta)
    scale = np.max(np.abs(lam))
    for k in (0, 1, 9, 49, 99):
        d = curve.delta[k]
        ref, _, _ = solve_lcp(lcp.W, lcp.q0 + d * lcp.q1, np.zeros(lcp.q0.size, bool),
                              1e-12 * d)
        assert np.max(np.abs(lam[k] - ref)) < 1e-6 * scale


@pytest.mark.parametrize("plate", [None, PLA])
def test_paths_equal_per_increment_lcp(plate, store):
    """``trace`` (the prefix fast path where it holds, else the general tracer), the general
    tracer advanced in two calls, and LCPs solved at every increment give one solution.
    On this coarse mesh the PLA plate lifts off its axis node between 7e-8 and 1.3e-7 m
    (a ring contact): not a sequence of prefixes, so the fallback is exercised."""
    t = 0.4e-3 if plate else 0.0
    curve, state = solve_curve(SOIL, plate, t, R, COARSE, store)
    lcp = state["lcp"]
    path, how = trace(lcp.W, lcp.q0, lcp.q1, curve.delta[-1])
    assert how["prefix"] == (1 if plate is None else 0)
    tr = Tracer(lcp.W, lcp.q0, lcp.q1)
    tr.advance(0.3 * curve.delta[-1])  # resumable: two calls make one path
    tr.advance(curve.delta[-1])
    slow = tr.path()
    assert path.pieces == slow.pieces
    assert np.allclose(path.breaks, slow.breaks, rtol=1e-9, atol=0)
    lf, ls = path.forces(curve.delta), slow.forces(curve.delta)
    scale = np.max(lf)
    assert np.max(np.abs(lf - ls)) < 1e-9 * scale
    active = np.zeros(lcp.q0.size, bool)
    for k in range(curve.delta.size):
        ref, active, _ = solve_lcp(lcp.W, lcp.q0 + curve.delta[k] * lcp.q1, active,
                                   1e-12 * curve.delta[k])
        assert np.max(np.abs(lf[k] - ref)) < 1e-9 * scale


def test_tracer_on_random_lcp_family():
    """A random SPD compliance with several zero initial gaps (ties at the start) and gaps
    closing at many rates: the path vs cold LCP solves at 40 points."""
    rng = np.random.default_rng(11)
    m = 40
    a = rng.normal(size=(m, m))
    W = a @ a.T / m + 0.2 * np.eye(m)
    q0 = np.abs(rng.normal(size=m))
    q0[[0, 5, 6, 17]] = 0.0
    q1 = -rng.uniform(0.0, 2.0, m)
    q1[[3, 8]] = 0.0  # gaps that never close by themselves
    tr = Tracer(W, q0, q1)
    tr.advance(5.0)
    path = tr.path()
    assert path.pieces > 5  # the active set changes many times
    for d in np.linspace(0.0, 5.0, 40):
        ref, _, _ = solve_lcp(W, q0 + d * q1, np.zeros(m, bool), 1e-13)
        got = path.forces(np.array([d]))[0]
        assert np.max(np.abs(got - ref)) < 1e-10 * max(1.0, np.max(np.abs(ref)))


def test_tracer_with_simultaneous_breakpoints():
    """Mirror-symmetric constraints (``W = [[B, C], [C, B]]``, equal gaps and rates) reach
    their bounds in twins: breakpoints past the start where two constraints switch at once
    (the directional problem), among single switches; the path vs cold LCP solves."""
    rng = np.random.default_rng(5)
    k = 12
    a, c = rng.normal(size=(k, k)), rng.normal(size=(k, k))
    B = a @ a.T / k + 1.0 * np.eye(k)
    C = 0.3 * (c + c.T) / np.sqrt(k)
    W = np.block([[B, C], [C, B]])
    assert np.all(np.linalg.eigvalsh(W) > 0)
    u = np.abs(rng.normal(size=k))
    u[0] = 0.0
    v = -rng.uniform(0.2, 2.0, k)
    q0, q1 = np.concatenate([u, u]), np.concatenate([v, v])
    tr = Tracer(W, q0, q1)
    tr.advance(4.0)
    path = tr.path()
    switched = np.count_nonzero(path.active[1:] != path.active[:-1], axis=1)
    assert np.all(switched % 2 == 0) and path.pieces > 5  # every change is a twin pair
    for d in np.concatenate([np.linspace(0.0, 4.0, 41), path.breaks[1:-1] * (1 + 1e-6)]):
        ref, _, _ = solve_lcp(W, q0 + d * q1, np.zeros(2 * k, bool), 1e-13)
        got = path.forces(np.array([d]))[0]
        assert np.max(np.abs(got - ref)) < 1e-10 * max(1.0, np.max(np.abs(ref)))


def test_trace_falls_back_when_not_a_prefix():
    """Where the active sets are not prefixes, ``trace`` must use the general tracer."""
    # constraint 0 touches first; once 1 closes (delta 0.106) its push unloads 0, which
    # lifts off at delta 0.12 (by hand: lam_0 = (0.06 - 0.5 delta) / 0.64 on {0, 1})
    W = np.array([[1.0, 0.6, 0.0], [0.6, 1.0, 0.3], [0.0, 0.3, 1.0]])
    q0 = np.array([0.0, 0.1, 0.5])
    q1 = np.array([-0.1, -1.0, -1.0])
    assert prefix_path(W, q0, q1, 2.0) is None
    path, how = trace(W, q0, q1, 2.0)
    assert how["prefix"] == 0 and not path.active[-1, 0]
    assert path.breaks[2] == pytest.approx(0.12, rel=1e-12)
    for d in (0.05, 0.3, 1.0, 2.0):
        ref, _, _ = solve_lcp(W, q0 + d * q1, np.zeros(3, bool), 1e-14)
        assert np.allclose(path.forces(np.array([d]))[0], ref, atol=1e-12)


def test_schur_complement_fast_equals_pivoted(monkeypatch, store):
    """A body's condensed stiffness from the LU's trailing block equals the one from a
    pivoted factorization of K_II and one solve per retained dof."""
    import ssw.contact.lu as ssw_lu
    from ssw.contact.operators import geometry_of
    from ssw.contact.scene import settings_of

    cfg = settings_of(COARSE)
    geom = geometry_of(cfg, 0.4e-3, R, 1e-4, "frictionless")
    fast = OperatorStore(None)
    op1 = fast.body(geom, "plate", 0.36)
    monkeypatch.setattr(ssw_lu, "BACKWARD_ERROR_TOL", -1.0)  # refuse the pivot-free factors
    slow = OperatorStore(None)
    op2 = slow.body(geom, "plate", 0.36)
    assert not op1.stats["pivoted"] and op2.stats["pivoted"]
    assert op1.stats["backward_error"] < 1e-14
    assert np.max(np.abs(op1.S - op2.S)) < 1e-9 * np.max(np.abs(op1.S))


def test_unstable_pivot_free_lu_is_caught():
    """A saddle point whose natural-order pivot is 1e-17: no pivoting would give garbage;
    the backward error flags it and the pivoted path gives the exact Schur complement."""
    import scipy.sparse as sp

    from ssw.contact.substructure import schur_complement

    K = np.array([[1e-17, 1.0, 0.0], [1.0, 0.0, 1.0], [0.0, 1.0, 2.0]])
    S, berr, _, pivoted = schur_complement(sp.csc_array(K), 2)
    exact = K[2:, 2:] - K[2:, :2] @ np.linalg.solve(K[:2, :2], K[:2, 2:])
    assert pivoted and berr < 1e-14
    assert S == pytest.approx(exact, rel=1e-12)


def test_disk_cache_round_trip(tmp_path):
    """Operators written by one store are read, bit for bit, by another; a corrupted file
    is rebuilt, not trusted; the key separates Poisson's ratios."""
    from ssw.contact.operators import geometry_of
    from ssw.contact.scene import settings_of

    geom = geometry_of(settings_of(COARSE), 0.0, R, 1e-4, "frictionless")
    a = OperatorStore(tmp_path)
    s1 = a.body(geom, "soil", 0.3)
    assert a.hits["built"] == 1
    b = OperatorStore(tmp_path)
    s2 = b.body(geom, "soil", 0.3)
    assert b.hits == {"memory": 0, "disk": 1, "built": 0}
    assert np.array_equal(s1.S, s2.S)
    files = sorted(tmp_path.rglob("soil-*.npz"))
    assert len(files) == 1
    files[0].write_bytes(b"not an npz")
    c = OperatorStore(tmp_path)
    with pytest.warns(CacheWarning, match="rebuilding the unreadable cached operator"):
        s3 = c.body(geom, "soil", 0.3)
    assert c.hits["built"] == 1 and np.array_equal(s1.S, s3.S)
    c.body(geom, "soil", 0.45)
    assert len(list(tmp_path.rglob("soil-*.npz"))) == 2


def test_sphere_gap_has_no_cancellation():
    """R - sqrt(R^2 - r^2) at r = 1e-9 m loses every digit in double precision;
    r^2 / (R + sqrt(R^2 - r^2)) keeps them: compare with 50-digit decimal arithmetic."""
    from decimal import Decimal, getcontext

    getcontext().prec = 50
    r = np.array([1e-12, 1e-9, 1e-6, 1e-3, 4e-3])
    Rd = Decimal(R)
    exact = [float(Rd - (Rd * Rd - Decimal(x) * Decimal(x)).sqrt()) for x in r]
    assert np.max(np.abs(sphere_gap0(r, R) / exact - 1)) < 4e-16
    naive = R - np.sqrt(R**2 - r**2)
    assert naive[0] == 0.0 and abs(naive[1] / exact[1] - 1) > 1e-3  # digits lost


def test_increments_are_uniform_over_the_whole_range():
    """One step, delta_max / steps, over [0, max(delta_max, reach)] (a fit's least squares
    weights every part of its range alike); the last increment ends at the reach."""
    d = indentation_steps(1e-4, 1000, 3.75e-4)
    assert d.size == 3750 and d[-1] == pytest.approx(3.75e-4, rel=1e-15)
    assert np.allclose(np.diff(d), 1e-7, rtol=1e-9)
    assert d[9] == pytest.approx(1e-6, rel=1e-15) and d[999] == pytest.approx(1e-4, rel=1e-15)
    d = indentation_steps(1e-4, 1000, 3.7004e-4)
    assert d[-1] == 3.7004e-4 and 0 < d[-1] - d[-2] < 1e-7
    assert np.allclose(np.diff(d[:-1]), 1e-7, rtol=1e-9)
    assert indentation_steps(1e-4, 10, 5e-5)[-1] == pytest.approx(1e-4)


def test_fitted_K_is_smooth_where_the_reach_crosses_delta_max(store):
    """The study's K(E) jumped where the chain's reach crossed delta_max (two sampling
    densities under an OLS fit). The exact law varies smoothly with E, so must K: across
    the crossing its E-differences stay of one sign and size (no step)."""
    from ssw.config import library, load_config
    from ssw.fit.fitting import fit_curve
    from ssw.fit.range import fit_ranges

    cfg = load_config("config/config.yaml")
    pla = library(cfg)["pla"]
    E = np.linspace(400e6, 640e6, 7)
    rng = fit_ranges(E, np.full(E.size, 0.5), np.full(E.size, np.inf), cfg,
                     [pla.E] * E.size, [pla.nu] * E.size)
    need = np.array([r.needed for r in rng])
    dmax = cfg["contact"]["delta_max"]
    assert need.max() > dmax > need.min()  # the grid straddles the crossing
    K = []
    for e, r in zip(E, rng, strict=True):
        c, _ = solve_curve((e, 0.5), (pla.E, pla.nu), 0.4e-3, R,
                           {**cfg["contact"], "delta_reach": max(dmax, r.needed)}, store)
        K.append(fit_curve(c, "k_hertz", (0.0, r.needed)).params["K"])
    dK = np.diff(K)
    assert np.all(dK < 0)  # a stiffer soil: a plate matters less, K falls
    assert dK.min() > 1.5 * dK.max()  # steps within 50 % of each other (the jump was +2.5 %)
