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


rule validation:
    """Tables 2 and 3 and Figs 9 and 10 for the config's validation samples."""
    priority: 30
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
            category="4. Validation (Stage III)",
            subcategory="Figures",
        ),
        fig9=report(
            f"{VALIDATION_DIR}/fig9_tof_scatter.png",
            caption="../report/fig9.rst",
            category="4. Validation (Stage III)",
            subcategory="Figures",
        ),
    log:
        f"{LOGS}/validation/validation.log",
    params:
        config=CONFIG_FILE,
        flags=validation_flags,
        root=RECORDINGS_ROOT,
    conda:
        SSW_ENV
    shell:
        "python -m ssw validate --config {params.config} {params.flags} --root {params.root} "
        "--sweep {input.sweep} "
        "--outdir $(dirname {output.csv}) --json > {output.json} 2> {log}"


# The study report is Snakemake's own, built after the run:
#   snakemake --report results/report.html [--configfile ...]
# with every figure and table the stages flag with report(...) (a category per stage,
# captions in workflow/report/*.rst, the description workflow/report/workflow.rst). It shows
# CSV files only as downloads, so rule report_tables renders each stage's tables as one HTML
# page (ssw report) that the report opens inline.
# Every other stage's targets exist when this file is included (the Snakefile includes it
# last).
_STAGE_TARGETS = [
    t
    for name in ("CONTACT_TARGETS", "FIT_TARGETS", "CHAIN_TARGETS", "SURVEY_TARGETS")
    for t in globals().get(name, [])
]
# results sub-folder -> the report's category (numbered: the report sorts categories by name)
REPORT_CATEGORIES = {
    "contact": "1. Contact (Stage I)",
    "fit": "2. Fits (Stage I)",
    "chain": "3. Chain (Stage II)",
    "validation": "4. Validation (Stage III)",
    "survey": "5. Survey",
}
# stage -> its CSV tables
REPORT_TABLES = {
    stage: tables
    for stage in REPORT_CATEGORIES
    if (
        tables := [
            str(t)
            for t in [*_STAGE_TARGETS, *rules.validation.output]
            if str(t).startswith(f"{RESULTS}/{stage}/") and str(t).endswith(".csv")
        ]
    )
}


rule report_tables:
    """Every stage's tables (CSV) as one HTML page per stage for the Snakemake report, in
    one process."""
    input:
        tables=[t for ts in REPORT_TABLES.values() for t in ts],
        captions=os.path.join(workflow.basedir, "workflow", "report", "captions.yaml"),
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
    params:
        pages=report_page_args,
    conda:
        SSW_ENV
    shell:
        "python -m ssw report {params.pages} --captions {input.captions} > {log} 2>&1"


VALIDATION_TARGETS = [*rules.validation.output, *rules.report_tables.output]
