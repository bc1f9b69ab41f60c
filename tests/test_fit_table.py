"""K(E, nu) tables: grid exactness, the stated interpolation error, files, errors."""


import numpy as np
import pytest

from ssw import hertz
from ssw.curve import ForceCurve
from ssw.errors import OutOfRangeError, SswError
from ssw.fit.fitting import fit_curve
from ssw.fit.table import KTable, build_tables, load_tables, write_tables
from ssw.h5io import read_rows_csv

R = 9.53e-3
DELTA = np.linspace(0.0, 1e-4, 201)
E_GRID = np.arange(10e6, 1000e6 + 1, 10e6)  # the thesis's Set 3 axis
NU_GRID = np.array([0.1, 0.3, 0.5])


def k_true(E, nu):
    """A smooth, monotone K(E, nu) of the shape the plate gives (large for soft soils)."""
    return 1.0 + 8.0 * (E / 1e7) ** -0.7 * (1.0 + 0.6 * nu**2)


def n_true(E, nu):
    return 1.5 - 0.3 / (1.0 + E / 1e8) + 0.05 * nu


def fits(E_grid=E_GRID, nu_grid=NU_GRID, plate=("pla", 0.4e-3)):
    """k_hertz fits of F = K A_H d^1.5 and power fits of F = c d^n, on the grid."""
    out = []
    for nu in nu_grid:
        for E in E_grid:
            A = hertz.hertz_coefficient(hertz.effective_modulus(E, nu), R)
            inputs = {
                "soil_E": E,
                "soil_nu": nu,
                "indenter_radius": R,
                "plate_material": plate[0],
                "plate_thickness": plate[1],
            }
            ck = ForceCurve(DELTA, k_true(E, nu) * A * DELTA**1.5, DELTA, inputs=inputs)
            cp = ForceCurve(
                DELTA,
                A * 1e-6 ** (1.5 - n_true(E, nu)) * DELTA ** n_true(E, nu),
                DELTA,
                inputs=inputs,
            )
            out += [fit_curve(ck, "k_hertz"), fit_curve(cp, "power")]
    return out


@pytest.fixture(scope="module")
def table():
    (tb,) = build_tables(fits())
    return tb


def test_interpolant_passes_through_the_fitted_values(table):
    EE, NN = np.meshgrid(table.soil_E, table.soil_nu)
    assert np.allclose(table.K(EE, NN), table.params["k_hertz"]["K"], rtol=1e-13, atol=0)
    C, n = table.power(EE, NN)
    assert np.allclose(C, table.params["power"]["C"], rtol=1e-12, atol=0)
    assert np.allclose(n, table.params["power"]["n"], rtol=1e-13, atol=0)
    # and the fitted values are the known ones (the fits are exact)
    assert np.allclose(table.params["k_hertz"]["K"], k_true(EE, NN), rtol=1e-10, atol=0)


def test_error_between_nodes_within_the_stated_bound(table):
    err = table.interp_error()
    Em = np.sqrt(E_GRID[1:] * E_GRID[:-1])  # midpoints in log E
    for nu in (0.1, 0.2, 0.3, 0.4, 0.5):  # on rows and between them
        true_err = np.max(np.abs(table.K(Em, nu) / k_true(Em, nu) - 1.0))
        assert true_err <= err["K"]
    # the bound is informative, not vacuous: within 10x of the worst true error
    worst = max(np.max(np.abs(table.K(Em, nu) / k_true(Em, nu) - 1.0)) for nu in (0.2, 0.4))
    assert err["K"] < 10 * worst


def test_interpolant_is_monotone_in_E_where_the_data_are(table):
    Ef = np.geomspace(10e6, 1000e6, 3000)
    for nu in (0.1, 0.25, 0.5):
        assert np.all(np.diff(table.K(Ef, nu)) < 0)


def test_error_bound_shrinks_with_a_finer_grid():
    coarse = build_tables(fits(E_GRID[::4], NU_GRID))[0].interp_error()["K_E"]
    fine = build_tables(fits(E_GRID[::2], NU_GRID))[0].interp_error()["K_E"]
    assert fine < coarse / 2  # PCHIP converges at least at order 1 (here ~2-3)


def test_no_extrapolation(table):
    with pytest.raises(OutOfRangeError, match="outside the table's range"):
        table.K(5e6, 0.3)
    with pytest.raises(OutOfRangeError, match="soil_nu"):
        table.K(50e6, 0.6)


def test_hdf5_and_csv_round_trip(table, tmp_path):
    h5, csvp = tmp_path / "k.h5", tmp_path / "k.csv"
    write_tables([table], h5, csvp, {"note": "test"})
    back = KTable.load(h5)
    E = np.array([15e6, 333.3e6, 999e6])
    assert np.array_equal(back.K(E, 0.37), table.K(E, 0.37))
    tables, inputs = load_tables(h5)
    assert inputs == {"note": "test"} and len(tables) == 1
    rows = read_rows_csv(csvp)
    assert len(rows) == E_GRID.size * NU_GRID.size
    r = rows[5]
    assert float(r["K"]) == pytest.approx(
        k_true(float(r["soil_E"]), float(r["soil_nu"])), rel=1e-10
    )


def test_several_plates_need_a_choice(tmp_path):
    tabs = build_tables(
        fits(E_GRID[:3], NU_GRID[:1]) + fits(E_GRID[:3], NU_GRID[:1], plate=("a36", 0.4e-3))
    )
    assert [t.name for t in tabs] == ["a36-t400um", "pla-t400um"]
    write_tables(tabs, tmp_path / "k.h5", None, {})
    with pytest.raises(OutOfRangeError, match="name one plate"):
        KTable.load(tmp_path / "k.h5")
    assert KTable.load(tmp_path / "k.h5", "pla").plate_material == "pla"
    # a one-nu table is valid at that nu only
    with pytest.raises(OutOfRangeError, match="one value"):
        tabs[1].K(20e6, 0.3)


def test_incomplete_grid_is_an_error():
    f = fits(E_GRID[:3], NU_GRID[:2])
    with pytest.raises(SswError, match="missing"):
        build_tables(f[:-1])


def test_power_law_force_between_nodes_within_the_stated_bound(table):
    """The power law's interpolated force, at the indentations its stated error covers
    (0.1, 0.3 and 1 x the fit range's upper end), is within that error of the true law
    between grid nodes in E and in nu; and the bound is informative."""
    err = table.interp_error()["power"]
    Em = np.sqrt(E_GRID[1:] * E_GRID[:-1])
    worst = 0.0
    for nu in (0.1, 0.2, 0.3, 0.4, 0.5):
        C, n = table.power(Em, np.full(Em.shape, nu))
        A = hertz.hertz_coefficient(hertz.effective_modulus(Em, nu), R)
        for d in np.array([0.1, 0.3, 1.0]) * np.max(table.delta_hi):
            F_true = A * 1e-6 ** (1.5 - n_true(Em, nu)) * d ** n_true(Em, nu)
            worst = max(worst, float(np.max(np.abs(C * d**n / F_true - 1.0))))
    assert worst <= err
    assert err < 10 * worst
