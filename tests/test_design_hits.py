"""The design's hit check (ssw.design.hits_check): a yielding sample struck through a
candidate plate, at the soil where the candidate's elastic yield index is largest, with the
design's soil strength. A stiffer plate spreads the bead's load: less permanent set; the set
grows from hit to hit while each hit dissipates less (shakedown)."""

from __future__ import annotations

from pathlib import Path

import pytest

from ssw.design.hits_check import hits_check
from ssw.design.spec import DesignSpec
from ssw.errors import ConfigError

CONFIG = str(Path(__file__).resolve().parents[1] / "config" / "config.yaml")


def _candidate(material: str, thickness: float) -> dict:
    return {"material": material, "thickness": thickness, "plate_diameter": 49.5e-3,
            "striker_velocity": 0.5, "source": "search", "soil_E": [20e6, 63e6, 200e6],
            "soil_yield_E": [1.0, 3.0, 2.0]}


def test_hits_through_a_soft_and_a_stiff_plate():
    from ssw.chain.params import chain_params, numerics_of
    from ssw.config import device_of, library, load_config

    cfg = load_config(CONFIG)
    mats = library(cfg)
    params = chain_params(device_of(cfg), mats, **numerics_of(cfg))
    spec = DesignSpec(soil_E=(20e6, 200e6), soil_nu=0.3, moduli=3)
    soft = hits_check(spec, params, mats, _candidate("pla", 0.4e-3), hits=3)
    stiff = hits_check(spec, params, mats, _candidate("al6061", 1.0e-3), hits=3)
    for chk in (soft, stiff):
        assert chk["soil_E"] == 63e6  # the soil of the largest elastic index
        assert chk["yield_stress"] == pytest.approx(spec.soil_strength_ratio * 63e6)
        assert len(chk["drift"]) == 2
    sets = [h["permanent_set"] for h in soft["hits"]]
    lost = [h["dissipated"] for h in soft["hits"]]
    assert 0 < sets[0] < sets[1] < sets[2]
    assert lost[0] > lost[1] > lost[2] > 0
    # 1 mm of aluminium spreads the load below yield (under the 0.4 mm PLA it yields)
    assert stiff["hits"][-1]["permanent_set"] < 0.1 * sets[-1]
    with pytest.raises(ConfigError, match="plastic-hits"):
        hits_check(spec, params, mats, _candidate("pla", 0.4e-3), hits=1)


def test_plastic_hits_refused_with_merge(capsys):
    """``--plastic-hits`` strikes the plates of one design run: with ``--merge`` it is
    refused by name, not ignored."""
    from ssw.cli import main

    assert main(["design", "--merge", "a.json", "--plastic-hits", "3"]) != 0
    assert "--plastic-hits" in capsys.readouterr().err
