# Config validation and the input functions shared by the stages. The only place that
# validates the config: ssw.config.validate_config, as every ssw command does (the JSON
# schema through ssw.schema, which fills its defaults and refuses NaN and infinities, then
# the checks a schema cannot express, ssw.config.check_config). What each job reads of the
# study is ssw.workflow.Study.inputs: the rules pass it as a param, so that Snakemake reruns
# a job exactly when its inputs change (docs/CONTRACTS.md, "Exact reruns").
import copy
import os
import sys
from pathlib import Path

# the repository: the package ssw and the config's relative paths (recordings) start there
REPO = Path(workflow.basedir).resolve().parent
sys.path.insert(0, str(REPO))
import ssw.config as sswcfg  # noqa: E402
import ssw.schema as sswschema  # noqa: E402
import ssw.warmstart as sswwarm  # noqa: E402
import ssw.workflow as sswwf  # noqa: E402

# The rules run `python -m ssw ...` with the repository on PYTHONPATH. `python` is the one
# of the environment that runs Snakemake (the project's .venv for `make study`, activated or
# not: its bin goes first on PATH) or, with `--sdm conda`, the rules' conda environment
# (workflow/envs/ssw.yaml: ssw's dependencies, not ssw itself). Snakemake formats the prefix
# once, here.
os.environ.update(
    PATH=os.pathsep.join([os.path.dirname(sys.executable), os.getenv("PATH", "")])
)
SSW_ROOT = str(REPO)
shell.prefix(
    "set -euo pipefail; export PYTHONPATH={SSW_ROOT:q}${{PYTHONPATH:+:$PYTHONPATH}}; "
)
SSW_ENV = "../envs/ssw.yaml"
# Jobs that Snakemake spawns as `python -m snakemake ...` (on Slurm, and the job step inside
# each job: both read this file) name the interpreter quoted, as every other argument.
sswwf.quote_job_python()

# A study config is complete by itself: `--configfile other.yaml` replaces
# config/config.yaml instead of being merged into it (`--config key=value` still applies).
if workflow.overwrite_configfiles:
    config.clear()
    config.update(copy.deepcopy(workflow.config_settings.overwrite_config))

# Parsing this file (a run, a dry run, a lint) reads the validations the jobs remembered
# (ssw.schema) and writes none: a dry run writes nothing.
sswschema.set_memo_writes(False)
sswcfg.validate_config(config)

RESULTS = sswwf.RESULTS
LOGS = f"{RESULTS}/logs"
BENCHMARKS = f"{RESULTS}/benchmarks"
# The resolved study config every job reads (`ssw ... --config {STUDY_CONFIG}`): written when
# a run starts (onstart; a dry run or a lint writes nothing), and only when it changed.
STUDY_CONFIG = sswwf.STUDY_CONFIG
STUDY = sswwf.Study(config)
SCENES = STUDY.scenes
# The report's outline: stage -> its category, the stages the study shows numbered in order
# (ssw.workflow.report_categories; workflow/report/workflow.rst lists the same categories).
REPORT_CATEGORIES = sswwf.report_categories(config)
# Relative recording paths in the config start from the repository (the Snakefile's folder),
# so that runs with --directory elsewhere find them; `ssw ... --root` gets the same.
RECORDINGS_ROOT = str(REPO)


onstart:
    # On Slurm, a run that would wait forever is an error now: a job no node can hold, a
    # status command that cannot see jobs end (no accounting: squeue instead of sacct), and,
    # while the run goes, jobs that Slurm no longer shows (ssw.cluster).
    if sswwf.submits_to_slurm(workflow):
        for note in sswwf.prepare_slurm_run(workflow):
            print(f"ssw cluster check: {note}", file=sys.stderr)
    sswwf.write_study_config(config, STUDY_CONFIG)
    # Jobs on this machine: their `python -m ssw` forks a process that has already imported
    # ssw and its libraries (ssw.warmstart; SSW_WARM_START=0 turns it off), this run's own
    # unless `make study` started one beside Snakemake.
    sswwarm.start_for(workflow, str(REPO), Path(LOGS) / "warm-start.log")


# Once the last job is done: the warm process ends, and no timer of the scheduler holds the
# exit (ssw.workflow.end_of_run).
onsuccess:
    sswwarm.stop_all()
    sswwf.end_of_run()


onerror:
    sswwarm.stop_all()
    sswwf.end_of_run()


def inputs_of(step, key=None):
    """The slice of the study a job reads (a param: Snakemake reruns the job when it
    changes) and its digest (recorded in the job's results)."""
    return STUDY.param(step, key)


def digest_of(step, key=None):
    return STUDY.digest(step, key)


# ---- validation and survey: the chain's wall law and calibration
def calibrated_inputs(wildcards):
    """The wall law's inputs and, with calibration.use, the calibration."""
    return sswwf.calibrated_inputs(config, RESULTS)


def chain_flags(wildcards, input):
    """The wall law's flags and --calibration for the inputs the job has (a list of
    arguments: the rules quote each, `{params.chain:q}`)."""
    return [*sswwf.wall_flags(config, input, RESULTS), *sswwf.calibration_flag(input)]


# ---- fit stage (workflow/rules/fit.smk)
def set_curves(wildcards):
    """The contact families holding the set's scenes (`ssw fit-set` takes the set's curves
    from them)."""
    return sswwf.set_families(config, wildcards.set, RESULTS)


def fit_figure(name, caption):
    """A fit job's figure `{set}_<name>.png`, flagged for the report with its caption."""
    return report(
        f"{RESULTS}/fit/figures/{{set}}_{name}.png",
        caption=f"../report/{caption}.rst",
        category=REPORT_CATEGORIES["fit"],
        subcategory="Figures",
    )


# ---- validation (workflow/rules/validation.smk)
def validation_inputs(wildcards):
    """The sweep's parts (drawn in Fig 10), the wall law's inputs, every sample's recording
    and, with calibration.use, the calibration."""
    inputs = {
        "sweep": gather.sweep(f"{RESULTS}/chain/parts/tof_{{scatteritem}}.h5"),
        **sswwf.calibrated_inputs(config, RESULTS),
    }
    recs = sswwf.recordings(config, RECORDINGS_ROOT)
    if recs:
        inputs["recordings"] = recs
    return inputs


# ---- survey (workflow/rules/survey.smk)
def survey_point_inputs(wildcards):
    """A test point's recordings (from the repository), the wall law's inputs and, with
    calibration.use, the calibration."""
    return {
        "recordings": sswwf.point_recordings(config, wildcards.point, RECORDINGS_ROOT),
        **sswwf.calibrated_inputs(config, RESULTS),
    }


def device_calibration(wc):
    """The calibration file of the device design's jobs (when the study calibrates)."""
    return {
        k: v
        for k, v in sswwf.calibrated_inputs(config, RESULTS).items()
        if k == "calibration"
    }
