"""The bracketed root finder (ssw.roots) against closed-form roots, with its cost."""

from __future__ import annotations

import numpy as np
import pytest

from ssw.errors import SolverError
from ssw.roots import XRTOL, find_root


def test_cube_roots_to_full_precision_in_few_calls():
    """``x^3 = c`` for c over 24 decades: every root within 4 ulp of ``cbrt(c)`` in at most
    16 calls of the function on all of them at once (bisection of the same brackets to the
    same precision: 52 halvings or more)."""
    c = np.geomspace(1e-12, 1e12, 25)
    r = find_root(lambda x: x**3 - c, np.zeros_like(c), 2.0 * np.cbrt(c))
    assert np.allclose(r.x, np.cbrt(c), rtol=XRTOL, atol=0)
    assert np.all(r.lo <= r.x) and np.all(r.x <= r.hi)
    assert np.all(r.lo**3 <= c) and np.all(r.hi**3 >= c)
    assert np.all(r.hi - r.lo <= 2 * XRTOL * r.x)
    assert r.calls <= 16


def test_growth_ends_and_tolerance():
    """A first guess far below the roots grows (its calls counted); a root exactly at an end
    is that end; an absolute tolerance in the unknown's unit stops early."""
    c = np.array([0.0, 1.0, 5.0, 1e6])
    r = find_root(lambda x: x**2 - c, np.zeros(4), np.full(4, 1e-3), grow=True)
    assert np.allclose(r.x, np.sqrt(c), rtol=XRTOL, atol=0)
    assert r.x[0] == 0.0 and r.hi[0] == 0.0
    coarse = find_root(lambda x: x**2 - 5.0, 0.0, 10.0, xatol=1e-3, xrtol=0.0)
    assert abs(coarse.x - np.sqrt(5.0)) < 1e-3 and coarse.hi - coarse.lo < 1e-3
    assert coarse.calls < find_root(lambda x: x**2 - 5.0, 0.0, 10.0).calls


def test_the_function_sees_every_element():
    """A function of the whole vector (a wall's force, one value per scene) is always called
    with every element, the converged ones kept at their roots."""
    seen = []
    k = np.array([1.0, 2.0, 3.0])

    def f(x):
        seen.append(x.shape)
        return k * x - 1.0

    r = find_root(f, np.zeros(3), np.ones(3))
    assert set(seen) == {(3,)} and len(seen) == r.calls
    assert np.allclose(r.x, 1.0 / k, rtol=XRTOL)


def test_refusals():
    with pytest.raises(SolverError, match="do not hold a root"):
        find_root(lambda x: x - 2.0, 0.0, 1.0)
    with pytest.raises(SolverError, match="no root up to"):
        find_root(lambda x: x - 2.0, 0.0, 0.1, grow=True, limit=1.0)
    with pytest.raises(SolverError, match="not finite"):
        find_root(lambda x: np.where(x < 1.0, np.nan, x - 2.0), 0.0, 3.0)


def test_closed_form_roots_many_brackets_at_once():
    """``x^3 = a`` and ``exp(x) = a`` on 40 elements with brackets of their own (wide,
    tight, lopsided, far from zero), each root within a few ulp of its closed form and
    inside its final bracket, which keeps the sign invariant."""
    rng = np.random.default_rng(7)
    a = 10.0 ** rng.uniform(-9, 9, 40)
    for f, root in ((lambda x: x**3 - a, np.cbrt(a)), (lambda x: np.exp(x) - a, np.log(a))):
        lo = root - np.abs(root) * rng.uniform(1e-6, 3.0, 40) - rng.uniform(0, 1, 40)
        hi = root + np.abs(root) * rng.uniform(1e-9, 0.5, 40) + 1e-300
        r = find_root(f, lo, hi)
        assert np.allclose(r.x, root, rtol=2 * XRTOL, atol=1e-300)
        assert np.all(f(r.lo) <= 0) and np.all(f(r.hi) >= 0)
        assert np.all((lo <= r.lo) & (r.lo <= r.x) & (r.x <= r.hi) & (r.hi <= hi))
        assert np.all(r.hi - r.lo <= 2 * XRTOL * np.abs(r.x) + 1e-300)
        # the slowest of 40 elements, on brackets up to 4 times the root wide: 14 and 18
        assert 8 <= r.calls <= 20


