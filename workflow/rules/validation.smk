# Stage III: validation on the control foams (thesis Tables 2 and 3, Figs 9 and 10) and the
# tables of the study report. Science lives in ssw.validation / ssw.signal / ssw.report;
# these rules call `ssw validate` and `ssw report`.
#
# Outputs:
#   results/validation/validation.csv / .h5 / .json   every field of Tables 2 and 3 (SI)
#   results/validation/table2_tof.csv, table3_modulus.csv  the thesis's tables, ssw beside it
#   results/validation/fig10_tof_validation.png      Fig 10: measured vs simulated TOF
#   results/validation/fig9_tof_scatter.png          Fig 9 style: TOF scatter of repeated hits
#   results/report/tables_{stage}.html               each stage's tables for the study report
#                                                    (snakemake --report results/report.html)

VALIDATION_DIR = f"{RESULTS}/validation"


# Tables 2 and 3 and Figs 9 and 10 for the validation samples of the config.
rule validation:
    input:
        unpack(validation_inputs),
    output:
        csv=f"{VALIDATION_DIR}/validation.csv",
        h5=f"{VALIDATION_DIR}/validation.h5",
        json=f"{VALIDATION_DIR}/validation.json",
        table2=f"{VALIDATION_DIR}/table2_tof.csv",
        table3=f"{VALIDATION_DIR}/table3_modulus.csv",
        fig10=report(
            f"{VALIDATION_DIR}/fig10_tof_validation.png",
            caption="../report/fig10.rst",
            category=REPORT_CATEGORIES["validation"],
            subcategory="Figures",
        ),
        fig9=report(
            f"{VALIDATION_DIR}/fig9_tof_scatter.png",
            caption="../report/fig9.rst",
            category=REPORT_CATEGORIES["validation"],
            subcategory="Figures",
        ),
    log:
        f"{LOGS}/validation/validation.log",
    benchmark:
        f"{BENCHMARKS}/validation/validation.tsv"
    priority: 30
    conda:
        SSW_ENV
    resources:
        mem_mb=lambda wc, attempt: sswwf.mem_mb("validation", 0) * attempt,
        runtime=lambda wc, attempt: sswwf.runtime_min("validation", 0) * attempt,
    params:
        inputs=inputs_of("validation"),
        digest=digest_of("validation"),
        config=STUDY_CONFIG,
        root=RECORDINGS_ROOT,
        outdir=lambda wc, output: os.path.dirname(output.csv),
        chain=chain_flags,
    shell:
        "python -m ssw --inputs-sha256 {params.digest:q} validate "
        "--config {params.config:q} {params.chain:q} --root {params.root:q} "
        "--sweep {input.sweep:q} --outdir {params.outdir:q} --json > {output.json:q} "
        "2> {log:q}"


# The study report is Snakemake's own, built after the run:
#   snakemake --report results/report.html [--configfile ...]
# with every figure and table the stages flag with report(...) (a category per stage the
# study shows, REPORT_CATEGORIES in common.smk; captions in workflow/report/*.rst, the
# description workflow/report/workflow.rst, which lists the same categories). It shows
# CSV files only as downloads, so rule report_tables renders each stage's tables as one HTML
# page (ssw report) that the report opens inline.
# stage -> its CSV tables (the targets of the stages before: the Snakefile includes them
# first; the plate design flags its own table)
REPORT_TABLES = sswwf.report_tables(
    [*FIT_TARGETS, *CHAIN_TARGETS, *SURVEY_TARGETS, *rules.validation.output],
    REPORT_CATEGORIES,
    RESULTS,
)


# The tables (CSV) of every stage as one HTML page per stage for the Snakemake report, in
# one process.
rule report_tables:
    input:
        tables=[t for ts in REPORT_TABLES.values() for t in ts],
        captions=os.path.join(workflow.basedir, "report", "captions.yaml"),
    output:
        **{
            stage: report(
                f"{RESULTS}/report/tables_{stage}.html",
                caption="../report/tables.rst",
                category=REPORT_CATEGORIES[stage],
                subcategory="Tables",
            )
            for stage in REPORT_TABLES
        },
    log:
        f"{LOGS}/report/tables.log",
    benchmark:
        f"{BENCHMARKS}/report/tables.tsv"
    conda:
        SSW_ENV
    params:
        inputs=inputs_of("report"),
        digest=digest_of("report"),
        pages=lambda wc, input, output: sswwf.report_page_args(
            output, REPORT_TABLES, REPORT_CATEGORIES
        ),
    shell:
        "python -m ssw --inputs-sha256 {params.digest:q} report {params.pages:q} "
        "--captions {input.captions:q} > {log:q} 2>&1"


VALIDATION_TARGETS = [*rules.validation.output, *rules.report_tables.output]
