"""Real acquisition through NI-DAQmx (``nidaqmx`` Python API, 1.x): NI 9234 + PCB 208C02.

One task, one IEPE force channel, configured once; each hit is one finite,
reference-triggered record (or, without an analog reference trigger, a record cut from a
continuous stream by the same rule in software: below):

* ``ai_channels.add_ai_force_iepe_chan(phys, min_val=-F_max, max_val=F_max,
  units=NEWTONS, sensitivity=S [mV/N], sensitivity_units=MILLIVOLTS_PER_NEWTON,
  current_excit_source=INTERNAL, current_excit_val=0.002)``: nidaqmx's default 4 mA does
  not exist on the NI 9234, which supplies 2 mA only;
* ``channel.ai_coupling = Coupling.AC`` (IEPE needs AC coupling on the NI 9234);
* ``timing.cfg_samp_clk_timing(rate, sample_mode=FINITE, samps_per_chan=N)``;
* ``triggers.reference_trigger.cfg_anlg_edge_ref_trig(phys, pretrigger_samples,
  trigger_slope, trigger_level)``: the trigger source is the force channel itself and the
  level is in the channel's units (N);
* ``control(TaskMode.TASK_COMMIT)`` once, so that restarting the task per hit is quick;
* per hit: ``start()``, ``read(N, timeout)``, overload check
  (``in_stream.overloaded_chans_exist``), ``stop()``.

Analog triggering on the NI 9234. In a cDAQ chassis only some C Series modules can source
an analog trigger (the "Analog Comparison Event"; cDAQ user manuals). The NI 9234 is
listed by NI among modules that can [U: the datasheet was not available here], so the
backend does not rely on it blindly: before configuring it reads the module's
``Device.anlg_trig_supported`` and ``Device.ai_trig_usage``. On a delta-sigma module the
comparison runs on the filtered data, so the trigger fires one filter delay after the
wave; the record is shifted by that delay as a whole, which cancels in a peak-to-peak TOF
(both peaks are delayed equally).

Software trigger (``settings.trigger_mode``: ``auto`` falls back to it when the module
cannot source an analog reference trigger; ``software`` forces it; ``hardware`` raises
:class:`ssw.errors.DaqError` instead). The task runs continuously
(``cfg_samp_clk_timing(rate, sample_mode=CONTINUOUS, samps_per_chan=buffer)``, no trigger);
chunks of ``CHUNK_SECONDS`` are read and fed to :class:`ssw.daq.trigger.RingTrigger`, which
applies the simulated backend's rule (level, slope, pretrigger, record length, hold-off) to
the stream and returns each record once its last sample has arrived. ``settings.timeout``
bounds the wait for each hit.

``nidaqmx`` is imported inside the functions; without the NI-DAQmx driver (this machine)
every entry point raises :class:`.DaqError` naming what is missing. The configuration is
tested against ``unittest.mock.create_autospec(nidaqmx.Task)``, as nidaqmx's own unit tests
mock the driver layer.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from ssw.daq.backend import Hit, register_backend
from ssw.daq.settings import DaqSettings
from ssw.daq.trigger import RingTrigger, TriggerRule
from ssw.errors import DaqError

CHUNK_SECONDS = 0.05  # s of samples per read of a continuous (software-triggered) task
BUFFER_SECONDS = 10.0  # s of samples in NI-DAQmx's buffer of a continuous task

NO_DRIVER = (
    "the NI-DAQmx driver is not installed (nidaqmx found no NI-DAQmx library); install "
    "NI-DAQmx from ni.com on the acquisition computer, or use the simulated backend "
    "(ssw acquire --simulate)"
)


def _nidaqmx() -> Any:
    """The ``nidaqmx`` module, or :class:`.DaqError` if the Python package is missing."""
    try:
        import nidaqmx
        import nidaqmx.constants
        import nidaqmx.errors
        import nidaqmx.system
    except ImportError as exc:  # pragma: no cover - nidaqmx is a dependency
        raise DaqError(f"the nidaqmx Python package is not installed: {exc}") from exc
    return nidaqmx


def _driver_call(what: str, fn: Callable[[], Any]) -> Any:
    """Run ``fn`` and turn nidaqmx's errors into :class:`.DaqError` saying ``what`` failed."""
    nidaqmx = _nidaqmx()
    try:
        return fn()
    except nidaqmx.errors.DaqNotFoundError as exc:
        raise DaqError(NO_DRIVER) from exc
    except nidaqmx.errors.DaqError as exc:
        raise DaqError(f"{what} failed (NI-DAQmx error {exc.error_code}): {exc}") from exc


