"""The compiled chain step (ssw.chain.kernel): it is used only when built from the source in
the tree (and says how to rebuild it otherwise), with a ctypes mirror of its struct that
matches the C layout; it refuses sizes it cannot hold; its lanes are the CPU's; it keeps no
state between calls. tests/test_chain_builds.py compares other compilers' builds with it."""

import ctypes
import platform
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

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


# ------------------------------------------------------------ the struct's layout, checked
def _mirror(fields: list) -> type[ctypes.Structure]:
    """A ctypes mirror of ``ssw_chain`` with the fields given (a broken copy of _Chain)."""
    return type("_Chain", (ctypes.Structure,), {"_fields_": fields})


def _swapped(fields: list, a: str, b: str) -> list:
    i, j = (next(k for k, f in enumerate(fields) if f[0] == x) for x in (a, b))
    out = list(fields)
    out[i], out[j] = out[j], out[i]
    return out


@pytest.mark.parametrize(("change", "names"), [
    ("reordered", r"field 'n' is at offset 8 .* at offset 4"),
    ("retyped", r"field 'K1' is at offset \d+ \(8 bytes\) in the mirror, .*\(4 bytes\)"),
    ("dropped", r"only in C \['rec_rows'\]"),
])
def test_a_mirror_that_is_not_the_struct_is_refused(monkeypatch, change, names):
    """The ctypes class ``_Chain`` mirrors the C struct by hand: a field out of order, of
    another width or missing would have the step read one field's bytes as another's. The
    loader compares the mirror with the offsets and sizes the library's own compiler gave
    (``ssw_chain_layout``) and refuses a copy of the mirror broken on purpose (``n`` and
    ``k`` swapped; ``K1`` an int64; ``rec_rows`` dropped), naming the field."""
    fields = list(kernel._Chain._fields_)
    broken = {
        "reordered": _swapped(fields, "n", "k"),
        "retyped": [(f[0], ctypes.c_int64) if f[0] == "K1" else f for f in fields],
        "dropped": [f for f in fields if f[0] != "rec_rows"],
    }[change]
    monkeypatch.setattr(kernel, "_Chain", _mirror(broken))
    with pytest.raises(SswError, match=rf"does not mirror _step.c's ssw_chain: .*{names}"):
        kernel.library.__wrapped__()


# ------------------------------------------------------------ sizes checked at the boundary
def _stepper(N: int = 4, n: int = 3, k: int = 0, **consts) -> kernel.Stepper:
    """A small chain at rest (the step's arithmetic is not what these tests check)."""
    c = dict(A=1e10, dt=1e-7, damping=0.0, law=0, g=9.81, predict=False,
             damped_tangent=False, c_D=-1, c_P=-1, c_E=-1, c_T=-1, mass_at=[])
    c.update(consts)
    return kernel.Stepper(N, n, k, c, np.full((N, n), 1 / 0.0287), None, False)


def _recording(st: kernel.Stepper, rows: int) -> tuple[np.ndarray, np.ndarray]:
    wall, pair = np.full((rows, st.n), np.nan), np.full((rows, 2, st.n), np.nan)
    st.start_record(1, wall, pair, None)
    return wall, pair


def test_the_compiled_step_refuses_sizes_and_touches_nothing():
    """Each exported function of the compiled step checks the sizes it is given before it
    reads or writes an array, and answers with an error code instead: called directly
    (no Python check in the way), a record row past the record's rows, an early-stop
    block of no rows (whose last time it would read), a piecewise law without breakpoints
    and a negative count are refused, and the arrays they would have written keep their
    sentinel values."""
    lib = kernel.library()
    st = _stepper()
    wall, pair = _recording(st, 5)
    st._c.rec_rows = 4  # the buffers have a fifth row: the C check alone keeps it clean
    assert lib.ssw_record(st._ref, 4) != 0
    assert lib.ssw_advance(st._ref, 2, 3) != 0
    assert np.isnan(wall).all() and np.isnan(pair).all()
    assert lib.ssw_record(st._ref, 3) == 0 and not np.isnan(wall[3]).any()

    n = 3
    done = np.full(n, 7, np.uint8)
    F, B, consts = np.zeros((9, n)), np.zeros((2, n), np.uint8), np.zeros(4)
    S = np.zeros((0, n))
    code = lib.ssw_stop_update(0, n, n, S.ctypes.data, S.ctypes.data, None,
                               consts.ctypes.data, F.ctypes.data, B.ctypes.data,
                               done.ctypes.data)
    assert code != 0 and b"rows" in lib.ssw_step_error(code)
    assert (done == 7).all()

    out = np.full(2, np.nan)
    d = np.zeros((1, 1))
    D = ctypes.POINTER(ctypes.c_double)
    ptr = d.ctypes.data_as(D)
    code = lib.ssw_piecewise(2, 1, 0, ptr, ptr, ptr, None, None, out.ctypes.data_as(D),
                             out.ctypes.data_as(D), None, None, None)
    assert code != 0 and b"breakpoints" in lib.ssw_step_error(code)
    assert np.isnan(out).all()
    assert lib.ssw_hertz(-1, ptr, ptr, 1.0, out.ctypes.data_as(D), None, None) != 0


