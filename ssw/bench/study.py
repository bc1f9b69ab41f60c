"""``ssw bench study``: wall time of the whole study, per stage, from a warm environment.

Runs the study's Snakefile with Snakemake (its workstation profile, ``--cores 2`` by
default) into a fresh working directory (a temporary folder unless ``--workdir``), so the
user's ``results/`` is never touched and nothing is reused: every job runs. Before the timed
run, a dry run builds the DAG once (warm bytecode, imports and file-system caches: "warm
environment"); its time is reported separately.

Bytecode comes from the environment: ``scripts/setup.sh`` compiles it at install, so a
run here and `make study` import the same way even where ``PYTHONDONTWRITEBYTECODE``
is set.

Per-job times come from Snakemake's ``benchmark:`` records: every rule of the study writes
``results/benchmarks/<stage>/<job>.tsv`` (wall seconds, peak memory, CPU time); the stage is
the record's folder. For each stage the report gives the jobs, their summed wall time
(``busy_s``: core-seconds for single-core jobs), their peak memory and the costliest job.

Then an edit: with ``--increment SET:THICKNESS`` (default ``set2_thickness:0.6e-3`` when the
config has that set) the study is rerun with one plate thickness added to that set, and the
rerun's wall time and jobs are reported (only the new family's contact job and the set's
fits should run).

Writes ``study.json`` and ``study.md`` under ``--output-dir`` (default ``results/bench``),
also when the run fails (then with ``status: failed`` and the times of the finished jobs,
and the command exits with an error).
"""

from __future__ import annotations

import argparse
import os
import platform
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from ssw.errors import ConfigError, SswError
from ssw.h5io import atomic_write_text, write_json
from ssw.yamlio import safe_load

REPO = Path(__file__).resolve().parents[2]
#: Parts of the repository a study run reads through relative paths (materials library,
#: devices, default config): linked into the temporary working directory.
LINKED = ("config",)
#: The benchmark records of a run, relative to its working folder (workflow/rules/common.smk).
BENCHMARKS = Path("results") / "benchmarks"
#: The edit the increment measurement makes by default: one more plate thickness (m) in the
#: thesis's Set 2.
DEFAULT_INCREMENT = ("set2_thickness", 0.6e-3)
#: Jobs whose log is not named as their benchmark record (job -> log, both without suffix).
LOG_OF = {"chain/sweep_figure": "chain/tof_sweep"}
#: Folder of the ``ssw`` processes' CPU records, relative to the working folder.
USAGE = "usage"


def register(kinds: argparse._SubParsersAction) -> None:
    """Add the ``ssw bench study`` command and its options.

    Parameters
    ----------
    kinds : argparse._SubParsersAction
        The ``ssw bench`` subcommands.
    """
    p = kinds.add_parser(
        "study", help="wall time of the whole study per stage (snakemake, 2 cores)",
        description="Run the whole study with Snakemake into a fresh working directory and "
        "report the wall time per stage; writes study.json and study.md.")
    p.add_argument("--config", default="config/config.yaml", help="study config (YAML)")
    p.add_argument("--cores", type=int, default=2, help="cores given to Snakemake")
    p.add_argument("--snakefile", default=str(REPO / "workflow" / "Snakefile"),
                   help="the study Snakefile")
    p.add_argument("--profile",
                   help="Snakemake profile (default: none; the Snakefile's workflow profile, "
                   "workflow/profiles/default, applies by itself)")
    p.add_argument("--increment", metavar="SET:THICKNESS",
                   help="after the run, add this plate thickness (m) to this set and time "
                   "the rerun (default set2_thickness:0.6e-3 when the config has that set; "
                   "none: skip)")
    p.add_argument("--workdir", help="run here instead of a temporary folder (must be empty)")
    p.add_argument("--keep", action="store_true", help="keep the temporary working folder")
    p.add_argument("--timeout", type=float, default=3600.0, help="give up after this, s")
    p.add_argument("--keep-going", action="store_true",
                   help="let Snakemake finish the independent jobs after a failure")
    p.add_argument("--output-dir", default="results/bench", help="folder of the outputs")
    p.set_defaults(func=run, human=human)


