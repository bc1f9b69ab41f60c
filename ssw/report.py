"""The study's tables as HTML pages for Snakemake's report.

The study report is Snakemake's own (``snakemake --report results/report.html``): every
figure and table the rules flag with ``report(...)``, in categories per stage, with the
captions of ``workflow/report/*.rst``. This module keeps the one thing that report cannot
show: a CSV file appears there only as a download, so the thesis's Tables 2 and 3 beside
ssw's numbers, the K(E, nu) table and the other study tables are rendered here as HTML
tables (numbers to 6 significant digits, long tables cut at ``MAX_ROWS`` rows with the
file's row count), one page per stage, which the report opens inline. The note under each
table comes from ``workflow/report/captions.yaml`` (file-name glob -> text).

Checks. A table's columns named after a check of :mod:`ssw.validity` (``contact_strain``,
``sample_yield [1]``, ``check_plate_yield``, ``sample_yield_upper_bound``) hold that check's
values: a value above the check's limit is drawn as failing (red), and the page says under
the table what each check tests, its limit and the source of the limit.
"""

from __future__ import annotations

import csv
import fnmatch
import html
from pathlib import Path
from typing import Any

from ssw import __version__
from ssw.errors import ConfigError
from ssw.h5io import atomic_write_text
from ssw.yamlio import safe_load

MAX_ROWS = 60  # rows shown per CSV table (the file holds them all)
STYLE = """body{font-family:sans-serif;margin:1em;color:#222}
table{border-collapse:collapse;font-size:12px;margin:0.5em 0 1.5em 0}
td,th{border:1px solid #bbb;padding:2px 6px;text-align:right}th{background:#eee}
td.text{text-align:left}.note{font-size:13px;color:#444;max-width:60em}
td.fail{background:#f6c6c6;font-weight:bold}
h2{font-size:16px;border-bottom:1px solid #888}"""


def load_captions(path: str | Path | None) -> dict[str, str]:
    """Notes from a YAML mapping of file-name globs to text ({} without a file).

    Parameters
    ----------
    path : str or pathlib.Path or None
        The YAML file (None or missing: no captions).

    Returns
    -------
    dict of str to str
        Glob -> caption, in the file's order.

    Raises
    ------
    ssw.errors.ConfigError
        When the file is not a YAML mapping.
    """
    if path is None or not Path(path).is_file():
        return {}
    data = safe_load(Path(path).read_text()) or {}
    if not isinstance(data, dict):
        raise ConfigError("captions", str(path), "a YAML mapping of file-name globs to text")
    return {str(k): str(v) for k, v in data.items()}


def caption_of(name: str, captions: dict[str, str]) -> str:
    """The first caption whose glob matches ``name`` ('' if none).

    Parameters
    ----------
    name : str
        The table's file name.
    captions : dict of str to str
        Glob -> caption (:func:`load_captions`).

    Returns
    -------
    str
        The caption.
    """
    for pattern, text in captions.items():
        if fnmatch.fnmatch(name, pattern):
            return text
    return ""


def _cell(cell: str) -> str:
    try:
        v = float(cell)
    except ValueError:
        return f"<td class='text'>{html.escape(cell)}</td>"
    return f"<td>{html.escape(f'{v:.6g}')}</td>"


def check_of(header: str) -> str | None:
    """The check (:data:`ssw.validity.RULES`) a column's header names, or None.

    Parameters
    ----------
    header : str
        The column's header, e.g. ``check_contact_radius_ratio [1]``.

    Returns
    -------
    str or None
        The check's name, a key of :data:`ssw.validity.RULES`.
    """
    from ssw.validity import RULES

    name = header.split("[")[0].strip()
    name = name.removeprefix("check_").removesuffix("_upper_bound")
    return name if name in RULES else None


def _check_cell(cell: str, check: str) -> str:
    """A check's value, drawn as failing above the check's limit."""
    from ssw.validity import RULES

    try:
        v = float(cell)
    except ValueError:
        return _cell(cell)
    fails = not v <= RULES[check].limit
    return f"<td{' class=fail' if fails else ''}>{html.escape(f'{v:.6g}')}</td>"


