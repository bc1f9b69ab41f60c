"""Sphinx extension of ssw's documentation: the references generated at build time.

Three directives write reStructuredText from the code itself, so the pages cannot drift
from it:

* ``ssw-config-reference`` (argument ``config`` or ``device``): every key of the JSON
  schema (``ssw/data/config.schema.yaml``, ``ssw/data/device.schema.yaml``) with its type,
  default, units and description;
* ``ssw-cli-reference``: every subcommand of ``ssw`` (``ssw.cli.build_parser``) with its
  usage, description, flags, defaults and help;
* ``ssw-api`` (argument a module or package of ``ssw``): an ``automodule`` section for that
  module, or for each module of that package (not its subpackages).

Checks (warnings, so that ``sphinx-build -W`` fails): a schema key without a description, a
command or flag without help, a module of ``ssw`` that no ``ssw-api`` directive documents,
and a numpydoc ``Parameters``/``Other Parameters`` entry that packs several names on one
line (``a, b : float``; the house rule is one parameter per entry).

A reference to an object of ``ssw`` by a name it is imported under (a package's re-export,
``ssw.validity.RULES``; a bare name a module imports) resolves to where the object is
documented (:func:`defining_target`).
"""

from __future__ import annotations

import argparse
import functools
import importlib
import pkgutil
import re
from pathlib import Path
from typing import Any

import yaml
from docutils import nodes
from docutils.statemachine import StringList
from sphinx.application import Sphinx
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective
from sphinx.util.nodes import nested_parse_with_titles

logger = logging.getLogger(__name__)

ROOT = Path(__file__).resolve().parents[2]
SCHEMAS = {
    "config": ROOT / "ssw" / "data" / "config.schema.yaml",
    "device": ROOT / "ssw" / "data" / "device.schema.yaml",
}

#: Units recognised in a schema description: a token standing alone after the start, a
#: comma or an opening parenthesis and before the end, a comma, a semicolon, a full stop
#: or a parenthesis.
UNITS = ("kg/m^3", "kg/m3", "m/s^2", "m/s", "N s/m", "N rms", "V/N", "S/s", "Pa", "Hz",
         "kg", "J", "N", "m", "s", "A", "%", "degrees")
_UNIT_RE = re.compile(
    r"(?:^|, |\()(" + "|".join(re.escape(u) for u in UNITS) + r")(?=$|[,;.)]| \(| -| rms)"
)


# ------------------------------------------------------------------ reStructuredText


def _rst_escape(text: str) -> str:
    """Text as inline reStructuredText: backslashes, stars, pipes and backquotes escaped,
    whitespace (YAML's folded lines) made single."""
    text = " ".join(str(text).split())
    for ch in ("\\", "*", "`", "|", "_"):
        text = text.replace(ch, "\\" + ch)
    return text


def _literal(value: Any) -> str:
    """A value as an inline literal (YAML flow style: what a config file would hold)."""
    text = yaml.safe_dump(value, default_flow_style=True, width=10**6).strip()
    if text.endswith("\n..."):
        text = text[:-4].strip()
    text = text.removesuffix("...").strip()
    return f"``{text}``"


def _parse_rst(directive: SphinxDirective, lines: list[str]) -> list[nodes.Node]:
    """Parse generated reStructuredText (sections allowed) into the directive's place."""
    node = nodes.section()
    node.document = directive.state.document
    source = directive.get_source_info()[0]
    content = StringList()
    for i, line in enumerate(lines):
        content.append(line, source, i)
    nested_parse_with_titles(directive.state, content, node)
    return node.children


def _heading(text: str, level: str) -> list[str]:
    return [text, level * len(text), ""]


def _list_table(header: list[str], rows: list[list[str]], widths: str) -> list[str]:
    out = [".. list-table::", "   :header-rows: 1", f"   :widths: {widths}", ""]
    for row in [header, *rows]:
        first = True
        for cell in row:
            out.append(("   * - " if first else "     - ") + (cell or "\\-"))
            first = False
    out.append("")
    return out


