"""``ssw chain``, ``ssw tof``, ``ssw tof-sweep``, ``ssw tof-merge``, ``ssw invert``.

The chain is a device (``--device``, or the config's) or a calibrated device
(``--calibration``), with flags overriding single fields; the numerics come from the study
config's ``chain:`` section (see :mod:`ssw.cli._device` for the resolution order). Bead
indices count from the striker (bead 0), 0-based; ``--beads`` counts every bead, the striker
included. SI units.
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from ssw.cli import _summary, add_json_flag
from ssw.cli._device import add_device_options, chain_context
from ssw.cli._soil import add_plate_model_options, add_soil_model_options
from ssw.errors import ConfigError


def _params_dict(params: Any) -> dict[str, Any]:
    from dataclasses import asdict

    return {f"chain_{k}": v for k, v in asdict(params).items()}


def context_strengths(ctx: Any, sample: Any = None, source: str = "") -> Any:
    """The strengths of the yield checks (:func:`ssw.validity.strengths_of`) of a resolved
    chain context: its device's beads and plate in its materials (the calibration's, else
    the config's library), the sample's ``sample`` (Pa, one or one per scene) from
    ``source`` when known.

    Parameters
    ----------
    ctx : ssw.cli._device.ChainContext
        The resolved chain context.
    sample : float or numpy.ndarray or None
        Pa, the sample's strength (one, or one per scene); None: not known.
    source : str
        Where the sample's strength comes from.

    Returns
    -------
    ssw.validity.Strengths
        The strengths of the beads, the plate and the sample (Pa).
    """
    from ssw.config import library
    from ssw.validity import strengths_of

    mats = ctx.calibration.materials() if ctx.calibration is not None else library(ctx.cfg)
    return strengths_of(ctx.params, mats, ctx.device.bead_material, sample=sample,
                        sample_source=source)


def sample_statement(sample: Any) -> str:
    """The stated sample geometry a ``finite_sample`` check rests on, in words.

    Parameters
    ----------
    sample : ssw.sample.Sample
        The tested block (lengths in m).

    Returns
    -------
    str
        Its thickness and radius (mm), base and side.
    """
    d = sample.to_dict()
    parts = [f"thickness {d['thickness'] * 1e3:g} mm"]
    if d.get("radius") is not None:
        parts.append(f"radius {d['radius'] * 1e3:g} mm")
    parts += [f"base {d['base']}", f"side {d['lateral']}"]
    return "the sample as stated: " + ", ".join(parts)


def finite_sample_validity(ctx: Any, E: Any, nu: Any, tof: Any) -> Any:
    """The ``finite_sample`` check of TOFs ``tof`` (s) on the context's stated sample at
    ``E`` (Pa), ``nu`` (:func:`ssw.lift.half_space_departure`), or None without a
    stated sample.

    Parameters
    ----------
    ctx : ssw.cli._device.ChainContext
        The resolved chain context (its sample and wall options).
    E : float or numpy.ndarray
        Pa, the soil moduli.
    nu : float or numpy.ndarray
        The soils' Poisson's ratios (-).
    tof : float or numpy.ndarray
        s, the TOFs on the sample.

    Returns
    -------
    ssw.validity.Validity or None
        The check, or None without a stated sample.
    """
    from ssw.lift import half_space_departure
    from ssw.validity import finite_sample

    if ctx.sample is None:
        return None
    dep = half_space_departure(ctx.params, E, nu, tof, ctx.device_wall_options or {})
    return finite_sample(dep, sample_statement(ctx.sample))


def add_stress_checks_option(p: argparse.ArgumentParser, default: str) -> None:
    """``--stress-checks`` (:data:`ssw.validity.STRESS_MODES`).

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser (the options are added to it).
    default : str
        The mode when the flag is not given.
    """
    from ssw.validity import STRESS_MODES

    p.add_argument("--stress-checks", choices=STRESS_MODES, default=default,
                   help="the yield checks of the sample and the plate (validity): fem (the "
                   "contact FEM's stresses at the peak wall force), bound (the sample's "
                   "Hertz upper bound only; no plate check) or none (default "
                   f"{default})")


# ---------------------------------------------------------------------------- ssw chain
def run_chain(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw chain``: one chain run to ``--t-end``, every contact force written to HDF5.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw chain --help``).

    Returns
    -------
    dict of str to Any
        The output file, its sizes, the time step (s), the wall, the peak wall force (N)
        and indentation (m).

    Raises
    ------
    ssw.errors.ConfigError
        When ``--t-end`` is not a duration > 0 s.
    """
    from ssw.h5io import atomic_h5, write_dataset
    from ssw.tof.api import run_chain as simulate_one

    ctx = chain_context(args, args.soil_E, args.soil_nu)
    params, wall, opts = ctx.params, ctx.wall, ctx.wall_options
    if not args.t_end > 0:
        raise ConfigError("--t-end", args.t_end, "a duration > 0 s")
    run = simulate_one(params, args.soil_E, args.soil_nu, wall, t_end=args.t_end, **opts)
    every = max(1, int(args.record_every))
    t = run.t[::every]
    forces = run.forces[::every, 0, :]
    energy = run.energy[::every, 0]
    inputs = {**vars(args), **_params_dict(params), **ctx.inputs()}
    inputs = {k: v for k, v in inputs.items() if k not in ("func", "human")}
    with atomic_h5(args.output, kind="chain_run", inputs=inputs) as f:
        write_dataset(f, "time", t, "s", "time from the striker's first contact")
        write_dataset(f, "contact_force", forces, "N",
                      "n_time x n_contacts: contact j between beads j and j+1 from the "
                      "striker end; last column the wall")
        write_dataset(f, "energy", energy, "J", "kinetic + elastic - gravity potential")
        write_dataset(f, "sensor_force", run.sensor[::every, 0], "N",
                      "mean of the sensor particle's two contact forces")
    e0 = float(energy[0])
    return {
        "output": args.output, "n_time": int(t.size), "n_contacts": int(forces.shape[1]),
        "dt": run.dt, "wall": wall,
        "peak_wall_force": float(np.max(forces[:, -1])),
        "peak_wall_indentation": float(run.peak_wall_indentation[0]),
        "energy_drift_relative": float(np.max(np.abs(energy - e0)) / abs(e0)) if e0 else 0.0,
    }


