"""What TOF, features and the whole waveform identify (ssw.calibration.information, ``ssw
identify``), against independent truth: a TOF level of one observation per hit has rank
one and, the device known, E's uncertainty is the TOF scatter over the TOF's slope (the
slope from central differences of independent runs, not the forward sensitivities); a
half-space (Hertz wall) sees E and nu only through E / (1 - nu^2), so no level separates
them, and every level identifies E once nu is known; the contact dissipation is the
coefficient of the device's law, in the law's unit and scale (its TOF-level column the
TOF's slope in that coefficient, from central differences of independent runs)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ssw.calibration.information import IDENTIFIED_U, identifiability
from ssw.chain.params import ChainParams
from ssw.cli import main
from ssw.daq.settings import DaqSettings
from ssw.tof import api

E, NU, SCATTER, HITS = 123e6, 0.33, 1.53e-5, 5


@pytest.fixture(scope="module")
def hertz():
    return identifiability(ChainParams(), "hertz", {}, E, NU, DaqSettings(), hits=HITS,
                           tof_scatter=SCATTER)


def test_tof_level_has_rank_one_and_the_scatter_over_the_slope(hertz):
    sv = hertz.levels["tof"].singular_values
    assert sv[0] > 0 and np.all(sv[1:] == 0)
    h = 1e-3
    T = np.asarray(api.tof(E * np.exp(np.array([-2, -1, 1, 2]) * h), NU, ChainParams(),
                           "hertz"), float)
    slope = (T[0] - 8 * T[1] + 8 * T[2] - T[3]) / (12 * h)  # dTOF / d ln E, s
    expect = SCATTER / abs(slope) / np.sqrt(HITS)
    got = hertz.device_known["tof"].std[0]
    assert got == pytest.approx(expect, rel=1e-3)


def test_a_half_space_sees_only_e_over_one_minus_nu_squared(hertz):
    for level in ("tof", "features", "waveform"):
        info = hertz.levels[level]
        assert "E" not in info.identified and "nu" not in info.identified, level
        assert not np.isfinite(info.std[info.names.index("E")]), level
    for level in ("features", "waveform"):
        assert "E" in hertz.nu_known[level].identified, level
    # more information never identifies less
    for view in (hertz.levels, hertz.nu_known):
        assert set(view["tof"].identified) <= set(view["features"].identified)
        assert set(view["features"].identified) <= set(view["waveform"].identified)
    for info in hertz.nu_known.values():
        ok = [n for n, s in zip(info.names, info.std, strict=True) if s <= IDENTIFIED_U]
        assert tuple(ok) == info.identified


def test_identify_cli_states_its_criterion(capsys):
    assert main(["identify", "--soil-E", "123e6", "--soil-nu", "0.33", "--wall", "hertz",
                 "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["wall"] == "hertz" and "marginal standard uncertainty" in r["criterion"]
    assert set(r["levels"]) == {"tof", "features", "waveform"}
    for level in r["levels"].values():
        assert len(level["singular_values"]) == 8 and len(level["correlation"]) == 8
    assert r["noise"]["tof_scatter"] == pytest.approx(SCATTER)



def test_the_contact_dissipation_is_the_laws_coefficient_in_its_own_unit():
    """With Kuwabara-Kono contacts the report states the dissipation in N s/m^1.5 on the
    law's scale (1.5e3 N s/m^1.5: the criterion's tenth is 150 N s/m^1.5), and the TOF
    level's rank-one row holds the TOF's slope in that coefficient times the scale,
    ``sigma |v_c| scatter / sqrt(hits) = |dTOF/dc| scale``, the slope from fourth-order
    central differences of TOFs of independent runs (within 1e-4); ``--damping-law``
    reaches the command's chain."""
    import argparse

    from ssw.chain.dissipation import LAWS
    from ssw.cli._device import add_device_options, chain_context

    law, c = LAWS["kuwabara_kono"], 1.5e3
    p = ChainParams(damping=c, damping_law=law.name)
    res = identifiability(p, "hertz", {}, E, NU, DaqSettings(), hits=HITS,
                          tof_scatter=SCATTER)
    r = res.as_dict()
    assert r["damping_law"] == law.name and r["units"]["damping"] == law.unit
    assert r["coordinates"]["damping"] == f"linear, scale {law.scale:g} {law.unit}"
    assert f"{0.1 * law.scale:g} {law.unit}" in r["criterion"]
    assert law.formula in r["labels"]["damping"]
    tof = res.levels["tof"]
    j = tof.names.index("damping")
    got = tof.singular_values[0] * abs(tof.vectors[j, 0]) * SCATTER / np.sqrt(HITS)
    h = 1e-3 * c
    T = [float(api.tof(E, NU, p.with_(damping=c + o * h), "hertz")) for o in (-2, -1, 1, 2)]
    slope = (T[0] - 8 * T[1] + 8 * T[2] - T[3]) / (12 * h)  # s per N s/m^1.5
    assert got == pytest.approx(abs(slope) * law.scale, rel=1e-4)
    parser = argparse.ArgumentParser()
    add_device_options(parser)
    args = parser.parse_args(["--damping-law", law.name, "--damping", str(c),
                              "--calibration", "none", "--wall", "hertz"])
    ctx = chain_context(args, E, NU)
    assert (ctx.params.damping_law, ctx.params.damping) == (law.name, c)