def job_records(workdir: Path, since: float = 0.0) -> list[dict[str, Any]]:
    """One record per job of a run in ``workdir`` from its ``benchmark:`` files
    (``results/benchmarks/<stage>/<job>.tsv``): stage, job, wall s, peak memory MB, and
    the CPU time (s) of its ``ssw`` processes (:func:`usage_records`), else the record's
    own ``cpu_time`` (Snakemake samples a job's processes every 0.5 s and misses the end
    of a job it ran itself; for a command the warm process served, the record holds the
    fork's whole account, :mod:`ssw.warmstart.run`), else None; the peak memory is the
    ``ssw`` process's own when it left a record, else the record's; only files written
    after ``since`` (Unix s).

    Parameters
    ----------
    workdir : Path
        The run's working folder.
    since : float
        Unix time (s): older files are left out.

    Returns
    -------
    list of dict
        ``stage``, ``job``, ``s``, ``max_rss_mb``, ``cpu_s`` and ``startup_s`` per job.
    """
    usage = usage_records(workdir, since)
    out = []
    root = workdir / BENCHMARKS
    for tsv in sorted(root.rglob("*.tsv")) if root.is_dir() else []:
        if tsv.stat().st_mtime < since:
            continue
        lines = tsv.read_text().splitlines()
        if len(lines) < 2:
            continue
        row = dict(zip(lines[0].split("\t"), lines[-1].split("\t"), strict=False))
        try:
            seconds = float(row["s"])
        except (KeyError, ValueError):
            continue
        rel = tsv.relative_to(root)
        job = str(rel.with_suffix(""))
        use = usage.get(job) or usage.get(LOG_OF.get(job, ""))
        peak = (use["max_rss_mb"] if use and use.get("max_rss_mb")
                else _number(row.get("max_rss")))
        out.append({"stage": rel.parts[0] if len(rel.parts) > 1 else "other",
                    "job": job, "s": seconds, "max_rss_mb": peak,
                    "cpu_s": use["cpu_s"] if use else _number(row.get("cpu_time")),
                    "startup_s": use["startup_s"] if use else None})
    return out


def _number(text: str | None) -> float | None:
    """A benchmark record's figure, or None where Snakemake had none (``NA``, ``-``)."""
    try:
        return float(text) if text is not None else None
    except ValueError:
        return None


