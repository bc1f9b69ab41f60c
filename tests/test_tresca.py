"""Tresca plasticity: the consistent tangent (Taylor test, second-order remainder) on the main
plane and at both corners, with and without hardening; the backward-Euler equations (the
return lands on the hexagon, the flow is normal to it: the plastic work is maximal); the
cases where Tresca and von Mises coincide (two equal principal stresses: Y = 2k; pure shear:
k = Y / sqrt(3)); the registry, the config's schema and the command line."""

from __future__ import annotations

import numpy as np
import pytest
from taylor import STEPS, rates, remainders

from ssw.constitutive import MODELS, Tresca, VonMises, model_from, model_of_strength
from ssw.constitutive.base import initial_state
from ssw.constitutive.tensors import ONE, P_DEV, SQRT2, bulk_shear, elastic_tangent
from ssw.errors import ConfigError
from ssw.materials import Strength

E, NU, K_SHEAR = 50e6, 0.3, 0.5e6
CASES = {"perfect": Tresca(K_SHEAR), "hardening": Tresca(K_SHEAR, hardening=5e6)}


def _tensor(m: np.ndarray) -> np.ndarray:
    """(n, 3, 3) tensors (r, z, theta) of Mandel 4-vectors (n, 4)."""
    t = np.zeros((m.shape[0], 3, 3))
    t[:, 0, 0], t[:, 1, 1], t[:, 2, 2] = m[:, 0], m[:, 1], m[:, 2]
    t[:, 0, 1] = t[:, 1, 0] = m[:, 3] / SQRT2
    return t


def _points(model: Tresca, n: int = 4000, seed: int = 1):
    """Strains from a random plastic history, spread over the elastic range, the main plane
    and both corners; the first 200 with equal in-plane principal strains (rr = zz, no rz)."""
    rng = np.random.default_rng(seed)
    scale = 4.0 * model.strength / E
    strain = rng.normal(size=(n, 4)) * scale
    state = initial_state(n)
    state[:, :4] = 0.3 * scale * rng.normal(size=(n, 4)) @ P_DEV
    state[:, 4] = rng.uniform(0, 0.05, n)
    strain[:200, 1] = strain[:200, 0] - state[:200, 0] + state[:200, 1]
    strain[:200, 3] = state[:200, 3]
    return strain, state, rng.normal(size=(n, 4)) * scale


@pytest.mark.parametrize("case", list(CASES))
def test_taylor_remainder_is_second_order(case):
    """|sigma(e + h d) - sigma(e) - h D d| falls 4x per halving of h on the main plane and at
    each corner (the tangent is the derivative of the return), the plain difference 2x;
    points whose region changes within the step are left out, and so are those whose
    remainder is round-off (a corner's return is linear in some directions)."""
    model = CASES[case]
    strain, state, d = _points(model)
    base, r1, r2, same = remainders(model, E, NU, strain, state, d)
    good = same & (r2[-1] > 1e-6 * r1[-1]) & (r1[-1] > 1e-9 * model.strength)
    for region in (1, 2, 3):
        sel = good & (base.region == region)
        assert sel.sum() > 300
        rate1, rate2 = rates(r1, r2, sel)
        assert np.median(rate2) == pytest.approx(2.0, abs=0.05)
        assert np.percentile(rate2, 1) > 1.8
        assert np.median(rate1) == pytest.approx(1.0, abs=0.05)
    # equal in-plane principal strains (the spin coefficient's limit): the tangent gives the
    # change to 1e-3 at the smallest step (a wrong spin coefficient leaves an O(h) error)
    tie = same[:200] & base.plastic[:200]
    assert tie.sum() > 50
    assert np.max(r2[-1, :200][tie] / r1[-1, :200][tie]) < 1e-3
    # the tangent of associated flow is symmetric
    np.testing.assert_allclose(base.tangent, np.swapaxes(base.tangent, 1, 2), atol=1e-9 * E)
    # the elastic tangent in place of the consistent one is first order: the test can fail
    K, G = bulk_shear(E, NU)
    sel = good & base.plastic
    wrong = np.linalg.norm(model.update(E, NU, strain + STEPS[-1] * d, state).stress
                           - base.stress - STEPS[-1] * d @ elastic_tangent(K, G), axis=1)[sel]
    assert np.median(wrong / r2[-1, sel]) > 10


