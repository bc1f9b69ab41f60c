"""The Hertzian power-law wall inside the compiled step (``Stepper.use_power_law``).

A run on a Hertzian :class:`ssw.chain.wall_power.PowerWall` (every exponent 1.5: ``rigid``,
``hertz``, ``fit`` with ``k_hertz``) advances a block of steps in one call of the compiled
step, which evaluates the wall's law itself. The Python loop it replaced (one step at a
time, the wall's row written by ``_WallDrive.write_row`` from the law's numpy methods) is
what a run on a wall the step does not know still takes: here :class:`_Reference`, the same
``PowerWall`` without ``step_power_law``, run with ``record_forces=True``. Truth, each a
second method:

* the two loops against each other, bit for bit: sensor signals, wall forces, the peaks,
  the stop times and the sensor's sensitivities (the modulus, the striker's speed and
  mass, the sensor's mass, the preload, the damping and the step's own column), each
  dissipation law, with and without tangents, scenes stopping early;
* a law of another exponent, or one whose exponent moves with E, stays on the Python loop
  (numpy's ``power`` and ``log`` are not libm's on every CPU: the module docstring of
  :mod:`ssw.chain.wall_power`);
* the step's law against numpy's IEEE operations (the Hertzian form) and Python's ``math``
  module (libm's ``pow`` and ``log``, one value at a time, for any exponent), bit for bit,
  at the indentations that test the edges (0, -0, negative, NaN, the smallest subnormal);
* physics: a bead on a rigid flat is the mirror image of a symmetric collision of two
  chains (``F = 2^1.5 A u^1.5 = A (2u)^1.5``), through the compiled loop.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from ssw.chain import kernel
from ssw.chain.integrate import simulate
from ssw.chain.params import ChainParams
from ssw.chain.sensitivity import PARAMETERS, STEP
from ssw.chain.statics import initial_state
from ssw.chain.wall_power import PowerWall, fit_wall, hertz_wall, rigid_wall
from ssw.errors import ConfigError

E = np.array([15e6, 60e6, 240e6, 900e6])
NU = np.full(E.size, 0.3)
#: Every parameter's column and the step's.
ALL = (*PARAMETERS, STEP)
#: m, where the non-Hertzian test laws equal the Hertz wall's (its indentations on these
#: soils: 0.09-0.5 mm).
D_REF = 2.0e-4
#: (law, coefficient): the dissipation laws at sizes that matter (test_chain_builds').
LAWS = {"dashpot": 2.0, "kuwabara_kono": 3e3, "hunt_crossley": 0.05}


def _power_law(p: ChainParams) -> PowerWall:
    """``F = coef d^n`` per scene, n 1.25 .. 2.2, each equal to the Hertz wall's force at
    the indentation ``D_REF``, with an E-dependent exponent."""
    h = hertz_wall(p, E, NU)
    n = np.array([1.25, 1.6, 1.9, 2.2])
    scale = D_REF ** (1.5 - n)
    return PowerWall(h.coef * scale, n, dcoef_dE=h.dcoef_dE * scale,
                     dexponent_dE=np.array([2.0e-9, -1.0e-9, 5.0e-10, 1.0e-10]))


#: The Hertzian laws (the step evaluates them).
WALLS = {
    "rigid": lambda p: rigid_wall(p, E, NU),
    "hertz": lambda p: hertz_wall(p, E, NU),
    "k_hertz": lambda p: fit_wall(p, E, NU, K=np.array([0.7, 0.9, 1.1, 1.3])),
    "constant-exponent": lambda p: replace(hertz_wall(p, E, NU),
                                           dexponent_dE=np.zeros(E.size)),
}
#: Laws the step leaves to the Python loop.
PYTHON_WALLS = {
    "power": _power_law,
    "mixed": lambda p: replace(hertz_wall(p, E, NU), exponent=np.array([1.5, 1.5, 1.5, 1.6])),
    "moving-exponent": lambda p: replace(hertz_wall(p, E, NU), dexponent_dE=np.full(E.size,
                                                                                    1e-9)),
}


def _bits(x: np.ndarray | None) -> np.ndarray | None:
    return None if x is None else np.ascontiguousarray(x).view(np.uint64)


def _same_bits(a, b) -> None:
    """Two runs' records, bit for bit."""
    for name in ("t", "sensor", "wall_force", "peak_wall_indentation", "stop_time",
                 "peak_contact_force", "dsensor"):
        x, y = getattr(a, name), getattr(b, name)
        assert (x is None) == (y is None), name
        if x is not None:
            assert x.shape == y.shape, name
            assert np.array_equal(_bits(x), _bits(y)), (
                name, int(np.count_nonzero(_bits(x) != _bits(y))))


