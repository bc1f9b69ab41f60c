"""The documentation site builds with no warning, and the README's links lead somewhere.

``make docs`` runs Sphinx with ``-W --keep-going -n``: a warning of docutils, MyST, autodoc
or numpydoc (its checks of the Parameters sections: docs/CONTRACTS.md, "Docstrings"), a
cross-reference to a missing object or page, a schema key without a description, a command
or flag without help, or a module of ``ssw`` on no API page fails the build.

The build keeps its doctrees in ``build/docs-cache/<key>`` (git-ignored; the key hashes the
Sphinx configuration, its extension and the package versions) and rewrites every page
(``-a``), so a build after a small edit rereads only what the edit touched (pages depend on
their Markdown, the schemas, the modules they document) while every cross-reference is
resolved again. A failed build deletes the cache, so the next one starts from nothing and
reports every warning again.

The build runs in ``make test-long``; ``make test`` checks its docstring and API-page rules
on the same objects without Sphinx, in seconds.
"""

from __future__ import annotations

import hashlib
import re
import shlex
import shutil
import subprocess
import sys
from importlib import metadata
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "docs" / "_ext"))


def _cache_key() -> str:
    h = hashlib.sha256()
    for path in [ROOT / "docs" / "conf.py", *sorted((ROOT / "docs" / "_ext").glob("*.py"))]:
        h.update(path.read_bytes())
    for dist in ("sphinx", "docutils", "myst-parser", "numpydoc", "furo"):
        h.update(f"{dist}={metadata.version(dist)}".encode())
    return h.hexdigest()[:16]


@pytest.mark.long
def test_make_docs_builds_without_warnings(tmp_path):
    """``make docs`` (the README's command) with warnings as errors: in ``make test-long``
    (the site from nothing, its figures made by small runs: 97 s of a 2-core CI run); the
    default run checks its docstring and API rules without Sphinx (below)."""
    cache = ROOT / "build" / "docs-cache" / _cache_key()
    cache.mkdir(parents=True, exist_ok=True)
    r = subprocess.run(
        ["make", "-o", "setup", "docs", f"VENV={Path(sys.prefix)}",
         f"DOCS_OUT={tmp_path / 'html'}", f"SPHINXOPTS=-a -d {shlex.quote(str(cache))}"],
        cwd=ROOT, capture_output=True, text=True, timeout=900,
    )
    if r.returncode != 0:
        shutil.rmtree(cache, ignore_errors=True)
    assert r.returncode == 0, f"make docs failed:\n{r.stdout[-3000:]}\n{r.stderr[-6000:]}"
    html = tmp_path / "html"
    for page in ["index", "study", "instrument", "performance", "guarantees", "cluster",
                 "reference/configuration", "reference/device", "reference/cli", "setup",
                 "api/ssw.contact"]:
        assert (html / f"{page}.html").is_file(), page
    # the generated references hold what they are generated from
    config_ref = (html / "reference" / "configuration.html").read_text()
    assert "contact.mesh_growth" in config_ref and "chain.wall_law" in config_ref
    cli_ref = (html / "reference" / "cli.html").read_text()
    assert "--reference-recording" in cli_ref and "ssw-bench-chain" in cli_ref
    _assert_generated_figures(html)


#: The pages that open with a figure made by the build (docs/_ext/ssw_figures.py).
FIGURE_PAGES = ["study", *(f"physics/{p.stem}" for p in sorted(
    (ROOT / "docs" / "physics").glob("*.md")))]


def _assert_generated_figures(html: Path) -> None:
    """The study page and each physics page hold an <img> of a PNG the build made (its
    ``ssw-generated`` class, a non-empty PNG in the site's ``_images``), before any other
    content of the page."""
    for page in FIGURE_PAGES:
        text = (html / f"{page}.html").read_text()
        imgs = re.findall(r"<img [^>]*>", text)
        made = [i for i in imgs if "ssw-generated" in i]
        assert made, f"{page}: no figure made by the build"
        src = re.search(r'src="([^"]+)"', made[0]).group(1)
        png = (html / page).parent / src
        assert png.is_file() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", (page, src)
        body = text[text.index("<h1"):]
        assert body.index(made[0]) < body.index("<p>"), f"{page}: the figure does not open it"


