"""The layered oracle alone against analytic truth (ssw.contact.layered*).

Kernel: a bonded layer of the substrate's own material is the homogeneous half-space; a
thin layer on a rigid base has the long-wave compliance of its membrane-equilibrium
state; a thin stiff plate on a soft half-space tends to a Kirchhoff plate on that
half-space (frictionless: free surface; bonded: surface held laterally) at the orders
plate theory predicts. Contact: no plate is Sneddon's exact sphere (and Hertz where Hertz
holds); a thick layer tends to the half-space of the layer's material (error ~ a/h), a
thin one to the substrate (~ h/a); the rings converge at order 2 within the stated error;
the discrete LCP is solved exactly (signs, complementarity, equilibrium).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from ssw import hertz
from ssw.contact.layered import LayeredSettings, increments, solve_curve, solve_stack
from ssw.contact.layered_kernel import Layer, Stack, compliance_ratio, plate_on_soil
from ssw.contact.layered_lcp import sphere_surface
from ssw.contact.layered_rings import Quadrature, disc_deflection, influence_matrix
from ssw.errors import ConfigError

R = 9.53e-3  # m, the study's rigid sphere
T = np.geomspace(1e-6, 1e3, 60)  # xi h values


def _slope(x, y) -> float:
    return float(np.polyfit(np.log(x), np.log(y), 1)[0])


def _sneddon_force(delta, E_star, radius=R):
    a = np.linspace(0.05 * np.sqrt(radius * delta.min()), 1.1 * np.sqrt(radius * delta.max()),
                    200_001)
    d, f = hertz.sneddon_sphere(a, E_star, radius)
    return np.interp(delta, d, f)


# ---- kernel


@pytest.mark.parametrize("E, nu", [(10e6, 0.3), (3.5e9, 0.5), (200e9, 0.0)])
def test_bonded_layer_of_the_substrate_material_is_the_halfspace(E, nu):
    """A bonded interface inside one material is no interface: A(xi) = 1 for any xi h."""
    A = compliance_ratio(plate_on_soil((E, nu), 0.4e-3, (E, nu), "bonded"), T / 0.4e-3)
    assert np.max(np.abs(A - 1)) < 1e-12


def test_kernel_limits_and_no_overflow():
    """A -> E1 (1 - nu2^2) / (E2 (1 - nu1^2)) as xi h -> 0 (the substrate alone), A -> 1 as
    xi h -> inf; the exponentially scaled form stays finite up to xi h = 1e6."""
    E1, n1, E2, n2 = 200e9, 0.26, 10e6, 0.3
    for iface in ("bonded", "frictionless"):
        st = plate_on_soil((E1, n1), 1.0, (E2, n2), iface)
        A = compliance_ratio(st, np.array([1e-13, 30.0, 1e3, 1e6]))
        assert A[0] == pytest.approx(E1 * (1 - n2**2) / (E2 * (1 - n1**2)), rel=1e-6)
        assert np.allclose(A[1:], 1.0, rtol=0, atol=1e-14)


@pytest.mark.parametrize("nu", [0.0, 0.3, 0.45])
def test_thin_layer_on_a_rigid_base(nu):
    """Long waves on a layer of thickness h over a rigid base (A = u_z / (2 (1-nu^2) p /
    (E xi))): bonded, uniaxial strain, u_z = p h (1+nu)(1-2nu) / (E (1-nu)), so
    A/t -> (1 - 2 nu) / (2 (1 - nu)^2); frictionless, the membrane equilibrium
    (div u = -nu (1+nu) sigma_zz / E, so sigma_rr + sigma_tt = nu sigma_zz) gives
    u_z = p h (1 - nu^2) / E, A/t -> 1/2. The corrections are of order t^2 or higher
    (bonded: t^2 for nu > 0; frictionless: smaller, t^4 here)."""
    t = np.array([1e-2, 2e-2, 4e-2, 8e-2])
    limits = {"bonded": (1 - 2 * nu) / (2 * (1 - nu) ** 2), "frictionless": 0.5}
    for iface, limit in limits.items():
        st = Stack((Layer(1e6, nu, 1.0),), (iface,), np.inf, 0.0)
        dev = np.abs(compliance_ratio(st, t) / t / limit - 1)
        assert dev[0] < 1e-3
        if iface == "bonded" and nu > 0:
            assert _slope(t, dev) == pytest.approx(2.0, abs=0.1)
        else:  # at nu = 0 bonded is frictionless: no Poisson coupling at the base
            assert _slope(t, dev) > 1.9


@pytest.mark.parametrize("iface, order", [("frictionless", 2.0), ("bonded", 1.0)])
def test_thin_stiff_plate_tends_to_kirchhoff_plate(iface, order):
    """E2/E1 -> 0: near the crossover xi_c (D xi^4 = soil stiffness; t_c = xi_c h -> 0) the
    kernel tends to a Kirchhoff plate (D = E1 h^3 / (12 (1 - nu1^2))) on a half-space,
    u_z_bar = p_bar / (D xi^4 + k xi), k = E2 / (2 (1 - nu2^2)): frictionless with error
    O(t_c^2) (transverse shear, thickness), bonded on a surface held laterally by the plate
    (k times 4 (1 - nu2)^2 / (3 - 4 nu2), the half-space with u_r = 0 at its surface)
    with error O(t_c) (the shear coupling at the interface)."""
    E1, n1, n2, h = 200e9, 0.26, 0.3, 1.0
    D = E1 * h**3 / (12 * (1 - n1**2))
    held = 1.0 if iface == "frictionless" else 4 * (1 - n2) ** 2 / (3 - 4 * n2)
    tcs, devs = [], []
    for ratio in (1e-4, 1e-5, 1e-6, 1e-7):
        E2 = E1 * ratio
        k = held * E2 / (2 * (1 - n2**2))
        tc = (k / D) ** (1 / 3) * h
        t = tc * np.geomspace(1 / 3, 3, 21)
        A = compliance_ratio(plate_on_soil((E1, n1), h, (E2, n2), iface), t / h)
        A_plate = E1 * t / (2 * (1 - n1**2)) / (D * t**4 + k * t)
        tcs.append(tc)
        devs.append(np.max(np.abs(A / A_plate - 1)))
    assert devs[-1] < 0.02 * order**2  # 5e-4 frictionless, 3e-3 bonded at the last t_c
    assert _slope(tcs, devs) == pytest.approx(order, abs=0.2)


def test_disc_deflection_is_loves_solution():
    """Johnson (1985) eq. 3.38: centre 2 (1-nu^2) p b / E, edge 4 (1-nu^2) p b / (pi E),
    far field P (1-nu^2) / (pi E r) (Boussinesq) with P = pi b^2 p."""
    E, nu, b = 50e6, 0.3, 1e-3
    c = (1 - nu**2) / E
    w = disc_deflection(np.array([0.0, b, 1000 * b]), b, E, nu)
    assert w[0] == pytest.approx(2 * c * b, rel=1e-14)
    assert w[1] == pytest.approx(4 * c * b / np.pi, rel=1e-14)
    assert w[2] == pytest.approx(c * np.pi * b**2 / (np.pi * 1000 * b), rel=1e-6)


def test_hankel_quadrature_is_converged():
    """The correction integral with the default quadrature equals one with ~30x the nodes."""
    st = plate_on_soil((200e9, 0.26), 0.4e-3, (10e6, 0.3), "bonded")
    edges = np.linspace(0, 1.5e-3, 41)
    pts = 0.5 * (edges[1:] + edges[:-1])
    C, n = influence_matrix(st, pts, edges)
    Cd, nd = influence_matrix(st, pts, edges, Quadrature(order=32, growth=1.25, width=0.5,
                                                         t_max=30.0, xi_low=1e-6))
    assert nd > 4 * n
    assert np.max(np.abs(C / Cd - 1)) < 1e-10


# ---- contact


def test_no_plate_is_sneddons_exact_sphere_within_the_stated_error():
    """h = 0: the homogeneous half-space. Sneddon (1965) within the stated error for
    delta >= 1 um; Hertz within that plus Hertz's own error (paraboloid vs sphere)."""
    E, nu = 50e6, 0.3
    Es = float(hertz.effective_modulus(E, nu))
    curve = solve_curve((E, nu), None, 0.0, R, {"steps": 1000, "delta_max": 1e-4})
    d, m = curve.delta, curve.delta >= 1e-6
    sn = _sneddon_force(d, Es)
    err = np.abs(curve.force / sn - 1)[m]
    assert err.max() <= LayeredSettings().force_error
    fh = hertz.force(d, Es, R)
    assert np.all(np.abs(curve.force / fh - 1)[m] <= err + np.abs(sn / fh - 1)[m] + 1e-12)
    a_grid = np.linspace(1e-6, 1.1e-3, 100_001)
    a_exact = np.interp(d, hertz.sneddon_sphere(a_grid, Es, R)[0], a_grid)
    assert np.max(np.abs(curve.contact_radius / a_exact - 1)[m]) < 0.01
    assert curve.inputs["engine"] == "layered" and curve.stats["xi_nodes"] == 0


