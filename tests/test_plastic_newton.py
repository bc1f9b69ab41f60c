"""The plastic contact solver's Newton algebra against independent truth: the assembled
Newton matrix (the elastic matrix plus the plastic elements' change) is the Jacobian of the
residual (a Taylor test: the remainder falls 4x per halving of the step), a factorization
in a kept elimination order solves as LAPACK's dense LU does, and the path at the residual
tolerance in use is the path at a tolerance a thousand times tighter to 1e-7 of its peak
force."""

from __future__ import annotations

import numpy as np
import pytest

from ssw.constitutive import VonMises
from ssw.constitutive.base import initial_state
from ssw.contact.plastic import RTOL, contact_mesh, johnson_first_yield, solve_path
from ssw.contact.plastic_model import _Model, _OrderedLU, _symmetric_order

E, NU, Y, R = 100e6, 0.3, 1e6, 4.75e-3


def _loaded(fine: float = 4.0) -> tuple[_Model, np.ndarray, object]:
    """A small mesh's model and a displacement that yields a zone under the axis: the
    sphere's gap closed on the candidates within a third of their reach, the rest smooth."""
    _, dy = johnson_first_yield(E, NU, Y, R)
    mesh = contact_mesh(R, 4 * dy, fine=fine, growth=0.4, domain=20.0)
    fe = _Model(mesh, E, NU, R, near=None)
    free = fe.free_dofs(np.zeros(fe.cand.size, bool))
    rhs = np.zeros(fe.ndof)
    rhs[fe.cand_dof] = -np.exp(-(fe.cand_r / (0.3 * fe.cand_r[-1])) ** 2)
    u = np.zeros(fe.ndof)
    u[free] = fe.solve(fe.elastic_matrix(), free, rhs[free])
    u *= 6 * dy / np.max(np.abs(u[fe.cand_dof]))
    return fe, u, free


def test_newton_matrix_is_the_residuals_jacobian():
    """At a displacement with yielded points, ``R(u + h v) - R(u) - h A v`` falls as
    ``h^2`` (the consistent tangent, assembled as the elastic matrix plus the change of
    the plastic elements), against ``h`` without the plastic change."""
    fe, u, free = _loaded()
    model = VonMises(Y)
    state = initial_state(fe.w.size)
    upd = fe.update(model, E, NU, u, state)
    assert 0 < np.count_nonzero(upd.plastic) < upd.plastic.size // 2
    res, _ = fe.residual_only(u, upd.stress)
    A = fe.matrix(upd.tangent, upd.plastic)
    v = np.zeros(fe.ndof)
    v[free] = np.random.default_rng(1).standard_normal(free.size) * np.max(np.abs(u))
    hs = 1e-6 * 0.5 ** np.arange(4)  # small enough that no point crosses the yield surface

    def remainder(data: np.ndarray) -> np.ndarray:
        out = []
        for h in hs:
            r_h, _ = fe.residual_only(u + h * v, fe.update(model, E, NU, u + h * v,
                                                           state).stress)
            out.append(np.max(np.abs((r_h - res - h * fe.matvec(data, v) * fe.scale)[free])))
        return np.array(out)

    rates = np.log2(remainder(A)[:-1] / remainder(A)[1:])
    assert np.all((rates > 1.8) & (rates < 2.2)), rates
    elastic_rates = np.log2(remainder(fe.elastic_matrix())[:-1]
                            / remainder(fe.elastic_matrix())[1:])
    assert np.all(elastic_rates < 1.2), elastic_rates


