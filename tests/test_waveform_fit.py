"""The fit of a waveform model's parameters (:func:`ssw.calibration.waveform_fit.fit`) on a model
whose observations exist only in part of the parameter space (a hit's pulse that the model
does not produce beyond some parameter value): the fit must not trade observations for
chi^2. Before, a step into the region where a hit's features vanish dropped their rows from
chi^2, was accepted as a better fit and trapped the fit there (every way back adds the rows
again): a features calibration of a device off its start grid stopped so, chi^2 1232 on 77
degrees of freedom against 2.7 on 85 at the device's values, and its model-error floor,
estimated from those residuals, came out 20-100x too large."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from ssw.calibration import waveform, waveform_fit
from ssw.calibration.waveform import Column, Observed, State

#: Row A wants theta = 2 (weight 10); row B wants 1.2 (weight 3) and exists only below
#: theta = 1.5. With both rows the least squares optimum, 1.934, lies where B is lost.
A_AT, A_W, B_AT, B_W, B_LIMIT = 2.0, 10.0, 1.2, 3.0, 1.5


def _observe(setup, state, wanted=None):
    """Two observations of the DAQ gain theta (chosen for its log coordinate)."""
    cols = waveform.columns_of(1, 1)
    theta = state.globals["gain"]
    b = B_W * (theta - B_AT) if theta < B_LIMIT else np.nan
    J = np.zeros((2, len(cols)))
    j = cols.index(Column("gain"))
    J[:, j] = [A_W, B_W if theta < B_LIMIT else np.nan]
    return Observed(np.array([A_W * (theta - A_AT), b]), np.zeros(2), np.ones(2),
                    np.array(["tof", "amplitude"]), np.zeros(2, int), J, cols)


def _state(theta):
    return State(np.array([1e8]), np.array([0.5]), np.zeros(1), np.zeros(1),
                 {"preload": 0.0, "sensor_mass": 0.03, "striker_mass": 0.03, "damping": 0.0,
                  "gain": theta})


def test_a_step_that_loses_observations_is_not_a_better_fit(monkeypatch):
    monkeypatch.setattr(waveform_fit, "observe", _observe)
    setup = SimpleNamespace(runs=0, floor={}, discrepancy=None, prior={},
                            acq=SimpleNamespace(sample_rate=51200.0),
                            tof_scatter=1.53e-5)
    f = waveform_fit.fit(setup, _state(1.0), [Column("gain")])
    # every observation kept: the optimum of the two rows on the part of the space where
    # both exist is its edge theta -> 1.5 (chi^2 falls towards it: the unconstrained
    # optimum 1.934 lies beyond)
    assert f.unexplained == 0
    theta = f.state.globals["gain"]
    assert 1.45 < theta < B_LIMIT
    assert f.chi2 == pytest.approx((A_W * (theta - A_AT)) ** 2 + (B_W * (theta - B_AT)) ** 2)
