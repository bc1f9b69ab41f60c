"""Short human summaries of command results: the lines a person reads at a terminal.

A command's ``run(args)`` returns its whole result (SI units); ``--json`` prints all of it.
Without ``--json``, ``ssw.cli.main`` prints the command's ``human(result)``: the
printers here (``ssw tof``, ``ssw invert``) and :func:`default`, the short summary of any
command without its own printer (its scalar fields, lists counted, nested dictionaries
left to ``--json``). The validity checks (:mod:`ssw.validity`) always read as one line:
how many hold, the failing ones named with their values.
"""

from __future__ import annotations

import math
from typing import Any

#: Result fields the summaries leave to ``--json``: the echo of the device and the wall's
#: options, the validity entries (read as one line by :func:`checks_lines`).
_ECHO = frozenset({"device_values", "device_source", "wall_options", "validity",
                   "checks_failed", "checks_skipped", "derivative_method", "derivative_units",
                   "derivative_step", "provenance"})

#: The pointer closing a summary that left fields out.
MORE = "(--json: every field and the inputs that produced them)"


def number(value: Any, unit: str = "", scale: float = 1.0, digits: int = 5) -> str:
    """``value / scale`` with ``digits`` significant digits and its ``unit``.

    Parameters
    ----------
    value : float or None
        The quantity in SI units; None or NaN reads ``n/a``.
    unit : str
        The unit printed after the number (the unit of ``value / scale``).
    scale : float
        The SI size of that unit (1e-3 for ms, 1e-6 for um, 1e6 for MPa).
    digits : int
        Significant digits.

    Returns
    -------
    str
        For example ``1.8259 ms``.
    """
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    text = f"{float(value) / scale:.{digits}g}"
    return f"{text} {unit}".rstrip()


def checks_lines(res: dict[str, Any]) -> list[str]:
    """The validity checks of a result (:meth:`ssw.validity.Validity.to_dict`) as one line,
    the failing ones named with their value and limit, and one more line per stated
    assumption a failing check rests on.

    Parameters
    ----------
    res : dict
        A command's result with ``validity`` (entries), ``checks_skipped`` (name -> why).

    Returns
    -------
    list of str
        Empty when the result has no checks.
    """
    entries = res.get("validity") or []
    skipped = res.get("checks_skipped") or {}
    if isinstance(entries, dict):
        return _grid_checks_lines(entries, res.get("validity_meta") or {})
    if not entries and not skipped:
        return []
    held = [e["check"] for e in entries if e["holds"]]
    failed = [e for e in entries if not e["holds"]]
    parts = [f"{len(held)} of {len(entries)} hold"]
    if failed:
        parts.append("FAIL: " + ", ".join(
            f"{e['check']} {number(e['value'], digits=3)} > {e['limit']:g}"
            + (" (upper bound)" if e.get("bound") == "upper" else "")
            + (" (assumed)" if e.get("assumed") else "") for e in failed))
    if skipped:
        parts.append("not evaluated: " + ", ".join(skipped))
    lines = ["checks: " + "; ".join(parts)]
    lines += [f"  {e['check']} assumed {e['assumed']}" for e in failed if e.get("assumed")]
    return lines


def _grid_checks_lines(values: dict[str, Any], meta: dict[str, Any]) -> list[str]:
    """The checks of a grid of scenes (``validity``: check -> one value a scene; its limits
    in ``validity_meta["rules"]``) as one line: per check, the scenes past its limit."""
    import numpy as np

    rules = meta.get("rules") or {}
    parts = []
    for name, vals in values.items():
        if name not in rules:
            continue
        v = np.asarray(vals, float)
        n = int(np.count_nonzero(v > rules[name]["limit"]))
        upper = " (an upper bound)" if (meta.get("bound") or {}).get(name) == "upper" else ""
        parts.append(f"{name} fails at {n} of {v.size}{upper}" if n else f"{name} holds")
    return ["checks: " + ", ".join(parts)] if parts else []


def derivatives_line(res: dict[str, Any]) -> str | None:
    """``dTOF/d...`` of a result in one line, with the method that gave them.

    Parameters
    ----------
    res : dict
        A result with ``dtof_d<parameter>`` fields (s per the parameter's SI unit),
        ``derivative_units`` and ``derivative_method`` (:mod:`ssw.chain.sensitivity`).

    Returns
    -------
    str or None
        The line, or None when the result has no derivative.
    """
    units = res.get("derivative_units") or {}
    keys = [k for k in res if k.startswith("dtof_d") and res[k] is not None]
    if not keys:
        return None
    methods = sorted({m for m in (res.get("derivative_method") or {}).values() if m != "none"})
    how = f" ({', '.join(methods)})" if methods else ""
    return f"dTOF/d{how}: " + ", ".join(
        f"{k[len('dtof_d'):]} {res[k]:.3e} {units.get(k, '')}".rstrip() for k in keys)


def device_line(res: dict[str, Any]) -> str:
    """``device NAME, WALL wall, calibration FILE`` of a result that ran a device.

    Parameters
    ----------
    res : dict
        A result with ``device_name``, ``wall`` and ``calibration_file``
        (:func:`ssw.cli._device.chain_context`'s inputs).

    Returns
    -------
    str
        The phrase.
    """
    cal = res.get("calibration_file") or "none"
    return (f"device {res.get('device_name', '?')}, {res.get('wall', '?')} wall, "
            f"calibration {cal}")


