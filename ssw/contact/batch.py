"""Batches of contact scenes: which scenes one process (one Snakemake job) computes.

What a scene costs (``ssw bench contact``; docs/cluster.md): its operators, once per mesh
family (the plate's thickness: the mesh), plate material and soil nu (~0.1-0.5 s each,
cached on disk), then milliseconds for the scene itself; a process pays ~1 s of imports.
So the workflow gives one job to every **mesh family**, whose scenes share their mesh and
their plate operators, whatever set lists them: the thesis study has five (no plate, 0.1,
0.2, 0.4 and 1 mm PLA), the 0.4 mm one holding Sets 1 and 3 and a scene of Set 2. A family
of more than ``contact.jobs_per_group`` scenes is cut into equal chunks along its
operator groups (plate material, soil nu), so that a cluster still spreads a large study;
families of a few scenes (fewer than :data:`SMALL_FAMILY`) share a job (a job's ~1 s of
imports would cost more than their solves); a scene belongs to exactly one batch.

Inside a job, ``mpiexec -n N ssw contact --scene ... --output-dir D`` deals the batch's
operator groups out to the ranks (:func:`rank_share`): each rank builds only its groups'
operators and writes its scenes' curves. (The factorizations themselves are serial: PETSc's
redundant LU would factor the whole matrix on every rank, N times the work.)
"""

from __future__ import annotations

import re
from itertools import pairwise
from typing import Any

import numpy as np

from ssw.config import Scene, all_scenes
from ssw.errors import ConfigError

#: Scenes per job when the config does not say (``contact.jobs_per_group``).
DEFAULT_SIZE = 25
#: Families (or chunks) of fewer scenes than this are packed into shared jobs.
SMALL_FAMILY = 20


