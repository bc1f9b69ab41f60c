"""Forward sensitivities of the chain: which parameters, and how each enters the scheme.

The integrator (:func:`ssw.chain.integrate.simulate`) can carry, alongside the positions
``u`` and velocities ``v`` (N, n), their derivatives ``U = du/dp`` and ``V = dv/dp``
(N, n, k) with respect to ``k`` parameters ``p``. Differentiating each line of the velocity
Verlet step gives the same step for the derivatives (the tangent linear scheme; Hairer,
Lubich & Wanner 2006, sec. VI.5 for variational equations of symplectic maps):

    V <- V + dt/2 A,   U <- U + dt V,   A <- da/du U + da/dv V' + da/dp,   V <- V + dt/2 A,

``A = da/dp`` along the discrete trajectory, ``V'`` the derivative of the velocity the
dashpot is evaluated at. The result is the exact derivative of the *discrete* solution at
the run's fixed step ``dt`` (the step is a numerical setting, held fixed: a run with a
perturbed parameter and the same ``dt`` differs by the derivative times the perturbation,
to second order). How each parameter enters (:data:`PARAMETERS`):

* ``E`` (Pa): the soil's modulus, through the wall law only: ``dF_wall/dE`` at fixed
  indentation (``wall.dforce_dE``; a stateful wall's ``advance_tangent``), and the static
  indentation of the initial state;
* ``striker_velocity`` (m/s): the striker's initial speed;
* ``preload`` (N): the force on bead 1 (statics and dynamics);
* ``sensor_mass``, ``striker_mass`` (kg): the masses of the sensor particle and of the
  striker (the statics' weights, the accelerations ``F / m``); a ``uniform`` chain's
  sensor has a bead's mass whatever ``sensor_mass`` says (derivative 0);
* ``damping`` (N s/m): the contact dashpot ``c (v_j - v_{j+1})`` of every closed contact.

The same names are the device's calibratable continuous parameters
(:data:`ssw.device.PARAMETERS`) plus the soil's modulus and the dashpot.
"""

from __future__ import annotations

from dataclasses import dataclass

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


@dataclass(frozen=True)
class Tangent:
    """The parameters a run differentiates with respect to (the columns of its
    sensitivity arrays, in this order).

    Attributes
    ----------
    names : tuple of str
        Names of :data:`PARAMETERS`, each at most once.
    """

    names: tuple[str, ...]

    def __post_init__(self) -> None:
        bad = [n for n in self.names if n not in PARAMETERS]
        if bad or len(set(self.names)) != len(self.names) or not self.names:
            raise ConfigError("derivatives", list(self.names),
                              f"one or more distinct names of {', '.join(PARAMETERS)}")

    @property
    def k(self) -> int:
        """Number of parameters."""
        return len(self.names)

    def col(self, name: str) -> int | None:
        """Column of ``name`` (None if not requested)."""
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
