# Stage III: validation on the control foams (thesis Tables 2 and 3, Figs 9 and 10) and the
# study report. Science lives in ssw.validation / ssw.signal / ssw.report; these rules call
# `ssw validate` and `ssw report`.
#
# Outputs:
#   results/validation/validation.csv / .h5 / .json   every field of Tables 2 and 3 (SI)
#   results/validation/table2_tof.csv, table3_modulus.csv  the thesis's tables, ssw beside it
#   results/validation/fig10_tof_validation.png      Fig 10: measured vs simulated TOF
#   results/validation/fig9_tof_scatter.png          Fig 9 style: TOF scatter of repeated hits
#   results/report/report.html                       every figure and table of the study


VALIDATION_DIR = f"{RESULTS}/validation"


rule validation:
    """Tables 2 and 3 and Figs 9 and 10 for the config's validation samples."""
    input:
        unpack(validation_inputs),
    output:
        csv=f"{VALIDATION_DIR}/validation.csv",
        h5=f"{VALIDATION_DIR}/validation.h5",
        json=f"{VALIDATION_DIR}/validation.json",
        table2=f"{VALIDATION_DIR}/table2_tof.csv",
        table3=f"{VALIDATION_DIR}/table3_modulus.csv",
        fig10=f"{VALIDATION_DIR}/fig10_tof_validation.png",
        fig9=f"{VALIDATION_DIR}/fig9_tof_scatter.png",
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


# Every other stage's targets exist when this file is included (the Snakefile includes it
# last); the report waits for all of them.
_STAGE_TARGETS = [
    t
    for name in ("CONTACT_TARGETS", "FIT_TARGETS", "CHAIN_TARGETS")
    for t in globals().get(name, [])
]


rule report:
    """A self-contained HTML report with every figure and table of the study."""
    input:
        stages=_STAGE_TARGETS,
        validation=rules.validation.output,
        captions=os.path.join(workflow.basedir, "workflow", "report", "captions.yaml"),
    output:
        html=f"{RESULTS}/report/report.html",
    log:
        f"{LOGS}/report/report.log",
    params:
        config=CONFIG_FILE,
    conda:
        SSW_ENV
    shell:
        "python -m ssw report --config {params.config} --results $(dirname $(dirname {output.html})) "
        "--captions {input.captions} --output {output.html} > {log} 2>&1"


VALIDATION_TARGETS = [*rules.validation.output, rules.report.output.html]
