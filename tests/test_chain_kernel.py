"""The compiled chain step (ssw.chain.kernel): it is used only when built from the source in
the tree, and says how to rebuild it otherwise."""

import numpy as np
import pytest

from ssw.chain import kernel
from ssw.errors import SswError


def test_a_library_built_from_another_source_is_refused(tmp_path, monkeypatch):
    """An edited ``_step.c`` whose library was not rebuilt would run old arithmetic under
    new docs: the loader compares the hash built into the library with the source's and
    refuses, naming the command that rebuilds it."""
    edited = tmp_path / "_step.c"
    edited.write_bytes(kernel.SOURCE.read_bytes() + b"\n/* edited */\n")
    monkeypatch.setattr(kernel, "SOURCE", edited)
    with pytest.raises(SswError, match=r"built from another _step.c .*scripts/setup.sh"):
        kernel.library.__wrapped__()


def test_the_library_in_the_tree_is_the_source_in_the_tree():
    """The library the tests run was built from the ``_step.c`` beside it."""
    lib = kernel.library()
    assert lib.ssw_step_source().decode() == kernel.source_digest()


def test_the_piecewise_wall_law_is_the_interpolation_of_its_breakpoints():
    """A piecewise-linear wall (the ``fem`` law) is the linear interpolation of its forces at
    its breakpoints, continued by its last piece and 0 for no contact: its force, slope and
    potential (the compiled search, at any array shape ending in the scenes) against
    ``numpy.interp`` and the trapezoid's exact integral of the interpolant."""
    from ssw.walls.fem import PiecewiseLinearWall

    rng = np.random.default_rng(7)
    n, K = 3, 6
    d = np.concatenate([np.zeros((n, 1)), np.cumsum(rng.uniform(1e-6, 5e-6, (n, K)), 1)], 1)
    F = np.concatenate([np.zeros((n, 1)), np.cumsum(rng.uniform(1.0, 50.0, (n, K)), 1)], 1)
    b = np.diff(F, axis=1) / np.diff(d, axis=1)
    b = np.concatenate([b, b[:, -1:]], 1)  # the last piece repeated at the end
    a = F - b * d
    U = np.concatenate([np.zeros((n, 1)), np.cumsum(0.5 * (F[:, 1:] + F[:, :-1])
                                                    * np.diff(d, axis=1), 1)], 1)
    wall = PiecewiseLinearWall(d, a, b, U, d[:, -1].copy())
    x = np.stack([np.full(n, -1e-6), 0.37 * d[:, -1], d[:, 3], 1.4 * d[:, -1]])  # (4, n)
    ref = np.empty_like(x)
    pot = np.empty_like(x)
    for i in range(n):
        beyond = F[i, -1] + b[i, -1] * (x[:, i] - d[i, -1])
        xp = np.maximum(x[:, i], 0.0)
        ref[:, i] = np.where(xp > d[i, -1], beyond, np.interp(xp, d[i], F[i]))
        grid = np.union1d(d[i], xp)
        Fg = np.where(grid > d[i, -1], F[i, -1] + b[i, -1] * (grid - d[i, -1]),
                      np.interp(grid, d[i], F[i]))
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (Fg[1:] + Fg[:-1]) * np.diff(grid))])
        pot[:, i] = np.interp(xp, grid, cum)
    np.testing.assert_allclose(wall.force(x), ref, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(wall.potential(x), pot, rtol=1e-12, atol=1e-18)
    h, inside = 1e-12, x[[1, 3]]  # off the breakpoints, where the slope is one piece's
    slope = (wall.force(inside + h) - wall.force(inside - h)) / (2 * h)
    np.testing.assert_allclose(wall.dforce_dd(inside), slope, rtol=1e-6)
    assert np.all(wall.dforce_dd(x[:1]) == 0.0)