def test_ring_discretization_converges_at_order_two():
    """Force error vs Sneddon at ring ratios 1/10, 1/20, 1/40: order 2, and each within
    its stated error ERROR_COEFF ratio^2."""
    E, nu = 80e6, 0.45
    stack = plate_on_soil(None, 0.0, (E, nu), "bonded")
    d = increments(1e-4, 200)
    sn = _sneddon_force(d, float(hertz.effective_modulus(E, nu)))
    ratios, errs = [1 / 10, 1 / 20, 1 / 40], []
    for rho in ratios:
        s = LayeredSettings(ring_ratio=rho)
        f = solve_stack(stack, R, d, s)[0].force
        errs.append(np.max(np.abs(f / sn - 1)[d >= 1e-6]))
        assert errs[-1] <= s.force_error
    assert _slope(ratios, errs) == pytest.approx(2.0, abs=0.25)


@pytest.mark.parametrize("iface", ["bonded", "frictionless"])
def test_thick_layer_tends_to_the_layer_halfspace(iface):
    """h >> a: the substrate is felt through a deflection ~ F / (E h): the relative force
    difference from the layer's own half-space falls like a/h (slope -1)."""
    d = increments(1e-5, 4)  # a = 0.31 mm
    s = LayeredSettings(ring_ratio=1 / 20)
    ref = solve_stack(plate_on_soil(None, 0.0, (50e6, 0.3), iface), R, d, s)[0].force
    hs = np.array([6e-3, 12e-3, 24e-3])
    dev = [np.max(np.abs(solve_stack(plate_on_soil((50e6, 0.3), h, (500e6, 0.2), iface), R, d,
                                     s)[0].force / ref - 1)) for h in hs]
    assert dev[-1] < 0.012
    assert _slope(hs, dev) == pytest.approx(-1.0, abs=0.1)


