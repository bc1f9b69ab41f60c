"""The measurement model (ssw.daq.model) against independent truth: the FIR's response from
scipy.signal.freqz, the RC coupling's closed form, a sine's gain and delay through the
sampled model, linearity (what the derivatives rely on), quantization and clipping."""

import numpy as np
import pytest
from scipy import signal

from ssw.daq.model import (
    AC_CORNER,
    Acquisition,
    acquire,
    antialias_fir,
    digitize,
    frequency_response,
    input_delay,
    lsb_volts,
)

ACQ = Acquisition(sample_rate=51200.0, sensitivity=11.24e-3)


def test_fir_response_is_scipys_freqz_and_meets_the_mask():
    f = np.linspace(0.0, 0.5 * ACQ.sample_rate * ACQ.oversample, 4001)
    _, h = signal.freqz(antialias_fir(), worN=f, fs=ACQ.sample_rate * ACQ.oversample)
    dc = Acquisition(coupling="DC")
    ours = frequency_response(dc, f) * np.exp(2j * np.pi * f * dc.pure_delay)
    assert np.allclose(ours, h, rtol=0, atol=1e-12)
    fs = ACQ.sample_rate
    passband = np.abs(h[f <= 0.45 * fs])
    assert np.max(np.abs(20 * np.log10(passband))) < 1e-3  # flat to 1 mdB
    assert np.max(np.abs(h[f >= 0.55 * fs])) < 10 ** (-99 / 20)


def test_ac_coupling_is_a_single_pole_rc_with_its_corner():
    f = np.array([AC_CORNER, 10 * AC_CORNER, 0.1 * AC_CORNER])
    h = frequency_response(ACQ, f) * np.exp(2j * np.pi * f * ACQ.delay)
    # closed form of the RC high-pass: |H| = f / sqrt(f^2 + fc^2), phase atan(fc / f)
    expect = f / np.hypot(f, AC_CORNER)
    assert np.allclose(np.abs(h), expect, rtol=1e-9)
    assert np.allclose(np.angle(h), np.arctan(AC_CORNER / f), atol=1e-9)
    assert abs(20 * np.log10(abs(h[0])) + 10 * np.log10(2)) < 1e-9  # -3.01 dB


@pytest.mark.parametrize("freq", [500.0, 5000.0, 20000.0])
def test_a_sine_through_the_sampled_model_has_the_stated_gain_and_delay(freq):
    """A cosine from t = 0 through acquire(): after the coupling's transient, sample k equals
    |H| cos(2 pi f t_k + arg H) with the closed-form H (delay 38.4/f_s + 4.5 us)."""
    acq = Acquisition(sample_rate=51200.0, coupling="DC")
    tk0 = np.array([2e-3 + 0.37 / acq.sample_rate])  # an arbitrary clock phase
    n = 200
    y = acquire(acq, lambda s: np.cos(2 * np.pi * freq * s), tk0, n)[:, 0]
    tk = tk0[0] + np.arange(n) / acq.sample_rate
    # independent: a pure delay of the module's stated input delay, unit gain in passband
    expect = np.cos(2 * np.pi * freq * (tk - input_delay(acq.sample_rate)))
    assert np.max(np.abs(y - expect)) < 2e-5


def test_gain_and_linearity_carry_derivatives_through():
    """The model is linear: A(a x1 + b x2) = a A x1 + b A x2, and the gain scales."""
    t0 = np.array([1e-3, 1.3e-3])
    x1 = lambda s: np.exp(-((s - 2e-3) / 1e-4) ** 2)  # noqa: E731
    x2 = lambda s: np.sin(3e3 * s) * (s > 0)  # noqa: E731
    both = lambda s: 2.0 * x1(s) - 0.5 * x2(s)  # noqa: E731
    y1 = acquire(ACQ, x1, t0, 300, start=0.0)
    y2 = acquire(ACQ, x2, t0, 300, start=0.0)
    y = acquire(ACQ, both, t0, 300, start=0.0, gain=1.5)
    assert np.allclose(y, 1.5 * (2.0 * y1 - 0.5 * y2), atol=1e-12)


def test_digitize_quantizes_at_24_bits_and_clips_at_the_rails():
    lsb_n = lsb_volts() / ACQ.sensitivity
    assert lsb_volts() == pytest.approx(10.0 / 2**24)
    y = np.array([0.0, 0.4 * lsb_n, 0.6 * lsb_n, 1e3, -1e3, 100.0])
    q, rails = digitize(ACQ, y)
    assert q[1] == 0.0 and q[2] == pytest.approx(lsb_n)
    assert np.all(np.abs(q - y)[[0, 1, 2, 5]] <= 0.5 * lsb_n + 1e-15)
    full = 5.0 / ACQ.sensitivity  # 445 N
    assert q[3] == pytest.approx(full, rel=1e-6) and q[4] == pytest.approx(-full, rel=1e-6)
    assert rails.tolist() == [False, False, False, True, True, False]


def test_noise_floor_is_the_modules_and_is_white():
    rng = np.random.default_rng(1)
    q, _ = digitize(ACQ, np.zeros(200000), rng)
    assert ACQ.noise == pytest.approx(50e-6 / 11.24e-3)
    assert np.std(q) == pytest.approx(ACQ.noise, rel=0.01)
    assert abs(np.corrcoef(q[:-1], q[1:])[0, 1]) < 0.01
