# Config validation and the input functions shared by the stages. The only place that
# validates the config: the JSON schema (snakemake.utils.validate fills its defaults), then
# the checks a schema cannot express (ssw.config.check_config).
import sys
from pathlib import Path

from snakemake.utils import validate

sys.path.insert(0, str(Path(workflow.basedir)))
import ssw.config as sswcfg  # noqa: E402


validate(config, schema="../schemas/config.schema.yaml")
sswcfg.check_config(config)

RESULTS = "results"
LOGS = "results/logs"
# The config file(s) Snakemake was given, passed to `ssw` commands with --config.
CONFIG_FILE = workflow.overwrite_configfiles[-1] if workflow.overwrite_configfiles else "config/config.yaml"
SCENES = sswcfg.all_scenes(config)


def scene_ids(set_name):
    """Scene ids of one set of the config."""
    return [s.scene_id for s in sswcfg.scenes(config, set_name)]


def scene_of(wildcards):
    """The Scene of a {scene} wildcard."""
    return SCENES[wildcards.scene]
