"""The Snakemake report in a real headless browser (Debian's chromium through selenium).

A tiny workflow built like the study's (figures made by ssw.plotting, the stage's tables
rendered by ``ssw report``, every caption of workflow/report/, the study's categories) is
run, its report built with ``snakemake --report`` (with the study's stylesheet), and opened
in chromium: the outline (the RESULTS menu and the introduction's list) must be the thesis
study's stages (ssw.workflow.report_categories), the introduction must start at the top of
the window, every result of every category is viewed; every image must have loaded
(naturalWidth > 0), every table page must open, and the screenshots must not be blank.
:func:`check_report` is usable on any Snakemake report (e.g. the CI study's).
"""

from __future__ import annotations

import os
import shlex
import shutil
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))
CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run",
         "--window-size=1280,900")


def _browser():
    """A headless chromium (fresh profile) or a skip/fail saying what is missing."""
    missing = [p for p in (CHROMIUM, CHROMEDRIVER) if not Path(p).exists()]
    if missing:
        msg = (f"{missing} missing: Debian's chromium and chromium-driver (scripts/setup.sh "
               "installs them as root)")
        if os.environ.get("CI") == "true":
            pytest.fail(msg)
        pytest.skip(msg)
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service

    opts = Options()
    opts.binary_location = CHROMIUM
    profile = tempfile.mkdtemp(prefix="ssw-chromium-")
    for flag in (*FLAGS, f"--user-data-dir={profile}"):
        opts.add_argument(flag)
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=opts)
    driver.set_page_load_timeout(30)
    return driver, profile


def _not_blank(png: bytes) -> bool:
    """More than a handful of colours and some contrast in a screenshot."""
    import io

    from matplotlib import image

    px = image.imread(io.BytesIO(png), format="png")[..., :3]
    colours = np.unique((px.reshape(-1, 3) * 255).astype(np.uint8), axis=0).shape[0]
    return colours > 16 and float(px.std()) > 0.05


def _wait(driver, script, timeout=10.0):
    from selenium.webdriver.support.ui import WebDriverWait

    return WebDriverWait(driver, timeout).until(lambda d: d.execute_script(script))


LOAD_ALL = """
const done = arguments[arguments.length - 1];
const entries = Object.entries(results).filter(([k, v]) => v.mime_type === "image/png");
Promise.all(entries.map(([path, v]) => new Promise(ok => {
    const img = new Image();
    img.onload = () => ok([path, img.naturalWidth]);
    img.onerror = () => ok([path, 0]);
    img.src = v.data_uri;
}))).then(done);
"""


def check_report(report: Path, shots: Path) -> dict:
    """Open a Snakemake report in headless chromium; return what it shows.

    * ``categories``: the report's categories that its RESULTS menu shows;
    * ``intro``: the categories the introduction lists (its links), each checked to open
      its category when clicked;
    * ``band``: px between the top of the window and the introduction's first line;
    * ``images``: ``(path, naturalWidth)`` of every PNG result, each decoded by the browser;
    * ``viewed``: ``(category, naturalWidth)`` of the first figure of each category, opened
      through the report's own menu and view button, with a screenshot in ``shots``;
    * ``pages``: categories whose table page (HTML result) opened in the viewer;
    * ``blank``: screenshots without content.
    """
    from selenium.webdriver.common.by import By

    driver, profile = _browser()
    seen: dict = {"categories": [], "intro": [], "band": None, "images": [], "viewed": [],
                  "pages": [], "blank": []}
    ready = "return document.body.innerText.includes('RESULTS')"
    try:
        url = report.resolve().as_uri()
        driver.get(url)
        _wait(driver, ready)
        menu = driver.execute_script("return categories")  # the report's own index
        seen["categories"] = [c for c in sorted(menu)
                              if driver.find_elements(By.LINK_TEXT, c)]
        seen["band"] = driver.execute_script(
            "const d = document.querySelector('.prose .document');"
            "return d ? d.firstElementChild.getBoundingClientRect().top : null")
        (shots / "intro.png").write_bytes(driver.get_screenshot_as_png())
        seen["intro"] = driver.execute_script(
            "return Array.from(document.querySelectorAll('.prose .document a'))"
            ".filter(a => a.href.startsWith('javascript:app.showCategory'))"
            ".map(a => a.innerText)")
        for name in seen["intro"]:  # each link opens its category: the menu leaves the
            # index (GENERAL ...) for the category, named in its breadcrumbs
            driver.find_element(By.CSS_SELECTOR, ".prose .document").find_element(
                By.LINK_TEXT, name).click()
            _wait(driver, "return !document.body.innerText.includes('GENERAL') && "
                  "Array.from(document.querySelectorAll('a')).filter("
                  f"a => a.innerText.trim() === {name!r}).length >= 2")
            driver.get(url)
            _wait(driver, ready)
        driver.set_script_timeout(30)
        seen["images"] = [tuple(x) for x in driver.execute_async_script(LOAD_ALL)]
        for ci, cat in enumerate(menu):
            for sub in menu[cat]:
                driver.find_element(By.LINK_TEXT, cat).click()
                links = driver.find_elements(By.LINK_TEXT, sub)
                if links:
                    links[0].click()
                driver.find_elements(By.CSS_SELECTOR, "a[iconname=eye]")[0].click()
                _wait(driver, "return document.querySelector("
                      "'img[src^=\"data:image/png\"], iframe[src^=\"data:text/html\"]')"
                      " !== null && Array.from(document.images).every(i => i.complete)")
                widths = driver.execute_script(
                    "return Array.from(document.images).filter(i => i.src.startsWith("
                    "'data:image/png')).map(i => i.naturalWidth)")
                seen["viewed"] += [(cat, w) for w in widths]
                if driver.find_elements(By.CSS_SELECTOR, "iframe[src^='data:text/html']"):
                    seen["pages"].append(cat)
                png = driver.get_screenshot_as_png()
                shot = shots / f"category{ci}_{sub.lower()}.png"
                shot.write_bytes(png)
                if not _not_blank(png):
                    seen["blank"].append(shot.name)
                driver.find_element(By.LINK_TEXT, "Results").click()  # back to the menu
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)
    return seen


