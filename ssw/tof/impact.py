"""How much each law's fit error matters for the time of flight (TOF).

For each contact curve, the chain (``ssw.tof.api.tof``) runs with these last-contact laws:

* ``fem``: the exact FEM law of the curve's scene (its plate, interface and mesh settings)
  at the chain bead's radius, computed to whatever depth the chain reaches
  (:mod:`ssw.walls.fem`): no fit, no interpolation, no extrapolation; the reference;
* ``fit_k``: ``F = K A_w delta^1.5`` with this curve's fitted K;
* ``fit_power``: ``F = C delta^n`` with this curve's fitted (C, n);
* ``table``: the curve's samples themselves, interpolated (the former reference: what a
  sampled curve and its power-law extension cost);
* ``hertz``: the bare soil (no plate), for scale.

The TOF error of a law is ``tof_law / tof_fem - 1``; the inverse problem turns it into a
modulus error through the local slope ``d ln TOF / d ln E`` (about -0.2 for a Hertz wall,
``TOF ~ E^(-1/5)`` at fixed striker speed), so a TOF error ``e`` costs about ``e / 0.2 = 5 e``
in E. ssw reports the slope from the Hertz-wall TOF at ``E (1 +- 1 %)``.

The fits use each scene's default range (:mod:`ssw.fit.range`); the result flags scenes
whose chain indentation exceeds the curve (the ``table`` law then extrapolates).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ssw.curve import ForceCurve
from ssw.fit.fitting import fit_curve, scene_inputs
from ssw.fit.range import fit_ranges

#: Relative step of the modulus for the slope d ln TOF / d ln E.
SLOPE_STEP = 0.01
#: The laws compared with the reference ``fem``.
LAWS = ("fit_k", "fit_power", "table", "hertz")


def _fem_groups(curves: list[ForceCurve], scs: list[dict[str, Any]], cfg: dict[str, Any]
                ) -> dict[tuple, tuple[dict[str, Any], dict[str, Any], list[int]]]:
    """Curves by FEM model (plate, interface, mesh settings): ChainParams overrides, the
    ``contact`` settings of the ``fem`` wall and the curves' indices."""
    from ssw.contact.scene import DEFAULTS

    groups: dict[tuple, tuple[dict[str, Any], dict[str, Any], list[int]]] = {}
    for i, (c, sc) in enumerate(zip(curves, scs, strict=True)):
        contact = {**DEFAULTS, **cfg.get("contact", {}),
                   **{k: c.inputs[k] for k in DEFAULTS if k in c.inputs}}
        contact = {k: contact[k] for k in DEFAULTS}
        t = float(sc.get("plate_thickness") or 0.0)
        plate: dict[str, Any] = {"plate_thickness": t,
                                 "plate_interface": str(contact["interface"]),
                                 "plate_diameter": float(contact["plate_diameter"])}
        if t > 0:
            plate.update(plate_E=float(sc["plate_E"]), plate_nu=float(sc["plate_nu"]),
                         plate_material=str(sc.get("plate_material", "custom")))
        key = (tuple(sorted(plate.items())), tuple(sorted(contact.items())))
        groups.setdefault(key, (plate, contact, []))[2].append(i)
    return groups


