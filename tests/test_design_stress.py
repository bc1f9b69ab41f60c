"""Stresses of a contact state (ssw.contact.stress) against Hertz's closed-form field.

Independent truth: the stress field of a sphere on an elastic half-space (Hertz 1882; on the
axis, Johnson 1985, eqs. 3.45: sigma_z = -p0 / (1 + z^2/a^2), sigma_r = -p0 [(1 + nu)
(1 - (z/a) atan(a/z)) - 1 / (2 (1 + z^2/a^2))]), whose von Mises stress |sigma_r - sigma_z|
peaks below the surface: 0.62 p0 at z = 0.48 a for nu = 0.3 (Johnson 1985, sec. 6.1), the
elastic first yield of the soil. The FEM's stresses come from its displacement field alone
(static condensation read backwards, strains at the element vertices); nothing here uses
those formulas.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from ssw.contact.operators import OperatorStore
from ssw.contact.stress import contact_stresses, equivalent_radius

R = 9.525e-3  # m, the chain's 3/4 in bead
#: Relative error allowed on the peak stress (vertex evaluation on the 5 um contact mesh;
#: measured 0.1-0.3 %).
PEAK_RTOL = 5e-3
#: Depth of the peak (the von Mises stress is flat there: +-3 % of a moves it by 1e-3).
DEPTH_ATOL = 0.04


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    return OperatorStore(tmp_path_factory.mktemp("operators"))


def axis_von_mises(zeta: np.ndarray | float, nu: float) -> np.ndarray:
    """von Mises stress over p0 on the axis of a Hertz contact at depth ``zeta = z / a``."""
    zeta = np.asarray(zeta, float)
    sz = -1.0 / (1.0 + zeta**2)
    sr = -((1.0 + nu) * (1.0 - zeta * np.arctan(1.0 / zeta)) - 0.5 / (1.0 + zeta**2))
    return np.abs(sr - sz)


def hertz_peak(nu: float) -> tuple[float, float]:
    """(peak von Mises / p0, its depth / a) of the closed-form axis field."""
    res = minimize_scalar(lambda z: -axis_von_mises(z, nu), bounds=(0.05, 2.0),
                          method="bounded", options={"xatol": 1e-8})
    return float(-res.fun), float(res.x)


def test_closed_form_peak_is_johnsons_first_yield_point():
    """The truth itself: 0.62 p0 at 0.48 a for nu 0.3 (Johnson 1985, sec. 6.1), and
    p0 = 1.81 Y at 0.53 a for nu 0.45 (REFERENCE.md)."""
    peak, depth = hertz_peak(0.3)
    assert peak == pytest.approx(0.62, abs=0.005) and depth == pytest.approx(0.48, abs=0.005)
    peak, depth = hertz_peak(0.45)
    assert 1.0 / peak == pytest.approx(1.81, abs=0.01) and depth == pytest.approx(0.53, abs=0.01)


@pytest.mark.parametrize("nu", [0.3, 0.45])
def test_soil_peak_under_rigid_sphere_is_hertz_first_yield(store, nu):
    """No plate, rigid sphere: the soil's peak von Mises stress and where it sits, at three
    indentations (contact radii 0.3-1 mm), against the Hertz field."""
    E = 50e6
    d = np.array([1e-5, 3e-5, 1e-4])
    st = contact_stresses(np.full(d.size, E), nu, None, 0.0, R, d, store=store)
    Es = E / (1.0 - nu**2)
    a = np.sqrt(R * d)
    p0 = 2.0 * Es * a / (np.pi * R)
    assert st.force == pytest.approx(4.0 / 3.0 * Es * np.sqrt(R) * d**1.5, rel=2e-3)
    peak, depth = hertz_peak(nu)
    assert st.plate is None
    assert st.soil.peak / p0 == pytest.approx(np.full(d.size, peak), rel=PEAK_RTOL)
    assert -st.soil.z / a == pytest.approx(np.full(d.size, depth), abs=DEPTH_ATOL)
    assert np.all(st.soil.r < 0.1 * a)  # on the axis (the field is flat there)


def test_elastic_bead_presses_with_the_combined_modulus(store):
    """A steel bead on a stiff half-space (70 GPa): through the Hertz-equivalent rigid
    sphere the peak is Hertz's with 1/E* = 1/E1* + 1/E2* at the force the rigid sphere of
    the bead's radius carries at the given indentation (the chain's state); the rigid
    sphere alone would overstate it by (E1*/E*)^(2/3) = 1.14."""
    E, nu, bead = 70e9, 0.3, (200e9, 0.28)
    d = np.array([1e-6, 3e-6])
    st = contact_stresses(np.full(d.size, E), nu, None, 0.0, R, d, store=store, bead=bead)
    rigid = contact_stresses(np.full(d.size, E), nu, None, 0.0, R, d, store=store)
    assert st.force == pytest.approx(rigid.force, rel=1e-9)
    Es = 1.0 / ((1.0 - nu**2) / E + (1.0 - bead[1] ** 2) / bead[0])
    F = st.force
    p0 = (6.0 * F * Es**2 / (np.pi**3 * R**2)) ** (1.0 / 3.0)
    a = (3.0 * F * R / (4.0 * Es)) ** (1.0 / 3.0)
    peak, depth = hertz_peak(nu)
    assert st.soil.peak / p0 == pytest.approx(np.full(d.size, peak), rel=PEAK_RTOL)
    assert -st.soil.z / a == pytest.approx(np.full(d.size, depth), abs=DEPTH_ATOL)
    assert rigid.soil.peak / st.soil.peak == pytest.approx(
        np.full(d.size, (E / (1 - nu**2) / Es) ** (2.0 / 3.0)), rel=PEAK_RTOL)
    assert equivalent_radius(R, (E, nu), bead) > R


def test_plate_and_soil_stresses_of_a_homogeneous_bonded_plate(store):
    """A 1 mm plate of the soil's own material bonded to it is a half-space cut by an
    interface: the plate's peak is the Hertz first-yield point inside the plate (0.48 a
    below its top), the soil's peak is the closed-form axis field at the interface's depth
    (1 mm = 1.8-3.2 a), and the force is Hertz's."""
    E, nu, t = 100e6, 0.3, 1.0e-3
    d = np.array([1e-5, 3e-5])
    st = contact_stresses(np.full(d.size, E), nu, (E, nu), t, R, d, {"interface": "bonded"},
                          store=store)
    Es = E / (1.0 - nu**2)
    a = np.sqrt(R * d)
    p0 = 2.0 * Es * a / (np.pi * R)
    assert st.force == pytest.approx(4.0 / 3.0 * Es * np.sqrt(R) * d**1.5, rel=2e-3)
    peak, depth = hertz_peak(nu)
    assert st.plate.peak / p0 == pytest.approx(np.full(d.size, peak), rel=PEAK_RTOL)
    assert (t - st.plate.z) / a == pytest.approx(np.full(d.size, depth), abs=DEPTH_ATOL)
    assert st.soil.peak / p0 == pytest.approx(axis_von_mises(t / a, nu), rel=PEAK_RTOL)
    assert np.all(np.abs(st.soil.z) < 1e-9) and np.all(st.soil.r < 0.1 * a)