@pytest.mark.parametrize("case", list(CASES))
def test_return_solves_backward_euler(case):
    """The returned stress is C (eps - eps_p) and lies on the (hardened) hexagon: s1 - s3 =
    2k + H kappa (eigenvalues by numpy, not by the model's closed form), s2 = s3 at the
    right corner and s1 = s2 at the left; the plastic strain increment keeps the volume, is
    coaxial with the stress, has a zero middle eigenvalue on the main plane, does the work
    sigma : d eps_p = sigma_y d kappa, and is normal to the hexagon: no admissible stress
    does more plastic work (the principle of maximum dissipation)."""
    model = CASES[case]
    strain, state, _ = _points(model, seed=2)
    up = model.update(E, NU, strain, state)
    K, G = bulk_shear(E, NU)
    scale = model.strength
    np.testing.assert_allclose(up.stress, (strain - up.state[:, :4]) @ elastic_tangent(K, G),
                               atol=1e-9 * scale)
    sy = 2.0 * model.cohesion + model.hardening * up.state[:, 4]
    s = np.linalg.eigvalsh(_tensor(up.stress))[:, ::-1]  # s1 >= s2 >= s3
    pl = up.plastic
    np.testing.assert_allclose((s[:, 0] - s[:, 2])[pl], sy[pl], rtol=1e-9)
    assert np.all((s[:, 0] - s[:, 2])[~pl] <= sy[~pl] * (1 + 1e-12))
    for region, (i, j) in ((2, (1, 2)), (3, (0, 1))):
        sel = up.region == region
        assert sel.sum() > 500
        np.testing.assert_allclose(s[sel, i], s[sel, j], atol=1e-9 * scale)
    main = up.region == 1
    assert main.sum() > 500
    assert np.all(np.diff(s[main], axis=1) < 1e-6 * scale)
    dep = up.state[:, :4] - state[:, :4]
    np.testing.assert_allclose(dep @ ONE, 0.0, atol=1e-12 * scale / E)
    ts, td = _tensor(up.stress), _tensor(dep)
    np.testing.assert_allclose(ts @ td - td @ ts, 0.0, atol=1e-9 * scale * scale / E)
    ev = np.linalg.eigvalsh(td[main])
    assert np.all(np.abs(ev[:, 1]) <= 1e-9 * np.abs(ev).max(axis=1))
    dk = up.state[:, 4] - state[:, 4]
    np.testing.assert_allclose(np.einsum("ni,ni->n", up.stress, dep), sy * dk,
                               atol=1e-9 * scale * scale / E)
    assert np.all(dk[pl] > 0) and np.all(dk[~pl] == 0)
    # maximum dissipation: (sigma - sigma*) : d eps_p >= 0 for stresses sigma* inside the
    # hardened hexagon (random deviators scaled into it, random mean stresses)
    rng = np.random.default_rng(5)
    for _ in range(20):
        star = rng.normal(size=dep.shape) * scale
        ss = np.linalg.eigvalsh(_tensor(star))
        star *= (rng.uniform(0, 1, len(star)) * sy / (ss[:, 2] - ss[:, 0]))[:, None]
        work = np.einsum("ni,ni->n", up.stress - star, dep)
        assert np.all(work[pl] >= -1e-9 * scale * scale / E)
    np.testing.assert_array_equal(up.state[~pl], state[~pl])


