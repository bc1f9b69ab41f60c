"""Fit one force-indentation curve with one law: :func:`fit_curve` -> :class:`FitResult`.

Which E* (the thesis leaves it implicit; ssw states it): the FEM indenter is rigid, so the
reference Hertz law of a contact curve is ``F_H = 4/3 E* sqrt(R) delta^(3/2)`` with

    ``E* = E_soil / (1 - nu_soil^2)``  (Johnson 1985 eq. 4.22 with E_sphere -> inf),

and ``R`` the indenter radius. ``K = 1`` means "exactly Hertz on the bare soil". The chain
applies K to its own Hertz wall law, whose E* combines the steel bead and the soil,
``1/E* = (1 - nu_b^2)/E_b + (1 - nu_s^2)/E_s``, and whose R is the bead radius; for soils
(E_s <= 1 GPa) the two E* differ by less than 0.5 %.

Residuals are reported on the points of the fit range with ``delta > 0`` and ``F > 0``:
relative ``r_i = F_fit(delta_i) / F_i - 1`` (rms and max ``|r|``) and the rms force error over
the largest force of the range.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ssw import hertz
from ssw.curve import ForceCurve
from ssw.errors import ConfigError, OutOfRangeError
from ssw.fit.laws import WEIGHTINGS, get_law

#: Keys under which a curve's ``inputs`` may hold each scene quantity (first match wins);
#: ``solve_scene`` writes the first of each, older or hand-written files may use the others.
INPUT_KEYS: dict[str, tuple[str, ...]] = {
    "soil_E": ("soil_E", "E_soil", "soil_e"),
    "soil_nu": ("soil_nu", "nu_soil"),
    "radius": ("indenter_radius", "radius", "R"),
    "plate_material": ("plate_material",),
    "plate_thickness": ("plate_thickness",),
    "plate_E": ("plate_E",),
    "plate_nu": ("plate_nu",),
}


@dataclass(frozen=True)
class FitResult:
    """A law fitted to one curve on ``[delta_lo, delta_hi]`` (m). SI units.

    Parameters
    ----------
    law : str
        The law's registry name.
    params : dict
        Fitted parameters (their units: ``Law.units``).
    rms_rel_residual : float
        RMS relative residual.
    max_rel_residual : float
        Largest relative residual.
    nrms_residual : float
        ``rms(F_fit - F) / max F`` on the range.
    delta_lo : float
        Lower end of the fit range (m).
    delta_hi : float
        Upper end of the fit range (m).
    n_points : int
        Number of curve samples fitted.
    weighting : str
        The residual weighting.
    E_star : float
        ``E_soil / (1 - nu_soil^2)`` (Pa).
    radius : float
        Indenter radius (m).
    hertz_coefficient : float
        ``4/3 E* sqrt(R)`` (N m^-1.5).
    scene : dict
        The curve's scene quantities (SI).
    """

    law: str
    params: dict[str, float]
    rms_rel_residual: float
    max_rel_residual: float
    nrms_residual: float  # rms(F_fit - F) / max F on the range
    delta_lo: float  # m
    delta_hi: float  # m
    n_points: int
    weighting: str
    E_star: float  # Pa, E_soil / (1 - nu_soil^2)
    radius: float  # m, indenter radius
    hertz_coefficient: float  # N m^-1.5, 4/3 E* sqrt(R)
    scene: dict[str, Any] = field(default_factory=dict)

    def predict(self, delta: ArrayLike) -> NDArray[np.float64]:
        """Force (N) of the fitted law at ``delta`` (m).

        Parameters
        ----------
        delta : array_like
            Indentations (m).

        Returns
        -------
        numpy.ndarray
            Force (N), the shape of ``delta``.
        """
        law = get_law(self.law)
        return law.evaluate(self.params, np.asarray(delta, float), self.hertz_coefficient)

    def as_dict(self) -> dict[str, Any]:
        """Flat dict: the law's parameters at top level (e.g. ``"K"``), then the rest.

        Returns
        -------
        dict
            The flat record (SI).
        """
        d = asdict(self)
        return {**d.pop("params"), **d}


def scene_inputs(curve: ForceCurve, **overrides: Any) -> dict[str, Any]:
    """Scene quantities of ``curve`` (soil_E, soil_nu, radius, plate_*), overrides first.

    Parameters
    ----------
    curve : ForceCurve
        The force-indentation curve (SI).
    **overrides : Any
        Values that replace the curve's (SI); None leaves the curve's.

    Returns
    -------
    dict
        ``soil_E`` (Pa), ``soil_nu``, ``radius`` (m) and the plate's quantities.
    """
    src = dict(curve.inputs)
    if isinstance(src.get("scene"), dict):
        src = {**src["scene"], **src}
    out: dict[str, Any] = {}
    for name, keys in INPUT_KEYS.items():
        if overrides.get(name) is not None:
            out[name] = overrides[name]
            continue
        for k in keys:
            if k in src:
                out[name] = src[k]
                break
    for name in ("soil_E", "soil_nu", "radius"):
        if name not in out:
            raise ConfigError(
                name, None, f"give it, or a curve whose inputs hold one of {INPUT_KEYS[name]}"
            )
    return out


def fit_curve(
    curve: ForceCurve,
    law: str = "k_hertz",
    delta_range: tuple[float, float] | None = None,
    *,
    weighting: str = "absolute",
    soil_E: float | None = None,
    soil_nu: float | None = None,
    radius: float | None = None,
) -> FitResult:
    """Fit ``law`` to ``curve`` on ``delta_range`` (m, inclusive; default: the whole curve).

    Parameters
    ----------
    curve : ssw.curve.ForceCurve
        The FEM (or synthetic) force-indentation curve.
    law : str
        A name of ``ssw.fit.laws.LAWS``.
    delta_range : tuple of float or None
        ``(lo, hi)``, m. ``hi`` beyond the curve's last indentation raises
        :class:`~ssw.errors.OutOfRangeError` (clip it first; :mod:`ssw.fit.range` does).
    weighting : str
        ``absolute`` (OLS on the force, the thesis's) or ``relative``.
    soil_E : float or None
        Overrides the curve's soil modulus, Pa.
    soil_nu : float or None
        Overrides the curve's soil Poisson's ratio.
    radius : float or None
        Overrides the curve's indenter radius, m.

    Returns
    -------
    FitResult
        The parameters and residuals; ``E* = soil_E / (1 - soil_nu^2)``.
    """
    lw = get_law(law)
    if weighting not in WEIGHTINGS:
        raise ConfigError("fit.weighting", weighting, f"one of {', '.join(WEIGHTINGS)}")
    sc = scene_inputs(curve, soil_E=soil_E, soil_nu=soil_nu, radius=radius)
    E_star = float(hertz.effective_modulus(sc["soil_E"], sc["soil_nu"]))
    R = float(sc["radius"])
    A_H = float(hertz.hertz_coefficient(E_star, R))
    d, F = np.asarray(curve.delta, float), np.asarray(curve.force, float)
    lo, hi = (0.0, float(d[-1])) if delta_range is None else map(float, delta_range)
    if not 0.0 <= lo < hi:
        raise ConfigError("delta_range", (lo, hi), "0 <= lo < hi (m)")
    if hi > d[-1] * (1 + 1e-12):
        raise OutOfRangeError(
            f"fit range upper end {hi:.6g} m is beyond the curve's last indentation "
            f"{d[-1]:.6g} m; clip the range or compute a longer curve"
        )
    sel = (d >= lo) & (d <= hi * (1 + 1e-12)) & (d > 0) & (F > 0)
    if np.count_nonzero(sel) < len(lw.params) + 1:
        raise OutOfRangeError(
            f"only {np.count_nonzero(sel)} points with delta > 0 and F > 0 in "
            f"[{lo:.6g}, {hi:.6g}] m; the {law} law needs at least {len(lw.params) + 1}"
        )
    ds, Fs = d[sel], F[sel]
    params = lw.fit(ds, Fs, A_H, weighting)
    Ff = lw.evaluate(params, ds, A_H)
    rel = Ff / Fs - 1.0
    return FitResult(
        law=law,
        params=params,
        rms_rel_residual=float(np.sqrt(np.mean(rel**2))),
        max_rel_residual=float(np.max(np.abs(rel))),
        nrms_residual=float(np.sqrt(np.mean((Ff - Fs) ** 2)) / np.max(Fs)),
        delta_lo=float(ds[0]),
        delta_hi=float(ds[-1]),
        n_points=int(ds.size),
        weighting=weighting,
        E_star=E_star,
        radius=R,
        hertz_coefficient=A_H,
        scene={k: sc.get(k) for k in INPUT_KEYS},
    )
