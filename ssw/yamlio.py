"""YAML documents read with libyaml's parser when PyYAML carries it.

PyYAML's ``yaml.safe_load`` scans and parses in pure Python; ``yaml.CSafeLoader`` does the
same in libyaml (C) and builds the same objects with the same safe constructor (YAML 1.1
types: no Python objects). The configuration schema (35 kB) loads in 13 ms instead of
88 ms, which every command that reads a study config, a device or the materials pays
(measured on a 2-core machine). Without libyaml, the pure-Python loader is used.
"""

from __future__ import annotations

from typing import Any

import yaml

#: The safe loader: libyaml's when available.
SAFE_LOADER: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def safe_load(text: str) -> Any:
    """The object of one YAML document, by the safe loader (:data:`SAFE_LOADER`).

    Parameters
    ----------
    text : str
        The document.

    Returns
    -------
    Any
        Its value (dicts, lists, str, int, float, bool, None, dates).
    """
    return yaml.load(text, Loader=SAFE_LOADER)