def test_hertz_energy_root_in_closed_form():
    """The indentation at which a Hertz law ``F = k d^(3/2)`` stores ``E = (2/5) k d^(5/2)``
    is ``(5 E / (2 k))^(2/5)``; with a load ``P`` the root of ``(2/5) k d^(5/2) - P d = W``
    (:func:`ssw.hertz.energy_indentation`) is checked on energies built from known
    indentations."""
    from ssw.hertz import energy_indentation

    k = np.array([2e9, 7e9, 3e10, 1.2e11])
    E = np.array([1e-9, 3e-6, 2e-3, 0.5])
    d = (2.5 * E / k) ** 0.4
    r = find_root(lambda x: 0.4 * k * x**2.5 - E, np.zeros(4), np.full(4, 1e-6), grow=True)
    assert np.allclose(r.x, d, rtol=4 * XRTOL, atol=0)
    assert r.calls <= 40  # the growth from 1 um included
    d0 = np.array([3e-6, 2e-5, 1e-4, 4e-4])
    P = 0.1 * k * d0**1.5  # a tenth of the force the contact carries at d0
    W = 0.4 * k * d0**2.5 - P * d0
    assert np.allclose(energy_indentation(k, W, P), d0, rtol=1e-13, atol=0)


def test_roots_exactly_at_the_ends():
    """``f`` zero at the lower end, at the upper end, at both and at the first midpoint:
    the root is that point and the bracket shrinks to it; the others converge as usual."""
    root = np.array([0.0, 1.0, 0.5, 0.3, 2.0])
    lo = np.array([0.0, 0.0, 0.0, 0.0, 2.0])
    hi = np.array([1.0, 1.0, 1.0, 1.0, 2.0])
    r = find_root(lambda x: x - root, lo, hi)
    assert np.array_equal(r.x[[0, 1, 2, 4]], root[[0, 1, 2, 4]])
    assert np.array_equal(r.lo[[0, 1, 2, 4]], root[[0, 1, 2, 4]])
    assert np.array_equal(r.hi[[0, 1, 2, 4]], root[[0, 1, 2, 4]])
    assert abs(r.x[3] - 0.3) <= XRTOL * 0.3 and r.lo[3] <= 0.3 <= r.hi[3]


def test_growth_from_a_small_bracket():
    """``exp(x) = a`` from ``[0, 1e-3]``: the bracket grows (lower end following) until it
    holds every root; growth and refinement calls are counted together."""
    a = np.array([1.5, 10.0, 1e5, 1e200])
    seen = []

    def f(x):
        seen.append(x.copy())
        return np.exp(x) - a

    r = find_root(f, np.zeros(4), np.full(4, 1e-3), grow=True)
    assert len(seen) == r.calls and r.calls > 16  # 9 doublings to reach log(1e200)
    assert np.allclose(r.x, np.log(a), rtol=2 * XRTOL, atol=0)
    assert np.all(f(r.lo) <= 0) and np.all(f(r.hi) >= 0)


def test_refusals_element_by_element():
    """One element of many without a root in its bracket, or with ``f`` not finite where it
    is evaluated (NaN, inf), fails the whole call with the element's values."""
    c = np.array([0.5, 2.0, 0.7])
    with pytest.raises(SolverError, match=r"brackets \[\[0\.0\], \[1\.0\]\] do not hold"):
        find_root(lambda x: x - c, np.zeros(3), np.ones(3))
    with pytest.raises(SolverError, match="do not hold a root"):
        find_root(lambda x: x - 0.5, 1.0, 0.0)  # reversed bracket
    with pytest.raises(SolverError, match=r"not finite at x = \[0\.5\]"):
        find_root(lambda x: np.where((x > 0.4) & (x < 0.6), np.nan, x - 0.7), 0.0, 1.0)
    with pytest.raises(SolverError, match="not finite"):
        find_root(lambda x: np.where(x > 0.9, np.inf, x - 0.5), np.zeros(2), np.ones(2))
    with pytest.raises(SolverError, match=r"bracket has an end that is not finite: \[\[-inf\]"):
        find_root(np.arctan, -np.inf, 1.0)


