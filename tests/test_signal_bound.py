"""The shortest physical round trip, and peak picking that cannot return a wrong peak silently.

Truth: Hertz's linearized contact stiffness (the sound speed of a precompressed chain,
c_0 = a sqrt(k/m), k = 3/2 A^(2/3) F_0^(1/3)); the chain model's TOF on its stiffest walls
(a wave cannot come back sooner than from a rigid wall); analytic records whose pulses
sit at known times.
"""

from __future__ import annotations

import numpy as np
import pytest

from ssw.chain.params import ChainParams
from ssw.daq.simulated import sech2
from ssw.errors import ConfigError
from ssw.signal.peaks import PeakError, PeakRule, check_tof, pick_peaks
from ssw.signal.tof import (
    SPEED_COEFFICIENT,
    ChainPath,
    TofOptions,
    session_tof,
    shortest_round_trip,
    solitary_wave_speed,
)
from ssw.tof import api

STEEL = {"bead_radius": 9.525e-3, "bead_E": 200e9, "bead_nu": 0.28, "bead_density": 7810.0}
RATE = 51200.0


@pytest.mark.parametrize("F0", [1.0, 5.5, 50.0])
def test_weak_wave_limit_is_the_hertz_sound_speed(F0):
    """f_r -> 1: Daraio's precompressed speed is c_0 of the linearized Hertz chain."""
    R, E, nu, rho = STEEL.values()
    A = E * np.sqrt(2 * R) / (3 * (1 - nu**2))  # bead-bead Hertz coefficient (N/m^1.5)
    m = 4 / 3 * np.pi * R**3 * rho
    c0 = 2 * R * np.sqrt(1.5 * A ** (2 / 3) * F0 ** (1 / 3) / m)
    assert solitary_wave_speed(1e-9, **STEEL, static_force=F0) == pytest.approx(c0, rel=1e-4)


def test_strong_wave_limit_is_the_uncompressed_law():
    """f_r -> inf: the precompressed law tends to V_s = 0.6802 X F_m^(1/6)."""
    R, E, nu, rho = STEEL.values()
    x = (2 * E / (2 * R * rho**1.5 * (1 - nu**2))) ** (1 / 3)
    v0 = solitary_wave_speed(1e6, **STEEL)
    assert v0 == pytest.approx(SPEED_COEFFICIENT * x * 1e6 ** (1 / 6), rel=1e-12)
    assert solitary_wave_speed(1e6 - 1e-3, **STEEL, static_force=1e-3) == pytest.approx(
        v0, rel=2e-4)
    # precompression only speeds a wave up
    assert solitary_wave_speed(100.0, **STEEL, static_force=5.0) > solitary_wave_speed(
        105.0, **STEEL)


def test_round_trip_path_and_checks():
    """L = (2 n + 1) R: the sensor's lower half and n whole beads, there and back."""
    v = solitary_wave_speed(3.2 * 100.0, **STEEL)
    assert shortest_round_trip(9, **STEEL, force=100.0) == pytest.approx(
        2 * 19 * STEEL["bead_radius"] / v, rel=1e-12)
    with pytest.raises(ConfigError, match="beads_below"):
        shortest_round_trip(2.5, **STEEL, force=100.0)
    with pytest.raises(ConfigError, match="force"):
        shortest_round_trip(9, **STEEL, force=0.0)


DEVICES = [{}, {"n_beads": 12, "sensor_index": 9}, {"striker_velocity": 0.05, "preload": 50.0},
           {"gravity": False, "striker_velocity": 3.0}]


@pytest.mark.parametrize("kw", DEVICES)
def test_bound_is_below_every_tof_the_chain_gives_even_on_a_rigid_wall(kw):
    """The stiffest walls return the wave soonest; the bound stays under them, and is not
    vacuous (within 25 % of the rigid wall's TOF)."""
    p = ChainParams(**kw)
    path = ChainPath.from_params(p)
    for wall, E in (("rigid", 1e9), ("hertz", 200e9), ("hertz", 1e9), ("hertz", 38e6)):
        _, F = api.sensor_signal(E, 0.3, p, wall)
        tof = float(api.tof(E, 0.3, p, wall))
        bound = path.min_tof(float(np.max(F - F[0])))
        assert bound < tof, (kw, wall, E)
        if wall == "rigid":
            assert tof < 1.25 * bound


