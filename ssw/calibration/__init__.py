"""Calibration of a device on measured reference samples (``ssw calibrate``).

* :mod:`~ssw.calibration.model`: references and the batched forward model TOF(theta);
* :mod:`~ssw.calibration.fit`: global scan, batched Levenberg-Marquardt, covariance,
  singular values, leave-one-out subsets;
* :mod:`~ssw.calibration.file`: the calibration file (JSON: the calibrated device, the
  identified values, their covariance, the wall law, the provenance) and
  :func:`~ssw.calibration.file.calibrate`, the whole procedure.
"""

from ssw.calibration.file import Calibration, calibrate, load_calibration, write_calibration
from ssw.calibration.model import Reference, parse_reference

__all__ = ["Calibration", "Reference", "calibrate", "load_calibration", "parse_reference",
           "write_calibration"]
