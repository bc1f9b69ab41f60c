"""NI 9234 / PCB 208C02 settings checks (NI 9234 specifications; REFERENCE.md)."""

from __future__ import annotations

import pytest

from ssw.config import load_config
from ssw.daq.settings import DaqSettings, allowed_rates, rate_divisor, settings_from_config
from ssw.errors import ConfigError


def test_allowed_rates_are_the_timebase_over_256_n():
    rates = allowed_rates()
    assert len(rates) == 31
    assert rates[0] == 51200.0  # 13.1072 MHz / 256
    assert rates[-1] == pytest.approx(1651.6129, rel=1e-6)  # 51200/31, "1.652 kS/s"
    assert rate_divisor(51200.0 / 7) == 7


@pytest.mark.parametrize("rate", [50000.0, 51200.0 / 32, 102400.0, 0.0])
def test_rates_the_module_cannot_make_are_rejected(rate):
    with pytest.raises(ConfigError, match=r"daq.sample_rate.*51200/n"):
        DaqSettings(sample_rate=rate)


@pytest.mark.parametrize(("kw", "field"), [
    ({"coupling": "DC"}, "daq.coupling"),  # IEPE on in DC coupling
    ({"excitation_current": 0.004}, "daq.excitation_current"),  # nidaqmx's default 4 mA
    ({"max_force": 500.0}, "daq.max_force"),  # 500 N x 11.24 mV/N = 5.6 V > 5 V
    ({"trigger_level": 0.0}, "daq.trigger_level"),
    ({"pretrigger_samples": 2047}, "daq.pretrigger_samples"),
    ({"trigger_slope": "up"}, "daq.trigger_slope"),
])
def test_invalid_settings_name_the_field(kw, field):
    with pytest.raises(ConfigError) as err:
        DaqSettings(**kw)
    assert err.value.field == field


def test_dc_coupling_is_allowed_without_excitation():
    s = DaqSettings(coupling="DC", excitation_current=0.0)
    assert s.coupling == "DC"


def test_sensor_range_fits_the_input_range():
    """100 lbf x 50 mV/lbf: 445 N x 11.24 mV/N ~ 5 V, the NI 9234's range."""
    s = DaqSettings()
    assert s.full_scale_force == pytest.approx(5.0 / 11.24e-3)
    assert s.sensitivity_mv_per_n == pytest.approx(11.24)


def test_settings_from_the_study_config():
    cfg = load_config()
    s = settings_from_config(cfg, hits=3)
    assert s.hits == 3 and s.sample_rate == 51200.0 and s.physical_channel == "cDAQ1Mod1/ai0"
    with pytest.raises(ConfigError, match=r"daq\.bogus"):
        settings_from_config({"daq": {"bogus": 1}})


def _float_fields(cls) -> list[str]:
    from dataclasses import fields

    return [f.name for f in fields(cls) if isinstance(getattr(cls(), f.name), float)]


def test_settings_built_in_code_refuse_nan_and_infinities():
    """Every number of the settings, made NaN, +inf or -inf in code (no schema on the way):
    refused naming the field. Without it a NaN sensitivity passes every bound (clipping
    would never be detected) and an infinite timeout would wait forever."""
    from ssw.daq.settings import SimulationSettings

    bad = (float("nan"), float("inf"), float("-inf"))
    names = _float_fields(DaqSettings)
    assert {"sensitivity", "sample_rate", "timeout", "trigger_level", "max_force"} <= set(names)
    for i, name in enumerate(names):
        with pytest.raises(ConfigError, match=rf"^daq\.{name} = {bad[i % 3]!r} is not allowed"):
            DaqSettings(**{name: bad[i % 3]})
    sim = _float_fields(SimulationSettings)
    assert {"noise_rms", "trigger_jitter", "striker_velocity_cov"} <= set(sim)
    for i, name in enumerate(sim):
        with pytest.raises(ConfigError, match=rf"^daq\.simulation\.{name} = "):
            DaqSettings(simulation=SimulationSettings(**{name: bad[i % 3]}))


def test_settings_from_a_config_refuse_nan_in_overrides_and_in_the_config():
    """A command-line override and the config's daq section both refuse a NaN."""
    cfg = load_config()
    with pytest.raises(ConfigError, match=r"daq\.timeout = inf"):
        settings_from_config(cfg, timeout=float("inf"))
    raw = {**cfg, "daq": {**cfg["daq"], "trigger_level": float("nan")}}
    from ssw.config import validate_config

    with pytest.raises(ConfigError, match=r"daq\.trigger_level = nan"):
        validate_config(raw)
