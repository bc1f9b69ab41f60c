"""The chain's compiled step: ``ssw/chain/_step.c``, loaded through :mod:`ctypes`.

One implementation of the step's arithmetic (:func:`ssw.chain.integrate.simulate` keeps the
walls, the records and the stop rule's state): the contact forces averaged over the step's
relative motion (:mod:`ssw.chain.impulse`), the contacts' damping at the predicted velocity
(by the law of :mod:`ssw.chain.dissipation`),
the accelerations with the preload and gravity, the two half kicks and the drift of velocity
Verlet, and the forward sensitivities of all of them (:mod:`ssw.chain.sensitivity`); a block
of whole steps in one call (:meth:`Stepper.advance`) and the early-stop rule
(:func:`stop_update`).

Why compiled: a chain has a few dozen contacts per scene, so a numpy step was a hundred
small ufunc calls whose overhead was most of their cost. Measured on this project's 2-core
machine (docs/performance.md, "The cost of a step"), a whole run's step costs 3.4-4.8x less
CPU for 1 to 20 scenes, and every recorded array agrees with the numpy step's to round-off.
The Hertz law far from an event (two divisions and a square root per contact, most of the
step's arithmetic) runs in SIMD lanes on x86-64 (AVX2 where the CPU has it, else SSE2;
:func:`simd_lanes`), whose IEEE operations give the scalar path's results (every other CPU):
the same bits, and a run of 900 scenes on Hertz walls (``simulate``, the study's chain)
costs 0.35 s of CPU instead of 0.76 s.

The library is built with the package (``setup.py``; ``bash scripts/setup.sh`` or ``pip
install -e .``, which need a C compiler: Debian's ``gcc`` and ``libc6-dev``; GCC, Clang and
MSVC build it, each with its flags in ``setup.py``). The loader (:func:`load`) checks what
it loads: the hash of the source the library was built from (a library older than its
source is refused with the command that rebuilds it), the constants it shares with
:mod:`ssw.chain.impulse`, and the layout of the C struct ``ssw_chain`` against its ctypes
mirror, field by field. Every exported function checks the sizes it is given and answers
with an error code, which the wrappers here raise as :class:`~ssw.errors.SswError`; the
wrappers check what C cannot see, that each array has the shape those sizes say.
"""

from __future__ import annotations

import ctypes
import hashlib
import importlib.util
from functools import lru_cache
from pathlib import Path
from typing import NoReturn

import numpy as np

from ssw.chain.impulse import FAR, ROOT_SERIES, SERIES
from ssw.errors import ConfigError, SswError

_D = ctypes.POINTER(ctypes.c_double)
#: The largest array index of the step (C ``int``).
MAX_INDEX = 2**31 - 1
SOURCE = Path(__file__).with_name("_step.c")
REBUILD = ("run `bash scripts/setup.sh` (or `pip install -e .`) in the ssw checkout; it needs "
           "a C compiler (Debian: apt-get install gcc libc6-dev)")


#: Scratch doubles of the step per contact (``ssw_chain.work``: this many ``N n`` blocks,
#: then ``N n k``).
WORK_BLOCKS = 9


class _Chain(ctypes.Structure):
    """The C ``ssw_chain`` (``_step.c``): sizes, constants and the arrays' addresses, field by
    field in the C declaration's order (:func:`check_layout` compares them)."""

    _fields_ = [
        ("N", ctypes.c_int), ("n", ctypes.c_int), ("k", ctypes.c_int),
        ("predict", ctypes.c_int), ("damped_tangent", ctypes.c_int),
        ("law", ctypes.c_int),
        ("c_D", ctypes.c_int), ("c_P", ctypes.c_int), ("c_T", ctypes.c_int),
        ("n_mass", ctypes.c_int), ("mass_row", ctypes.c_int * 2),
        ("mass_col", ctypes.c_int * 2),
        ("A", ctypes.c_double), ("dt", ctypes.c_double), ("damping", ctypes.c_double),
        ("g", ctypes.c_double),
        ("z", _D), ("acc", _D), ("inv_m", _D), ("preload", _D), ("f", _D), ("power", _D),
        ("ZT", _D), ("Acc", _D), ("dF", _D), ("work", _D),
        ("s", ctypes.c_int), ("n_rec", ctypes.c_int), ("rec_rows", ctypes.c_int),
        ("pair", _D), ("wall", _D), ("dpair", _D), ("peak_u", _D), ("peak_f", _D),
        ("K1", ctypes.c_int), ("c_E", ctypes.c_int),
        ("wd", _D), ("wa", _D), ("wb", _D), ("wda", _D), ("wdb", _D),
        ("power_law", ctypes.c_int), ("pc", _D), ("pe", _D), ("pdc", _D), ("pde", _D),
    ]


