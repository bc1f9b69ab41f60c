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


def test_new_attributes_are_stored_as_h5py_stores_them(tmp_path):
    """``new_attrs`` against h5py's own ``attrs[name] = value``: the same HDF5 type, shape and
    value for every kind of value ssw writes (and those it leaves to h5py)."""
    import h5py

    from ssw.h5io import new_attrs

    values = {"text": "pla-t400um-E10MPa", "unicode": "ν = 0.3, 10 µm", "empty": "",
              "float": 0.1, "nan": float("nan"), "int": -7, "big": 2**40, "bool": True,
              "np_float32": np.float32(1.5), "np_int16": np.int16(3), "np_bool": np.bool_(False),
              "array": np.linspace(0.0, 1.0, 7), "matrix": np.arange(6.0).reshape(2, 3),
              "int_list": [1, 2, 3], "empty_array": np.zeros(0), "bytes": b"raw",
              "text_list": ["a", "bc"]}
    with h5py.File(tmp_path / "ref.h5", "w") as ref, h5py.File(tmp_path / "new.h5", "w") as new:
        for k, v in values.items():
            ref.attrs[k] = v
        new_attrs(new, values)
    with h5py.File(tmp_path / "ref.h5") as ref, h5py.File(tmp_path / "new.h5") as new:
        assert list(new.attrs) == list(ref.attrs)
        for k in values:
            a, b = ref.attrs.get_id(k), new.attrs.get_id(k)
            assert a.get_type().equal(b.get_type()), k
            assert a.shape == b.shape, k
            np.testing.assert_array_equal(np.asarray(new.attrs[k]), np.asarray(ref.attrs[k]))
            assert type(new.attrs[k]) is type(ref.attrs[k]), k
