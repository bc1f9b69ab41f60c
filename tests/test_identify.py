"""What TOF, features and the whole waveform identify (ssw.calibration.information, ``ssw
identify``), against independent truth: a TOF level of one observation per hit has rank
one and, the device known, E's uncertainty is the TOF scatter over the TOF's slope (the
slope from central differences of independent runs, not the forward sensitivities); a
half-space (Hertz wall) sees E and nu only through E / (1 - nu^2), so no level separates
them, and every level identifies E once nu is known."""

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