def source_digest() -> str:
    """The first 16 hex digits of the SHA-256 of ``_step.c`` (what ``setup.py`` builds in).

    Returns
    -------
    str
        The digest.
    """
    return hashlib.sha256(SOURCE.read_bytes()).hexdigest()[:16]


@lru_cache(maxsize=1)
def library() -> ctypes.CDLL:
    """The compiled step built with the package, checked (:func:`load`).

    Returns
    -------
    ctypes.CDLL
        The library, its functions' argument types set.

    Raises
    ------
    SswError
        The library is missing, was built from another source, or disagrees with this
        module (:func:`load`).
    """
    spec = importlib.util.find_spec("ssw.chain._step")
    if spec is None or spec.origin is None:
        raise SswError(f"ssw's compiled chain step ({SOURCE.name}) is not built: {REBUILD}")
    return load(spec.origin)


def load(path: str | Path) -> ctypes.CDLL:
    """A compiled step (a build of ``_step.c``), checked against this module.

    Refused: a library built from another ``_step.c`` than the one beside this module
    (its built-in hash, ``SSW_STEP_SOURCE``), one whose constants differ from
    :mod:`ssw.chain.impulse`'s (``FAR``, ``SERIES``, ``ROOT_SERIES``) or from
    :data:`WORK_BLOCKS`, and one whose ``ssw_chain`` the ctypes mirror does not match
    (:func:`check_layout`).

    Parameters
    ----------
    path : str or pathlib.Path
        The shared library.

    Returns
    -------
    ctypes.CDLL
        The library, its functions' argument and result types set.

    Raises
    ------
    SswError
        A check failed; the message names it (and the command that rebuilds the library,
        when it is older than its source).
    """
    lib = ctypes.CDLL(str(path))
    lib.ssw_step_source.restype = ctypes.c_char_p
    built = lib.ssw_step_source().decode()
    if SOURCE.exists() and built != source_digest():
        raise SswError(f"the compiled chain step ({path}) was built from another "
                       f"{SOURCE.name} (source {built}, now {source_digest()}): {REBUILD}")
    lib.ssw_step_error.argtypes = [ctypes.c_int]
    lib.ssw_step_error.restype = ctypes.c_char_p
    lib.ssw_step_lanes.argtypes = []
    lib.ssw_step_lanes.restype = ctypes.c_int
    lib.ssw_step_constants.argtypes = [_D, ctypes.c_int]
    lib.ssw_step_constants.restype = ctypes.c_int
    got = np.empty(7)
    if code := lib.ssw_step_constants(got.ctypes.data_as(_D), got.size):
        _refused(lib, "ssw_step_constants", code)
    want = [FAR, *SERIES, *ROOT_SERIES]
    if not np.array_equal(got[:6], want):
        raise SswError(f"{SOURCE.name} and ssw.chain.impulse disagree on FAR, SERIES and "
                       f"ROOT_SERIES ({got[:6].tolist()} against {want})")
    if got[6] != WORK_BLOCKS:
        raise SswError(f"{SOURCE.name} and ssw.chain.kernel disagree on WORK_BLOCKS "
                       f"({got[6]:g} against {WORK_BLOCKS})")
    check_layout(lib, _Chain)
    ref = ctypes.POINTER(_Chain)
    types = {
        "ssw_drift": [ref],
        "ssw_forces": [ref, ctypes.c_int, ctypes.c_int],
        "ssw_record": [ref, ctypes.c_int],
        "ssw_advance": [ref, ctypes.c_int, ctypes.c_int],
        # addresses as integers (ndarray.ctypes.data): a block's call costs a few us
        "ssw_stop_update": [ctypes.c_int, ctypes.c_int, ctypes.c_int64]
        + [ctypes.c_void_p] * 7,
        "ssw_hertz": [ctypes.c_int64, _D, _D, ctypes.c_double, _D, _D, _D],
        "ssw_piecewise": [ctypes.c_int64, ctypes.c_int, ctypes.c_int, _D, _D, _D, _D, _D, _D,
                          _D, _D, _D, ctypes.POINTER(ctypes.c_int)],
        "ssw_power_law": [ctypes.c_int64, ctypes.c_int, _D, _D, _D, _D, _D, _D, _D, _D],
    }
    for name, args in types.items():
        fn = getattr(lib, name)
        fn.argtypes = args
        fn.restype = ctypes.c_int
    return lib


