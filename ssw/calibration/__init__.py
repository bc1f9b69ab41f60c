"""Calibration of a device on measured reference samples (``ssw calibrate``).

* :mod:`~ssw.calibration.model`: references and the batched forward model TOF(theta);
* :mod:`~ssw.calibration.residuals`: the observations fitted and the model's derivatives
  (one function ``theta -> (values, d values / d theta)``; central differences today);
* :mod:`~ssw.calibration.lm`: the bounded (active-set) Levenberg-Marquardt that advances
  many problems in one batched model run per iteration;
* :mod:`~ssw.calibration.fit`: the identification, the covariance conditional on the
  parameters a bound holds, singular values, leave-one-out subsets;
* :mod:`~ssw.calibration.scan`: its global scan and the batched refinement from the scan's
  starts;
* :mod:`~ssw.calibration.model_error`: the model's own error where the references' misfit
  exceeds their uncertainties (one estimator at every level: the TOF's ``tau``, the records'
  floors);
* :mod:`~ssw.calibration.records`: the calibration refined by the references' records, the
  features and then the whole waveform (:mod:`~ssw.calibration.waveform`: the calibration
  of records; :mod:`~ssw.calibration.hits`: the records and the parameters' state;
  :mod:`~ssw.calibration.observation`: the model's observations and their derivatives;
  :mod:`~ssw.calibration.waveform_fit`: the fit and its covariance;
  :mod:`~ssw.calibration.start`: the model-error floor and the global start);
* :mod:`~ssw.calibration.laws`: the contacts' dissipation laws compared on the references'
  records by AIC and BIC (``ssw calibrate --compare-laws``);
* :mod:`~ssw.calibration.file`: the calibration file (JSON: the calibrated device, the
  identified values, their covariance, the model-error term, the wall law, the provenance;
  checked against ``ssw/data/calibration.schema.yaml`` when read) and
  :func:`~ssw.calibration.file.calibrate`, the whole procedure.
"""

from ssw.calibration.file import Calibration, calibrate, load_calibration, write_calibration
from ssw.calibration.model import Reference, parse_reference

__all__ = ["Calibration", "Reference", "calibrate", "load_calibration", "parse_reference",
           "write_calibration"]
