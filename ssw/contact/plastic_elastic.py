"""The elastic parts of an elasto-plastic contact's path (:mod:`ssw.contact.plastic_path`):
while no point yields the discrete problem (:mod:`ssw.contact.plastic_model`) is linear
between the changes of the contact's active set, so its state is affine in the sphere's
indentation there.

* Elastic spans (``_elastic_span``): loading before first yield, unloading, elastic
  reloading; one solve with the elastic matrix to round-off per piece of constant active
  set gives every increment of the span, the trial stresses of every increment affine too.
* First yield (``_first_yield``): between the last elastic increment and the first at
  which a point yields, the indentation where the largest yield ratio of the elastic
  state's stresses reaches 1, by :func:`ssw.roots.find_root` (the state affine in the
  indentation while the contact's active set holds: the search costs one solve).

References
----------
Hintermueller, M., Ito, K. & Kunisch, K. (2003). The primal-dual active set strategy as a
semismooth Newton method. *SIAM J. Optim.* 13, 865-888.
Johnson, K. L. (1985). *Contact Mechanics*. Cambridge, sec. 6.1.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ssw.constitutive.base import Update, initial_state
from ssw.contact.plastic_model import EXACT_RTOL, _Model
from ssw.errors import SolverError

#: Changes of the contact's active set an elastic span follows, at most (one solve each;
#: ``_elastic_span``).
SPAN_EVENTS = 64
#: Relative tolerance of the first yield's indentation (``_first_yield``): the force
#: there is exact to 1.5 times it (``F ~ delta^1.5``), far below the mesh's error.
FIRST_YIELD_XRTOL = 1e-9


def _elastic_at(fe: _Model, d: float, active: np.ndarray, tol: float, max_iter: int
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The elastic contact state at the indentation ``d`` (m) of a body that has not
    yielded: the primal-dual active set (from ``active``) with the elastic matrix, each
    solve to round-off (:data:`ssw.contact.plastic_model.EXACT_RTOL`). Returns the dofs,
    the active set and the contact forces (N); the set's forces are above ``-tol`` (N),
    the other candidates' gaps open. Raises SolverError when the set does not settle."""
    data = fe.elastic_matrix()
    target = fe.g0 - d
    tol_g = 1e-9 * max(abs(d), fe.h_min * 1e-6)
    for _ in range(max_iter):
        free = fe.free_dofs(active)
        u = np.zeros(fe.ndof)
        u[fe.cand_dof[active]] = target[active]
        u[free] = fe.solve(data, free, -fe.matvec(data, u)[free], rtol=EXACT_RTOL)
        lam = -fe.matvec(data, u)[fe.cand_dof] * fe.scale
        # a node at the edge (force and gap both within their tolerances) stays as it is
        new = np.where(active, lam > -tol, target - u[fe.cand_dof] < -tol_g)
        if np.array_equal(new, active):
            return u, active, lam
        active = new
    raise SolverError(f"plastic contact: the elastic active set at delta = {d:.4g} m "
                      f"did not settle in {max_iter} iterations")


