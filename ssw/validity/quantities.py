"""What the checks measure, from what a run computed: the contact radius and the plate's
deflection over their limits, the wall law's reach, the pulses' overlap at the sensor, and
the yield indices of the beads, the sample and the plate (with the strengths they compare
stresses with, :class:`Strengths`). Pure functions; SI units.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

#: A sample's strength over its modulus where none is stated: ``ssw design``'s stated
#: assumption (:mod:`ssw.design.spec`: inside the range of compacted clays, ``E_u / s_u``
#: 100-1500 with ``Y = 2 s_u``, Duncan & Buchignani 1976, and of rigid polyurethane foams,
#: compressive strength ~0.04 E [U]), named in every entry that rests on it.
SOIL_STRENGTH_RATIO = 0.01


def contact_radius_ratio(d: Any, radius: float) -> np.ndarray:
    """``a / R = sqrt(d / R)`` (Hertz, ``a^2 = R d``) of peak indentations ``d`` (m) under a
    bead of ``radius`` (m); 0 where ``d <= 0``.

    Parameters
    ----------
    d : array_like
        Peak indentations, m.
    radius : float
        The bead's radius ``R``, m.

    Returns
    -------
    numpy.ndarray
        ``a / R``, dimensionless.

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*, ch. 4 (Hertz: ``a^2 = R d``).
    """
    from ssw.hertz import contact_radius

    return contact_radius(np.asarray(d, float), radius) / float(radius)


def plate_deflection_ratio(d: Any, thickness: float) -> np.ndarray:
    """``d / t``: peak indentations ``d`` (m) over the plate's ``thickness`` (m, > 0).

    Parameters
    ----------
    d : array_like
        Peak indentations, m.
    thickness : float
        The plate's thickness, m (> 0).

    Returns
    -------
    numpy.ndarray
        ``d / t``, dimensionless.
    """
    return np.asarray(d, float) / float(thickness)


def reach_ratio(wall: Any, d: Any) -> np.ndarray | None:
    """The peak indentations ``d`` (m) over the wall's exact reach (m,
    :func:`ssw.chain.wall.beyond_exact_reach`: above 1 the force was an extension), or None
    for a law defined at any depth.

    Parameters
    ----------
    wall : object
        The wall law (its ``exact_reach``, m, if any).
    d : array_like
        Peak indentations, m.

    Returns
    -------
    numpy.ndarray or None
        ``d / reach``, dimensionless; None when the wall has no ``exact_reach``.
    """
    reach = getattr(wall, "exact_reach", None)
    if reach is None:
        return None
    return np.asarray(d, float) / np.asarray(reach, float)


def pulse_overlap(run: Any, pk: Any) -> np.ndarray:
    """(n,) the sensor signal's lowest value between the incident and the reflected peak
    (above its static value, at the run's steps) over the peak rule's gap share of the
    smaller peak (:data:`ssw.signal.rule.RULE`): > 1, the pulses merge. Infinite where the
    reflected peak is not on the run's record (a scene run again for longer keeps its first
    record) or not found.

    Parameters
    ----------
    run : object
        The chain's run: ``t`` (n_t,) s and ``sensor`` (n_t, n) N.
    pk : object
        Its peaks: ``t_incident``, ``t_reflected``, ``tof`` (s), ``f_incident`` and
        ``f_reflected`` (N), (n,) each.

    Returns
    -------
    numpy.ndarray
        The overlap ratio, dimensionless.
    """
    from ssw.signal.rule import RULE

    s = run.sensor - run.sensor[0]
    t = run.t[:, None]
    between = (t >= pk.t_incident[None]) & (t <= pk.t_reflected[None])
    valley = np.maximum(np.where(between & np.isfinite(s), s, np.inf).min(axis=0), 0.0)
    smaller = np.minimum(pk.f_incident, pk.f_reflected)
    seen = np.isfinite(pk.tof) & (pk.t_reflected <= run.t[-1])
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(seen & (smaller > 0), valley / (RULE.gap_fraction * smaller), np.inf)


def first_yield_index(force: Any, E: Any, nu: Any, radius: float, strength: Any) -> np.ndarray:
    """Hertz's first-yield index ``p0 / (k(nu) Y)`` of forces ``F`` (N) of a rigid sphere of
    ``radius`` (m) on a half-space of ``E`` (Pa), ``nu`` and uniaxial strength ``Y`` (Pa):
    ``p0 = (6 F E*^2 / (pi^3 R^2))^(1/3)``, ``E* = E / (1 - nu^2)`` (Johnson 1985, eq. 4.23,
    :func:`ssw.constitutive.yield_index.hertz_peak_pressure`); ``k`` = 1.61 at nu 0.3
    (sec. 6.1, :func:`ssw.constitutive.yield_index.first_yield_ratio`). Two identical beads
    of radius R and modulus E have the same ``p0`` (``R* = R/2``, ``E* = E / (2 (1 -
    nu^2))``).

    Parameters
    ----------
    force : array_like
        Contact forces ``F``, N.
    E : array_like
        The half-space's Young's modulus, Pa.
    nu : array_like
        Its Poisson's ratio.
    radius : float
        The sphere's radius ``R``, m.
    strength : array_like
        The uniaxial strength ``Y``, Pa.

    Returns
    -------
    numpy.ndarray
        The index, dimensionless (> 1: yield has begun).

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*. Cambridge University Press, eq. (4.23) and
    sec. 6.1.
    """
    from ssw.constitutive.yield_index import first_yield_ratio, hertz_peak_pressure

    p0 = hertz_peak_pressure(np.asarray(force, float), E, nu, radius)
    ratios, where = np.unique(np.asarray(nu, float), return_inverse=True)
    k = np.array([first_yield_ratio(float(v)) for v in ratios])[where]
    return p0 / (k.reshape(np.shape(nu)) * np.asarray(strength, float))


@dataclass(frozen=True)
class Strengths:
    """The uniaxial strengths the yield checks compare stresses with. Pa; None: unknown.

    Parameters
    ----------
    sample : float, numpy.ndarray or None
        The sample's (one per scene, or one for all; None: ``ratio E``, an assumption
        named in the entries; NaN in an array: that scene's sample states none).
    sample_source : str
        Where it comes from (a library material, a flag).
    plate : float or None
        The plate material's yield stress (None: no plate check).
    bead : float or None
        The beads' yield stress or compressive strength (None: no bead check).
    ratio : float
        The assumed strength over modulus of a sample without one
        (:data:`SOIL_STRENGTH_RATIO`).
    """

    sample: float | np.ndarray | None = None
    sample_source: str = ""
    plate: float | None = None
    bead: float | None = None
    ratio: float = SOIL_STRENGTH_RATIO

    def sample_at(self, E: Any) -> tuple[np.ndarray, str | None]:
        """The sample's strength (Pa) at moduli ``E`` (Pa), and the assumption it rests on
        (None when it is stated).

        Parameters
        ----------
        E : array_like
            The samples' Young's moduli, Pa.

        Returns
        -------
        Y : numpy.ndarray
            The strengths, Pa.
        assumed : str or None
            The assumption, when ``ratio E`` stands for a strength not given.
        """
        E = np.asarray(E, float)
        what = (f"Y_sample = {self.ratio:g} E, ssw design's stated assumption (no strength "
                "given: --sample-strength or --sample-material states one)")
        if self.sample is None:
            return self.ratio * E, what
        Y = np.broadcast_to(np.asarray(self.sample, float), E.shape).copy()
        missing = ~np.isfinite(Y)
        if np.any(missing):  # a scene whose sample states no strength: the assumption
            Y[missing] = self.ratio * E[missing]
            return Y, what + " where the sample states none"
        return Y, None


def strengths_of(params: Any, materials: dict[str, Any], bead_material: str | None, *,
                 sample: Any = None, sample_source: str = "") -> Strengths:
    """The strengths of a device's beads and plate (the library's) and its sample.

    Parameters
    ----------
    params : ssw.chain.params.ChainParams
        The chain (its plate's material and thickness).
    materials : dict
        The materials library (key -> :class:`ssw.materials.Material`).
    bead_material : str or None
        The beads' material key (the device's).
    sample : float, array_like or None
        The sample's uniaxial strength, Pa, when known (one per scene, or one).
    sample_source : str
        Where it comes from.

    Returns
    -------
    Strengths
        With the design's assumed ratio for a sample without a strength.
    """
    def of(key: str | None, fields: tuple[str, ...]) -> float | None:
        m = materials.get(key) if key else None
        st = getattr(m, "strength", None)
        for f in fields:
            v = getattr(st, f, None) if st is not None else None
            if v is not None:
                return float(v)
        return None

    plate = (of(params.plate_material, ("yield_stress",)) if params.plate_thickness > 0
             else None)
    return Strengths(sample=None if sample is None else np.asarray(sample, float)
                     if np.ndim(sample) else float(sample),
                     sample_source=sample_source, plate=plate,
                     bead=of(bead_material, ("yield_stress", "compressive")),
                     ratio=SOIL_STRENGTH_RATIO)


def stress_indices(params: Any, E: np.ndarray, nu: np.ndarray, d: np.ndarray,
                   force: np.ndarray, strengths: Strengths, *, contact: Any = None,
                   operators: Any = None
                   ) -> tuple[np.ndarray, np.ndarray | None, list[str]]:
    """The sample's and the plate's yield indices (n,) at the chain's peak wall indentations
    ``d`` (m) and forces ``force`` (N): :func:`ssw.walls.fem.peak_stresses` (one call per
    Poisson's ratio), over :meth:`Strengths.sample_at` and the plate's yield stress; and
    the reasons of scenes the FEM could not evaluate. NaN where ``d`` is not a positive
    number or the FEM failed; the plate's None without a plate or its strength.

    Parameters
    ----------
    params : ssw.chain.params.ChainParams
        The chain (its plate's thickness).
    E : numpy.ndarray
        The samples' Young's moduli, Pa, (n,).
    nu : numpy.ndarray
        Their Poisson's ratios, (n,).
    d : numpy.ndarray
        Peak wall indentations, m, (n,).
    force : numpy.ndarray
        Peak wall forces, N, (n,).
    strengths : Strengths
        The strengths.
    contact : dict or None
        The contact FEM's settings.
    operators : object or None
        Prepared contact operators.

    Returns
    -------
    soil : numpy.ndarray
        The sample's yield index, (n,).
    plate : numpy.ndarray or None
        The plate's yield index, (n,).
    errors : list of str
        Why the FEM failed, per Poisson's ratio it failed at.
    """
    from ssw.errors import SswError
    from ssw.walls.fem import peak_stresses

    n = E.size
    soil = np.full(n, np.nan)
    plate = np.full(n, np.nan) if (params.plate_thickness > 0
                                   and strengths.plate is not None) else None
    ok = np.isfinite(d) & (d > 0) & np.isfinite(force) & (force > 0)
    Y, _ = strengths.sample_at(E)
    errors: list[str] = []
    for v in np.unique(nu[ok]):
        idx = np.flatnonzero(ok & (nu == v))
        try:
            st = peak_stresses(params, E[idx], float(v), d[idx], contact=contact,
                               operators=operators, force=force[idx])
        except SswError as exc:  # e.g. beyond the contact FEM's zone: NaN, never holds
            errors.append(f"the contact FEM's stresses at nu {v:g}: {exc}")
            continue
        soil[idx] = st.soil.peak / Y[idx]
        if plate is not None and st.plate is not None:
            plate[idx] = st.plate.peak / strengths.plate
    return soil, plate, errors


