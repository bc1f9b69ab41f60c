# Stage I contact FEM: one force-indentation curve per scene of every set of the config.
# Science lives in ssw.contact; these rules call the `ssw contact` command.
#
# Outputs (results/contact/):
#   {scene}.h5                     the curve of a scene (ssw.curve.read_curve)
#   figures/fig5_materials.png     force vs indentation per plate material (set1_materials)
#   figures/fig6_thickness.png     force vs indentation per PLA thickness (set2_thickness)
#                                  (both drawn by the set's fit job: workflow/rules/fit.smk)
#
# Batches: a scene costs milliseconds once its operators exist (the plate and the soil
# condensed per mesh and Poisson's ratio, ~0.1-0.5 s each: ssw.contact.operators), a process
# ~1 s of imports. So one job solves a whole mesh family (the scenes of one plate thickness,
# whatever set lists them: they share the mesh and the plate's operators), cut into equal
# chunks only beyond contact.jobs_per_group scenes (ssw.contact.batch.batches): one rule per
# batch, contact_batch_<family>[_<k>], defined in a loop (the `name:` directive). Each
# declares its resources (scaled with its size; doubled on a retry), so the SLURM profile
# needs no per-batch entries. The operators are cached on disk under $SSW_CACHE_DIR
# (default here: results/cache, so a run from clean builds them), shared by every rule of
# the study (the chain's `fem` wall uses the same ones); the variable is set for all jobs.

import ssw.contact.batch as contact_batch

os.environ.setdefault("SSW_CACHE_DIR", os.path.abspath(f"{RESULTS}/cache"))

# set -> (figure name, --label-by, title): the thesis's Figs 5 and 6, drawn by the set's fit
# job (workflow/rules/fit.smk)
CONTACT_FIGURES = {
    "set1_materials": ("fig5_materials", "material", "Plate materials (thesis Fig 5)"),
    "set2_thickness": ("fig6_thickness", "thickness", "PLA plate thickness (thesis Fig 6)"),
}

# the figures (thesis Figs 5, 6) are drawn by the fit job of their set, which reads those
# curves anyway (workflow/rules/fit.smk: rule fit_set_<set>, `ssw fit-set --contact-figure`)
CONTACT_TARGETS = expand(f"{RESULTS}/contact/{{scene}}.h5", scene=list(SCENES))


wildcard_constraints:
    scene="[A-Za-z0-9_.\-]+",


CONTACT_BATCHES = contact_batch.batches(config)

for _batch, _ids in CONTACT_BATCHES.items():

    # the scenes of one mesh family (or a chunk of it), solved in turn by one process
    rule:
        name:
            f"contact_batch_{_batch}"
        output:
            expand(f"{RESULTS}/contact/{{scene}}.h5", scene=_ids),
        log:
            f"{LOGS}/contact/batch_{_batch}.log",
        params:
            config=CONFIG_FILE,
            out_dir=lambda wildcards, output: os.path.dirname(output[0]),
            scenes=" ".join(f"--scene {s}" for s in _ids),
        threads: 1
        resources:
            mem_mb=lambda wildcards, attempt: contact_batch.MEM_MB * attempt,
            runtime=lambda wildcards, attempt, n=len(_ids): contact_batch.runtime(n) * attempt,
        conda:
            SSW_ENV
        shell:
            # one core per job: the factorizations are sequential; keep BLAS (the dense
            # scene systems) from spawning threads
            "OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 python -m ssw contact {params.scenes} "
            "--config {params.config} --output-dir {params.out_dir} > {log} 2>&1"