@pytest.fixture
def compiled_blocks(monkeypatch):
    """The blocks of steps the compiled loop ran (``Stepper.advance`` calls)."""
    calls = []
    advance = kernel.Stepper.advance

    def spy(self, rows, row0=0):
        calls.append(rows)
        return advance(self, rows, row0)

    monkeypatch.setattr(kernel.Stepper, "advance", spy)
    return calls


class _Reference:
    """The law a run drives from Python: the wrapped :class:`PowerWall`'s own methods, its
    ``step_power_law`` hidden."""

    def __init__(self, wall: PowerWall) -> None:
        self.w = wall

    def __getattr__(self, name: str):
        if name == "step_power_law":
            raise AttributeError(name)
        return getattr(self.w, name)

    def take(self, idx: np.ndarray) -> _Reference:
        return _Reference(self.w.take(idx))


def _both(p: ChainParams, wall: PowerWall, calls: list, **kw):
    """The run through the compiled loop, and through the Python loop (the wall as a
    :class:`_Reference`, every force recorded)."""
    fast = simulate(p, wall, **kw)
    assert calls, "the run did not go through the compiled loop"
    n_calls = len(calls)
    slow = simulate(p, _Reference(wall), record_forces=True, **kw)
    assert len(calls) == n_calls, "the reference went through the compiled loop"
    return fast, slow


@pytest.mark.parametrize("wall", sorted(WALLS))
@pytest.mark.parametrize("law", sorted(LAWS))
def test_the_compiled_loop_gives_the_python_loops_bits(wall, law, compiled_blocks):
    """Every Hertzian law, every dissipation law, with the preload and every tangent
    column: the same bits either loop; the scenes stop at different times (early stops
    leave the step's law rows with the scenes kept)."""
    p = ChainParams(damping=LAWS[law], damping_law=law, preload=2.0)
    w = WALLS[wall](p)
    fast, slow = _both(p, w, compiled_blocks, derivatives=ALL)
    _same_bits(fast, slow)
    # every scene stopped early, at different times but the rigid wall's (one law); every
    # column moves the signal but the rigid wall's E
    assert np.all(np.isfinite(fast.stop_time))
    assert (np.unique(fast.stop_time).size > 1) == (wall != "rigid")
    moved = np.any(fast.dsensor != 0.0, axis=(0, 1))
    assert np.all(moved[[i for i, c in enumerate(ALL) if c != "E" or wall != "rigid"]])


@pytest.mark.parametrize("wall", sorted(PYTHON_WALLS))
def test_other_laws_stay_on_the_python_loop(wall, compiled_blocks):
    """A law with an exponent other than 1.5, or one moving with E, is the run's Python
    loop's: no block of the compiled loop, and a run like any other."""
    p = ChainParams(damping=2.0)
    run = simulate(p, PYTHON_WALLS[wall](p), derivatives=ALL)
    assert not compiled_blocks
    assert np.all(np.isfinite(run.stop_time)) and np.all(np.isfinite(run.dsensor[0]))


@pytest.mark.parametrize("wall", ["hertz", "k_hertz"])
def test_without_tangents_the_loops_agree(wall, compiled_blocks):
    """No sensitivities, undamped, with gravity: the same bits either loop."""
    p = ChainParams()
    fast, slow = _both(p, WALLS[wall](p), compiled_blocks)
    _same_bits(fast, slow)


def test_a_law_without_its_E_dependence_keeps_to_python_for_E(compiled_blocks):
    """A law whose E-dependence is unknown (``dcoef_dE`` None) runs compiled for the other
    columns, the same bits as the Python loop; asked for the E column, the run stays in
    Python and raises the law's ConfigError, as it did before the step evaluated power
    laws."""
    p = ChainParams(damping=2.0)
    w = replace(hertz_wall(p, E, NU), dcoef_dE=None)
    names = ("striker_velocity", "damping")
    fast, slow = _both(p, w, compiled_blocks, derivatives=names)
    _same_bits(fast, slow)
    n_calls = len(compiled_blocks)
    with pytest.raises(ConfigError, match="E-dependence"):
        simulate(p, w, derivatives=("E",))
    assert len(compiled_blocks) == n_calls


def test_the_per_step_loop_with_the_steps_law_gives_the_same_bits(compiled_blocks):
    """``record_forces`` runs one step per call, the step still evaluating the law: the
    compiled blocks' bits, and the forces it records are the wall force's."""
    p = ChainParams(damping=0.05, damping_law="hunt_crossley")
    w = WALLS["k_hertz"](p)
    fast, slow = (simulate(p, w, derivatives=ALL, record_forces=r) for r in (False, True))
    _same_bits(fast, slow)
    assert np.array_equal(_bits(slow.forces[:, :, -1]), _bits(slow.wall_force))


