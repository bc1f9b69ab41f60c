"""A calibration refined by the references' records, level by level (``ssw calibrate
--information features|waveform``).

The TOF calibration (:func:`ssw.calibration.file.calibrate`) always answers: where its
references reject its model it carries the model's error (:mod:`ssw.calibration.model_error`)
instead of refusing, so the records' levels never wait on its chi^2. Each level then stands
on its own records:

* ``features``: from the TOF calibration's device, the start the records point to (a grid
  of the sensor's mass and the contact dashpot, each point's hits fitted, refined around
  the best: :func:`ssw.calibration.waveform.global_start`,
  :func:`ssw.calibration.waveform.refine_start`), then every global the features identify
  freed, with the model-error floor their residuals call for
  (:func:`ssw.calibration.waveform.calibrate_records`);
* ``waveform``: from the features' calibration (its globals and DAQ gain; each hit's
  parameters fitted to the samples and the floor they leave estimated before the globals
  are freed), every global the samples identify freed with the samples' own floor. The
  samples' chi^2 is far sharper in the device than the features' (``ssw identify``: 1e3
  times narrower marginal uncertainties), so a grid over the waveform's chi^2 would need
  a far finer spacing; the features' optimum lies within its basin.

The records' fit of each level is stored in the calibration's ``provenance["information"]``
(:func:`ssw.calibration.waveform.with_fit`; ``from``: the level it started from) and its
floor and findings in ``warnings``.
"""

from __future__ import annotations

from typing import Any

from ssw.errors import ConfigError


def calibrate_levels(cal: Any, samples: list[Any], acq: Any, level: str, *,
                     trigger_level: float, tof_scatter: float, wall: str,
                     wall_options: dict[str, Any] | None = None,
                     start_grid: tuple[tuple[float, ...], tuple[float, ...]] | None = None,
                     refine_levels: int | None = None) -> dict[str, Any]:
    """The TOF calibration ``cal`` refined by its references' records up to ``level``
    (module docstring): every level's calibration, in order.

    Parameters
    ----------
    cal : ssw.calibration.Calibration
        The TOF calibration of the same references.
    samples : list of ssw.calibration.waveform.Hits
        The references' records, each with its E.
    acq : ssw.daq.model.Acquisition
        The measurement model.
    level : str
        ``features`` or ``waveform``.
    trigger_level : float
        N, the records' trigger level.
    tof_scatter : float
        s, a hit's TOF scatter (the prior of each hit's reflected-wave delay).
    wall : str
        The wall law.
    wall_options : dict or None
        Its options.
    start_grid : tuple or None
        The features' global start grid (sensor masses, multiples of the device's; dashpots,
        N s/m); None: the default one.
    refine_levels : int or None
        Refinements of that start; None: the default.

    Returns
    -------
    dict
        ``{"features": Calibration[, "waveform": Calibration]}``.

    Raises
    ------
    ConfigError
        ``level`` is not ``features`` or ``waveform``.
    """
    from ssw.calibration.waveform import REFINE_LEVELS, calibrate_records, with_fit

    if level not in ("features", "waveform"):
        raise ConfigError("--information", level, "features | waveform for a fit of records")
    opts = dict(wall_options or {})
    f = calibrate_records(samples, cal.chain_params(), wall, opts, acq, "features",
                          trigger_level, tof_scatter, start_grid=start_grid,
                          refine_levels=REFINE_LEVELS if refine_levels is None
                          else refine_levels)
    out = {"features": with_fit(cal, f, "features")}
    if level == "waveform":
        feat = out["features"]
        w = calibrate_records(samples, feat.chain_params(), wall, opts, acq, "waveform",
                              trigger_level, tof_scatter, scan=False,
                              gain=float(feat.provenance["information"]["gain"]))
        out["waveform"] = with_fit(feat, w, "waveform")
    return out
