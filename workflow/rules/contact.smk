# Stage I contact FEM: one force-indentation curve per scene of every set of the config.
# Science lives in ssw.contact; rule contact_batch calls the `ssw contact` command.
#
# Outputs (results/contact/):
#   {family}/{scene}.h5            the curve of a scene (ssw.curve.read_curve); a family is
#                                  the scenes of one plate material and thickness (or of no
#                                  plate), whatever set lists them (ssw.workflow.families)
#   figures/{set}_contact.png      force vs indentation of a one-soil set (thesis Figs 5, 6:
#                                  drawn by the set's fit job, workflow/rules/fit.smk)
#
# One job per family: its scenes share the mesh and the plate's condensed operators (~0.1-0.5
# s each to build, ssw.contact.operators), then cost milliseconds each; a process costs ~1 s
# of start-up. An edit reruns the families it touches only (a plate material's modulus: that
# material's families; a new thickness: one new family). The operators are cached on disk
# under $SSW_CACHE_DIR (default here: results/cache, so a run from clean builds them),
# shared by every rule of the study (the chain's `fem` wall uses the same ones).

os.environ.setdefault("SSW_CACHE_DIR", os.path.abspath(f"{RESULTS}/cache"))

CONTACT_FAMILIES = STUDY.families
CONTACT_TARGETS = [f"{RESULTS}/contact/{f}" for f in CONTACT_FAMILIES]


wildcard_constraints:
    family=sswwf.alternatives(CONTACT_FAMILIES),


# The scenes of one plate family, solved in turn by one process.
rule contact_batch:
    output:
        directory(f"{RESULTS}/contact/{{family}}"),
    log:
        f"{LOGS}/contact/{{family}}.log",
    benchmark:
        f"{BENCHMARKS}/contact/{{family}}.tsv"
    conda:
        SSW_ENV
    threads: 1
    resources:
        mem_mb=lambda wc, attempt: sswwf.mem_mb(
            "contact", len(CONTACT_FAMILIES[wc.family])
        )
        * attempt,
        runtime=lambda wc, attempt: sswwf.runtime_min(
            "contact", len(CONTACT_FAMILIES[wc.family])
        )
        * attempt,
    params:
        inputs=lambda wc: inputs_of("contact", wc.family),
        digest=lambda wc: digest_of("contact", wc.family),
        config=STUDY_CONFIG,
    shell:
        "python -m ssw --inputs-sha256 {params.digest:q} contact "
        "--family {wildcards.family:q} --config {params.config:q} --output-dir {output:q} "
        "> {log:q} 2>&1"