def _first_yield(fe: _Model, model: Any, E: float, nu: float, u0: np.ndarray,
                 active: np.ndarray, d0: float, d1: float, tol: float, max_iter: int
                 ) -> dict[str, Any]:
    """First yield between the converged elastic state ``u0`` at ``d0`` (m; its active set
    ``active``) and the increment ``d1`` (m) at which a point yields: the root of ``max
    yield ratio - 1`` of the elastic state by :func:`ssw.roots.find_root`, to
    :data:`FIRST_YIELD_XRTOL` (the largest ratio of the trial stresses over the points
    grows with the indentation). While ``active`` holds up to ``d1`` the elastic state is
    affine in the indentation (:func:`_unit_rate`: its stresses and contact forces too);
    else each trial indentation's state is solved (:func:`_elastic_at`). Returns ``force``
    (N) and ``delta`` (m) there, the yielding point's radius ``first_yield_r`` and depth
    below the loaded surface ``first_yield_depth`` (m), and the states evaluated."""
    from ssw.roots import find_root

    state = initial_state(fe.w.size)
    data = fe.elastic_matrix()
    v = _unit_rate(fe, active)
    lam0 = -fe.matvec(data, u0)[fe.cand_dof] * fe.scale
    dlam = -fe.matvec(data, v)[fe.cand_dof] * fe.scale
    gap1 = fe.g0 - d1 - (u0 + (d1 - d0) * v)[fe.cand_dof]
    tol_g = 1e-9 * max(abs(d1), fe.h_min * 1e-6)
    affine = bool(active.any()) and not np.any(active & (lam0 + (d1 - d0) * dlam <= -tol)) \
        and not np.any(~active & (gap1 < -tol_g))
    s0, s1 = fe.elastic_stress(E, nu, u0), fe.elastic_stress(E, nu, v)
    seen: dict[float, tuple] = {}

    def excess(x: float) -> float:
        if affine:
            stress = s0 + (x - d0) * s1
            force = float(np.sum((lam0 + (x - d0) * dlam)[active]))
        else:
            u, act, lam = _elastic_at(fe, x, active, tol, max_iter)
            stress, force = fe.elastic_stress(E, nu, u), float(lam[act].sum())
        ratios = np.minimum(fe.yield_ratios(model, stress, state), 1e300)  # finite
        seen[x] = (force, int(np.argmax(ratios)))
        return float(np.max(ratios)) - 1.0

    lo, hi = excess(d0), excess(d1)
    if lo >= 0.0 or hi <= 0.0:  # at an end (the return's own tolerance)
        x = d0 if lo >= 0.0 else d1
    else:
        x = float(find_root(lambda y: np.asarray(excess(float(y))), d0, d1,
                            xrtol=FIRST_YIELD_XRTOL).x)
        if x not in seen:
            excess(x)
    force, i = seen[x]
    return {"force": force, "delta": x, "first_yield_r": float(fe.rq.ravel()[i]),
            "first_yield_depth": float(fe.top - fe.zq.ravel()[i]),
            "first_yield_evaluations": len(seen), "first_yield_affine": affine}


def _unit_rate(fe: _Model, active: np.ndarray) -> np.ndarray:
    """The elastic response (dofs, m per m) to a unit indentation with the contact's
    ``active`` set held: the prescribed candidates move by -1, the free dofs solve the
    elastic equations to round-off (the kept LU of the free set, or GMRES preconditioned
    by the newest factorization, a free set a few contact dofs away; :data:`EXACT_RTOL
    <ssw.contact.plastic_model.EXACT_RTOL>`)."""
    free = fe.free_dofs(active)
    data = fe.elastic_matrix()
    v = np.zeros(fe.ndof)
    v[fe.cand_dof[active]] = -1.0
    if active.any():
        v[free] = fe.solve(data, free, -fe.matvec(data, v)[free], rtol=EXACT_RTOL)
    return v


def _elastic_span(fe: _Model, model: Any, E: float, nu: float, u: np.ndarray,
                  res: np.ndarray, state: np.ndarray, active: np.ndarray, path: list,
                  k: int, d0: float, tol: float) -> tuple[list[tuple], Update | None]:
    """The increments ``path[k:]`` reached elastically from the converged state ``(u,
    res)`` at ``d0`` (its active set ``active``).

    While no point yields the problem is linear between the changes of the active set: in
    each piece ``u(d) = u_p + (d - d_p) v`` with ``v`` the response to a unit indentation
    on the piece's set (:func:`_unit_rate`), ``res(d) = res_p + (d - d_p) K v`` (``K v``
    vanishes on the free dofs, so each increment keeps the converged residual), the gaps,
    contact forces and trial stresses affine in ``d``. A piece ends where a candidate's
    gap closes (to the Newton iteration's ``-tol_g``) or a contact force falls to the
    tolerance ``tol`` (N), the first to do so along the path: the set changes there (the
    node joins or leaves it) and the next piece starts, one solve each, at most
    :data:`SPAN_EVENTS`; the new set must hold beyond (the new node's force grows, the
    released node's gap opens), else the span stops. An increment joins the span while
    every point's yield ratio stays at most 1 (the return mapping then leaves it elastic);
    the span stops before the first that fails (it is solved by Newton's iteration), and
    before the contact is lost.

    Returns
    -------
    list of tuple
        Per increment of the span: ``(delta m, u, residual N, largest yield ratio, active
        set)``.
    Update or None
        The return mapping at the span's last increment (None: an empty span).
    """
    out: list[tuple] = []
    if not active.any():
        return out, None
    piece = _Piece(fe, E, nu, u, res, state, active, d0)
    events, j = 0, k
    while j < len(path):
        d = path[j]
        u_d, res_d = piece.at(d)
        lam = -res_d[fe.cand_dof]
        gap = fe.g0 - d - u_d[fe.cand_dof]
        tol_g = 1e-9 * max(abs(d), fe.h_min * 1e-6)
        off, on = piece.active & ~(lam > tol), ~piece.active & (gap < -tol_g)
        if off.any() or on.any():  # the set changes on the way to d
            if events >= SPAN_EVENTS:
                break
            nxt = piece.next_set(d, off, on, tol, tol_g)
            if nxt is None:
                break
            piece, events = nxt, events + 1
            continue
        ratio = float(np.max(fe.yield_ratios(model, piece.stress(d), state)))
        if not ratio <= 1.0:
            break
        out.append((d, u_d, res_d, ratio, piece.active))
        j += 1
    while out:  # the return mapping at the last increment (elastic, as its ratios say)
        upd = fe.update(model, E, nu, out[-1][1], state)
        if not upd.plastic.any():
            return out, upd
        out.pop()
    return out, None


