"""NI-DAQmx configuration against autospec'd fakes of nidaqmx's Task (no driver here).

As nidaqmx's own unit tests, the driver layer is replaced by ``create_autospec`` mocks; the
channel, timing and trigger collections are autospec'd from their classes so that a call
with a wrong argument name fails as it would on the real API.
"""

from __future__ import annotations

from unittest import mock

import numpy as np
import pytest
from nidaqmx import constants as c
from nidaqmx.system import Device
from nidaqmx.task import InStream, Task, Timing
from nidaqmx.task.collections import AIChannelCollection
from nidaqmx.task.triggering import ReferenceTrigger, Triggers

from ssw.daq.backend import get_backend, run_session
from ssw.daq.nidaq import (
    NidaqBackend,
    buffer_samples,
    check_device,
    chunk_samples,
    configure_task,
)
from ssw.daq.recording import read_recording
from ssw.daq.settings import DaqSettings
from ssw.daq.simulated import sech2
from ssw.daq.trigger import TriggerRule, split_records
from ssw.errors import DaqError, RecordingError


def fake_task(records=(), overloaded=False):
    """An autospec'd Task whose ``read`` returns ``records`` one after another."""
    task = mock.create_autospec(Task, instance=True)
    task.ai_channels = mock.create_autospec(AIChannelCollection, instance=True)
    task.timing = mock.create_autospec(Timing, instance=True)
    task.triggers = mock.create_autospec(Triggers, instance=True)
    task.triggers.reference_trigger = mock.create_autospec(ReferenceTrigger, instance=True)
    task.in_stream = mock.create_autospec(InStream, instance=True)
    task.in_stream.overloaded_chans_exist = overloaded
    task.read.side_effect = [list(r) for r in records]
    return task


def fake_device(product="NI 9234", analog=True):
    dev = mock.create_autospec(Device, instance=True)
    dev.product_type = product
    dev.serial_num = 0x1234
    dev.anlg_trig_supported = analog
    dev.ai_trig_usage = [c.TriggerUsage.START, c.TriggerUsage.REFERENCE]
    return dev


def test_configure_task_channel_timing_trigger_calls():
    s = DaqSettings(sample_rate=25600.0, pretrigger_samples=100, record_samples=1000,
                    trigger_level=7.5, trigger_slope="falling")
    task = fake_task()
    chan = configure_task(task, s)
    task.ai_channels.add_ai_force_iepe_chan.assert_called_once_with(
        "cDAQ1Mod1/ai0",
        min_val=-445.0,
        max_val=445.0,
        units=c.ForceUnits.NEWTONS,
        sensitivity=pytest.approx(11.24),  # mV/N from 11.24e-3 V/N
        sensitivity_units=c.ForceIEPESensorSensitivityUnits.MILLIVOLTS_PER_NEWTON,
        current_excit_source=c.ExcitationSource.INTERNAL,
        current_excit_val=0.002,
    )
    assert chan.ai_coupling == c.Coupling.AC
    task.timing.cfg_samp_clk_timing.assert_called_once_with(
        25600.0, sample_mode=c.AcquisitionType.FINITE, samps_per_chan=1000
    )
    task.triggers.reference_trigger.cfg_anlg_edge_ref_trig.assert_called_once_with(
        "cDAQ1Mod1/ai0", 100, trigger_slope=c.Slope.FALLING, trigger_level=7.5
    )


def test_backend_reads_one_finite_record_per_hit(tmp_path):
    s = DaqSettings(record_samples=64, pretrigger_samples=8, hits=3)
    records = [np.sin(np.arange(64) / 5.0) * (i + 1) for i in range(3)]
    task = fake_task(records)
    backend = NidaqBackend(task_factory=lambda: task, device_factory=lambda name: fake_device())
    path = run_session(backend, s, tmp_path / "s.h5", sample_id="PCF15", operator="mj")
    task.control.assert_called_once_with(c.TaskMode.TASK_COMMIT)
    assert task.start.call_count == 3 and task.stop.call_count == 3
    task.read.assert_called_with(number_of_samples_per_channel=64, timeout=60.0)
    task.close.assert_called_once()
    rec = read_recording(path)
    assert len(rec.hits) == 3
    for h, r in zip(rec.hits, records, strict=True):
        np.testing.assert_array_equal(h.force, r)
    assert rec.meta["hw_product_type"] == "NI 9234" and rec.meta["backend"] == "nidaqmx"
    assert rec.meta["complete"] is True