@pytest.mark.parametrize(("call", "message"), [
    (lambda st: st.record(4), r"ssw_record .*row, the record's row"),
    (lambda st: st.advance(3, 2), r"ssw_advance .*row, the record's row"),
    (lambda st: _stepper(k=2, c_T=2).forces(False, False), r"ssw_forces .*-1 \(none\) or 0"),
    (lambda st: _stepper().advance(1), r"ssw_advance .*the record: s, the sensor bead"),
    (lambda st: kernel.stop_update(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0),
                                   np.zeros(4), np.zeros((9, 3)), np.zeros((2, 3), bool)),
     r"ssw_stop_update .*rows, the block's rows: at least 1"),
    (lambda st: st.start_record(1, np.zeros((4, 3)), np.zeros((4, 2, 2)), None),
     r"the record's pair buffer: \(4, 2, 2\)"),
])
def test_a_refused_size_is_an_error_that_names_it(call, message):
    """The Python side raises each refusal of the compiled step as an SswError that names
    the function and the size (and what it allows); the shapes C cannot see (an array's
    length) are checked before the call."""
    st = _stepper()
    _recording(st, 4)
    with pytest.raises(SswError, match=message):
        call(st)


# ------------------------------------------------------------------ lanes and threads
def test_the_lanes_are_this_cpus():
    """The far law's SIMD lanes are chosen once, when the library loads, from CPUID and the
    OS's saved register state: 4 (AVX2) where the kernel reports ``avx2`` among the CPU's
    flags (Linux clears the flag where the OS does not save the AVX state), else 2 (SSE2,
    every x86-64); 1, the scalar path, elsewhere."""
    if platform.machine().lower() not in ("x86_64", "amd64"):
        assert kernel.simd_lanes() == 1
        return
    info = Path("/proc/cpuinfo")
    if not info.exists():
        pytest.skip("no /proc/cpuinfo to read the CPU's flags from")
    flags = next(line for line in info.read_text().splitlines() if line.startswith("flags"))
    assert kernel.simd_lanes() == (4 if "avx2" in flags.split() else 2)


def _bits(run) -> list[np.ndarray]:
    return [x.view(np.uint64) for x in (run.sensor, run.wall_force, run.dsensor,
                                        run.stop_time, run.peak_wall_indentation)]


def test_runs_in_threads_give_their_bits_alone():
    """ctypes lets go of the GIL around each call of the compiled step, so runs in threads
    run its C code at the same time. The step keeps no state but its arguments (the lanes
    are fixed when the library loads): four runs at once, on the Hertz wall (a call per
    step) and on the ``fem`` wall's law (blocks of steps in one call), with the damping and
    the E tangent, each give the bits of the same run alone."""
    from ssw.chain.integrate import simulate
    from ssw.chain.params import ChainParams
    from ssw.walls import build_wall

    p = ChainParams(damping=3e3, damping_law="kuwabara_kono")
    cases = [("hertz", [40e6, 90e6, 300e6]), ("fem", [50e6, 200e6]),
             ("hertz", [25e6, 600e6]), ("fem", [120e6])]

    def run(case):
        name, E = case
        w = build_wall(name, p, np.array(E), np.full(len(E), 0.3),
                       **({"with_dE": True} if name == "fem" else {}))
        return simulate(p, w, derivatives=("E",))

    alone = [run(c) for c in cases]
    with ThreadPoolExecutor(max_workers=4) as pool:
        together = list(pool.map(run, cases))
    for a, b in zip(alone, together, strict=True):
        for x, y in zip(_bits(a), _bits(b), strict=True):
            np.testing.assert_array_equal(x, y)