def check_device(device: Any, settings: DaqSettings) -> dict[str, Any]:
    """Check the module and choose the trigger; return its description.

    ``device`` is an ``nidaqmx.system.Device`` (or a fake of one). The description's
    ``trigger`` is ``hardware`` (analog reference trigger) or ``software`` (continuous
    acquisition, :class:`ssw.daq.trigger.RingTrigger`): ``settings.trigger_mode`` ``auto``
    takes hardware where the module supports it. Raises :class:`.DaqError` if it is not an
    NI 9234, or if ``hardware`` is asked of a module that cannot source an analog reference
    trigger.

    Parameters
    ----------
    device : nidaqmx.system.Device
        The module.
    settings : ssw.daq.settings.DaqSettings
        The acquisition settings (``device``, ``trigger_mode``).

    Returns
    -------
    dict
        ``product_type``, ``serial_num``, ``analog_reference_trigger`` (bool) and ``trigger``.

    Raises
    ------
    ssw.errors.DaqError
        When the module is not an NI 9234, or cannot give the hardware trigger asked for.
    """
    nidaqmx = _nidaqmx()
    product = str(device.product_type)
    if "9234" not in product:
        raise DaqError(
            f"device {settings.device!r} is a {product!r}; the settings are checked for an "
            "NI 9234 (rates 51200/n, 2 mA IEPE, +-5 V)"
        )
    why = ""
    if not device.anlg_trig_supported:
        why = "cannot source an analog trigger"
    elif nidaqmx.constants.TriggerUsage.REFERENCE not in list(device.ai_trig_usage):
        why = "has no AI reference trigger"
    if why and settings.trigger_mode == "hardware":
        raise DaqError(f"device {settings.device!r} ({product}) {why}; use the software "
                       "trigger (--trigger software or auto)")
    trigger = "software" if why or settings.trigger_mode == "software" else "hardware"
    return {"product_type": product, "serial_num": str(getattr(device, "serial_num", "")),
            "analog_reference_trigger": not why, "trigger": trigger}


def configure_task(task: Any, settings: DaqSettings, trigger: str = "hardware") -> Any:
    """Add the IEPE force channel, timing and trigger to ``task``; return the channel.

    ``trigger = "hardware"``: finite timing and the analog reference trigger.
    ``"software"``: continuous timing with a ``BUFFER_SECONDS`` buffer and no trigger
    (records are cut by :class:`ssw.daq.trigger.RingTrigger`). ``task`` is an
    ``nidaqmx.Task`` (or an autospec'd fake).

    Parameters
    ----------
    task : nidaqmx.Task
        The task to configure.
    settings : ssw.daq.settings.DaqSettings
        The acquisition settings.
    trigger : str
        ``hardware`` or ``software``.

    Returns
    -------
    object
        The channel added (``nidaqmx`` AI channel).
    """
    c = _nidaqmx().constants
    chan = _add_channel(task, settings)
    if trigger == "software":
        task.timing.cfg_samp_clk_timing(
            settings.sample_rate,
            sample_mode=c.AcquisitionType.CONTINUOUS,
            samps_per_chan=buffer_samples(settings),
        )
        return chan
    task.timing.cfg_samp_clk_timing(
        settings.sample_rate,
        sample_mode=c.AcquisitionType.FINITE,
        samps_per_chan=settings.record_samples,
    )
    task.triggers.reference_trigger.cfg_anlg_edge_ref_trig(
        settings.physical_channel,
        settings.pretrigger_samples,
        trigger_slope=c.Slope.RISING if settings.trigger_slope == "rising" else c.Slope.FALLING,
        trigger_level=settings.trigger_level,
    )
    return chan


