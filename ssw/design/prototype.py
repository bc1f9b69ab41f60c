"""A virtual prototype of a designed device: simulated, calibrated and measured as a lab
would, its achieved errors and interval widths beside the predicted ones.

1. Recordings (:class:`ssw.daq.simulated.SimulatedBackend` through
   :class:`ssw.daq.recording.RecordingWriter`): ``hits`` hits on each of ``references``
   reference samples (the ends and the middle of the soil range, log-spaced) and
   ``unseen`` samples it never saw (the centres of ``unseen`` equal cells of the range in
   ``ln E``), the chain of the device on its fem wall through the DAQ's model (anti-alias
   filter, noise, sample phase, trigger jitter), the striker's speed scattering from hit
   to hit by ``striker_cov`` (relative).
2. The calibration (:func:`ssw.calibration.calibrate`, the ``ssw calibrate`` library path
   at the TOF level): the striker speed and the preload free, from the references' pooled
   TOFs (:func:`ssw.measure.pooled_tof`: their mean and standard error).
3. The measurements (:func:`ssw.measure.measure`, the ``ssw measure`` library path): each
   unseen sample's E with its 95 % interval through the calibration.
4. The predicted interval of each unseen sample at the TOF level per point of ``hits``
   hits (:func:`ssw.design.predict.predict` with the calibration's covariance and model
   term), one hit's TOF scatter the striker's (``|dTOF/d ln v| striker_cov``) and the
   DAQ's (its noise through the peak picker, the sampled peaks' spread) in quadrature,
   with the terms ``ssw measure`` states rather than estimates (:data:`STATED`: the fem
   mesh, the integrator, the peak picking's sampling) taken from its budget.

The report: per unseen sample the true E, the measured E and interval, the error, the
achieved and the predicted interval widths and their ratio, and whether the true E is
inside.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

#: Reference samples and unseen samples of a prototype, and hits per sample.
REFERENCES, UNSEEN, HITS = 3, 4, 5


def soils(soil_E: tuple[float, float], references: int, unseen: int
          ) -> tuple[np.ndarray, np.ndarray]:
    """The moduli of a prototype's samples.

    Parameters
    ----------
    soil_E : tuple of float
        (lo, hi) Pa.
    references : int
        Reference samples (log-spaced, ends included).
    unseen : int
        Unseen samples (centres of equal cells in ``ln E``).

    Returns
    -------
    tuple of numpy.ndarray
        Pa, the references' and the unseen samples' moduli.
    """
    a, b = np.log(soil_E[0]), np.log(soil_E[1])
    refs = np.exp(np.linspace(a, b, references))
    new = np.exp(a + (b - a) * (np.arange(unseen) + 0.5) / unseen)
    return refs, new


def _record(path: Path, E: float, nu: float, params: Any, wall_options: dict[str, Any],
            settings: Any, hits: int, seed: int) -> Any:
    """One session of ``hits`` simulated hits, written and read back."""
    from ssw.daq.recording import RecordingWriter, read_recording
    from ssw.daq.simulated import SimulatedBackend

    backend = SimulatedBackend(soil_E=E, soil_nu=nu, chain_params=params, wall="fem",
                               wall_options=wall_options, seed=seed)
    with RecordingWriter(path, settings, {"sample_id": path.stem, "synthetic": True},
                         overwrite=True) as w:
        for hit in backend.hits(settings, hits):
            w.append(hit)
    return read_recording(path)


#: The terms of ``ssw measure``'s budget that are stated, not predicted from the
#: information: the fem wall's mesh, the integrator and the peak picking's sampling.
STATED = ("wall", "integrator", "sampling")


def _budget(m: Any) -> float:
    """The quadrature sum (in ``ln E``) of a measurement's stated terms (:data:`STATED`)."""
    return float(np.sqrt(sum(m.contributions.get(k, 0.0) ** 2 for k in STATED)))


def _daq_scatter(params: Any, E: float, nu: float, wall_options: dict[str, Any],
                 settings: Any) -> float:
    """s, one hit's TOF scatter from the DAQ (its noise through the peak picker and the
    sampled peaks' spread over the clock phase, :func:`ssw.design.sampling.sampled_tof`)."""
    from ssw.chain.params import Batch
    from ssw.chain.run import run_peaks
    from ssw.design.sampling import sampled_tof
    from ssw.walls.fem import fem_wall

    wall = fem_wall(params, np.array([E]), np.array([nu]), **wall_options)
    pk, run = run_peaks(Batch.of(params, 1, {}), wall, strict=False)
    st = sampled_tof(run, pk, settings.sample_rate, settings.simulation.noise_rms)
    return float(np.hypot(st.noise[0], st.spread[0]))


