"""A run's checks (:func:`assess`): every check of :mod:`ssw.validity` evaluated from what a
chain run computed, the sample's yield from the contact FEM's stresses, from an upper bound,
or not at all (:data:`STRESS_MODES`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ssw.validity.checks import Validity
from ssw.validity.quantities import (
    Strengths,
    contact_radius_ratio,
    first_yield_index,
    plate_deflection_ratio,
    pulse_overlap,
    reach_ratio,
    stress_indices,
)

#: Factor on the bare Hertz first-yield index that makes it an upper bound of the contact
#: FEM's (the FEM's largest excess over Hertz without a plate, 2.5 % at 1 MPa, rounded up;
#: tests/test_validity.py).
BOUND_MARGIN = 1.05
#: ``stresses=`` modes of :func:`assess`: the contact FEM's stresses, the sample's upper
#: bound only (no plate check), or no stress check.
STRESS_MODES = ("fem", "bound", "none")


def assess(params: Any, E: Any, nu: Any, run: Any, pk: Any, wall: Any, *,
           strengths: Strengths, stresses: str = "fem", contact: Any = None,
           operators: Any = None) -> Validity:
    """The checks of a chain run (:mod:`ssw.validity`) from what it computed.

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

