"""A batch of contact scenes solved by one process (a workflow contact job).

What a scene costs (``ssw bench contact``; docs/cluster.md): its operators, once per mesh
(the plate's thickness), plate material and soil nu (~0.1-0.5 s each, cached on disk), then
milliseconds for the scene itself; a process pays ~0.3 s of start-up. So the workflow gives
one job to every **plate family** (:func:`ssw.workflow.families`: the scenes of one plate
material and thickness, whatever set lists them), whose scenes share their mesh and their
plate operators.

Inside a job, ``mpiexec -n N ssw contact --family F --output-dir D`` deals the batch's
operator groups out to the ranks (:func:`rank_share`): each rank builds only its groups'
operators and writes its scenes' curves. (The factorizations themselves are serial: PETSc's
redundant LU would factor the whole matrix on every rank, N times the work.)
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ssw.config import Scene


def group_key(scene: Scene) -> tuple[float, str, float]:
    """What a scene's operators depend on besides the mesh settings: (thickness, plate
    material, soil nu).

    Parameters
    ----------
    scene : Scene
        A study scene.

    Returns
    -------
    tuple
        ``(plate_thickness m, plate material, soil nu)``.
    """
    plate = scene.plate_material if scene.plate_thickness > 0 else "none"
    return (float(scene.plate_thickness), plate, float(scene.soil_nu))


def rank_share(scenes: list[Scene], rank: int, size: int) -> list[int]:
    """Indices of the scenes rank ``rank`` of ``size`` solves: whole operator groups, dealt
    largest first to the least loaded rank (a group's operators are built once).

    Parameters
    ----------
    scenes : list of Scene
        The batch.
    rank : int
        This rank.
    size : int
        Number of ranks.

    Returns
    -------
    list of int
        The scene indices, sorted.
    """
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

    Parameters
    ----------
    scenes : list of Scene
        The batch.
    reach : list of float
        Each scene's ``contact.delta_reach`` (m).
    contact : dict
        The contact settings.
    radius : float
        Indenter radius (m).
    materials : dict
        The materials library (SI).
    out_dir : path-like
        Directory of the curve files.
    material_set : str
        The material set's name (recorded in each curve).
    solve_scene : callable
        The engine's ``solve_scene``.
    rank : int
        This rank.
    size : int
        Number of ranks.
    progress : callable or None
        Called after each scene.

    Returns
    -------
    list of dict
        Per scene solved: id, output path, rank, largest force (N) and contact radius (m),
        dofs and wall time (s).
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
    """Every rank's ``items`` on rank 0 (None on the others); ``items`` with one rank.

    Parameters
    ----------
    items : list of dict
        This rank's items.
    size : int
        Number of ranks.

    Returns
    -------
    list of dict or None
        All items on rank 0, None on the others.
    """
    if size <= 1:
        return items
    from ssw.contact.petsc_solver import _petsc

    comm = _petsc().COMM_WORLD.tompi4py()
    parts = comm.gather(items, root=0)
    return None if parts is None else [x for p in parts for x in p]
