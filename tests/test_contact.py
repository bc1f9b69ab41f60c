"""Stage I contact FEM against independent truth: Hertz/Sneddon, energy balance, ordering.

Tolerances: the required 0.5 % for Hertz; discretization-level agreement elsewhere, with the
measured figure in a comment.
"""

from __future__ import annotations

import numpy as np
import pytest

from ssw import hertz
from ssw.contact import solve_curve, strain_energy
from ssw.contact.contact_lcp import edge_radius, solve_lcp, sphere_gap

R = 9.53e-3  # m, the thesis's indenter
E_SOIL = 50e6  # Pa
PLA = (3.5e9, 0.36)
AL = (68.9e9, 0.33)
STEEL = (200e9, 0.26)
#: A cheaper mesh (growth 0.2: ~0.4 % force error) for the ordering tests.
COARSE = {"mesh_growth": 0.2, "steps": 50}


def _release(state):
    """Free the PETSc objects of a monolithic solve (the substructured engine holds none)."""
    if "solver" in state:
        state["solver"].destroy()


def _curve(soil, plate=None, t=0.0, engine="substructured", **cfg):
    curve, state = solve_curve(soil, plate, t, R, {"steps": 100, **cfg}, engine=engine)
    return curve, state


@pytest.mark.parametrize("nu", [0.1, 0.3, 0.499, 0.5])
def test_no_plate_matches_hertz(nu):
    """F = 4/3 E/(1-nu^2) sqrt(R) delta^1.5 within 0.5 % for delta in [1e-6, 1e-4] m."""
    curve, state = _curve((E_SOIL, nu))
    _release(state)
    m = curve.delta >= 1e-6 * (1 - 1e-9)
    fh = hertz.force(curve.delta[m], hertz.effective_modulus(E_SOIL, nu), R)
    assert np.max(np.abs(curve.force[m] / fh - 1)) < 5e-3
    # contact radius vs a = sqrt(R delta): measured within 1.4 %
    a_h = hertz.contact_radius(curve.delta[m], R)
    assert np.max(np.abs(curve.contact_radius[m] / a_h - 1)) < 0.03


def test_bonded_plate_of_soil_material_is_no_plate():
    """A plate glued to a soil of its own material is just more soil (measured 0.17 %)."""
    soil = (E_SOIL, 0.3)
    c0, s0 = _curve(soil)
    c1, s1 = _curve(soil, soil, 0.4e-3, interface="bonded")
    for s in (s0, s1):
        _release(s)
    m = c0.delta >= 1e-6 * (1 - 1e-9)
    assert np.max(np.abs(c1.force[m] / c0.force[m] - 1)) < 5e-3


@pytest.mark.parametrize("interface", ["frictionless", "unilateral"])
def test_work_equals_stored_energy(interface):
    """int_0^delta F d(delta) = strain energy x^T K x / 2 (path independence, no friction)."""
    curve, state = _curve((E_SOIL, 0.3), PLA, 0.4e-3, interface=interface, steps=400)
    d = np.concatenate([[0.0], curve.delta])
    f = np.concatenate([[0.0], curve.force])
    work = np.trapezoid(f, d)
    energy = strain_energy(state, state["lam"])
    _release(state)
    # trapezoid rule on a piecewise-linear F(delta): measured 3e-6
    assert work == pytest.approx(energy, rel=1e-4)


def test_stiffer_plates_are_stiffer():
    """At every indentation: no plate < PLA < aluminium < steel (0.4 mm, bonded physics)."""
    forces = []
    for plate, t in ((None, 0.0), (PLA, 0.4e-3), (AL, 0.4e-3), (STEEL, 0.4e-3)):
        c, s = _curve((E_SOIL, 0.3), plate, t, **COARSE)
        _release(s)
        forces.append(c.force)
    assert np.all(np.diff(np.array(forces), axis=0) > 0)


