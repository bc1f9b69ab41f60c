"""Which assumptions of a result hold: one entry per check, with its value, limit and source.

Every result of ssw rests on assumptions its model makes: small strain at the contact and in
the plate, elastic beads, plate and sample, the wall law within the range it was computed
over, a half-space under the plate, and incident and reflected pulses apart at the sensor.
This module owns the checks (the registry :data:`RULES`, one :class:`Rule` each: what the
value is, its limit and the source of the limit) and evaluates them from what a run already
computed (pure functions of the peak wall indentation, the contact forces, the sensor signal,
the contact's elastic stresses: :func:`assess`; a sweep's run,
:func:`ssw.tof.sweep.run_sweep`, carries them for its points and for the single point of an
inverted E). Commands only attach the result, a :class:`Validity`: per check one value per
scene, ``holds`` where the value is at or below its limit. A failing
check never changes a number: it says which assumption the number was computed beyond.

The checks (``check``: value <= limit):

* ``contact_strain``: ``a / R`` with ``a = sqrt(R d)`` (Hertz's contact radius at the peak
  wall indentation ``d``, the bead's radius ``R``) <= 0.2. Hertz is a small-strain theory for
  ``a << R``; its errors grow past ``a/R`` 0.1-0.2 (Johnson 1985, sec. 4.2); the exact sphere
  (Sneddon 1965, :func:`ssw.hertz.sneddon_sphere`) departs from Hertz's force at a given
  contact radius by ``2/5 (a/R)^2``, 1.6 % at the limit; Tabor's representative strain
  ``0.2 a/R`` is 4 % there.
* ``plate_deflection``: ``d / t``, the peak indentation (an upper bound of the plate's
  deflection: the bead's own approach is in it) over the plate's thickness, <= 0.5. The
  plate of the contact FEM is linear (small deflection, Kirchhoff); small-deflection theory
  holds while the deflection stays under half the thickness (the textbook boundary between
  small and large deflections of plates, e.g. Ross, *Mechanics of Solids*, "Lateral
  deflections of circular plates" [edition recalled]); beyond it membrane stretching
  stiffens the plate (a clamped circular plate: ``w/h + 0.488 (w/h)^3`` against the
  linear ``w/h``, 12 % at ``w = h/2``; Timoshenko and Woinowsky-Krieger 1959, sec. 96
  [coefficient recalled, unconfirmed]).
* ``wall_reach``: the peak indentation over the reach of the wall law's exact part (the
  FEM law's computed range, a table's end) <= 1; beyond it the force is an extension
  (:func:`ssw.chain.wall.beyond_exact_reach`).
* ``pulse_separation``: the sensor signal's valley between the incident and the reflected
  peak over the peak rule's gap share (:data:`ssw.signal.rule.RULE`, 0.25) of the smaller
  peak <= 1: the incident pulse has fallen below a quarter of its height before the
  reflected one rises, so each peak is its own pulse's.
* ``bead_yield``: Hertz's peak pressure of two beads at the chain's largest bead-bead
  force over their first-yield pressure ``k(nu) Y`` (``k`` = 1.61 at nu 0.3) <= 1 (Johnson
  1985, eq. 4.23 and sec. 6.1; ``Y`` the bead material's yield stress, or its compressive
  strength).
* ``sample_yield``: the sample's peak von Mises stress (the contact FEM's elastic field at
  the hit's peak wall force, through the plate, under the elastic bead:
  :func:`ssw.walls.fem.peak_stresses`) over its uniaxial strength <= 1 (first yield,
  Johnson 1985, sec. 6.1). The strength is the library material's, or a stated one; else
  ``ssw design``'s stated assumption ``Y = 0.01 E`` (:data:`SOIL_STRENGTH_RATIO`), named
  in the entry's ``assumed``. Where
  the FEM's stresses are not evaluated (a sweep and ``ssw validate`` by default:
  ``--stress-checks bound``), the value is an upper bound: Hertz's first-yield index of a
  rigid sphere of the bead's radius on the bare sample at the same force, times
  :data:`BOUND_MARGIN` (a plate spreads the load and an elastic bead presses less; measured
  on the thesis device: the FEM's value is 0.4-0.85 of the bare Hertz one under its PLA
  plate, and within 2.5 % of it without a plate), ``"bound": "upper"``: above its limit,
  yield is possible, not established.
* ``plate_yield``: the plate's peak von Mises stress (the same FEM field) over its
  material's yield stress <= 1.
* ``finite_sample``: the relative error of E a half-space reading would make on the stated
  sample or lift, <= 0.02 (``ssw measure``'s lift warning,
  :data:`ssw.cli.measure.LIFT_TOLERANCE`): beyond it, E rests on the stated geometry and
  its boundary conditions.

References
----------
Johnson, K. L. (1985). *Contact Mechanics*. Cambridge, sec. 4.2, 6.1.
Sneddon, I. N. (1965). The relation between load and penetration in the axisymmetric
Boussinesq problem for a punch of arbitrary profile. Int. J. Eng. Sci. 3, 47-57.
Tabor, D. (1951). *The Hardness of Metals*. Oxford.
Ross, C. T. F. *Mechanics of Solids*. Horwood, "Lateral deflections of circular plates"
[edition recalled, unconfirmed].
Timoshenko, S. P. and Woinowsky-Krieger, S. (1959). *Theory of Plates and Shells*, 2nd ed.
McGraw-Hill, ch. 13.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

#: A sample's strength over its modulus where none is stated: ``ssw design``'s stated
#: assumption (:mod:`ssw.design.spec`: inside the range of compacted clays, ``E_u / s_u``
#: 100-1500 with ``Y = 2 s_u``, Duncan & Buchignani 1976, and of rigid polyurethane foams,
#: compressive strength ~0.04 E [U]), named in every entry that rests on it.
SOIL_STRENGTH_RATIO = 0.01
#: Factor on the bare Hertz first-yield index that makes it an upper bound of the contact
#: FEM's (the FEM's largest excess over Hertz without a plate, 2.5 % at 1 MPa, rounded up;
#: tests/test_validity.py).
BOUND_MARGIN = 1.05
#: ``stresses=`` modes of :func:`assess`: the contact FEM's stresses, the sample's upper
#: bound only (no plate check), or no stress check.
STRESS_MODES = ("fem", "bound", "none")


@dataclass(frozen=True)
class Rule:
    """One check of the registry (module docstring).

    Parameters
    ----------
    name : str
        The check's name (``check`` of its entries).
    quantity : str
        What its value is.
    limit : float
        The largest value at which the assumption holds.
    unit : str
        The value's unit (``1``: a ratio).
    assumption : str
        The assumption of the model the check tests.
    source : str
        Where the limit comes from.
    """

    name: str
    quantity: str
    limit: float
    unit: str
    assumption: str
    source: str


#: The registry of checks: name -> :class:`Rule` (module docstring).
RULES: dict[str, Rule] = {}


def register(rule: Rule) -> Rule:
    """Add ``rule`` to :data:`RULES` (its name must be new) and return it.

    Parameters
    ----------
    rule : Rule
        The check's rule.

    Returns
    -------
    Rule
        ``rule``.

    Raises
    ------
    ValueError
        When a rule of that name is registered already.
    """
    if rule.name in RULES:
        raise ValueError(f"check {rule.name!r} is registered already")
    RULES[rule.name] = rule
    return rule


CONTACT_STRAIN = register(Rule(
    "contact_strain", "a/R: Hertz's contact radius a = sqrt(R d) at the peak wall "
    "indentation d over the bead's radius R", 0.2, "1",
    "small strain at the wall (Hertz: a << R)",
    "Johnson 1985 sec. 4.2 (Hertz's errors grow past a/R 0.1-0.2); Sneddon 1965's exact "
    "sphere departs from Hertz by 2/5 (a/R)^2 in force at a given contact radius (1.6 % at "
    "the limit)"))
PLATE_DEFLECTION = register(Rule(
    "plate_deflection", "d/t: the peak wall indentation (an upper bound of the plate's "
    "deflection) over the plate's thickness", 0.5, "1",
    "small deflection of the plate (linear Kirchhoff plate in the contact FEM)",
    "Ross, Mechanics of Solids, lateral deflections of circular plates (small-deflection "
    "theory up to half the thickness); "
    "Timoshenko & Woinowsky-Krieger 1959 sec. 96 (membrane stiffening ~0.49 (w/h)^2, 12 % "
    "at the limit; coefficient recalled)"))
WALL_REACH = register(Rule(
    "wall_reach", "the peak wall indentation over the reach of the wall law's exact part",
    1.0, "1", "the wall law within the range it was computed over",
    "ssw.chain.wall.beyond_exact_reach: beyond the reach the force is an extension"))
PULSE_SEPARATION = register(Rule(
    "pulse_separation", "the sensor signal's valley between the incident and reflected "
    "peaks over the peak rule's gap share (0.25) of the smaller peak", 1.0, "1",
    "incident and reflected pulses apart at the sensor (each peak its own pulse's)",
    "ssw.signal.rule.RULE.gap_fraction: the incident pulse has ended below a quarter of its "
    "height"))
BEAD_YIELD = register(Rule(
    "bead_yield", "Hertz's peak pressure of two beads at the largest bead-bead force over "
    "their first-yield pressure k(nu) Y (k = 1.61 at nu 0.3)", 1.0, "1",
    "elastic beads", "Johnson 1985 eq. 4.23 and sec. 6.1 (first yield below the surface)"))
SAMPLE_YIELD = register(Rule(
    "sample_yield", "the sample's peak von Mises stress (elastic field at the hit's peak "
    "wall force, through the plate, under the elastic bead) over its uniaxial strength",
    1.0, "1", "an elastic sample", "Johnson 1985 sec. 6.1 (von Mises first yield)"))
PLATE_YIELD = register(Rule(
    "plate_yield", "the plate's peak von Mises stress (the same field) over its yield "
    "stress", 1.0, "1", "an elastic plate", "von Mises first yield; the library's yield "
    "stress"))
FINITE_SAMPLE = register(Rule(
    "finite_sample", "|relative error of E| a half-space reading makes on the stated sample "
    "or lift", 0.02, "1", "a half-space under the plate",
    "ssw measure's lift tolerance (ssw.cli.measure.LIFT_TOLERANCE)"))


@dataclass(frozen=True)
class Check:
    """One entry of a result's ``validity`` list (module docstring).

    Parameters
    ----------
    check : str
        The rule's name.
    value : float
        The value (NaN: could not be evaluated, never holds).
    limit : float
        The rule's limit.
    holds : bool
        ``value <= limit``.
    unit : str
        The value's unit.
    assumed : str or None
        An assumption the value rests on (e.g. an assumed strength).
    bound : str or None
        ``upper`` when the value is an upper bound, not the value itself.
    note : str or None
        How the value was obtained, where it needs saying.
    """

    check: str
    value: float
    limit: float
    holds: bool
    unit: str = "1"
    assumed: str | None = None
    bound: str | None = None
    note: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """The JSON entry ``{"check", "value", "limit", "holds", "unit", "assumption",
        "source", ...}`` (``value`` None when not a number).

        Returns
        -------
        dict
            The entry (``value`` and ``limit`` in ``unit``).
        """
        rule = RULES[self.check]
        out: dict[str, Any] = {
            "check": self.check,
            "value": float(self.value) if np.isfinite(self.value) else None,
            "limit": self.limit, "holds": bool(self.holds), "unit": self.unit,
            "assumption": rule.assumption, "source": rule.source}
        for k in ("assumed", "bound", "note"):
            if getattr(self, k) is not None:
                out[k] = getattr(self, k)
        return out


@dataclass(frozen=True)
class Validity:
    """The checks of ``n`` scenes: per check one value per scene (module docstring).

    Parameters
    ----------
    values : dict
        Check name -> (n,) values (NaN: not evaluable at that scene).
    assumed : dict
        Check name -> the assumption its values rest on (all scenes).
    bound : dict
        Check name -> ``upper`` where its values are upper bounds.
    notes : dict
        Check name -> how its values were obtained.
    skipped : dict
        Check name -> why it was not evaluated (and how to get it).
    """

    values: dict[str, np.ndarray]
    assumed: dict[str, str] = field(default_factory=dict)
    bound: dict[str, str] = field(default_factory=dict)
    notes: dict[str, str] = field(default_factory=dict)
    skipped: dict[str, str] = field(default_factory=dict)

    @property
    def n(self) -> int:
        """Number of scenes."""
        return next((v.size for v in self.values.values()), 0)

    def holds(self, name: str) -> np.ndarray:
        """(n,) bool: the check ``name`` holds (a NaN value does not).

        Parameters
        ----------
        name : str
            The check's name (a key of :data:`RULES`).

        Returns
        -------
        numpy.ndarray
            Per scene: value <= limit.
        """
        v = self.values[name]
        with np.errstate(invalid="ignore"):
            return np.asarray(v <= RULES[name].limit, bool)

    def checks(self, i: int = 0) -> list[Check]:
        """Scene ``i``'s entries, in the registry's order.

        Parameters
        ----------
        i : int
            The scene's index.

        Returns
        -------
        list of Check
            One per evaluated check.
        """
        out = []
        for name in (k for k in RULES if k in self.values):
            v = float(self.values[name][i])
            out.append(Check(name, v, RULES[name].limit, bool(self.holds(name)[i]),
                             RULES[name].unit, self.assumed.get(name),
                             self.bound.get(name), self.notes.get(name)))
        return out

    def entries(self, i: int = 0) -> list[dict[str, Any]]:
        """Scene ``i``'s entries as JSON dicts (:meth:`Check.to_dict`).

        Parameters
        ----------
        i : int
            The scene's index.

        Returns
        -------
        list of dict
            One per evaluated check.
        """
        return [c.to_dict() for c in self.checks(i)]

    def failed(self, i: int = 0) -> list[str]:
        """Scene ``i``'s failing checks, each as ``name value > limit`` with what it
        assumed (empty: every evaluated check holds).

        Parameters
        ----------
        i : int
            The scene's index.

        Returns
        -------
        list of str
            :func:`describe` of each failing check.
        """
        return [describe(c) for c in self.checks(i) if not c.holds]

    def columns(self) -> dict[str, np.ndarray]:
        """Table columns: each check's values (named by the check) and ``checks_failed``
        (the failing checks' names per scene, ``;``-joined, empty when all hold).

        Returns
        -------
        dict of str to numpy.ndarray
            Column name -> values, one per scene.
        """
        names = [k for k in RULES if k in self.values]
        cols = {k: np.asarray(self.values[k], float) for k in names}
        bad = [";".join(k for k in names if not self.holds(k)[i]) for i in range(self.n)]
        return {**cols, "checks_failed": np.array(bad, dtype=object)}

    def worst(self) -> Validity:
        """One scene: each check's largest value over the scenes (NaN if any is NaN).

        Returns
        -------
        Validity
            The worst case, one scene.
        """
        vals = {k: np.array([np.max(v) if v.size else np.nan]) for k, v in self.values.items()}
        return Validity(vals, dict(self.assumed), dict(self.bound), dict(self.notes),
                        dict(self.skipped))

    def take(self, idx: Any) -> Validity:
        """The scenes ``idx`` (an index or a slice).

        Parameters
        ----------
        idx : int or slice or array_like
            The scenes to keep.

        Returns
        -------
        Validity
            The checks of those scenes (at least one-dimensional).
        """
        vals = {k: np.atleast_1d(np.asarray(v)[idx]) for k, v in self.values.items()}
        return Validity(vals, dict(self.assumed), dict(self.bound), dict(self.notes),
                        dict(self.skipped))

    def merged(self, other: Validity) -> Validity:
        """These checks and ``other``'s (same scenes; ``other``'s win a name in both).

        Parameters
        ----------
        other : Validity
            Further checks of the same scenes.

        Returns
        -------
        Validity
            Both sets of checks; a check evaluated by either is no longer listed as skipped.
        """
        return Validity({**self.values, **other.values}, {**self.assumed, **other.assumed},
                        {**self.bound, **other.bound}, {**self.notes, **other.notes},
                        {k: v for k, v in {**self.skipped, **other.skipped}.items()
                         if k not in other.values and k not in self.values})

    @classmethod
    def concat(cls, parts: list[Validity]) -> Validity:
        """The scenes of ``parts`` one after another (the checks every part has; the first
        part's assumptions and notes).

        Parameters
        ----------
        parts : list of Validity
            The parts, at least one.

        Returns
        -------
        Validity
            The scenes of every part.
        """
        names = [k for k in parts[0].values if all(k in p.values for p in parts)]
        first = parts[0]
        return cls({k: np.concatenate([p.values[k] for p in parts]) for k in names},
                   dict(first.assumed), dict(first.bound), dict(first.notes),
                   dict(first.skipped))

    def meta(self) -> dict[str, Any]:
        """What the values rest on, for a file's attributes: assumptions, bounds, notes,
        skipped checks, and each check's limit and source.

        Returns
        -------
        dict
            ``assumed``, ``bound``, ``notes``, ``skipped`` and ``rules`` (check -> ``limit``,
            ``unit``, ``quantity``, ``source``).
        """
        return {"assumed": self.assumed, "bound": self.bound, "notes": self.notes,
                "skipped": self.skipped,
                "rules": {k: {"limit": RULES[k].limit, "unit": RULES[k].unit,
                              "quantity": RULES[k].quantity, "source": RULES[k].source}
                          for k in RULES if k in self.values}}

    def to_dict(self, i: int = 0) -> dict[str, Any]:
        """Scene ``i`` for a JSON result: ``validity`` (entries), ``checks_failed`` (list)
        and ``checks_skipped`` (name -> why).

        Parameters
        ----------
        i : int
            The scene's index.

        Returns
        -------
        dict
            ``validity``, ``checks_failed`` and ``checks_skipped``.
        """
        return {"validity": self.entries(i), "checks_failed": self.failed(i),
                "checks_skipped": dict(self.skipped)}


def describe(c: Check | dict[str, Any]) -> str:
    """``name value > limit (assumed ...)`` of a failing entry (a Check or its dict).

    Parameters
    ----------
    c : Check or dict
        The entry.

    Returns
    -------
    str
        E.g. ``contact_radius_ratio 0.31 > 0.2 (assumed ...)`` (``<=`` when it holds).
    """
    d = c.to_dict() if isinstance(c, Check) else c
    v = "nan" if d["value"] is None else f"{d['value']:.3g}"
    rel = "<=" if d["holds"] else ">"
    text = f"{d['check']} {v} {rel} {d['limit']:g}"
    if d.get("bound") == "upper":
        text += " (an upper bound: not established)"
    if d.get("assumed"):
        text += f" (assumed {d['assumed']})"
    return text


def human_lines(entries: list[dict[str, Any]], skipped: dict[str, str] | None = None
                ) -> list[str]:
    """Lines for a command's human output: one per entry (``holds`` or ``FAILS`` with the
    assumption it tests) and one per skipped check.

    Parameters
    ----------
    entries : list of dict
        The entries (:meth:`Validity.entries`).
    skipped : dict of str to str or None
        Check name -> why it was not evaluated.

    Returns
    -------
    list of str
        The lines.
    """
    lines = []
    for d in entries:
        state = "holds" if d["holds"] else "FAILS"
        lines.append(f"check {describe(d)}: {state} ({d['assumption']})")
    lines += [f"check {k}: not evaluated ({v})" for k, v in (skipped or {}).items()]
    return lines


# ---------------------------------------------------------------------------- the checks
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


def assess(params: Any, E: Any, nu: Any, run: Any, pk: Any, wall: Any, *,
           strengths: Strengths, stresses: str = "fem", contact: Any = None,
           operators: Any = None) -> Validity:
    """The checks of a chain run (module docstring) from what it computed.

    Parameters
    ----------
    params : ssw.chain.params.ChainParams
        The chain.
    E : array_like
        (n,) the scenes' sample moduli, Pa.
    nu : array_like
        (n,) their Poisson's ratios.
    run : ssw.chain.integrate.Run
        The run (peak wall indentation, sensor signal, largest bead-bead force).
    pk : ssw.chain.tof.Peaks
        Its peaks.
    wall : Wall
        The built wall (its exact reach, its force at the peak indentation).
    strengths : Strengths
        The sample's, plate's and beads' strengths.
    stresses : str
        ``fem`` (the contact FEM's stresses at every scene), ``bound`` (the sample's upper
        bound only; the plate not checked) or ``none`` (no stress check).
    contact : dict or None
        The contact FEM's settings (``fem``).
    operators : ssw.contact.operators.OperatorStore or None
        Its operators.

    Returns
    -------
    Validity
        One value per scene and check.
    """
    from ssw.errors import ConfigError

    if stresses not in STRESS_MODES:
        raise ConfigError("--stress-checks", stresses, " | ".join(STRESS_MODES))
    d = np.asarray(run.peak_wall_indentation, float)
    n = d.size
    E = np.broadcast_to(np.asarray(E, float), (n,)).copy()
    nu = np.broadcast_to(np.asarray(nu, float), (n,)).copy()
    vals: dict[str, np.ndarray] = {"contact_strain": contact_radius_ratio(d,
                                                                           params.bead_radius)}
    notes: dict[str, str] = {}
    assumed: dict[str, str] = {}
    bound: dict[str, str] = {}
    skipped: dict[str, str] = {}
    if params.plate_thickness > 0:
        vals["plate_deflection"] = plate_deflection_ratio(d, params.plate_thickness)
    reach = reach_ratio(wall, d)
    if reach is not None:
        vals["wall_reach"] = reach
    vals["pulse_separation"] = pulse_overlap(run, pk)
    if strengths.bead is not None and getattr(run, "peak_contact_force", None) is not None:
        vals["bead_yield"] = first_yield_index(run.peak_contact_force, params.bead_E,
                                               params.bead_nu, params.bead_radius,
                                               strengths.bead)
    if stresses == "none":
        skipped["sample_yield"] = skipped["plate_yield"] = "--stress-checks none"
        return Validity(vals, assumed, bound, notes, skipped)
    force = (np.asarray(wall.force(np.where(np.isfinite(d), d, 0.0)), float)
             if hasattr(wall, "force") else np.nanmax(run.wall_force, axis=0))
    Y, what = strengths.sample_at(E)
    if what is not None:
        assumed["sample_yield"] = what
    elif strengths.sample_source:
        notes["sample_yield"] = f"the sample's strength: {strengths.sample_source}"
    if stresses == "bound":
        vals["sample_yield"] = BOUND_MARGIN * first_yield_index(force, E, nu,
                                                                params.bead_radius, Y)
        bound["sample_yield"] = "upper"
        notes["sample_yield"] = ((notes.get("sample_yield", "") + "; ").lstrip("; ")
                                 + "Hertz's first-yield index on the bare sample at the "
                                 f"peak wall force x {BOUND_MARGIN:g}: above 1 yield is "
                                 "possible, not established (--stress-checks fem: the "
                                 "contact FEM's value)")
        if params.plate_thickness > 0:
            skipped["plate_yield"] = ("no cheap bound of a bending plate's stress: "
                                      "--stress-checks fem evaluates the contact FEM's")
        return Validity(vals, assumed, bound, notes, skipped)
    soil, plate, errors = stress_indices(params, E, nu, d, force, strengths, contact=contact,
                                         operators=operators)
    if errors:
        notes["sample_yield"] = "; ".join([*filter(None, [notes.get("sample_yield")]),
                                           *errors])
    vals["sample_yield"] = soil
    if plate is not None:
        vals["plate_yield"] = plate
    elif params.plate_thickness > 0:
        skipped["plate_yield"] = (f"the library states no yield stress of "
                                  f"{params.plate_material}")
    return Validity(vals, assumed, bound, notes, skipped)


def fem_options(wall: str, wall_options: dict[str, Any]) -> dict[str, Any]:
    """``contact`` and ``operators`` of a wall's options for the contact FEM's stresses
    (the fem wall's own; another law's: the study's contact settings, if given).

    Parameters
    ----------
    wall : str
        The wall law's name (not read).
    wall_options : dict
        The wall's options.

    Returns
    -------
    dict
        Its ``contact`` and ``operators`` entries.
    """
    return {k: v for k, v in wall_options.items() if k in ("contact", "operators")}


def finite_sample(departure: Any, assumed: str) -> Validity:
    """The ``finite_sample`` check of relative errors ``departure`` (n,) of a half-space
    reading (:func:`ssw.lift.half_space_departure`, :func:`ssw.lift.lift_errors`), resting
    on the stated geometry ``assumed``.

    Parameters
    ----------
    departure : array_like
        Relative errors of the half-space reading, (n,).
    assumed : str
        The stated sample geometry.

    Returns
    -------
    Validity
        The check, value ``|departure|``.
    """
    return Validity({"finite_sample": np.abs(np.atleast_1d(np.asarray(departure, float)))},
                    assumed={"finite_sample": assumed})


def from_entries(entries: list[dict[str, Any]]) -> Validity:
    """A one-scene :class:`Validity` from a result's ``validity`` list (a JSON result read
    back: a survey's points).

    Parameters
    ----------
    entries : list of dict
        The result's ``validity`` list (checks not registered are skipped).

    Returns
    -------
    Validity
        One scene.
    """
    vals, assumed, bound, notes = {}, {}, {}, {}
    for d in entries:
        name = d["check"]
        if name not in RULES:
            continue
        vals[name] = np.array([np.nan if d.get("value") is None else float(d["value"])])
        for tgt, key in ((assumed, "assumed"), (bound, "bound"), (notes, "note")):
            if d.get(key):
                tgt[name] = d[key]
    return Validity(vals, assumed, bound, notes)