def test_iteration_limit(monkeypatch):
    """An iteration that runs out of steps fails rather than returning a loose root."""
    import ssw.roots

    monkeypatch.setattr(ssw.roots, "MAX_ITERATIONS", 3)
    with pytest.raises(SolverError, match=r"did not converge in 3 iterations"):
        find_root(lambda x: x**3 - 2.0, 0.0, 2.0)


def test_shapes():
    """Scalars give 0-d results, arrays keep their shape (broadcast ends), empty ones
    evaluate the two ends only."""
    r = find_root(lambda x: x**2 - 2.0, 0.0, 2.0)
    assert r.x.shape == () and abs(r.x - np.sqrt(2.0)) <= XRTOL
    c = np.arange(1.0, 7.0).reshape(2, 3)
    r = find_root(lambda x: x**2 - c, 0.0, np.full((2, 3), 3.0))
    assert r.x.shape == r.lo.shape == r.hi.shape == (2, 3)
    assert np.allclose(r.x, np.sqrt(c), rtol=XRTOL, atol=0)
    r = find_root(lambda x: x, np.zeros(0), np.ones(0))
    assert r.x.shape == (0,) and r.calls == 2


def test_same_iterates_as_scipy():
    """scipy's implementation of the same method (``scipy.optimize.elementwise.find_root``)
    reaches the same roots and final brackets bit for bit, in as many evaluations (scipy
    evaluates the two ends itself: its count is ours without the growth)."""
    elementwise = pytest.importorskip("scipy.optimize.elementwise")
    rng = np.random.default_rng(3)
    c = 10.0 ** rng.uniform(-6, 6, 50)
    p = rng.choice([0.5, 1.5, 2.5, 3.0], 50)
    hi = 3.0 * c ** (1.0 / p) * rng.uniform(0.5, 2.0, 50)
    for xatol, xrtol in ((0.0, XRTOL), (1e-9, 1e-6)):
        r = find_root(lambda x: x**p - c, np.zeros(50), hi, xatol=xatol, xrtol=xrtol)
        s = elementwise.find_root(lambda x, p, c: x**p - c, (np.zeros(50), hi), args=(p, c),
                                  tolerances={"xatol": max(xatol, 4 * np.finfo(float).tiny),
                                              "xrtol": xrtol, "fatol": 0.0, "frtol": 0.0})
        assert np.all(s.success)
        assert np.array_equal(r.x, s.x)
        assert np.array_equal(r.lo, np.where(s.f_x <= 0, s.x, s.bracket[0]))
        assert np.array_equal(r.hi, np.where(s.f_x >= 0, s.x, s.bracket[1]))
        assert r.calls == s.nfev.max()