class _Piece:
    """One piece of an elastic span (:func:`_elastic_span`): the state ``(u, res)`` at
    ``d0`` (m), its active set, the unit-indentation rates of the dofs, residual (N) and
    trial stresses (Pa) with that set held."""

    def __init__(self, fe: _Model, E: float, nu: float, u: np.ndarray, res: np.ndarray,
                 state: np.ndarray, active: np.ndarray, d0: float) -> None:
        self.fe, self.E, self.nu, self.state = fe, E, nu, state
        self.u, self.res, self.active, self.d0 = u, res, active, float(d0)
        fe.begin_increment()  # GMRES may serve again: the newest factorization is near
        self.v = _unit_rate(fe, active)
        self.dres = fe.matvec(fe.elastic_matrix(), self.v) * fe.scale
        self.dres[fe.free_dofs(active)] = 0.0
        self.s0 = fe.elastic_stress(E, nu, u, state)
        self.s1 = fe.elastic_stress(E, nu, self.v)

    def at(self, d: float) -> tuple[np.ndarray, np.ndarray]:
        """The dofs and the residual (N) at ``d`` (m)."""
        return self.u + (d - self.d0) * self.v, self.res + (d - self.d0) * self.dres

    def stress(self, d: float) -> np.ndarray:
        """The trial stresses (Pa) at ``d`` (m)."""
        return self.s0 + (d - self.d0) * self.s1

    def next_set(self, d: float, off: np.ndarray, on: np.ndarray, tol: float,
                 tol_g: float) -> _Piece | None:
        """The piece after the first change of the set on the way to ``d`` (m): of the
        nodes ``off`` (their force at ``d`` at most ``tol`` N) and ``on`` (their gap at
        ``d`` below ``-tol_g`` m), the one that crosses first; None when the new set does
        not hold beyond the crossing, or would leave no contact."""
        fe, c = self.fe, self.fe.cand_dof
        lam0, dlam = -self.res[c], -self.dres[c]
        gap0 = fe.g0 - self.d0 - self.u[c]
        dgap = -1.0 - self.v[c]
        with np.errstate(divide="ignore", invalid="ignore"):
            x = np.where(off, self.d0 + (tol - lam0) / dlam,
                         np.where(on, self.d0 + (-tol_g - gap0) / dgap, np.nan))
        lo, hi = min(self.d0, d), max(self.d0, d)
        x = np.where(np.isfinite(x), np.clip(x, lo, hi), np.nan)
        if np.all(np.isnan(x)):
            return None
        i = int(np.nanargmin(np.abs(x - self.d0)))
        active = self.active.copy()
        active[i] = bool(on[i])
        if not active.any():
            return None
        u_x, res_x = self.at(float(x[i]))
        nxt = _Piece(fe, self.E, self.nu, u_x, res_x, self.state, active, float(x[i]))
        ahead = np.sign(d - nxt.d0)
        grows = -nxt.dres[c[i]] * ahead > 0 if on[i] else (-1.0 - nxt.v[c[i]]) * ahead > 0
        return nxt if grows or ahead == 0 else None