# ------------------------------------------------------------------ configuration schema


class _Schema:
    """A schema's keys, walked with ``$ref`` resolved against its ``$defs``."""

    def __init__(self, schema: dict[str, Any]) -> None:
        self.schema = schema
        self.defs = schema.get("$defs", {})

    def resolve(self, node: dict[str, Any]) -> dict[str, Any]:
        """``node`` with a ``$ref`` merged in (the node's own keywords win)."""
        if "$ref" in node:
            target = self.defs[node["$ref"].rsplit("/", 1)[1]]
            node = {**self.resolve(target), **{k: v for k, v in node.items() if k != "$ref"}}
        return node

    def type_of(self, node: dict[str, Any]) -> str:
        """What a value may be: types, enumerated values, bounds, in words."""
        raw = node
        node = self.resolve(node)
        if "$ref" in raw and raw["$ref"].endswith("/grid"):
            return "grid: ``{values: [...]}`` or ``{start, stop, step}``"
        if "enum" in node:
            return "one of " + ", ".join(_literal(v) for v in node["enum"])
        for key in ("oneOf", "anyOf"):
            if key in node:
                return " or ".join(self.type_of(alt) for alt in node[key])
        types = node.get("type", "any")
        types = [types] if isinstance(types, str) else list(types)
        words = []
        for t in types:
            if t == "array" and isinstance(node.get("items"), dict):
                item = self.type_of(node["items"])
                words.append(f"array of ({item})")
            else:
                words.append(t)
        text = " or ".join(words)
        bounds = []
        for key, sign in (("minimum", ">="), ("exclusiveMinimum", ">"),
                          ("maximum", "<="), ("exclusiveMaximum", "<")):
            if key in node:
                bounds.append(f"{sign} {node[key]}")
        for key, word in (("minItems", "at least"), ("maxItems", "at most")):
            if key in node:
                bounds.append(f"{word} {node[key]} items")
        if "pattern" in node:
            bounds.append(f"matching ``{node['pattern']}``")
        return text + (f" ({', '.join(bounds)})" if bounds else "")

    def keys(self, node: dict[str, Any] | None = None,
             path: tuple[str, ...] = ()) -> list[tuple[tuple[str, ...], dict[str, Any]]]:
        """(path, node) of every key below ``node``, depth first, in the schema's order.
        ``NAME`` stands for a key of the user's choosing, ``[]`` for a list's item."""
        node = self.resolve(self.schema if node is None else node)
        out = []
        for name, sub in node.get("properties", {}).items():
            out.append(((*path, name), sub))
            out.extend(self.keys(sub, (*path, name)))
        extra = node.get("additionalProperties")
        if isinstance(extra, dict) and "properties" in self.resolve(extra):
            out.append(((*path, "NAME"), extra))
            out.extend(self.keys(extra, (*path, "NAME")))
        items = node.get("items")
        if isinstance(items, dict) and "properties" in self.resolve(items):
            out.append(((*path, "[]"), items))
            out.extend(self.keys(items, (*path, "[]")))
        return out


def units_of(description: str) -> str:
    """The unit a schema description names (``m``, ``Pa``, ``kg/m^3``, ...), or ``""``."""
    match = _UNIT_RE.search(" ".join(description.split()))
    return match.group(1) if match else ""


def _dotted(path: tuple[str, ...]) -> str:
    return ".".join(path).replace(".[]", "[]")


