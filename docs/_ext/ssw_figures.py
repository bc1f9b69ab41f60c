"""Sphinx extension: the figures of the site, made when it builds.

``{ssw-figure} NAME`` (a recipe of ``docs/figures/recipes.py``) places a figure drawn by
ssw's own plotting code: the study's PNG under ``results/`` when ``make study`` (or ``ssw
bench``) wrote it, else the PNG of a small run of the public command, made now and cached
in ``build/docs-figures/`` under a key of the recipe's command and ssw's source (a build after an
edit of the pages alone reuses it; an edit of ssw's code makes it again). The caption says
which of the two it is and the command. A command that fails is a warning, so
``sphinx-build -W`` fails.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

from docutils import nodes
from sphinx.application import Sphinx
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

logger = logging.getLogger(__name__)

ROOT = Path(__file__).resolve().parents[2]
CACHE = ROOT / "build" / "docs-figures"
sys.path.insert(0, str(ROOT / "docs" / "figures"))

from recipes import RECIPES, Recipe  # noqa: E402


def source_key() -> str:
    """A digest of ssw's source (``ssw/**/*.py``, ``*.c``, ``*.yaml``), computed once."""
    if not hasattr(source_key, "value"):
        h = hashlib.sha256()
        for path in sorted((ROOT / "ssw").rglob("*")):
            if path.suffix in {".py", ".c", ".yaml"} and "__pycache__" not in path.parts:
                h.update(path.relative_to(ROOT).as_posix().encode())
                h.update(path.read_bytes())
        source_key.value = h.hexdigest()[:16]  # type: ignore[attr-defined]
    return source_key.value  # type: ignore[attr-defined]


def _argv(recipe: Recipe, out: Path) -> list[str]:
    return [a.format(out=out, root=ROOT) for a in recipe.command]


def _shown(recipe: Recipe) -> str:
    """The small run's command as a reader types it (in the repository)."""
    words = [a.replace("{root}/", "").replace("{out}/", "").replace("{out}", "out")
             for a in recipe.command]
    return "ssw " + " ".join(words)


def make(name: str) -> tuple[Path, str]:
    """The PNG of figure ``name`` and where it came from (a sentence for the caption).

    Parameters
    ----------
    name : str
        A key of ``RECIPES``.

    Returns
    -------
    tuple of (Path, str)
        The PNG under ``build/docs-figures/`` and its provenance.
    """
    recipe = RECIPES[name]
    CACHE.mkdir(parents=True, exist_ok=True)
    result = ROOT / "results" / recipe.result if recipe.result else None
    if result is not None and result.is_file():
        data = result.read_bytes()
        png = CACHE / f"{name}-study-{hashlib.sha256(data).hexdigest()[:16]}.png"
        if not png.is_file():
            png.write_bytes(data)
        return png, f"From the study's results (`results/{recipe.result}`, `make study`)."
    key = hashlib.sha256(f"{recipe.command!r}{source_key()}".encode()).hexdigest()[:16]
    png = CACHE / f"{name}-{key}.png"
    said = (f"Made when this site was built, by a small run: `{_shown(recipe)}` "
            f"({recipe.small}); after `make study` the site shows the study's own figure.")
    if png.is_file():
        return png, said
    with tempfile.TemporaryDirectory(prefix=f"ssw-fig-{name}-") as tmp:
        out = Path(tmp)
        env = {**os.environ, "MPLBACKEND": "Agg", "SSW_WARM_START": "0"}
        r = subprocess.run([sys.executable, "-m", "ssw", *_argv(recipe, out)], cwd=tmp,
                           env=env, capture_output=True, text=True, timeout=600)
        made = out / recipe.output
        if r.returncode != 0 or not made.is_file():
            raise RuntimeError(f"`{_shown(recipe)}` exited {r.returncode} without "
                               f"{recipe.output}:\n{r.stderr[-2000:]}")
        part = png.with_suffix(".part")
        shutil.copyfile(made, part)
        part.replace(png)
    return png, said


class SswFigure(SphinxDirective):
    """``{ssw-figure} NAME``: the figure of recipe NAME with its caption and provenance."""

    required_arguments = 1

    def run(self) -> list[nodes.Node]:
        """The figure node (image and caption), or a warning when it cannot be made.

        Returns
        -------
        list of docutils.nodes.Node
            One figure, or nothing.
        """
        name = self.arguments[0]
        if name not in RECIPES:
            logger.warning("ssw-figure: no recipe %r (docs/figures/recipes.py)", name,
                           location=self.get_location())
            return []
        self.env.note_dependency(str(ROOT / "docs" / "figures" / "recipes.py"))
        try:
            png, said = make(name)
        except (RuntimeError, OSError, subprocess.TimeoutExpired) as exc:
            logger.warning("ssw-figure %s: %s", name, exc, location=self.get_location())
            return []
        srcdir = Path(self.env.srcdir)
        uri = "/" + os.path.relpath(png, srcdir).replace(os.sep, "/")
        figure = nodes.figure(classes=["ssw-figure"])
        figure += nodes.image(uri=uri, alt=RECIPES[name].caption, classes=["ssw-generated"])
        caption = nodes.caption()
        for i, part in enumerate(f"{RECIPES[name].caption} {said}".split("`")):
            caption += nodes.literal(part, part) if i % 2 else nodes.Text(part)
        figure += caption
        return [figure]


def _prefetch(app: Sphinx) -> None:
    """Make every figure a page names before the pages are read, as many at once as the
    machine has cores (the small runs are separate processes). A failure here is left to
    the page's directive, which tries again and warns."""
    from concurrent.futures import ThreadPoolExecutor

    def one(name: str) -> None:
        try:
            make(name)
        except (RuntimeError, OSError, subprocess.TimeoutExpired):
            pass

    with ThreadPoolExecutor(max_workers=max(1, os.cpu_count() or 1)) as pool:
        list(pool.map(one, RECIPES))


def setup(app: Sphinx) -> dict[str, Any]:
    """Register ``ssw-figure`` and the figures' making at the build's start."""
    app.add_directive("ssw-figure", SswFigure)
    app.connect("builder-inited", _prefetch)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