def test_thicker_plates_are_stiffer_and_unilateral_is_softer():
    """Force grows with PLA thickness; letting the plate lift off can only soften it."""
    forces = []
    for t in (0.0, 0.1e-3, 0.4e-3, 1.0e-3):
        c, s = _curve((E_SOIL, 0.3), PLA if t > 0 else None, t, **COARSE)
        _release(s)
        forces.append(c.force)
    assert np.all(np.diff(np.array(forces), axis=0) > 0)
    cu, s = _curve((E_SOIL, 0.3), PLA, 0.4e-3, interface="unilateral", **COARSE)
    _release(s)
    assert np.all(cu.force <= forces[2] * (1 + 1e-9))
    cb, s = _curve((E_SOIL, 0.3), PLA, 0.4e-3, interface="bonded", **COARSE)
    _release(s)
    assert np.all(cb.force >= forces[2] * (1 - 1e-9))


def test_mesh_convergence_rate():
    """Max force error vs the exact sphere (Sneddon 1965) falls as growth^2.

    Node-to-surface contact makes F(delta) piecewise linear between nodes entering the
    contact (spacing ~ growth * a), an interpolation error O(growth^2) relative. The
    domain is 3 m so that its boundary effect (0.02 %) stays below the errors.
    """
    growth = np.array([0.4, 0.2, 0.1])
    err = []
    nu = 0.3
    es = hertz.effective_modulus(E_SOIL, nu)
    a_ref = np.linspace(1e-5, 1.2e-3, 20000)
    d_ref, f_ref = hertz.sneddon_sphere(a_ref, es, R)
    for g in growth:
        c, s = _curve((E_SOIL, nu), soil_radius=3.0, soil_depth=3.0, mesh_size_max=0.3,
                      mesh_growth=g, mesh_size_contact=5e-5 * g)
        _release(s)
        m = c.delta >= 1e-6 * (1 - 1e-9)
        err.append(np.max(np.abs(c.force[m] / np.interp(c.delta[m], d_ref, f_ref) - 1)))
    rate = np.polyfit(np.log(growth), np.log(err), 1)[0]
    assert 1.5 < rate < 2.6, (rate, err)


def test_lcp_matches_nnls():
    """The active-set LCP equals the NNLS form of the same QP (min lam.W.lam/2 + g0.lam)."""
    from scipy.linalg import cholesky, solve_triangular
    from scipy.optimize import nnls

    rng = np.random.default_rng(3)
    a = rng.normal(size=(30, 30))
    W = a @ a.T + 30 * np.eye(30)
    g0 = rng.normal(size=30)
    lam, _, _ = solve_lcp(W, g0, np.zeros(30, bool), 1e-12)
    L = cholesky(W, lower=True)
    ref, _ = nnls(L.T, -solve_triangular(L, g0, lower=True))
    assert np.allclose(lam, ref, atol=1e-10)
    g = g0 + W @ lam
    assert np.all(lam >= 0) and np.all(g >= -1e-10) and abs(lam @ g) < 1e-9