class ConfigReference(SphinxDirective):
    """``.. ssw-config-reference:: config|device``: the schema's keys, section by section."""

    required_arguments = 1

    def run(self) -> list[nodes.Node]:
        which = self.arguments[0]
        path = SCHEMAS[which]
        self.env.note_dependency(str(path))
        schema = _Schema(yaml.safe_load(path.read_text()))
        source = path.relative_to(ROOT)
        lines = [
            f"Generated from ``{source}`` when these pages are built"
            f" ({_rst_escape(schema.schema.get('title', ''))}).",
            "",
            _rst_escape(schema.schema.get("description", "")),
            "",
        ]
        sections: dict[str, list[tuple[tuple[str, ...], dict[str, Any]]]] = {}
        for key_path, node in schema.keys():
            sections.setdefault(key_path[0], []).append((key_path, node))
        scalars = []
        for top, entries in sections.items():
            node = schema.resolve(entries[0][1])
            if len(entries) == 1 and node.get("type") != "object":
                scalars.append(entries[0])
                continue
            if scalars:
                lines += self._table(schema, scalars, which)
                scalars = []
            lines += [f".. _{which}-{top}:", ""]
            lines += _heading(f"``{top}``", "-")
            lines += self._table(schema, entries, which)
        if scalars:
            lines += self._table(schema, scalars, which)
        return _parse_rst(self, lines)

    def _table(self, schema: _Schema, entries: list, which: str) -> list[str]:
        rows = []
        for key_path, raw in entries:
            node = schema.resolve(raw)
            description = node.get("description", "")
            if not description:
                logger.warning("%s schema: key %s has no description", which,
                               _dotted(key_path), location=self.get_location())
            default = _literal(node["default"]) if "default" in node else ""
            rows.append([
                f"``{_dotted(key_path)}``",
                schema.type_of(raw),
                default,
                _rst_escape(units_of(str(description))),
                _rst_escape(description),
            ])
        return _list_table(["key", "type", "default", "units", "description"], rows,
                           "22 18 12 6 42")


# ------------------------------------------------------------------ command line


def _subparsers(parser: argparse.ArgumentParser) -> argparse._SubParsersAction | None:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return action
    return None


def _flag_rows(cmd: str, parser: argparse.ArgumentParser,
               location: Any) -> list[list[str]]:
    rows = []
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction | argparse._SubParsersAction):
            continue
        if action.help == argparse.SUPPRESS:
            continue
        if not action.help:
            logger.warning("ssw %s: %s has no help text", cmd,
                           "/".join(action.option_strings) or action.dest, location=location)
        if action.option_strings:
            names = ", ".join(action.option_strings)
            if action.nargs != 0:
                metavar = action.metavar or action.dest.upper()
                names += f" {metavar if isinstance(metavar, str) else ' '.join(metavar)}"
        else:
            names = str(action.metavar or action.dest)
        default = ""
        if action.default not in (None, argparse.SUPPRESS, False) and action.nargs != 0:
            default = f"``{action.default!r}``"
        help_text = _rst_escape(action.help or "")
        if "%(" in help_text:
            help_text = help_text.replace("%(default)s", str(action.default))
        if action.choices is not None and not isinstance(action.choices, dict):
            help_text += " (choices: " + ", ".join(f"``{c}``" for c in action.choices) + ")"
        if action.required and action.option_strings:
            help_text = "**required.** " + help_text
        rows.append([f"``{names}``", default, help_text])
    return rows