def run_prototype(device: Any, materials: dict[str, Any], numerics: dict[str, Any],
                  wall_options: dict[str, Any], settings: Any,
                  soil_E: tuple[float, float], soil_nu: float, folder: str | Path, *,
                  striker_cov: float = 0.01, references: int = REFERENCES,
                  unseen: int = UNSEEN, hits: int = HITS, seed: int = 0) -> dict[str, Any]:
    """Simulate, calibrate and measure a device (module docstring).

    Parameters
    ----------
    device : ssw.device.Device
        The device (a design's device file).
    materials : dict
        The materials library.
    numerics : dict
        The chain's numerics (``ssw.chain.params.numerics_of``).
    wall_options : dict
        The fem wall's options (its ``contact``).
    settings : ssw.daq.settings.DaqSettings
        The acquisition (its simulation's noise and jitter).
    soil_E : tuple of float
        (lo, hi) Pa, the range.
    soil_nu : float
        The samples' Poisson's ratio.
    folder : str or pathlib.Path
        Where the recordings are written.
    striker_cov : float
        Relative standard deviation of the striker's speed from hit to hit.
    references : int
        Reference samples.
    unseen : int
        Unseen samples.
    hits : int
        Hits per sample.
    seed : int
        Seeds each sample's recording (``seed + i``).

    Returns
    -------
    dict
        ``calibration`` (its parameters), ``references`` and ``unseen`` (one record each).
    """
    from dataclasses import replace

    from ssw.calibration import Reference, calibrate
    from ssw.chain.params import chain_params
    from ssw.design.predict import Z95, model_error_of, predict
    from ssw.measure import measure, pooled_tof
    from ssw.tof import api

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    sim = replace(settings, simulation=replace(settings.simulation,
                                               striker_velocity_cov=float(striker_cov)))
    params = chain_params(device, materials, **numerics)
    ref_E, new_E = soils(soil_E, references, unseen)
    refs, ref_rows = [], []
    for i, E in enumerate(ref_E):
        rec = _record(folder / f"ref{i}.h5", float(E), soil_nu, params, wall_options, sim,
                      hits, seed + i)
        pool = pooled_tof([rec])
        refs.append(Reference(float(E), soil_nu, pool["tof_mean"], pool["tof_sem"],
                              id=f"ref{i}"))
        ref_rows.append({"E": float(E), "tof_mean": pool["tof_mean"],
                         "tof_sem": pool["tof_sem"]})
    cal = calibrate(refs, device, ["striker_velocity", "preload"], materials=materials,
                    numerics=numerics, wall="fem", wall_options=wall_options, loo=False)
    cp = cal.chain_params()
    rows = []
    for j, E in enumerate(new_E):
        rec = _record(folder / f"unseen{j}.h5", float(E), soil_nu, params, wall_options,
                      sim, hits, seed + references + j)
        m = measure([rec], soil_nu, cp, "fem", wall_options, calibration=cal, device=device)
        td = api.tof_derivatives(float(E), soil_nu, cp, "fem", **wall_options)
        daq = _daq_scatter(cp, float(E), soil_nu, wall_options, settings)
        scatter = np.hypot(abs(float(td.dtof["striker_velocity"]) * cp.striker_velocity)
                           * striker_cov, daq)
        pred = predict(cp, wall_options, np.array([float(E)]), soil_nu, settings,
                       tof=np.array([float(td.tof)]), tof_scatter=np.array([scatter]),
                       noise_rms=settings.simulation.noise_rms, bias=np.zeros(1),
                       calibration=cal, model_error=model_error_of(cal))["tof"]
        budget = _budget(m)
        sigma = float(np.hypot(pred.sigma(hits)[0], budget))
        predicted = float(2.0 * np.sinh(Z95 * sigma))
        achieved = float((m.E_high - m.E_low) / m.E)
        rows.append({"E_true": float(E), "E": float(m.E), "E_low": float(m.E_low),
                     "E_high": float(m.E_high), "error": float(m.E / E - 1.0),
                     "width": achieved, "width_predicted": predicted,
                     "tof_scatter_predicted": float(scatter),
                     "tof_std_achieved": float(m.tof_std), "stated_terms": budget,
                     "width_ratio": achieved / predicted,
                     "inside": bool(m.E_low <= E <= m.E_high), "n_accepted": m.n_accepted})
    return {"calibration": {k: float(v) for k, v in cal.parameters.items()},
            "striker_cov": float(striker_cov), "hits": hits, "references": ref_rows,
            "unseen": rows}