def stage_times(records: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Per-stage job count, summed wall and CPU times of its jobs, peak memory and
    costliest job.

    Parameters
    ----------
    records : list of dict
        The jobs' records (:func:`job_records`: ``stage``, ``job``, ``s``, ``cpu_s``,
        ``max_rss_mb``).

    Returns
    -------
    dict
        Stage -> ``jobs``, ``busy_s`` (s), ``cpu_s`` (s; None when a job's is unknown),
        ``max_rss_mb`` (MB), ``costliest`` and the per-job times; busiest stage first.
    """
    by_stage: dict[str, list[dict[str, Any]]] = defaultdict(list)
    for r in records:
        by_stage[r["stage"]].append(r)
    out = {}
    for stage, recs in by_stage.items():
        top = max(recs, key=lambda r: r["s"])
        rss = [r["max_rss_mb"] for r in recs if r["max_rss_mb"] is not None]
        cpu = [r.get("cpu_s") for r in recs]
        out[stage] = {"jobs": len(recs), "busy_s": sum(r["s"] for r in recs),
                      "cpu_s": None if None in cpu else sum(cpu),
                      "max_rss_mb": max(rss) if rss else None,
                      "costliest": {"job": top["job"], "s": top["s"],
                                    "cpu_s": top.get("cpu_s")},
                      "busy_s_per_job": {r["job"]: r["s"] for r in
                                         sorted(recs, key=lambda r: -r["s"])},
                      "cpu_s_per_job": {r["job"]: r.get("cpu_s") for r in
                                        sorted(recs, key=lambda r: -r["s"])}}
    return dict(sorted(out.items(), key=lambda kv: -kv[1]["busy_s"]))


def machine() -> dict[str, Any]:
    """The machine the benchmark ran on.

    Returns
    -------
    dict
        ``host``, ``cpu``, ``logical_cpus``, ``memory_bytes``, ``os`` and ``python``.
    """
    model = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") if hasattr(os, "sysconf") \
        else 0
    return {"host": platform.node(), "cpu": model or platform.processor(),
            "logical_cpus": os.cpu_count(), "memory_bytes": mem,
            "os": platform.platform(), "python": platform.python_version()}


def _snakemake_cmd(args: argparse.Namespace, workdir: Path, config: Path) -> list[str]:
    exe = Path(sys.executable).with_name("snakemake")
    cmd = [str(exe), "--snakefile", str(Path(args.snakefile).resolve()),
           "--directory", str(workdir), "--cores", str(args.cores), "--configfile", str(config)]
    if args.profile:
        cmd += ["--profile", str(Path(args.profile).resolve())]
    return cmd


def _increment(args: argparse.Namespace, config: Path) -> tuple[str, float] | None:
    """The (set, thickness) of the rerun measurement, or None."""
    spec = getattr(args, "increment", None)
    if spec is not None and spec.lower() == "none":
        return None
    if spec is None:
        sets = (safe_load(config.read_text()) or {}).get("sets", {})
        return DEFAULT_INCREMENT if DEFAULT_INCREMENT[0] in sets else None
    name, _, value = spec.partition(":")
    try:
        return name, float(value)
    except ValueError as exc:
        raise ConfigError("--increment", spec, "SET:THICKNESS (m), or none") from exc


def _incremented_config(config: Path, set_name: str, thickness: float, out: Path) -> Path:
    """A copy of ``config`` with ``thickness`` added to ``set_name``'s plate thicknesses."""
    import yaml

    cfg = safe_load(config.read_text())
    if set_name not in cfg.get("sets", {}):
        raise ConfigError("--increment", set_name, f"a set of {config}")
    axis = cfg["sets"][set_name]["plate_thickness"]
    if "values" not in axis:
        raise ConfigError("--increment", set_name, "a set whose plate_thickness is a list")
    axis["values"] = [*axis["values"], thickness]
    atomic_write_text(out, yaml.safe_dump(cfg, sort_keys=False))
    return out


def load_average() -> list[float] | None:
    """The machine's 1, 5 and 15 minute load averages (``/proc/loadavg``), or None.

    Returns
    -------
    list of float or None
        The load averages; None where ``/proc/loadavg`` cannot be read.
    """
    try:
        return [float(x) for x in Path("/proc/loadavg").read_text().split()[:3]]
    except (OSError, ValueError):
        return None


def _children_cpu() -> float:
    """CPU time (user + system, s) of this process's waited-for children so far."""
    import resource

    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


@dataclass(frozen=True)
class RunTime:
    """One Snakemake run: its wall time (s), the CPU time (s) of Snakemake and every job
    it ran, the load averages before and after, and, if it failed, the tail of its log.

    Parameters
    ----------
    wall_s : float
        The wall time, s.
    cpu_s : float
        The CPU time of Snakemake and its jobs, s.
    load_before : list of float or None
        The 1, 5 and 15 minute load averages before.
    load_after : list of float or None
        The load averages after.
    error : str or None
        The tail of the log when the run failed (None: it did not).
    """

    wall_s: float
    cpu_s: float
    load_before: list[float] | None
    load_after: list[float] | None
    error: str | None


def _run(cmd: list[str], cwd: Path, timeout: float) -> RunTime:
    """Run ``cmd`` (module docstring). The condensed FEM operators are cached in the
    working folder (``SSW_CACHE_DIR``), so "from clean" also means no operator reused from
    an earlier run; every ``ssw`` process records its CPU time in ``usage/`` there
    (:data:`ssw.cli.USAGE_ENV`)."""
    from ssw.cli import USAGE_ENV

    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env["SSW_CACHE_DIR"] = str(cwd / "cache")
    env[USAGE_ENV] = str(cwd / USAGE)
    load0, cpu0 = load_average(), _children_cpu()
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True,
                              timeout=timeout)
    except subprocess.TimeoutExpired as exc:
        raise SswError(f"study run exceeded --timeout {timeout} s: {shlex.join(cmd)}") from exc
    wall = time.perf_counter() - t0
    error = (f"snakemake failed (exit {proc.returncode}): {proc.stderr[-3000:]}"
             if proc.returncode != 0 else None)
    return RunTime(wall, _children_cpu() - cpu0, load0, load_average(), error)


def usage_records(workdir: Path, since: float = 0.0) -> dict[str, dict[str, float]]:
    """CPU time of each job of a run in ``workdir`` (the ``ssw`` processes' records,
    ``ssw.cli._record_usage``), keyed as :func:`job_records` keys the jobs (the job's
    log ``results/logs/<stage>/<job>.log``; a process without a log: its command): ``cpu_s``,
    ``wall_s`` and ``startup_s`` (s before the command's own code ran), summed over the
    job's processes, and ``max_rss_mb``, the largest peak memory of one of them (MB); only
    records written after ``since`` (Unix s).

    Parameters
    ----------
    workdir : pathlib.Path
        The run's working folder.
    since : float
        The earliest record time kept, Unix s.

    Returns
    -------
    dict
        Job key -> ``cpu_s``, ``wall_s``, ``startup_s`` (s) and ``max_rss_mb`` (MB).
    """
    import json

    out: dict[str, dict[str, float]] = {}
    folder = workdir / USAGE
    for f in sorted(folder.glob("*.json")) if folder.is_dir() else []:
        if f.stat().st_mtime < since:
            continue
        try:
            rec = json.loads(f.read_text())
        except (OSError, ValueError):
            continue
        log = Path(rec.get("log") or "")
        logs = workdir / BENCHMARKS.parent / "logs"
        try:
            key = str(log.resolve().relative_to(logs.resolve()).with_suffix(""))
        except ValueError:
            key = " ".join(a for a in rec.get("argv", []) if not a.startswith("-"))[:60]
        acc = out.setdefault(key, {"cpu_s": 0.0, "wall_s": 0.0, "startup_s": 0.0,
                                   "max_rss_mb": 0.0})
        for k in ("cpu_s", "wall_s", "startup_s"):
            acc[k] += float(rec.get(k) or 0.0)
        acc["max_rss_mb"] = max(acc["max_rss_mb"], float(rec.get("max_rss_mb") or 0.0))
    return out