def check_layout(lib: ctypes.CDLL, mirror: type[ctypes.Structure]) -> None:
    """Refuse a ctypes mirror of ``ssw_chain`` whose layout is not the C struct's.

    The library names the struct's fields in their order (``ssw_chain_fields``) and gives
    its size and each field's offset and size as its compiler laid them out
    (``ssw_chain_layout``); the mirror must have the same fields, each at the same offset
    with the same size, and the same total size.

    Parameters
    ----------
    lib : ctypes.CDLL
        The compiled step.
    mirror : type
        The :class:`ctypes.Structure` that mirrors ``ssw_chain`` (``ssw.chain.kernel._Chain``).

    Raises
    ------
    SswError
        A field only one side has, a field at another offset or of another size (the
        first one in the C order, by name), or another total size.
    """
    lib.ssw_chain_fields.restype = ctypes.c_char_p
    lib.ssw_chain_layout.argtypes = [ctypes.POINTER(ctypes.c_int64), ctypes.c_int]
    lib.ssw_chain_layout.restype = ctypes.c_int
    names = lib.ssw_chain_fields().decode().split()
    got = np.zeros(1 + 2 * len(names), np.int64)
    if code := lib.ssw_chain_layout(got.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)),
                                    got.size):
        _refused(lib, "ssw_chain_layout", code)
    ours = [f[0] for f in mirror._fields_]
    where = (f"{mirror.__module__}.{mirror.__qualname__} does not mirror {SOURCE.name}'s "
             "ssw_chain")
    how = "the mirror lists the struct's fields in their order, with their C types"
    if set(ours) != set(names):
        raise SswError(f"{where}: fields only in the mirror {sorted(set(ours) - set(names))}, "
                       f"only in C {sorted(set(names) - set(ours))} ({how})")
    for i, name in enumerate(names):
        off, size = int(got[1 + 2 * i]), int(got[2 + 2 * i])
        field = getattr(mirror, name)
        if (field.offset, field.size) != (off, size):
            raise SswError(f"{where}: field {name!r} is at offset {field.offset} "
                           f"({field.size} bytes) in the mirror, at offset {off} ({size} "
                           f"bytes) in C ({how})")
    if ctypes.sizeof(mirror) != int(got[0]):
        raise SswError(f"{where}: {ctypes.sizeof(mirror)} bytes in the mirror, {int(got[0])} "
                       f"in C ({how})")


def simd_lanes() -> int:
    """The lanes the compiled step's far Hertz law runs in on this CPU.

    Returns
    -------
    int
        4 (AVX2), 2 (SSE2) or 1 (the scalar path: not x86-64, or built with
        ``-DSSW_SCALAR``); the results are the same bits whatever the lanes.
    """
    return int(library().ssw_step_lanes())


def _refused(lib: ctypes.CDLL, name: str, code: int) -> NoReturn:
    """Raise the error a function of the compiled step answered with."""
    raise SswError(f"the compiled chain step's {name} refused its arguments (error {code}): "
                   f"{lib.ssw_step_error(code).decode()}")


def _rows(x: np.ndarray, shape: tuple[int, ...], what: str) -> np.ndarray:
    """``x`` as a C-contiguous float array of ``shape``, or an SswError naming ``what``."""
    x = np.ascontiguousarray(x, float)
    if x.shape != shape:
        raise SswError(f"{what}: shape {x.shape}, the compiled chain step needs {shape}")
    return x


def _ptr(x: np.ndarray | None) -> ctypes._Pointer | None:
    return None if x is None else x.ctypes.data_as(_D)