TINY = """
import os
import shlex
import sys
sys.path.insert(0, "{root}")
from ssw.config import load_config
from ssw.workflow import report_categories
REPORT = os.path.join("{root}", "workflow", "report")
# the thesis study's outline (config/config.yaml: no survey, a plate design)
CATEGORIES = report_categories(load_config(os.path.join("{root}", "config", "config.yaml")))


PLOT = "{python} " + shlex.quote(os.path.join(workflow.basedir, "plot.py"))


report: os.path.join(REPORT, "workflow.rst")

rule all:
    input:
        "results/contact/figures/fig5_materials.png",
        "results/fit/figures/set1_curves.png",
        "results/fit/figures/set1_deviation.png",
        "results/fit/figures/set3_k_vs_E.png",
        "results/chain/figures/fig8_tof_vs_E.png",
        "results/validation/fig9_tof_scatter.png",
        "results/validation/fig10_tof_validation.png",
        "results/report/tables_validation.html",
        "results/design/figures/thesis_pareto.png",

rule contact_figure:
    output:
        report("results/contact/figures/{{figure}}.png", category=CATEGORIES["contact"],
               subcategory="Figures", caption=os.path.join(REPORT, "contact_figure.rst")),
    shell:
        PLOT + " {{output}} {{wildcards.figure}}"

rule fit_figure_curves:
    output:
        report("results/fit/figures/{{set}}_curves.png", category=CATEGORIES["fit"],
               subcategory="Figures", caption=os.path.join(REPORT, "fit_curves.rst")),
    shell:
        PLOT + " {{output}} {{wildcards.set}}"

rule fit_figure_deviation:
    output:
        report("results/fit/figures/{{set}}_deviation.png", category=CATEGORIES["fit"],
               subcategory="Figures", caption=os.path.join(REPORT, "fit_deviation.rst")),
    shell:
        PLOT + " {{output}} {{wildcards.set}}"

rule fit_figure_k:
    output:
        report("results/fit/figures/{{set}}_k_vs_E.png", category=CATEGORIES["fit"],
               subcategory="Figures", caption=os.path.join(REPORT, "fit_k_vs_E.rst")),
    shell:
        PLOT + " {{output}} {{wildcards.set}}"

rule tof_sweep:
    output:
        report("results/chain/figures/fig8_tof_vs_E.png", category=CATEGORIES["chain"],
               subcategory="Figures", caption=os.path.join(REPORT, "fig8.rst")),
    shell:
        PLOT + " {{output}} 'fig 8'"

rule validation:
    output:
        csv="results/validation/table2_tof.csv",
        fig9=report("results/validation/fig9_tof_scatter.png",
                    category=CATEGORIES["validation"], subcategory="Figures",
                    caption=os.path.join(REPORT, "fig9.rst")),
        fig10=report("results/validation/fig10_tof_validation.png",
                     category=CATEGORIES["validation"], subcategory="Figures",
                     caption=os.path.join(REPORT, "fig10.rst")),
    shell:
        "printf 'sample,E,tof_sim,tof\\\\nPCF08,3.8e7,0.0018,0.00178\\\\n' > {{output.csv}}; "
        + PLOT + " {{output.fig9}} 'fig 9'; " + PLOT + " {{output.fig10}} 'fig 10'"


rule design_figure:
    output:
        report("results/design/figures/{{soil}}_pareto.png", category=CATEGORIES["design"],
               subcategory="Figures", caption=os.path.join(REPORT, "design_pareto.rst")),
    shell:
        PLOT + " {{output}} 'pareto'"


rule report_tables:
    input:
        tables=["results/validation/table2_tof.csv"],
        captions=os.path.join(REPORT, "captions.yaml"),
    output:
        report("results/report/tables_{{stage}}.html", caption=os.path.join(REPORT, "tables.rst"),
               category=lambda wc: CATEGORIES[wc.stage], subcategory="Tables")
    shell:
        "{python} -m ssw report {{input.tables:q}} --captions {{input.captions:q}} "
        "--output {{output:q}}"
"""