# ------------------------------------------------------------- the build's rules, without it


def _build_settings() -> dict:
    """docs/conf.py's values, as Sphinx reads them."""
    import runpy

    return runpy.run_path(str(ROOT / "docs" / "conf.py"))


def _documented(module) -> list[tuple[str, object, str]]:
    """What ``automodule`` with ``:members:`` (docs/conf.py's ``autodoc_default_options``)
    renders of ``module``: its public functions and classes (those of ``__all__`` when it
    has one) defined in it and holding a docstring of their own, and the classes' public
    methods and properties with one, as ``(name, object, autodoc's kind)``."""
    import inspect

    names = getattr(module, "__all__", None) or [n for n in vars(module)
                                                  if not n.startswith("_")]
    out: list[tuple[str, object, str]] = []
    for name in names:
        obj = getattr(module, name, None)
        if (not (inspect.isfunction(obj) or inspect.isclass(obj))
                or obj.__module__ != module.__name__):
            continue
        own = obj.__doc__ if inspect.isfunction(obj) else vars(obj).get("__doc__")
        if not own:
            continue
        full = f"{module.__name__}.{name}"
        out.append((full, obj, "function" if inspect.isfunction(obj) else "class"))
        for attr, raw in (vars(obj).items() if inspect.isclass(obj) else ()):
            fn = raw.__func__ if isinstance(raw, (staticmethod, classmethod)) else raw
            if attr.startswith("_") or not getattr(fn, "__doc__", None):
                continue
            if isinstance(raw, property):
                out.append((f"{full}.{attr}", raw, "attribute"))
            elif inspect.isfunction(fn):
                out.append((f"{full}.{attr}", getattr(obj, attr), "method"))
    return out


def _docstring_faults(name: str, obj: object, what: str, checks: set[str]) -> list[str]:
    """The faults the build reports in one docstring: numpydoc's validation codes of
    ``checks`` (as numpydoc's Sphinx hook runs it) and ssw_docs' one parameter per entry."""
    import inspect

    from numpydoc.docscrape_sphinx import get_doc_object
    from numpydoc.validate import validate
    from ssw_docs import parameter_entry_faults

    text = inspect.getdoc(obj) or ""
    faults = [] if what == "attribute" else parameter_entry_faults(text.splitlines())
    report = validate(get_doc_object(obj, what, text))
    faults += [f"{code}: {msg}" for code, msg in report["errors"] if code in checks]
    return [f"{name}: {f}" for f in faults]


def test_every_rendered_docstring_passes_the_builds_numpydoc_checks():
    """The docstring rules of ``make docs`` (docs/conf.py's ``numpydoc_validation_checks``
    and exclusions, one parameter per entry) on every docstring the API pages render,
    without Sphinx: seconds, where the whole build (``make test-long``) takes minutes."""
    import importlib

    from ssw_docs import ssw_modules

    conf = _build_settings()
    checks = set(conf["numpydoc_validation_checks"])
    excluded = re.compile("|".join(conf["numpydoc_validation_exclude"]))
    faults: list[str] = []
    seen = 0
    for module in ssw_modules():
        for name, obj, what in _documented(importlib.import_module(module)):
            if not excluded.search(name):
                seen += 1
                faults += _docstring_faults(name, obj, what, checks)
    assert seen > 1000, f"only {seen} docstrings found: the walk lost the package"
    assert not faults, "\n".join(faults[:30])


def test_the_docstring_check_finds_what_the_build_rejects():
    """The check above fails on the faults the build warns on: a parameter left out (PR01),
    one the signature lacks (PR02), two in one entry, no Returns (RT01)."""
    def area(width: float, height: float, scale: float) -> float:
        """Area of a rectangle.

        Parameters
        ----------
        width, height : float
            Its sides (m).
        depth : float
            Not a parameter.
        """
        return width * height * scale

    faults = "\n".join(_docstring_faults("area", area, "function",
                                         set(_build_settings()["numpydoc_validation_checks"])))
    for expected in ("PR01", "PR02", "RT01", "names several parameters"):
        assert expected in faults, (expected, faults)


