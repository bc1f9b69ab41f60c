"""What a Slurm cluster can run: a job that asks for more than any node has is an error.

Slurm queues a job whose request exceeds every node forever (``Reason=PartitionConfig`` or
``Resources``) and Snakemake waits for it without a word. The workflow checks every job it
is about to submit against the largest node (``sinfo``) when it starts (its ``onstart``
handler, ``workflow/rules/common.smk``) and stops with an error naming the rule, the
resource, what it asks and what the largest node has.
"""

from __future__ import annotations

import shutil
import subprocess
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from ssw.errors import ConfigError, SswError


@dataclass(frozen=True)
class NodeLimits:
    """The largest node of a cluster: CPUs and memory (MB), each the maximum over nodes."""

    cpus: int
    mem_mb: int


def parse_sinfo(text: str) -> NodeLimits:
    """:class:`NodeLimits` of ``sinfo -h -N -o "%c %m"`` output (one line per node: CPUs,
    memory in MB; ``sinfo`` may append ``+`` to a range's lower end)."""
    cpus, mem = 0, 0
    for line in text.splitlines():
        parts = line.split()
        if len(parts) < 2:
            continue
        try:
            c, m = int(parts[0].rstrip("+")), int(parts[1].rstrip("+"))
        except ValueError:
            continue
        cpus, mem = max(cpus, c), max(mem, m)
    if cpus <= 0 or mem <= 0:
        raise SswError(f"sinfo reported no node with CPUs and memory: {text.strip()!r}")
    return NodeLimits(cpus, mem)


def node_limits(partition: str | None = None) -> NodeLimits:
    """The largest node of the cluster (of ``partition`` when given), from ``sinfo``."""
    if shutil.which("sinfo") is None:
        raise SswError("sinfo is not on PATH: is this a Slurm cluster's login node?")
    cmd = ["sinfo", "-h", "-N", "-o", "%c %m"]
    if partition:
        cmd += ["-p", partition]
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=60, check=True)
    except (OSError, subprocess.SubprocessError) as exc:
        raise SswError(f"{' '.join(cmd)} failed: {exc}") from exc
    return parse_sinfo(out.stdout)


def job_cpus(threads: int, resources: Mapping[str, Any]) -> int:
    """CPUs a job's sbatch asks for: ``cpus_per_task`` (else ``threads``) times ``tasks``
    (the Slurm executor's rule: ``--cpus-per-task`` and ``--ntasks``)."""
    per_task = resources.get("cpus_per_task") or threads or 1
    return int(per_task) * int(resources.get("tasks") or 1)


def oversized(jobs: Iterable[tuple[str, int, Mapping[str, Any]]], limits: NodeLimits
              ) -> list[str]:
    """One message per job (``(rule, threads, resources)``) that asks for more CPUs or
    memory than the largest node has (single-node jobs: ``nodes`` unset or 1)."""
    out = []
    for rule, threads, res in jobs:
        if int(res.get("nodes") or 1) > 1:
            continue
        cpus = job_cpus(threads, res)
        if cpus > limits.cpus:
            out.append(f"rule {rule} asks for {cpus} CPUs (threads/cpus_per_task x tasks); "
                       f"the largest node has {limits.cpus}")
        mem = res.get("mem_mb")
        if mem is not None and int(mem) > limits.mem_mb:
            out.append(f"rule {rule} asks for mem_mb={int(mem)}; the largest node has "
                       f"{limits.mem_mb} MB")
    return out


def check_jobs_fit(jobs: Iterable[tuple[str, int, Mapping[str, Any]]],
                   limits: NodeLimits | None = None) -> None:
    """ConfigError listing every job that no node can run (:func:`oversized`)."""
    limits = limits or node_limits()
    bad = sorted(set(oversized(jobs, limits)))
    if bad:
        raise ConfigError("resources", "; ".join(bad),
                          "requests a node of the cluster can hold (lower them with "
                          "--set-resources RULE:mem_mb=... or the profile's set-resources; "
                          "no job was submitted)")