def test_factorization_in_a_kept_order_solves_as_dense_lu():
    """A plastic Newton matrix factored in the order of the elastic one's first
    factorization (same pattern) solves ``A x = b`` as numpy's dense LU, to 1e-10."""
    fe, u, free = _loaded()
    upd = fe.update(VonMises(Y), E, NU, u, initial_state(fe.w.size))
    first = fe.factor(fe.elastic_matrix(), free)
    order = _symmetric_order(first)
    assert order is not None
    data = fe.matrix(upd.tangent, upd.plastic)
    lu = _OrderedLU.factor(fe.restricted(data, free, order), order)
    assert lu is not None
    b = np.random.default_rng(2).standard_normal(free.size)
    dense = fe.restricted(data, free).T.toarray()  # A[free][:, free]
    x_ref = np.linalg.solve(dense, b)
    x = lu.solve(b, trans="T")
    assert np.max(np.abs(x - x_ref)) <= 1e-10 * np.max(np.abs(x_ref))
    # the model's own factor() takes the kept order for the second matrix of the free set
    x2 = fe.factor(data, free).solve(b, trans="T")
    assert isinstance(fe._pre[0], _OrderedLU)
    assert np.max(np.abs(x2 - x_ref)) <= 1e-10 * np.max(np.abs(x_ref))


def test_residual_tolerance_costs_nothing_in_the_curve():
    """Loading past first yield and unloading at the solver's residual tolerance
    (:data:`RTOL`) gives the curve of a tolerance a thousand times tighter to 1e-7 of the
    peak force, and its residual indentation to 1e-6."""
    _, dy = johnson_first_yield(E, NU, Y, R)
    mesh = contact_mesh(R, 4 * dy, fine=6.0, growth=0.3, domain=20.0)
    deltas = dy * np.linspace(0, 4, 41)[1:]
    used = solve_path(mesh, E, NU, VonMises(Y), R, deltas, unload=True)
    tight = solve_path(mesh, E, NU, VonMises(Y), R, deltas, unload=True, rtol=RTOL * 1e-3)
    assert used.force.size == tight.force.size
    assert np.max(np.abs(used.force - tight.force)) <= 1e-7 * np.max(tight.force)
    assert used.residual_indentation == pytest.approx(tight.residual_indentation, rel=1e-6)
    assert used.stats["newton_iterations"] < tight.stats["newton_iterations"]


def test_apex_stiffness_converges_to_the_same_path(monkeypatch):
    """Drucker-Prager clay (c 50 kPa, phi 25 deg, psi 0) under the device's 0.4 mm PLA plate,
    loaded to 1.12 mm in 12 increments and lifted (a path of the plastic wall's tables for
    ``ssw tof --hits 5 --soil-material compacted_clay --soil-model drucker-prager``): as the
    sphere lifts, the bilateral tie pulls the clay under the dent to the cone's tension
    apex, where the perfectly plastic return's tangent vanishes. With a zero tangent there
    the Newton iteration cycles between apex and cone (SolverError at 6e-6 of the load
    scale); with :data:`APEX_STIFFNESS <ssw.contact.plastic_model.APEX_STIFFNESS>` of the
    elastic tangent in the Newton matrix it converges. The Newton matrix changes only the
    iteration, not the equations: where both converge (the loading branch) the two curves
    agree to the residual tolerance."""
    import ssw.contact.plastic_model as pm
    from ssw.constitutive import DruckerPrager

    radius, d_m, clay = 9.525e-3, 1.122e-3, DruckerPrager(50e3, 25.0, 0.0)
    mesh = contact_mesh(radius, d_m, fine=8.0, growth=0.3, domain=40.0,
                        plate_thickness=4e-4, plate_radius=0.02475)
    deltas = d_m * np.arange(1, 13) / 12

    def path(unload: bool):
        return solve_path(mesh, 40e6, 0.35, clay, radius, deltas, unload=unload,
                          plate=(3.5e9, 0.36))

    c = path(True)
    assert 0 < c.residual_indentation < d_m and c.dissipated_work > 0
    regularized = path(False)
    monkeypatch.setattr(pm, "APEX_STIFFNESS", 0.0)
    exact = path(False)
    np.testing.assert_allclose(regularized.force, exact.force, rtol=0,
                               atol=1e-6 * float(np.max(exact.force)))