def test_the_recorded_force_alone_is_not_a_bound_on_a_stiff_wall():
    """Why WALL_AMPLIFICATION: at the recorded force and without the static load, V_s gives
    a 'shortest' TOF longer than the chain's on a rigid wall (overlapping waves run faster)."""
    p = ChainParams()
    _, F = api.sensor_signal(1e9, 0.3, p, "rigid")
    naive = shortest_round_trip(9, **STEEL, force=float(np.max(F - F[0])), amplification=1.0)
    assert float(api.tof(1e9, 0.3, p, "rigid")) < naive


def record(t_peaks, heights, widths=None, duration=4e-3):
    t = np.arange(int(duration * RATE)) / RATE
    y = np.zeros_like(t)
    for tp, h, w in zip(t_peaks, heights, widths or [40e-6] * len(t_peaks), strict=True):
        y += h * sech2((t - tp) / w)
    return y


def test_a_ripple_before_the_bound_is_not_taken_for_the_reflection():
    """An incident ripple (0.3 ms after it, larger than the reflection): the plain rule picks
    it (TOF 0.3 ms, a wrong number); with the bound the reflection at 1.46 ms is taken."""
    y = record([1e-3, 1.3e-3, 2.46e-3], [60.0, 20.0, 12.0])
    wrong = pick_peaks(y, RATE, 0.0, PeakRule(), min_tof=None)
    assert wrong.tof == pytest.approx(0.3e-3, abs=1e-6)
    right = pick_peaks(y, RATE, 0.0, PeakRule(), min_tof=0.6e-3)
    assert right.tof == pytest.approx(1.46e-3, abs=0.01 / RATE)  # a hundredth of a sample


def test_a_pulse_straddling_the_bound_is_an_error_naming_both_numbers():
    y = record([1e-3, 1.62e-3], [60.0, 30.0], widths=[40e-6, 80e-6])
    with pytest.raises(PeakError, match=r"TOF 0\.62\d* ms, just before the shortest physical "
                                        r"round trip 0\.6400 ms"):
        pick_peaks(y, RATE, 0.0, PeakRule(), min_tof=0.64e-3)


def test_a_refined_tof_below_the_bound_is_an_error():
    """The reflected peak 0.2 sample before the bound, at sample 113.7: its largest sample
    (114) is the first one past the bound (113.9), the refined vertex is not."""
    ti, tof = 52.0 / RATE, 61.7 / RATE
    y = record([ti, ti + tof], [60.0, 30.0])
    with pytest.raises(PeakError, match=r"TOF 1\.2051 ms is shorter than the shortest physical "
                                        r"round trip sensor -> wall -> sensor, 1\.2090 ms"):
        pick_peaks(y, RATE, 0.0, PeakRule(), min_tof=tof + 0.2 / RATE)
    assert check_tof(1.3e-3, 1.2e-3) == 1.3e-3


def test_session_rejects_a_hit_faster_than_physics_and_says_why():
    good = record([1.5e-3, 2.96e-3], [60.0, 25.0])
    early = record([1.5e-3, 1.9e-3], [60.0, 25.0])
    res = session_tof([good, early, good, good], RATE, 64, opts=TofOptions(min_tof=0.6e-3))
    assert res.accepted.tolist() == [True, False, True, True]
    assert "shortest physical round trip 0.6000 ms" in res.reasons[0]
    assert res.mean == pytest.approx(1.46e-3, abs=0.01 / RATE)


def test_options_take_the_larger_of_a_fixed_and_the_chains_bound():
    path = ChainPath.from_params(ChainParams())
    assert path.beads_below == 9 and path.static_force == pytest.approx(
        20 * ChainParams().bead_mass * 9.80665)
    opts = TofOptions(min_tof=1e-4, chain=path)
    assert opts.bound(200.0) == path.min_tof(200.0) > 1e-4
    assert TofOptions(min_tof=1e-2, chain=path).bound(200.0) == 1e-2
    assert TofOptions().bound(200.0) is None
