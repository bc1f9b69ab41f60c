"""Every YAML file the project ships (schemas, configs, devices, materials, profiles) holds
each mapping key once: a YAML loader keeps the last of two equal keys silently, so a key
written twice (a merge that kept both sides) would hide the first definition."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
FILES = sorted(
    p for d in ("ssw/data", "config", "workflow") for p in (ROOT / d).rglob("*.y*ml")
    if p.suffix in (".yaml", ".yml")
)


class _UniqueKeys(yaml.SafeLoader):
    """A SafeLoader that refuses a mapping with a key twice."""


def _mapping(loader: _UniqueKeys, node: yaml.MappingNode, deep: bool = False) -> dict:
    seen: dict = {}
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)
        if key in seen:
            raise yaml.constructor.ConstructorError(
                None, None, f"key {key!r} twice (first at line {seen[key] + 1})",
                key_node.start_mark)
        seen[key] = key_node.start_mark.line
    return loader.construct_mapping(node, deep=deep)


_UniqueKeys.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _mapping)


def test_the_loader_refuses_a_key_twice() -> None:
    with pytest.raises(yaml.constructor.ConstructorError, match="'a' twice"):
        yaml.load("a: 1\nb: 2\na: 3\n", Loader=_UniqueKeys)


@pytest.mark.parametrize("path", FILES, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_key_twice(path: Path) -> None:
    yaml.load(path.read_text(), Loader=_UniqueKeys)
