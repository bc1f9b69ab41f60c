"""TOF impact: on a bare-soil Hertz curve every law gives the Hertz-wall TOF."""

import numpy as np
import pytest

from ssw import hertz
from ssw.config import load_config
from ssw.curve import ForceCurve


def test_hertz_curve_gives_the_hertz_tof_with_every_law():
    from ssw.fit.tof_impact import tof_impact

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
        # power and table walls rescale the same rigid-sphere law: identical TOF; the K and
        # Hertz walls use the bead radius (9.525 mm) instead of the FEM indenter's (9.53 mm):
        # force ratio sqrt(9.53/9.525) - 1 = 2.6e-4, TOF ~ F^(-1/5): ~5e-5
        assert abs(r["tof_err_fit_power"]) < 1e-9
        for law in ("fit_k", "hertz"):
            assert abs(r[f"tof_err_{law}"]) < 1.5e-4
        assert -0.3 < r["dlnTOF_dlnE"] < -0.1  # TOF ~ E^(-1/5) for a Hertz wall