class CliReference(SphinxDirective):
    """``.. ssw-cli-reference::``: every subcommand of ``ssw`` from its argparse parser."""

    def run(self) -> list[nodes.Node]:
        from ssw.cli import build_parser

        # A flag's choices and defaults may come from anywhere in the package (registries,
        # settings): the page is rebuilt when any of its files changes.
        files = _package_files()
        for path in files:
            self.env.note_dependency(path)
        # ... and read again when a file is added or removed (_outdated)
        self.env.domaindata.setdefault("ssw_cli_pages", {})[self.env.docname] = files
        parser = build_parser()
        lines = ["Generated from ``ssw.cli.build_parser()`` when these pages are built.", ""]
        lines += ["::", ""] + ["   " + ln for ln in parser.format_usage().splitlines()] + [""]
        lines += _list_table(["flag", "default", "what"],
                             _flag_rows("", parser, self.get_location()), "30 15 55")
        lines += self._commands(parser, "ssw", "-")
        return _parse_rst(self, lines)

    def _commands(self, parser: argparse.ArgumentParser, prefix: str,
                  level: str) -> list[str]:
        sub = _subparsers(parser)
        if sub is None:
            return []
        helps = {a.dest: a.help for a in sub._choices_actions}
        lines: list[str] = []
        for name, child in sub.choices.items():
            cmd = f"{prefix} {name}"
            summary = helps.get(name) or ""
            if not summary:
                logger.warning("%s has no help text (add_parser(..., help=...))", cmd,
                               location=self.get_location())
            lines += [f".. _cli-{cmd.replace(' ', '-')}:", ""]
            lines += _heading(f"``{cmd}``", level)
            lines += [_rst_escape(summary), ""]
            if child.description and child.description != summary:
                lines += [_rst_escape(child.description), ""]
            lines += ["::", ""] + ["   " + ln for ln in child.format_usage().splitlines()]
            lines.append("")
            rows = _flag_rows(cmd.removeprefix("ssw "), child, self.get_location())
            if rows:
                lines += _list_table(["flag", "default", "what"], rows, "30 15 55")
            lines += self._commands(child, cmd, "^" if level == "-" else '"')
        return lines


# ------------------------------------------------------------------ API


def _python(info: pkgutil.ModuleInfo) -> bool:
    """A Python module or package, not a compiled library (``ssw/chain/_step.c``'s, which
    :mod:`ssw.chain.kernel` loads through ctypes and documents)."""
    spec = info.module_finder.find_spec(info.name)
    origin = "" if spec is None or spec.origin is None else spec.origin
    return info.ispkg or origin.endswith(".py")


def ssw_modules() -> list[str]:
    """Every Python module of the ``ssw`` package (``__main__`` aside), sorted."""
    import ssw

    names = {"ssw"}
    for info in pkgutil.walk_packages(ssw.__path__, "ssw."):
        if not info.name.endswith("__main__") and _python(info):
            names.add(info.name)
    return sorted(names)


def api_modules(target: str) -> list[str]:
    """``target`` and, for a package, its modules (not its subpackages), sorted."""
    module = importlib.import_module(target)
    names = [target]
    if hasattr(module, "__path__"):
        names += sorted(
            f"{target}.{m.name}" for m in pkgutil.iter_modules(module.__path__)
            if m.name != "__main__" and not m.ispkg and _python(m)
        )
    return names


class ApiReference(SphinxDirective):
    """``.. ssw-api:: ssw.chain``: the package itself and its modules (subpackages have
    their own directive), each an ``automodule`` section with its documented members."""

    required_arguments = 1

    def run(self) -> list[nodes.Node]:
        target = self.arguments[0]
        names = api_modules(target)
        # the page is read again when its package gains or loses a module (_outdated)
        self.env.domaindata.setdefault("ssw_api_pages", {})[self.env.docname] = (target, names)
        documented = self.env.domaindata.setdefault("ssw_api", {})
        lines: list[str] = []
        for name in names:
            documented[name] = self.env.docname
            mod = importlib.import_module(name)
            if mod.__file__:
                self.env.note_dependency(mod.__file__)
            lines += _heading(f"``{name}``", "-")
            lines += [f".. automodule:: {name}", "   :members:", ""]
        return _parse_rst(self, lines)


def _check_api_coverage(app: Sphinx, env: Any) -> None:
    documented = env.domaindata.get("ssw_api", {})
    for name in ssw_modules():
        if name not in documented:
            logger.warning("module %s is in no ssw-api directive of the API pages", name,
                           type="ssw", subtype="api")


def _package_files() -> list[str]:
    return [str(p) for p in sorted((ROOT / "ssw").rglob("*.py"))]


