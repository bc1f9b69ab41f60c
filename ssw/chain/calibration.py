"""Calibration of the one unknown device parameter on one foam of the thesis's Table 2.

The device of Villacreses et al. (2021) is undocumented (REFERENCE.md [U]): the striker's
drop height is unknown. We keep every other parameter at its documented default and choose
the striker speed ``V`` so that the model's TOF on ONE control foam equals the thesis's
simulated TOF; the other foams are then predictions (tested in ``tests/test_chain_table2.py``).

Choice of the foam: PCF 30 (445 MPa, nu 0.30, TOF 1.15 ms), the stiffest, where the plate
under the last bead changes the contact least, so that the Hertz wall (available without
the FEM results) is the best stand-in for the thesis's K-modified wall. TOF(V) decreases
with V (a stronger wave is faster and shortens the wall contact, ``t_c ~ V^(-1/5)``), so
the root is bracketed and found by Brent's method.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ssw.chain import api
from ssw.chain.params import ChainParams
from ssw.chain.walls import build_wall
from ssw.errors import ConfigError, OutOfRangeError, SolverError

#: Thesis Table 2: (id, E Pa, nu, simulated TOF s).
TABLE2 = (
    ("PCF08", 38.0e6, 0.34, 1.80e-3),
    ("PCF15", 123.0e6, 0.33, 1.46e-3),
    ("PCF30", 445.0e6, 0.30, 1.15e-3),
)
#: The foam the striker speed is calibrated on.
CALIBRATION_FOAM = "PCF30"
#: Bracket of striker speeds searched, m/s (drops of 0.05 mm .. 0.8 m).
V_BRACKET = (0.03, 4.0)


@dataclass(frozen=True)
class Calibration:
    """The calibrated striker speed (m/s) and the TOF (s) it gives on each Table 2 foam."""

    striker_velocity: float
    foam: str
    tof: dict[str, float | None]
    tof_thesis: dict[str, float]
    #: Why a foam has no model TOF (its E or nu lies outside the wall law's table).
    skipped: dict[str, str]

    @property
    def drop_height(self) -> float:
        """Free-fall height (m) giving that speed, ``V^2 / (2 g)``."""
        return self.striker_velocity**2 / (2.0 * 9.80665)


def read_calibrated_velocity(path: str | Path) -> float:
    """The striker speed (m/s) of a ``ssw tof-calibrate --json`` result file."""
    p = Path(path)
    try:
        data = json.loads(p.read_text())
    except (OSError, ValueError) as exc:
        raise ConfigError("--calibration", str(p), f"a readable JSON file ({exc})") from exc
    v = data.get("striker_velocity") if isinstance(data, dict) else None
    if data.get("command") != "tof-calibrate" or not isinstance(v, float) or not v > 0:
        raise ConfigError("--calibration", str(p),
                          "the JSON output of `ssw tof-calibrate --json` (striker_velocity > 0)")
    return v


def table2_tof(
    params: ChainParams, wall: str = "hertz", **wall_options: Any
) -> tuple[dict[str, float | None], dict[str, str]]:
    """Model TOF (s) of the three Table 2 foams, and why any foam has none.

    A foam whose (E, nu) lies outside the wall law's validity (a ``fit`` K table that
    does not cover it) gets ``None`` and the range error's message; the others are one
    batched run.
    """
    inside: list[tuple[str, float, float]] = []
    skipped: dict[str, str] = {}
    for foam, E, nu, _ in TABLE2:
        try:
            build_wall(wall, params, E, nu, **wall_options)
        except OutOfRangeError as exc:
            skipped[foam] = str(exc)
        else:
            inside.append((foam, E, nu))
    tof: dict[str, float | None] = {row[0]: None for row in TABLE2}
    if inside:
        T = api.tof([r[1] for r in inside], [r[2] for r in inside], params, wall, **wall_options)
        tof.update({r[0]: float(t) for r, t in zip(inside, T, strict=True)})
    return tof, skipped


def calibrate_striker_velocity(
    params: ChainParams, foam: str = CALIBRATION_FOAM, wall: str = "hertz", *,
    xtol: float = 1e-6, **wall_options: Any,
) -> Calibration:
    """Striker speed (m/s) whose TOF on ``foam`` equals the thesis's simulated TOF."""
    from scipy.optimize import brentq

    row = {r[0]: r for r in TABLE2}[foam]

    def gap(v: float) -> float:
        p = params.with_(striker_velocity=v)
        return float(api.tof(row[1], row[2], p, wall, **wall_options)) - row[3]

    lo, hi = V_BRACKET
    if gap(lo) * gap(hi) > 0:
        raise SolverError(
            f"no striker speed in {V_BRACKET} m/s gives TOF {row[3]} s on {foam}"
        )
    v = float(brentq(gap, lo, hi, xtol=xtol))
    p = params.with_(striker_velocity=v)
    tof, skipped = table2_tof(p, wall, **wall_options)
    return Calibration(v, foam, tof, {r[0]: r[3] for r in TABLE2}, skipped)
