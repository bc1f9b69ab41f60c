"""Deviation from Hertz at a reference indentation: the thesis's Set 1 and Set 2 statements.

The thesis (Torres Constante 2024, Stage I results) states, at ``delta = 0.001 mm``:

* Set 1 (plate material, 0.4 mm): "ratios of 0.28 (PLA), 1.75 (aluminum), and 2.75
  (steel). Stiffer plates exhibited greater deviations";
* Set 2 (PLA thickness): "deviations were 37% for the 0.2 mm plate and 42% for the 0.4 mm
  plate".

ssw reads both as the relative deviation of the force from the bare-soil Hertz force,

    ``dev(delta) = F(delta) / F_H(delta) - 1``,  ``F_H = 4/3 E/(1 - nu^2) sqrt(R) delta^1.5``,

(so 0.28 means 28 % above Hertz; it grows with plate stiffness, as the thesis says) and
also reports the ratio ``F / F_H``. The thesis does not state the soil of Sets 1 and 2,
nor whether its moduli are the realistic ones or the Table 1 values as printed; ssw
computes both material sets (config ``material_set``) on the config's soil.

``F(delta_ref)`` is interpolated linearly in ``(log delta, log F)`` between the two
neighbouring samples (exact for a local power law; exact at a sample).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ssw import hertz
from ssw.curve import ForceCurve
from ssw.errors import OutOfRangeError
from ssw.fit.fitting import scene_inputs

#: m, the thesis's reference indentation (0.001 mm).
DELTA_REF = 1.0e-6
#: Thesis statements at DELTA_REF: Set 1 by plate material (0.4 mm), Set 2 by thickness (m).
THESIS_SET1: dict[str, float] = {"pla": 0.28, "al6061": 1.75, "a36": 2.75}
THESIS_SET2: dict[float, float] = {0.2e-3: 0.37, 0.4e-3: 0.42}


def force_at(curve: ForceCurve, delta: float) -> float:
    """Force (N) at ``delta`` (m), log-log interpolated between neighbouring samples.

    Parameters
    ----------
    curve : ForceCurve
        The force-indentation curve (SI).
    delta : float
        Indentation (m), > 0, within the curve's range.

    Returns
    -------
    float
        Force (N).

    Raises
    ------
    OutOfRangeError
        If ``delta`` is outside the curve's range or has no positive sample below it.
    """
    d, F = np.asarray(curve.delta), np.asarray(curve.force)
    if not d[0] <= delta <= d[-1] or delta <= 0:
        raise OutOfRangeError(
            f"delta = {delta:g} m is outside the curve's range [{d[0]:g}, {d[-1]:g}] m"
        )
    i = int(np.searchsorted(d, delta))
    if np.isclose(d[i], delta, rtol=1e-12, atol=0.0):
        return float(F[i])
    if d[i - 1] <= 0 or F[i - 1] <= 0 or F[i] <= 0:
        raise OutOfRangeError(f"no positive force sample below delta = {delta:g} m")
    t = np.log(delta / d[i - 1]) / np.log(d[i] / d[i - 1])
    return float(np.exp((1 - t) * np.log(F[i - 1]) + t * np.log(F[i])))


def deviation(curve: ForceCurve, delta_ref: float = DELTA_REF, **overrides: Any) -> dict:
    """``{"ratio": F/F_H, "deviation": F/F_H - 1, ...scene}`` at ``delta_ref`` (m).

    ``F_H = 4/3 E/(1 - nu^2) sqrt(R) delta^(3/2)`` is the bare soil's Hertz force under a rigid
    sphere (Johnson 1985, *Contact Mechanics*, section 4.2).

    Parameters
    ----------
    curve : ForceCurve
        The force-indentation curve (SI).
    delta_ref : float
        Reference indentation (m).
    **overrides : Any
        Scene quantities replacing the curve's (:func:`ssw.fit.fitting.scene_inputs`).

    Returns
    -------
    dict
        The scene's inputs, ``delta_ref`` (m), ``ratio`` and ``deviation``.
    """
    sc = scene_inputs(curve, **overrides)
    E_star = hertz.effective_modulus(sc["soil_E"], sc["soil_nu"])
    F_H = float(hertz.force(delta_ref, E_star, sc["radius"]))
    ratio = force_at(curve, delta_ref) / F_H
    return {**sc, "delta_ref": delta_ref, "ratio": ratio, "deviation": ratio - 1.0}


def thesis_value(set_kind: str, plate_material: str, plate_thickness: float) -> float | None:
    """The thesis's stated deviation for a Set 1 (``materials``) or Set 2 (``thickness``)
    scene, or None where it states none.

    Parameters
    ----------
    set_kind : str
        ``materials`` (Set 1) or ``thickness`` (Set 2).
    plate_material : str
        The plate's material key.
    plate_thickness : float
        The plate's thickness (m).

    Returns
    -------
    float or None
        The deviation the thesis states (dimensionless), or None.
    """
    if set_kind == "materials" and abs(plate_thickness - 0.4e-3) < 1e-9:
        return THESIS_SET1.get(plate_material)
    if set_kind == "thickness" and plate_material in ("pla", "none"):
        for t, v in THESIS_SET2.items():
            if abs(plate_thickness - t) < 1e-9:
                return v
    return None


def deviation_rows(
    curves: list[ForceCurve], set_kind: str, delta_ref: float = DELTA_REF
) -> list[dict[str, Any]]:
    """One row per curve: scene, ratio, deviation and the thesis's value (or None).

    Parameters
    ----------
    curves : list of ForceCurve
        The curves (SI).
    set_kind : str
        ``materials`` or ``thickness``.
    delta_ref : float
        Reference indentation (m).

    Returns
    -------
    list of dict
        The rows (see :func:`deviation`) with ``thesis_deviation``.
    """
    rows = []
    for c in curves:
        r = deviation(c, delta_ref)
        r["thesis_deviation"] = thesis_value(
            set_kind, str(r.get("plate_material")), float(r.get("plate_thickness") or 0.0)
        )
        rows.append(r)
    return rows


def calibrate_soil_E(
    target: float,
    deviation_of_E: Callable[[float], float],
    E_lo: float = 1.0e6,
    E_hi: float = 1.0e10,
    rtol: float = 1.0e-4,
) -> float:
    """The soil modulus (Pa) at which ``deviation_of_E(E)`` equals ``target``.

    ``deviation_of_E`` is usually an FEM solve and :func:`deviation` (see ``ssw
    fit-calibrate-soil``): the deviation of a plate falls as the soil stiffens, so one
    statement of the thesis fixes the soil it left unstated; the other statements are then
    predictions.

    Parameters
    ----------
    target : float
        The deviation to reach (dimensionless).
    deviation_of_E : callable
        ``E (Pa) -> deviation``, monotone in ``E`` on ``[E_lo, E_hi]``.
    E_lo : float
        Pa, the bracket's lower end.
    E_hi : float
        Pa, the bracket's upper end.
    rtol : float
        Tolerance on ``log E`` (absolute and relative, :func:`ssw.roots.find_root`'s
        ``xatol`` and ``xrtol``): about ``rtol`` relative on ``E``.

    Returns
    -------
    float
        Pa, the soil modulus.

    Raises
    ------
    OutOfRangeError
        ``target`` is not reached in ``[E_lo, E_hi]`` (the message gives the deviations at
        the ends).

    Notes
    -----
    The root of ``deviation(exp x) - target`` in ``x = log E``, by the bracketed root
    finder of ssw (:func:`ssw.roots.find_root`, Chandrupatla 1997), with the sign turned
    so that the function increases; the bracket's two ends are solved once.

    References
    ----------
    Chandrupatla, T. R. (1997). A new hybrid quadratic/bisection algorithm for finding the
    zero of a nonlinear function without using derivatives. Adv. Eng. Softw. 28(3), 145-149.
    """
    from ssw.roots import find_root

    known: dict[float, float] = {}

    def g(x: float) -> float:
        if x not in known:
            known[x] = deviation_of_E(float(np.exp(x))) - target
        return known[x]

    a, b = float(np.log(E_lo)), float(np.log(E_hi))
    ga, gb = g(a), g(b)
    if ga * gb > 0:
        raise OutOfRangeError(
            f"deviation {target:g} is not reached for soil E in [{E_lo:g}, {E_hi:g}] Pa "
            f"(deviation {ga + target:.4g} .. {gb + target:.4g})"
        )
    sign = 1.0 if gb >= ga else -1.0
    root = find_root(lambda x: np.asarray(sign * g(float(x))), a, b, xatol=rtol, xrtol=rtol)
    return float(np.exp(root.x))


def thesis_statements(
    cfg: dict[str, Any],
    solve: Callable[[Any, dict[str, Any]], ForceCurve],
    material_sets: tuple[str, ...] = ("realistic", "as_printed"),
    sets: dict[str, str] | None = None,
) -> list[dict[str, Any]]:
    """Deviation rows of the thesis's Sets 1 and 2 for each material set, ours and theirs.

    ``solve(scene, cfg_with_material_set)`` returns the scene's curve (an FEM solve);
    ``sets`` maps config set names to kinds (default ``set1_materials -> materials``,
    ``set2_thickness -> thickness``, those present in the config).

    Parameters
    ----------
    cfg : dict
        The validated study config.
    solve : callable
        ``solve(scene, cfg)`` returning the scene's :class:`ssw.curve.ForceCurve`.
    material_sets : tuple of str
        The material sets to compare.
    sets : dict or None
        Config set name -> kind; None: the default mapping.

    Returns
    -------
    list of dict
        Deviation rows per material set and scene.
    """
    import copy

    from ssw.config import scenes

    sets = sets or {"set1_materials": "materials", "set2_thickness": "thickness"}
    rows = []
    for ms in material_sets:
        c = copy.deepcopy(cfg)
        c["material_set"] = ms
        for name, kind in sets.items():
            if name not in c["sets"]:
                continue
            for sc in scenes(c, name):
                if sc.plate_thickness == 0:
                    continue
                r = deviation_rows([solve(sc, c)], kind, c["fit"]["delta_ref"])[0]
                rows.append({"material_set": ms, "set": name, **r})
    return rows
