"""The plate design's thickness search (ssw.design.optimize.search): on merits whose
minimizer is known in closed form, the batched grid refinement finds it to the stated
tolerance ``thickness_tol`` in ln(thickness), as scipy's bounded scalar minimization
(Brent, the search it replaces) does, and it evaluates its thicknesses a round at a time
(a few batched chain runs, not one run per thickness)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from ssw.design.evaluate import quantize
from ssw.design.optimize import REFINE_POINTS, search
from ssw.design.spec import DesignSpec

NO_VIOLATION = {"plate_yield_index": 0.0, "mass_ratio": 0.0, "soil_yield_index": 0.0}


class Merit:
    """A stand-in evaluator: the candidate of thickness t has merit ``g(ln t)`` (its
    sensitivity is ``-g``, no limit violated); every call of ``many`` is recorded."""

    def __init__(self, spec: DesignSpec, g) -> None:
        self.spec, self.g, self.calls = spec, g, []

    def many(self, plates, plate_diameter=None, striker_velocity=None, sources=None):
        self.calls.append(len(plates))
        return [SimpleNamespace(thickness=quantize(t), plate_diameter=0.05,
                                striker_velocity=0.4, sensitivity=-self.g(np.log(quantize(t))),
                                violations=NO_VIOLATION) for _, t in plates]


SPEC = DesignSpec(soil_E=(2e7, 2e8), soil_nu=0.3, thickness=(1e-4, 3e-3))


@pytest.mark.parametrize("x_opt", [np.log(2.7e-4), np.log(1.3e-3), np.log(2.2e-4)])
def test_interior_minimizer_within_tolerance_in_few_batched_runs(x_opt):
    from scipy.optimize import minimize_scalar

    g = lambda x: (x - x_opt) ** 2 + 0.3 * abs(x - x_opt) ** 3  # noqa: E731
    ev = Merit(SPEC, g)
    res = search(ev, "pla")
    tol = SPEC.thickness_tol
    # the minimizer is x_opt; rounding the thickness to 1e-6 m adds up to 0.5e-6 / t
    quantum = 0.5e-6 / np.exp(x_opt)
    assert abs(np.log(res.best.thickness) - x_opt) <= tol + quantum
    # as close as Brent's bounded search gets to the same tolerance
    brent = minimize_scalar(g, bounds=np.log(SPEC.thickness), method="bounded",
                            options={"xatol": tol})
    assert abs(brent.x - x_opt) <= tol
    # the scan, then a few rounds, each one batched call
    assert len(ev.calls) <= 5
    assert ev.calls[0] == SPEC.scan_points
    assert all(n <= REFINE_POINTS for n in ev.calls[1:])
    assert res.nfev == sum(ev.calls) == len(res.evaluated)


@pytest.mark.parametrize("side", [0, 1])
def test_minimizer_on_a_bound(side):
    """Every plate yields and the thinnest yields least (the thesis design's case), or the
    thickest wins: the search ends on the bound, its nearest neighbour evaluated within
    the tolerance of it, after one round of points approaching the bound."""
    ev = Merit(SPEC, (lambda x: x) if side == 0 else (lambda x: -x))
    res = search(ev, "pla")
    bound = SPEC.thickness[side]
    assert res.best.thickness == pytest.approx(bound)
    assert ev.calls == [SPEC.scan_points, REFINE_POINTS]
    nearest = min((t for t in res.evaluated if t != bound),
                  key=lambda t: abs(np.log(t / bound)))
    assert abs(np.log(nearest / bound)) <= SPEC.thickness_tol
