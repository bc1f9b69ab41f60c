# ssw workflow: the table of contents. Stages live in workflow/rules/*.smk; the science
# lives in the ssw package, which the rules call through the `ssw` command line.
from snakemake.utils import min_version

min_version("9.0")


configfile: "config/config.yaml"


report: "workflow/report/workflow.rst"


# the sweep's parts (rule tof_sweep); more for a cluster: --set-scatter sweep=8
scattergather:
    sweep=1,


include: "workflow/rules/common.smk"
include: "workflow/rules/contact.smk"
include: "workflow/rules/fit.smk"
include: "workflow/rules/chain.smk"
include: "workflow/rules/survey.smk"
include: "workflow/rules/validation.smk"


# light jobs run where Snakemake runs, never submitted to a cluster
localrules:
    all,
    sweep_figure,
    survey_table,
    report_tables,


rule all:
    default_target: True
    input:
        CONTACT_TARGETS,
        FIT_TARGETS,
        CHAIN_TARGETS,
        SURVEY_TARGETS,
        VALIDATION_TARGETS,
