"""The model's own error, estimated from the references' misfit: one estimator at every level.

A calibration's model (ssw's chain, its contact law, its dashpot) is not the device. Where
the references' residuals exceed what their stated uncertainties explain, the model's error
is a random term of its own: each observation ``y_i`` of a reference departs from the model
by its noise (standard deviation ``sigma_i``) and by a model error of relative standard
deviation ``phi`` on the observation's scale ``s_i``::

    y_i - model_i(theta) ~ N(0, sigma_i^2 + phi^2 s_i^2)

(the additional variance of a random-effects model, the "dark uncertainty" of
inter-laboratory comparisons: Thompson & Ellison 2011; Paule & Mandel 1982 estimate it by
making the weighted chi^2 equal to its degrees of freedom, Birge's ratio of 1, Birge 1932).
With a handful of references the point estimate is itself uncertain (one degree of freedom
leaves its variance unknown within a factor of 250 at 95 %), and a sample beyond the
references' range meets an error no smaller than theirs; so ssw takes the **upper
confidence bound** of ``phi`` (:data:`FLOOR_CONFIDENCE`): the ``phi`` at which the chi^2 with
the term falls to the lower quantile of its law (:func:`floor_bound`). Exact for residuals
of equal variance that the fit does not project (a linear model's residuals have
``n - p`` degrees of freedom: their chi^2 is that law's; the coverage is tested in
``tests/test_model_error.py``).

One estimator answers "how large is the model's error?" at every level:

* ``tof`` (:func:`ssw.calibration.fit.identify`): a relative TOF model error ``tau``
  (``s_i`` the reference's measured TOF), estimated only where the references **reject**
  the model (their chi^2 with the stated uncertainties beyond its :data:`REJECT_QUANTILE`
  quantile, :func:`rejects`: a calibration the references do not reject is left as it
  was, to the digit), and fitted with the parameters: the weights ``sigma_i^2 + tau^2
  T_i^2``, ``tau`` re-estimated from the new residuals until it settles
  (:data:`PASSES`, ``RTOL``). Every interval made through the calibration carries it
  (:func:`ssw.modulus.estimate_moduli`): its covariance, from those weights, and the
  sample's own model error ``tau / |d ln TOF / d ln E|`` (the term
  :data:`ssw.modulus.MODEL_TERM`);
* ``features`` and ``waveform`` (:func:`ssw.calibration.waveform.model_floor`): one ``phi``
  per kind of observation (each feature; the samples of a record), always estimated (a
  chain is never the device to an NI 9234's noise floor), the fit repeated with it.

The references' leave-one-out predictions (:func:`ssw.calibration.file.calibrate`) are
reported beside it, as a check of the term on samples the fit did not see, not as a second
term (one mechanism per question).

References
----------
Birge, R. T. (1932). The calculation of errors by the method of least squares. Phys. Rev.
40, 207-227.
Paule, R. C. and Mandel, J. (1982). Consensus values and weighting factors. J. Res. Natl.
Bur. Stand. 87(5), 377-385.
Thompson, M. and Ellison, S. L. R. (2011). Dark uncertainty. Accred. Qual. Assur. 16,
483-487.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

#: The confidence of the model-error term's upper bound (:func:`floor_bound`).
FLOOR_CONFIDENCE = 0.95
#: The chi^2 quantile beyond which the references reject the TOF model (:func:`rejects`).
REJECT_QUANTILE = 0.95
#: Fits of the TOF level with ``tau`` re-estimated from their residuals, at most; they stop
#: when ``tau`` changes by at most RTOL of itself.
PASSES = 4
RTOL = 0.1


def floor_bound(r: np.ndarray, sigma: np.ndarray, scale: np.ndarray, dof: float,
                confidence: float = FLOOR_CONFIDENCE) -> float:
    """The upper confidence bound of a relative model-error floor ``phi`` from residuals
    ``r_i ~ N(0, sigma_i^2 + phi^2 s_i^2)``: the root of ``sum_i r_i^2 / (sigma_i^2 +
    phi^2 s_i^2) = chi2.ppf(1 - confidence, dof)`` (the left side falls as ``phi``
    grows), 0 where the noise alone explains them.

    Parameters
    ----------
    r : numpy.ndarray
        (n,) residuals (any unit, that of ``sigma``).
    sigma : numpy.ndarray
        (n,) the noise's standard deviations.
    scale : numpy.ndarray
        (n,) the scale the floor is relative to (``|s_i|``).
    dof : float
        The residuals' degrees of freedom (their share of a fit's).
    confidence : float
        The bound's confidence.

    Returns
    -------
    float
        ``phi`` (dimensionless).

    References
    ----------
    Birge (1932); Paule & Mandel (1982) (module docstring).
    """
    from scipy import stats

    from ssw.roots import find_root

    rr, sig, sc = np.asarray(r, float) ** 2, np.asarray(sigma, float) ** 2, \
        np.asarray(scale, float) ** 2
    target = float(stats.chi2.ppf(1.0 - confidence, max(dof, 1e-3)))

    def shortfall(phi: np.ndarray) -> np.ndarray:
        """``target - sum_i r_i^2 / (sigma_i^2 + phi^2 s_i^2)``: rises with ``phi``."""
        return target - np.sum(rr / (sig + np.asarray(phi)[..., None] ** 2 * sc), axis=-1)

    if shortfall(np.asarray(0.0)) >= 0.0:
        return 0.0
    hi = float(np.sqrt(np.sum(rr) / max(np.sum(sc), 1e-300) * rr.size / target))
    # the bracket grows from the moment estimate until it holds the root
    root = find_root(shortfall, 0.0, hi, xatol=1e-12 * hi, xrtol=1e-6, grow=True)
    return float(root.x)


def chi2_cdf(chi2: float, dof: int) -> float:
    """``P(X <= chi2)`` for ``X`` chi^2-distributed with ``dof`` degrees of freedom (NaN for
    ``dof < 1``).

    Parameters
    ----------
    chi2 : float
        -, the chi^2 value.
    dof : int
        Its degrees of freedom.

    Returns
    -------
    float
        -, the chi^2 distribution's CDF at ``chi2``.
    """
    from scipy.special import chdtr  # scipy.stats is a 0.4 s import for this one number

    return float(chdtr(dof, chi2)) if dof >= 1 else float("nan")


def rejects(chi2: float, dof: int) -> bool:
    """Whether a chi^2 with ``dof`` degrees of freedom rejects the model at
    ``1 - REJECT_QUANTILE`` (False without a degree of freedom).

    Parameters
    ----------
    chi2 : float
        -, the references' chi^2.
    dof : int
        Its degrees of freedom.

    Returns
    -------
    bool
        True when ``P(X <= chi2) > REJECT_QUANTILE``.
    """
    return bool(dof >= 1 and chi2_cdf(chi2, dof) > REJECT_QUANTILE)


@dataclass(frozen=True)
class ModelError:
    """A TOF calibration's model-error term (module docstring). SI units.

    Parameters
    ----------
    tau : float
        The TOF model's relative standard error (1), the :data:`FLOOR_CONFIDENCE` upper
        bound; in every interval made through the calibration.
    chi2 : float
        The references' chi^2 with their stated TOF uncertainties, before the term (at the
        fit without it).
    dof : int
        Its degrees of freedom (references minus the parameters no bound holds).
    quantile : float
        ``P(X <= chi2)``: beyond :data:`REJECT_QUANTILE` the references reject the model.
    chi2_with_term : float
        chi^2 at the calibration with the term in the weights (its lower
        :data:`FLOOR_CONFIDENCE` quantile, by construction).
    passes : int
        Fits made with the term.
    settled : bool
        ``tau`` changed by at most ``RTOL`` of itself at the last pass.
    """

    tau: float
    chi2: float
    dof: int
    quantile: float
    chi2_with_term: float
    passes: int
    settled: bool

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready, with the estimator named.

        Returns
        -------
        dict
            ``level``, the fields, ``confidence``, ``reject_quantile`` and ``estimator``.
        """
        return {"level": "tof", **asdict(self), "confidence": FLOOR_CONFIDENCE,
                "reject_quantile": REJECT_QUANTILE,
                "estimator": "upper confidence bound of a relative TOF error tau: weights "
                "TOF_STD^2 + tau^2 TOF^2 (ssw.calibration.model_error)"}

    @classmethod
    def from_dict(cls, d: dict[str, Any] | None) -> ModelError | None:
        """The term of a calibration file's ``model_error`` (None: none).

        Parameters
        ----------
        d : dict or None
            The file's ``model_error`` mapping (:meth:`to_dict`), or None.

        Returns
        -------
        ModelError or None
            The term, or None when ``d`` is empty.
        """
        if not d:
            return None
        return cls(float(d["tau"]), float(d["chi2"]), int(d["dof"]), float(d["quantile"]),
                   float(d["chi2_with_term"]), int(d["passes"]), bool(d["settled"]))

    def note(self) -> str:
        """What the term is, in a sentence (outputs, notes).

        Returns
        -------
        str
            The sentence, with chi^2, its degrees of freedom and ``tau``.
        """
        return (f"MODEL ERROR: the references reject the TOF model (chi2 {self.chi2:.4g} on "
                f"{self.dof} degree(s) of freedom, beyond its {REJECT_QUANTILE:.0%} "
                f"quantile): calibrated with a relative TOF model error tau = "
                f"{self.tau:.3g} ({FLOOR_CONFIDENCE:.0%} upper bound) in the weights; "
                "every interval through the calibration carries it")
