"""What a job asks of a cluster: memory and wall time scaled with its size
(:data:`RESOURCES`), and the MPI launcher of a job with several tasks.
"""

from __future__ import annotations

from typing import Any

#: Memory (MB) and wall time (min) a job asks of a cluster: (base, per unit of size), the
#: size being a contact family's scene count (0 for the other steps). Measured on the
#: thesis study (``results/benchmarks``: max_rss and s): a 300-scene family 320 MB and 7 s,
#: the calibration 250 MB and 8 s, the sweep 200 MB and 3 s, a fit 350 MB and 7 s; the
#: figures leave room (x4 memory, x40 time for slower nodes and finer meshes), and a retry
#: doubles them (Snakemake's ``attempt``).
RESOURCES: dict[str, tuple[float, float, float, float]] = {
    #                mem base, mem per unit, min base, min per unit
    "contact": (1000.0, 2.0, 5.0, 1.0 / 60.0),
    "fit": (1500.0, 0.0, 10.0, 0.0),
    "calibration": (1500.0, 0.0, 15.0, 0.0),
    "sweep": (1500.0, 0.0, 15.0, 0.0),
    "validation": (1500.0, 0.0, 15.0, 0.0),
    "survey_point": (1000.0, 0.0, 10.0, 0.0),
    "design": (2000.0, 0.0, 20.0, 0.0),
    "design_device": (3000.0, 0.0, 60.0, 0.0),
}


def mem_mb(step: str, size: int) -> int:
    """MB of memory a job of ``step`` of ``size`` asks for (:data:`RESOURCES`).

    Parameters
    ----------
    step : str
        The job's step (a key of :data:`RESOURCES`).
    size : int
        The job's size (a family's scene count; 0 for other steps).

    Returns
    -------
    int
        Memory, MB.
    """
    base, per, _, _ = RESOURCES[step]
    return round(base + per * size)


def runtime_min(step: str, size: int) -> int:
    """Minutes of wall time a job of ``step`` of ``size`` asks for (:data:`RESOURCES`).

    Parameters
    ----------
    step : str
        The job's step (a key of :data:`RESOURCES`).
    size : int
        The job's size (a family's scene count; 0 for other steps).

    Returns
    -------
    int
        Wall time, min (rounded up).
    """
    _, _, base, per = RESOURCES[step]
    return int(-(-(base + per * size) // 1))


def mpi_launch(resources: Any) -> list[str]:
    """The MPI launcher of a job with resources ``tasks`` > 1, else nothing.

    Parameters
    ----------
    resources : snakemake.io.Resources
        The job's resources: ``tasks`` (ranks) and ``mpi`` (the launcher's command line,
        default ``mpiexec``; e.g. ``srun`` or ``srun --mpi=pmi2`` on a cluster).

    Returns
    -------
    list of str
        ``[*launcher words, "-n", tasks]``, one argument each (a rule quotes each); empty
        for one task.
    """
    import shlex

    tasks = int(getattr(resources, "tasks", 1) or 1)
    if tasks <= 1:
        return []
    launcher = getattr(resources, "mpi", None) or "mpiexec"
    return [*shlex.split(str(launcher)), "-n", str(tasks)]


def mpi_flag(resources: Any) -> list[str]:
    """``--mpi`` for a job with resources ``tasks`` > 1 (its command splits its work over
    the ranks), else nothing.

    Parameters
    ----------
    resources : snakemake.io.Resources
        The job's resources.

    Returns
    -------
    list of str
        ``["--mpi"]`` or ``[]``.
    """
    return ["--mpi"] if int(getattr(resources, "tasks", 1) or 1) > 1 else []