# ---------------------------------------------------------------------------- ssw tof
#: ``--derivatives`` choices: the method (``auto``: exact forward sensitivities where the
#: wall states its derivatives, else central differences; the dynamic FEM wall, a minute
#: per run, only when asked: ``central``) or ``none``.
DERIVATIVES = ("auto", "forward", "central", "none")


def run_tof(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw tof``: the TOF at the sensor for one soil (with its sensitivities when asked).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw tof --help``).

    Returns
    -------
    dict of str to Any
        The TOF and the peaks' times (s) and forces (N), the time step (s), the
        sensitivities and validity checks, with the device's inputs (SI units).

    Raises
    ------
    ssw.errors.ConfigError
        When only one of ``--soil-E`` and ``--soil-nu`` is given, or on a
        ``--derivatives`` method the wall cannot give.
    """
    from ssw.chain.sensitivity import PARAMETERS
    from ssw.chain.sensitivity import units as sensitivity_units
    from ssw.tof.api import peaks, tof_derivatives

    if args.hits is not None or args.soil_model is not None or args.plate_model is not None:
        args.human = _human_hits
        return _run_hits(args)
    if args.soil_E is None or args.soil_nu is None:
        raise ConfigError("--soil-E/--soil-nu", (args.soil_E, args.soil_nu), "both given")
    ctx = chain_context(args, args.soil_E, args.soil_nu)
    params = ctx.params
    method = args.derivatives
    units = {f"dtof_d{k}": f"s/({u})" for k, u in sensitivity_units(params.damping_law).items()}
    if ctx.wall_options.get("dynamics") == "fem":
        from ssw.dynamics.api import fem_tof, fem_tof_derivatives

        res = fem_tof(params, args.soil_E, args.soil_nu, ctx.wall_options["soil_density"])
        out = {**ctx.inputs(), "tof": float(np.ravel(res.tof_dynamic)[0]),
               "tof_quasi_static_half_space": float(np.ravel(res.tof_half_space)[0]),
               "tof_quasi_static_box": float(np.ravel(res.tof_static)[0]),
               "quasi_static_error": float(np.ravel(res.error)[0]),
               "striker_velocity": params.striker_velocity}
        if method == "forward":
            raise ConfigError("--derivatives", method, "central or none with --wall-dynamics "
                              "fem (the dynamic FEM wall has no forward sensitivities)")
        if method == "central":
            _, dtof, steps = fem_tof_derivatives(params, args.soil_E, args.soil_nu,
                                                 ctx.wall_options["soil_density"])
            out.update({f"dtof_d{k}": float(v[0]) for k, v in dtof.items()})
            out.update(derivative_method=dict.fromkeys(dtof, "central"),
                       derivative_units=units, derivative_step=steps)
        else:
            out.update(derivative_method=dict.fromkeys(PARAMETERS, "none"),
                       derivative_note="--derivatives central: central differences of the "
                       "dynamic FEM wall's TOF, two FEM runs per parameter")
        return {**out, **_quasi_static_validity(args, ctx).to_dict(0)}
    if method == "none":
        pk, run = peaks(args.soil_E, args.soil_nu, params, ctx.wall, **ctx.wall_options)
        extra: dict[str, Any] = {"derivative_method": dict.fromkeys(PARAMETERS, "none")}
    else:
        res = tof_derivatives(args.soil_E, args.soil_nu, params, ctx.wall, method=method,
                              **ctx.wall_options)
        pk, run = res.peaks, res.run
        extra = res.as_dict(0)
        extra.pop("tof")
    return {
        **ctx.inputs(),
        "tof": float(pk.tof[0]), "t_incident": float(pk.t_incident[0]),
        "t_reflected": float(pk.t_reflected[0]), "f_incident": float(pk.f_incident[0]),
        "f_reflected": float(pk.f_reflected[0]), "dt": run.dt,
        "peak_wall_indentation": float(run.peak_wall_indentation[0]),
        "striker_velocity": params.striker_velocity, **extra,
        **_point_validity(args, ctx, pk, run).to_dict(0),
    }


def _quasi_static_validity(args: argparse.Namespace, ctx: Any) -> Any:
    """The checks of the dynamic FEM wall's point, from the quasi-static chain at the same
    ``--soil-E``/``--soil-nu`` (its peak indentation, pulses and stresses; each entry says
    so)."""
    from dataclasses import replace

    from ssw.tof.sweep import run_sweep

    opts = {k: v for k, v in ctx.wall_options.items() if k not in ("dynamics", "soil_density")}
    v = run_sweep(ctx.params, np.array([float(args.soil_E)]), np.array([float(args.soil_nu)]),
                  ctx.wall, strengths=context_strengths(ctx), stresses=args.stress_checks,
                  **opts).validity
    said = "from the quasi-static chain at the same E (the dynamic FEM wall keeps no run)"
    return replace(v, notes={k: "; ".join(filter(None, [v.notes.get(k), said]))
                             for k in v.values})


def _point_validity(args: argparse.Namespace, ctx: Any, pk: Any, run: Any) -> Any:
    """The checks of ``ssw tof``'s run at ``--soil-E``/``--soil-nu`` (ssw.validity)."""
    from ssw.validity import assess, fem_options
    from ssw.walls import build_wall

    E, nu = np.atleast_1d(float(args.soil_E)), np.atleast_1d(float(args.soil_nu))
    wall = build_wall(ctx.wall, ctx.params, E, nu, **ctx.wall_options)
    v = assess(ctx.params, E, nu, run, pk, wall, strengths=context_strengths(ctx),
               stresses=args.stress_checks, **fem_options(ctx.wall, ctx.wall_options))
    fs = finite_sample_validity(ctx, E, nu, pk.tof)
    return v if fs is None else v.merged(fs)


