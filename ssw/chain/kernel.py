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
step's arithmetic) runs in SIMD lanes (AVX2 where the CPU has it, else SSE2), whose IEEE
operations give the scalar code's results: the same bits, and a run of 900 scenes on Hertz
walls (``simulate``, the study's chain) costs 0.35 s of CPU instead of 0.76 s.

The library is built with the package (``setup.py``; ``bash scripts/setup.sh`` or ``pip
install -e .``, which need a C compiler: Debian's ``gcc`` and ``libc6-dev``). It carries the
hash of the source it was built from; a library older than its source is refused with the
command that rebuilds it.
"""

from __future__ import annotations

import ctypes
import hashlib
import importlib.util
from functools import lru_cache
from pathlib import Path

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
    field in the C declaration's order."""

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
        ("s", ctypes.c_int), ("n_rec", ctypes.c_int),
        ("pair", _D), ("wall", _D), ("dpair", _D), ("peak_u", _D), ("peak_f", _D),
        ("K1", ctypes.c_int), ("c_E", ctypes.c_int),
        ("wd", _D), ("wa", _D), ("wb", _D), ("wda", _D), ("wdb", _D),
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
    """The compiled step, checked against its source.

    Returns
    -------
    ctypes.CDLL
        The library, its functions' argument types set.

    Raises
    ------
    SswError
        The library is missing or was built from another source.
    """
    spec = importlib.util.find_spec("ssw.chain._step")
    if spec is None or spec.origin is None:
        raise SswError(f"ssw's compiled chain step ({SOURCE.name}) is not built: {REBUILD}")
    lib = ctypes.CDLL(spec.origin)
    lib.ssw_step_source.restype = ctypes.c_char_p
    built = lib.ssw_step_source().decode()
    if SOURCE.exists() and built != source_digest():
        raise SswError(f"the compiled chain step ({spec.origin}) was built from another "
                       f"{SOURCE.name} (source {built}, now {source_digest()}): {REBUILD}")
    lib.ssw_step_constants.argtypes = [_D]
    got = np.empty(6)
    lib.ssw_step_constants(got.ctypes.data_as(_D))
    if not np.array_equal(got, [FAR, *SERIES, *ROOT_SERIES]):
        raise SswError(f"{SOURCE.name} and ssw.chain.impulse disagree on FAR, SERIES and "
                       f"ROOT_SERIES ({got.tolist()} against "
                       f"{[FAR, *SERIES, *ROOT_SERIES]})")
    ref = ctypes.POINTER(_Chain)
    lib.ssw_drift.argtypes = [ref]
    lib.ssw_drift.restype = None
    lib.ssw_forces.argtypes = [ref, ctypes.c_int, ctypes.c_int]
    lib.ssw_forces.restype = None
    lib.ssw_record.argtypes = [ref, ctypes.c_int]
    lib.ssw_record.restype = None
    lib.ssw_advance.argtypes = [ref, ctypes.c_int, ctypes.c_int]
    lib.ssw_advance.restype = None
    # addresses as integers (ndarray.ctypes.data): a block's call costs a few us
    lib.ssw_stop_update.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_long] + \
        [ctypes.c_void_p] * 7
    lib.ssw_stop_update.restype = None
    lib.ssw_hertz.argtypes = [ctypes.c_int, _D, _D, ctypes.c_double, _D, _D, _D]
    lib.ssw_hertz.restype = None
    lib.ssw_piecewise.argtypes = [ctypes.c_long, ctypes.c_int, ctypes.c_int, _D, _D, _D, _D,
                                  _D, _D, _D, _D, _D, ctypes.POINTER(ctypes.c_int)]
    lib.ssw_piecewise.restype = None
    return lib


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
    library().ssw_hertz(d.size, _ptr(d), _ptr(a), float(A), _ptr(out), _ptr(fd), _ptr(fa))
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
    d, a, b, da, db = law
    n = d.shape[0]
    x = np.asarray(x, float)
    shape = np.broadcast_shapes(x.shape, (n,))
    x = np.ascontiguousarray(np.broadcast_to(x, shape))
    out = np.empty(shape)
    kd = np.empty_like(out) if tangent else None
    kE = np.empty_like(out) if with_E else None
    j = np.empty(shape, np.intc) if piece else None
    library().ssw_piecewise(out.size // max(n, 1), n, d.shape[1], _ptr(d), _ptr(a), _ptr(b),
                            _ptr(da if with_E else None), _ptr(db if with_E else None),
                            _ptr(x), _ptr(out), _ptr(kd), _ptr(kE),
                            None if j is None else j.ctypes.data_as(ctypes.POINTER(ctypes.c_int)))
    return out, kd, kE, j


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
    if S.strides[1] != 8 or W.strides != S.strides:
        S, W = np.ascontiguousarray(S), np.ascontiguousarray(W)
    done = np.empty(n, bool)
    library().ssw_stop_update(rows, n, S.strides[0] // 8, S.ctypes.data, W.ctypes.data,
                              times.ctypes.data, consts.ctypes.data, F.ctypes.data,
                              B.ctypes.data, done.ctypes.data)
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
        self.inv_m = np.ascontiguousarray(inv_m, float)
        self.preload = None if preload is None else np.ascontiguousarray(preload, float)
        self.power = np.zeros(n) if power else None
        self.ZT = np.zeros((2, N, n, k)) if k else None
        self.Acc = np.zeros((N, n, k)) if k else None
        self.dF = np.zeros((N, n, k)) if k else None
        self.peak_u = np.zeros(n)
        self.peak_f = np.zeros((N - 1, n))
        self._rec: tuple = (0, None, None, None)
        self.law: tuple | None = None
        self._bind()

    def _bind(self) -> None:
        N, n, k, c = self.N, self.n, self.k, self.consts
        self.work = np.empty(WORK_BLOCKS * N * n + N * n * k)
        rows = [i for i, _ in c["mass_at"]] + [0, 0]
        cols = [j for _, j in c["mass_at"]] + [0, 0]
        self._c = _Chain(
            N, n, k, int(c["predict"]), int(c["damped_tangent"]), int(c.get("law", 0)),
            c["c_D"], c["c_P"], int(c.get("c_T", -1)),
            len(c["mass_at"]), (ctypes.c_int * 2)(*rows[:2]), (ctypes.c_int * 2)(*cols[:2]),
            c["A"], c["dt"], c["damping"], c["g"],
            _ptr(self.z), _ptr(self.acc), _ptr(self.inv_m), _ptr(self.preload), _ptr(self.f),
            _ptr(self.power), _ptr(self.ZT), _ptr(self.Acc), _ptr(self.dF), _ptr(self.work),
            self._rec[0], 0 if self._rec[1] is None else self._rec[1].shape[-1],
            # pair, wall, dpair
            *(_ptr(x) for x in self._rec[1:]), _ptr(self.peak_u), _ptr(self.peak_f),
            0 if self.law is None else self.law[0].shape[1], c["c_E"],
            *(_ptr(x) for x in (self.law or (None,) * 5)))
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
            ``(d, a, b, da_dE, db_dE)``.
        """
        self.law = tuple(None if x is None else np.ascontiguousarray(x, float) for x in law)
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
        """
        self._rec = (s, pair, wall, dpair)
        self.peak_u[:] = self.z[0, -1]
        self.peak_f[:] = self.f[:-1]
        self._bind()

    def record(self, row: int) -> None:
        """Row ``row`` of the record's buffers (the current scenes' first columns), and the
        peaks.

        Parameters
        ----------
        row : int
            The row.
        """
        self._record(self._ref, row)

    def advance(self, rows: int, row0: int = 0) -> None:
        """``rows`` whole steps, each :meth:`drift`, :meth:`forces` (``has_old``, ``kick``)
        and :meth:`record` into rows ``row0 ..``: one call for a block of steps of a run
        whose wall row does not change from Python (the step evaluates the wall's law,
        :meth:`use_law`). A block of 32 steps of a few scenes cost 3-4 us of call overhead
        per step as three calls.

        Parameters
        ----------
        rows : int
            Steps.
        row0 : int
            The first record row.
        """
        self._advance(self._ref, rows, row0)

    def drift(self) -> None:
        """The step's first half: ``v += dt/2 acc``, ``u += dt v`` (and their sensitivities)."""
        self._drift(self._ref)

    def forces(self, has_old: bool, kick: bool) -> None:
        """Contact forces, accelerations and sensitivities at the drifted state.

        Parameters
        ----------
        has_old : bool
            ``acc`` holds the last step's accelerations (the dashpot's predicted velocity).
        kick : bool
            Then the step's second half, ``v += dt/2 acc``.
        """
        self._forces(self._ref, int(has_old), int(kick))

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
