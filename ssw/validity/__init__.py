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

Modules: :mod:`ssw.validity.checks` (the registry and the record),
:mod:`ssw.validity.quantities` (what each check measures), :mod:`ssw.validity.assessment`
(a run's checks). Every public name of them is importable from ``ssw.validity``.
"""

from __future__ import annotations

from ssw.validity.assessment import (
    BOUND_MARGIN,
    STRESS_MODES,
    assess,
    fem_options,
)
from ssw.validity.checks import (
    BEAD_YIELD,
    CONTACT_STRAIN,
    FINITE_SAMPLE,
    PLATE_DEFLECTION,
    PLATE_YIELD,
    PULSE_SEPARATION,
    RULES,
    SAMPLE_YIELD,
    WALL_REACH,
    Check,
    Rule,
    Validity,
    describe,
    finite_sample,
    from_entries,
    human_lines,
    register,
)
from ssw.validity.quantities import (
    SOIL_STRENGTH_RATIO,
    Strengths,
    contact_radius_ratio,
    first_yield_index,
    plate_deflection_ratio,
    pulse_overlap,
    reach_ratio,
    strengths_of,
    stress_indices,
)

__all__ = [
    "BEAD_YIELD",
    "BOUND_MARGIN",
    "CONTACT_STRAIN",
    "FINITE_SAMPLE",
    "PLATE_DEFLECTION",
    "PLATE_YIELD",
    "PULSE_SEPARATION",
    "RULES",
    "SAMPLE_YIELD",
    "SOIL_STRENGTH_RATIO",
    "STRESS_MODES",
    "WALL_REACH",
    "Check",
    "Rule",
    "Strengths",
    "Validity",
    "assess",
    "contact_radius_ratio",
    "describe",
    "fem_options",
    "finite_sample",
    "first_yield_index",
    "from_entries",
    "human_lines",
    "plate_deflection_ratio",
    "pulse_overlap",
    "reach_ratio",
    "register",
    "strengths_of",
    "stress_indices",
]
