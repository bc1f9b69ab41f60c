# Stage I fits: modified-Hertz laws per contact scene, aggregated into K(E, nu) tables; the
# thesis's reports (Figs 5-7) and what each fitted law costs in TOF. One job per set: a
# set's outputs come from one `ssw fit-set` process (imports paid once; the fits are cheap).
# Science lives in ssw.fit.
#
# Outputs (results/fit/):
#   sets/{set}/k_table.h5 / .csv / .json   every law's fit of every scene of the set (the
#                                 chain's `fit` wall reads the one of fit.set)
#   deviation_{set}.csv / .json   deviation from Hertz at fit.delta_ref, next to the thesis
#                                 (sets with one soil: the thesis's Sets 1 and 2)
#   figures/{set}_curves.png      force vs indentation with bare-soil Hertz (Figs 5, 6)
#   figures/{set}_deviation.png   deviation from Hertz per scene (Figs 5, 6 statements)
#   figures/{set}_k_vs_E.png      K vs soil E for each nu (Fig 7; sets with several soils)
#   tof_impact_{set}.csv / .json  TOF with the FEM law itself vs the K and power fits
# and results/contact/figures/{set}_contact.png (one-soil sets: thesis Figs 5, 6).

FIT_DIR = f"{RESULTS}/fit"
ONE_SOIL_SETS = sswwf.one_soil_sets(config)
GRID_SETS = sswwf.grid_sets(config)


if ONE_SOIL_SETS:

    # Every fit output of a one-soil set, and its contact figure, in one process.
    rule fit_set:
        input:
            set_curves,
        output:
            k_table=multiext(f"{FIT_DIR}/sets/{{set}}/k_table", ".h5", ".csv", ".json"),
            deviation=multiext(f"{FIT_DIR}/deviation_{{set}}", ".csv", ".json"),
            curves=fit_figure("curves", "fit_curves"),
            deviation_figure=fit_figure("deviation", "fit_deviation"),
            contact_figure=report(
                f"{RESULTS}/contact/figures/{{set}}_contact.png",
                caption="../report/contact_figure.rst",
                category=REPORT_CATEGORIES["contact"],
                subcategory="Figures",
            ),
        log:
            f"{LOGS}/fit/{{set}}.log",
        benchmark:
            f"{BENCHMARKS}/fit/{{set}}.tsv"
        wildcard_constraints:
            set=sswwf.alternatives(ONE_SOIL_SETS),
        conda:
            SSW_ENV
        resources:
            mem_mb=lambda wc, attempt: sswwf.mem_mb("fit", 0) * attempt,
            runtime=lambda wc, attempt: sswwf.runtime_min("fit", 0) * attempt,
        params:
            inputs=lambda wc: inputs_of("fit", wc.set),
            digest=lambda wc: digest_of("fit", wc.set),
            config=STUDY_CONFIG,
            # results/fit: two levels above sets/{set}/k_table.h5
            outdir=lambda wc, output: os.path.dirname(
                os.path.dirname(os.path.dirname(output.k_table[0]))
            ),
        shell:
            "python -m ssw --inputs-sha256 {params.digest:q} fit-set {wildcards.set:q} "
            "{input:q} --outdir {params.outdir:q} "
            "--contact-figure {output.contact_figure:q} --config {params.config:q} "
            "> {log:q} 2>&1"


if GRID_SETS:

    # Every fit output of a set over several soils (K(E, nu), its TOF cost).
    rule fit_grid:
        input:
            set_curves,
        output:
            k_table=multiext(f"{FIT_DIR}/sets/{{set}}/k_table", ".h5", ".csv", ".json"),
            k_figure=fit_figure("k_vs_E", "fit_k_vs_E"),
            tof_impact=multiext(f"{FIT_DIR}/tof_impact_{{set}}", ".csv", ".json"),
        log:
            f"{LOGS}/fit/{{set}}.log",
        benchmark:
            f"{BENCHMARKS}/fit/{{set}}.tsv"
        wildcard_constraints:
            set=sswwf.alternatives(GRID_SETS),
        conda:
            SSW_ENV
        resources:
            mem_mb=lambda wc, attempt: sswwf.mem_mb("fit", 0) * attempt,
            runtime=lambda wc, attempt: sswwf.runtime_min("fit", 0) * attempt,
        params:
            inputs=lambda wc: inputs_of("fit", wc.set),
            digest=lambda wc: digest_of("fit", wc.set),
            config=STUDY_CONFIG,
            # results/fit: two levels above sets/{set}/k_table.h5
            outdir=lambda wc, output: os.path.dirname(
                os.path.dirname(os.path.dirname(output.k_table[0]))
            ),
        shell:
            "python -m ssw --inputs-sha256 {params.digest:q} fit-set {wildcards.set:q} "
            "{input:q} --outdir {params.outdir:q} --config {params.config:q} > {log:q} 2>&1"


FIT_TARGETS = []
if ONE_SOIL_SETS:
    FIT_TARGETS += expand(rules.fit_set.output, set=ONE_SOIL_SETS)
if GRID_SETS:
    FIT_TARGETS += expand(rules.fit_grid.output, set=GRID_SETS)
