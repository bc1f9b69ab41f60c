# Config validation and the input functions shared by the stages. The only place that
# validates the config: the JSON schema (snakemake.utils.validate fills its defaults), then
# the checks a schema cannot express (ssw.config.check_config).
import copy
import os
import shlex
import sys
from pathlib import Path

from snakemake.utils import validate

sys.path.insert(0, str(Path(workflow.basedir)))
import ssw.chain.workflow as chainwf  # noqa: E402
import ssw.config as sswcfg  # noqa: E402
from ssw.h5io import atomic_write_text  # noqa: E402

# The rules run `python -m ssw ...` with the repository on PYTHONPATH. `python` is the one
# of the environment that runs Snakemake (the project's .venv for `make study`, activated or
# not: its bin goes first on PATH) or, with `--sdm conda`, the rules' conda environment
# (workflow/envs/ssw.yaml: ssw's dependencies, not ssw itself). Snakemake formats the prefix
# once, here.
os.environ.update(PATH=os.pathsep.join([os.path.dirname(sys.executable), os.getenv("PATH", "")]))
SSW_ROOT = shlex.quote(str(Path(workflow.basedir).resolve()))
shell.prefix("set -euo pipefail; export PYTHONPATH={SSW_ROOT}${{PYTHONPATH:+:$PYTHONPATH}}; ")
SSW_ENV = "../envs/ssw.yaml"

# A study config is complete by itself: `--configfile other.yaml` replaces
# config/config.yaml instead of being merged into it (`--config key=value` still applies).
if workflow.overwrite_configfiles:
    config.clear()
    config.update(copy.deepcopy(workflow.config_settings.overwrite_config))

validate(config, schema="../schemas/config.schema.yaml")
sswcfg.check_config(config)

RESULTS = "results"
LOGS = "results/logs"


def _resolved_config_file():
    """Write the validated config (defaults filled) for the `ssw` commands; only on change."""
    path = Path(RESULTS) / "study_config.yaml"
    text = sswcfg.dump_config(config)
    if not path.exists() or path.read_text() != text:
        atomic_write_text(path, text)
    return str(path)


# The resolved study config, passed to `ssw ... --config {CONFIG_FILE}` by the rules.
CONFIG_FILE = _resolved_config_file()
SCENES = sswcfg.all_scenes(config)


def scene_ids(set_name):
    """Scene ids of one set of the config."""
    return [s.scene_id for s in sswcfg.scenes(config, set_name)]


def scene_of(wildcards):
    """The Scene of a {scene} wildcard."""
    return SCENES[wildcards.scene]


# ---- fit stage (workflow/rules/fit.smk)
def contact_curves(set_name):
    """The contact curve files of one set."""
    return expand(f"{RESULTS}/contact/{{scene}}.h5", scene=scene_ids(set_name))


def _n_soils(set_name):
    s = config["sets"][set_name]
    return len(sswcfg.expand_grid(s["soil_E"], f"sets.{set_name}.soil_E"))


def deviation_kind(set_name):
    """`materials` for a set varying the plate material, else `thickness`."""
    return "materials" if len(config["sets"][set_name]["plate_material"]) > 1 else "thickness"


# ---- validation stage (workflow/rules/validation.smk)
# Relative recording paths in the config start from the repository (the Snakefile's folder),
# so that runs with --directory elsewhere find them; `ssw validate --root` gets the same.
RECORDINGS_ROOT = workflow.basedir


def validation_inputs(wildcards):
    """The chain's TOF sweep (drawn in Fig 10), the wall law's inputs, every sample's
    recording and, with calibration.use, the calibration."""
    inputs = {"sweep": rules.tof_sweep.output.h5, **chainwf.calibrated_inputs(config, RESULTS)}
    recs = chainwf.recordings(config, RECORDINGS_ROOT)
    if recs:
        inputs["recordings"] = recs
    return inputs


def validation_flags(wildcards, input):
    """The wall law's flags and --calibration for the inputs the validation job has."""
    return " ".join([chainwf.wall_flags(config, input, RESULTS), chainwf.calibration_flag(input)])


# ---- survey (workflow/rules/survey.smk)
def survey_point_inputs(point_id):
    """A test point's recordings (from the repository), the wall law's inputs and, with
    calibration.use, the calibration."""
    pt = {p["id"]: p for p in config["survey"]["points"]}[point_id]
    return {"recordings": [os.path.join(RECORDINGS_ROOT, r) for r in pt["recordings"]],
            **chainwf.calibrated_inputs(config, RESULTS)}


def survey_nu(point_id):
    """The point's --soil-nu argument (NU or LO:HI)."""
    from ssw.survey import nu_text

    return nu_text({p["id"]: p for p in config["survey"]["points"]}[point_id]["soil_nu"])


def survey_has_coordinates():
    """Whether any survey point has plan or geographic coordinates (a map is drawn)."""
    return any(p.get("x") is not None or p.get("latitude") is not None
               for p in config.get("survey", {}).get("points", []))


# ---- report (workflow/rules/validation.smk)
def report_page_args(wildcards, input, output):
    """`ssw report --page OUTPUT TITLE CSV...` for every stage's tables page."""
    return " ".join(
        f"--page {shlex.join([getattr(output, st), f'{REPORT_CATEGORIES[st]}: tables', *ts])}"
        for st, ts in REPORT_TABLES.items()
    )