def buffer_samples(settings: DaqSettings) -> int:
    """NI-DAQmx buffer of a continuous task: ``BUFFER_SECONDS`` and at least 4 records.

    Parameters
    ----------
    settings : ssw.daq.settings.DaqSettings
        The acquisition settings.

    Returns
    -------
    int
        The buffer's size, samples.
    """
    return max(int(BUFFER_SECONDS * settings.sample_rate), 4 * settings.record_samples)


def chunk_samples(settings: DaqSettings) -> int:
    """Samples per read of a continuous task: ``CHUNK_SECONDS`` of data, at least 1.

    Parameters
    ----------
    settings : ssw.daq.settings.DaqSettings
        The acquisition settings.

    Returns
    -------
    int
        Samples per read.
    """
    return max(int(CHUNK_SECONDS * settings.sample_rate), 1)


def _add_channel(task: Any, settings: DaqSettings) -> Any:
    c = _nidaqmx().constants
    phys = settings.physical_channel
    chan = task.ai_channels.add_ai_force_iepe_chan(
        phys,
        min_val=-settings.max_force,
        max_val=settings.max_force,
        units=c.ForceUnits.NEWTONS,
        sensitivity=settings.sensitivity_mv_per_n,
        sensitivity_units=c.ForceIEPESensorSensitivityUnits.MILLIVOLTS_PER_NEWTON,
        current_excit_source=(c.ExcitationSource.INTERNAL if settings.excitation_current > 0
                              else c.ExcitationSource.NONE),
        current_excit_val=settings.excitation_current,
    )
    chan.ai_coupling = c.Coupling.AC if settings.coupling == "AC" else c.Coupling.DC
    return chan


def read_hit(task: Any, settings: DaqSettings) -> Hit:
    """Start the task, wait for one triggered record, read it, stop. Returns the :class:`.Hit`.

    Parameters
    ----------
    task : nidaqmx.Task
        A task configured for the hardware trigger.
    settings : ssw.daq.settings.DaqSettings
        The acquisition settings.

    Returns
    -------
    ssw.daq.backend.Hit
        The record (force in N).

    Raises
    ------
    ssw.errors.DaqError
        When the read returns another number of samples than ``record_samples``.
    """
    task.start()
    try:
        data = task.read(number_of_samples_per_channel=settings.record_samples,
                         timeout=settings.timeout)
        overloaded = bool(task.in_stream.overloaded_chans_exist)
    finally:
        task.stop()
    force = np.asarray(data, dtype=np.float64).ravel()
    if force.size != settings.record_samples:
        raise DaqError(
            f"read {force.size} samples from {settings.physical_channel}, expected "
            f"{settings.record_samples}"
        )
    return Hit(force=force, trigger_index=settings.pretrigger_samples, overloaded=overloaded,
               extra={"trigger": "hardware"})


def software_hits(task: Any, settings: DaqSettings, n_hits: int) -> Iterator[Hit]:
    """Records of ``n_hits`` hits from a started continuous task, cut by the software trigger.

    Reads chunks of :func:`chunk_samples`, feeds them to a :class:`.RingTrigger` and yields
    each record it completes. A hit is marked overloaded if the driver reported an
    overload during any read since the previous hit. Raises :class:`.DaqError` if no hit
    arrives within ``settings.timeout`` s of stream.

    Parameters
    ----------
    task : nidaqmx.Task
        A started continuous task.
    settings : ssw.daq.settings.DaqSettings
        The acquisition settings.
    n_hits : int
        How many hits.

    Yields
    ------
    ssw.daq.backend.Hit
        One record per hit (force in N).

    Raises
    ------
    ssw.errors.DaqError
        When a read returns no sample, or no trigger comes within ``settings.timeout`` s.
    """
    rule = TriggerRule.of(settings)
    ring = RingTrigger(rule, capacity=4 * settings.record_samples + chunk_samples(settings))
    chunk = chunk_samples(settings)
    limit = settings.timeout * settings.sample_rate
    got, waited, overloaded = 0, 0, False
    while got < n_hits:
        data = _driver_call(
            f"reading {settings.physical_channel} (continuous, software trigger)",
            lambda: task.read(number_of_samples_per_channel=chunk,
                              timeout=chunk / settings.sample_rate + settings.timeout))
        overloaded |= bool(task.in_stream.overloaded_chans_exist)
        x = np.asarray(data, dtype=np.float64).ravel()
        if x.size == 0:
            raise DaqError(f"read 0 samples from {settings.physical_channel}")
        waited += x.size
        for rec in ring.feed(x):
            yield Hit(force=rec, trigger_index=rule.pretrigger_samples, overloaded=overloaded,
                      extra={"trigger": "software", "stream_samples": ring.samples_seen})
            got, waited, overloaded = got + 1, 0, False
            if got == n_hits:
                return
        if waited > limit:
            raise DaqError(
                f"no trigger within {settings.timeout} s: the force on "
                f"{settings.physical_channel} never crossed {settings.trigger_level} N "
                f"({settings.trigger_slope}, software trigger)"
            )