def test_stress_scales_with_the_load_and_not_with_the_modulus_alone(store):
    """Linear elasticity: at a fixed indentation the stresses scale with E (two moduli of
    one plate-soil ratio give the same field over E), a check of the per-state modulus."""
    d = np.array([2e-5, 2e-5])
    E = np.array([20e6, 200e6])
    st = [contact_stresses(E[k:k + 1], 0.3, (3.5e9 * E[k] / 20e6, 0.36), 0.4e-3, R, d[:1],
                           store=store) for k in range(2)]
    ratio_soil = st[1].soil.peak / st[0].soil.peak
    ratio_plate = st[1].plate.peak / st[0].plate.peak
    assert ratio_soil == pytest.approx(10.0, rel=1e-6)
    assert ratio_plate == pytest.approx(10.0, rel=1e-6)


@pytest.mark.parametrize("interface", ["frictionless", "bonded", "unilateral"])
def test_retained_displacements_meet_the_sphere(store, interface):
    """The retained displacements rebuilt from the LCP's forces (ssw.contact.stress) satisfy
    the contact conditions the LCP solved through another assembly (Schur complements,
    ssw.contact.operators.scene_lcp): on every loaded candidate the plate's top follows
    the sphere, ``u_z = s(r) - delta``, nowhere does it cross it, and a shared interface
    moves the plate and the soil together."""
    from ssw.contact.operators import geometry_of, scene_lcp, sphere_gap0
    from ssw.contact.parametric import trace
    from ssw.contact.scene import settings_of
    from ssw.contact.stress import retained_displacements

    cfg = settings_of({"interface": interface})
    geom = geometry_of(cfg, 0.4e-3, R, 3e-5, interface)
    layout = store.layout(geom)
    P, S = store.body(geom, "plate", 0.36), store.body(geom, "soil", 0.3)
    E_soil, E_plate, d = 50e6, 3.5e9, 3e-5
    lcp = scene_lcp(layout, P, S, E_soil, E_plate, interface, R)
    path, _ = trace(lcp.W, lcp.q0, lcp.q1, d)
    lam = path.forces(np.array([d]))[0]
    up, us = retained_displacements(layout, P, S, E_soil, E_plate, interface, lam)
    nc = layout.r.size
    surface = sphere_gap0(layout.r, R) - d
    loaded = lam[:nc] > 1e-9 * lam[:nc].max()
    assert 3 <= loaded.sum() < nc
    assert up[:nc][loaded] == pytest.approx(surface[loaded], rel=1e-7, abs=1e-12)
    assert np.all(up[:nc] <= surface + 1e-9 * d)
    if interface != "unilateral":
        assert us == pytest.approx(up[nc:], rel=1e-12, abs=0)