PLOT_SCRIPT = """
import struct
import sys
import zlib

# a 320 x 200 RGB PNG (a colour ramp with a diagonal line) without matplotlib: fast jobs
w, h = 320, 200
rows = b"".join(b"\\x00" + bytes(c for x in range(w) for c in (
    (0, 0, 0) if abs(x * h - y * w) < w else (x * 255 // w, y * 255 // h, 128)))
    for y in range(h))


def chunk(kind, data):
    return (struct.pack(">I", len(data)) + kind + data
            + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))


png = (b"\\x89PNG\\r\\n\\x1a\\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
       + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))
open(sys.argv[1], "wb").write(png)
"""


@pytest.fixture(scope="module")
def tiny_report(tmp_path_factory):
    work = tmp_path_factory.mktemp("report")
    (work / "plot.py").write_text(PLOT_SCRIPT)
    (work / "Snakefile").write_text(
        textwrap.dedent(TINY.format(root=ROOT, python=shlex.quote(sys.executable))))
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    css = str(ROOT / "workflow" / "report" / "report.css")
    for args in (["--cores", "2"], ["--report", "report.html", "--report-stylesheet", css]):
        r = subprocess.run([SNAKEMAKE, *args], cwd=work, capture_output=True, text=True,
                           env=env, timeout=300)
        assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    return work


def test_every_caption_renders_into_the_report(tiny_report):
    text = (tiny_report / "report.html").read_text()
    assert "Error loading caption" not in text and "System Message" not in text
    results = text.split('<script id="results">', 1)[1].split("</script>", 1)[0]
    for phrase in ("thesis&#x27;s", "Fig 8", "Fig 10", "Fig 7", "fig5_materials", "table2_tof.csv"):
        assert phrase in results or phrase.replace("&#x27;", "'") in results, phrase


# long: chromium over the whole report; the default run keeps the same report's build and
# its captions and results (test_every_caption_renders_into_the_report) and the outline's
# categories and introduction (tests/test_report_outline.py)
@pytest.mark.long
def test_report_renders_in_a_headless_browser(tiny_report):
    from ssw.config import load_config
    from ssw.workflow import report_categories, report_stages

    seen = check_report(tiny_report / "report.html", tiny_report)
    cfg = load_config(ROOT / "config" / "config.yaml")
    outline = [report_categories(cfg)[st] for st in report_stages(cfg)]
    assert outline[-1] == "5. Plate design"
    assert seen["categories"] == outline, seen  # the menu: the study's stages
    assert seen["intro"] == outline, seen       # the introduction: the same list
    assert seen["band"] is not None and seen["band"] < 60, seen  # no blank band above
    assert len(seen["images"]) == 8 and all(w > 0 for _, w in seen["images"]), seen
    assert [c for c, _ in seen["viewed"]] == seen["categories"], seen  # a figure in each
    assert all(w > 0 for _, w in seen["viewed"]), seen
    assert seen["pages"] == ["4. Validation (Stage III)"], seen  # the tables page opens
    assert not seen["blank"], seen["blank"]