def test_overload_reported_by_the_driver_marks_the_hit_clipped(tmp_path):
    s = DaqSettings(record_samples=32, pretrigger_samples=4, hits=1)
    task = fake_task([np.zeros(32)], overloaded=True)
    backend = NidaqBackend(task_factory=lambda: task, device_factory=lambda name: fake_device())
    path = run_session(backend, s, tmp_path / "o.h5", sample_id="x")
    with pytest.raises(RecordingError, match="clipped"):
        read_recording(path)


def test_short_read_is_a_daq_error():
    s = DaqSettings(record_samples=32, pretrigger_samples=4)
    task = fake_task([np.zeros(10)])
    backend = NidaqBackend(task_factory=lambda: task, device_factory=lambda name: fake_device())
    with pytest.raises(DaqError, match="read 10 samples"):
        list(backend.hits(s, 1))
    task.close.assert_called_once()


@pytest.mark.parametrize(("product", "analog", "match"), [
    ("NI 9215", True, "NI 9234"), ("NI 9234", False, "analog trigger")])
def test_check_device_rejects_modules_it_was_not_checked_for(product, analog, match):
    with pytest.raises(DaqError, match=match):
        check_device(fake_device(product, analog), DaqSettings(trigger_mode="hardware"))


@pytest.mark.parametrize(("analog", "mode", "trigger"), [
    (True, "auto", "hardware"), (False, "auto", "software"), (True, "software", "software")])
def test_trigger_choice(analog, mode, trigger):
    d = check_device(fake_device(analog=analog), DaqSettings(trigger_mode=mode))
    assert d["trigger"] == trigger and d["analog_reference_trigger"] is analog


def hit_stream(starts, n, rng):
    """Noise (0.05 N rms) with a two-pulse hit (40 N, then 20 N 60 samples later) at ``starts``."""
    k = np.arange(n)
    y = rng.normal(0.0, 0.05, n)
    for s in starts:
        y += 40.0 * sech2((k - s) / 2.0) + 20.0 * sech2((k - s - 60.0) / 3.0)
    return y


def test_software_trigger_fallback_cuts_the_stream_like_the_simulated_rule(tmp_path):
    """A module without an analog reference trigger: continuous task, records cut in software
    across read boundaries, identical to the trigger rule applied to the whole stream."""
    s = DaqSettings(record_samples=256, pretrigger_samples=32, hits=3, trigger_level=5.0)
    chunk = chunk_samples(s)
    y = hit_stream([3000, 5100, 9000, 12000], 6 * chunk, np.random.default_rng(4))
    task = fake_task([y[i : i + chunk] for i in range(0, y.size, chunk)])
    backend = NidaqBackend(task_factory=lambda: task,
                           device_factory=lambda name: fake_device(analog=False))
    path = run_session(backend, s, tmp_path / "sw.h5", sample_id="PCF15")
    task.timing.cfg_samp_clk_timing.assert_called_once_with(
        51200.0, sample_mode=c.AcquisitionType.CONTINUOUS, samps_per_chan=buffer_samples(s))
    task.triggers.reference_trigger.cfg_anlg_edge_ref_trig.assert_not_called()
    assert task.start.call_count == 1 and task.stop.call_count == 1
    task.close.assert_called_once()
    rec = read_recording(path)
    want = split_records(y, TriggerRule.of(s))[:3]
    assert len(rec.hits) == 3 and rec.meta["hw_trigger"] == "software"
    for h, w in zip(rec.hits, want, strict=True):
        np.testing.assert_array_equal(h.force, w)
        assert h.trigger_index == 32 and h.extra["trigger"] == "software"


def test_software_trigger_times_out_clearly():
    s = DaqSettings(record_samples=256, pretrigger_samples=32, timeout=0.1,
                    trigger_mode="software")
    chunk = chunk_samples(s)
    quiet = np.random.default_rng(0).normal(0.0, 0.05, chunk)
    task = fake_task([quiet] * 10)
    backend = NidaqBackend(task_factory=lambda: task, device_factory=lambda name: fake_device())
    with pytest.raises(DaqError, match=r"no trigger within 0\.1 s"):
        list(backend.hits(s, 1))
    task.stop.assert_called_once()
    task.close.assert_called_once()


def test_missing_driver_is_a_clear_daq_error():
    """This machine has no NI-DAQmx driver: the real backend must say so, not crash."""
    with pytest.raises(DaqError, match="NI-DAQmx driver is not installed"):
        list(get_backend("nidaqmx").hits(DaqSettings(), 1))
