"""Acquisition settings: the ``daq:`` section of the config as a frozen, checked dataclass.

The checks encode the NI 9234 (C Series sound and vibration module) and the PCB 208C02
IEPE force sensor the thesis used (Torres Constante 2024, Stage III; REFERENCE.md):

* sample rate ``f_s = (13.1072 MHz / 256) / n = 51200 / n`` S/s, ``n = 1..31``
  (internal master timebase; NI 9234 specifications, "Data rates");
* input range +-5 V; the sensor range times its sensitivity must fit in it, otherwise
  every full-scale hit clips;
* IEPE excitation 2 mA (or 0 = off), and only with AC coupling (the module switches the
  excitation off in DC coupling).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

from ssw.errors import ConfigError

NI9234_BASE_RATE = 13.1072e6 / 256  # S/s, 51200: master timebase / 256 (NI 9234 specs)
NI9234_MAX_DIVISOR = 31  # rate divisor n = 1..31 (NI 9234 specs)
NI9234_RANGE_V = 5.0  # V, input range +-5 V (NI 9234 specs)
NI9234_BITS = 24  # delta-sigma ADC resolution (NI 9234 specs)
NI9234_IEPE_A = 0.002  # A, the only IEPE excitation current the module supplies
RATE_RTOL = 1e-9  # relative tolerance when matching a rate to 51200/n
TRIGGER_MODES = ("auto", "hardware", "software")


def allowed_rates() -> list[float]:
    """The NI 9234's sample rates with the internal timebase, S/s, fastest first.

    Returns
    -------
    list of float
        ``51200 / n`` for n = 1 .. 31, S/s.
    """
    return [NI9234_BASE_RATE / n for n in range(1, NI9234_MAX_DIVISOR + 1)]


def rate_divisor(rate: float) -> int:
    """The divisor ``n`` with ``rate = 51200 / n``; :class:`.ConfigError` if none matches.

    Parameters
    ----------
    rate : float
        The sample rate, S/s.

    Returns
    -------
    int
        The NI 9234 divisor, 1 to 31.

    Raises
    ------
    ssw.errors.ConfigError
        When no divisor gives ``rate`` within ``RATE_RTOL``.
    """
    n = round(NI9234_BASE_RATE / rate) if rate > 0 else 0
    if 1 <= n <= NI9234_MAX_DIVISOR and abs(NI9234_BASE_RATE / n - rate) <= RATE_RTOL * rate:
        return n
    raise ConfigError(
        "daq.sample_rate",
        rate,
        "an NI 9234 rate 51200/n S/s with n = 1..31 (51200, 25600, 17066.67, 12800, ... "
        f"{NI9234_BASE_RATE / NI9234_MAX_DIVISOR:.2f})",
    )


@dataclass(frozen=True)
class SimulationSettings:
    """Imperfections the simulated backend adds (``daq.simulation``), SI units.

    Parameters
    ----------
    noise_rms : float
        Additive white noise at the sensor, N (rms).
    trigger_jitter : float
        Standard deviation of the random delay between the wave and the sample clock
        beyond the uniform sample phase, s.
    source : str
        Waveform source: ``chain`` (``ssw.tof.api.sensor_signal``) or ``analytic`` (two
        sech^2 pulses with a known TOF, for tests without the chain).
    striker_velocity_cov : float
        Relative standard deviation of the striker speed from hit to hit (chain source
        only; 0 = every hit identical). A physical scatter: the TOF goes
        as ``F_m^(-1/6)`` and ``F_m`` as ``v^(6/5)``, so TOF ~ ``v^(-1/5)`` and a 5 %
        speed scatter gives ~1 % TOF scatter.
    """

    noise_rms: float = 0.05
    trigger_jitter: float = 2.0e-6
    source: str = "chain"
    striker_velocity_cov: float = 0.0


@dataclass(frozen=True)
class DaqSettings:
    """One force channel of an NI 9234 in a cDAQ chassis, from config ``daq:`` (SI units).

    ``sensitivity`` is in V/N (NI-DAQmx takes mV/N: :attr:`sensitivity_mv_per_n`);
    ``trigger_level`` and ``max_force`` are in N. ``trigger_mode``: ``hardware`` (an analog
    reference trigger in the module), ``software`` (continuous acquisition, the same rule
    over a ring buffer: :mod:`ssw.daq.trigger`) or ``auto`` (hardware where the module can
    source it, else software).

    Parameters
    ----------
    device : str
        The NI-DAQmx name of the module.
    channel : str
        The module's channel (``ai0`` .. ``ai3``).
    sensor_model : str
        The force sensor's model.
    sensitivity : float
        The sensor's sensitivity, V/N.
    excitation_current : float
        The IEPE excitation current, A.
    coupling : str
        ``AC`` or ``DC``.
    sample_rate : float
        The sample rate, S/s (``51200 / n``).
    max_force : float
        The sensor's range, N.
    trigger_level : float
        The trigger level, N.
    trigger_slope : str
        ``rising`` or ``falling``.
    pretrigger_samples : int
        Samples kept before the trigger.
    record_samples : int
        Samples per record.
    hits : int
        Hits per session.
    timeout : float
        How long to wait for a trigger, s.
    trigger_mode : str
        ``hardware``, ``software`` or ``auto``.
    simulation : SimulationSettings
        What the simulated backend adds.
    """

    device: str = "cDAQ1Mod1"
    channel: str = "ai0"
    sensor_model: str = "PCB 208C02"
    sensitivity: float = 11.24e-3
    excitation_current: float = NI9234_IEPE_A
    coupling: str = "AC"
    sample_rate: float = NI9234_BASE_RATE
    max_force: float = 445.0
    trigger_level: float = 5.0
    trigger_slope: str = "rising"
    pretrigger_samples: int = 256
    record_samples: int = 2048
    hits: int = 10
    timeout: float = 60.0
    trigger_mode: str = "auto"
    simulation: SimulationSettings = field(default_factory=SimulationSettings)

    def __post_init__(self) -> None:
        check_settings(self)

    @property
    def physical_channel(self) -> str:
        """NI-DAQmx physical channel name, e.g. ``cDAQ1Mod1/ai0``."""
        return f"{self.device}/{self.channel}"

    @property
    def sensitivity_mv_per_n(self) -> float:
        """Sensitivity in mV/N, the unit NI-DAQmx's force IEPE channel takes."""
        return self.sensitivity * 1e3

    @property
    def full_scale_force(self) -> float:
        """Force at the module's +-5 V limit, N: ``5 V / sensitivity``."""
        return NI9234_RANGE_V / self.sensitivity

    @property
    def dt(self) -> float:
        """Sample period, s."""
        return 1.0 / self.sample_rate

    def to_dict(self) -> dict[str, Any]:
        """Plain dict (for metadata and ``--json``).

        Returns
        -------
        dict
            Field name -> value (SI units; ``simulation`` as a dict).
        """
        return asdict(self)


