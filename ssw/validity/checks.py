"""The checks and their record: the registry :data:`RULES` (one :class:`Rule` per check:
what its value is, its limit, the assumption it tests and the source of the limit), one
result's entries (:class:`Check`) and a run's values (:class:`Validity`), and their text
(:func:`describe`, :func:`human_lines`). The checks themselves are listed in
:mod:`ssw.validity`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Rule:
    """One check of the registry (:mod:`ssw.validity`).

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


#: The registry of checks: name -> :class:`Rule` (:mod:`ssw.validity`).
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
    """One entry of a result's ``validity`` list (:mod:`ssw.validity`).

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
    """The checks of ``n`` scenes: per check one value per scene (:mod:`ssw.validity`).

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