class NidaqBackend:
    """The ``nidaqmx`` backend. ``task_factory``/``device_factory`` exist for tests.

    Parameters
    ----------
    task_factory : callable or None
        ``task_factory()`` returns a new task (None: ``nidaqmx.Task``).
    device_factory : callable or None
        ``device_factory(name)`` returns the device (None: ``nidaqmx.system.Device``).
    """

    name = "nidaqmx"

    def __init__(
        self,
        task_factory: Callable[[], Any] | None = None,
        device_factory: Callable[[str], Any] | None = None,
    ) -> None:
        self._task_factory = task_factory
        self._device_factory = device_factory
        self._description: dict[str, Any] = {}

    def _device(self, settings: DaqSettings) -> Any:
        if self._device_factory is not None:
            return self._device_factory(settings.device)
        return _nidaqmx().system.Device(settings.device)

    def describe(self) -> dict[str, Any]:
        """The hardware the records go with: the driver, and the module's description
        (:func:`check_device`; filled when the task is opened).

        Returns
        -------
        dict
            ``driver``, then ``product_type``, ``serial_num``, ``analog_reference_trigger`` and
            ``trigger`` once a task was opened.
        """
        return {"driver": "NI-DAQmx", **self._description}

    def open(self, settings: DaqSettings) -> Any:
        """Check the device and return a configured task (caller closes it).

        Parameters
        ----------
        settings : ssw.daq.settings.DaqSettings
            The acquisition settings.

        Returns
        -------
        nidaqmx.Task
            The task, configured and committed.

        Raises
        ------
        ssw.errors.DaqError
            When the device is refused or a driver call fails.
        """
        nidaqmx = _nidaqmx()
        self._description = _driver_call(
            f"querying device {settings.device!r}",
            lambda: check_device(self._device(settings), settings),
        )
        factory = self._task_factory or nidaqmx.Task
        task = _driver_call("creating an NI-DAQmx task", factory)
        trigger = self._description["trigger"]
        try:
            _driver_call(f"configuring {settings.physical_channel}",
                         lambda: configure_task(task, settings, trigger))
            # Commit once: the per-hit start/stop then skips verification and reservation.
            _driver_call("committing the task",
                         lambda: task.control(nidaqmx.constants.TaskMode.TASK_COMMIT))
        except BaseException:
            task.close()
            raise
        return task

    def hits(self, settings: DaqSettings, n_hits: int) -> Iterator[Hit]:
        """Record ``n_hits`` hits on the NI 9234: one triggered record per hit (hardware trigger),
        or records cut from a continuous stream (software trigger); the task is closed after.

        Parameters
        ----------
        settings : ssw.daq.settings.DaqSettings
            The acquisition settings.
        n_hits : int
            How many hits.

        Yields
        ------
        ssw.daq.backend.Hit
            One record per hit (force in N).

        Raises
        ------
        ssw.errors.DaqError
            When the device is refused, a driver call fails or no trigger comes in time.
        """
        task = self.open(settings)
        try:
            if self._description["trigger"] == "software":
                _driver_call("starting the continuous task", task.start)
                try:
                    yield from software_hits(task, settings, n_hits)
                finally:
                    task.stop()
                return
            for _ in range(n_hits):
                yield _driver_call(
                    f"reading a hit on {settings.physical_channel} (no trigger within "
                    f"{settings.timeout} s?)", lambda: read_hit(task, settings)
                )
        finally:
            task.close()


register_backend("nidaqmx", NidaqBackend)