def check_finite(s: DaqSettings) -> None:
    """Raise :class:`.ConfigError` naming ``daq.<field>`` (or ``daq.simulation.<field>``)
    for a number of ``s`` that is NaN or infinite.

    Settings built in code do not pass the config schema, which refuses them; NaN passes
    every bound of :func:`check_settings` (a NaN sensitivity would never detect clipping,
    an infinite timeout would wait forever).

    Parameters
    ----------
    s : DaqSettings
        The settings.
    """
    import math
    from dataclasses import fields

    for prefix, obj in (("daq", s), ("daq.simulation", s.simulation)):
        for f in fields(obj):
            v = getattr(obj, f.name)
            if isinstance(v, int | float) and not isinstance(v, bool) and not math.isfinite(v):
                raise ConfigError(f"{prefix}.{f.name}", v,
                                  "a finite number (NaN and infinities are refused)")


def check_settings(s: DaqSettings) -> None:
    """Raise :class:`.ConfigError` unless ``s`` is a configuration the NI 9234 accepts.

    Parameters
    ----------
    s : DaqSettings
        The settings; every number finite (:func:`check_finite`), then the module's rules.
    """
    check_finite(s)
    rate_divisor(s.sample_rate)
    if s.coupling not in ("AC", "DC"):
        raise ConfigError("daq.coupling", s.coupling, "AC or DC")
    if s.excitation_current not in (0.0, NI9234_IEPE_A):
        raise ConfigError(
            "daq.excitation_current", s.excitation_current,
            "0 (off) or 0.002 A: the NI 9234 supplies 2 mA IEPE excitation only",
        )
    if s.excitation_current > 0 and s.coupling != "AC":
        raise ConfigError(
            "daq.coupling", s.coupling,
            "AC when IEPE excitation is on: the NI 9234 supplies IEPE current only in AC coupling",
        )
    if s.sensitivity <= 0:
        raise ConfigError("daq.sensitivity", s.sensitivity, "a positive value in V/N")
    if s.max_force <= 0:
        raise ConfigError("daq.max_force", s.max_force, "a positive force in N")
    volts = s.max_force * s.sensitivity
    if volts > NI9234_RANGE_V * (1 + 1e-3):
        raise ConfigError(
            "daq.max_force", s.max_force,
            f"at most {s.full_scale_force:.4g} N: max_force x sensitivity = {volts:.4g} V "
            f"exceeds the NI 9234's +-{NI9234_RANGE_V} V range",
        )
    if s.trigger_slope not in ("rising", "falling"):
        raise ConfigError("daq.trigger_slope", s.trigger_slope, "rising or falling")
    if s.trigger_mode not in TRIGGER_MODES:
        raise ConfigError("daq.trigger_mode", s.trigger_mode, " | ".join(TRIGGER_MODES))
    if not 0 < abs(s.trigger_level) < s.max_force:
        raise ConfigError(
            "daq.trigger_level", s.trigger_level, f"a nonzero force below max_force {s.max_force} N"
        )
    if not 2 <= s.pretrigger_samples <= s.record_samples - 2:
        raise ConfigError(
            "daq.pretrigger_samples", s.pretrigger_samples,
            f"between 2 and record_samples - 2 = {s.record_samples - 2}",
        )
    if s.hits < 1:
        raise ConfigError("daq.hits", s.hits, "at least 1")
    if s.timeout <= 0:
        raise ConfigError("daq.timeout", s.timeout, "a positive time in s")
    sim = s.simulation
    if sim.noise_rms < 0:
        raise ConfigError("daq.simulation.noise_rms", sim.noise_rms, "a nonnegative force in N")
    if sim.trigger_jitter < 0:
        raise ConfigError("daq.simulation.trigger_jitter", sim.trigger_jitter, "a nonnegative time")
    if not 0 <= sim.striker_velocity_cov < 0.5:
        raise ConfigError("daq.simulation.striker_velocity_cov", sim.striker_velocity_cov,
                          "a relative standard deviation in [0, 0.5)")
    if sim.source not in ("chain", "analytic"):
        raise ConfigError("daq.simulation.source", sim.source, "chain or analytic")