def checks_note(headers: list[str]) -> str:
    """What the check columns among ``headers`` test: limit and source ('' if none).

    Parameters
    ----------
    headers : list of str
        The table's column headers.

    Returns
    -------
    str
        An HTML note listing each check's limit, quantity, assumption and source.
    """
    from ssw.validity import RULES

    names = list(dict.fromkeys(c for c in map(check_of, headers) if c))
    if not names:
        return ""
    items = "".join(f"<li><b>{html.escape(k)}</b> &le; {RULES[k].limit:g}: "
                    f"{html.escape(RULES[k].quantity)} ({html.escape(RULES[k].assumption)}; "
                    f"{html.escape(RULES[k].source)})</li>" for k in names)
    return ("<p class='note'>Checks of the assumptions (ssw.validity; red: the value is "
            "above its limit, the number was computed beyond that assumption):</p>"
            f"<ul class='note'>{items}</ul>")


def csv_table(path: Path, max_rows: int = MAX_ROWS) -> str:
    """An HTML table of a CSV file (lines starting with '#' skipped; first ``max_rows`` rows;
    check columns drawn as failing above their limit, and explained under the table).

    Parameters
    ----------
    path : pathlib.Path
        The CSV file.
    max_rows : int
        The most rows shown.

    Returns
    -------
    str
        The HTML table and its notes.
    """
    with Path(path).open(newline="") as fh:
        rows = list(csv.reader(line for line in fh if not line.startswith("#")))
    if not rows:
        return "<p class='note'>(empty table)</p>"
    head, body = rows[0], rows[1:]
    checks = [check_of(h) for h in head]
    out = ["<table><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in head) + "</tr>"]
    out += ["<tr>" + "".join(_check_cell(c, k) if k else _cell(c)
                             for c, k in zip(r, checks, strict=False)) + "</tr>"
            for r in body[:max_rows]]
    out.append("</table>")
    note = checks_note(head)
    if note:
        out.append(note)
    if len(body) > max_rows:
        out.append(f"<p class='note'>First {max_rows} of {len(body)} rows; all of them in "
                   f"{html.escape(Path(path).name)} (the report's download of it).</p>")
    return "\n".join(out)


def tables_page(tables: list[str | Path], *, title: str, captions: dict[str, str]) -> str:
    """One HTML page holding every table of ``tables`` (CSV paths), each with its note.

    Parameters
    ----------
    tables : list of str or pathlib.Path
        The CSV files.
    title : str
        The page's title.
    captions : dict of str to str
        Glob -> caption (:func:`load_captions`).

    Returns
    -------
    str
        The HTML page.
    """
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}"
             f"</title><style>{STYLE}</style></head><body>",
             f"<p class='note'>{html.escape(title)}; ssw {__version__}. SI units unless a "
             "column says otherwise.</p>"]
    for t in map(Path, tables):
        parts.append(f"<h2>{html.escape(t.name)}</h2>")
        note = caption_of(t.name, captions)
        if note:
            parts.append(f"<p class='note'>{html.escape(note)}</p>")
        parts.append(csv_table(t))
    parts.append("</body></html>")
    return "\n".join(parts)


def write_tables(tables: list[str | Path], output: str | Path, *, title: str,
                 captions_file: str | Path | None = None) -> dict[str, Any]:
    """Write :func:`tables_page` atomically; return what it holds.

    Parameters
    ----------
    tables : list of str or pathlib.Path
        The CSV files.
    output : str or pathlib.Path
        The HTML file to write.
    title : str
        The page's title.
    captions_file : str or pathlib.Path or None
        The YAML captions file (:func:`load_captions`).

    Returns
    -------
    dict
        ``output`` (path), ``tables`` (paths) and ``bytes`` (the page's length, characters).

    Raises
    ------
    ssw.errors.ConfigError
        When a table file is missing, or the captions file is not a YAML mapping.
    """
    missing = [str(t) for t in tables if not Path(t).is_file()]
    if missing:
        raise ConfigError("tables", missing, "existing CSV files")
    text = tables_page(tables, title=title, captions=load_captions(captions_file))
    atomic_write_text(output, text)
    return {"output": str(output), "tables": [str(t) for t in tables], "bytes": len(text)}
