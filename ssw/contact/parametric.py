"""The contact LCP as a function of the indentation: its exact, piecewise-affine solution path.

The condensed contact problem of a rigid sphere pushed by ``delta`` (m) is, for every
``delta``, the linear complementarity problem (Cottle, Pang & Stone 1992)

    lam >= 0,   g = q0 + delta q1 + W lam >= 0,   lam . g = 0,

with ``W`` the symmetric positive definite compliance of the candidate constraints (m/N),
``q0`` their gaps at ``delta = 0`` and ``q1`` the gaps' rate (-1 for a sphere candidate, 0
for a plate-soil pair of the unilateral interface). With the active set ``A`` fixed the
solution is affine in ``delta``:

    lam_A = alpha + delta beta,   W_AA alpha = -q0_A,   W_AA beta = -q1_A,
    g_N   = gamma + delta eta,    gamma = q0_N + W_NA alpha,   eta = q1_N + W_NA beta.

So the path is followed from breakpoint to breakpoint (Murty 1988, ch. 5, the parametric
LCP): the piece ends where the first active force reaches zero (``beta_j < 0``) or the first
inactive gap closes (``eta_j < 0``). At a breakpoint ``delta*`` the constraints that reach
their bound there, ``H``, are sorted by the directional problem: with ``F = A \\ H`` kept
active (``dg_F = 0``), ``dlam_H`` solves the small LCP

    dlam_H >= 0,  dg_H = (q1_H - W_HF W_FF^-1 q1_F) + (W_HH - W_HF W_FF^-1 W_FH) dlam_H >= 0,
    dlam_H . dg_H = 0,

whose matrix (a Schur complement of ``W``) is positive definite: the new active set is
``F`` plus the ``H`` with ``dlam > 0``. When ``H`` is one constraint ``h`` reached along a
piece (the usual breakpoint) that problem is ``1 x 1`` with ``M > 0`` and ``q`` of the sign
of the rate that ended the piece: ``q = eta_h < 0`` for a closing gap, ``q = -M beta_h > 0``
for a vanishing force (block elimination of ``W_AA beta = -q1_A``), so ``h`` switches, with
no solve. The directional problem also settles degenerate starts: at ``delta = 0`` every
constraint with ``q0 = 0`` (the sphere's axis node; every pair of an unilateral interface,
all touching) is in ``H``. Every increment between breakpoints is then filled in one
vectorized step, and the curve is exact (to round-off) at any indentation: the
per-increment LCP (:mod:`ssw.contact.contact_lcp`) gives the same numbers.

Cholesky factors of ``W_AA`` are reused between pieces: ``A`` is kept sorted, and when it
changes only the part of the factor from the first changed position on is recomputed
(most changes happen at the edge of the contact zone, the end of the sphere block).

Fast path (:func:`prefix_path`). When the only constraints are the sphere's, sorted by
radius, the contact zone of a monotone indentation usually grows as a disk: the active sets
are the prefixes ``{0..k-1}``. All of them come from one factorization: with
``W = L L^T`` and ``Z = L^-1``, the leading block ``W_kk`` has the factor ``L_kk``, so
``W_kk^-1 b_k = Z_kk^T (Z b)_k``, the ``k``-th row of the cumulative sum over ``j`` of
``Z[j, :] (Z b)[j]``: every piece of the path in ``O(m^3)`` vectorized work. The result is
checked (every force >= 0 and every gap >= 0 at both ends of every piece, where the affine
values take their extremes); a path that is not a sequence of prefixes (a plate lifting
off the axis) is traced by :class:`Tracer` instead.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import cholesky, solve_triangular

from ssw.contact.contact_lcp import solve_lcp
from ssw.contact.lapack import cholesky as lapack_cholesky
from ssw.contact.lapack import triangular_solve
from ssw.errors import SolverError

#: Breakpoints closer than this (relative to the indentation) are simultaneous.
TIE_RTOL = 1e-9
#: Most pieces a path may have (a safeguard against cycling; a curve has ~1-3 per candidate).
MAX_PIECES = 100_000
#: No constraint pending at a breakpoint.
_NONE = np.zeros(0, dtype=np.int64)


@dataclass(frozen=True)
class Path:
    """The solution path on ``[0, delta_end]``: ``k`` pieces, ``m`` constraints. SI units.

    ``breaks`` (k + 1,) m: piece ``j`` covers ``[breaks[j], breaks[j + 1]]``;
    ``lam0, lam1`` (k, m) N and N/m: ``lam = lam0 + delta lam1`` (0 off the active set);
    ``gap0, gap1`` (k, m) m and -: ``g = gap0 + delta gap1`` (0 on the active set);
    ``active`` (k, m) bool.

    Parameters
    ----------
    breaks : numpy.ndarray
        Piece breakpoints (m), (k + 1,).
    lam0 : numpy.ndarray
        Force intercepts (N), (k, m).
    lam1 : numpy.ndarray
        Force slopes (N/m), (k, m).
    gap0 : numpy.ndarray
        Gap intercepts (m), (k, m).
    gap1 : numpy.ndarray
        Gap slopes, (k, m).
    active : numpy.ndarray
        Active sets, (k, m) bool.
    """

    breaks: np.ndarray
    lam0: np.ndarray
    lam1: np.ndarray
    gap0: np.ndarray
    gap1: np.ndarray
    active: np.ndarray

    @property
    def pieces(self) -> int:
        """Number of affine pieces."""
        return self.lam0.shape[0]

    def piece_of(self, delta: np.ndarray) -> np.ndarray:
        """Index of the piece holding each ``delta`` (m); a breakpoint belongs to the piece
        that starts there.

        Parameters
        ----------
        delta : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Piece indices, (n,).
        """
        j = np.searchsorted(self.breaks, np.asarray(delta, float), side="right") - 1
        return np.clip(j, 0, self.pieces - 1)

    def forces(self, delta: np.ndarray) -> np.ndarray:
        """(n, m) constraint forces ``lam`` (N) at the indentations ``delta`` (n,).

        Parameters
        ----------
        delta : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Constraint forces (N), (n, m).
        """
        d = np.asarray(delta, float)
        j = self.piece_of(d)
        return self.lam0[j] + d[:, None] * self.lam1[j]

    def gaps(self, delta: np.ndarray) -> np.ndarray:
        """(n, m) gaps ``g`` (m) at the indentations ``delta`` (n,).

        Parameters
        ----------
        delta : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Gaps (m), (n, m).
        """
        d = np.asarray(delta, float)
        j = self.piece_of(d)
        return self.gap0[j] + d[:, None] * self.gap1[j]


def prefix_path(W: np.ndarray, q0: np.ndarray, q1: np.ndarray,
                delta_end: float = np.inf) -> Path | None:
    """The path if its active sets are the prefixes of the constraints' order (module
    docstring), else None. ``delta_end`` (m, may be inf): the path ends there or where the
    last constraint enters the contact, whichever comes first.

    Parameters
    ----------
    W : numpy.ndarray
        Constraint compliance matrix (m/N), (m, m), symmetric positive definite.
    q0 : numpy.ndarray
        Gaps at zero indentation (m), (m,).
    q1 : numpy.ndarray
        Gap change per unit indentation, (m,).
    delta_end : float
        Last indentation (m), may be inf.

    Returns
    -------
    Path or None
        The piecewise-linear path, or None.
    """
    W, q0, q1 = np.asarray(W, float), np.asarray(q0, float), np.asarray(q1, float)
    m = q0.size
    if m == 0 or q0[0] != 0.0 or np.any(q1 >= 0) or np.any(np.diff(q0) < 0):
        return None
    try:
        L = cholesky(W, lower=True, check_finite=False)
    except np.linalg.LinAlgError:
        return None
    Z = solve_triangular(L, np.eye(m), lower=True, check_finite=False)
    y = Z @ np.column_stack([-q0, -q1])
    lam0 = np.cumsum(Z * y[:, 0:1], axis=0)  # row k-1: W_kk^-1 (-q0_k), zeros beyond
    lam1 = np.cumsum(Z * y[:, 1:2], axis=0)
    gap0 = q0 + lam0 @ W
    gap1 = q1 + lam1 @ W
    active = np.tri(m, m, dtype=bool)
    gap0[active], gap1[active] = 0.0, 0.0
    # piece k - 1 (prefix k) ends where constraint k closes its gap
    k = np.arange(m - 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        ends = np.where(gap1[k, k + 1] < 0, -gap0[k, k + 1] / gap1[k, k + 1], np.inf)
    breaks = np.concatenate([[0.0], ends, [np.inf]])
    if np.any(~(np.diff(breaks[:-1]) > 0)):
        return None
    n = int(np.searchsorted(breaks, delta_end, side="left"))  # pieces up to delta_end
    n = max(1, min(n, m))
    br = breaks[: n + 1].copy()
    if np.isfinite(delta_end):
        br[n] = delta_end
    elif not np.isfinite(br[n]):
        br[n] = br[n - 1] if n > 1 else 0.0
        n -= 1
        br = br[: n + 1]
        if n < 1:
            return None
    p = Path(br, lam0[:n], lam1[:n], gap0[:n], gap1[:n], active[:n])
    # the check: complementarity holds on every piece (affine: at its two ends)
    ends2 = np.stack([br[:-1], br[1:]])  # (2, n)
    lam = p.lam0[None] + ends2[..., None] * p.lam1[None]
    gap = p.gap0[None] + ends2[..., None] * p.gap1[None]
    scale_l = max(float(np.max(np.abs(lam))), 1e-300)
    scale_g = max(float(br[-1]), 1e-300)
    if np.any(lam < -TIE_RTOL * scale_l) or np.any(gap < -TIE_RTOL * scale_g):
        return None
    return p


def trace(W: np.ndarray, q0: np.ndarray, q1: np.ndarray, delta_end: float
          ) -> tuple[Path, dict[str, int]]:
    """The path on ``[0, delta_end]``: :func:`prefix_path` when it holds, else
    :class:`Tracer`. Also returns ``{"pieces", "prefix"}`` (1 if the fast path served).

    Parameters
    ----------
    W : numpy.ndarray
        Constraint compliance matrix (m/N), (m, m), symmetric positive definite.
    q0 : numpy.ndarray
        Gaps at zero indentation (m), (m,).
    q1 : numpy.ndarray
        Gap change per unit indentation, (m,).
    delta_end : float
        Last indentation (m).

    Returns
    -------
    path : Path
        The piecewise-linear path.
    stats : dict
        ``pieces`` and ``prefix``.
    """
    p = prefix_path(W, q0, q1, delta_end)
    if p is not None and p.breaks[-1] >= delta_end:
        return p, {"pieces": p.pieces, "prefix": 1}
    tracer = Tracer(W, q0, q1)
    tracer.advance(delta_end)
    p = tracer.path()
    return p, {"pieces": p.pieces, "prefix": 0}


class Tracer:
    """Follows the solution path of ``LCP(W, q0 + delta q1)`` from ``delta = 0`` (resumable:
    :meth:`advance` extends it).

    A breakpoint reached by one constraint switches it (module docstring); the start and
    simultaneous breakpoints solve their directional problem
    (:func:`ssw.contact.contact_lcp.solve_lcp`).

    Parameters
    ----------
    W : numpy.ndarray
        (m, m) symmetric positive definite, m/N.
    q0 : numpy.ndarray
        (m,) gaps at ``delta = 0``, m, >= 0.
    q1 : numpy.ndarray
        (m,) d(gap)/d(delta), -.
    """

    def __init__(self, W: np.ndarray, q0: np.ndarray, q1: np.ndarray) -> None:
        self.W = np.asarray(W, float)
        self.q0 = np.asarray(q0, float)
        self.q1 = np.asarray(q1, float)
        m = self.q0.size
        if self.W.shape != (m, m) or self.q1.shape != (m,):
            raise SolverError(
                f"LCP data of inconsistent shapes {self.W.shape}, {m}, {self.q1.shape}")
        if np.any(self.q0 < 0):
            raise SolverError("the gaps at zero indentation must be >= 0 (no initial penetration)")
        self._minus_q = -np.column_stack([self.q0, self.q1])  # (m, 2) right-hand sides
        self.delta = 0.0
        self.active = np.zeros(m, dtype=bool)  # the active set of the current piece
        self._idx = np.zeros(0, dtype=np.int64)  # sorted active indices of the factor
        self._L = np.zeros((0, 0))  # lower Cholesky factor of W[idx, idx]
        self.breaks: list[float] = [0.0]
        self.rows: list[tuple[np.ndarray, ...]] = []
        self.cholesky_rows = 0  # rows of factors recomputed (work measure)
        #: start: every constraint touching at delta = 0 is a candidate to become active
        self._pending = np.flatnonzero(self.q0 == 0.0)
        self._piece: tuple[np.ndarray, ...] | None = None
        self._open = False  # the last row is a piece cut at the requested end

    # -- factor of W_AA, updated from the first changed position ------------------------
    def _factor(self, idx: np.ndarray) -> np.ndarray:
        """Lower Cholesky factor of ``W[idx, idx]``, reusing the leading block shared with
        the previous factor.

        Parameters
        ----------
        idx : numpy.ndarray
            (n,) sorted constraint indices, int.

        Returns
        -------
        numpy.ndarray
            (n, n) the lower factor (also kept for the next call).

        Raises
        ------
        SolverError
            ``W[idx, idx]`` is not positive definite.
        """
        old = self._idx
        n = idx.size
        p = min(old.size, n)
        changed = (old[:p] != idx[:p]).nonzero()[0]
        if changed.size:
            p = int(changed[0])
        elif p == n == old.size:
            return self._L
        L = np.zeros((n, n))
        L[:p, :p] = self._L[:p, :p]
        if n > p:
            W = self.W
            tail = idx[p:]
            if p:
                L21 = triangular_solve(L[:p, :p], W[idx[:p, None], tail], lower=True).T
                L[p:, :p] = L21
                S = W[tail[:, None], tail] - L21 @ L21.T
            else:
                S = W[tail[:, None], tail]
            try:
                L[p:, p:] = lapack_cholesky(S, lower=True)
            except np.linalg.LinAlgError as exc:
                raise SolverError(
                    f"contact compliance not positive definite on the active set: {exc}"
                ) from exc
            self.cholesky_rows += n - p
        self._idx, self._L = idx, L
        return L

    def _solve(self, L: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        """``x`` with ``L L^T x = rhs``.

        Parameters
        ----------
        L : numpy.ndarray
            (n, n) lower Cholesky factor.
        rhs : numpy.ndarray
            (n,) or (n, k) right-hand sides.

        Returns
        -------
        numpy.ndarray
            The solution, the shape of ``rhs``.
        """
        return triangular_solve(L.T, triangular_solve(L, rhs, lower=True), lower=False)

    # -- the active set after a breakpoint ------------------------------------------------
    def _resolve(self, hits: np.ndarray) -> None:
        """New active set when the constraints ``hits`` reach a bound at ``self.delta``.

        Parameters
        ----------
        hits : numpy.ndarray
            (h,) indices of the constraints at a bound, int.
        """
        act = self.active.copy()
        act[hits] = False
        F = np.flatnonzero(act)
        q1, W = self.q1, self.W
        if F.size:
            L = self._factor(F)
            Z = self._solve(L, np.column_stack([W[F[:, None], hits], q1[F]]))
            M = W[hits[:, None], hits] - W[hits[:, None], F] @ Z[:, :-1]
            q = q1[hits] - W[hits[:, None], F] @ Z[:, -1]
        else:
            M, q = W[hits[:, None], hits], q1[hits].copy()
        M = 0.5 * (M + M.T)
        scale = max(float(np.max(np.abs(q))), 1e-300)
        dlam, on, _ = solve_lcp(M, q, q < 0, 1e-13 * scale)
        act[hits[on & (dlam > 0)]] = True
        self.active = act

    def _affine(self) -> tuple[np.ndarray, ...]:
        """The current active set's piece.

        Returns
        -------
        tuple of numpy.ndarray
            (lam0, lam1, gap0, gap1), each (m,), N, N/m, m and -.
        """
        A = self.active.nonzero()[0]
        m = self.q0.size
        lam0, lam1 = np.zeros(m), np.zeros(m)
        if A.size:
            ab = self._solve(self._factor(A), self._minus_q[A])
            a, b = ab[:, 0], ab[:, 1]
            lam0[A], lam1[A] = a, b
            WA = self.W[:, A]
            gap0 = self.q0 + WA @ a
            gap1 = self.q1 + WA @ b
            gap0[A], gap1[A] = 0.0, 0.0
        else:
            gap0, gap1 = self.q0.copy(), self.q1.copy()
        return lam0, lam1, gap0, gap1

    def _next_break(self, piece: tuple[np.ndarray, ...]) -> tuple[float, np.ndarray]:
        """The end of the current piece and the constraints that reach a bound there.

        A force (on the active set) or a gap (off it) with a negative rate reaches zero at
        ``-value / rate``; the values and rates are the sums ``lam + gap`` (each zero where
        the other is not).

        Parameters
        ----------
        piece : tuple of numpy.ndarray
            (lam0, lam1, gap0, gap1) of the current piece (:meth:`_affine`).

        Returns
        -------
        nxt : float
            The end (m), inf if none.
        hits : numpy.ndarray
            (h,) indices of the constraints reaching a bound there, int.
        """
        lam0, lam1, gap0, gap1 = piece
        fall = -(lam1 + gap1)  # the rates of fall
        cross = np.full(fall.size, np.inf)
        np.divide(lam0 + gap0, fall, out=cross, where=fall > 0)
        # the ones at or behind the current point change sign there only by round-off
        cross[~(cross > self.delta * (1.0 + TIE_RTOL))] = np.inf
        nxt = float(cross.min(initial=np.inf))
        if nxt == np.inf:
            return np.inf, np.zeros(0, dtype=np.int64)
        return nxt, (cross <= nxt * (1.0 + TIE_RTOL)).nonzero()[0]

    def advance(self, delta_end: float) -> None:
        """Extend the path to ``delta_end`` (nothing if it already reaches it).

        Parameters
        ----------
        delta_end : float
            The indentation to reach, m.

        Raises
        ------
        SolverError
            More than :data:`MAX_PIECES` pieces, or an active block not positive definite.
        """
        delta_end = float(delta_end)
        if self.breaks[-1] >= delta_end:
            return
        if self._open:  # the last piece was cut at the previous end: continue it
            self.rows.pop()
            self.breaks.pop()
            self._open = False
        rows, breaks = self.rows, self.breaks
        while True:
            pending = self._pending
            if pending.size == 1 and self._piece is not None:  # one constraint switches
                self.active[pending[0]] = not self.active[pending[0]]
                self._piece = self._affine()
            elif pending.size:
                self._resolve(pending)
                self._piece = self._affine()
            elif self._piece is None:
                self._piece = self._affine()
            self._pending = _NONE
            nxt, hits = self._next_break(self._piece)
            rows.append((*self._piece, self.active.copy()))
            if len(rows) > MAX_PIECES:
                raise SolverError(f"the contact path has more than {MAX_PIECES} pieces")
            if nxt < delta_end:
                breaks.append(nxt)
                self.delta = nxt
                self._pending = hits
            else:
                breaks.append(delta_end)
                self._open = True
                return

    def path(self) -> Path:
        """The path traced so far.

        Returns
        -------
        Path
            Its pieces from ``delta = 0`` to the last requested end.
        """
        lam0, lam1, gap0, gap1, active = (np.array(x) for x in zip(*self.rows, strict=True))
        return Path(np.array(self.breaks), lam0, lam1, gap0, gap1, active)