def settings_from_config(cfg: dict[str, Any], device: Any = None,
                         **overrides: Any) -> DaqSettings:
    """Build :class:`DaqSettings` from a loaded config's ``daq:`` section (the acquisition:
    module, channel, rate, trigger, hits) and the device's DAQ sensor (model, sensitivity
    V/N, range N: ``device`` or the config's, :func:`ssw.config.device_of`), plus
    overrides.

    Parameters
    ----------
    cfg : dict
        The loaded study config.
    device : ssw.device.Device or None
        The device (None: the config's).
    **overrides
        Settings that replace the config's (None values are ignored).

    Returns
    -------
    DaqSettings
        The settings (SI units).

    Raises
    ------
    ssw.errors.ConfigError
        When a key is not a setting, or a value is invalid (:class:`DaqSettings`).
    """
    from ssw.config import device_of

    dev = device if device is not None else device_of(cfg)
    raw = dict(cfg.get("daq", {}) or {})
    raw.update({"sensor_model": dev.sensor_model, "sensitivity": dev.sensitivity,
                "max_force": dev.sensor_range})
    raw.update({k: v for k, v in overrides.items() if v is not None})
    sim_raw = raw.pop("simulation", {}) or {}
    known = set(DaqSettings.__dataclass_fields__)
    unknown = sorted(set(raw) - known)
    if unknown:
        raise ConfigError(f"daq.{unknown[0]}", raw[unknown[0]], f"one of {sorted(known)}")
    sim_known = set(SimulationSettings.__dataclass_fields__)
    bad = sorted(set(sim_raw) - sim_known)
    if bad:
        raise ConfigError(
            f"daq.simulation.{bad[0]}", sim_raw[bad[0]], f"one of {sorted(sim_known)}"
        )
    for key in ("sensitivity", "excitation_current", "sample_rate", "max_force", "trigger_level",
                "timeout"):
        if key in raw:
            raw[key] = float(raw[key])
    for key in ("noise_rms", "trigger_jitter", "striker_velocity_cov"):
        if key in sim_raw:
            sim_raw[key] = float(sim_raw[key])
    return DaqSettings(**raw, simulation=SimulationSettings(**sim_raw))
