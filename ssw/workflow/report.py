"""The study's report (Snakemake's ``--report``): its stages in order, each stage's
category and its tables' pages.
"""

from __future__ import annotations

from typing import Any

from ssw.workflow.jobs import RESULTS, one_soil_sets, survey_points

#: The study's stages in the report's order: results sub-folder -> the title of its category
#: (workflow/report/workflow.rst describes each title).
REPORT_STAGES: dict[str, str] = {
    "contact": "Contact (Stage I)",
    "fit": "Fits (Stage I)",
    "chain": "Chain (Stage II)",
    "validation": "Validation (Stage III)",
    "survey": "Survey",
    "design": "Plate design",
}


def report_stages(cfg: dict[str, Any]) -> list[str]:
    """The stages whose figures and tables a study's report shows, in report order.

    Parameters
    ----------
    cfg : dict[str, Any]
        The validated study config.

    Returns
    -------
    list[str]
        Keys of :data:`REPORT_STAGES`: ``contact`` when a set has one soil (its contact
        figure, rule ``fit_set``), ``fit`` when there are sets, ``chain`` and ``validation``
        always, ``survey`` when it has points, ``design`` when it has soil ranges.
    """
    shown = {
        "contact": bool(one_soil_sets(cfg)),
        "fit": bool(cfg.get("sets")),
        "chain": True,
        "validation": True,
        "survey": bool(survey_points(cfg)),
        "design": bool(cfg.get("design", {}).get("soils")),
    }
    return [stage for stage in REPORT_STAGES if shown[stage]]


def report_categories(cfg: dict[str, Any]) -> dict[str, str]:
    """Stage -> its category in the study's report: the stages the report shows numbered
    1, 2, ... in order (:func:`report_stages`); a stage it does not show keeps its bare
    title (no file of it reaches the report).

    Parameters
    ----------
    cfg : dict[str, Any]
        The validated study config.

    Returns
    -------
    dict[str, str]
        Every key of :data:`REPORT_STAGES`, e.g. ``{"design": "5. Plate design", ...}``.
    """
    numbered = {st: f"{i}. {REPORT_STAGES[st]}"
                for i, st in enumerate(report_stages(cfg), start=1)}
    return {st: numbered.get(st, title) for st, title in REPORT_STAGES.items()}


def report_tables(targets: list[Any], categories: dict[str, str], results: str = RESULTS
                  ) -> dict[str, list[str]]:
    """Stage -> its CSV tables among ``targets`` (a stage is a results sub-folder).

    Parameters
    ----------
    targets : list
        The report job's input files.
    categories : dict of str to str
        Stage -> its report category (only the keys are read).
    results : str
        The results folder.

    Returns
    -------
    dict of str to list of str
        Stage -> its CSV tables, in ``targets``' order, each once; stages with none left out.
    """
    out: dict[str, list[str]] = {}
    for stage in categories:
        tables = list(dict.fromkeys(str(t) for t in targets
                                    if str(t).startswith(f"{results}/{stage}/")
                                    and str(t).endswith(".csv")))
        if tables:
            out[stage] = tables
    return out


def report_page_args(output: Any, tables: dict[str, list[str]], categories: dict[str, str]
                     ) -> list[str]:
    """``ssw report`` arguments ``--page OUTPUT TITLE CSV...`` for every stage's tables
    page.

    Parameters
    ----------
    output : snakemake.io.OutputFiles
        The job's outputs, one per stage.
    tables : dict
        Stage -> its CSV tables (:func:`report_tables`).
    categories : dict
        Stage -> its report category (:func:`report_categories`).

    Returns
    -------
    list of str
        One argument per item (a rule quotes each: ``{params.pages:q}``).
    """
    return [a for st, ts in tables.items()
            for a in ("--page", str(getattr(output, st)), f"{categories[st]}: tables", *ts)]