@pytest.mark.parametrize("E1, iface, law", [
    (50e6, "bonded", "h"), (50e6, "frictionless", "h"), (5e9, "bonded", "h log h"),
    (5e9, "frictionless", "none")])
def test_thin_layer_tends_to_the_substrate(E1, iface, law):
    """h << a = 0.31 mm: a soft (E1 = E2 / 10) or stiff (10 E2) layer on a 500 MPa substrate.
    The relative force difference from the substrate alone falls like h/a for the soft
    layer; the stiff bonded one spreads the load over its thickness, the kernel's O(xi h)
    correction summed up to xi ~ 1/h against the contact's p_bar ~ xi^(-3/2):
    (h/a) ln(a/h); the stiff frictionless one (no membrane coupling) stays within the
    rings' error of the substrate."""
    d = increments(1e-5, 4)
    a = np.sqrt(R * d[-1])
    # the kernel's correction is below 1e-8 beyond xi h = 12: a cheaper quadrature
    s = LayeredSettings(ring_ratio=1 / 20, quadrature=Quadrature(order=8, t_max=12.0))
    ref = solve_stack(plate_on_soil(None, 0.0, (500e6, 0.2), iface), R, d, s)[0].force
    hs = np.array([1.25e-6, 2.5e-6, 5e-6])
    dev = np.array([np.max(np.abs(solve_stack(plate_on_soil((E1, 0.35), h, (500e6, 0.2),
                                                            iface), R, d, s)[0].force / ref - 1))
                    for h in hs])
    if law == "none":
        assert dev.max() < 2 * s.force_error
        return
    scale = hs / a * (np.log(a / hs) if law == "h log h" else 1.0)
    assert dev[0] < 0.035
    assert _slope(scale, dev) == pytest.approx(1.0, abs=0.1)