def _outdated(app: Sphinx, env: Any, added: set[str], changed: set[str],
              removed: set[str]) -> list[str]:
    """Pages to read again although none of their files changed: an API page whose package
    gained or lost a module, the command-line page when a file of ``ssw`` came or went
    (Sphinx tracks the files a page names, not folders)."""
    pages = env.domaindata.get("ssw_api_pages", {})
    out = [doc for doc, (target, names) in pages.items() if api_modules(target) != names]
    files = _package_files()
    out += [doc for doc, known in env.domaindata.get("ssw_cli_pages", {}).items()
            if known != files]
    return out


def _purge(app: Sphinx, env: Any, docname: str) -> None:
    data = env.domaindata.get("ssw_api", {})
    for name in [n for n, d in data.items() if d == docname]:
        del data[name]
    env.domaindata.get("ssw_api_pages", {}).pop(docname, None)
    env.domaindata.get("ssw_cli_pages", {}).pop(docname, None)


def _merge(app: Sphinx, env: Any, docnames: Any, other: Any) -> None:
    for key in ("ssw_api", "ssw_api_pages", "ssw_cli_pages"):
        env.domaindata.setdefault(key, {}).update(other.domaindata.get(key, {}))


# ------------------------------------------------------------------ re-exported names


def _documented_in(module: Any, name: str) -> str | None:
    """The module (``module`` or one of its package's modules) whose source documents the
    data ``name`` (a ``#:`` comment), or None."""
    from sphinx.pycode import ModuleAnalyzer, PycodeError

    names = [module.__name__]
    if hasattr(module, "__path__"):
        names += api_modules(module.__name__)[1:]
    for m in names:
        try:
            docs = ModuleAnalyzer.for_module(m).find_attr_docs()
        except PycodeError:
            continue
        if ("", name) in docs and getattr(importlib.import_module(m), name, None) is \
                getattr(module, name, None):
            return m
    return None


def defining_target(target: str, context: str | None = None) -> str | None:
    """Where an object of ``ssw`` that a reference names through an import is documented:
    its defining module's dotted name (``ssw.validity.RULES``, re-exported by its package,
    is ``ssw.validity.checks.RULES``; a bare ``Validity`` referenced from a module that
    imports it is ``ssw.validity.checks.Validity``), or None.

    Parameters
    ----------
    target : str
        The reference's target.
    context : str or None
        The module the reference is written in (a bare name is looked up there).

    Returns
    -------
    str or None
        The dotted name of the definition (an attribute's path kept), or None when the
        target names no imported object of ``ssw``.
    """
    path = target if target.startswith("ssw.") or not context else f"{context}.{target}"
    parts = path.split(".")
    for i in range(len(parts) - 1, 0, -1):
        try:
            module = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        obj = getattr(module, parts[i], None)
        if obj is None:
            return None
        home = getattr(obj, "__module__", None) if callable(obj) else None
        if callable(obj) and home and home.startswith("ssw."):
            where = f"{home}.{getattr(obj, '__qualname__', parts[i])}"
        else:
            found = _documented_in(module, parts[i])
            if found is None:
                return None
            where = f"{found}.{parts[i]}"
        return ".".join([where, *parts[i + 1:]])
    return None


def _resolve_reexport(app: Sphinx, env: Any, node: Any, contnode: Any) -> Any:
    """A Python reference Sphinx could not resolve, to where its object is documented
    (:func:`defining_target`), or None (the reference stays missing)."""
    if node.get("refdomain") != "py" or node.get("reftype") == "mod":
        return None
    target = node.get("reftarget", "")
    context = node.get("py:module")
    if not (target.startswith("ssw.") or (context or "").startswith("ssw.")):
        return None
    try:
        where = defining_target(target, context)
    except Exception:  # an import the build cannot make: the reference stays missing
        return None
    if where is None or where == target:
        return None
    return env.get_domain("py").resolve_xref(env, node["refdoc"], app.builder,
                                             node["reftype"], where, node, contnode)


# ------------------------------------------------------------------ docstrings


_SECTIONS = ("Parameters", "Other Parameters")


