"""``ssw bench study``: wall time of the whole study, per stage, from a warm environment.

Runs the study's Snakefile with Snakemake (workstation profile, ``--cores 2`` by default)
into a fresh working directory (a temporary folder unless ``--workdir``), so the user's
``results/`` is never touched and nothing is reused: every job runs. Before the timed run, a
dry run builds the DAG once (warm bytecode, imports and file-system caches: "warm
environment"); its time is reported separately.

Per-stage times come from Snakemake's own job records: for every output file Snakemake
stores the rule and the start and end time of the job that made it
(``.snakemake/metadata``). A stage is the rule file that defines a rule
(``workflow/rules/<stage>.smk``). For each stage the report gives

* ``wall_s``: from its first job's start to its last job's end (stages may overlap);
* ``busy_s``: the sum of its jobs' durations (core-seconds for single-core jobs);
* ``jobs``: the number of jobs.

Writes ``study.json`` and ``study.md`` under ``--output-dir`` (default ``results/bench``),
also when the run fails (then with ``status: failed`` and the times of the finished jobs,
and the command exits with an error).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from base64 import urlsafe_b64decode
from collections import defaultdict
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from ssw.errors import ConfigError, SswError
from ssw.h5io import atomic_write_text, to_json

REPO = Path(__file__).resolve().parents[2]
RULE_RE = re.compile(r"^[ \t]*(?:rule|checkpoint)\s+(\w+)\s*:", re.MULTILINE)
# Rules named by the `name:` directive (e.g. defined in a loop: `name: f"contact_batch_{b}"`):
# the name's literal start, a prefix of every rule it defines.
NAME_RE = re.compile(r"^\s+name:\s*(?:\n\s*)?f?[\"']([A-Za-z_]\w*)", re.MULTILINE)
# Parts of the repository a study run reads through relative paths (materials library,
# default config): linked into the temporary working directory.
LINKED = ("config",)


def register(kinds: argparse._SubParsersAction) -> None:
    from ssw.cli import add_json_flag

    p = kinds.add_parser(
        "study", help="wall time of the whole study per stage (snakemake, 2 cores)",
        description="Run the whole study with Snakemake into a fresh working directory and "
        "report the wall time per stage; writes study.json and study.md.")
    p.add_argument("--config", default="config/config.yaml", help="study config (YAML)")
    p.add_argument("--cores", type=int, default=2, help="cores given to Snakemake")
    p.add_argument("--snakefile", default=str(REPO / "Snakefile"), help="the study Snakefile")
    p.add_argument("--profile", default=str(REPO / "workflow" / "profiles" / "default"),
                   help="Snakemake profile (default: the workstation profile)")
    p.add_argument("--workdir", help="run here instead of a temporary folder (must be empty)")
    p.add_argument("--keep", action="store_true", help="keep the temporary working folder")
    p.add_argument("--timeout", type=float, default=3600.0, help="give up after this, s")
    p.add_argument("--keep-going", action="store_true",
                   help="let Snakemake finish the independent jobs after a failure")
    p.add_argument("--output-dir", default="results/bench", help="folder of the outputs")
    add_json_flag(p)
    p.set_defaults(func=run, human=human)


def rule_stages(snakefile: Path) -> dict[str, str]:
    """Rule name -> stage (the stem of the ``.smk`` file defining it, else ``Snakefile``).

    Rules named with the ``name:`` directive appear as ``<literal start of the name>*``
    (a prefix: a loop defines many such rules); :func:`stage_of` resolves them.
    """
    def found(text: str) -> list[str]:
        return RULE_RE.findall(text) + [f"{p}*" for p in NAME_RE.findall(text)]

    stages = {name: "Snakefile" for name in found(snakefile.read_text())}
    for smk in sorted((snakefile.parent / "workflow" / "rules").glob("*.smk")):
        stages.update({name: smk.stem for name in found(smk.read_text())})
    return stages


def stage_of(rule: str, stages: dict[str, str]) -> str:
    """The stage of ``rule``: its exact entry, else the longest matching ``prefix*``."""
    if rule in stages:
        return stages[rule]
    prefixes = [k for k in stages if k.endswith("*") and rule.startswith(k[:-1])]
    return stages[max(prefixes, key=len)] if prefixes else "other"


def job_records(workdir: Path) -> list[dict[str, Any]]:
    """One record (rule, start, end; Unix s) per finished job of a run in ``workdir``.

    Snakemake keeps one metadata file per output and log file, named by the file's path in
    URL-safe base64 (split into ``@``-prefixed folders when long), each with the job's hash.
    A job counts once, and only if one of its outputs (not logs) still exists: Snakemake
    deletes a failed job's outputs.
    """
    root = workdir / ".snakemake" / "metadata"
    seen: dict[tuple[str, Any], dict[str, Any]] = {}
    for meta in root.rglob("*"):
        if not meta.is_file():
            continue
        try:
            rec = json.loads(meta.read_text())
            b64 = "".join(part.lstrip("@") for part in meta.relative_to(root).parts)
            output = workdir / urlsafe_b64decode(b64.encode()).decode()
        except (OSError, ValueError):
            continue
        if rec.get("incomplete") or rec.get("starttime") is None or rec.get("endtime") is None:
            continue
        # Logs outlive failed jobs: only outputs prove that a job finished.
        if not output.exists() or str(output.relative_to(workdir)) in rec.get("log", []):
            continue
        key = (rec["rule"], rec.get("job_hash", rec["starttime"]))
        seen[key] = {"rule": rec["rule"], "start": float(rec["starttime"]),
                     "end": float(rec["endtime"])}
    return sorted(seen.values(), key=lambda r: r["start"])


def stage_times(records: list[dict[str, Any]], stages: dict[str, str],
                t0: float) -> dict[str, dict[str, Any]]:
    """Per-stage wall time, busy time and job count; times relative to ``t0`` (Unix s)."""
    by_stage: dict[str, list[dict[str, Any]]] = defaultdict(list)
    for r in records:
        by_stage[stage_of(r["rule"], stages)].append(r)
    out = {}
    for stage, recs in by_stage.items():
        start, end = min(r["start"] for r in recs), max(r["end"] for r in recs)
        rules: dict[str, float] = defaultdict(float)
        for r in recs:
            rules[r["rule"]] += r["end"] - r["start"]
        out[stage] = {
            "wall_s": end - start, "busy_s": sum(r["end"] - r["start"] for r in recs),
            "jobs": len(recs), "start_s": start - t0, "end_s": end - t0,
            "busy_s_per_rule": dict(sorted(rules.items(), key=lambda kv: -kv[1])),
        }
    return dict(sorted(out.items(), key=lambda kv: kv[1]["start_s"]))


def machine() -> dict[str, Any]:
    """The machine the benchmark ran on."""
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
    return [str(exe), "--snakefile", str(Path(args.snakefile).resolve()),
            "--directory", str(workdir), "--profile", str(Path(args.profile).resolve()),
            "--cores", str(args.cores), "--configfile", str(config)]


def _run(cmd: list[str], cwd: Path, timeout: float) -> tuple[float, str | None]:
    """Run ``cmd``; its wall time (s) and, if it failed, the tail of its log. The condensed
    FEM operators are cached in the working folder (``SSW_CACHE_DIR``), so "from clean"
    also means no operator reused from an earlier run."""
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env["SSW_CACHE_DIR"] = str(cwd / "cache")
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True,
                              timeout=timeout)
    except subprocess.TimeoutExpired as exc:
        raise SswError(f"study run exceeded --timeout {timeout} s: {shlex.join(cmd)}") from exc
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        return wall, f"snakemake failed (exit {proc.returncode}): {proc.stderr[-3000:]}"
    return wall, None


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
    config = Path(args.config).resolve()
    if not config.is_file():
        raise ConfigError("--config", args.config, "an existing study config file")
    if args.cores < 1:
        raise ConfigError("--cores", args.cores, "an integer >= 1")
    snakefile = Path(args.snakefile).resolve()
    if not snakefile.is_file():
        raise ConfigError("--snakefile", args.snakefile, "an existing Snakefile")
    work, temporary = _prepare_workdir(args)
    try:
        cmd = _snakemake_cmd(args, work, config)
        dag_s, error = _run([*cmd, "--dry-run", "--quiet"], work, args.timeout)
        if error:
            raise SswError(f"the study's dry run failed: {shlex.join(cmd)}\n{error}")
        if args.keep_going:
            cmd.append("--keep-going")
        t0 = time.time()
        wall_s, error = _run(cmd, work, args.timeout)
        stages = stage_times(job_records(work), rule_stages(snakefile), t0)
    finally:
        if temporary and not args.keep:
            shutil.rmtree(work, ignore_errors=True)
    result = {
        "status": "failed" if error else "complete", "error": error,
        "config": str(config), "cores": args.cores, "wall_s": wall_s, "dry_run_s": dag_s,
        "jobs": sum(s["jobs"] for s in stages.values()), "stages": stages,
        "command": shlex.join(cmd), "workdir": str(work) if (args.keep or not temporary)
        else None, "machine": machine(),
        "date_utc": datetime.now(UTC).isoformat(timespec="seconds"),
    }
    out = Path(args.output_dir)
    atomic_write_text(out / "study.json", to_json(result, indent=2))
    atomic_write_text(out / "study.md", markdown(result))
    if error:
        raise SswError(f"{error}\n(per-stage times of the finished jobs: {out / 'study.md'})")
    return result


def markdown(result: dict[str, Any]) -> str:
    """The report as a Markdown table."""
    m = result["machine"]
    lines = [
        "# Whole-study benchmark (`ssw bench study`)", "",
        f"- config: `{result['config']}`; {result['cores']} cores; {result['jobs']} jobs",
        f"- machine: {m['cpu']}, {m['logical_cpus']} logical CPUs, "
        f"{m['memory_bytes'] / 2**30:.0f} GiB, {m['os']}, Python {m['python']}",
        f"- date: {result['date_utc']}",
        f"- command: `{result['command']}`", "",
        f"**Total wall time: {result['wall_s']:.1f} s** (DAG dry run before: "
        f"{result['dry_run_s']:.1f} s)"
        + ("" if result["status"] == "complete" else
           " -- **the run FAILED**; the table shows the jobs that finished"), "",
        "| stage | jobs | wall (s) | busy (s) | from (s) | to (s) | costliest rule |",
        "|---|---:|---:|---:|---:|---:|---|",
    ]
    for name, s in result["stages"].items():
        top = next(iter(s["busy_s_per_rule"].items()))
        lines.append(f"| {name} | {s['jobs']} | {s['wall_s']:.1f} | {s['busy_s']:.1f} | "
                     f"{s['start_s']:.1f} | {s['end_s']:.1f} | {top[0]} ({top[1]:.1f} s) |")
    lines += ["", "wall: first job start to last job end of the stage; busy: sum of its "
              "job durations; from/to: seconds after the timed run started.", ""]
    return "\n".join(lines)


def human(result: dict[str, Any]) -> str:
    """Short summary for the terminal."""
    rows = [f"study: {result['wall_s']:.1f} s wall on {result['cores']} cores, "
            f"{result['jobs']} jobs"]
    rows += [f"  {k:<12} {s['wall_s']:8.1f} s wall  {s['busy_s']:8.1f} s busy  {s['jobs']} jobs"
             for k, s in result["stages"].items()]
    return "\n".join(rows)
