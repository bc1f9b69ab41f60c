"""``ssw dynamic-tof`` and ``ssw dynamic-study``: the soil's inertia at the last contact.

``dynamic-tof`` gives one scene's TOF with a dynamic wall (``--wall-dynamics fem``: the
elastodynamic FEM, ~1 min; ``reduced``: the quasi-static law plus radiation damping and
participating mass, seconds: the scene's static FEM laws, then milliseconds per run) next to
its quasi-static TOF. ``dynamic-study`` runs (or
resumes) the grid of soil E x density, with and without the plate, and writes the table
and the figure of the quasi-static assumption's TOF error. The chain comes from the study
config (``--config``); SI units.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from ssw.cli import add_json_flag
from ssw.errors import ConfigError


def _params(args: argparse.Namespace) -> Any:
    from ssw.chain.params import ChainParams
    from ssw.config import load_config

    cfg = load_config(args.config)
    over = {}
    if args.plate_thickness is not None:
        over["plate_thickness"] = float(args.plate_thickness)
    return ChainParams.from_config(cfg, **over)


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--config", default=None, help="study config (default config/config.yaml)")
    p.add_argument("--plate-thickness", type=float, default=None,
                   help="m, the plate under the last bead (0: none; default: the config's)")
    p.add_argument("--soil-nu", type=float, default=0.3, help="soil Poisson's ratio")
    p.add_argument("--boundary", choices=("absorbing", "fixed"), default="absorbing",
                   help="truncation boundary of the dynamic FEM")
    p.add_argument("--wave-elements", type=float, default=None,
                   help="quadratic elements per shear wavelength at f_max (default: "
                        "ssw.dynamics.domain.WAVE_ELEMENTS)")
    add_json_flag(p)


def _spec(args: argparse.Namespace) -> dict[str, Any]:
    return {} if args.wave_elements is None else {"wave_elements": float(args.wave_elements)}


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``ssw dynamic-tof``, ``ssw dynamic-study`` subcommands to the command line.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of the ``ssw`` parser.
    """
    p = sub.add_parser("dynamic-tof", help="TOF with a dynamic (inertial) wall vs quasi-static",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--soil-E", type=float, required=True, help="soil Young's modulus, Pa")
    p.add_argument("--soil-density", type=float, required=True, help="soil density, kg/m^3")
    p.add_argument("--wall-dynamics", choices=("fem", "reduced"), default="reduced",
                   help="fem: elastodynamic FEM wall; reduced: quasi-static law + damping "
                        "and participating mass")
    _common(p)
    p.set_defaults(func=run_tof, human=human_tof)

    s = sub.add_parser("dynamic-study", help="TOF error of the quasi-static wall over soils",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    s.add_argument("--output-dir", default="results/dynamics", help="folder of the outputs")
    s.add_argument("--soil-E", type=float, nargs="+", default=None, help="moduli, Pa")
    s.add_argument("--soil-density", type=float, nargs="+", default=None,
                   help="densities, kg/m^3")
    s.add_argument("--plates", nargs="+", choices=("plate", "none"), default=["plate", "none"],
                   help="with the config's plate and/or without")
    s.add_argument("--summary-only", action="store_true",
                   help="only tabulate the points already computed")
    s.add_argument("--refresh-reduced", action="store_true",
                   help="recompute the reduced wall's columns of the points (seconds each)")
    _common(s)
    s.set_defaults(func=run_study, human=human_study)


def run_tof(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw dynamic-tof``: the TOF with a dynamic (inertial) wall against the quasi-static ones.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw dynamic-tof --help``).

    Returns
    -------
    dict of str to Any
        ``tof_dynamic``, ``tof_static_box``, ``tof_half_space`` (s), the relative
        errors ``error`` and ``error_box`` (-), ``wall_dynamics`` and the run's statistics.

    Raises
    ------
    ssw.errors.ConfigError
        When the soil's E or density is missing.
    """
    from ssw.dynamics.api import fem_tof, reduced_tof

    if not args.soil_E > 0 or not args.soil_density > 0:
        raise ConfigError("--soil-E/--soil-density", (args.soil_E, args.soil_density),
                          "E > 0 Pa and a density > 0 kg/m^3")
    params = _params(args)
    if args.wall_dynamics == "fem":
        r = fem_tof(params, args.soil_E, args.soil_nu, args.soil_density,
                    boundary=args.boundary, spec=_spec(args))
        st = r.stats[0]
        return {"tof_dynamic": float(r.tof_dynamic[0]), "tof_static_box": float(r.tof_static[0]),
                "tof_half_space": float(r.tof_half_space[0]), "error": float(r.error[0]),
                "error_box": float(r.error_box[0]), "wall_dynamics": "fem", **st}
    r = reduced_tof(params, args.soil_E, args.soil_nu, args.soil_density)
    return {"tof_dynamic": float(r.tof_dynamic[0]), "tof_static_box": float(r.tof_static[0]),
            "tof_half_space": float(r.tof_half_space[0]), "error": float(r.error[0]),
            "error_box": float(r.error_box[0]), "wall_dynamics": "reduced", **r.stats[0]}


def human_tof(res: dict[str, Any]) -> str:
    """The short summary of ``ssw dynamic-tof`` on the terminal: the dynamic TOF beside the
    quasi-static ones.

    Parameters
    ----------
    res : dict of str to Any
        The command's result (SI units).

    Returns
    -------
    str
        The summary (times in ms, errors in %).
    """
    return (f"TOF {res['wall_dynamics']} {1e3 * res['tof_dynamic']:.5f} ms; quasi-static: "
            f"half-space {1e3 * res['tof_half_space']:.5f} ms ({100 * res['error']:+.3f} %), "
            f"1 m box {1e3 * res['tof_static_box']:.5f} ms ({100 * res['error_box']:+.3f} %)")


def run_study(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw dynamic-study``: the TOF error of the quasi-static wall over soils.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw dynamic-study --help``).

    Returns
    -------
    dict of str to Any
        The study's summary (:func:`ssw.dynamics.study.summarize`).

    Raises
    ------
    ssw.errors.ConfigError
        When ``--output-dir`` holds no ``points.jsonl``.
    """
    from ssw.dynamics import study

    params = _params(args)
    out = Path(args.output_dir)
    path = out / "points.jsonl"
    if args.summary_only:
        if not path.is_file():
            raise ConfigError("--output-dir", str(out), "a folder with a points.jsonl")
        points = study.read_points(path)
        if args.refresh_reduced:
            from ssw.h5io import atomic_write_text

            points = study.refresh_reduced(params, points)
            atomic_write_text(path, "".join(json.dumps(p) + "\n" for p in points))
    else:
        points = study.run_study(
            params, path, E=tuple(args.soil_E or study.STUDY_E),
            density=tuple(args.soil_density or study.STUDY_DENSITY), nu=args.soil_nu,
            plates=tuple(x == "plate" for x in args.plates), boundary=args.boundary,
            spec=_spec(args))
    return study.summarize(points, out)


def human_study(res: dict[str, Any]) -> str:
    """The short summary of ``ssw dynamic-study`` on the terminal: the largest errors and the
    outputs.

    Parameters
    ----------
    res : dict of str to Any
        The command's result (SI units).

    Returns
    -------
    str
        The summary (times in ms, errors in %).
    """
    w = res["worst"]
    lines = [f"{res['points']} points; largest |TOF error| of the quasi-static wall "
             f"{100 * res['max_abs_error']:.3f} %"
             + (f" ({w['plate_material']}, E {w['soil_E'] / 1e6:g} MPa, "
                f"{w['soil_density']:g} kg/m^3)" if w else ""),
             f"above {100 * res['threshold']:.2f} %: {len(res['above_threshold'])} points; "
             f"reduced wall: largest |error| {100 * res['max_abs_reduced_error']:.3f} %",
             "outputs: " + ", ".join(res["outputs"])]
    return "\n".join(lines)