def _run_hits(args: argparse.Namespace) -> dict[str, Any]:
    """``--hits N`` consecutive hits on one plastic sample, or through a yielding plate
    (:mod:`ssw.walls.hits`)."""
    from ssw.cli._soil import plate_model_of, soil_material_of, soil_model_of
    from ssw.config import library, load_config
    from ssw.walls.hits import run_hits
    from ssw.walls.plastic import Settings, plastic_wall

    cfg = load_config(args.config)
    if args.soil_model is None and args.plate_model is None:
        raise ConfigError("--soil-model", None, "a plastic model of the sample (or "
                          "--plate-model: a yielding plate on an elastic sample)")
    model = None
    if args.soil_model is not None:
        model = soil_model_of(args, cfg)
    else:  # an elastic sample: its E and nu from the flags, or the library's
        soil_material_of(args, cfg)
    if model is None and (args.soil_E is None or args.soil_nu is None):
        raise ConfigError("--soil-E/--soil-nu", (args.soil_E, args.soil_nu), "both given")
    ctx = chain_context(args, args.soil_E, args.soil_nu)
    if ctx.wall_options.get("dynamics"):
        raise ConfigError("--wall-dynamics", ctx.wall_options["dynamics"],
                          "quasi-static with --hits (the plastic wall is static)")
    p = ctx.params
    plate_model = plate_model_of(args, library(cfg),
                                 p.plate_material if p.plate_thickness > 0 else "none")
    settings = Settings(levels=args.plastic_levels, increments=args.plastic_increments)
    wall = plastic_wall(ctx.params, args.soil_E, args.soil_nu, soil_model=model,
                        plate_model=plate_model, settings=settings)
    res = run_hits(ctx.params, wall, 1 if args.hits is None else args.hits)
    rows = res.rows()
    tof = np.array([r["tof"] for r in rows])
    return {
        **ctx.inputs(), "wall": "plastic", "soil_E": args.soil_E, "soil_nu": args.soil_nu,
        # the plate the tables were computed with (the device's unless flags override it)
        "plate_material": ctx.params.plate_material if ctx.params.plate_thickness > 0
        else "none", "plate_thickness": ctx.params.plate_thickness,
        "plate_diameter": ctx.params.plate_diameter,
        "plate_interface": ctx.params.plate_interface,
        "soil_model": model.params() if model is not None else {"model": "linear-elastic"},
        "soil_model_key": model.key if model is not None else "elastic",
        "plate_model": plate_model.params() if plate_model is not None else None,
        "plate_model_key": plate_model.key if plate_model is not None else None,
        "plastic_levels": settings.levels, "plastic_increments": settings.increments,
        "hits": rows, "static_set": float(res.static_set[0]),
        "static_dissipated": float(res.static_dissipated[0]),
        "tof_drift": np.diff(tof).tolist(), "tof_std": float(np.std(tof, ddof=1))
        if tof.size > 1 else 0.0,
        "exact_reach": float(res.wall.exact_reach[0]),
        "beyond_exact_reach": bool(res.wall.d_max0[0] > res.wall.exact_reach[0]),
        "striker_velocity": ctx.params.striker_velocity,
        **_hits_validity(ctx.params, res.wall).to_dict(0),
    }