def test_the_steps_law_is_libms_pow_and_log_and_the_hertzian_form():
    """``kernel.power_law`` against Python's ``math`` (libm), one value at a time, bit for
    bit: ``coef pow(d, n)``, ``(n coef) pow(d, n - 1)``, ``dc pow(d, n) + ((coef pow(d, n))
    log(d)) dn`` for d > 0 (0 and the log's term 0 otherwise, NaN kept); the Hertzian form
    ``(coef d) sqrt(d)``, ``(1.5 coef) sqrt(d)``, and a Hertzian ``PowerWall``'s methods."""
    rng = np.random.default_rng(7)
    x = np.concatenate([rng.uniform(-1e-5, 1e-4, 200), 10 ** rng.uniform(-12, -3, 300),
                        [0.0, -0.0, -1.0, 5e-324, np.nan, 1e-300, 1.0]])
    m = x.size
    coef = 10 ** rng.uniform(8, 11, m)
    n = rng.uniform(1.0, 3.0, m)
    dc, dn = rng.normal(0.0, 10.0, m), rng.normal(0.0, 1e-9, m)
    F, kd, kE = kernel.power_law((coef, n, dc, dn), x, tangent=True, with_E=True)

    def ref(c: float, e: float, a: float, b: float, xi: float) -> tuple:
        d = xi if (xi > 0 or xi != xi) else 0.0
        pw = math.pow(d, e)
        k = e * c * math.pow(d, e - 1.0) if d > 0 else 0.0
        return c * pw, k, a * pw + c * pw * math.log(d if d > 0 else 1.0) * b

    want = np.array([ref(*v) for v in zip(coef, n, dc, dn, x, strict=True)]).T
    for got, w in zip((F, kd, kE), want, strict=True):
        assert np.array_equal(_bits(got), _bits(w))
    h = np.full(m, 1.5)
    law = (coef, h, dc, np.zeros(m))
    Fh, kh, kEh = kernel.power_law(law, x, tangent=True, with_E=True)
    dp = np.where((x > 0) | np.isnan(x), x, 0.0)
    assert np.array_equal(_bits(Fh), _bits(coef * dp * np.sqrt(dp)))
    assert np.array_equal(_bits(kh), _bits(1.5 * coef * np.sqrt(dp)))
    w = PowerWall(*law[:2], dcoef_dE=law[2], dexponent_dE=law[3])
    for got, mine in zip((Fh, kh, kEh), (w.force(x), w.dforce_dd(x), w.dforce_dE(x)),
                         strict=True):
        assert np.array_equal(_bits(got), _bits(mine))


def test_rigid_wall_is_the_mirror_image_through_the_compiled_loop(compiled_blocks):
    """A bead on a rigid flat obeys ``F = 2^1.5 A u^1.5 = A (2u)^1.5``: the wall is the
    mirror plane of a chain of 2N beads hit at both ends with opposite speeds, so the wall
    force of the N-bead chain is the middle contact's force of the 2N chain (the sensor's
    upper contact here) up to the step's averaging of a bead pair's law over its motion
    (a wall's is not averaged): within 1.5e-4 of the peak force at 100 steps per contact,
    the gap falling at least 1.8x at 200 (the record_forces variant in
    tests/test_chain_physics.py measured 7.1e-5 and 3.4e-5)."""
    diffs = []
    for spc in (100, 200):
        p = ChainParams(gravity=False, striker_velocity=0.5, n_beads=8, sensor_index=4,
                        steps_per_contact=spc)
        run_w = simulate(p, rigid_wall(p, 1e9, 0.3), t_end=1.2e-3, stop_early=False)
        p2 = p.with_(n_beads=16, sensor_index=8, sensor_reads="upper")
        far = PowerWall(np.array([1.0]), np.array([1.5]))  # never touched: the chain moves up
        u, v = initial_state(p2, far)
        v[0, -1] = -p.striker_velocity
        run_m = simulate(p2, far, t_end=1.2e-3, dt=run_w.dt, stop_early=False,
                         initial=(u, v))
        f_wall, f_mid = run_w.wall_force[:, 0], run_m.sensor[:, 0]
        diffs.append(np.max(np.abs(f_wall - f_mid)) / np.max(f_wall))
    assert len(compiled_blocks) > 0
    assert diffs[0] < 1.5e-4 and diffs[1] < diffs[0] / 1.8, diffs
