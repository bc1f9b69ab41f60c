"""The study as the workflow runs it: its jobs, and the inputs each job reads.

Pure functions of a validated config (and one cached view of it, :class:`Study`), used by
the rules of ``workflow/rules/*.smk`` so that the rule files hold only rules and these
helpers are tested like any code.

Exact reruns. Every job declares the slice of the study it reads (:meth:`Study.inputs`):
its part of the config with every reference resolved to values (the device's physics, not
its file name; each material's E, nu, density and strength, not the library's path), and
the hash of the ssw source its command runs (:func:`ssw.provenance.source_hash` of the
command's import closure). The rules pass that slice to Snakemake as a param; Snakemake
stores params with each output and reruns a job whose params changed (its rerun trigger
``params``), so an edit reruns exactly the jobs whose slice it changes, a dry run shows
them, and nothing else reruns. Files a job reads (curves, the calibration, recordings, the
sweep) are its inputs, compared by time as usual.

A job's command reads the whole resolved study config (``results/study_config.yaml``,
written when a run starts, never at parse time: a dry run and a lint write nothing) and
uses only its slice. The slice's digest is passed to the command
(``ssw --inputs-sha256 ...``) and recorded in every result it writes.

Steps and their keys:

* ``contact`` (one job per plate family, :func:`ssw.workflow.families`: the scenes of one plate
  material and thickness, or of no plate, whatever set lists them: they share a mesh and
  their operators);
* ``fit`` (one job per set); ``calibration``; ``sweep`` (the TOF sweep, in parts:
  ``scattergather``) and ``sweep_figure``; ``validation``; ``survey_point`` (one job per
  point) and ``survey_table``; ``report``.

Modules:

* :mod:`ssw.workflow.jobs`: the results' layout, the sets and plate families, each job's
  input files and the ``ssw`` flags that name them, the survey's points;
* :mod:`ssw.workflow.inputs`: each job's slice of the study (:class:`Study`, exact reruns);
* :mod:`ssw.workflow.resources`: what a job asks of a cluster (memory, time, MPI ranks);
* :mod:`ssw.workflow.run`: the Snakemake run around the jobs (its end, spawned jobs'
  interpreter, a run on Slurm);
* :mod:`ssw.workflow.report`: the report's stages, categories and table pages.

Every public name of these modules is importable from ``ssw.workflow`` (the rules'
``import ssw.workflow as sswwf``).
"""

from __future__ import annotations

from ssw.workflow.inputs import (
    CHAIN_KEYS,
    CONTACT_KEYS,
    FEM_WALL_KEYS,
    STEP_MODULES,
    Study,
)
from ssw.workflow.jobs import (
    CALIBRATION,
    RESULTS,
    STUDY_CONFIG,
    alternatives,
    calibrated_inputs,
    calibration_flag,
    contact_file,
    device_parts,
    families,
    family_of,
    grid_sets,
    k_table_file,
    one_soil_sets,
    point_recordings,
    recordings,
    scatter_part,
    scene_file,
    set_families,
    survey_has_coordinates,
    survey_nu,
    survey_points,
    sweep_scene_ids,
    uses_calibration,
    wall_flags,
    wall_inputs,
    wall_law,
    write_study_config,
)
from ssw.workflow.report import (
    REPORT_STAGES,
    report_categories,
    report_page_args,
    report_stages,
    report_tables,
)
from ssw.workflow.resources import (
    RESOURCES,
    mem_mb,
    mpi_flag,
    mpi_launch,
    runtime_min,
)
from ssw.workflow.run import (
    cancel_in_flight,
    cap_status_pause,
    check_cluster_fit,
    end_of_run,
    prepare_slurm_run,
    quote_job_python,
    submits_to_slurm,
)

__all__ = [
    "CALIBRATION",
    "CHAIN_KEYS",
    "CONTACT_KEYS",
    "FEM_WALL_KEYS",
    "REPORT_STAGES",
    "RESOURCES",
    "RESULTS",
    "STEP_MODULES",
    "STUDY_CONFIG",
    "Study",
    "alternatives",
    "calibrated_inputs",
    "calibration_flag",
    "cancel_in_flight",
    "cap_status_pause",
    "check_cluster_fit",
    "contact_file",
    "device_parts",
    "end_of_run",
    "families",
    "family_of",
    "grid_sets",
    "k_table_file",
    "mem_mb",
    "mpi_flag",
    "mpi_launch",
    "one_soil_sets",
    "point_recordings",
    "prepare_slurm_run",
    "quote_job_python",
    "recordings",
    "report_categories",
    "report_page_args",
    "report_stages",
    "report_tables",
    "runtime_min",
    "scatter_part",
    "scene_file",
    "set_families",
    "submits_to_slurm",
    "survey_has_coordinates",
    "survey_nu",
    "survey_points",
    "sweep_scene_ids",
    "uses_calibration",
    "wall_flags",
    "wall_inputs",
    "wall_law",
    "write_study_config",
]
