"""Deviation from Hertz at the reference indentation, and the soil calibration."""

import numpy as np
import pytest

from ssw import hertz
from ssw.curve import ForceCurve
from ssw.errors import OutOfRangeError
from ssw.fit.deviation import (
    DELTA_REF,
    THESIS_SET1,
    calibrate_soil_E,
    deviation,
    deviation_rows,
    force_at,
)

R = 9.53e-3
D = np.linspace(0.0, 1e-4, 1001)  # the thesis's increments: delta_ref = 1 um is sample 10


def curve(F, d=D, **kw):
    inputs = {
        "soil_E": 50e6,
        "soil_nu": 0.3,
        "indenter_radius": R,
        "plate_material": "pla",
        "plate_thickness": 0.4e-3,
        **kw,
    }
    return ForceCurve(d, F, np.sqrt(R * d), inputs=inputs)


def test_bare_hertz_has_zero_deviation():
    F = hertz.force(D, hertz.effective_modulus(50e6, 0.3), R)
    r = deviation(curve(F))
    assert r["deviation"] == pytest.approx(0.0, abs=1e-14)
    assert r["ratio"] == pytest.approx(1.0, rel=1e-14)


def test_known_stiffening_is_measured_between_samples():
    # F = (1 + c) F_H on a grid that does not contain delta_ref: log-log interpolation of
    # a power law is exact
    c = np.e / 10
    d = np.geomspace(1e-7, 1e-4, 77)
    F = (1 + c) * hertz.force(d, hertz.effective_modulus(50e6, 0.3), R)
    assert not np.any(np.isclose(d, DELTA_REF, rtol=1e-9))
    assert deviation(curve(F, d))["deviation"] == pytest.approx(c, rel=1e-12)
    assert force_at(curve(F, d), DELTA_REF) == pytest.approx(
        (1 + c) * hertz.force(DELTA_REF, hertz.effective_modulus(50e6, 0.3), R), rel=1e-12
    )


def test_rows_carry_the_thesis_values():
    F = 1.28 * hertz.force(D, hertz.effective_modulus(50e6, 0.3), R)
    rows = deviation_rows(
        [curve(F), curve(F, plate_material="a36"), curve(F, plate_thickness=0.1e-3)], "materials"
    )
    assert [r["thesis_deviation"] for r in rows] == [THESIS_SET1["pla"], THESIS_SET1["a36"], None]
    rows = deviation_rows(
        [curve(F, plate_thickness=0.2e-3), curve(F, plate_thickness=1e-3)], "thickness"
    )
    assert [r["thesis_deviation"] for r in rows] == [0.37, None]


def test_outside_the_curve_is_an_error():
    F = hertz.force(D, hertz.effective_modulus(50e6, 0.3), R)
    with pytest.raises(OutOfRangeError):
        deviation(curve(F), 2e-4)


def test_calibration_inverts_a_known_deviation_law():
    # dev(E) = (E0/E)^0.7 is reached at E = E0 target^(-1/0.7)
    E0 = 3e8
    E = calibrate_soil_E(0.28, lambda E: (E0 / E) ** 0.7, rtol=1e-12)
    assert E == pytest.approx(E0 * 0.28 ** (-1 / 0.7), rel=1e-9)
    with pytest.raises(OutOfRangeError, match="not reached"):
        calibrate_soil_E(1e6, lambda E: (E0 / E) ** 0.7)


def test_calibration_takes_either_sense_and_solves_each_end_once():
    """An increasing law, dev(E) = (E/E0)^0.5, reached at E = E0 target^2; the bracket's
    ends are evaluated once (an FEM solve each), and Chandrupatla's method needs few more
    (tests/test_roots.py: full precision in 8-16 evaluations)."""
    E0, seen = 3e8, []

    def dev(E):
        seen.append(E)
        return (E / E0) ** 0.5

    E = calibrate_soil_E(0.5, dev, rtol=1e-10)
    assert E == pytest.approx(E0 * 0.25, rel=1e-8)
    assert len(set(seen)) == len(seen)  # no abscissa solved twice
    assert len(seen) <= 20


def test_thesis_statements_cover_both_material_sets():
    """With a stand-in solver that stiffens by the plate's modulus ratio, the rows follow
    the material set's moduli (as_printed PLA is 100 MPa) and carry the thesis's values."""
    from ssw.config import library, load_config
    from ssw.fit.deviation import thesis_statements

    cfg = load_config("config/config.yaml")

    def solve(sc, c):
        E_plate = library(c)[sc.plate_material].E
        F = (1 + E_plate / sc.soil_E) * hertz.force(
            D, hertz.effective_modulus(sc.soil_E, sc.soil_nu), R
        )
        return ForceCurve(
            D,
            F,
            D,
            inputs={
                "soil_E": sc.soil_E,
                "soil_nu": sc.soil_nu,
                "indenter_radius": R,
                "plate_material": sc.plate_material,
                "plate_thickness": sc.plate_thickness,
            },
        )

    rows = thesis_statements(cfg, solve)
    pla = [r for r in rows if r["set"] == "set1_materials" and r["plate_material"] == "pla"]
    by_set = {r["material_set"]: r for r in pla}
    E_soil = by_set["realistic"]["soil_E"]
    assert by_set["realistic"]["deviation"] == pytest.approx(3.5e9 / E_soil, rel=1e-12)
    assert by_set["as_printed"]["deviation"] == pytest.approx(100e6 / E_soil, rel=1e-12)
    assert all(r["thesis_deviation"] == 0.28 for r in pla)
    assert {r["set"] for r in rows} == {"set1_materials", "set2_thickness"}
