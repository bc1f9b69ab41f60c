"""Validation tables on disk: CSV (thesis Tables 2 and 3 columns) and HDF5 (every field)."""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any

import numpy as np

from ssw.h5io import atomic_h5, to_json, write_csv_text, write_dataset
from ssw.validation.table import SampleResult

KIND = "validation"
#: CSV columns and their units.
COLUMNS = {
    "sample": "", "material": "", "E_manufacturer": "Pa", "nu": "1", "tof_sim": "s",
    "tof_measured": "s", "tof_measured_std": "s", "tof_source": "", "tof_diff_pct": "%",
    "tof_diff_signed_pct": "%", "tof_sem": "s", "E_measured": "Pa", "E_low": "Pa",
    "E_high": "Pa", "E_u_pct": "%", "E_cov_pct": "%", "E_diff_pct": "%", "E_loo": "Pa",
    "E_loo_diff_pct": "%",
    "n_hits": "1", "n_accepted": "1", "tof_published": "s", "tof_sim_published": "s",
    "E_published": "Pa", "E_cov_published": "%", "synthetic": "",
}


def check_names(rows: list[SampleResult]) -> list[str]:
    """The checks (:data:`ssw.validity.RULES` order) any row carries.

    Parameters
    ----------
    rows : list of SampleResult
        The validation rows.

    Returns
    -------
    list of str
        The checks' names.
    """
    from ssw.validity import RULES

    have = {e["check"] for r in rows for e in r.validity}
    return [k for k in RULES if k in have]


def to_csv_text(rows: list[SampleResult]) -> str:
    """CSV text; the header names each column with its unit, ``name [unit]``. After the
    thesis's columns, each check's value (dimensionless, ``[1]``; ``_upper_bound`` after the
    name of an upper bound; empty where a row has none) and ``checks_failed`` (the failing
    checks, ``;``-joined).

    Parameters
    ----------
    rows : list of SampleResult
        The validation rows.

    Returns
    -------
    str
        The CSV text, one line per row after the header.
    """
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    checks = check_names(rows)
    bounds = {e["check"] for r in rows for e in r.validity if e.get("bound") == "upper"}
    tail = ([f"{k}_upper_bound [1]" if k in bounds else f"{k} [1]" for k in checks]
            + (["checks_failed"] if checks else []))
    w.writerow([f"{k} [{u}]" if u else k for k, u in COLUMNS.items()] + tail)
    for r in rows:
        d = r.to_dict()
        vals = {e["check"]: e["value"] for e in r.validity}
        failed = ";".join(e["check"] for e in r.validity if not e["holds"])
        w.writerow(["" if d[k] is None else d[k] for k in COLUMNS]
                   + ["" if vals.get(k) is None else vals[k] for k in checks]
                   + ([failed] if checks else []))
    return buf.getvalue()


def write_table(csv_path: str | Path, h5_path: str | Path, rows: list[SampleResult],
                inputs: dict[str, Any]) -> None:
    """Write the CSV and the HDF5 (one group per sample, per-hit arrays included).

    Parameters
    ----------
    csv_path : str or Path
        The CSV file (:func:`to_csv_text`, with its provenance line).
    h5_path : str or Path
        The HDF5 file, written atomically.
    rows : list of SampleResult
        The validation rows.
    inputs : dict
        The inputs recorded in both files' provenance.
    """
    write_csv_text(csv_path, to_csv_text(rows), inputs)
    with atomic_h5(h5_path, kind=KIND, inputs=inputs) as f:
        for r in rows:
            g = f.create_group(r.sample)
            d = r.to_dict()
            for k, u in COLUMNS.items():
                if d[k] is not None and u and k != "synthetic":
                    write_dataset(g, k, d[k], u)
            g.attrs["row_json"] = to_json(d)
            write_dataset(g, "tof_per_hit", np.asarray(r.tof_per_hit, float), "s")
            write_dataset(g, "E_per_hit", np.asarray(r.E_per_hit, float), "Pa")


def _r(x: float | None, scale: float = 1.0, nd: int = 4) -> str:
    return "" if x is None else f"{x * scale:.{nd}g}"


def thesis_tables_text(rows: list[SampleResult]) -> tuple[str, str]:
    """Thesis Tables 2 and 3 side by side with ssw's values, in the thesis's units.

    Table 2: E (MPa), nu, TOF simulated (ssw / thesis, s), TOF measured (s), difference
    (ssw / thesis, %). Table 3: E (MPa), measured E (ssw with its 95 % interval / thesis,
    MPa), the leave-one-out E (ssw: calibrated without that sample), its COV (ssw / thesis,
    %), difference (ssw / leave-one-out / thesis, %). Thesis differences are recomputed
    from its printed values with the same formulas.

    Parameters
    ----------
    rows : list of SampleResult
        The validation rows.

    Returns
    -------
    tuple of str
        The CSV texts of Table 2 and Table 3.
    """
    t2 = io.StringIO()
    w = csv.writer(t2, lineterminator="\n")
    w.writerow(["sample", "E [MPa]", "nu [1]", "TOF sim ssw [s]", "TOF sim thesis [s]",
                "TOF measured [s]", "TOF source", "diff ssw [%]", "diff thesis [%]"])
    for r in rows:
        thesis = (abs(r.tof_published - r.tof_sim_published) / r.tof_sim_published * 100
                  if r.tof_published and r.tof_sim_published else None)
        w.writerow([r.sample, _r(r.E_manufacturer, 1e-6), r.nu, _r(r.tof_sim),
                    _r(r.tof_sim_published), _r(r.tof_measured), r.tof_source,
                    _r(r.tof_diff_pct, nd=3), _r(thesis, nd=3)])
    t3 = io.StringIO()
    w = csv.writer(t3, lineterminator="\n")
    w.writerow(["sample", "E [MPa]", "E measured ssw [MPa]", "E low 95% [MPa]",
                "E high 95% [MPa]", "E leave-one-out ssw [MPa]", "E measured thesis [MPa]",
                "COV ssw [%]", "COV thesis [%]", "diff ssw [%]", "diff leave-one-out [%]",
                "diff thesis [%]"])
    for r in rows:
        thesis = (abs(r.E_published - r.E_manufacturer) / r.E_manufacturer * 100
                  if r.E_published else None)
        loo = None if r.E_loo_diff_pct is None else abs(r.E_loo_diff_pct)
        w.writerow([r.sample, _r(r.E_manufacturer, 1e-6), _r(r.E_measured, 1e-6),
                    _r(r.E_low, 1e-6), _r(r.E_high, 1e-6), _r(r.E_loo, 1e-6),
                    _r(r.E_published, 1e-6), _r(r.E_cov_pct, nd=3), _r(r.E_cov_published, nd=3),
                    _r(r.E_diff_pct, nd=3), _r(loo, nd=3), _r(thesis, nd=3)])
    return t2.getvalue(), t3.getvalue()


def write_thesis_tables(table2: str | Path, table3: str | Path, rows: list[SampleResult],
                        inputs: Any = None) -> None:
    """Write :func:`thesis_tables_text` to two CSV files (with their provenance line, for
    tables made from ``inputs``: default the rows).

    Parameters
    ----------
    table2 : str or Path
        The CSV file of Table 2.
    table3 : str or Path
        The CSV file of Table 3.
    rows : list of SampleResult
        The validation rows.
    inputs : Any
        The inputs recorded in the provenance line (None: the rows' mappings).
    """
    a, b = thesis_tables_text(rows)
    inputs = [r.to_dict() for r in rows] if inputs is None else inputs
    write_csv_text(table2, a, inputs)
    write_csv_text(table3, b, inputs)
