# Stage I contact FEM: one force-indentation curve per scene of every set of the config.
# Science lives in ssw.contact; these rules call the `ssw contact` and `ssw contact-plot`
# commands.
#
# Outputs (results/contact/):
#   {scene}.h5                     the curve of a scene (ssw.curve.read_curve)
#   figures/fig5_materials.png     force vs indentation per plate material (set1_materials)
#   figures/fig6_thickness.png     force vs indentation per PLA thickness (set2_thickness)
#
# Grouping: every contact_scene job belongs to the group "contact"; on a cluster,
# `--group-components contact=N` (the SLURM profile sets it; use contact.jobs_per_group)
# submits N scenes as one job. Snakemake runs groups' jobs one by one when local.

CONTACT_FIGURES = {
    "set1_materials": ("fig5_materials", "material", "Plate materials (thesis Fig 5)"),
    "set2_thickness": ("fig6_thickness", "thickness", "PLA plate thickness (thesis Fig 6)"),
}

# figure name -> (curve files, --label-by, title), for the sets the config has
CONTACT_FIGURE_JOBS = {
    name: (
        expand(f"{RESULTS}/contact/{{scene}}.h5", scene=scene_ids(set_name)),
        label_by,
        title,
    )
    for set_name, (name, label_by, title) in CONTACT_FIGURES.items()
    if set_name in config["sets"]
}

CONTACT_TARGETS = expand(f"{RESULTS}/contact/{{scene}}.h5", scene=list(SCENES)) + [
    f"{RESULTS}/contact/figures/{name}.png" for name in CONTACT_FIGURE_JOBS
]


wildcard_constraints:
    scene="[A-Za-z0-9_.\-]+",


rule contact_scene:
    """Force-indentation curve of one scene (gmsh + PETSc FEM, 1 LU, LCP per increment)."""
    output:
        curve=f"{RESULTS}/contact/{{scene}}.h5",
    log:
        f"{LOGS}/contact/{{scene}}.log",
    params:
        config=CONFIG_FILE,
    group:
        "contact"
    threads: 1
    resources:
        mem_mb=1500,
    conda:
        SSW_ENV
    shell:
        # one core per job: the LU is sequential; keep BLAS (the small LCP) from spawning more
        "OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 python -m ssw contact --scene {wildcards.scene} "
        "--config {params.config} --output {output.curve} > {log} 2>&1"


rule contact_figure:
    """The thesis's Figs 5 and 6: force vs indentation of a one-soil set, with Hertz."""
    input:
        lambda wc: CONTACT_FIGURE_JOBS[wc.figure][0],
    output:
        png=f"{RESULTS}/contact/figures/{{figure}}.png",
    log:
        f"{LOGS}/contact/figures/{{figure}}.log",
    params:
        label_by=lambda wc: CONTACT_FIGURE_JOBS[wc.figure][1],
        title=lambda wc: CONTACT_FIGURE_JOBS[wc.figure][2],
    conda:
        SSW_ENV
    shell:
        "python -m ssw contact-plot {input} --output {output.png} --label-by {params.label_by} "
        "--title '{params.title}' > {log} 2>&1"
