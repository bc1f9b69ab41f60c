"""The device design's evaluation (ssw.design.device_eval): the thesis device among the
candidates has the TOF and dTOF/dE that ``ssw tof`` prints for it; a device scaled in every
length (no gravity) has its TOF scaled by the same factor (Hertz contact is scale-free,
Johnson 1985 sec. 4.2: F ~ E* R^1/2 d^3/2, masses ~ R^3, so t ~ R at one impact speed);
the DAQ noise's TOF scatter of a sampled peak agrees with a Monte Carlo of the peak picker.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from ssw.cli import main

ROOT = Path(__file__).resolve().parents[1]
CONFIG = str(ROOT / "config" / "config.yaml")
#: Round-off between a batched and a separate run of the same scene (ssw.chain.integrate).
SAME_RTOL = 1e-9
#: The similarity check's tolerance (the statement: within 0.1 %).
SIMILARITY_RTOL = 1e-3


@pytest.fixture(scope="module")
def setting():
    from ssw.chain.params import chain_params, numerics_of
    from ssw.config import device_of, library, load_config

    cfg = load_config(CONFIG)
    dev = device_of(cfg)
    mats = library(cfg)
    params = chain_params(dev, mats, **numerics_of(cfg))
    return cfg, dev, mats, params


def _evaluate(setting, items, moduli=2, **kw):
    from ssw.design.device_eval import evaluate
    from ssw.design.device_spec import DeviceSpec

    cfg, dev, mats, params = setting
    spec = DeviceSpec((20e6, 200e6), 0.3, moduli=moduli)
    return evaluate(items, spec, mats, dict(cfg.get("contact", {})), params.bead_radius,
                    dev.full_scale_force, own_step=True, **kw)


def test_thesis_device_is_what_ssw_tof_gives(setting, capsys):
    from ssw.design.space import point_of

    _, dev, mats, params = setting
    pt = point_of(params, dev.bead_material, dev.plate_material)
    assert pt.params(params, mats).striker_velocity == pytest.approx(
        params.striker_velocity, rel=1e-12)
    (c,) = _evaluate(setting, [(pt, pt.params(params, mats))])
    for E, tof, dtof in zip(c.soil_E, c.tof_E, c.dtof_dE_E, strict=True):
        assert main(["tof", "--config", CONFIG, "--calibration", "none", "--law", "fem",
                     "--soil-E", repr(float(E)), "--soil-nu", "0.3", "--derivatives",
                     "forward", "--json"]) == 0
        out = json.loads(capsys.readouterr().out)
        assert tof == pytest.approx(out["tof"], rel=SAME_RTOL)
        assert dtof == pytest.approx(out["dtof_dE"], rel=1e-7)
    # the resolution follows from them: u_TOF / (TOF |d ln TOF / d ln E|)
    sens = np.abs(c.soil_E * c.dtof_dE_E) / c.tof_E
    np.testing.assert_allclose(c.resolution_E, c.u_tof_E / (c.tof_E * sens), rtol=1e-12)


def test_scaled_device_scales_its_tof(setting):
    """Without gravity the TOF of a device scaled by 0.5 and 2 in every length (beads,
    plate thickness and diameter, the contact mesh; masses by the cube; one speed) is
    the base device's times the factor. With gravity the weight's precompression is not
    scaled alike (it goes as R^3 while the contact force goes as R^2): the check fails."""
    from ssw.design.space import point_of

    _, dev, mats, params = setting
    factors = (1.0, 0.5, 2.0)
    tofs = {}
    for gravity in (False, True):
        p = params.with_(gravity=gravity)
        pt = point_of(p, dev.bead_material, dev.plate_material)
        items = []
        for f in factors:
            q = replace(pt, bead_diameter=pt.bead_diameter * f,
                        plate_thickness=pt.plate_thickness * f,
                        plate_diameter=pt.plate_diameter * f)
            items.append((q, q.params(p, mats)))
        cs = _evaluate(setting, items)
        tofs[gravity] = [c.tof_E for c in cs]
    base = tofs[False][0]
    for f, tof in zip(factors[1:], tofs[False][1:], strict=True):
        np.testing.assert_allclose(tof, f * base, rtol=SIMILARITY_RTOL)
    g = tofs[True]
    assert np.max(np.abs(g[1] / (0.5 * g[0]) - 1.0)) > 10 * SIMILARITY_RTOL
    assert np.max(np.abs(g[2] / (2.0 * g[0]) - 1.0)) > 10 * SIMILARITY_RTOL


def test_noise_scatter_of_a_sampled_peak_matches_monte_carlo():
    """The noise's TOF scatter of a refined peak, sigma ||g|| / f_s with g the picker's
    derivative (ssw.design.sampling.picker_gain), against a Monte Carlo of the picker
    (ssw.signal.peaks.refine_peaks) on noisy samples of a Gaussian pulse."""
    from ssw.design.sampling import picker_gain
    from ssw.signal.peaks import UPSAMPLE, refine_peaks

    rate, width, sigma, n = 51200.0, 1.5e-4, 1e-3, 4000
    t = (np.arange(-40, 41) + 0.3) / rate
    y = np.exp(-0.5 * (t / width) ** 2)
    pos0, _ = refine_peaks(y[None, :], np.array([40]), UPSAMPLE)
    gain = picker_gain(y[None, :], np.array([40]), pos0)[0]
    rng = np.random.default_rng(1)
    Y = y[None, :] + sigma * rng.standard_normal((n, t.size))
    pos, _ = refine_peaks(Y, np.full(n, 40), UPSAMPLE)
    measured = np.std(pos) / rate
    # the Monte Carlo's own standard error: 1 / sqrt(2 n) ~ 1.1 %
    assert measured == pytest.approx(sigma * gain / rate, rel=0.05)


def test_stresses_at_the_walls_known_force_equal_the_traced_ones(setting):
    """peak_stresses with the fem wall's force at the indentation (what the device
    evaluation passes) gives the stresses of the traced rigid-sphere path."""
    from ssw.walls.fem import fem_wall, peak_stresses

    cfg, _, _, params = setting
    contact = dict(cfg["contact"])
    E = np.array([20e6, 200e6])
    wall = fem_wall(params, E, np.full(2, 0.3), contact=contact)
    d = np.array([1.5e-5, 3.0e-6])
    traced = peak_stresses(params, E, 0.3, d, contact=contact)
    known = peak_stresses(params, E, 0.3, d, contact=contact, force=wall.force(d))
    np.testing.assert_allclose(known.plate.peak, traced.plate.peak, rtol=1e-3)
    np.testing.assert_allclose(known.soil.peak, traced.soil.peak, rtol=1e-3)
    np.testing.assert_allclose(known.force, traced.force, rtol=1e-3)
