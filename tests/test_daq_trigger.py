"""The one trigger rule: first crossing, long-channel splitting and the streaming ring buffer.

Truth: records placed at known positions in a stream (each hit's first crossing known by
construction), and the whole-stream rule against the chunked one for random chunk sizes.
"""

from __future__ import annotations

import numpy as np
import pytest

from ssw.daq.settings import DaqSettings
from ssw.daq.simulated import sech2, trigger_index
from ssw.daq.trigger import RingTrigger, TriggerRule, crossings, split_records, trigger_starts
from ssw.errors import ConfigError, DaqError

RULE = TriggerRule(level=5.0, slope="rising", pretrigger_samples=32, record_samples=256)


def stream(starts, n=6000, seed=0, height=40.0):
    """Noise (0.05 N rms) with a two-pulse hit whose level crossing is near each of ``starts``."""
    rng = np.random.default_rng(seed)
    k = np.arange(n)
    y = rng.normal(0.0, 0.05, n)
    for s in starts:
        y += height * sech2((k - s - 4.0) / 2.0) + 0.5 * height * sech2((k - s - 60.0) / 3.0)
    return y


def test_crossing_rule_rising_and_falling():
    y = np.array([0.0, 4.0, 5.0, 6.0, 5.0, 4.0, 5.0])
    assert crossings(y, 5.0, "rising").tolist() == [2, 6]
    assert crossings(y, 5.0, "falling").tolist() == [4]


def test_split_finds_every_hit_once_with_its_pretrigger():
    starts = [500, 1500, 2600, 4000]
    y = stream(starts)
    recs = split_records(y, RULE)
    assert len(recs) == len(starts)  # the reflected pulse inside a record is not a new hit
    k = RULE.pretrigger_samples
    for r in recs:
        assert r.size == RULE.record_samples
        assert r[k - 1] < RULE.level <= r[k]  # the crossing sits at the pretrigger index
    # the level (5 N of 40 N) is crossed within 4 samples before each pulse's peak
    got = np.array(trigger_starts(y, RULE)) + k
    assert np.all((got > np.array(starts)) & (got <= np.array(starts) + 4))


def test_first_trigger_is_the_simulated_backends_rule():
    s = DaqSettings(trigger_level=5.0, pretrigger_samples=32, record_samples=256)
    y = stream([700, 3000])
    assert trigger_index(y, s) == trigger_starts(y, RULE)[0] + 32
    with pytest.raises(DaqError, match="no trigger"):
        trigger_index(np.zeros(1000), s)


def test_hit_too_close_to_the_stream_ends_is_skipped():
    y = stream([2000, 5900])  # no room for a record after the last
    y[:20] += 40.0 * sech2((np.arange(20) - 10.0) / 2.0)  # no pretrigger before this one
    starts = trigger_starts(y, RULE)
    assert len(starts) == 1 and 1990 < starts[0] + RULE.pretrigger_samples <= 2004


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_ring_buffer_gives_the_whole_stream_records_for_any_chunking(seed):
    rng = np.random.default_rng(seed)
    starts = np.sort(rng.choice(np.arange(300, 19000, 400), 12, replace=False))
    y = stream(starts, n=20000, seed=seed)
    ref = split_records(y, RULE)
    ring = RingTrigger(RULE, capacity=2 * RULE.record_samples)
    out, i = [], 0
    while i < y.size:  # chunks from 1 sample to 1.5 records, crossing every boundary
        n = int(rng.integers(1, 384))
        out += ring.feed(y[i : i + n])
        i += n
    assert ring.samples_seen == y.size
    assert len(out) == len(ref) == len(starts)
    for a, b in zip(out, ref, strict=True):
        np.testing.assert_array_equal(a, b)


def test_rule_checks():
    with pytest.raises(ConfigError, match="trigger_slope"):
        TriggerRule(5.0, "up")
    with pytest.raises(ConfigError, match="ring buffer"):
        RingTrigger(RULE, capacity=RULE.record_samples)
