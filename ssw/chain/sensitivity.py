"""Forward sensitivities of the chain: which parameters, and how each enters the scheme.

The integrator (:func:`ssw.chain.integrate.simulate`) can carry, alongside the positions
``u`` and velocities ``v`` (N, n), their derivatives ``U = du/dp`` and ``V = dv/dp``
(N, n, k) with respect to ``k`` parameters ``p``. Differentiating each line of the velocity
Verlet step gives the same step for the derivatives (the tangent linear scheme; Hairer,
Lubich & Wanner 2006, sec. VI.5 for variational equations of symplectic maps):

    V <- V + dt/2 A,   U <- U + dt V,   A <- da/du U + da/dv V' + da/dp,   V <- V + dt/2 A,

``A = da/dp`` along the discrete trajectory, ``V'`` the derivative of the velocity the
damping is evaluated at. The result is the exact derivative of the *discrete* solution at
the run's fixed step ``dt`` (a run with a perturbed parameter and the same ``dt`` differs
by the derivative times the perturbation, to second order). How each parameter enters
(:data:`PARAMETERS`):

* ``E`` (Pa): the soil's modulus, through the wall law only: ``dF_wall/dE`` at fixed
  indentation (``wall.dforce_dE``; a stateful wall's ``advance_tangent``), and the static
  indentation of the initial state;
* ``striker_velocity`` (m/s): the striker's initial speed;
* ``preload`` (N): the force on bead 1 (statics and dynamics);
* ``sensor_mass``, ``striker_mass`` (kg): the masses of the sensor particle and of the
  striker (the statics' weights, the accelerations ``F / m``); a ``uniform`` chain's
  sensor has a bead's mass whatever ``sensor_mass`` says (derivative 0);
* ``damping`` (the law's unit: N s/m for the dashpot): the dissipation coefficient ``c``
  of every closed contact, whatever its law (:mod:`ssw.chain.dissipation`).

The same names are the device's calibratable continuous parameters
(:data:`ssw.device.PARAMETERS`) plus the soil's modulus and the dissipation.

The step itself. The step is a fixed fraction of a Hertz contact time at the striker speed
(:func:`ssw.chain.integrate.time_step`), so a TOF computed at the step its parameters give
moves with the striker's speed and mass (``t_c ~ (m^2 / v)^(1/5)``: 1-3e-4 of the striker
speed's derivative on the thesis device) through the step as well. A run may carry the
step's own column, :data:`STEP` (``dt``, s): the derivative of the discrete solution with
respect to ``dt`` at a fixed number of steps, the scheme differentiated line by line in its
explicit ``dt`` too (the drift's and the kicks' ``dt``, the averaging's ``|delta| = |d'|
dt``, the predicted velocity's ``dt/2 a``); the record's times ``t_n = n dt`` enter on the
dense output (:mod:`ssw.chain.dense`). The chain rule with the step's analytic derivative
(:func:`ssw.chain.integrate.step_tangent`) then gives the derivative of the TOF a run at the
parameters' own step computes (:func:`ssw.chain.run.run_peaks` without ``dt``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ssw.errors import ConfigError

#: Parameters the chain differentiates with respect to, and their SI units.
PARAMETERS: dict[str, str] = {
    "E": "Pa",
    "striker_velocity": "m/s",
    "preload": "N",
    "sensor_mass": "kg",
    "striker_mass": "kg",
    "damping": "N s/m",
}


def units(damping_law: str) -> dict[str, str]:
    """:data:`PARAMETERS`' SI units with the dissipation coefficient's in the law's unit.

    Parameters
    ----------
    damping_law : str
        A name of :data:`ssw.chain.dissipation.LAWS`.

    Returns
    -------
    dict
        Name -> unit.
    """
    from ssw.chain.dissipation import law_of

    return {**PARAMETERS, "damping": law_of(damping_law, "chain.damping_law").unit}


#: The time step's own column (s): carried on request (module docstring), not a parameter.
STEP = "dt"
#: Parameters the step depends on (:func:`ssw.chain.integrate.time_step`: the Hertz contact
#: time of the striker on bead 1 and of the last bead on a rigid flat; ``sensor_mass``
#: when the sensor is bead 1, ``E`` only for a wall stiffer than a rigid flat).
MOVES_STEP = ("striker_velocity", "striker_mass", "sensor_mass", "E")


@dataclass(frozen=True)
class Tangent:
    """The parameters a run differentiates with respect to (the columns of its
    sensitivity arrays, in this order).

    Parameters
    ----------
    names : tuple of str
        Names of :data:`PARAMETERS`, each at most once, and :data:`STEP` (the step's own
        column).
    """

    names: tuple[str, ...]

    def __post_init__(self) -> None:
        bad = [n for n in self.names if n not in PARAMETERS and n != STEP]
        if bad or len(set(self.names)) != len(self.names) or not self.names:
            raise ConfigError("derivatives", list(self.names),
                              f"one or more distinct names of {', '.join(PARAMETERS)}")

    @property
    def parameters(self) -> tuple[str, ...]:
        """The names without :data:`STEP`."""
        return tuple(n for n in self.names if n != STEP)

    def with_step(self) -> Tangent:
        """These columns and the step's (:data:`STEP`) last.

        Returns
        -------
        Tangent
            The tangent with the step's column last.
        """
        return self if STEP in self.names else Tangent((*self.names, STEP))

    @property
    def k(self) -> int:
        """Number of parameters."""
        return len(self.names)

    def col(self, name: str) -> int | None:
        """Column of ``name`` (None if not requested).

        Parameters
        ----------
        name : str
            A parameter's name.

        Returns
        -------
        int or None
            Its column in the tangent, or None.
        """
        return self.names.index(name) if name in self.names else None


def tangent_of(names: Tangent | str | list[str] | tuple[str, ...] | None) -> Tangent | None:
    """A :class:`Tangent` from names (a comma-separated string, a sequence, or one already
    made); None for None.

    Parameters
    ----------
    names : Tangent or str or sequence of str or None
        The parameters.

    Returns
    -------
    Tangent or None
        The validated parameter set.

    Raises
    ------
    ConfigError
        An unknown or repeated name.
    """
    if names is None or isinstance(names, Tangent):
        return names
    if isinstance(names, str):
        names = [x.strip() for x in names.split(",") if x.strip()]
    return Tangent(tuple(names))


#: Relative step of the central differences (of the value, or of 1 SI unit when the value
#: is 0): TOFs are smooth to ~1e-10 relative, so the differences' error is their
#: truncation (tests/test_tof_derivatives.py).
CENTRAL_STEP = 1e-4
#: Difference stencils for walls without forward sensitivities: order -> (central,
#: one-sided at a lower bound of 0: a preload or a dashpot of 0), each (offsets in steps,
#: weights, denominator in steps).
STENCILS = {
    2: ((np.array([-1.0, 1.0]), np.array([-1.0, 1.0]), 2.0),
        (np.arange(3.0), np.array([-3.0, 4.0, -1.0]), 2.0)),
    4: ((np.array([-2.0, -1.0, 1.0, 2.0]), np.array([1.0, -8.0, 8.0, -1.0]), 12.0),
        (np.arange(5.0), np.array([-25.0, 48.0, -36.0, 16.0, -3.0]), 12.0)),
}
#: Parameters that may not go below 0.
NON_NEGATIVE = ("preload", "damping")


@dataclass(frozen=True)
class Stencil:
    """A difference stencil for one parameter: evaluate at ``value + offsets h`` and combine
    with :meth:`derivative`.

    Parameters
    ----------
    offsets : numpy.ndarray
        Offsets in steps.
    weights : numpy.ndarray
        Weights of the values.
    denominator : float
        Steps the weighted sum is divided by (times ``h``).
    h : numpy.ndarray
        (n,) the step per scene (the parameter's SI unit).
    """

    offsets: np.ndarray
    weights: np.ndarray
    denominator: float
    h: np.ndarray

    def derivative(self, values: list[np.ndarray]) -> np.ndarray:
        """The derivative from the values at the offsets (one array each).

        ``sum_i w_i f(x + o_i h) / (denominator h)``.

        Parameters
        ----------
        values : list of numpy.ndarray
            The quantity at each offset of ``offsets``, in their order, (n,) each.

        Returns
        -------
        numpy.ndarray
            The derivative (the quantity's unit per the parameter's), (n,).
        """
        total = sum(w * v for w, v in zip(self.weights, values, strict=True))
        return total / (self.denominator * self.h)


def stencil(name: str, value: np.ndarray, rel: float = CENTRAL_STEP, order: int = 4
            ) -> Stencil:
    """The difference stencil of parameter ``name`` at ``value`` (:data:`STENCILS`): central,
    or one-sided where a non-negative parameter would go below 0.

    Parameters
    ----------
    name : str
        A name of :data:`PARAMETERS`.
    value : numpy.ndarray
        (n,) the parameter per scene (SI).
    rel : float
        Relative step (of 1 SI unit where the value is 0).
    order : int
        2 or 4.

    Returns
    -------
    Stencil
        Offsets, weights and steps.
    """
    value = np.asarray(value, float)
    h = rel * np.where(value != 0, np.abs(value), 1.0)
    central, one_sided = STENCILS[order]
    reach = np.max(np.abs(central[0]))
    at_bound = name in NON_NEGATIVE and bool(np.any(value - reach * h < 0))
    offsets, weights, den = one_sided if at_bound else central
    return Stencil(offsets, weights, den, h)
