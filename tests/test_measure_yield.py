"""A measurement's yield index: the sample's peak von Mises stress under the bead at the
hit's peak, over its strength, checked against Hertz's field (Johnson 1985, sec. 6.1)."""

from __future__ import annotations

import numpy as np
import pytest

from ssw.chain.params import chain_params
from ssw.device import load_device
from ssw.errors import ConfigError
from ssw.hertz import effective_modulus
from ssw.materials import Strength, material_set
from ssw.measure import uniaxial_strength, yield_check

NUM = {"steps_per_contact": 60}


def _hertz_axis_peak(nu: float) -> float:
    """max over depth of sigma_vM / p0 on the axis of a Hertz contact (Johnson 1985,
    eqs. 3.45): sigma_z = -p0 / (1 + z^2), sigma_r = -p0 ((1 + nu)(1 - z atan(1/z))
    - 1 / (2 (1 + z^2))), z in units of the contact radius."""
    z = np.linspace(1e-4, 3.0, 300001)
    sz = -1.0 / (1.0 + z * z)
    sr = -((1.0 + nu) * (1.0 - z * np.arctan(1.0 / z)) - 0.5 / (1.0 + z * z))
    return float(np.max(sr - sz))


@pytest.mark.parametrize("E", [40e6, 400e6])
def test_without_a_plate_the_index_is_hertzs_first_yield_field(E):
    """No plate: the chain's peak wall force F on the soil, with the steel bead's own
    compliance, gives Hertz's p0 = (6 F E*^2 / (pi^3 R^2))^(1/3) (E* of bead and soil); the
    soil's peak von Mises stress is 0.620 p0 at nu 0.3 (Johnson). Within 2 %."""
    mats = material_set()
    p = chain_params(load_device("thesis"), mats, **NUM).with_(plate_thickness=0.0)
    nu = 0.3
    r = yield_check(E, nu, p, None, strength=1.0e6)
    F = r["peak_wall_force"]
    Es = float(effective_modulus(E, nu, p.bead_E, p.bead_nu))
    p0 = np.cbrt(6.0 * F * Es**2 / (np.pi**3 * p.bead_radius**2))
    expected = _hertz_axis_peak(nu) * p0
    assert _hertz_axis_peak(nu) == pytest.approx(0.620, abs=0.002)
    assert r["sample_peak_von_mises"] == pytest.approx(expected, rel=0.02)
    assert r["yield_index"] == pytest.approx(r["sample_peak_von_mises"] / 1.0e6)
    assert r["sample_yielded"] == (r["yield_index"] >= 1.0)


def test_a_plate_spreads_the_load_and_lowers_the_index():
    """The thesis's 0.4 mm PLA plate over a 40 MPa soil: the soil's peak stress is below
    the bare soil's under the same device (the plate spreads the bead's force)."""
    mats = material_set()
    p = chain_params(load_device("thesis"), mats, **NUM)
    with_plate = yield_check(40e6, 0.3, p, None, strength=1.0e6)
    bare = yield_check(40e6, 0.3, p.with_(plate_thickness=0.0), None, strength=1.0e6)
    assert with_plate["sample_peak_von_mises"] < bare["sample_peak_von_mises"]


def test_uniaxial_strength_of_a_library_entry():
    """Yield stress first, then the compressive strength, then Mohr-Coulomb's unconfined
    compressive strength 2 c cos(phi) / (1 - sin(phi)) (c 50 kPa, phi 30 deg: 173.2 kPa)."""
    assert uniaxial_strength(Strength(yield_stress=2e6, compressive=1e6)) == 2e6
    assert uniaxial_strength(Strength(compressive=1e6)) == 1e6
    assert uniaxial_strength(Strength(cohesion=50e3, friction_angle=30.0)) == pytest.approx(
        50e3 * 2 * np.sqrt(3) / 2 / 0.5)
    assert uniaxial_strength(Strength()) is None
    p = chain_params(load_device("thesis"), material_set(), **NUM)
    with pytest.raises(ConfigError, match="sample strength"):
        yield_check(40e6, 0.3, p, None, strength=-1.0)