def _hits_validity(params: Any, wall: Any) -> Any:
    """The checks of ``--hits`` (ssw.validity) at the sample's largest indentation over the
    hits: small strain at the contact and in the plate, the plastic wall's reach; the
    sample's and the plate's yield are the plastic model's own (skipped, said why)."""
    from ssw.validity import Validity, contact_radius_ratio, plate_deflection_ratio

    d = np.asarray(wall.d_max0[:1], float)
    vals = {"contact_strain": contact_radius_ratio(d, params.bead_radius),
            "wall_reach": d / np.asarray(wall.exact_reach[:1], float)}
    if params.plate_thickness > 0:
        vals["plate_deflection"] = plate_deflection_ratio(d, params.plate_thickness)
    why = "modelled: the plastic wall's set and dissipation per hit"
    return Validity(vals, notes=dict.fromkeys(vals, "at the largest indentation over the hits"),
                    skipped={"sample_yield": why, "plate_yield": why})


def _human_hits(res: dict[str, Any]) -> str:
    """Per hit: TOF, peak wall force, permanent set, its increment, dissipated energy."""
    t = float(res.get("plate_thickness") or 0.0)
    plate = (f"under a {t * 1e3:.3g} mm {res.get('plate_material', '')} plate" if t > 0
             else "no plate")
    if res.get("plate_model_key"):
        plate += f", {res['plate_model_key']}"
    lines = [f"{res['soil_model_key']} on E = {res['soil_E']:.4g} Pa, nu = {res['soil_nu']:.3g}"
             f" ({plate}); static set {res['static_set'] * 1e6:.3f} um",
             "hit   TOF (s)        peak F (N)  set (um)  d set (um)  interface (um)  plate "
             "thinning (um)  dissipated (J)"]
    lines += [f"{r['hit']:3d}  {r['tof']:.6e}  {r['peak_force']:10.4g}  "
              f"{r['permanent_set'] * 1e6:8.3f}  {r['set_increment'] * 1e6:10.3f}  "
              f"{r['interface_set'] * 1e6:14.3f}  {r['plate_thinning'] * 1e6:19.3f}  "
              f"{r['dissipated']:.4e}" for r in res["hits"]]
    lines.append(f"TOF std over the hits {res['tof_std']:.3e} s"
                 + ("; beyond the tabulated reach" if res["beyond_exact_reach"] else ""))
    if "validity" in res:
        from ssw.validity import human_lines

        lines += human_lines(res["validity"], res.get("checks_skipped"))
    return "\n".join(lines)


