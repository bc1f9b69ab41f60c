"""HDF5 conventions: round trips keep values, units and inputs; interrupted writes leave nothing."""

import h5py
import numpy as np
import pytest

from ssw import __version__
from ssw.curve import ForceCurve, read_curve, write_curve
from ssw.errors import SswError
from ssw.h5io import atomic_h5, atomic_write_text, read_inputs


def test_curve_round_trip(tmp_path):
    # values with infinite decimal expansions test precision (meshio's advice)
    d = np.linspace(0, 1e-4, 7)[1:] / 3
    c = ForceCurve(d, d**1.5 * 7 / 3, np.sqrt(d * 9.53e-3),
                   inputs={"soil_E": 1e8 / 3, "plate_material": "pla"},
                   stats={"dofs": 123, "wall_time": 0.1})
    path = tmp_path / "c.h5"
    write_curve(path, c)
    back = read_curve(path)
    assert np.array_equal(back.delta, c.delta) and back.force.dtype == np.float64
    assert back.inputs == c.inputs and back.stats["dofs"] == 123
    with h5py.File(path) as f:
        assert f["delta"].attrs["units"] == "m" and f["force"].attrs["units"] == "N"
        assert f.attrs["ssw_version"] == __version__
        assert read_inputs(f)["soil_E"] == 1e8 / 3


def test_interrupted_write_leaves_no_file(tmp_path):
    path = tmp_path / "x.h5"
    with pytest.raises(RuntimeError), atomic_h5(path, kind="t", inputs={}) as f:
        f["a"] = np.arange(3)
        raise RuntimeError("killed")
    assert list(tmp_path.iterdir()) == []


def test_atomic_replace_keeps_old_file_until_done(tmp_path):
    path = tmp_path / "a.txt"
    atomic_write_text(path, "old")
    with pytest.raises(KeyboardInterrupt), atomic_h5(path, kind="t", inputs={}):
        assert path.read_text() == "old"
        raise KeyboardInterrupt
    assert path.read_text() == "old"


def test_bad_curves_are_refused(tmp_path):
    with pytest.raises(SswError, match="increasing"):
        ForceCurve(np.array([0, 2e-6, 1e-6]), np.zeros(3), np.zeros(3))
    with pytest.raises(SswError, match="finite"):
        ForceCurve(np.array([0, 1e-6]), np.array([0, np.nan]), np.zeros(2))
    with pytest.raises(SswError, match="kind"):
        with atomic_h5(tmp_path / "o.h5", kind="other", inputs={}):
            pass
        read_curve(tmp_path / "o.h5")


def test_finished_files_get_the_umask_mode_not_mkstemps_0600(tmp_path):
    """mkstemp creates 0600 files; a result must be readable like any file the user writes."""
    import os

    old = os.umask(0o022)
    try:
        atomic_write_text(tmp_path / "a.txt", "x")
    finally:
        os.umask(old)
    assert (tmp_path / "a.txt").stat().st_mode & 0o777 == 0o644