def test_no_scipy_optimize_import():
    """The module and a solve need numpy only: importing scipy.optimize costs a process
    0.15-0.25 s."""
    import subprocess
    import sys

    code = ("import sys, ssw.roots; ssw.roots.find_root(lambda x: x - 1.0, 0.0, 2.0); "
            "print('scipy.optimize' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"


def _polyline(breaks, slopes):
    """A continuous increasing piecewise-affine ``f`` with ``f(0) = 0`` (pieces between
    ``breaks``), as ``newton_bracketed``'s ``fun`` with the piece's index as the state."""
    b = np.asarray(breaks, float)
    s = np.asarray(slopes, float)
    f_at = np.concatenate([[0.0], np.cumsum(s[:-1] * np.diff(b))])

    def fun(x, states):
        j = np.clip(np.searchsorted(b, x, side="right") - 1, 0, s.size - 1)
        return f_at[j] + s[j] * (x - b[j]), s[j], list(j)

    return fun, b, s, f_at


def test_newton_on_a_piecewise_affine_function_is_exact_in_one_step_per_piece():
    """Levels on five pieces of a stiffening polyline: every root equals the closed-form
    inversion of its piece (to round-off), found from a first guess 1000 times too small
    (the bracket grows) in fewer steps than pieces plus growth; the states name the root's
    piece."""
    from ssw.roots import newton_bracketed

    fun, b, s, f_at = _polyline([0.0, 1.0, 2.0, 3.0, 4.0], [1.0, 2.0, 4.0, 8.0, 16.0])
    level = np.array([0.5, 1.5, 4.0, 10.0, 30.0])
    j = np.searchsorted(f_at, level, side="right") - 1
    exact = b[j] + (level - f_at[j]) / s[j]
    r = newton_bracketed(fun, level, 0.0, 5e-3, [None] * 5, grow=True,
                         same_piece=lambda p, q: p == q)
    assert r.x == pytest.approx(exact, rel=4 * XRTOL, abs=0)
    assert list(r.state) == list(j)
    assert np.all(r.lo < r.x) and np.all(r.x <= r.hi)
    assert r.calls <= 10 + 5 + 1  # growth to 5.12 (10 doublings), pieces, first point


def test_newton_with_a_residual_tolerance_and_its_bisection_safeguard():
    """``atan(x - c) = 0`` from brackets up to 40 wide: Newton's step from the bracket's end
    overshoots far out of it (the safeguard bisects); every root ``c`` to ``ftol``. A bracket
    that never holds the level, and a missing stopping rule, are errors."""
    from ssw.roots import newton_bracketed

    c = np.array([-3.0, 0.1, 7.0])

    def fun(x, states):  # each element's state is its c
        u = x - np.array(states)
        return np.arctan(u), 1.0 / (1.0 + u**2), states

    r = newton_bracketed(fun, 0.0, -10.0, 30.0, list(c), ftol=1e-13)
    assert r.x == pytest.approx(c, abs=1e-12)
    from_lo = newton_bracketed(fun, 0.0, -10.0, 30.0, list(c), ftol=1e-13, x0=-10.0)
    assert from_lo.x == pytest.approx(c, abs=1e-12)
    with pytest.raises(ValueError, match="same_piece or ftol"):
        newton_bracketed(fun, 0.0, -10.0, 30.0, list(c))
    with pytest.raises(SolverError, match="reaches the level"):
        newton_bracketed(lambda x, st: (np.zeros_like(x), np.zeros_like(x), st), 1.0, 0.0,
                         1.0, [None], grow=True, ftol=0.0)


def test_newton_with_array_states_selects_rows_without_a_list():
    """The states as an array (a row per element): the same roots as the list of states,
    bit for bit, with the stopped elements' rows returned in the array. ``atan(x - c) = 0``
    with the bracket grown from a first guess below some roots; the roots are ``c`` to
    ``ftol`` (the equation's closed form)."""
    from ssw.roots import newton_bracketed

    c = np.array([-3.0, 0.1, 7.0, 25.0, 0.0, 12.5])

    def fun(x, states):  # each element's state is its c, as a list or an array
        u = x - np.asarray(states, float)
        return np.arctan(u), 1.0 / (1.0 + u**2), states

    as_list = newton_bracketed(fun, 0.0, -10.0, 2.0, list(c), grow=True, ftol=1e-13)
    as_array = newton_bracketed(fun, 0.0, -10.0, 2.0, c.copy(), grow=True, ftol=1e-13)
    assert isinstance(as_array.state, np.ndarray)
    np.testing.assert_array_equal(as_array.x, as_list.x)
    np.testing.assert_array_equal(as_array.state, c)
    assert as_array.calls == as_list.calls
    assert as_array.x == pytest.approx(c, abs=1e-12)