def _lcp_by_enumeration(M: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The LCP's solution by trying every active set (a second method: 2^m linear solves)."""
    from itertools import product

    m = q.size
    found = []
    for bits in product((False, True), repeat=m):
        A = np.array(bits)
        lam = np.zeros(m)
        if A.any():
            lam[A] = np.linalg.solve(M[np.ix_(A, A)], -q[A])
        g = q + M @ lam
        if np.all(lam >= -1e-12) and np.all(g[~A] >= -1e-12):
            found.append(lam)
    assert len(found) >= 1
    return found[0]


@pytest.mark.parametrize("seed", range(5))
def test_lcp_of_a_nonsymmetric_p_matrix_matches_enumeration(seed):
    """A non-symmetric P-matrix (the layered oracle's ring influence coefficients are one)
    through a caller's block solver: the solution every active set is tried for, from a
    cold start and from a wrong warm start (every constraint active)."""
    rng = np.random.default_rng(seed)
    m = 9
    M = np.diag(rng.uniform(2.0, 4.0, m)) + 0.15 * rng.normal(size=(m, m))
    q = rng.normal(size=m)
    ref = _lcp_by_enumeration(M, q)
    calls = []

    def block(idx, rhs):
        calls.append(idx.size)
        return np.linalg.solve(M[np.ix_(idx, idx)], rhs)

    for guess in (np.zeros(m, bool), np.ones(m, bool)):
        lam, act, _ = solve_lcp(M, q, guess, 1e-14, solve_active=block)
        assert np.allclose(lam, ref, rtol=1e-10, atol=1e-12)
        assert np.array_equal(act, lam > 0)
    assert calls  # the caller's solver served


def test_lcp_force_vanishing_at_the_solution_does_not_cycle():
    """Degenerate complementarity (a constraint at zero force and zero gap): round-off may
    make its force -1e-17; the one tolerance policy keeps it, the solve ends at once."""
    W = np.array([[2.0, 1.0], [1.0, 2.0]])
    lam_true = np.array([1.0, 0.0])
    g0 = -W @ lam_true  # constraint 1: g = 0 and lam = 0 at the solution
    lam, _, pivots = solve_lcp(W, g0, np.array([True, True]), 1e-14)
    assert np.allclose(lam, lam_true, atol=1e-14)
    assert pivots <= 1
    g = g0 + W @ lam
    assert np.all(g >= -1e-14) and abs(lam @ g) < 1e-14


def test_sphere_gap_and_edge_radius():
    """Exact spherical gap; the edge estimate recovers a gap opening as (r - a)^1.5."""
    r = np.array([0.0, 1e-3])
    assert sphere_gap(r, R, 0.0)[1] == pytest.approx(R - np.sqrt(R**2 - 1e-6))
    rr = np.linspace(0, 1, 11)
    gap = np.clip(rr - 0.43, 0, None) ** 1.5
    assert edge_radius(rr, gap, rr < 0.43) == pytest.approx(0.43, abs=1e-9)


def test_lazy_condensation_equals_full(monkeypatch):
    """Condensing the sphere candidates on demand gives the LCP on the whole candidate set."""
    import ssw.contact.scene as scene

    soil = (E_SOIL, 0.3)
    lazy, s1 = _curve(soil, STEEL, 0.2e-3, engine="monolithic", **COARSE)
    monkeypatch.setattr(scene, "INITIAL_ZONE", 10.0)  # everything condensed at once
    full, s2 = _curve(soil, STEEL, 0.2e-3, engine="monolithic", **COARSE)
    for s in (s1, s2):
        _release(s)
    assert lazy.stats["solves"] < full.stats["solves"]
    assert np.allclose(lazy.force, full.force, rtol=1e-9, atol=0)


@pytest.mark.parametrize("nu", [0.3, 0.5])
def test_steel_plate_on_soft_soil(nu):
    """Stiffness ratio 2e4 (A36 on 10 MPa soil): the u-p LU still factors (per-body
    pressure scaling) and the plate stiffens the contact at every indentation."""
    soil = (10e6, nu)
    c0, s0 = _curve(soil, **COARSE)
    c1, s1 = _curve(soil, STEEL, 0.1e-3, **COARSE)
    for s in (s0, s1):
        _release(s)
    assert np.all(c1.force > c0.force)


def test_pressure_profile_is_hertzian():
    """Contact pressure vs Hertz p(r) = p0 sqrt(1 - r^2/a^2) inside 0.8 a (measured 0.3 %)."""
    nu = 0.3
    curve, s = _curve((E_SOIL, nu))
    _release(s)
    r, p, d = curve.pressure["r"], curve.pressure["p"][-1], curve.pressure["delta"][-1]
    es = hertz.effective_modulus(E_SOIL, nu)
    inside = r <= 0.8 * hertz.contact_radius(d, R)
    ph = hertz.pressure_profile(r[inside], d, es, R)
    assert np.max(np.abs(p[inside] / ph - 1)) < 0.01


@pytest.mark.slow
def test_plate_curve_converges_under_refinement():
    """With a 0.4 mm steel plate (no closed form), successive refinements of the mesh
    growth (0.2 -> 0.1 -> 0.05) change the force by shrinking amounts (Cauchy convergence),
    and the finest two agree within 0.1 % (measured 0.01 %)."""
    forces = []
    for g in (0.2, 0.1, 0.05):
        c, s = _curve((E_SOIL, 0.3), STEEL, 0.4e-3, mesh_growth=g, mesh_size_contact=5e-5 * g)
        _release(s)
        forces.append(c.force)
    d1 = np.max(np.abs(forces[1] / forces[0] - 1))
    d2 = np.max(np.abs(forces[2] / forces[1] - 1))
    assert d2 < d1 and d2 < 1e-3
