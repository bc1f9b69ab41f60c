# Config validation and the input functions shared by the stages. The only place that
# validates the config: the JSON schema (snakemake.utils.validate fills its defaults), then
# the checks a schema cannot express (ssw.config.check_config).
import copy
import sys
from pathlib import Path

from snakemake.utils import validate

sys.path.insert(0, str(Path(workflow.basedir)))
import ssw.config as sswcfg  # noqa: E402
from ssw.h5io import atomic_write_text  # noqa: E402

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