def tof_impact(curves: list[ForceCurve], cfg: dict[str, Any],
               records: list[dict[str, Any]] | None = None) -> list[dict[str, Any]]:
    """Per curve: TOF (s) with each law, their errors against the ``fem`` law, K and (C, n).

    ``records``: the curves' fits when already made (:func:`ssw.fit.pipeline.fit_files`,
    with the ``k_hertz`` and ``power`` laws on the default ranges), else they are fitted.

    Parameters
    ----------
    curves : list of ForceCurve
        Force-indentation curves of the contact FEM (SI).
    cfg : dict
        The validated config (device, fit settings).
    records : list of dict or None
        The curves' fits, or None to fit them here.

    Returns
    -------
    list of dict
        One record per curve: TOFs (s), relative errors, ``K`` (N/m^1.5), ``C`` and ``n``.
    """
    from ssw.chain.params import ChainParams
    from ssw.chain.run import run_peaks
    from ssw.chain.wall import PowerWall
    from ssw.fit.range import FitRange
    from ssw.tof import api
    from ssw.walls import build_wall

    params = ChainParams.from_config(cfg)
    scs = [scene_inputs(c) for c in curves]
    E = np.array([float(s["soil_E"]) for s in scs])
    nu = np.array([float(s["soil_nu"]) for s in scs])
    if records is not None and all({"k_hertz", "power"} <= set(r["fits"]) for r in records):
        ranges = [FitRange(**r["range"]) for r in records]
        fk = [r["fits"]["k_hertz"] for r in records]
        fp = [r["fits"]["power"] for r in records]
    else:
        ranges = fit_ranges(E, nu, [float(c.delta[-1]) for c in curves], cfg,
                            [s.get("plate_E") for s in scs], [s.get("plate_nu") for s in scs])
        w = cfg["fit"]["weighting"]
        fk = [fit_curve(c, "k_hertz", (r.lo, r.hi), weighting=w)
              for c, r in zip(curves, ranges, strict=True)]
        fp = [fit_curve(c, "power", (r.lo, r.hi), weighting=w)
              for c, r in zip(curves, ranges, strict=True)]
    K = np.array([f.params["K"] for f in fk])
    C = np.array([f.params["C"] for f in fp])
    n = np.array([f.params["n"] for f in fp])
    tof_fem = np.empty(E.size)
    for plate, contact, idx in _fem_groups(curves, scs, cfg).values():
        ix = np.array(idx)
        tof_fem[ix] = api.tof(E[ix], nu[ix], params.with_(**plate), "fem", contact=contact)
    # the power-law walls in one batched run: K, (C, n), and Hertz at E and E (1 +- step)
    # (the slope)
    walls = [build_wall("fit", params, E, nu, K=K),
             build_wall("fit", params, E, nu, power=(C, n)),
             build_wall("hertz", params, np.concatenate([E, E * (1 + SLOPE_STEP),
                                                         E * (1 - SLOPE_STEP)]),
                        np.concatenate([nu, nu, nu]))]
    allw = PowerWall(np.concatenate([w.coef for w in walls]),
                     np.concatenate([w.exponent for w in walls]))
    pk, _ = run_peaks(params, allw)
    fit_k, fit_power, hertz, up, dn = np.split(pk.tof, 5)
    tof = {
        "fem": tof_fem,
        "fit_k": fit_k,
        "fit_power": fit_power,
        "table": api.tof(E, nu, params, "table", curve=list(curves)),
        "hertz": hertz,
    }
    slope = np.log(up / dn) / np.log((1 + SLOPE_STEP) / (1 - SLOPE_STEP))
    rows = []
    for i, sc in enumerate(scs):
        row: dict[str, Any] = {
            "plate_material": sc.get("plate_material"),
            "plate_thickness": sc.get("plate_thickness"),
            "soil_E": E[i],
            "soil_nu": nu[i],
            "fit_delta_hi": ranges[i].hi,
            "chain_delta_needed": ranges[i].needed,
            "curve_too_short": ranges[i].clipped,
            "K": K[i],
            "k_rms_rel_residual": fk[i].rms_rel_residual,
            "C": C[i],
            "n": n[i],
            "power_rms_rel_residual": fp[i].rms_rel_residual,
            "dlnTOF_dlnE": slope[i],
        }
        for law, t in tof.items():
            row[f"tof_{law}"] = float(t[i])
        for law in LAWS:
            e = float(tof[law][i] / tof["fem"][i] - 1.0)
            row[f"tof_err_{law}"] = e
            row[f"E_err_{law}"] = e / float(slope[i])
        rows.append(row)
    return rows
