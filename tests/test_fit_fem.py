"""Fits of real FEM curves (ssw.contact): the no-plate curve is Hertz, K = 1 within 0.5 %."""

import pytest

from ssw import contact
from ssw.config import Scene, library, load_config
from ssw.fit.fitting import fit_curve


@pytest.fixture(scope="module")
def cfg():
    return load_config("config/ci.yaml")


def solve(cfg, scene):
    return contact.solve_scene(scene, cfg["contact"], cfg["indenter"]["radius"], library(cfg))


def test_no_plate_fem_curve_gives_K_one(cfg):
    c = solve(cfg, Scene("none", 0.0, 50e6, 0.3))
    K = fit_curve(c, "k_hertz").params["K"]
    assert abs(K - 1.0) < 5e-3
    assert fit_curve(c, "power").params["n"] == pytest.approx(1.5, abs=0.01)


def test_plate_stiffens_small_indentations_more(cfg):
    """A stiff plate on soft soil: K fitted on a small range exceeds K on the whole curve,
    and the free exponent falls below Hertz's 3/2 (REFERENCE.md [M])."""
    c = solve(cfg, Scene("pla", 0.4e-3, 50e6, 0.3))
    K_small = fit_curve(c, "k_hertz", (0.0, 1e-5)).params["K"]
    K_all = fit_curve(c, "k_hertz").params["K"]
    assert K_small > K_all > 1.0
    assert fit_curve(c, "power").params["n"] < 1.45
