"""TOF impact: on a bare-soil Hertz curve every law gives the Hertz-wall TOF."""

import numpy as np
import pytest

from ssw import hertz
from ssw.config import load_config
from ssw.curve import ForceCurve


def test_hertz_curve_gives_the_hertz_tof_with_every_law():
    from ssw.tof.impact import tof_impact

    cfg = load_config("config/ci.yaml")
    R = cfg["indenter"]["radius"]
    d = np.linspace(0.0, 6e-4, 3001)  # beyond the chain's reach on these soils
    curves = [
        ForceCurve(
            d,
            hertz.force(d, hertz.effective_modulus(E, 0.3), R),
            np.sqrt(R * d),
            inputs={
                "soil_E": E,
                "soil_nu": 0.3,
                "indenter_radius": R,
                "plate_material": "none",
                "plate_thickness": 0.0,
            },
        )
        for E in (38e6, 445e6)
    ]
    rows = tof_impact(curves, cfg)
    for r in rows:
        assert r["K"] == pytest.approx(1.0, rel=1e-12)
        assert r["n"] == pytest.approx(1.5, rel=1e-12)
        # power and table walls rescale the same rigid-sphere law: identical TOF
        assert r["tof_fit_power"] == pytest.approx(r["tof_table"], rel=1e-9)
        # the reference is the FEM law itself (ci mesh, growth 0.2: ~0.4 % force error):
        # a Hertz curve's laws are within the FEM's accuracy of it in TOF (measured 1.2e-3)
        for law in ("fit_k", "fit_power", "table", "hertz"):
            assert abs(r[f"tof_err_{law}"]) < 3e-3
        assert -0.3 < r["dlnTOF_dlnE"] < -0.1  # TOF ~ E^(-1/5) for a Hertz wall
