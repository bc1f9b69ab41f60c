"""The loading (and unloading) path of the elasto-plastic contact (:mod:`ssw.contact.plastic`):
increments of the sphere's indentation, each a semismooth Newton iteration with the contact's
active set inside it, on the discrete problem of :mod:`ssw.contact.plastic_model`.

Contact. The sphere's candidates are the top-surface nodes with ``r < R / 2``; at an
indentation ``delta`` the gap of a node is ``g = g0(r) - delta - u_z`` (``g0`` the exact
spherical gap). Each Newton iteration prescribes ``u_z = g0 - delta`` on the active set and
solves for the rest; at convergence the contact forces are the reactions ``lam = -f_int,z``;
the set gains the nodes with ``g < 0`` and loses those with ``lam < 0`` (a primal-dual active
set, Hintermueller, Ito & Kunisch 2003) until it is stable and the residual is below
``rtol`` times the load scale. An increment that does not converge in ``max_iter``
iterations is cut in two (at most ``max_cuts`` times), unless its best iterate stalled
within :data:`STALL_RTOL` of the load scale (accepted), then raises SolverError.

Path. Loading through ``delta`` then, with ``unload``, back in the same steps until the
sphere leaves the surface; the residual indentation is the axis's depth then (contact is
lost; the body stays as it is). Per increment: force, contact radius, the plastic zone
(volume, depth below the loaded surface, radius), the plastic work ``sum int sigma_{n+1} :
d eps_p dV`` (backward Euler) and Newton's iterations.

First yield (:mod:`ssw.contact.plastic_elastic`). Between the last elastic increment and the
first at which a point yields, the body is elastic up to first yield: the indentation where
the largest yield ratio of the elastic state's stresses reaches 1 is found by
:func:`ssw.roots.find_root` (the state is affine in the indentation while the contact's
active set holds, so the search costs one solve), and its force, indentation and point are
the path's first yield. (The extrapolation it replaces, ``F_y = F / ratio^3`` of the last
elastic increment, assumed Hertz's self-similar field: 0.07 % off on the study's plastic
mesh, but 9 % in the indentation through the device's plate, where the field is not
Hertz's.)

Two meshes (``elastic_mesh``). Below first yield the body is elastic and its state a
function of the indentation alone, not of the path: the loading increments before first
yield are solved on a mesh for the elastic contact (every contact radius from the first
increment's on resolved, refined where the plastic zone starts and at the contact's edge
then, :func:`ssw.contact.plastic_mesh.elastic_mesh_settings`), which also locates the first
yield; the path then goes on from the virgin state on the plastic mesh, from the first
plastic increment (a plastic mesh's own first yield is not located: the elastic mesh's
is the path's). When nothing yields the elastic mesh carries the whole path. The force
steps between the two by the difference of their elastic solutions there (the plastic
mesh's error at the contact radius of first yield: 0.07 % on the study's plastic scene,
docs/physics/plastic.md).

Cost (the curve is the one the increments' Newton iterations on the whole mesh give, to
round-off within the Newton tolerance; tests):

* the near zone (:func:`ssw.contact.plastic_mesh.near_radius`, doubled when the plastic
  zone or the contact reaches its edge): the far field beyond it condensed
  (:mod:`ssw.contact.plastic_model`);
* elastic spans: while no point yields and the active set holds, the path is affine in the
  indentation (loading before first yield, unloading, elastic reloading); one solve with
  the elastic matrix to round-off gives every increment of the span, and the trial
  stresses of every increment are affine too (:mod:`ssw.contact.plastic_elastic`);
* the Newton steps: inexact (the linear residual a tenth of the Newton test's tolerance,
  :data:`ssw.contact.plastic_model.KRYLOV_FORCING`; Eisenstat & Walker 1996), and each
  plastic increment starts from the last one's rate (a predictor).

References
----------
Eisenstat, S. C. & Walker, H. F. (1996). Choosing the forcing terms in an inexact Newton
method. *SIAM J. Sci. Comput.* 17, 16-32.
Hintermueller, M., Ito, K. & Kunisch, K. (2003). The primal-dual active set strategy as a
semismooth Newton method. *SIAM J. Optim.* 13, 865-888.
Simo, J. C. & Hughes, T. J. R. (1998). *Computational Inelasticity*. Springer.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Any, NamedTuple

import numpy as np

from ssw.constitutive.base import Update, initial_state
from ssw.constitutive.elastic import LinearElastic
from ssw.contact.contact_lcp import edge_radius
from ssw.contact.mesh import Mesh
from ssw.contact.plastic_elastic import _elastic_span, _first_yield
from ssw.contact.plastic_mesh import near_radius
from ssw.contact.plastic_model import KRYLOV_FORCING, _Model
from ssw.errors import ConfigError, SolverError

#: Newton iterations allowed per increment (active-set changes included).
MAX_ITER = 40
#: Iterations of an increment in which the active set follows every iterate; later it
#: changes only at equilibrium (no cycling).
SET_UPDATES = 8
#: A Newton step moving a node by more than this many indentation steps is taken as a
#: leap along a nearly singular tangent and replaced by an elastic-tangent step.
STEP_BOUND = 10.0
#: An increment whose Newton iteration stalls (cycling between the branches of a
#: non-smooth return, e.g. Drucker-Prager's apex and cone, with the set of points at the
#: apex changing by a few from one iterate to the next) is accepted after ``max_iter``
#: iterations when its residual is below this share of the load scale
#: (``stats['stalled']`` counts them; the force then carries an error of that order).
STALL_RTOL = 1e-6
#: Halvings of a Newton step that does not lower the residual.
LINE_SEARCH = 4
#: Halvings of an increment whose Newton iteration fails, before SolverError.
MAX_CUTS = 5
#: Residual tolerance relative to the load scale (the largest nodal internal force): the
#: study's curve moves by 4e-11 of its peak force from 1e-9 (docs/physics/plastic.md),
#: far below its discretization errors (1e-3).
RTOL = 1e-8


class ContactZoneError(SolverError):
    """The contact reached the candidates' edge (half the sphere's radius): the indentation
    lies beyond what the small-strain contact of a sphere models."""


class _NearZoneTooSmall(Exception):
    """The plastic zone, or the contact, reached the edge of the condensed near zone."""


@dataclass(frozen=True)
class PlasticCurve:
    """A loading (and unloading) path. SI units; arrays of shape (n,) per increment.

    ``branch`` 0 loading, 1 unloading; ``dissipated`` the cumulative plastic work (J);
    ``plastic_volume`` (m^3), ``plastic_depth`` and ``plastic_radius`` (m) the extent of the
    points that have yielded so far; ``iterations`` Newton's per increment.

    Parameters
    ----------
    delta : numpy.ndarray
        m, the indentation at each increment.
    force : numpy.ndarray
        N, the contact force.
    branch : numpy.ndarray
        0 loading, 1 unloading.
    contact_radius : numpy.ndarray
        m, the contact's radius.
    dissipated : numpy.ndarray
        J, the cumulative plastic work.
    plastic_volume : numpy.ndarray
        m^3, volume of the points that have yielded so far.
    plastic_depth : numpy.ndarray
        m, depth of the yielded zone.
    plastic_radius : numpy.ndarray
        m, radius of the yielded zone.
    iterations : numpy.ndarray
        Newton iterations per increment.
    yield_ratio : numpy.ndarray
        -, the largest yield ratio of the sample's (and plate's) points.
    first_yield_force : float or None
        N, the force at first yield (None: nothing yields).
    first_yield_delta : float or None
        m, the indentation at first yield.
    residual_indentation : float or None
        m, the permanent indentation on the axis after unloading (None: not unloaded).
    stored_energy : float
        J, the elastic energy stored at the end of the path.
    stats : dict
        Solver counts and timings (s).
    interface_residual : float or None
        m, the plate-sample interface's residual depth on the axis (the residual
        indentation less the plate's permanent thinning there; without a plate the
        residual indentation).
    """

    delta: np.ndarray
    force: np.ndarray
    branch: np.ndarray
    contact_radius: np.ndarray
    dissipated: np.ndarray
    plastic_volume: np.ndarray
    plastic_depth: np.ndarray
    plastic_radius: np.ndarray
    iterations: np.ndarray
    yield_ratio: np.ndarray
    first_yield_force: float | None
    first_yield_delta: float | None
    residual_indentation: float | None
    stored_energy: float
    stats: dict[str, Any] = field(default_factory=dict)
    # the plate-sample interface's residual depth on the axis (m; the residual indentation
    # less the plate's permanent thinning there; without a plate the residual indentation)
    interface_residual: float | None = None

    @property
    def dissipated_work(self) -> float:
        """Plastic work of the whole path, J."""
        return float(self.dissipated[-1]) if self.dissipated.size else 0.0

    @property
    def external_work(self) -> float:
        """``int F d delta`` over the path (trapezoids), J."""
        d = np.concatenate([[0.0], self.delta])
        f = np.concatenate([[0.0], self.force])
        return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(d)))


def solve_path(
    mesh: Mesh, E: float, nu: float, model: Any, radius: float, deltas: np.ndarray,
    unload: bool = False, *, rtol: float = RTOL, max_iter: int = MAX_ITER,
    punch: str | None = None, max_cuts: int = MAX_CUTS,
    plate: tuple[float, float] | None = None, interface: str = "frictionless",
    plate_model: Any = None, near: float | None = -1.0, elastic_mesh: Mesh | None = None,
) -> PlasticCurve:
    """Load a rigid sphere into a plastic sample and, with ``unload``, lift it back in the
    same steps until it leaves the surface (module docstring).

    Parameters
    ----------
    mesh : Mesh
        The sample (and plate) mesh, :func:`ssw.contact.mesh.build_mesh`.
    E : float
        The sample's Young's modulus, Pa.
    nu : float
        The sample's Poisson's ratio.
    model : model of :mod:`ssw.constitutive` or None
        The sample's constitutive law (None: linear elastic).
    radius : float
        The sphere's radius, m (``punch``: the punch's).
    deltas : array_like
        Increasing indentations > 0, m: the loading increments.
    unload : bool
        Lift the sphere back after loading, in the loading's step.
    rtol : float
        Residual tolerance relative to the load scale.
    max_iter : int
        Newton iterations per increment.
    punch : str or None
        ``smooth`` or ``rough``: a rigid flat punch of radius ``radius`` instead of the
        sphere (frictionless, or without slip under its face; the limit-load check of Eason
        & Shield 1960).
    max_cuts : int
        Halvings of an increment whose Newton iteration fails (``stats['cutbacks']`` counts
        them; the path then holds the intermediate indentations).
    plate : tuple of float or None
        A plate's ``(E Pa, nu)`` on a mesh with a plate.
    interface : str
        Plate-sample tie: ``frictionless`` | ``bonded`` (``_Model``).
    plate_model : model of :mod:`ssw.constitutive` or None
        The plate's constitutive law (None: elastic).
    near : float or None
        Radius (m) of the near zone about the contact point outside which the mesh is
        condensed (the elastic far field, ``_Model._condense``); -1 (default):
        ``near_radius`` of the path, doubled while the plastic zone or the contact
        reaches its edge; None: no condensation.
    elastic_mesh : Mesh or None
        A mesh for the path's elastic part (module docstring, "Two meshes"): the loading
        increments before first yield, and the whole path when nothing yields, are solved
        on it, the rest on ``mesh``; None: ``mesh`` throughout.

    Returns
    -------
    PlasticCurve
        Per increment and the path's scalars; ``stats`` the solver's counts (the plastic
        mesh's size, the counts of both meshes added, the elastic mesh's size as
        ``elastic_*``, ``elastic_increments`` the increments solved on it) and the first
        yielding point (``first_yield_r``, ``first_yield_depth`` below the loaded surface,
        m).

    Raises
    ------
    ConfigError
        On bad arguments.
    SolverError
        On an increment that does not converge; :class:`ContactZoneError` when the contact
        reaches the last candidate node (half the sphere's radius).
    """
    if model is None:
        model = LinearElastic()
    if not hasattr(model, "update"):
        raise ConfigError("soil_model", model, "a model of ssw.constitutive")
    if plate_model is not None and not hasattr(plate_model, "update"):
        raise ConfigError("plate_model", plate_model, "a model of ssw.constitutive")
    deltas = np.asarray(deltas, float)
    if deltas.ndim != 1 or deltas.size < 1 or np.any(np.diff(deltas) <= 0) or deltas[0] <= 0:
        raise ConfigError("deltas", deltas, "increasing indentations > 0 m")
    if punch not in (None, "smooth", "rough"):
        raise ConfigError("punch", punch, "smooth | rough (or none: the sphere)")
    setup = _Setup(float(E), float(nu), model, float(radius), punch, plate, interface,
                   plate_model, float(rtol), int(max_iter), int(max_cuts), float(deltas[0]),
                   int(deltas.size), bool(unload))
    t0 = time.perf_counter()
    if elastic_mesh is None:
        return _near_path(mesh, setup, deltas, near, False, t0)
    elastic = _near_path(elastic_mesh, setup, deltas, near, True, t0)
    if elastic.first_yield_delta is None:  # nothing yields: the elastic mesh's path
        elastic.stats["elastic_increments"] = int(elastic.delta.size)
        return elastic
    done = elastic.delta[-1] if elastic.delta.size else 0.0
    plastic = _near_path(mesh, setup, deltas[deltas > done * (1 + 1e-12)], near, False,
                         time.perf_counter(), locate=False)
    return _joined(elastic, plastic, t0)


@dataclass(frozen=True)
class _Setup:
    """The parameters of a path (:func:`solve_path`'s; SI): the sample's ``E``, ``nu`` and
    model, the sphere's (or punch's) radius, the plate's constants, tie and model, the
    Newton settings, the first loading step ``h0`` (m, the cutbacks' unit), the loading's
    increments (the unloading's step is the loading's mean) and whether to unload."""

    E: float
    nu: float
    model: Any
    radius: float
    punch: str | None
    plate: tuple[float, float] | None
    interface: str
    plate_model: Any
    rtol: float
    max_iter: int
    max_cuts: int
    h0: float
    unload_steps: int
    unload: bool


def _near_path(mesh: Mesh, setup: _Setup, deltas: np.ndarray, near: float | None,
               stop: bool, t0: float, locate: bool = True) -> PlasticCurve:
    """:func:`_path` on ``mesh`` with the near zone ``near`` (-1: :func:`near_radius`),
    doubled until it holds the plastic zone and the contact."""
    if near is not None and near < 0:
        near = near_radius(mesh, setup.E, setup.nu, setup.radius, float(deltas[-1]),
                           setup.punch, setup.plate)
    extent = float(np.max(np.hypot(mesh.nodes[:, 0], mesh.nodes[:, 1] - mesh.top)))
    restarts = 0
    while True:
        if near is not None and near >= extent:
            near = None
        try:
            curve = _path(mesh, setup, deltas, near, stop, t0, locate)
            curve.stats["near_restarts"] = restarts
            return curve
        except _NearZoneTooSmall:
            near, restarts = 2.0 * near, restarts + 1


def _joined(elastic: PlasticCurve, plastic: PlasticCurve, t0: float) -> PlasticCurve:
    """The path of two meshes: ``elastic``'s increments (before first yield, on the elastic
    mesh) then ``plastic``'s (from the virgin state, on the plastic mesh); the first yield
    is the elastic mesh's, the rest the plastic mesh's. ``stats`` are the plastic mesh's,
    the counts of both added, the elastic mesh's size as ``elastic_*``."""
    def cat(name: str) -> np.ndarray:
        return np.concatenate([getattr(elastic, name), getattr(plastic, name)])

    st = dict(plastic.stats)
    for key in ("increments", "newton_iterations", "elastic_spans", "spanned_increments",
                "factorizations", "lu_reused", "krylov_iterations", "cutbacks", "stalled",
                "near_restarts"):
        st[key] = elastic.stats.get(key, 0) + plastic.stats.get(key, 0)
    for key in ("nodes", "elements", "near_elements", "dofs", "near_radius",
                "near_restarts"):
        st[f"elastic_{key}"] = elastic.stats.get(key)
    for key in ("first_yield_r", "first_yield_depth", "first_yield_evaluations",
                "first_yield_affine"):
        st[key] = elastic.stats.get(key)
    st["elastic_increments"] = int(elastic.delta.size)
    st["wall_total"] = time.perf_counter() - t0
    return replace(plastic, **{name: cat(name) for name in (
        "delta", "force", "branch", "contact_radius", "dissipated", "plastic_volume",
        "plastic_depth", "plastic_radius", "iterations", "yield_ratio")},
        first_yield_force=elastic.first_yield_force,
        first_yield_delta=elastic.first_yield_delta, stats=st)


@dataclass
class _State:
    """The converged state of a path (the walker's, updated increment by increment): the
    dofs ``u``, the residual there ``res`` (N), the last return mapping ``upd``, the
    committed internal variables ``state``, the active set, the last converged tangent
    ``last = (tangent, plastic)``, the last increment's residual tolerance ``tol`` (N), the
    path's largest load scale ``load_ref`` (N) and the last plastic increment's rate
    ``trend`` (du / d delta)."""

    u: np.ndarray
    res: np.ndarray
    upd: Update
    state: np.ndarray
    active: np.ndarray
    last: tuple
    tol: float = 0.0
    load_ref: float = 0.0
    trend: np.ndarray | None = None


class _Step(NamedTuple):
    """One increment's Newton iteration: ``ok`` (converged or an accepted stall), its last
    iterate (``u``, ``upd``, ``res``, ``lam``, ``active``), iterations, the last residual
    ``err`` and load scale ``load`` (N), and whether it was an accepted stall."""

    ok: bool
    u: np.ndarray
    upd: Update
    res: np.ndarray
    lam: np.ndarray
    active: np.ndarray
    it: int
    err: float
    load: float
    stalled: bool


def _schedule(deltas: np.ndarray, setup: _Setup) -> tuple[list, list]:
    """The path's indentations (m) and branches: ``deltas``, then with ``setup.unload``
    back to 0 in the whole loading's mean step (its last indentation over its
    ``setup.unload_steps`` increments)."""
    path = list(deltas)
    branch = [0] * deltas.size
    if setup.unload:
        n = setup.unload_steps
        down = deltas[-1] - (deltas[-1] / n) * np.arange(1, n + 1)
        path += [*down[down > 0], 0.0]
        branch += [1] * int(np.count_nonzero(down > 0) + 1)
    return path, branch


def _path(mesh: Mesh, setup: _Setup, deltas: np.ndarray, near: float | None, stop: bool,
          t0: float, locate: bool = True) -> PlasticCurve:
    """The path of :func:`solve_path` on ``mesh`` with the near zone ``near`` (m; None: the
    whole mesh), ending before the first increment at which a point yields with ``stop``;
    first yield located between the increments (:func:`_first_yield`) with ``locate``.
    Raises ``_NearZoneTooSmall`` when the plastic zone reaches the near zone's edge
    elements, or the contact its last candidate short of half the sphere's radius."""
    E, nu, model = setup.E, setup.nu, setup.model
    mixed = all(getattr(m, "isochoric", False) for m in (model, setup.plate_model)
                if m is not None)
    fe = _Model(mesh, E, nu, setup.radius, setup.punch, mixed=mixed, plate=setup.plate,
                interface=setup.interface, plate_model=setup.plate_model, near=near)
    ne, nq = fe.w.shape
    state = initial_state(ne * nq)
    u = np.zeros(fe.ndof)
    s = _State(u, np.zeros(fe.ndof), fe.update(model, E, nu, u, state), state,
               np.zeros(fe.cand.size, bool), (None, np.zeros(ne * nq, bool)))
    path, branch = _schedule(deltas, setup)
    out: dict[str, list] = {k: [] for k in (
        "delta", "force", "a", "work", "vol", "depth", "rad", "it", "ratio")}
    first: dict[str, Any] = {}  # first yield (_first_yield)
    work = 0.0
    residual = interface_residual = None
    k, d_prev, cuts, spans, spanned, stalled = 0, 0.0, 0, 0, 0, 0
    ring = np.repeat(fe.ring, nq)
    while k < len(path):
        if k > 0 and not s.last[1].any():
            # elastic: the path is affine in delta while the active set holds and no point
            # yields; those increments need no Newton iteration (_elastic_span)
            n = _take_span(fe, setup, s, path, k, d_prev, out, work)
            if n:
                k, d_prev = k + n, path[k + n - 1]
                spans, spanned = spans + 1, spanned + n
            if k >= len(path):
                break
        d = path[k]
        step = abs(d - d_prev)
        u_start, active_start = s.u.copy(), s.active.copy()
        if s.trend is not None and branch[k] == branch[k - 1]:
            s.u = s.u + (d - d_prev) * s.trend  # the last plastic increment's rate
        r = _newton(fe, model, E, nu, s, d, step, setup.rtol, setup.max_iter)
        s.u, s.upd, s.res, s.active = r.u, r.upd, r.res, r.active
        if not r.ok:
            if step > setup.h0 * 0.5 ** setup.max_cuts * (1 + 1e-9):
                # cut the increment in two: back to the last converged state
                s.u, s.active, s.trend = u_start, active_start, None
                path.insert(k, 0.5 * (d_prev + d))
                branch.insert(k, branch[k])
                cuts += 1
                continue
            _not_converged(model, k, d, r, setup.max_iter, step)
        if not first and r.upd.plastic.any():
            first = _first_yield(fe, model, E, nu, u_start, active_start, d_prev, d, s.tol,
                                 setup.max_iter) \
                if locate else {"located": False}
            if stop:
                break
        stalled += int(r.stalled)
        work += _commit(fe, s, r.upd, u_start, d, d_prev)
        d_prev = d
        if np.any(s.state[ring, 4] > 0):
            raise _NearZoneTooSmall
        force = float(r.lam[s.active].sum())
        gap = np.clip(fe.g0 - d - s.u[fe.cand_dof], 0.0, None)
        _check_reach(fe, s.active, setup.punch)
        _record(out, fe, s.state, d, force, edge_radius(fe.cand_r, gap, s.active), work,
                r.it, fe.yield_ratio(model, s.upd.stress, s.state))
        if branch[k] == 1 and not s.active.any():
            residual = float(-s.u[fe.axis_dof])
            interface_residual = float(-s.u[fe.interface_axis_dof])
            branch = branch[: k + 1]
            break
        k += 1
    stored = fe.stored_energy(s.u, s.upd.stress)
    stats = {"nodes": fe.n, "elements": fe.n_elements, "near_elements": ne, "dofs": fe.ndof,
             "candidates": fe.cand.size, "near_radius": near,
             "increments": len(out["delta"]), "newton_iterations": int(np.sum(out["it"])),
             "elastic_spans": spans, "spanned_increments": spanned,
             "factorizations": fe.factorizations, "lu_reused": fe.lu_reused,
             "krylov_iterations": fe.krylov, "cutbacks": cuts, "stalled": stalled,
             **fe.far_stats,
             **{k: v for k, v in first.items() if k not in ("force", "delta", "located")},
             "wall_total": time.perf_counter() - t0}
    return PlasticCurve(
        np.array(out["delta"]), np.array(out["force"]),
        np.array(branch[:len(out["delta"])], np.int8), np.array(out["a"]),
        np.array(out["work"]), np.array(out["vol"]), np.array(out["depth"]),
        np.array(out["rad"]), np.array(out["it"]), np.array(out["ratio"]),
        first.get("force"), first.get("delta"), residual, stored, stats, interface_residual)


def _take_span(fe: _Model, setup: _Setup, s: _State, path: list, k: int, d0: float,
               out: dict[str, list], work: float) -> int:
    """Take the elastic span from ``path[k]`` on (:func:`_elastic_span`) into ``s`` and
    ``out`` (``work`` J, the path's so far); returns its number of increments."""
    span, upd = _elastic_span(fe, setup.model, setup.E, setup.nu, s.u, s.res, s.state,
                              s.active, path, k, d0, s.tol)
    for d, u_d, res_d, ratio, active in span:
        s.u, s.res, s.active = u_d, res_d, active
        force = float(-s.res[fe.cand_dof][s.active].sum())
        gap = np.clip(fe.g0 - d - s.u[fe.cand_dof], 0.0, None)
        _record(out, fe, s.state, d, force, edge_radius(fe.cand_r, gap, s.active), work, 0,
                ratio)
    if upd is not None:
        s.upd = upd
        s.last = (upd.tangent, upd.plastic)
    return len(span)


def _commit(fe: _Model, s: _State, upd: Update, u_start: np.ndarray, d: float,
            d_prev: float) -> float:
    """Commit a converged increment to ``s`` (its rate for the next predictor when it was
    plastic, its tangent, its internal variables); returns its plastic work, J
    (backward Euler: ``sum int sigma_{n+1} : d eps_p dV``)."""
    s.trend = (s.u - u_start) / (d - d_prev) if upd.plastic.any() else None
    s.last = (upd.tangent, upd.plastic)
    dep = upd.state[:, :4] - s.state[:, :4]
    s.state = upd.state
    return float(np.sum(np.einsum("gi,gi->g", upd.stress, dep) * fe.w.ravel()))


def _not_converged(model: Any, k: int, d: float, r: _Step, max_iter: int, step: float
                   ) -> None:
    """Raise SolverError for the increment ``k`` to ``d`` (m) whose Newton iteration did
    not converge at the smallest step allowed."""
    hint = ("; a perfectly plastic model with corners (tresca) may stall there: "
            "a small hardening (e.g. E/100) restores Newton's convergence"
            if getattr(model, "hardening", None) == 0.0 else "")
    raise SolverError(
        f"plastic contact: increment {k} (delta = {d:.6g} m) did not converge in "
        f"{max_iter} Newton iterations (residual {r.err:.3g} N, load scale "
        f"{r.load:.3g} N), its step cut to {step:.3g} m{hint}")


def _check_reach(fe: _Model, active: np.ndarray, punch: str | None) -> None:
    """Raise when the contact holds the last candidate: ``_NearZoneTooSmall`` when the
    candidates stop at the near zone's edge, :class:`ContactZoneError` at half the
    sphere's radius."""
    if active.size and active[-1]:
        if fe.cand_short:
            raise _NearZoneTooSmall
        if punch is None:
            raise ContactZoneError(
                f"the contact zone reached the last candidate node (r = "
                f"{fe.cand_r[-1]:.4g} m, half the sphere's radius): an indentation "
                f"beyond the small-strain contact's reach")


def _newton(fe: _Model, model: Any, E: float, nu: float, s: _State, d: float, step: float,
            rtol: float, max_iter: int) -> _Step:
    """The Newton iteration of the increment to ``d`` (m) from ``s.u`` (the predictor
    applied), with the active set inside it (module docstring). Updates ``s.tol`` and
    ``s.load_ref``; returns the last iterate (on a stall within :data:`STALL_RTOL`, its
    best), ``ok`` False when it did not converge. Raises SolverError on a singular
    Newton matrix."""
    u, active = s.u, s.active
    target = fe.g0 - d
    tol_g = 1e-9 * max(abs(d), fe.h_min * 1e-6)
    fe.begin_increment()
    prev, was_elastic = np.inf, False
    ahead = None  # the update and residual at u, when the line search computed them
    best: tuple | None = None  # the equilibrium iterate of least residual (a stall)
    for it in range(max_iter):
        upd, known = ahead if ahead is not None else (fe.update(model, E, nu, u, s.state),
                                                      None)
        ahead = None
        # the first iteration of an increment takes the last converged tangent (at the
        # committed state the return cannot tell loading from unloading)
        tangent, plastic = (s.last if it == 0 else (upd.tangent, upd.plastic))
        res, load = known if known is not None else fe.residual_only(u, upd.stress)
        lam = -res[fe.cand_dof]
        s.load_ref = max(s.load_ref, load)
        tol = s.tol = rtol * max(load, 1e-6 * s.load_ref)
        gap = target - u[fe.cand_dof]
        new_active = np.where(active, lam > tol, gap < -tol_g)
        if 0 < it < SET_UPDATES and not np.array_equal(new_active, active):
            # semismooth Newton: the set follows the iterate (Hintermueller et al. 2003)
            active = new_active
        free = fe.free_dofs(active)
        jump = np.zeros(fe.ndof)
        jump[fe.cand_dof[active]] = target[active] - u[fe.cand_dof[active]]
        err = float(np.max(np.abs(res[free]), initial=0.0))
        if it > 0 and (best is None or err < best[0]) and not np.any(jump) \
                and np.array_equal(new_active, active):
            best = (err, u.copy(), upd, res, lam, load)
        if it > 0 and err <= tol and not np.any(jump):
            if np.array_equal(new_active, active):
                return _Step(True, u, upd, res, lam, active, it, err, load, False)
            active, prev = new_active, np.inf
            continue
        elastic = err > prev and not was_elastic  # one elastic step, then Newton again
        prev = err
        du, elastic = _newton_step(fe, d, step, res, jump, free, tol, tangent, plastic,
                                   elastic)
        if not np.any(jump) and not elastic:
            du, ahead = _line_search(fe, model, E, nu, s.state, u, free, du, err, res)
        was_elastic = elastic
        u = u.copy() if u is s.u else u
        u[free] += du
        u += jump
    if best is not None and best[0] <= STALL_RTOL * best[5]:  # a stall: accepted
        b_err, b_u, b_upd, b_res, b_lam, b_load = best
        return _Step(True, b_u, b_upd, b_res, b_lam, active, max_iter - 1, b_err, b_load,
                     True)
    return _Step(False, u, upd, res, lam, active, max_iter - 1, err, load, False)


def _newton_step(fe: _Model, d: float, step: float, res: np.ndarray, jump: np.ndarray,
                 free: np.ndarray, tol: float, tangent: Any, plastic: np.ndarray,
                 elastic: bool) -> tuple[np.ndarray, bool]:
    """A Newton step's ``du`` on ``free`` (m) with the consistent tangent, or the elastic
    one (``elastic``, or when the consistent step is singular or leaps beyond
    :data:`STEP_BOUND` indentation steps), and whether the elastic tangent was taken."""
    # the Newton matrix, assembled only now that a step is needed
    data = fe.elastic_matrix() if elastic else fe.matrix(tangent, plastic)
    for _ in range(2):
        if elastic:
            # Newton stalls or leaps (a nearly singular perfectly plastic tangent):
            # a step with the elastic tangent, a contraction for the return mapping
            data = fe.elastic_matrix()
        rhs = -res / fe.scale
        if np.any(jump):
            rhs -= fe.matvec(data, jump)
        try:
            # an inexact Newton step: its linear residual a tenth of the tolerance
            du = fe.solve(data, free, rhs[free], KRYLOV_FORCING * tol / fe.scale)
        except RuntimeError:  # a singular consistent tangent (e.g. a region at
            if elastic:       # the apex): the elastic tangent's step instead
                raise SolverError(f"plastic contact: singular Newton matrix at "
                                  f"delta = {d:.4g} m") from None
            elastic = True
            continue
        if elastic or (np.all(np.isfinite(du))
                       and np.max(np.abs(du), initial=0.0) <= STEP_BOUND * step):
            break
        elastic = True
    if not np.all(np.isfinite(du)):
        raise SolverError(f"plastic contact: singular Newton matrix at delta = {d:.4g} m")
    return du, elastic


def _line_search(fe: _Model, model: Any, E: float, nu: float, state: np.ndarray,
                 u: np.ndarray, free: np.ndarray, du: np.ndarray, err: float,
                 res: np.ndarray) -> tuple[np.ndarray, tuple | None]:
    """Backtracking on the residual: a step that does not lower it is halved, and after
    :data:`LINE_SEARCH` halvings replaced by an elastic-tangent step. Returns the step and
    the update and residual it reaches (None for the elastic step)."""
    for _ in range(LINE_SEARCH):
        trial_u = u.copy()
        trial_u[free] += du
        t_upd = fe.update(model, E, nu, trial_u, state)
        r_t = fe.residual_only(trial_u, t_upd.stress)
        if np.max(np.abs(r_t[0][free]), initial=0.0) < err:
            return du, (t_upd, r_t)
        du = 0.5 * du
    return fe.solve(fe.elastic_matrix(), free, -res[free] / fe.scale), None


def _record(out: dict[str, list], fe: _Model, state: np.ndarray, d: float, force: float,
            a: float, work: float, it: int, ratio: float) -> None:
    """Append one increment's outputs to ``out``."""
    yielded = state[:, 4] > 0
    out["delta"].append(d)
    out["force"].append(force)
    out["a"].append(a)
    out["work"].append(work)
    out["vol"].append(float(np.sum(fe.w.ravel()[yielded])))
    out["depth"].append(float(fe.top - np.min(fe.zq.ravel()[yielded], initial=fe.top)))
    out["rad"].append(float(np.max(fe.rq.ravel()[yielded], initial=0.0)))
    out["it"].append(it)
    out["ratio"].append(ratio)
