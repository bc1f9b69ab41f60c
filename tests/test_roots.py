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
