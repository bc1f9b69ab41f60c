"""The forward model of a calibration: TOF of the reference samples for many parameter sets.

A calibration asks, many times over, "what TOF does the device give on each reference sample
(E, nu) when its free parameters take the values theta?". :class:`TofModel` answers for a
whole table of parameter sets at once: the walls of the references are built once (their laws
do not depend on the free parameters), tiled over the parameter sets, and every set whose
integer parameters agree (the bead count) advances in ONE batched run of the integrator, the
continuous parameters (striker speed, preload, masses) varying per scene
(:class:`ssw.chain.params.Batch`). A set whose run fails (no reflected wave, a truncated
record) gets NaN, so a global scan over wide ranges never stops on one bad corner.

Every run of one model uses ONE time step, that of the fastest striker the scan may try
(:meth:`TofModel.fix_time_step`): otherwise the step would follow each batch's fastest
scene, and the O(dt^2) TOF error (up to 5e-5 relative at 80 steps per contact) would differ
from run to run, a noise the least squares would chase.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ssw.chain.params import VARYING, Batch, ChainParams, chain_params
from ssw.device import Device, parameter
from ssw.errors import ConfigError


@dataclass(frozen=True)
class Reference:
    """A reference sample: known E (Pa) and nu, the TOF measured on it (s) and the TOF's
    standard uncertainty (s; the standard error of its mean), or None if not known.

    Parameters
    ----------
    E : float
        Pa, the sample's known Young's modulus (> 0).
    nu : float
        -, its Poisson's ratio, in (-1, 0.5].
    tof : float
        s, the TOF measured on it (> 0).
    tof_std : float or None
        s, the TOF's standard uncertainty (standard error of its mean); None: not known.
    id : str
        The reference's name.
    source : str
        Where the TOF comes from (``given``, a recording, the published table).

    Raises
    ------
    ssw.errors.ConfigError
        A value out of its range, naming the reference and the field.
    """

    E: float
    nu: float
    tof: float
    tof_std: float | None = None
    id: str = ""
    source: str = "given"

    def __post_init__(self) -> None:
        if not (np.isfinite(self.E) and self.E > 0):
            raise ConfigError(f"reference {self.id or '?'}: E", self.E, "a modulus > 0 Pa")
        if not -1.0 < self.nu <= 0.5:
            raise ConfigError(f"reference {self.id or '?'}: nu", self.nu, "in (-1, 0.5]")
        if not (np.isfinite(self.tof) and self.tof > 0):
            raise ConfigError(f"reference {self.id or '?'}: TOF", self.tof, "a TOF > 0 s")
        if self.tof_std is not None and not (np.isfinite(self.tof_std) and self.tof_std > 0):
            raise ConfigError(f"reference {self.id or '?'}: TOF_STD", self.tof_std,
                              "a standard uncertainty > 0 s (or none)")


def parse_reference(text: str, index: int = 0) -> Reference:
    """``E,nu,TOF[,TOF_STD]`` (SI: Pa, -, s, s) from the command line.

    Parameters
    ----------
    text : str
        ``E,nu,TOF`` or ``E,nu,TOF,TOF_STD``.
    index : int
        The reference's position among the ``--reference`` options (its id ``ref<index>``).

    Returns
    -------
    Reference
        The reference.

    Raises
    ------
    ssw.errors.ConfigError
        Not three or four numbers (``--reference``), or a value out of range.
    """
    parts = [p.strip() for p in str(text).split(",")]
    if len(parts) not in (3, 4):
        raise ConfigError(f"--reference[{index}]", text, "E,nu,TOF or E,nu,TOF,TOF_STD (SI)")
    try:
        vals = [float(p) for p in parts]
    except ValueError as exc:
        raise ConfigError(f"--reference[{index}]", text, "numbers: E,nu,TOF[,TOF_STD]") from exc
    return Reference(vals[0], vals[1], vals[2], vals[3] if len(vals) == 4 else None,
                     id=f"ref{index}")


@dataclass
class TofModel:
    """TOF (s) of the references for parameter sets of the free device parameters.

    Parameters
    ----------
    device : ssw.device.Device
        The device (its values of the free parameters are the nominal ones).
    free : tuple of str
        Names of :data:`ssw.device.PARAMETERS` to identify.
    refs_E : numpy.ndarray
        The references' moduli, Pa.
    refs_nu : numpy.ndarray
        The references' Poisson's ratios.
    materials : dict
        The materials library (key -> Material).
    numerics : dict
        Non-device ChainParams fields (steps_per_contact, t_max, gravity, ...).
    wall : str
        The last-contact law's name (:data:`ssw.walls.WALLS`).
    wall_options : dict
        The wall builder's options.

    Other Parameters
    ----------------
    evaluations : int
        Parameter sets evaluated so far (a cost counter).
    runs : int
        Batched integrator runs so far.
    dt : float or None
        The time step of every run, s (``fix_time_step``); None: each run's own.
    on_run : callable or None
        Called after each batched run (a progress bar's update).
    _walls : object
        Internal: the walls built for the references (leave the default).
    _extremes : dict
        Internal: the extreme parameter values seen (leave the default).
    """

    device: Device
    free: tuple[str, ...]
    refs_E: np.ndarray
    refs_nu: np.ndarray
    materials: dict[str, Any]
    numerics: dict[str, Any]
    wall: str
    wall_options: dict[str, Any]
    evaluations: int = 0  # parameter sets evaluated (a cost counter)
    runs: int = 0  # batched integrator runs
    dt: float | None = None  # s, the time step of every run (fix_time_step)
    on_run: Any = None  # called after each batched run (a progress bar's update)
    _walls: Any = field(default=None, repr=False)
    _extremes: dict[str, float] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        self.refs_E = np.asarray(self.refs_E, float).ravel()
        self.refs_nu = np.asarray(self.refs_nu, float).ravel()
        if len(set(self.free)) != len(self.free) or not self.free:
            raise ConfigError("--free", list(self.free), "one or more distinct parameter names")
        for name in self.free:
            parameter(name)
        self.continuous = tuple(n for n in self.free if parameter(n).kind == "continuous")
        self.integers = tuple(n for n in self.free if parameter(n).kind == "integer")
        for name in self.continuous:
            if name not in VARYING:
                raise ConfigError("--free", name, f"a batched field: {', '.join(VARYING)}")

    @property
    def n_refs(self) -> int:
        """The number of references."""
        return int(self.refs_E.size)

    def params_for(self, values: dict[str, float]) -> ChainParams:
        """ChainParams of the device with ``values`` of the free parameters (one set).

        Parameters
        ----------
        values : dict of str to float
            Free parameter -> value, SI (integers rounded); the others nominal.

        Returns
        -------
        ssw.chain.params.ChainParams
            The device's chain with those values and the model's numerics.
        """
        return chain_params(self.device.with_(**_cast(values)), self.materials, **self.numerics)

    def walls(self) -> Any:
        """The references' walls, built once: no free parameter changes a wall law, but a
        law computed to a finite depth (``fem``: to the energy the chain can bring) is built
        for the most energetic set the scan may try (:meth:`fix_time_step`'s extremes).

        Returns
        -------
        object
            The walls of :func:`ssw.walls.build_wall` for the references.
        """
        if self._walls is None:
            from ssw.walls import build_wall

            params = self.params_for({})
            if self._extremes:
                params = params.with_(**{k: v for k, v in self._extremes.items()
                                         if k in ("striker_velocity", "preload",
                                                  "striker_mass")})
            self._walls = build_wall(self.wall, params, self.refs_E, self.refs_nu,
                                     **self.wall_options)
        return self._walls

    def fix_time_step(self, ranges: dict[str, tuple[float, float]]) -> float:
        """Fix the time step of every run: the integrator's step for the fastest and
        lightest striker of ``ranges`` (SI) on the stiffest reference wall.

        Parameters
        ----------
        ranges : dict of str to tuple of float
            ``(lo, hi)`` per free parameter, SI.

        Returns
        -------
        float
            s, the time step kept for every later run.
        """
        vals = {}
        for n in self.continuous:
            lo, hi = ranges[n]
            vals[n] = hi if n == "striker_velocity" else (lo if n.endswith("mass") else hi)
        # the walls' depth: the most energy (fastest, heaviest striker, largest preload)
        self._extremes = {n: ranges[n][1] for n in self.continuous
                          if n in ("striker_velocity", "preload", "striker_mass")}
        self._walls = None
        return self._set_time_step(vals, {n: ranges[n][1] for n in self.integers})

    def _set_time_step(self, vals: dict[str, float], ints: dict[str, float]) -> float:
        """The integrator's step (s) for the device with the integer values ``ints`` and the
        continuous ``vals`` on every reference wall, kept for every later run."""
        from ssw.chain.integrate import time_step

        b = Batch.of(self.params_for(ints), self.n_refs,
                     {k: np.full(self.n_refs, v) for k, v in vals.items()})
        self.dt = float(time_step(b, self.walls()))
        return self.dt

    def refix_time_step(self, theta: np.ndarray, ranges: dict[str, tuple[float, float]],
                        margin: float = 2.0) -> float:
        """Fix the time step for the refinement around the parameter sets ``theta`` (rows,
        ``free`` order): the step of ``margin`` times their fastest striker (capped at the
        scan's range), instead of the scan's fastest. One step for every later run, so the
        least squares compare TOFs of one discretization (module docstring).

        Parameters
        ----------
        theta : numpy.ndarray
            (m, len(free)) parameter sets, SI.
        ranges : dict of str to tuple of float
            ``(lo, hi)`` per free parameter, SI (caps the striker speed).
        margin : float
            -, factor on the fastest striker speed of ``theta``.

        Returns
        -------
        float
            s, the time step kept for every later run.
        """
        th = np.atleast_2d(np.asarray(theta, float))
        vals = {}
        if "striker_velocity" in self.continuous:
            j = self.free.index("striker_velocity")
            vals["striker_velocity"] = min(margin * float(np.max(th[:, j])),
                                           ranges["striker_velocity"][1])
        for n in ("striker_mass", "sensor_mass"):
            if n in self.continuous:
                vals[n] = float(np.min(th[:, self.free.index(n)]))
        ints = {n: float(np.max(th[:, self.free.index(n)])) for n in self.integers}
        return self._set_time_step(vals, ints)

    def __call__(self, theta: np.ndarray, refs: np.ndarray | None = None) -> np.ndarray:
        """TOF (s), shape (m, n_refs): rows of ``theta`` (m, len(free)) in SI units, columns
        the references (``refs``: a subset of their indices, default all). NaN where the
        run gives no TOF."""
        return self._run(theta, refs, False)[0]

    def forward(self) -> bool:
        """Whether the references' walls carry the forward sensitivities of every
        continuous free parameter (:func:`ssw.tof.api.forward_ok`): then
        :meth:`derivatives` is exact, else a calibration takes central differences.

        Returns
        -------
        bool
            True when every continuous free parameter has forward sensitivities.
        """
        from ssw.tof.api import forward_ok

        return bool(self.continuous) and all(
            forward_ok(self.walls(), self.continuous).values())

    def derivatives(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """TOFs and their exact derivatives in the continuous free parameters, from the
        runs that give the TOFs (the integrator's forward sensitivities,
        :mod:`ssw.chain.sensitivity`; the wall must have them: :meth:`forward`).

        Parameters
        ----------
        theta : numpy.ndarray
            (m, len(free)) parameter sets, SI.

        Returns
        -------
        tuple of numpy.ndarray
            ``values`` (m, n_refs) s and ``jacobian`` (m, n_refs, len(continuous)) s per SI
            unit of each continuous free parameter (:mod:`ssw.calibration.residuals`'s
            ``derivatives(theta)``); NaN where the run gives no TOF.
        """
        return self._run(theta, None, True)

    def _run(self, theta: np.ndarray, refs: np.ndarray | None, tangent: bool
             ) -> tuple[np.ndarray, np.ndarray | None]:
        """TOFs (m, k) and, with ``tangent``, their derivatives (m, k, p)."""
        from ssw.chain.run import run_peaks

        th = np.atleast_2d(np.asarray(theta, float))
        if th.shape[1] != len(self.free):
            raise ValueError(f"theta has {th.shape[1]} columns for {len(self.free)} parameters")
        idx = np.arange(self.n_refs) if refs is None else np.asarray(refs, int)
        m, k = th.shape[0], idx.size
        p = len(self.continuous)
        out = np.full((m, k), np.nan)
        jac = np.full((m, k, p), np.nan) if tangent else None
        cols = {name: th[:, j] for j, name in enumerate(self.free)}
        ints = np.stack([np.rint(cols[n]) for n in self.integers], axis=1) if self.integers \
            else np.zeros((m, 0))
        walls = self.walls()
        for combo in np.unique(ints, axis=0):
            rows = np.flatnonzero(np.all(ints == combo, axis=1))
            base = self.params_for({n: float(v) for n, v in zip(self.integers, combo,
                                                                 strict=True)})
            vary = {n: np.repeat(cols[n][rows], k) for n in self.continuous}
            batch = Batch.of(base, rows.size * k, vary)
            w = walls.take(np.tile(idx, rows.size))
            pk, _ = run_peaks(batch, w, strict=False, dt=self.dt,
                              derivatives=self.continuous if tangent and p else None)
            out[rows] = pk.tof.reshape(rows.size, k)
            if jac is not None:
                jac[rows] = np.asarray(pk.dtof, float).reshape(rows.size, k, p)
            self.runs += 1
            if self.on_run is not None:
                self.on_run(1, sets=self.evaluations + m)
        self.evaluations += m
        return out, jac


def _cast(values: dict[str, float]) -> dict[str, Any]:
    """Integer parameters as ints."""
    return {k: (round(float(v)) if parameter(k).kind == "integer" else float(v))
            for k, v in values.items()}
