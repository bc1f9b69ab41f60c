"""A self-contained HTML report of a study: every figure and table under ``results/``.

Figures (PNG) are embedded as base64 data URIs and CSV tables as HTML tables, so the one
file can be mailed or archived. Sections follow the stages (contact, fit, chain,
validation, bench); captions come from ``workflow/report/captions.yaml`` (file-name glob ->
text), falling back to the file name. The validation table (thesis Tables 2 and 3) comes
first, next to the thesis's published values.
"""

from __future__ import annotations

import base64
import csv
import fnmatch
import html
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from ssw import __version__
from ssw.h5io import atomic_write_text

#: Section order and titles: results sub-folder -> heading.
SECTIONS = {
    "validation": "Stage III: validation on the control foams (thesis Tables 2, 3; Figs 9, 10)",
    "contact": "Stage I: contact FEM (sphere on plate on soil)",
    "fit": "Stage I: modified Hertz fits K(E, nu) (thesis Figs 5-7)",
    "chain": "Stage II: chain dynamics and TOF(E, nu) (thesis Fig 8)",
    "bench": "Benchmarks",
}
MAX_ROWS = 60  # rows shown per CSV table (the file holds them all)
STYLE = """body{font-family:sans-serif;max-width:1100px;margin:auto;padding:1em}
table{border-collapse:collapse;font-size:12px;margin:0.5em 0}td,th{border:1px solid #bbb;
padding:2px 6px;text-align:right}th{background:#eee}img{max-width:100%}
figcaption,.note{font-size:13px;color:#444}h2{border-bottom:1px solid #888}"""


def load_captions(path: str | Path | None) -> dict[str, str]:
    """Captions from a YAML mapping of file-name globs to text ({} if no file)."""
    if path is None or not Path(path).is_file():
        return {}
    import yaml

    data = yaml.safe_load(Path(path).read_text()) or {}
    return {str(k): str(v) for k, v in data.items()}


def caption_of(name: str, captions: dict[str, str]) -> str:
    for pattern, text in captions.items():
        if fnmatch.fnmatch(name, pattern):
            return text
    return name


def _fmt(cell: str) -> str:
    try:
        v = float(cell)
    except ValueError:
        return html.escape(cell)
    return html.escape(f"{v:.6g}")


def csv_table(path: Path, max_rows: int = MAX_ROWS) -> str:
    """An HTML table of a CSV file (the first ``max_rows`` rows)."""
    with path.open(newline="") as fh:
        rows = list(csv.reader(line for line in fh if not line.startswith("#")))
    if not rows:
        return "<p class='note'>(empty table)</p>"
    head, body = rows[0], rows[1:]
    out = ["<table><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in head) + "</tr>"]
    out += ["<tr>" + "".join(f"<td>{_fmt(c)}</td>" for c in r) + "</tr>" for r in body[:max_rows]]
    out.append("</table>")
    if len(body) > max_rows:
        out.append(f"<p class='note'>first {max_rows} of {len(body)} rows; all in "
                   f"{html.escape(str(path))}</p>")
    return "\n".join(out)


def figure(path: Path, caption: str) -> str:
    data = base64.b64encode(path.read_bytes()).decode()
    return (f"<figure><img src='data:image/png;base64,{data}' alt='{html.escape(path.name)}'>"
            f"<figcaption><b>{html.escape(path.name)}</b>: {html.escape(caption)}"
            "</figcaption></figure>")


def build_report(results: str | Path, *, title: str, captions: dict[str, str],
                 config_text: str = "", extra: dict[str, Any] | None = None) -> str:
    """The report's HTML text for everything under ``results``."""
    root = Path(results)
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}"
             f"</title><style>{STYLE}</style></head><body><h1>{html.escape(title)}</h1>",
             f"<p class='note'>ssw {__version__}, built "
             f"{datetime.now(UTC).isoformat(timespec='seconds')}. SI units unless a column "
             "says otherwise.</p>"]
    for key, val in (extra or {}).items():
        parts.append(f"<p class='note'>{html.escape(key)}: {html.escape(str(val))}</p>")
    subdirs = [d for d in SECTIONS if (root / d).is_dir()]
    subdirs += sorted(d.name for d in root.iterdir() if d.is_dir() and d.name not in SECTIONS
                      and d.name not in ("logs", "report")) if root.is_dir() else []
    for sub in subdirs:
        d = root / sub
        parts.append(f"<h2>{html.escape(SECTIONS.get(sub, sub))}</h2>")
        for f in sorted(d.rglob("*.csv")):
            rel = str(f.relative_to(root))
            parts.append(f"<h3>{html.escape(rel)}</h3><p class='note'>"
                         f"{html.escape(caption_of(f.name, captions))}</p>{csv_table(f)}")
        for f in sorted(d.rglob("*.png")):
            parts.append(figure(f, caption_of(f.name, captions)))
    if config_text:
        parts.append(f"<h2>Configuration</h2><pre>{html.escape(config_text)}</pre>")
    parts.append("</body></html>")
    return "\n".join(parts)


def write_report(results: str | Path, output: str | Path, *, title: str,
                 captions_file: str | Path | None = None, config_file: str | Path | None = None
                 ) -> dict[str, Any]:
    """Write the report atomically; return what it holds (counts of figures and tables)."""
    text = build_report(
        results, title=title, captions=load_captions(captions_file),
        config_text=Path(config_file).read_text() if config_file else "",
    )
    atomic_write_text(output, text)
    root = Path(results)
    return {"output": str(output), "figures": len(list(root.rglob("*.png"))),
            "tables": len(list(root.rglob("*.csv"))), "bytes": len(text)}