def test_interior_solve_from_the_condensation_factor_is_the_bodys_own(tmp_path):
    """The body field that reuses its condensation's LU (the whole body matrix's factors,
    ssw.contact.operators.keeping_factors) gives the displacements
    of a body field that assembles and factors ``K_II`` itself, and the interior solve
    satisfies the body's own equilibrium ``K_II u_I = -K_IB u_B``."""
    from ssw.contact.operators import geometry_of, keeping_factors, take_factor
    from ssw.contact.scene import settings_of
    from ssw.contact.stress import BodyField, retained_dofs
    from ssw.contact.substructure import LeadingBlock

    store = OperatorStore(tmp_path)  # a cold store: the operators are condensed here
    cfg = settings_of({"interface": "frictionless"})
    geom = geometry_of(cfg, 0.2e-3, R, 2e-5, "frictionless")
    model = store._model(geom)
    u_B = {}
    for which, nu in (("plate", 0.33), ("soil", 0.3)):
        with keeping_factors(2):
            store.body(geom, which, nu)
            prepared = take_factor(geom, which, nu)
        assert prepared is not None and take_factor(geom, which, nu) is None
        b_nodes, b_comps = retained_dofs(model, which)
        tri = model.tri[model.body == (1 if which == "plate" else 0)]
        own = BodyField(model.nodes, tri, model.free, b_nodes, b_comps, nu)
        reused = BodyField(model.nodes, tri, model.free, b_nodes, b_comps, nu, prepared)
        assert isinstance(reused._interior.__self__, LeadingBlock)
        u_B[which] = np.random.default_rng(3).normal(size=(b_nodes.size, 3)) * 1e-6
        a, b = own.displacements(u_B[which]), reused.displacements(u_B[which])
        assert b == pytest.approx(a, rel=1e-9, abs=1e-12 * np.max(np.abs(a)))
        K = prepared[0].K.tocsr()
        n = prepared[0].n_int
        x = np.empty((n, 3))
        x[:] = reused._interior(u_B[which])
        res = K[:n, :n] @ x + K[:n, n:] @ u_B[which]
        assert np.max(np.abs(res)) <= 1e-10 * np.max(np.abs(K[:n, n:] @ u_B[which]))
    # outside keeping_factors nothing is kept
    store2 = OperatorStore(tmp_path / "other")
    store2.body(geom, "soil", 0.25)
    assert take_factor(geom, "soil", 0.25) is None


@pytest.mark.parametrize("interface, plate", [("frictionless", (200e9, 0.26)),
                                               ("unilateral", (200e9, 0.26)),
                                               ("bonded", (3.5e9, 0.36))])
def test_state_at_a_force_is_the_traced_paths(store, interface, plate):
    """The contact state that carries a given force, found by Newton steps on the LCP at
    single indentations (ssw.contact.stress), is the one the exact path traced from zero
    (ssw.contact.parametric.trace) gives when its piecewise affine force is inverted, on a
    steel plate whose path lifts off the axis and on a PLA plate."""
    from ssw.contact.operators import geometry_of, scene_lcp
    from ssw.contact.parametric import trace
    from ssw.contact.scene import settings_of
    from ssw.contact.stress import _state_at_force

    cfg = settings_of({"interface": interface})
    geom = geometry_of(cfg, 0.2e-3, R, 4e-5, interface)
    layout = store.layout(geom)
    P, S = store.body(geom, "plate", plate[1]), store.body(geom, "soil", 0.3)
    lcp = scene_lcp(layout, P, S, 80e6, plate[0], interface, 2.0 * R)
    ms = lcp.n_sphere
    path, _ = trace(lcp.W, lcp.q0, lcp.q1, 4e-5)
    F_end = float(path.forces(np.array([4e-5]))[0, :ms].sum())
    force = F_end * np.array([0.003, 0.05, 0.4, 0.97])
    d, lam, active = _state_at_force(lcp, force, 4e-5)
    # invert the traced path's force on its pieces
    br = path.breaks
    f_hi = path.lam0[:, :ms].sum(1) + br[1:] * path.lam1[:, :ms].sum(1)
    j = np.searchsorted(f_hi, force)
    f_lo = path.lam0[j, :ms].sum(1) + br[j] * path.lam1[j, :ms].sum(1)
    d_ref = br[j] + (force - f_lo) / path.lam1[j, :ms].sum(1)
    assert d == pytest.approx(d_ref, rel=1e-10)
    assert lam[:, :ms].sum(1) == pytest.approx(force, rel=1e-10)
    lam_ref = path.forces(d_ref)
    assert np.max(np.abs(lam - lam_ref)) <= 1e-9 * np.max(np.abs(lam_ref))
    assert np.array_equal(active, lam_ref > 0) or np.all(np.abs(lam_ref[active != (lam_ref > 0)])
                                                        <= 1e-9 * np.max(lam_ref))