# ---------------------------------------------------------------------------- sweeps
def _sweep_points(args: argparse.Namespace, cfg: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    from ssw.config import expand_grid
    from ssw.tof.sweep import grid_points

    sw = cfg["chain"]["sweep"]
    if args.soil_E_min is not None:
        if args.soil_E_max is None or args.soil_E_step is None:
            raise ConfigError("--soil-E-max/--soil-E-step", None, "given with --soil-E-min")
        E = expand_grid({"start": args.soil_E_min, "stop": args.soil_E_max,
                         "step": args.soil_E_step}, "--soil-E-*")
    else:
        E = expand_grid(sw["soil_E"], "chain.sweep.soil_E")
    nu = (np.asarray(args.soil_nu, float) if args.soil_nu
          else expand_grid(sw["soil_nu"], "chain.sweep.soil_nu"))
    return grid_points(E, nu)


def run_tof_sweep(args: argparse.Namespace) -> dict[str, Any] | None:
    """``ssw tof-sweep``: the TOF over a grid of soil E (Pa) and nu, batched, one chunk of it
    written.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw tof-sweep --help``).

    Returns
    -------
    dict of str to Any or None
        The soils (E in Pa, nu), their TOFs (s), the points, the wall time (s), the MPI
        ranks and the validity checks; None on an MPI rank other than 0 (rank 0 writes
        and reports).
    """
    import time
    from dataclasses import replace

    from ssw.config import load_config
    from ssw.tof.sweep import chunk_slice, run_sweep, write_csv, write_sweep

    E, nu = _sweep_points(args, load_config(args.config))
    chunk, chunks = args.chunk, args.chunks or 1
    if args.part is not None:
        chunk, chunks = _part(args.part)
    idx = chunk_slice(E.size, chunk, chunks)
    E, nu = E[idx], nu[idx]
    ctx = chain_context(args, E, nu)
    params, wall, opts = ctx.params, ctx.wall, ctx.wall_options
    comm = None
    if args.mpi:
        from mpi4py import MPI

        comm = MPI.COMM_WORLD
    from ssw.progress import progress_bar

    t0 = time.perf_counter()
    with progress_bar(E.size, desc="TOF sweep", unit="pt",
                      enabled=False if comm is not None and comm.Get_rank() else None) as bar:
        sw = run_sweep(params, E, nu, wall, comm=comm, on_progress=bar,
                       strengths=context_strengths(ctx), stresses=args.stress_checks, **opts)
    if ctx.sample is not None and sw.validity is not None:  # its half-space reading
        fs = finite_sample_validity(ctx, sw.soil_E, sw.soil_nu, sw.tof)
        sw = replace(sw, validity=sw.validity.merged(fs))
    wall_time = time.perf_counter() - t0
    if comm is not None and comm.Get_rank() != 0:
        return None  # rank 0 writes and reports
    if args.output:
        inputs = {k: v for k, v in vars(args).items() if k not in ("func", "human")}
        from ssw.tof.sweep import model_digest

        write_sweep(args.output, sw, {**inputs, **_params_dict(params), **ctx.inputs(),
                                      "model_sha256": model_digest(params, wall, opts)})
        if args.csv:
            write_csv(args.csv, sw)
    if args.plot:
        from ssw.tof.sweep import plot_fig8

        plot_fig8(args.plot, sw.sorted(), f"TOF vs soil modulus, {wall} wall (cf. thesis Fig 8)")
    checks = sw.validity.columns()
    return {
        **ctx.inputs(), "soil_E": sw.soil_E, "soil_nu": sw.soil_nu, "tof": sw.tof,
        "points": int(sw.tof.size), "wall_time": wall_time,
        "ranks": 1 if comm is None else comm.Get_size(),
        "validity": {k: v.tolist() for k, v in checks.items()},
        "validity_meta": sw.validity.meta(),
        "points_failing_checks": int(sum(bool(x) for x in checks["checks_failed"])),
    }


def _part(text: str) -> tuple[int, int]:
    """``I-of-N`` (1-based, Snakemake's scatter item) -> (chunk index from 0, chunks)."""
    from ssw.errors import ConfigError

    try:
        i, n = (int(x) for x in text.split("-of-"))
    except ValueError:
        i, n = 0, 0
    if not 1 <= i <= n:
        raise ConfigError("--part", text, "I-of-N with 1 <= I <= N (e.g. 2-of-4)")
    return i - 1, n


def run_tof_merge(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw tof-merge``: the sweep's chunks merged into one file, its CSV and figure.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw tof-merge --help``).

    Returns
    -------
    dict of str to Any
        The output file and the number of points.
    """
    from ssw.provenance import require_match
    from ssw.tof.sweep import (
        merge_sweeps,
        plot_fig8,
        read_sweep,
        sweep_model,
        write_csv,
        write_sweep,
    )

    parts = [read_sweep(p) for p in args.inputs]
    models = [sweep_model(p[1], path) for p, path in zip(parts, args.inputs, strict=True)]
    for path, m in zip(args.inputs[1:], models[1:], strict=True):
        require_match("the chain model", (f"sweep part {args.inputs[0]}", models[0]),
                      (f"sweep part {path}", m))
    sw = merge_sweeps([p[0] for p in parts])
    write_sweep(args.output, sw, {"parts": [str(p) for p in args.inputs],
                                  "part_inputs": [p[1] for p in parts]})
    if args.csv:
        write_csv(args.csv, sw)
    if args.plot:
        walls = sorted({str(p[1].get("wall", "?")) for p in parts})
        plot_fig8(args.plot, sw, f"TOF vs soil modulus, {'/'.join(walls)} wall (cf. thesis Fig 8)")
    return {"output": args.output, "points": int(sw.tof.size),
            "tof_min": float(np.min(sw.tof)), "tof_max": float(np.max(sw.tof))}


# ---------------------------------------------------------------------------- ssw invert
def run_invert(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw invert``: the soil's E (Pa) from a TOF (s) and an assumed Poisson's ratio.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw invert --help``).

    Returns
    -------
    dict of str to Any
        ``E`` (Pa) with its interval (``E_low``, ``E_high``, Pa), the contributions to it (%)
        and the validity checks, with the inputs.

    Raises
    ------
    ssw.errors.ConfigError
        On ``--law table`` or several Poisson's ratios with ``--table``.
    """
    from ssw.measure import parse_nu

    E_range = (args.soil_E_min, args.soil_E_max)
    nu = parse_nu(args.soil_nu)
    nu_mid = 0.5 * (nu[0] + nu[1]) if isinstance(nu, tuple) else nu
    ctx = chain_context(args, np.geomspace(*E_range, 48), nu_mid)
    if ctx.wall == "table":
        raise ConfigError("--law", "table", "fem | hertz | fit | rigid for the inverse "
                          "(the table wall needs one FEM curve per E)")
    if args.table:
        from ssw.tof.inverse import invert
        from ssw.tof.sweep import read_sweep

        if isinstance(nu, tuple):
            raise ConfigError("--soil-nu", args.soil_nu, "one Poisson's ratio with --table")
        from ssw.tof.sweep import require_same_model

        table, table_inputs = read_sweep(args.table)
        require_same_model(table_inputs, args.table, ctx.params, ctx.wall, ctx.wall_options)
        res = invert(args.tof, nu, ctx.params, ctx.wall, tof_std=args.tof_std,
                     E_range=E_range, sweep=table, **ctx.wall_options)
        return {**ctx.inputs(), "E": float(res.E), "E_low": float(res.E_low),
                "E_high": float(res.E_high), "interval": "E(TOF -+ tof_std) on the sweep",
                "interval_clipped": bool(res.clipped), "tof_range": list(res.tof_range),
                "E_range": list(res.E_range),
                **_inverse_validity(args, ctx, float(res.E), nu).to_dict(0)}
    from ssw.modulus import estimate_moduli

    nu_arg = np.array(nu, float) if isinstance(nu, tuple) else nu
    est = estimate_moduli([args.tof], [args.tof_std], nu_arg, ctx.params, ctx.wall,
                          ctx.wall_options, calibration=ctx.calibration, E_range=E_range)[0]
    return {
        **ctx.inputs(), **est.to_dict(),
        "interval": "95 %: tof_std as the TOF's standard error, with the calibration, "
        "Poisson's ratio range, wall law and integrator contributions",
        "contributions_pct": {k: 100.0 * v for k, v in est.contributions.items()},
        "E_range": list(E_range),
        **_inverse_validity(args, ctx, float(est.E), est.nu).to_dict(0),
    }


def _inverse_validity(args: argparse.Namespace, ctx: Any, E: float, nu: float) -> Any:
    """The checks of an inverted E (the chain run at E, nu: ssw.tof.sweep.run_sweep), with
    the stated sample's half-space reading of ``--tof``."""
    from ssw.tof.sweep import run_sweep

    v = run_sweep(ctx.params, np.array([E]), np.array([nu]), ctx.wall,
                  strengths=context_strengths(ctx), stresses=args.stress_checks,
                  **ctx.wall_options).validity
    fs = finite_sample_validity(ctx, E, nu, args.tof)
    return v if fs is None else v.merged(fs)


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``ssw chain``, ``ssw tof``, ``ssw tof-sweep``, ``ssw tof-merge``, ``ssw invert``
    subcommands to the command line.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of the ``ssw`` parser.
    """
    p = sub.add_parser("chain", help="simulate the bead chain; write every contact force",
                       description="One chain run to --t-end; HDF5 datasets time (s) and "
                       "contact_force (N, n_time x n_contacts, last column the wall).")
    add_device_options(p)
    p.add_argument("--soil-E", type=float, default=100.0e6, help="soil modulus, Pa")
    p.add_argument("--soil-nu", type=float, default=0.3, help="soil Poisson's ratio")
    p.add_argument("--t-end", type=float, required=True, help="simulated time, s")
    p.add_argument("--record-every", type=int, default=1, help="keep every n-th step")
    p.add_argument("--output", required=True, help="output HDF5")
    add_json_flag(p)
    p.set_defaults(func=run_chain)

    p = sub.add_parser("tof", help="TOF at the sensor for one soil",
                       description="TOF (s) between the incident and reflected peaks.")
    add_device_options(p)
    p.add_argument("--soil-E", type=float, help="soil modulus, Pa")
    p.add_argument("--soil-nu", type=float, help="soil Poisson's ratio")
    h = p.add_argument_group("plastic sample (ssw.walls.plastic; through the device's plate, "
                             "none with --plate-thickness 0)")
    h.add_argument("--hits", type=int,
                   help="consecutive hits on one plastic sample: per hit the TOF, peak wall "
                   "force, permanent set and dissipated energy")
    add_soil_model_options(h)
    add_plate_model_options(h)
    h.add_argument("--plastic-levels", type=int, default=10,
                   help="unloading curves tabulated between first yield and the reach")
    h.add_argument("--plastic-increments", type=int, default=12,
                   help="FEM increments per loading-unloading path")
    p.add_argument("--derivatives", choices=DERIVATIVES, default="auto",
                   help="the TOF's derivatives with respect to E and the device's parameters "
                   "(dtof_dE, dtof_d<parameter>, s per SI unit, at the run's time step): "
                   "auto (exact forward sensitivities where the wall states its "
                   "derivatives, else central differences; the dynamic FEM wall only with "
                   "central), forward, central or none")
    add_stress_checks_option(p, "fem")
    add_json_flag(p)
    p.set_defaults(func=run_tof, human=_summary.tof)

    p = sub.add_parser("tof-sweep", help="TOF over a grid of soil E and nu (batched)",
                       description="TOF(E, nu); without --soil-E-min the config's "
                       "chain.sweep grid. --chunk/--chunks select an interleaved part.")
    add_device_options(p)
    p.add_argument("--soil-E-min", type=float, help="Pa")
    p.add_argument("--soil-E-max", type=float, help="Pa (included)")
    p.add_argument("--soil-E-step", type=float, help="Pa")
    p.add_argument("--soil-nu", type=float, nargs="+", help="Poisson's ratio(s)")
    p.add_argument("--chunk", type=int, default=0, help="0-based chunk index")
    p.add_argument("--chunks", type=int, default=1, help="number of chunks")
    p.add_argument("--part", metavar="I-of-N",
                   help="part I (from 1) of N: chunk I-1 of N (the workflow's scatter items)")
    p.add_argument("--mpi", action="store_true", help="split the points over MPI ranks")
    p.add_argument("--output", help="output HDF5 (kind tof_sweep)")
    p.add_argument("--csv", help="also write this CSV")
    p.add_argument("--plot", help="also draw the Fig 8 style PNG (a whole sweep: one chunk)")
    add_stress_checks_option(p, "bound")
    add_json_flag(p)
    p.set_defaults(func=run_tof_sweep)

    p = sub.add_parser("tof-merge", help="merge sweep chunks; CSV and Fig 8 plot")
    p.add_argument("inputs", nargs="+", help="chunk HDF5 files")
    p.add_argument("--output", required=True, help="merged HDF5")
    p.add_argument("--csv", help="merged CSV")
    p.add_argument("--plot", help="Fig 8 style PNG")
    add_json_flag(p)
    p.set_defaults(func=run_tof_merge)

    p = sub.add_parser("invert", help="soil E from a TOF and an assumed nu",
                       description="E (Pa) with its 95 % interval and the uncertainty "
                       "budget (ssw.modulus); with --table, E(TOF -+ std) on a stored sweep.")
    add_device_options(p)
    p.add_argument("--tof", type=float, required=True, help="measured TOF, s")
    p.add_argument("--tof-std", type=float, default=0.0,
                   help="its standard uncertainty (the standard error of a mean), s")
    p.add_argument("--soil-nu", required=True, metavar="NU|LO:HI",
                   help="assumed Poisson's ratio, or a range LO:HI")
    p.add_argument("--soil-E-min", type=float, default=10.0e6, help="range searched, Pa")
    p.add_argument("--soil-E-max", type=float, default=1000.0e6, help="range searched, Pa")
    p.add_argument("--table", help="use a stored sweep (tof_sweep HDF5) instead of the model")
    add_stress_checks_option(p, "fem")
    add_json_flag(p)
    p.set_defaults(func=run_invert, human=_summary.invert)
