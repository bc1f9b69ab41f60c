# ssw workflow: the table of contents. Stages live in workflow/rules/*.smk; the science
# lives in the ssw package, which the rules call through the `ssw` command line.
from snakemake.utils import min_version

min_version("9.0")


configfile: "config/config.yaml"


report: "workflow/report/workflow.rst"


include: "workflow/rules/common.smk"
include: "workflow/rules/contact.smk"
include: "workflow/rules/fit.smk"
include: "workflow/rules/chain.smk"
include: "workflow/rules/survey.smk"
include: "workflow/rules/validation.smk"


rule all:
    default_target: True
    input:
        CONTACT_TARGETS,
        FIT_TARGETS,
        CHAIN_TARGETS,
        SURVEY_TARGETS,
        VALIDATION_TARGETS,