def _prepare_workdir(args: argparse.Namespace) -> tuple[Path, bool]:
    if args.workdir:
        work = Path(args.workdir).resolve()
        if work.exists() and any(work.iterdir()):
            raise ConfigError("--workdir", str(work), "an empty or new folder")
        work.mkdir(parents=True, exist_ok=True)
        temporary = False
    else:
        work, temporary = Path(tempfile.mkdtemp(prefix="ssw-bench-study-")), True
    root = Path(args.snakefile).resolve().parent
    for name in LINKED:
        if (root / name).exists():
            (work / name).symlink_to(root / name)
    return work, temporary


def run(args: argparse.Namespace) -> dict[str, Any]:
    """Run ``ssw bench study`` (module docstring) and write its outputs under ``--output-dir``.

    Parameters
    ----------
    args : argparse.Namespace
        The command's options (:func:`register`).

    Returns
    -------
    dict
        The run's status, wall and CPU times (s), load, per-stage times
        (:func:`stage_times`), the rerun's (``increment``), the command and the machine.

    Raises
    ------
    ssw.errors.ConfigError
        When the config or the Snakefile is missing, ``--cores`` < 1, ``--increment`` is
        invalid or ``--workdir`` is not empty.
    ssw.errors.SswError
        When the dry run fails.
    """
    config = Path(args.config).resolve()
    if not config.is_file():
        raise ConfigError("--config", args.config, "an existing study config file")
    if args.cores < 1:
        raise ConfigError("--cores", args.cores, "an integer >= 1")
    snakefile = Path(args.snakefile).resolve()
    if not snakefile.is_file():
        raise ConfigError("--snakefile", args.snakefile, "an existing Snakefile")
    increment = _increment(args, config)
    work, temporary = _prepare_workdir(args)
    inc: dict[str, Any] | None = None
    try:
        cmd = _snakemake_cmd(args, work, config)
        dry = _run([*cmd, "--dry-run", "--quiet"], work, args.timeout)
        if dry.error:
            raise SswError(f"the study's dry run failed: {shlex.join(cmd)}\n{dry.error}")
        if args.keep_going:
            cmd.append("--keep-going")
        full = _run(cmd, work, args.timeout)
        error = full.error
        records = job_records(work)
        if increment is not None and error is None:
            edited = _incremented_config(config, *increment, work / "incremented.yaml")
            t0 = time.time()
            rerun = _run(_snakemake_cmd(args, work, edited), work, args.timeout)
            new = job_records(work, t0)
            inc = {"set": increment[0], "thickness": increment[1], "wall_s": rerun.wall_s,
                   "cpu_s": rerun.cpu_s, "load_before": rerun.load_before,
                   "load_after": rerun.load_after, "error": rerun.error,
                   "jobs": [r["job"] for r in new],
                   "cpu_s_per_job": {r["job"]: r["cpu_s"] for r in new}}
    finally:
        if temporary and not args.keep:
            shutil.rmtree(work, ignore_errors=True)
    stages = stage_times(records)
    result = {
        "status": "failed" if error else "complete", "error": error,
        "config": str(config), "cores": args.cores, "wall_s": full.wall_s,
        "cpu_s": full.cpu_s, "jobs_cpu_s": _sum_cpu(records),
        "load_before": full.load_before, "load_after": full.load_after,
        "dry_run_s": dry.wall_s,
        "jobs": len(records), "busy_s": sum(r["s"] for r in records), "stages": stages,
        "increment": inc,
        "command": shlex.join(cmd), "workdir": str(work) if (args.keep or not temporary)
        else None, "machine": machine(),
        "date_utc": datetime.now(UTC).isoformat(timespec="seconds"),
    }
    out = Path(args.output_dir)
    write_json(out / "study.json", result, result)
    atomic_write_text(out / "study.md", markdown(result))
    if error:
        raise SswError(f"{error}\n(per-stage times of the finished jobs: {out / 'study.md'})")
    if inc is not None and inc["error"]:
        raise SswError(f"the rerun with one more thickness failed: {inc['error']}")
    return result