def test_lcp_is_solved_exactly():
    """At every stored increment: p >= 0 on the rings, the gap to the exact sphere >= 0,
    p g = 0, and the force is the integral of p (steel plate on a soft soil, bonded)."""
    st = plate_on_soil((200e9, 0.26), 0.4e-3, (10e6, 0.3), "bonded")
    d = increments(1e-4, 50)
    curve, state = solve_stack(st, R, d, profiles=6)
    C, pts, areas = state["C"], state["points"], state["areas"]
    s = sphere_surface(pts, R)
    assert np.allclose(s, R - np.sqrt(R**2 - pts**2), rtol=1e-12, atol=4 * np.spacing(R))
    for delta, p in zip(curve.pressure["delta"], curve.pressure["p"], strict=True):
        g = s - delta + C @ p
        assert p.min() >= -1e-12 * p.max() and g.min() >= -1e-10 * d[-1]
        assert np.max(np.abs(p * g)) <= 1e-9 * delta * p.max()
        k = int(np.searchsorted(d, delta))
        assert areas @ p == pytest.approx(curve.force[k], rel=1e-12)
    assert np.all(np.diff(curve.force) > 0) and np.all(np.diff(curve.contact_radius) >= 0)


def test_soil_depth_tends_to_the_halfspace():
    """A soil layer of depth H on a rigid base: the force difference from the half-space
    soil falls like a/H (the rigid base's deflection correction ~ F / (E H))."""
    s = LayeredSettings(ring_ratio=1 / 20)
    ref = solve_curve((30e6, 0.3), (3.5e9, 0.36), 0.4e-3, R, {"steps": 4}, s).force
    Hs = np.array([0.25, 0.5, 1.0])
    dev = [np.max(np.abs(solve_curve((30e6, 0.3), (3.5e9, 0.36), 0.4e-3, R, {"steps": 4},
                                     LayeredSettings(ring_ratio=1 / 20, soil_depth=H)).force
                         / ref - 1)) for H in Hs]
    assert np.all(np.diff(dev) < 0) and dev[-1] < 5e-3
    assert _slope(Hs, dev) == pytest.approx(-1.0, abs=0.15)


def test_bad_inputs_name_the_field():
    with pytest.raises(ConfigError, match=r"contact\.interface"):
        solve_curve((1e7, 0.3), (3.5e9, 0.36), 4e-4, R, {"interface": "unilateral"})
    with pytest.raises(ConfigError, match="plate"):
        solve_curve((1e7, 0.3), None, 4e-4, R, {})
    with pytest.raises(ConfigError, match=r"layers\[0\]\.nu"):
        solve_curve((1e7, 0.3), (3.5e9, 0.7), 4e-4, R, {})
    with pytest.raises(ConfigError, match="ring_ratio"):
        LayeredSettings(ring_ratio=0.0)


def test_cli_engine_layered_writes_the_curve_contract(tmp_path, capsys):
    """`ssw contact --engine layered` prints and writes what the FEM engine does."""
    from pathlib import Path

    from ssw.cli import main
    from ssw.curve import read_curve

    ci = str(Path(__file__).resolve().parent.parent / "config" / "ci.yaml")
    out = tmp_path / "c.h5"
    rc = main(["contact", "--engine", "layered", "--soil-E", "30e6", "--soil-nu", "0.3",
               "--plate-material", "pla", "--plate-thickness", "0.4e-3", "--steps", "20",
               "--interface", "bonded", "--config", ci, "--output", str(out), "--json"])
    assert rc == 0
    printed = json.loads(capsys.readouterr().out)
    curve = read_curve(out)
    assert printed["engine"] == "layered" and curve.inputs["engine"] == "layered"
    assert curve.inputs["interface"] == "bonded" and curve.inputs["plate_material"] == "pla"
    assert printed["stats"]["wall_total"] > 0 and curve.stats["rings"] > 0
    assert np.allclose(printed["force"], curve.force) and len(curve.delta) == 20
    assert np.allclose(printed["contact_radius"], curve.contact_radius)
    r, p = curve.pressure["r"], curve.pressure["p"][-1]
    edges = np.concatenate([[0.0], 0.5 * (r[1:] + r[:-1])])  # p is constant on each ring
    assert p.shape == r.shape and np.all(p >= 0) and p[0] > 0
    assert np.sum(p[:-1] * np.pi * np.diff(edges**2)) == pytest.approx(curve.force[-1],
                                                                        rel=0.02)
