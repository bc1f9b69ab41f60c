"""How far the fitted laws' TOF is from the FEM curve's own TOF (the ``table`` wall).

For the scenes of a contact set (plate on soils ``E``, ``nu``) the chain is run with four
last-contact laws: the FEM curve itself (``table``, no fit error), the thesis's modified
Hertz ``K A_w d^1.5`` (``fit``, ``k_hertz``), the power law ``C d^n`` (``fit``, ``power``)
and the bare soil (``hertz``, no plate). The relative TOF differences to the table wall are
the error a fitted law carries into the TOF, and so into the inverted E.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ssw.chain import api
from ssw.chain.params import ChainParams
from ssw.h5io import atomic_write_text

LAWS = ("table", "k_hertz", "power", "hertz")


@dataclass(frozen=True)
class LawComparison:
    """TOF (s) per law, flat arrays over the scenes; a law that could not run is NaN."""

    soil_E: np.ndarray
    soil_nu: np.ndarray
    tof: dict[str, np.ndarray]

    def relative_to_table(self) -> dict[str, np.ndarray]:
        """``TOF_law / TOF_table - 1`` for every other law."""
        ref = self.tof["table"]
        return {k: v / ref - 1.0 for k, v in self.tof.items() if k != "table"}


def compare_laws(
    params: ChainParams, soil_E: Any, soil_nu: Any, curves: list[Any], k_table: Any
) -> LawComparison:
    """TOF of each law of :data:`LAWS` at the flat scenes (``curves``: one per scene)."""
    E, nu = (np.asarray(x, float).ravel() for x in (soil_E, soil_nu))
    tof = {
        "table": api.tof(E, nu, params, "table", curve=list(curves)),
        "k_hertz": api.tof(E, nu, params.with_(fit_law="k_hertz"), "fit", k_table=k_table),
        "hertz": api.tof(E, nu, params, "hertz"),
    }
    try:
        tof["power"] = api.tof(E, nu, params.with_(fit_law="power"), "fit", k_table=k_table)
    except Exception as exc:  # the table may hold only k_hertz fits
        from ssw.errors import SswError

        if not isinstance(exc, SswError):
            raise
        tof["power"] = np.full(E.size, np.nan)
    return LawComparison(E, nu, {k: tof[k] for k in LAWS})


def write_comparison_csv(path: str | Path, cmp: LawComparison) -> None:
    """CSV: E, nu, TOF per law (s) and the relative differences to the table wall."""
    rel = cmp.relative_to_table()
    cols = [cmp.soil_E, cmp.soil_nu, *(cmp.tof[k] for k in LAWS), *rel.values()]
    head = ",".join(["soil_E_Pa", "soil_nu", *(f"tof_{k}_s" for k in LAWS),
                     *(f"rel_{k}_vs_table" for k in rel)])
    rows = [",".join(f"{v:.10g}" for v in row) for row in np.column_stack(cols)]
    atomic_write_text(path, "\n".join([head, *rows]) + "\n")