def _sum_cpu(records: list[dict[str, Any]]) -> float | None:
    cpu = [r.get("cpu_s") for r in records]
    return None if None in cpu else float(sum(cpu))


def _f(x: float | None, fmt: str = ".1f") -> str:
    return "-" if x is None else format(x, fmt)


def _load(x: list[float] | None) -> str:
    return "-" if not x else " ".join(f"{v:.2f}" for v in x)


def markdown(result: dict[str, Any]) -> str:
    """The report as a Markdown table.

    Parameters
    ----------
    result : dict
        The result of :func:`run`.

    Returns
    -------
    str
        The Markdown text.
    """
    m = result["machine"]
    lines = [
        "# Whole-study benchmark (`ssw bench study`)", "",
        f"- config: `{result['config']}`; {result['cores']} cores; {result['jobs']} jobs",
        f"- machine: {m['cpu']}, {m['logical_cpus']} logical CPUs, "
        f"{m['memory_bytes'] / 2**30:.0f} GiB, {m['os']}, Python {m['python']}",
        f"- date: {result['date_utc']}",
        f"- command: `{result['command']}`", "",
        f"**Total wall time: {result['wall_s']:.1f} s** ({result['busy_s']:.1f} s of jobs; "
        f"CPU {_f(result.get('cpu_s'))} s with Snakemake's own, "
        f"{_f(result.get('jobs_cpu_s'))} s in the jobs; "
        f"DAG dry run before: {result['dry_run_s']:.1f} s)"
        + ("" if result["status"] == "complete" else
           " -- **the run FAILED**; the table shows the jobs that finished"),
        f"- load average (1, 5, 15 min) before: {_load(result.get('load_before'))}, "
        f"after: {_load(result.get('load_after'))}", "",
        "| stage | jobs | busy (s) | CPU (s) | peak memory (MB) | costliest job |",
        "|---|---:|---:|---:|---:|---|",
    ]
    for name, s in result["stages"].items():
        rss = "-" if s["max_rss_mb"] is None else f"{s['max_rss_mb']:.0f}"
        top = s["costliest"]
        lines.append(f"| {name} | {s['jobs']} | {s['busy_s']:.1f} | {_f(s.get('cpu_s'))} | "
                     f"{rss} | {top['job']} ({top['s']:.1f} s, "
                     f"CPU {_f(top.get('cpu_s'))} s) |")
    lines += ["", "busy: the summed wall time of the stage's jobs (Snakemake's benchmark "
              "records, results/benchmarks/<stage>/); CPU: user + system time of the "
              "jobs' ssw processes (their own records).", ""]
    inc = result.get("increment")
    if inc:
        lines += [f"**Rerun after adding a {inc['thickness'] * 1e3:g} mm plate to "
                  f"{inc['set']}: {inc['wall_s']:.1f} s** (CPU {_f(inc.get('cpu_s'))} s; "
                  f"load before {_load(inc.get('load_before'))}), jobs: "
                  + ", ".join(f"`{j}` ({_f((inc.get('cpu_s_per_job') or {}).get(j))} s CPU)"
                              for j in inc["jobs"]), ""]
    return "\n".join(lines)


def human(result: dict[str, Any]) -> str:
    """Short summary for the terminal.

    Parameters
    ----------
    result : dict
        The result of :func:`run`.

    Returns
    -------
    str
        One line for the run, one per stage, and the rerun's.
    """
    rows = [f"study: {result['wall_s']:.1f} s wall on {result['cores']} cores, "
            f"{result['jobs']} jobs, {result['busy_s']:.1f} s of jobs, CPU "
            f"{_f(result.get('cpu_s'))} s ({_f(result.get('jobs_cpu_s'))} s in jobs), load "
            f"{_load(result.get('load_before'))} -> {_load(result.get('load_after'))}"]
    rows += [f"  {k:<12} {s['busy_s']:8.1f} s busy {_f(s.get('cpu_s')):>8} s CPU  "
             f"{s['jobs']} jobs" for k, s in result["stages"].items()]
    inc = result.get("increment")
    if inc:
        rows.append(f"rerun with {inc['thickness'] * 1e3:g} mm added to {inc['set']}: "
                    f"{inc['wall_s']:.1f} s wall, {_f(inc.get('cpu_s'))} s CPU, jobs "
                    f"{', '.join(inc['jobs'])}")
    return "\n".join(rows)