def _path(model, strains: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Stresses (steps, n, 4) and hardening variables (steps, n) along strain paths (steps,
    n, 4) from a virgin state."""
    state = initial_state(strains.shape[1])
    out, kappa = [], []
    for eps in strains:
        up = model.update(E, NU, eps, state)
        state = up.state
        out.append(up.stress)
        kappa.append(state[:, 4])
    return np.array(out), np.array(kappa)


def _cycle(rng, n: int, shape: np.ndarray, scale: float) -> np.ndarray:
    """Strain paths (40, n, 4): random directions of the form ``shape`` (n, 4), loaded out
    to a few yield strains, back through zero and out again, plus a random volume change."""
    amp = np.concatenate([np.linspace(0, 3, 15), np.linspace(3, -2, 15)[1:],
                          np.linspace(-2, 4, 12)[1:]])
    vol = rng.normal(size=(n, 1)) * ONE
    return scale * (amp[:, None, None] * shape[None] + 0.3 * amp[:, None, None] * vol[None])


@pytest.mark.parametrize("H", [0.0, 4e6])
def test_two_equal_principal_stresses_are_von_mises(H):
    """With two equal principal stresses (e_rr = e_tt, no rz) the hexagon's corner is von
    Mises's circle: Tresca(k, H) = VonMises(Y = 2k, H) along loading, reversal and reloading,
    stresses and hardening variables alike."""
    rng = np.random.default_rng(3)
    n = 200
    shape = np.zeros((n, 4))
    shape[:, 0] = shape[:, 2] = rng.normal(size=n)
    shape[:, 1] = rng.normal(size=n)
    strains = _cycle(rng, n, shape, 2 * K_SHEAR / E)
    st, kt = _path(Tresca(K_SHEAR, H), strains)
    sv, kv = _path(VonMises(2 * K_SHEAR, H), strains)
    assert np.count_nonzero(kt[-1]) > 0.8 * n
    np.testing.assert_allclose(st, sv, atol=1e-9 * K_SHEAR)
    np.testing.assert_allclose(kt, kv, atol=1e-12)


@pytest.mark.parametrize("H", [0.0, 4e6])
def test_pure_shear_is_von_mises(H):
    """In pure shear (in-plane deviator only, no hoop deviator) Tresca's k is von Mises's
    Y / sqrt(3); the hardening matches when von Mises's modulus is 3/4 of Tresca's
    (Tresca's d kappa = sqrt(3)/2 of von Mises's there, and its tau_y = k + H kappa / 2)."""
    rng = np.random.default_rng(4)
    n = 200
    shape = np.zeros((n, 4))
    shape[:, 0] = rng.normal(size=n)
    shape[:, 1] = -shape[:, 0]
    shape[:, 3] = rng.normal(size=n)
    strains = _cycle(rng, n, shape, 2 * K_SHEAR / E)
    st, kt = _path(Tresca(K_SHEAR, H), strains)
    sv, kv = _path(VonMises(np.sqrt(3.0) * K_SHEAR, 0.75 * H), strains)
    assert np.count_nonzero(kt[-1]) > 0.8 * n
    np.testing.assert_allclose(st, sv, atol=1e-9 * K_SHEAR)
    np.testing.assert_allclose(kt, kv * np.sqrt(3.0) / 2.0, atol=1e-12)


def test_registry_and_strengths():
    """``model_from`` and ``model_of_strength`` (k = the material's cohesion), the key, the
    unconfined strength 2k, the refusals."""
    assert MODELS["tresca"] is Tresca and Tresca.isochoric
    tr = model_from({"model": "tresca", "cohesion": 25e3})
    assert tr == Tresca(25e3) and tr.key == "tresca-k25kPa" and tr.strength == 50e3
    assert Tresca(25e3, 2e6).key == "tresca-k25kPa-H2MPa"
    assert model_from(tr.params()) == tr
    clay = Strength(cohesion=40e3, friction_angle=0.0, source="undrained")
    assert model_of_strength("tresca", clay) == Tresca(40e3)
    with pytest.raises(ConfigError, match="cohesion"):
        model_of_strength("tresca", Strength(compressive=1e6, source="x"), "materials.pcf08")
    with pytest.raises(ConfigError, match="cohesion"):
        Tresca(0.0)
    with pytest.raises(ConfigError, match="hardening"):
        Tresca(1e3, -1.0)
    # yield ratio: 1 in uniaxial compression at 2k, 1/2 at k
    st = np.array([[0.0, -50e3, 0.0, 0.0], [0.0, -25e3, 0.0, 0.0]])
    np.testing.assert_allclose(tr.yield_ratio(st, initial_state(2)), [1.0, 0.5])


def test_config_and_cli(tmp_path, capsys):
    """The config's schema takes ``soil_model: {model: tresca, cohesion: k}``; ``ssw
    contact --soil-model tresca --soil-cohesion K`` solves the sphere on it (below yield:
    no plastic work)."""
    import json
    from pathlib import Path

    import yaml

    from ssw.cli import main
    from ssw.config import all_scenes, load_config

    sets = {"plate_material": ["pla"], "plate_thickness": {"values": [0.0]},
            "soil_E": {"values": [38e6]}, "soil_nu": {"values": [0.45]},
            "soil_model": {"model": "tresca", "cohesion": 30e3}}
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump({"sets": {"clay": sets}}))
    assert list(all_scenes(load_config(path))) == ["noplate-E38MPa-nu0.450-tresca-k30kPa"]
    ci = str(Path(__file__).resolve().parent.parent / "config" / "ci.yaml")
    rc = main(["contact", "--soil-E", "40e6", "--soil-nu", "0.45", "--plate-thickness", "0",
               "--soil-model", "tresca", "--soil-cohesion", "5e6", "--delta-max", "4e-6",
               "--steps", "3", "--config", ci, "--json"])
    assert rc == 0
    res = json.loads(capsys.readouterr().out)
    assert res["soil_model_key"] == "tresca-k5000kPa" and res["dissipated_work"] == 0.0