def chunks(items: list[str], size: int) -> list[list[str]]:
    """``items`` in order, cut into ``ceil(n / size)`` chunks of equal sizes (+-1)."""
    if int(size) != size or size < 1:
        raise ConfigError("contact.jobs_per_group", size, "an integer >= 1")
    n = len(items)
    k = -(-n // int(size))
    bounds = [(i * n) // k for i in range(k + 1)] if k else [0]
    return [items[a:b] for a, b in pairwise(bounds)]


def family_name(plate_thickness: float) -> str:
    """Batch-name stem of a mesh family: ``noplate`` or ``t<thickness in um>um``."""
    if plate_thickness <= 0:
        return "noplate"
    um = f"{plate_thickness * 1e6:.6g}".replace(".", "p")
    return f"t{um}um"


def group_key(scene: Scene) -> tuple[float, str, float]:
    """What a scene's operators depend on besides the mesh settings: (thickness, plate
    material, soil nu)."""
    plate = scene.plate_material if scene.plate_thickness > 0 else "none"
    return (float(scene.plate_thickness), plate, float(scene.soil_nu))


def batches(cfg: dict[str, Any], size: int | None = None) -> dict[str, list[str]]:
    """Batch name -> scene ids, for every scene of a (validated) config (module docstring).

    ``size`` defaults to ``cfg["contact"]["jobs_per_group"]``. Names are ``<family>`` or,
    when a family is cut, ``<family>_<k>`` (``k`` zero-padded, from 0); the workflow's rule
    of a batch is ``contact_batch_<name>``. Scenes are ordered by operator group, then by
    soil E.
    """
    if size is None:
        size = cfg.get("contact", {}).get("jobs_per_group", DEFAULT_SIZE)
    families: dict[float, list[Scene]] = {}
    for sc in all_scenes(cfg).values():
        families.setdefault(float(sc.plate_thickness), []).append(sc)
    out: dict[str, list[str]] = {}
    small: list[tuple[str, list[str]]] = []
    for t in sorted(families):
        scs = sorted(families[t], key=lambda s: (*group_key(s), s.soil_E, s.scene_id))
        ids = [s.scene_id for s in scs]
        parts = chunks(ids, size)
        stem = family_name(t)
        if len(parts) == 1:
            names = [stem]
        else:
            width = len(str(len(parts) - 1))
            names = [f"{stem}_{k:0{width}d}" for k in range(len(parts))]
        for name, part in zip(names, parts, strict=True):
            if not re.fullmatch(r"\w+", name):
                raise ConfigError("sets", name, "batch names of letters, digits and _")
            if len(part) < SMALL_FAMILY:
                small.append((name, part))
            else:
                out[name] = part
    # families of a few scenes (a thickness series: one scene each) share one job: a job's
    # start-up (~1 s of imports) would cost more than their solves; still at most `size`
    packed: list[list[tuple[str, list[str]]]] = []
    for name, part in small:
        if packed and sum(len(p) for _, p in packed[-1]) + len(part) <= size:
            packed[-1].append((name, part))
        else:
            packed.append([(name, part)])
    for group in packed:
        name = group[0][0] if len(group) == 1 else "_".join(n for n, _ in group)
        out[name] = [i for _, part in group for i in part]
    return out


def rank_share(scenes: list[Scene], rank: int, size: int) -> list[int]:
    """Indices of the scenes rank ``rank`` of ``size`` solves: whole operator groups, dealt
    largest first to the least loaded rank (a group's operators are built once)."""
    if size <= 1:
        return list(range(len(scenes)))
    groups: dict[tuple, list[int]] = {}
    for i, sc in enumerate(scenes):
        groups.setdefault(group_key(sc), []).append(i)
    load = np.zeros(size)
    mine: list[int] = []
    for key in sorted(groups, key=lambda k: (-len(groups[k]), k)):
        r = int(np.argmin(load))
        load[r] += len(groups[key]) + 10  # a group's operators cost ~10 scenes
        if r == rank:
            mine.extend(groups[key])
    return sorted(mine)


#: MB of memory a contact job asks for (a 300-scene family: 320 MB resident; the figure
#: leaves room for finer meshes). Doubled on a retry (Snakemake's ``attempt``).
MEM_MB = 1500


def runtime(n_scenes: int) -> int:
    """Minutes of wall time a batch of ``n_scenes`` asks for (its SLURM time limit): 5 plus
    1 s per scene, ~50x the ~20 ms a scene takes (operators, curve file) on one core;
    doubled on a retry."""
    return 5 + -(-int(n_scenes) // 60)


def solve_batch(
    scenes: list[Scene], reach: list[float], contact: dict[str, Any], radius: float,
    materials: dict, out_dir: Any, material_set: str, solve_scene: Any, *,
    rank: int = 0, size: int = 1, progress: Any = None,
) -> list[dict[str, Any]]:
    """Solve this rank's share of a batch (:func:`rank_share`) in turn and write each curve
    to ``out_dir/<scene_id>.h5`` (atomically) as soon as it is done.

    ``reach`` (m) is each scene's ``contact.delta_reach``; ``solve_scene`` the engine's
    (:func:`ssw.contact.solve_scene` or the layered oracle's); ``progress(i, n, scene,
    curve, path)`` is called after each scene (the CLI's log line). Returns one summary per
    scene solved here.
    """
    from dataclasses import replace
    from pathlib import Path

    from ssw.contact.scene import MeshCache
    from ssw.curve import write_curve

    cache = MeshCache()  # a family's scenes share their mesh and operators
    out_dir = Path(out_dir)
    mine = rank_share(scenes, rank, size)
    out = []
    for j, i in enumerate(mine):
        scene = scenes[i]
        curve = solve_scene(scene, {**contact, "delta_reach": reach[i]}, radius, materials,
                            cache)
        path = out_dir / f"{scene.scene_id}.h5"
        write_curve(path, replace(curve, inputs={**curve.inputs, "material_set": material_set}))
        st = curve.stats
        out.append({"scene_id": scene.scene_id, "output": str(path), "rank": rank,
                    "force_max": float(curve.force[-1]),
                    "contact_radius_max": float(curve.contact_radius[-1]),
                    "dofs": st.get("dofs"), "wall_total": st.get("wall_total"),
                    "operators_built": st.get("operators_built", 0)})
        if progress is not None:
            progress(j, len(mine), scene, curve, path)
    return out


def gather(items: list[dict[str, Any]], size: int) -> list[dict[str, Any]] | None:
    """Every rank's ``items`` on rank 0 (None on the others); ``items`` with one rank."""
    if size <= 1:
        return items
    from ssw.contact.petsc_solver import _petsc

    comm = _petsc().COMM_WORLD.tompi4py()
    parts = comm.gather(items, root=0)
    return None if parts is None else [x for p in parts for x in p]