def parameter_entry_faults(lines: list[str]) -> list[str]:
    """What breaks the rule of one parameter per entry in a docstring's ``Parameters`` and
    ``Other Parameters`` sections (an entry ``a, b : float``), or numpydoc's own parse
    error, each as a sentence; empty when the docstring keeps the rule.

    Parameters
    ----------
    lines : list of str
        The docstring's lines, as autodoc hands them on (before numpydoc rewrites them).

    Returns
    -------
    list of str
        The faults.
    """
    from numpydoc.docscrape import NumpyDocString

    try:
        doc = NumpyDocString("\n".join(lines))
    except Exception as exc:  # numpydoc's own parse error, reported as such
        return [f"numpydoc cannot parse the docstring: {exc}"]
    return [f"{section} entry {param.name!r} names several parameters (one per entry)"
            for section in _SECTIONS for param in doc[section] if "," in param.name]


def _check_one_parameter_per_entry(app: Sphinx, what: str, name: str, obj: Any,
                                   options: Any, lines: list[str]) -> None:
    """Warn on what :func:`parameter_entry_faults` finds in a function's, method's or
    class's docstring. Runs before numpydoc rewrites the docstring."""
    if what not in {"function", "method", "class"}:
        return
    for fault in parameter_entry_faults(lines):
        logger.warning("%s: %s", name, fault, type="ssw", subtype="docstring")


# ------------------------------------------------------------------ numpydoc's template


@functools.cache
def _numpydoc_template(builder: Any) -> Any:
    """numpydoc's docstring template, loaded as numpydoc loads it (through the builder's
    template loader when there is a builder, so a project template still overrides it), once
    per builder."""
    import os

    from jinja2 import FileSystemLoader
    from jinja2.sandbox import SandboxedEnvironment
    from numpydoc import docscrape_sphinx
    from sphinx.jinja2glue import BuiltinTemplateLoader

    dirs = [os.path.join(os.path.dirname(docscrape_sphinx.__file__), "templates")]
    if builder is not None:
        loader: Any = BuiltinTemplateLoader()
        loader.init(builder, dirs=dirs)
    else:
        loader = FileSystemLoader(dirs)
    return SandboxedEnvironment(loader=loader).get_template("numpydoc_docstring.rst")


def _numpydoc_doc_object(obj: Any, what: str | None = None, doc: str | None = None,
                         config: dict[str, Any] | None = None, builder: Any = None) -> Any:
    """``numpydoc.docscrape_sphinx.get_doc_object`` with the template compiled once per
    builder: numpydoc 1.x compiles it anew for every docstring and signature it rewrites
    (some 3700 compiles, a tenth of the site's build). The rendered text is the same."""
    from numpydoc import docscrape_sphinx as sphinx_doc

    config = {} if config is None else config
    config["template"] = _numpydoc_template(builder)
    return sphinx_doc.get_doc_object_orig(
        obj, what=what, doc=doc, config=config, class_doc=sphinx_doc.SphinxClassDoc,
        func_doc=sphinx_doc.SphinxFunctionDoc, obj_doc=sphinx_doc.SphinxObjDoc)


def setup(app: Sphinx) -> dict[str, Any]:
    # numpydoc's own hook for its doc objects (the get_doc_object_ argument of its setup,
    # which sets this module global): the same objects, the template compiled once
    import numpydoc.numpydoc

    numpydoc.numpydoc.get_doc_object = _numpydoc_doc_object
    app.add_directive("ssw-config-reference", ConfigReference)
    app.add_directive("ssw-cli-reference", CliReference)
    app.add_directive("ssw-api", ApiReference)
    app.connect("env-check-consistency", _check_api_coverage)
    app.connect("env-get-outdated", _outdated)
    app.connect("env-purge-doc", _purge)
    app.connect("env-merge-info", _merge)
    app.connect("missing-reference", _resolve_reexport)
    # numpydoc rewrites the docstring at priority 500: check it before.
    app.connect("autodoc-process-docstring", _check_one_parameter_per_entry, priority=400)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True,
            "env_version": 1}
