"""The answer: the TOF error of the quasi-static assumption over soils and plates.

For every scene of a grid (soil E x density, with and without the plate, one Poisson's
ratio) :func:`scene_point` runs the dynamic FEM wall and the quasi-static references
(:func:`ssw.dynamics.api.fem_tof`) and the reduced wall on the same quasi-static laws
(:func:`ssw.dynamics.api.reduced_tof`: the static FEM laws of the 1 and 3 m boxes,
tabulated, half-space by ``1 / L`` extrapolation as for the FEM). Points are appended to
a JSON-lines file as they finish (a long study resumes where it stopped);
:func:`summarize` turns them into the table and the figure.

Error conventions (relative, of the TOF): ``error = TOF_qs / TOF_dyn - 1`` against the
half-space's static law (the quasi-static *assumption*); ``error_box`` against the 1 m box
of the quasi-static study (what the study's TOFs carry: assumption plus the box's static
stiffening); ``reduced_error = TOF_red / TOF_dyn - 1`` for the reduced wall on the
half-space law (what remains with the reduced wall).
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import numpy as np

#: The study's grid: soil moduli (Pa) and densities (kg/m^3): foams 130-480, soils
#: 1600-2200.
STUDY_E = (10e6, 30e6, 100e6, 300e6, 1000e6)
STUDY_DENSITY = (130.0, 480.0, 1600.0, 2200.0)
STUDY_NU = 0.3
#: Where the study says the reduced wall is needed: ``|error|`` above this.
THRESHOLD = 0.0025


def scene_point(params: Any, E: float, nu: float, rho: float, **options: Any
                ) -> dict[str, Any]:
    """One scene: dynamic FEM, quasi-static boxes, reduced wall (module docstring).

    Parameters
    ----------
    params : ChainParams
        The chain.
    E : float
        Soil Young's modulus (Pa).
    nu : float
        Soil Poisson's ratio.
    rho : float
        Soil density (kg/m^3).
    **options : Any
        Options of :func:`ssw.dynamics.api.fem_tof`.

    Returns
    -------
    dict
        The point: soil, plate, TOFs (s), errors, dofs and timings (s).
    """
    from ssw.dynamics.api import fem_tof

    t0 = time.perf_counter()
    res = fem_tof(params, E, nu, rho, keep_curves=True, **options)
    st = res.stats[0]
    red = reduced_point(params, E, nu, rho, res.curves[0])
    return {
        "soil_E": E, "soil_nu": nu, "soil_density": rho,
        "plate_thickness": float(params.plate_thickness),
        "plate_material": params.plate_material if params.plate_thickness > 0 else "none",
        "tof_dynamic": float(res.tof_dynamic[0]), "tof_static_box": float(res.tof_static[0]),
        "tof_half_space": float(res.tof_half_space[0]),
        "error": float(res.error[0]), "error_box": float(res.error_box[0]),
        "tof_reduced": red,
        "reduced_error": red / float(res.tof_dynamic[0]) - 1.0,
        "wall_total": time.perf_counter() - t0, **{k: v for k, v in st.items()},
    }


def reduced_point(params: Any, E: float, nu: float, rho: float,
                  laws: dict[float, tuple[np.ndarray, np.ndarray]] | None = None,
                  **coefficients: float) -> float:
    """The reduced wall's TOF (s) on the half-space law of one scene
    (:func:`ssw.dynamics.api.reduced_tof`; ``laws``: the static boxes' laws if known).

    Parameters
    ----------
    params : ChainParams
        The chain.
    E : float
        Soil Young's modulus (Pa).
    nu : float
        Soil Poisson's ratio.
    rho : float
        Soil density (kg/m^3).
    laws : dict or None
        The static boxes' laws, if known.
    **coefficients : float
        Reduced-wall coefficients (``c_r``, ``m_r``, ``k_p``) replacing the defaults.

    Returns
    -------
    float
        TOF (s).
    """
    from ssw.dynamics.api import reduced_tof

    r = reduced_tof(params, E, nu, rho, laws=None if laws is None else [laws], **coefficients)
    return float(r.tof_dynamic[0])


def refresh_reduced(params: Any, points: list[dict[str, Any]], **coefficients: float
                    ) -> list[dict[str, Any]]:
    """The points with their reduced-wall columns recomputed (static laws rebuilt: seconds
    per point), e.g. after a change of the reduced wall; the FEM columns are kept.

    Parameters
    ----------
    params : ChainParams
        The chain.
    points : list of dict
        The study's points.
    **coefficients : float
        Reduced-wall coefficients (``c_r``, ``m_r``, ``k_p``) replacing the defaults.

    Returns
    -------
    list of dict
        The points with new ``tof_reduced`` (s) and ``reduced_error``.
    """
    out = []
    for p in points:
        pk = params if p["plate_thickness"] > 0 else params.with_(plate_thickness=0.0)
        if pk.plate_thickness > 0 and abs(pk.plate_thickness - p["plate_thickness"]) > 1e-12:
            pk = params.with_(plate_thickness=p["plate_thickness"])
        tof = reduced_point(pk, p["soil_E"], p["soil_nu"], p["soil_density"], **coefficients)
        out.append({**p, "tof_reduced": tof, "reduced_error": tof / p["tof_dynamic"] - 1.0})
    return out


def run_study(params: Any, out: Path, *, E: tuple[float, ...] = STUDY_E,
              density: tuple[float, ...] = STUDY_DENSITY, nu: float = STUDY_NU,
              plates: tuple[bool, ...] = (True, False), **options: Any) -> list[dict[str, Any]]:
    """Run (or resume) the grid; every point is appended to ``out`` (JSON lines) when done.
    Returns every point of the grid.

    Parameters
    ----------
    params : ChainParams
        The chain.
    out : pathlib.Path
        The JSON lines file.
    E : tuple of float
        Soil moduli (Pa).
    density : tuple of float
        Soil densities (kg/m^3).
    nu : float
        Soil Poisson's ratio.
    plates : tuple of bool
        With and/or without the plate.
    **options : Any
        Options of :func:`scene_point`.

    Returns
    -------
    list of dict
        Every point of the grid.
    """
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    done = {_key(r): r for r in read_points(out)} if out.is_file() else {}
    points = []
    for plate in plates:
        p = params if plate else params.with_(plate_thickness=0.0)
        for e in E:
            for rho in density:
                key = _key({"soil_E": e, "soil_density": rho, "soil_nu": nu,
                            "plate_thickness": float(p.plate_thickness)})
                if key not in done:
                    rec = scene_point(p, e, nu, rho, **options)
                    with out.open("a") as f:
                        f.write(json.dumps(rec) + "\n")
                    done[key] = rec
                points.append(done[key])
    return points


def _key(r: dict[str, Any]) -> tuple:
    return (round(float(r["soil_E"]), 3), round(float(r["soil_density"]), 6),
            round(float(r["soil_nu"]), 6), round(float(r["plate_thickness"]), 9))


def read_points(path: Path) -> list[dict[str, Any]]:
    """The points of a study file (JSON lines).

    Parameters
    ----------
    path : pathlib.Path
        The JSON lines file.

    Returns
    -------
    list of dict
        The points.
    """
    return [json.loads(x) for x in Path(path).read_text().splitlines() if x.strip()]


def summarize(points: list[dict[str, Any]], out_dir: Path, threshold: float = THRESHOLD
              ) -> dict[str, Any]:
    """CSV table, figure and verdict of the study's points (written atomically).

    Parameters
    ----------
    points : list of dict
        The study's points.
    out_dir : pathlib.Path
        The output directory.
    threshold : float
        Largest accepted relative TOF error.

    Returns
    -------
    dict
        The verdict: the point count, the largest errors, the points above the threshold
        and the outputs' paths.
    """
    from ssw.h5io import atomic_write_text
    from ssw.plotting import pyplot, save_png

    out_dir = Path(out_dir)
    cols = ("plate_material", "soil_E", "soil_density", "soil_nu", "tof_dynamic",
            "tof_static_box", "tof_half_space", "error", "error_box", "tof_reduced",
            "reduced_error", "dofs", "wall_total")
    lines = [",".join(cols)] + [",".join(_fmt(p[c]) for c in cols) for p in points]
    atomic_write_text(out_dir / "dynamic_error.csv", "\n".join(lines) + "\n")
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2), sharey=True)
    for ax, mat in zip(axes, ("pla", "none"), strict=True):
        sel = [p for p in points if (p["plate_material"] != "none") == (mat != "none")]
        for rho in sorted({p["soil_density"] for p in sel}):
            pts = sorted((p for p in sel if p["soil_density"] == rho), key=lambda p: p["soil_E"])
            E = [p["soil_E"] / 1e6 for p in pts]
            ax.semilogx(E, [100 * p["error"] for p in pts], "o-", label=f"{rho:g} kg/m3")
            ax.semilogx(E, [100 * p["reduced_error"] for p in pts], "x:", color="gray")
        ax.axhline(100 * threshold, color="r", lw=0.8, ls="--")
        ax.axhline(-100 * threshold, color="r", lw=0.8, ls="--")
        ax.set_xlabel("soil E (MPa)")
        ax.set_title("0.4 mm PLA plate" if mat != "none" else "no plate")
        ax.grid(alpha=0.3, which="both")
    axes[0].set_ylabel("TOF error of the quasi-static wall (%)")
    axes[0].legend(title="soil density (o: quasi-static, x: reduced)", fontsize=8)
    fig.tight_layout()
    save_png(fig, out_dir / "dynamic_error.png", dpi=150)
    worst = max(points, key=lambda p: abs(p["error"])) if points else None
    above = [p for p in points if abs(p["error"]) > threshold]
    return {"points": len(points), "threshold": threshold,
            "max_abs_error": abs(worst["error"]) if worst else float("nan"),
            "worst": worst, "above_threshold": above,
            "max_abs_reduced_error": max((abs(p["reduced_error"]) for p in points),
                                         default=float("nan")),
            "outputs": [str(out_dir / "dynamic_error.csv"), str(out_dir / "dynamic_error.png")]}


def _fmt(x: Any) -> str:
    if isinstance(x, float):
        return f"{x:.9g}"
    return str(x)
