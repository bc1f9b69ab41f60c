"""The `ssw fit*` commands: JSON contract, tables from files, errors as exit status 2."""

import json

import numpy as np
import pytest

from ssw import hertz
from ssw.cli import main
from ssw.curve import ForceCurve, write_curve

R = 9.53e-3
D = np.linspace(0.0, 1e-4, 101)


def write(path, E, nu, K, plate=("pla", 0.4e-3)):
    F = K * hertz.force(D, hertz.effective_modulus(E, nu), R)
    inputs = {
        "soil_E": E,
        "soil_nu": nu,
        "indenter_radius": R,
        "plate_material": plate[0],
        "plate_thickness": plate[1],
    }
    write_curve(path, ForceCurve(D, F, np.sqrt(R * D), inputs=inputs))
    return str(path)


def test_fit_json_contract(tmp_path, capsys):
    p = write(tmp_path / "c.h5", 50e6, 0.3, K=np.sqrt(3))
    assert main(["fit", p, "--law", "k_hertz", "--range-mode", "curve", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["K"] == pytest.approx(np.sqrt(3), rel=1e-12)
    assert out["rms_rel_residual"] < 1e-12 and out["max_rel_residual"] < 1e-12
    assert out["curve"] == p and out["law"] == "k_hertz"  # inputs are echoed
    assert out["E_star"] == pytest.approx(50e6 / 0.91, rel=1e-14)
    assert out["range"]["hi"] == pytest.approx(1e-4)


def test_fit_fixed_range_and_power_law(tmp_path, capsys):
    p = write(tmp_path / "c.h5", 50e6, 0.3, K=1.0)
    assert main(["fit", p, "--law", "power", "--delta-max", "5e-5", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["n"] == pytest.approx(1.5, rel=1e-12)
    assert out["range"]["mode"] == "fixed" and out["delta_hi"] == pytest.approx(5e-5)


def test_fit_table_writes_a_loadable_table(tmp_path, capsys):
    from ssw.fit.table import KTable

    paths = [
        write(tmp_path / f"c{i}.h5", E, 0.3, K=1 + 1e8 / E)
        for i, E in enumerate([30e6, 60e6, 120e6, 240e6])
    ]
    h5, csvp = tmp_path / "k.h5", tmp_path / "k.csv"
    assert (
        main(
            [
                "fit-table",
                *paths,
                "--output",
                str(h5),
                "--csv",
                str(csvp),
                "--config",
                "config/ci.yaml",
                "--json",
            ]
        )
        == 0
    )
    out = json.loads(capsys.readouterr().out)
    assert out["tables"][0]["n_E"] == 4
    tb = KTable.load(h5)
    assert np.allclose(tb.K([30e6, 240e6], 0.3), [1 + 1e8 / 30e6, 1 + 1e8 / 240e6], rtol=1e-10)


def test_missing_file_is_exit_status_2(tmp_path, capsys):
    assert main(["fit", str(tmp_path / "none.h5")]) == 2
    assert "no contact curve" in capsys.readouterr().err


def test_fit_range_reports_what_the_chain_needs(capsys):
    from ssw.config import load_config
    from ssw.fit.range import ChainEstimate, energy_bound_indentation

    assert (
        main(
            [
                "fit-range",
                "--soil-E",
                "38e6",
                "--soil-nu",
                "0.34",
                "--json",
                "--config",
                "config/ci.yaml",
            ]
        )
        == 0
    )
    out = json.loads(capsys.readouterr().out)
    bound = energy_bound_indentation(
        38e6, 0.34, ChainEstimate.from_config(load_config("config/ci.yaml"))
    )
    assert 0 < out["delta_hi"] <= bound