def averaged_hertz(d: np.ndarray, a: np.ndarray, A: float, tangent: bool = False
                   ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """The Hertz force a step applies to contacts (:mod:`ssw.chain.impulse`), by the step's
    own code.

    ``F = A |delta|^(3/2) psi(d / |delta|)`` near an event, ``A d^(3/2) (1 + r / 16 + r^2 /
    640)``, ``r = (delta / d)^2``, from ``d >= FAR |delta|``.

    Parameters
    ----------
    d : numpy.ndarray
        Overlaps (m), any shape.
    a : numpy.ndarray
        ``|delta| = |d'| dt`` (m), the shape of ``d``.
    A : float
        Hertz coefficient (N/m^1.5).
    tangent : bool
        Also ``dF/dd`` and ``dF/d|delta|`` (N/m).

    Returns
    -------
    tuple
        ``(F, dF/dd, dF/d|delta|)``, the shape of ``d`` (None, None without ``tangent``).
    """
    d = np.ascontiguousarray(d, float)
    a = np.ascontiguousarray(np.broadcast_to(a, d.shape), float)
    out = np.empty_like(d)
    fd = np.empty_like(d) if tangent else None
    fa = np.empty_like(d) if tangent else None
    lib = library()
    if code := lib.ssw_hertz(d.size, _ptr(d), _ptr(a), float(A), _ptr(out), _ptr(fd), _ptr(fa)):
        _refused(lib, "ssw_hertz", code)
    return out, fd, fa


def piecewise(law: tuple, x: np.ndarray, tangent: bool = False, with_E: bool = False,
              piece: bool = False) -> tuple[np.ndarray | None, ...]:
    """A piecewise-linear law per scene, by the step's own code (one implementation for the
    step and :class:`ssw.walls.fem.PiecewiseLinearWall`).

    ``F = a_j + b_j d`` with ``j`` the last breakpoint ``d_j <= d``, ``d = max(x, 0)``
    (``d_0 = 0``; the last piece continues beyond the last breakpoint).

    Parameters
    ----------
    law : tuple
        ``(d, a, b, da_dE, db_dE)``: (n, K) C-contiguous float arrays, breakpoints (m,
        increasing per row), ``a`` (N), ``b`` (N/m) of the piece starting at each, and the
        derivatives of ``a`` and ``b`` with respect to the soil's modulus (N/Pa, N/m/Pa;
        None when unknown).
    x : numpy.ndarray
        m, the indentations: shape (..., n), the last axis the scenes'.
    tangent : bool
        Also ``dF/dd`` (N/m; 0 for ``x <= 0``).
    with_E : bool
        Also ``dF/dE = da/dE + db/dE d`` (N/Pa; 0 for ``x <= 0``): needs ``da_dE``.
    piece : bool
        Also ``j``, each scene's piece (its index in the row).

    Returns
    -------
    tuple
        ``(F, dF/dd, dF/dE, j)``, each the shape of ``x`` broadcast with (n,) (None where
        not asked).
    """
    n, K1 = np.shape(law[0])
    d, a, b = (_rows(y, (n, K1), f"the piecewise law's {w}")
               for y, w in zip(law[:3], "dab", strict=True))
    da, db = (None if y is None else _rows(y, (n, K1), "the piecewise law's derivatives")
              for y in law[3:])
    if with_E and (da is None or db is None):
        raise SswError("the piecewise law's dF/dE needs its da_dE and db_dE")
    x = np.asarray(x, float)
    shape = np.broadcast_shapes(x.shape, (n,))
    x = np.ascontiguousarray(np.broadcast_to(x, shape))
    out = np.empty(shape)
    kd = np.empty_like(out) if tangent else None
    kE = np.empty_like(out) if with_E else None
    j = np.empty(shape, np.intc) if piece else None
    lib = library()
    if code := lib.ssw_piecewise(
            out.size // max(n, 1), n, K1, _ptr(d), _ptr(a), _ptr(b),
            _ptr(da if with_E else None), _ptr(db if with_E else None), _ptr(x), _ptr(out),
            _ptr(kd), _ptr(kE),
            None if j is None else j.ctypes.data_as(ctypes.POINTER(ctypes.c_int))):
        _refused(lib, "ssw_piecewise", code)
    return out, kd, kE, j


def power_law(law: tuple, x: np.ndarray, tangent: bool = False, with_E: bool = False
              ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """A power law per scene, by the step's own code (what :meth:`Stepper.use_power_law`
    evaluates).

    ``F = coef d^e``, ``d = max(x, 0)`` (a NaN stays); when every exponent is 1.5 the
    ``d sqrt(d)`` form (``(coef d) sqrt(d)``, ``dF/dd = (1.5 coef) sqrt(d)``), the
    operations of :class:`ssw.chain.wall_power.PowerWall` in their order (the same bits),
    else libm's ``pow`` (``coef pow(d, e)``, ``dF/dd = (e coef) pow(d, e - 1)``, 0 for
    ``d = 0``), which numpy's ``power`` matches only where it calls libm (not its AVX-512
    code).

    Parameters
    ----------
    law : tuple
        ``(coef, exponent, dcoef_dE, dexponent_dE)``: (n,) float arrays, N/m^e, -, N/m^e/Pa
        and 1/Pa (the last two None when unknown, or constant in E for ``dexponent_dE``).
    x : numpy.ndarray
        m, the indentations: shape (..., n), the last axis the scenes'.
    tangent : bool
        Also ``dF/dd`` (N/m).
    with_E : bool
        Also ``dF/dE = dcoef/dE d^e + coef d^e ln(d) de/dE`` (N/Pa; the logarithm's term 0
        for ``x <= 0``): needs ``dcoef_dE``.

    Returns
    -------
    tuple
        ``(F, dF/dd, dF/dE)``, each the shape of ``x`` broadcast with (n,) (None where not
        asked).

    Raises
    ------
    SswError
        ``with_E`` without ``dcoef_dE``; rows of different shapes.
    """
    coef = np.asarray(law[0], float)
    shape = np.broadcast_shapes(np.shape(x), coef.shape)
    hertzian = bool(np.all(np.asarray(law[1]) == 1.5))
    if with_E and law[2] is None:
        raise SswError("the power law's dF/dE needs its dcoef_dE")

    def full(y: object, rows: bool = True) -> np.ndarray | None:
        if y is None:
            return None
        if rows and np.shape(y) != coef.shape:
            raise SswError(f"the power law's rows: {np.shape(y)}, its coefficients "
                           f"{coef.shape}")
        return np.ascontiguousarray(np.broadcast_to(np.asarray(y, float), shape))

    c, e, dc, de = (full(y) for y in law)
    xs = full(x, rows=False)
    out = np.empty(shape)
    kd = np.empty(shape) if tangent else None
    kE = np.empty(shape) if with_E else None
    lib = library()
    if code := lib.ssw_power_law(out.size, int(hertzian), _ptr(c), _ptr(e),
                                 _ptr(dc if with_E else None), _ptr(de if with_E else None),
                                 _ptr(xs), _ptr(out), _ptr(kd), _ptr(kE)):
        _refused(lib, "ssw_power_law", code)
    return out, kd, kE


def stop_update(S: np.ndarray, W: np.ndarray, times: np.ndarray, consts: np.ndarray,
                F: np.ndarray, B: np.ndarray) -> np.ndarray:
    """The early-stop rule over a block of the record, by the step's code
    (the module docstring of :mod:`ssw.chain.integrate` states the rule).

    Parameters
    ----------
    S : numpy.ndarray
        (rows, n) N, the sensor's rows (scenes contiguous, any row stride).
    W : numpy.ndarray
        (rows, n) N, the wall force's, the same strides.
    times : numpy.ndarray
        (rows,) s, C-contiguous.
    consts : numpy.ndarray
        ``(INCIDENT_END, WALL_RELEASE, TRAVEL_FACTOR, TAIL_CONTACTS)``.
    F : numpy.ndarray
        (9, n) C-contiguous, per scene: ``sensor0``, ``wall0``, ``f_noise``, ``t_c``, then
        ``inc_max``, ``t_inc``, ``t_onset``, ``w_max``, ``t_rel`` (updated).
    B : numpy.ndarray
        (2, n) bool, C-contiguous: ``inc_done``, ``released`` (updated).

    Returns
    -------
    numpy.ndarray
        (n,) bool, the scenes that may stop.
    """
    rows, n = S.shape
    if (S.dtype != float or W.shape != S.shape or S.strides[1] != 8 or W.strides != S.strides
            or S.strides[0] % 8):
        S, W = _rows(S, (rows, n), "the sensor's block"), _rows(W, (rows, n), "the wall's")
    times = _rows(times, (rows,), "the block's times")
    consts = _rows(consts, (4,), "the stop rule's constants")
    if (F.shape != (9, n) or F.dtype != float or not F.flags.c_contiguous
            or B.shape != (2, n) or B.dtype != bool or not B.flags.c_contiguous):
        raise SswError(f"the stop rule's state: F {F.shape} {F.dtype}, B {B.shape} {B.dtype}, "
                       f"the compiled chain step needs C-contiguous (9, {n}) float and "
                       f"(2, {n}) bool (updated in place)")
    done = np.empty(n, bool)
    lib = library()
    if code := lib.ssw_stop_update(rows, n, S.strides[0] // 8, S.ctypes.data, W.ctypes.data,
                                   times.ctypes.data, consts.ctypes.data, F.ctypes.data,
                                   B.ctypes.data, done.ctypes.data):
        _refused(lib, "ssw_stop_update", code)
    return done


class Stepper:
    """The state of ``n`` chains of ``N`` beads (``k`` sensitivity columns) and their step.

    Arrays (C-contiguous, SI): ``z`` (2, N, n) positions and velocities, ``acc`` (N, n) the
    last accelerations, ``f`` (N, n) the contact forces (row N - 1 the wall's: set it before
    :meth:`forces`), ``power`` (n,) the damping's dissipation rate, ``peak_u`` (n,) the
    largest wall indentation and ``peak_f`` (N - 1, n) the largest bead-bead forces (from
    :meth:`start_record`); with ``k``: ``ZT`` (2, N, n, k), ``Acc`` and ``dF`` (N, n, k),
    the wall's row of ``dF`` set by the caller.

    Parameters
    ----------
    N : int
        Beads.
    n : int
        Scenes.
    k : int
        Sensitivity columns (0: none).
    consts : dict
        ``A`` (N/m^1.5), ``dt`` (s), ``damping`` (the law's coefficient, its unit), ``law``
        (the law's ``code``, :class:`ssw.chain.dissipation.DissipationLaw`), ``g`` (m/s^2),
        ``predict``, ``damped_tangent`` (bool), ``c_D``, ``c_P``, ``c_E``, ``c_T`` (int,
        -1: none; ``c_T`` the time step's column), ``mass_at`` (list of (bead, column)).
    inv_m : numpy.ndarray
        (N, n) 1/kg.
    preload : numpy.ndarray or None
        (n,) N on bead 1.
    power : bool
        Keep the damping's dissipation rate.

    Raises
    ------
    ConfigError
        More scenes than the compiled step's C ``int`` indices hold.
    SswError
        ``inv_m`` or ``preload`` of another shape.
    """

    def __init__(self, N: int, n: int, k: int, consts: dict, inv_m: np.ndarray,
                 preload: np.ndarray | None, power: bool) -> None:
        if N * n * (WORK_BLOCKS + k) > MAX_INDEX:
            raise ConfigError("scenes", n, f"at most {MAX_INDEX // (N * (WORK_BLOCKS + k))} "
                              f"per run of "
                              f"{N} beads with {k} sensitivities (the compiled step indexes "
                              "its arrays with C ints): run the scenes in batches")
        self.N, self.n, self.k, self.consts = N, n, k, consts
        self.z = np.zeros((2, N, n))
        self.acc = np.zeros((N, n))
        self.f = np.zeros((N, n))
        self.inv_m = _rows(inv_m, (N, n), "the inverse masses")
        self.preload = None if preload is None else _rows(preload, (n,), "the preload")
        self.power = np.zeros(n) if power else None
        self.ZT = np.zeros((2, N, n, k)) if k else None
        self.Acc = np.zeros((N, n, k)) if k else None
        self.dF = np.zeros((N, n, k)) if k else None
        self.peak_u = np.zeros(n)
        self.peak_f = np.zeros((N - 1, n))
        self._rec: tuple = (0, None, None, None)
        self._rec_rows = 0
        self.law: tuple | None = None
        self.power_law = False
        self._bind()

    def _bind(self) -> None:
        N, n, k, c = self.N, self.n, self.k, self.consts
        self.work = np.empty(WORK_BLOCKS * N * n + N * n * k)
        rows = [i for i, _ in c["mass_at"]] + [0, 0]
        cols = [j for _, j in c["mass_at"]] + [0, 0]
        s, pair, wall, dpair = self._rec
        pw = self.power_law
        wd, wa, wb, wda, wdb = (None,) * 5 if pw or self.law is None else self.law
        pc, pe, pdc, pde = self.law if pw and self.law is not None else (None,) * 4
        self._c = _Chain(
            N=N, n=n, k=k, predict=int(c["predict"]), damped_tangent=int(c["damped_tangent"]),
            law=int(c.get("law", 0)), c_D=c["c_D"], c_P=c["c_P"], c_T=int(c.get("c_T", -1)),
            n_mass=len(c["mass_at"]), mass_row=(ctypes.c_int * 2)(*rows[:2]),
            mass_col=(ctypes.c_int * 2)(*cols[:2]),
            A=c["A"], dt=c["dt"], damping=c["damping"], g=c["g"],
            z=_ptr(self.z), acc=_ptr(self.acc), inv_m=_ptr(self.inv_m),
            preload=_ptr(self.preload), f=_ptr(self.f), power=_ptr(self.power),
            ZT=_ptr(self.ZT), Acc=_ptr(self.Acc), dF=_ptr(self.dF), work=_ptr(self.work),
            s=s, n_rec=0 if pair is None else pair.shape[-1], rec_rows=self._rec_rows,
            pair=_ptr(pair), wall=_ptr(wall), dpair=_ptr(dpair),
            peak_u=_ptr(self.peak_u), peak_f=_ptr(self.peak_f),
            K1=0 if wd is None else wd.shape[1], c_E=c["c_E"],
            wd=_ptr(wd), wa=_ptr(wa), wb=_ptr(wb), wda=_ptr(wda), wdb=_ptr(wdb),
            power_law=int(pw), pc=_ptr(pc), pe=_ptr(pe), pdc=_ptr(pdc), pde=_ptr(pde))
        self._ref = ctypes.byref(self._c)
        lib = library()
        self._drift, self._forces, self._record = lib.ssw_drift, lib.ssw_forces, lib.ssw_record
        self._advance = lib.ssw_advance

    def use_law(self, law: tuple) -> None:
        """Evaluate the wall's row in the step, from a piecewise-linear law (:func:`piecewise`'s
        ``law``, one row per current scene; ``da_dE``, ``db_dE`` needed with the ``E``
        sensitivity, ``consts["c_E"]``).

        Parameters
        ----------
        law : tuple
            ``(d, a, b, da_dE, db_dE)``, each (n, K1) or None (the derivatives).
        """
        shape = (self.n, np.shape(law[0])[1])
        self.law = tuple(None if x is None else _rows(x, shape, "the wall law's rows")
                         for x in law)
        self.power_law = False
        self._bind()

    def use_power_law(self, coef: np.ndarray, exponent: np.ndarray,
                      dcoef_dE: np.ndarray | None, dexponent_dE: np.ndarray | None) -> None:
        """Evaluate the wall's row in the step, from a power law ``F = coef [d]_+^e`` per
        scene (:func:`power_law`, :class:`ssw.chain.wall_power.PowerWall`; ``dcoef_dE``
        needed with the ``E`` sensitivity, ``consts["c_E"]``). Its ``d sqrt(d)`` form
        while every current scene's exponent is 1.5 (the step checks each time, so the
        scenes :meth:`keep` leaves decide, as they do the law of
        :meth:`ssw.chain.wall_power.PowerWall.take`).

        Parameters
        ----------
        coef : numpy.ndarray
            (n,) N/m^e.
        exponent : numpy.ndarray
            (n,) -.
        dcoef_dE : numpy.ndarray or None
            (n,) N/m^e/Pa, or None (unknown).
        dexponent_dE : numpy.ndarray or None
            (n,) 1/Pa, or None (constant).
        """
        self.law = tuple(None if x is None else _rows(x, (self.n,), "the power law's rows")
                         for x in (coef, exponent, dcoef_dE, dexponent_dE))
        self.power_law = True
        self._bind()

    def start_record(self, s: int, wall: np.ndarray, pair: np.ndarray,
                     dpair: np.ndarray | None) -> None:
        """Record into block buffers from now on (:meth:`record`); the peaks start from the
        current state.

        Parameters
        ----------
        s : int
            The sensor bead: its contacts ``s - 1`` and ``s`` are recorded.
        wall : numpy.ndarray
            (rows, n) N, the wall force's rows.
        pair : numpy.ndarray
            (rows, 2, n) N, the sensor's two contact forces.
        dpair : numpy.ndarray or None
            (rows, 2, n, k), their sensitivities.

        Raises
        ------
        SswError
            A buffer that is not C-contiguous float64 of those shapes, with ``n`` (their
            last axis but ``dpair``'s) at least the current scenes' and ``rows`` the same.
        """
        rows, n_rec = wall.shape
        want = {"pair": (pair, (rows, 2, n_rec)), "wall": (wall, (rows, n_rec))}
        if dpair is not None:
            want["dpair"] = (dpair, (rows, 2, n_rec, self.k))
        for name, (x, shape) in want.items():
            if x.shape != shape or x.dtype != float or not x.flags.c_contiguous:
                raise SswError(f"the record's {name} buffer: {x.shape} {x.dtype}, the "
                               f"compiled chain step needs C-contiguous float {shape}")
        if n_rec < self.n or not 1 <= s <= self.N - 1:
            raise SswError(f"the record: {n_rec} scenes for {self.n}, sensor bead {s} (1 .. "
                           f"{self.N - 1})")
        self._rec = (s, pair, wall, dpair)
        self._rec_rows = rows
        self.peak_u[:] = self.z[0, -1]
        self.peak_f[:] = self.f[:-1]
        self._bind()

    def record(self, row: int) -> None:
        """Row ``row`` of the record's buffers (the current scenes' first columns), and the
        peaks.

        Parameters
        ----------
        row : int
            The row, ``0 .. rows - 1`` of the buffers.
        """
        if code := self._record(self._ref, row):
            _refused(library(), "ssw_record", code)

    def advance(self, rows: int, row0: int = 0) -> None:
        """``rows`` whole steps, each :meth:`drift`, :meth:`forces` (``has_old``, ``kick``)
        and :meth:`record` into rows ``row0 ..``: one call for a block of steps of a run
        whose wall row does not change from Python (the step evaluates the wall's law,
        :meth:`use_law`, :meth:`use_power_law`). A block of 32 steps of a few scenes cost
        3-4 us of call overhead per step as three calls.

        Parameters
        ----------
        rows : int
            Steps.
        row0 : int
            The first record row (``row0 + rows`` at most the buffers' rows).
        """
        if code := self._advance(self._ref, rows, row0):
            _refused(library(), "ssw_advance", code)

    def drift(self) -> None:
        """The step's first half: ``v += dt/2 acc``, ``u += dt v`` (and their sensitivities)."""
        if code := self._drift(self._ref):
            _refused(library(), "ssw_drift", code)

    def forces(self, has_old: bool, kick: bool) -> None:
        """Contact forces, accelerations and sensitivities at the drifted state.

        Parameters
        ----------
        has_old : bool
            ``acc`` holds the last step's accelerations (the dashpot's predicted velocity).
        kick : bool
            Then the step's second half, ``v += dt/2 acc``.
        """
        if code := self._forces(self._ref, int(has_old), int(kick)):
            _refused(library(), "ssw_forces", code)

    def keep(self, mask: np.ndarray) -> None:
        """Keep the scenes ``mask`` (bool over the current ones), in order.

        Parameters
        ----------
        mask : numpy.ndarray
            (n,) bool.
        """
        self.n = int(np.count_nonzero(mask))
        self.z = np.ascontiguousarray(self.z[:, :, mask])
        self.acc = np.ascontiguousarray(self.acc[:, mask])
        self.f = np.ascontiguousarray(self.f[:, mask])
        self.inv_m = np.ascontiguousarray(self.inv_m[:, mask])
        if self.preload is not None:
            self.preload = np.ascontiguousarray(self.preload[mask])
        if self.power is not None:
            self.power = np.ascontiguousarray(self.power[mask])
        if self.law is not None:
            self.law = tuple(None if x is None else np.ascontiguousarray(x[mask])
                             for x in self.law)
        self.peak_u = np.ascontiguousarray(self.peak_u[mask])
        self.peak_f = np.ascontiguousarray(self.peak_f[:, mask])
        if self.k:
            self.ZT = np.ascontiguousarray(self.ZT[:, :, mask])
            self.Acc = np.ascontiguousarray(self.Acc[:, mask])
            self.dF = np.ascontiguousarray(self.dF[:, mask])
        self._bind()
