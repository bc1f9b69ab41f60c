"""Batches of contact scenes: one process (one Snakemake job) computes several scenes.

Starting ``ssw contact`` costs ~0.6 s (Python, petsc4py and gmsh imports) against a ~1.2 s
solve, so the workflow gives every job a batch of up to ``contact.jobs_per_group`` scenes
(``ssw contact --scene A --scene B ... --output-dir DIR``). Batches are cut per set, in the
set's scene order, into as few chunks as that size allows, of equal sizes (+-1): adding a
scene to one set changes no other set's batches. A scene shared by several sets belongs to
the first set that lists it (every curve file has exactly one producing job).
"""

from __future__ import annotations

import re
from itertools import pairwise
from typing import Any

from ssw.config import scenes
from ssw.errors import ConfigError


def chunks(items: list[str], size: int) -> list[list[str]]:
    """``items`` in order, cut into ``ceil(n / size)`` chunks of equal sizes (+-1)."""
    if int(size) != size or size < 1:
        raise ConfigError("contact.jobs_per_group", size, "an integer >= 1")
    n = len(items)
    k = -(-n // int(size))
    bounds = [(i * n) // k for i in range(k + 1)] if k else [0]
    return [items[a:b] for a, b in pairwise(bounds)]


def batches(cfg: dict[str, Any], size: int | None = None) -> dict[str, list[str]]:
    """Batch name -> scene ids, for every scene of every set of a (validated) config.

    ``size`` defaults to ``cfg["contact"]["jobs_per_group"]`` (schema default 25). Names
    are ``<set>_<k>`` (``k`` zero-padded, from 0); the workflow's rule of a batch is
    ``contact_batch_<name>``.
    """
    if size is None:
        size = cfg.get("contact", {}).get("jobs_per_group", 25)
    seen: set[str] = set()
    out: dict[str, list[str]] = {}
    for set_name in cfg["sets"]:
        ids = [s.scene_id for s in scenes(cfg, set_name) if s.scene_id not in seen]
        seen.update(ids)
        parts = chunks(ids, size)
        width = len(str(max(len(parts) - 1, 0)))
        for k, part in enumerate(parts):
            name = f"{set_name}_{k:0{width}d}"
            if not re.fullmatch(r"\w+", name):  # the schema's set names; rule names need it
                raise ConfigError("sets", set_name, "a name of letters, digits and _")
            out[name] = part
    return out


#: MB of memory a contact job asks for (a batch of 25 thesis scenes: 350 MB resident; the
#: figure leaves room for finer meshes). Doubled on a retry (Snakemake's ``attempt``).
MEM_MB = 1500


def runtime(n_scenes: int) -> int:
    """Minutes of wall time a batch of ``n_scenes`` asks for (its SLURM time limit): 5
    plus 12 s per scene, ~8x the ~1.5 s a thesis scene takes on one core; doubled on a
    retry."""
    return 5 + -(-12 * int(n_scenes) // 60)
