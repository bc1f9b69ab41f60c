"""NI-DAQmx configuration against autospec'd fakes of nidaqmx's Task (no driver here).

As nidaqmx's own unit tests, the driver layer is replaced by ``create_autospec`` mocks; the
channel, timing and trigger collections are autospec'd from their classes so that a call
with a wrong argument name fails as it would on the real API.
"""

from __future__ import annotations

from unittest import mock

import numpy as np
import pytest

nidaqmx = pytest.importorskip("nidaqmx")
from nidaqmx import constants as c  # noqa: E402
from nidaqmx.system import Device  # noqa: E402
from nidaqmx.task import InStream, Task, Timing  # noqa: E402
from nidaqmx.task.collections import AIChannelCollection  # noqa: E402
from nidaqmx.task.triggering import ReferenceTrigger, Triggers  # noqa: E402

from ssw.daq.backend import get_backend, run_session  # noqa: E402
from ssw.daq.nidaq import NidaqBackend, check_device, configure_task  # noqa: E402
from ssw.daq.recording import read_recording  # noqa: E402
from ssw.daq.settings import DaqSettings  # noqa: E402
from ssw.errors import DaqError, RecordingError  # noqa: E402


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
        check_device(fake_device(product, analog), DaqSettings())


def test_missing_driver_is_a_clear_daq_error():
    """This machine has no NI-DAQmx driver: the real backend must say so, not crash."""
    with pytest.raises(DaqError, match="NI-DAQmx driver is not installed"):
        list(get_backend("nidaqmx").hits(DaqSettings(), 1))