def test_every_module_is_on_an_api_page():
    """Each module of ``ssw`` is in the ``ssw-api`` directive of one API page (the build's
    ``env-check-consistency`` rule, without the build)."""
    from ssw_docs import api_modules, ssw_modules

    targets = [m.group(1) for page in sorted((ROOT / "docs" / "api").glob("*.rst"))
               for m in re.finditer(r"^\.\. ssw-api:: (\S+)$", page.read_text(),
                                    re.MULTILINE)]
    assert targets
    on_pages = {name for target in targets for name in api_modules(target)}
    assert set(ssw_modules()) <= on_pages, sorted(set(ssw_modules()) - on_pages)


# ---------------------------------------------------------------------------- README links


def _slug(heading: str) -> str:
    """GitHub's anchor of a Markdown heading (lower case, punctuation dropped, spaces to
    hyphens), as MyST's ``myst_heading_anchors`` makes it too."""
    text = re.sub(r"[`*_]", "", heading.strip().lower())
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def _anchors(path: Path) -> set[str]:
    text = path.read_text()
    if path.suffix == ".md":
        return {_slug(m.group(1)) for m in re.finditer(r"^#{1,6} (.+)$", text, re.MULTILINE)}
    return set()


@pytest.mark.parametrize("page", ["README.md", "config/README.md"])
def test_readme_links_resolve(page):
    """Every relative link of the front pages names a file that exists, and an anchor into
    a Markdown page names one of its headings."""
    path = ROOT / page
    text = re.sub(r"```.*?```", "", path.read_text(), flags=re.DOTALL)
    links = re.findall(r"\]\(([^)\s]+)\)", text)
    assert links, page
    for link in links:
        if re.match(r"[a-z]+://", link):
            continue
        target, _, anchor = link.partition("#")
        dest = (path.parent / target).resolve() if target else path
        assert dest.exists(), f"{page}: link to a missing file: {link}"
        if anchor and dest.suffix == ".md":
            assert anchor in _anchors(dest), f"{page}: no heading for #{anchor} in {target}"


def test_readme_is_a_short_page():
    """The front page stays a page a newcomer reads in five minutes (the rest is the site)."""
    assert len((ROOT / "README.md").read_text().splitlines()) <= 200


# ---------------------------------------------------------------------------- generators


def test_units_are_read_off_the_schema_descriptions():
    from ssw_docs import units_of

    assert units_of("rigid indenter radius, m") == "m"
    assert units_of("J, the energy whose Hertz indentation a curve reaches") == "J"
    assert units_of("density of the tested medium, kg/m^3, for wall_dynamics reduced") \
        == "kg/m^3"
    assert units_of("sample rate, S/s (NI 9234 - 51200/n, n = 1..31)") == "S/s"
    assert units_of("number of equal indentation increments") == ""
    assert units_of("A study of the device") == ""


def test_every_schema_key_is_in_the_configuration_reference():
    """The generated reference walks every key of both schemas, nested ones included."""
    import yaml
    from ssw_docs import SCHEMAS, _Schema

    keys = {".".join(p) for p, _ in
            _Schema(yaml.safe_load(SCHEMAS["config"].read_text())).keys()}
    for key in ("contact.mesh_growth", "sets.NAME.sample.base_nu", "survey.points.[].target_E",
                "design.soils.NAME.soil_E", "validation.samples.[].tof_published",
                "daq.simulation.noise_rms", "chain.sweep.soil_E"):
        assert key in keys, key
    device = {".".join(p) for p, _ in
              _Schema(yaml.safe_load(SCHEMAS["device"].read_text())).keys()}
    assert {"chain.beads", "striker.velocity", "repeatability.tof_std"} <= device
