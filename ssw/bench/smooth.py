"""``ssw bench smooth``: the TOF's smoothness in its parameters, its derivatives, their cost.

Model: the study's chain (``ChainParams.from_config`` of ``--config``: its device, no
calibration file). Parts (``--parts``, default all):

* ``noise``: the TOF on ``--moduli`` moduli 95-105 MPa (0.1 % apart, nu 0.3), per wall of
  ``--walls`` (default ``hertz`` and ``fem``): the relative residual from a polynomial in E
  of degree ``--degree`` (5: the TOF's own curvature over +-5 % needs it to reach 1e-9),
  rms and worst (the measure: 8.7e-7 rms, 1.9e-6 worst on the ``fem`` wall before
  the dense peak and the smooth contact events);
* ``derivatives``: on the thesis's three foams (PCF 08, 15, 30), each parameter's forward
  derivative (:func:`ssw.tof.api.tof_derivatives`) against fourth-order central differences
  of TOFs at the same step, relative step 1e-4 (their worst relative difference, to the
  parameter's largest derivative over the foams), per wall;
* ``cost``: the CPU time (``time.process_time``, best of ``--repeat``) of the 300-point
  sweep (E 10..1000 MPa x nu 0.1/0.3/0.5, Hertz wall, one batched run) without derivatives
  and with 1 and with all 6 parameters' forward sensitivities: the cost factor per
  parameter count.

Writes ``smooth_bench.json`` under ``--output-dir``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

from ssw.h5io import write_json

PARTS = ("noise", "derivatives", "cost")
#: Moduli of the noise part (Pa): 101 values 95-105 MPa.
E_LO, E_HI = 95e6, 105e6
#: The thesis's foams (Table 2): E (Pa), nu.
FOAMS = (np.array([38e6, 123e6, 445e6]), np.array([0.34, 0.33, 0.30]))


def register(kinds: argparse._SubParsersAction) -> None:
    """Add the ``ssw bench smooth`` command and its options.

    Parameters
    ----------
    kinds : argparse._SubParsersAction
        The ``ssw bench`` subcommands.
    """
    p = kinds.add_parser("smooth", help="TOF noise in E, derivatives vs central "
                         "differences, the sensitivities' cost")
    p.add_argument("--config", default="config/config.yaml", help="study config (YAML)")
    p.add_argument("--output-dir", default="results/bench", help="folder of the outputs")
    p.add_argument("--parts", nargs="+", choices=PARTS, default=list(PARTS),
                   help="what to measure: noise, derivatives, cost (default all)")
    p.add_argument("--walls", nargs="+", default=["hertz", "fem"],
                   help="walls of the noise and derivative parts")
    p.add_argument("--moduli", type=int, default=101, help="moduli 95-105 MPa")
    p.add_argument("--degree", type=int, default=5, help="degree of the smooth fit in E")
    p.add_argument("--repeat", type=int, default=3, help="timing repeats (best is kept)")
    p.set_defaults(func=run, human=human)


def noise_part(params: Any, walls: list[str], moduli: int, degree: int) -> dict[str, Any]:
    """rms and worst relative residual of the TOF from a polynomial in E, per wall.

    Parameters
    ----------
    params : ssw.chain.params.ChainParams
        The chain.
    walls : list of str
        The wall laws.
    moduli : int
        Moduli from 95 to 105 MPa.
    degree : int
        The polynomial's degree.

    Returns
    -------
    dict
        Wall -> ``rms`` and ``worst`` (relative), ``tof_100MPa`` (s).
    """
    from ssw.tof import api

    E = np.linspace(E_LO, E_HI, moduli)
    x = (E - 0.5 * (E_LO + E_HI)) / (0.5 * (E_HI - E_LO))
    out = {}
    for wall in walls:
        t = api.tof(E, 0.3, params, wall)
        r = t / np.polyval(np.polyfit(x, t, degree), x) - 1
        out[wall] = {"rms": float(np.sqrt(np.mean(r**2))), "worst": float(np.max(np.abs(r))),
                     "tof_100MPa": float(np.interp(100e6, E, t))}
    return out


def derivatives_part(params: Any, walls: list[str]) -> dict[str, Any]:
    """Forward derivatives against central differences at the same step, per wall.

    Parameters
    ----------
    params : ssw.chain.params.ChainParams
        The chain.
    walls : list of str
        The wall laws.

    Returns
    -------
    dict
        Wall -> parameter -> ``method``, ``worst_relative_difference``, ``forward`` and
        ``central`` (s per unit of the parameter).
    """
    from ssw.tof import api

    E, nu = FOAMS
    out = {}
    for wall in walls:
        fw = api.tof_derivatives(E, nu, params, wall)
        ce = api.tof_derivatives(E, nu, params, wall, method="central")
        out[wall] = {
            k: {"method": fw.method[k],
                "worst_relative_difference": float(np.max(np.abs(fw.dtof[k] - ce.dtof[k]))
                                                   / np.max(np.abs(ce.dtof[k]))),
                "forward": fw.dtof[k].tolist(), "central": ce.dtof[k].tolist()}
            for k in fw.dtof}
    return out


def cost_part(params: Any, repeat: int) -> dict[str, Any]:
    """CPU time of the 300-point Hertz sweep with 0, 1 and 6 parameters' sensitivities.

    Parameters
    ----------
    params : ssw.chain.params.ChainParams
        The chain.
    repeat : int
        Timings; the fastest is kept.

    Returns
    -------
    dict
        ``points`` and ``rows``: per case, ``parameters``, ``cpu`` (s) and ``factor``.
    """
    from ssw.chain.sensitivity import PARAMETERS
    from ssw.tof import api

    E = np.repeat(np.arange(10e6, 1000e6 + 1, 10e6), 3)
    nu = np.tile([0.1, 0.3, 0.5], E.size // 3)
    rows = {}
    for label, names in (("none", None), ("E", ("E",)), ("all", tuple(PARAMETERS))):
        best = np.inf
        for _ in range(max(1, repeat)):
            c0 = time.process_time()
            api.peaks(E, nu, params, "hertz", derivatives=names)
            best = min(best, time.process_time() - c0)
        rows[label] = {"parameters": 0 if names is None else len(names), "cpu": best}
    base = rows["none"]["cpu"]
    for r in rows.values():
        r["factor"] = r["cpu"] / base
    return {"points": int(E.size), "rows": rows}


def run(args: argparse.Namespace) -> dict[str, Any]:
    """Run ``ssw bench smooth`` (module docstring) and write its outputs under ``--output-dir``.

    Parameters
    ----------
    args : argparse.Namespace
        The command's options (:func:`register`).

    Returns
    -------
    dict
        The measurements (times in s, errors relative, SI units otherwise) and the files
        written.
    """
    from ssw.chain.params import ChainParams
    from ssw.config import load_config

    params = ChainParams.from_config(load_config(args.config))
    res: dict[str, Any] = {"command": "ssw bench smooth", "config": args.config}
    if "noise" in args.parts:
        res["noise"] = noise_part(params, args.walls, args.moduli, args.degree)
    if "derivatives" in args.parts:
        res["derivatives"] = derivatives_part(params, args.walls)
    if "cost" in args.parts:
        res["cost"] = cost_part(params, args.repeat)
    out = Path(args.output_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "smooth_bench.json", res, res)
    res["outputs"] = [str(out / "smooth_bench.json")]
    return res


def human(res: dict[str, Any]) -> str:
    """The result of :func:`run` as text for the terminal.

    Parameters
    ----------
    res : dict
        The result of :func:`run`.

    Returns
    -------
    str
        One line per measurement.
    """
    lines = []
    for wall, r in res.get("noise", {}).items():
        lines.append(f"noise {wall:6s}: rms {r['rms']:.2e}, worst {r['worst']:.2e} "
                     f"(101 moduli 95-105 MPa)")
    for wall, r in res.get("derivatives", {}).items():
        worst = max(v["worst_relative_difference"] for v in r.values())
        methods = ", ".join(f"{k} {v['method']}" for k, v in r.items())
        lines.append(f"derivatives {wall}: forward vs central worst {worst:.1e} ({methods})")
    if "cost" in res:
        lines.append("cost (300-point sweep, CPU s): " + ", ".join(
            f"{k} {v['cpu']:.2f} (x{v['factor']:.2f})" for k, v in res["cost"]["rows"].items()))
    return "\n".join(lines)
