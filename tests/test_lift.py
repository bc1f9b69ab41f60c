"""A lift on a subgrade read as a half-space (ssw.lift): the layered oracle's lift on a
very stiff subgrade is the FEM's block on a rigid bonded base (two methods, one chain); a
subgrade of the lift's own modulus is the half-space."""

from __future__ import annotations

import numpy as np
import pytest

from ssw.chain.params import chain_params
from ssw.device import load_device
from ssw.lift import lift_errors, warning_thickness
from ssw.materials import material_set
from ssw.sample import Sample
from ssw.tof import api

P = chain_params(load_device("thesis"), material_set(), steps_per_contact=60)


def test_a_subgrade_like_the_lift_is_the_half_space():
    """E2 = E1: the layered ground is the half-space, read back within the interpolation
    of the half-space TOFs (1e-4)."""
    res = lift_errors(P, 100e6, 0.35, [1.0], [0.03, 0.1])
    assert np.max(np.abs(res.error)) < 1e-4


def test_a_stiff_subgrade_is_the_fems_block_on_a_rigid_base():
    """A 30 mm lift on a subgrade 1e4 times stiffer (the oracle, an infinite layer) and the
    FEM's 30 mm block bonded to a rigid base (radius 0.5 m, free side), both under the
    device's plate and chain: the same TOF within 0.1 % (the two methods' stated errors)."""
    res = lift_errors(P, 100e6, 0.35, [1e4], [0.03])
    contact = Sample(0.03, 0.5, "bonded", "free").contact_settings({})
    fem = float(api.tof(100e6, 0.35, P, "fem", contact=contact))
    assert res.tof[0, 0] == pytest.approx(fem, rel=1e-3)
    assert res.error[0, 0] > 0.03  # the rigid base reads stiffer: a real effect


def test_the_error_shrinks_with_the_lift_and_names_its_warning_thickness():
    """Softer subgrade: the reading is low, the more so the thinner the lift; the
    2 % warning thickness lies between the computed thicknesses that bracket 2 %."""
    res = lift_errors(P, 100e6, 0.35, [0.25], [0.05, 0.1, 0.2, 0.4])
    e = res.error[0]
    assert np.all(e < 0) and np.all(np.diff(np.abs(e)) < 0)
    h = warning_thickness(res, 0.25)
    j = int(np.flatnonzero(np.abs(e) > 0.02)[-1])
    assert h is not None and res.thicknesses[j] < h < res.thicknesses[j + 1]


def test_measure_warns_on_a_thin_lift():
    """``ssw measure --lift-thickness``: a 30 mm lift is read 3-4 % off on a subgrade of
    half or twice its modulus: a note says so; a 300 mm lift is within 2 %: no note."""
    import contextlib
    import io
    import json
    from pathlib import Path

    from ssw.cli import main

    root = Path(__file__).resolve().parent.parent
    rec = str(root / "data" / "survey_example" / "P1.h5")

    def run(h: str) -> dict:
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            main(["measure", rec, "--soil-nu", "0.3", "--calibration", "none", "--config",
                  str(root / "config" / "ci.yaml"), "--lift-thickness", h, "--json"])
        return json.loads(buf.getvalue())

    thin, thick = run("0.03"), run("0.3")
    assert max(abs(e) for e in thin["lift_error"].values()) > 0.02
    assert any("lift read as a half-space" in n for n in thin["notes"])
    assert max(abs(e) for e in thick["lift_error"].values()) < 0.02
    assert not any("lift read as a half-space" in n for n in thick["notes"])
