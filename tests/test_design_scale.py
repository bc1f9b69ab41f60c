"""The device design at scale: the pieces that make a candidate cheap give what the direct
computation gives.

* the noise's TOF gain of the peak picker (:func:`ssw.design.sampling.picker_gain`, the
  picker's exact derivative) equals central differences of the picker itself
  (:func:`ssw.signal.peaks.refine_peaks`), sample by sample;
"""

from __future__ import annotations

import numpy as np


def test_picker_gain_is_the_pickers_derivative():
    """picker_gain against central differences of refine_peaks (step 1e-6 of the peak:
    truncation error ~1e-12 of the gain, rounding ~1e-10); rows whose window is cut by the
    record's edge, and rows whose sample is no peak (gain 0: the picker's parabola is
    clipped or convex there) included."""
    from ssw.design.sampling import picker_gain
    from ssw.signal.peaks import HALF_WINDOW, UPSAMPLE, refine_peaks

    rng = np.random.default_rng(3)
    m, n_s = 24, 70
    t = (np.arange(n_s)[None, :] - 30 - rng.uniform(-3, 3, (m, 1))) / rng.uniform(1.5, 5, (m, 1))
    s = np.exp(-0.5 * t**2) * rng.uniform(1, 100, (m, 1)) + 0.01 * rng.normal(size=(m, n_s))
    c = np.argmax(s, axis=1)
    c[:3] = [10, 12, 60]  # off the peak; the last one's window cut by the end
    pos, _ = refine_peaks(s, c, UPSAMPLE)
    gain = picker_gain(s, c, pos)
    fd = np.zeros(m)
    for i in range(m):
        h = 1e-6 * abs(s[i, c[i]])
        grad = []
        for k in range(max(c[i] - HALF_WINDOW, 0), min(c[i] + HALF_WINDOW + 1, n_s)):
            up, down = s[i].copy(), s[i].copy()
            up[k] += h
            down[k] -= h
            p = refine_peaks(np.stack([up, down]), np.array([c[i], c[i]]), UPSAMPLE)[0]
            grad.append((p[0] - p[1]) / (2 * h))
        fd[i] = np.linalg.norm(grad)
    live = fd > 0
    assert live.sum() >= m - 3
    np.testing.assert_allclose(gain[live], fd[live], rtol=1e-6)
    assert np.all(gain[~live] == 0.0)
