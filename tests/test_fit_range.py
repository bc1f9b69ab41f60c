"""Default fit ranges: the energy bound, its relation to the chain's peak, modes, clipping."""

import dataclasses

import numpy as np
import pytest
from scipy.integrate import quad

from ssw import hertz
from ssw.config import load_config
from ssw.errors import ConfigError
from ssw.fit.range import ChainEstimate, G, energy_bound_indentation, fit_range, fit_ranges

E = np.array([10e6, 38e6, 123e6, 445e6, 1000e6])


@pytest.fixture(scope="module")
def cfg():
    return load_config("config/ci.yaml")


def test_energy_bound_balances_the_energy(cfg):
    """The wall's stored energy at the bound equals striker energy + weight's work."""
    ch = ChainEstimate.from_config(cfg)
    d = energy_bound_indentation(E, 0.3, ch)
    A = hertz.hertz_coefficient(
        hertz.effective_modulus(ch.bead_E, ch.bead_nu, E, 0.3), ch.bead_radius
    )
    for di, Ai in zip(d, A, strict=True):
        stored, _ = quad(lambda x, Ai=Ai: Ai * x**1.5, 0.0, di, epsabs=0, epsrel=1e-13)
        supplied = 0.5 * ch.bead_mass * ch.striker_velocity**2 + ch.beads * ch.bead_mass * G * di
        assert stored == pytest.approx(supplied, rel=1e-10)


def test_without_gravity_the_bound_is_the_closed_form(cfg):
    ch = dataclasses.replace(ChainEstimate.from_config(cfg), gravity=False)
    A = hertz.hertz_coefficient(
        hertz.effective_modulus(ch.bead_E, ch.bead_nu, E, 0.3), ch.bead_radius
    )
    closed = (5 * ch.bead_mass * ch.striker_velocity**2 / (4 * A)) ** 0.4  # (2/5) A d^2.5 = W
    assert np.allclose(energy_bound_indentation(E, 0.3, ch), closed, rtol=1e-12)


def test_chain_peak_lies_below_the_energy_bound(cfg):
    """The chain keeps energy in its beads: its peak is below the bound,
    and not far below (the solitary wave carries most of the striker's energy)."""
    from ssw.chain.params import ChainParams
    from ssw.chain.run import peak_wall_indentation

    peak = peak_wall_indentation(E, 0.3, ChainParams.from_config(cfg))
    bound = energy_bound_indentation(E, 0.3, ChainEstimate.from_config(cfg))
    assert np.all(peak <= bound)
    assert np.all(peak > 0.5 * bound)


def test_modes_and_clipping(cfg):
    c = {**cfg, "fit": {**cfg["fit"], "range": {**cfg["fit"]["range"]}}}
    rngs = fit_ranges(E, np.full(E.size, 0.3), np.full(E.size, 1e-4), c)
    needed = np.array([r.needed for r in rngs])
    assert np.all(np.diff(needed) < 0)  # stiffer soil, smaller indentation
    for r in rngs:
        assert r.hi == min(r.needed, 1e-4) and r.clipped == (r.needed > 1e-4)
    c["fit"]["range"].update(mode="fixed", delta_max=3e-5, delta_min=1e-6)
    r = fit_range(50e6, 0.3, 1e-4, c)
    assert (r.lo, r.hi, r.source, r.clipped) == (1e-6, 3e-5, "config", False)
    c["fit"]["range"].update(mode="curve")
    assert fit_range(50e6, 0.3, 7e-5, c).hi == 7e-5
    c["fit"]["range"].update(mode="fixed", delta_min=2e-4)
    with pytest.raises(ConfigError, match="delta_min"):
        fit_range(50e6, 0.3, 1e-4, c)


def test_a_softer_plate_sets_the_indentation_a_stiffer_one_does_not(cfg):
    """The chain's need is bounded by a Hertz wall of the softer material: a 100 MPa plate
    on a 445 MPa foam needs the 100 MPa half-space's indentation; a 3.5 GPa plate keeps the
    soil's; no plate (None) keeps the soil's."""
    from ssw.fit.range import scene_delta_max, softer_half_space

    E, nu = softer_half_space([445e6, 445e6, 445e6], [0.3, 0.3, 0.3],
                              [100e6, 3.5e9, None], [0.36, 0.36, None])
    assert E.tolist() == [100e6, 445e6, 445e6]
    assert nu.tolist() == [0.36, 0.3, 0.3]
    soil = scene_delta_max(445e6, 0.3, cfg)
    assert scene_delta_max(445e6, 0.3, cfg, (3.5e9, 0.36)) == soil
    soft = scene_delta_max(445e6, 0.3, cfg, (100e6, 0.36))
    assert soft == pytest.approx(scene_delta_max(100e6, 0.36, cfg))
    # Hertz-wall peak ~ E*^(-2/5) at fixed energy: a 4.45x softer wall indents ~1.8x deeper
    assert 1.5 < soft / soil < 2.1