def tof(res: dict[str, Any]) -> str:
    """``ssw tof``: the TOF, the incident and reflected peaks' times and forces, the peak
    wall indentation, the checks in one line and the derivatives in one line (at most 15
    lines; ``--json`` keeps everything).

    Parameters
    ----------
    res : dict
        The result of ``ssw.cli.chain.run_tof`` (one soil; the dynamic FEM wall's
        result has no peaks but the quasi-static TOFs).

    Returns
    -------
    str
        The summary.
    """
    lines = [f"TOF {_fixed(res.get('tof'), 1e-3, 5)} ms  ({device_line(res)})"]
    if "t_incident" in res:
        for side in ("incident", "reflected"):
            t, f = res[f"t_{side}"], res[f"f_{side}"]
            lines.append(f"{side + ' peak':15} t {_fixed(t, 1e-3, 5)} ms   F "
                         f"{_fixed(f, 1.0, 2)} N")
    if "tof_quasi_static_half_space" in res:
        lines.append("quasi-static TOF: half-space "
                     f"{number(res['tof_quasi_static_half_space'], 'ms', 1e-3, 6)}, box "
                     f"{number(res['tof_quasi_static_box'], 'ms', 1e-3, 6)}; error "
                     f"{number(res['quasi_static_error'], digits=3)}")
    if "peak_wall_indentation" in res:
        step = (f"; time step {number(res['dt'], 'us', 1e-6, 4)}" if "dt" in res else "")
        lines.append(f"peak wall indentation {number(res['peak_wall_indentation'], 'um', 1e-6)}"
                     + step)
    lines += checks_lines(res)
    deriv = derivatives_line(res)
    if deriv:
        lines.append(deriv)
    elif res.get("derivative_note"):
        lines.append(f"derivatives: {res['derivative_note']}")
    lines.append(MORE)
    return "\n".join(lines)


def invert(res: dict[str, Any]) -> str:
    """``ssw invert``: E with its interval, the TOF it came from, the budget of its
    uncertainty, the terms left out, the checks at that E.

    Parameters
    ----------
    res : dict
        The result of ``ssw.cli.chain.run_invert`` (the model's inverse, or with
        ``--table`` a stored sweep's).

    Returns
    -------
    str
        The summary.
    """
    nu = res.get("nu_range") or res.get("nu")
    nu_text = (f"nu {nu[0]:g}..{nu[1]:g}" if isinstance(nu, list | tuple)
               else f"nu {nu:g}" if nu is not None else "nu as the sweep's")
    lines = [f"E = {number(res['E'], 'MPa', 1e6, 5)}, interval "
             f"{number(res['E_low'], '', 1e6, 5)} .. {number(res['E_high'], 'MPa', 1e6, 5)}"
             f"  ({nu_text}; {device_line(res)})",
             f"interval: {res.get('interval', '?')}"]
    if "tof" in res:
        sem = res.get("tof_sem")
        lines.append(f"from TOF {number(res['tof'], 'ms', 1e-3, 6)}"
                     + (f" +- {number(sem, 'us', 1e-6, 3)}" if sem else ""))
    if res.get("contributions_pct"):
        lines.append(f"relative uncertainty of E (1 sigma) {number(res.get('u'), '%', 0.01, 3)} = "
                     + ", ".join(f"{k} {v:.2f} %" for k, v in res["contributions_pct"].items()))
    if res.get("missing_terms"):
        lines.append("not in the interval: " + ", ".join(res["missing_terms"]))
    lo, hi = (res.get("E_range") or [None, None])[:2]
    searched = f"{number(lo, '', 1e6)}..{number(hi, 'MPa', 1e6)}"
    if res.get("extrapolated"):
        lines.append(f"EXTRAPOLATED: outside the searched E range {searched}")
    if res.get("interval_clipped"):
        lines.append(f"INTERVAL CLIPPED at the sweep's E range {searched}")
    lines += [f"note: {n}" for n in res.get("notes") or []]
    lines += checks_lines(res)
    lines.append(MORE)
    return "\n".join(lines)


def default(result: dict[str, Any]) -> str:
    """The short summary of a command without its own printer: each scalar field as
    ``key: value`` (floats to 6 significant digits), a list as its length and ends, the
    checks in one line; nested dictionaries and the echo of the device are left to
    ``--json`` (the last line says so).

    Parameters
    ----------
    result : dict
        The command's result.

    Returns
    -------
    str
        The summary.
    """
    lines, left = [], False
    for k, v in result.items():
        if hasattr(v, "tolist"):  # numpy arrays and scalars
            v = v.tolist()
        if k in _ECHO or isinstance(v, dict):
            left = True
        elif isinstance(v, list | tuple):
            if len(v) > 4 or any(isinstance(x, dict | list) for x in v):
                ends = (f": {_scalar(v[0])} ... {_scalar(v[-1])}"
                        if v and not isinstance(v[0], dict | list) else "")
                lines.append(f"{k}: {len(v)} values{ends}")
                left = True
            else:
                lines.append(f"{k}: {', '.join(_scalar(x) for x in v) or '[]'}")
        else:
            lines.append(f"{k}: {_scalar(v)}")
    lines += checks_lines(result)
    if left:
        lines.append(MORE)
    return "\n".join(lines)


def _fixed(v: Any, scale: float, decimals: int) -> str:
    """``v / scale`` with ``decimals`` decimals; ``n/a`` for None or NaN."""
    if v is None or not math.isfinite(float(v)):
        return "n/a"
    return f"{float(v) / scale:.{decimals}f}"


def _scalar(v: Any) -> str:
    """A float to 6 significant digits, anything else as ``str``."""
    return f"{v:.6g}" if isinstance(v, float) else str(v)
