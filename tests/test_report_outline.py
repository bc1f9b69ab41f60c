"""The study report's outline: one category per stage the study produces, numbered in
order, and an introduction that lists the same categories (workflow/report/workflow.rst).
The browser tests (tests/test_report_browser.py, tests/test_workflow.py) check the rendered
report against the same function."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from ssw.config import load_config
from ssw.workflow import REPORT_STAGES, report_categories, report_stages

ROOT = Path(__file__).resolve().parent.parent


@pytest.mark.parametrize(("config", "shown"), [
    # the thesis study: no survey, a plate design -> the design is 5 (it was "6." after a
    # missing "5."), as a report of that study once showed
    ("config.yaml", ["1. Contact (Stage I)", "2. Fits (Stage I)", "3. Chain (Stage II)",
                     "4. Validation (Stage III)", "5. Plate design"]),
    ("ci.yaml", ["1. Contact (Stage I)", "2. Fits (Stage I)", "3. Chain (Stage II)",
                 "4. Validation (Stage III)", "5. Survey"]),
    # the field example: no FEM sets, so no contact figure and no fits
    ("survey_example.yaml", ["1. Chain (Stage II)", "2. Validation (Stage III)",
                             "3. Survey"]),
])
def test_categories_are_numbered_over_the_stages_the_study_produces(config, shown):
    cfg = load_config(ROOT / "config" / config)
    cats = report_categories(cfg)
    assert [cats[st] for st in report_stages(cfg)] == shown
    assert set(cats) == set(REPORT_STAGES)


def test_the_introduction_describes_every_stage_and_lists_the_report_categories():
    text = (ROOT / "workflow" / "report" / "workflow.rst").read_text()
    about = text.split("{%- set about = {", 1)[1].split("} %}", 1)[0]
    described = re.findall(r'^\s*"([^"]+)":', about, re.MULTILINE)
    assert described == list(REPORT_STAGES.values())
    # the list is the report's own categories, not a fixed text
    assert "{% for cat, _ in categories|dictsort %}" in text


def test_no_rule_names_a_numbered_category():
    """Every report(...) category comes from REPORT_CATEGORIES (common.smk): a hard-coded
    "6. Plate design" is how the outline drifted from the study."""
    for smk in (ROOT / "workflow" / "rules").glob("*.smk"):
        assert not re.search(r'category\s*=\s*"\d', smk.read_text()), smk.name
