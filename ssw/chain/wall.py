"""The chain's last contact: the protocol the integrator needs of a wall.

A wall law gives the force ``F(d)`` (N) at the last bead's indentation ``d = u_{N-1}`` (m,
``[d]_+``: no tension), batched over scenes (one law per scene). The chain knows only the
protocols: :class:`Wall` (a law of the indentation) and :class:`StatefulWall` (a wall with
internal state: the soil's motion, a sample's history), with :func:`force_and_tangent`
(a law's force and its derivatives), :func:`is_stateful` and :func:`beyond_exact_reach`
(the scenes that went deeper than a law's exact part reaches).

The laws made of the chain's numbers live beside it and are importable from here:
:mod:`ssw.chain.wall_power` (``rigid``, ``hertz`` and the fitted laws,
:class:`~ssw.chain.wall_power.PowerWall`), :mod:`ssw.chain.wall_table` (a FEM curve
interpolated, :class:`~ssw.chain.wall_table.TableWall`) and what they share,
:mod:`ssw.chain.wall_base` (the scenes' arrays, the bead's compliance, a monotone law's
inverse). The laws that need the contact FEM, the fitted tables or the soil's
dynamics, and the registry of every law by name, live above the chain in :mod:`ssw.walls`.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

# the laws made of the chain's numbers, importable where the chain's users look for them
from ssw.chain.wall_base import compliance_scale as compliance_scale
from ssw.chain.wall_base import compliance_scale_dE as compliance_scale_dE
from ssw.chain.wall_base import force_indentation as force_indentation
from ssw.chain.wall_base import scene_arrays as scene_arrays
from ssw.chain.wall_power import PowerWall as PowerWall
from ssw.chain.wall_power import fit_wall as fit_wall
from ssw.chain.wall_power import hertz_wall as hertz_wall
from ssw.chain.wall_power import rigid_wall as rigid_wall
from ssw.chain.wall_table import TABLE_CELLS as TABLE_CELLS
from ssw.chain.wall_table import TABLE_TAIL as TABLE_TAIL
from ssw.chain.wall_table import TableWall as TableWall
from ssw.chain.wall_table import table_wall as table_wall


def beyond_exact_reach(wall: Any, peak_indentation: np.ndarray) -> np.ndarray:
    """The scenes whose last bead went deeper than the wall's exact law reaches.

    Parameters
    ----------
    wall : Wall
        The last contact (its ``exact_reach``, m: a tabulated FEM curve's end, the FEM
        law's computed range; none for a law defined at any depth).
    peak_indentation : numpy.ndarray
        (n,) m, the run's largest indentations.

    Returns
    -------
    numpy.ndarray
        (n,) bool: where the force was an extension, not the model.
    """
    reach = getattr(wall, "exact_reach", None)
    peak = np.asarray(peak_indentation, float)
    if reach is None:
        return np.zeros(peak.shape, bool)
    return peak > np.asarray(reach, float) * (1.0 + 1e-9)


class Wall(Protocol):
    """What the integrator needs of a last-contact law (one law per scene, ``n`` scenes).

    Every method is vectorized over the scenes: arrays of shape (n,), SI units.
    ``take(idx)`` selects scenes by index; ``idx`` may repeat one (a calibration scan
    tiles the walls of a few references over many parameter sets).

    Parameters
    ----------
    *args : Any
        Unused: a protocol is not instantiated.
    **kwargs : Any
        Unused: a protocol is not instantiated.
    """

    @property
    def n(self) -> int:
        """Number of scenes."""
        ...

    def force(self, d: np.ndarray) -> np.ndarray:
        """Wall force (N) at indentation ``d`` (m); 0 for ``d <= 0``.

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Force (N), (n,).
        """

    def potential(self, d: np.ndarray) -> np.ndarray:
        """Stored energy ``int_0^d F`` (J).

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Stored energy (J), (n,).
        """

    def indentation(self, F: np.ndarray) -> np.ndarray:
        """Indentation (m) carrying the force ``F >= 0`` (N): the inverse of :meth:`force`.

        Parameters
        ----------
        F : numpy.ndarray
            Forces (N), (n,), >= 0.

        Returns
        -------
        numpy.ndarray
            Indentation (m), (n,).
        """

    def take(self, idx: np.ndarray) -> Wall:
        """The scenes ``idx`` (may repeat).

        Parameters
        ----------
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        Wall
            The law of the selected scenes.
        """
        ...

    def hertz_equivalent(self, d_ref: float) -> np.ndarray:
        """``F(d_ref) / d_ref^1.5`` (N/m^1.5), for the time-step choice.

        Parameters
        ----------
        d_ref : float
            Reference indentation (m), > 0.

        Returns
        -------
        numpy.ndarray
            Equivalent Hertz coefficient (N/m^1.5), (n,).
        """


def force_and_tangent(wall: Wall, d: np.ndarray, with_E: bool
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """A displacement wall's force, its tangent stiffness and (with ``with_E``) ``dF/dE`` at
    ``d``: the wall's own fused evaluation where it has one (``force_and_tangent``, e.g.
    :meth:`ssw.walls.fem.PiecewiseLinearWall.force_and_tangent`: one search of its pieces
    for the three), else its ``force``, ``dforce_dd`` and ``dforce_dE``.

    Parameters
    ----------
    wall : Wall
        The law, with ``dforce_dd`` (and ``dforce_dE`` for ``with_E``).
    d : numpy.ndarray
        Indentations (m), (n,).
    with_E : bool
        Whether ``dF/dE`` is wanted.

    Returns
    -------
    tuple
        ``(F, dF/dd, dF/dE)``: N, N/m and N/Pa, (n,) each; ``dF/dE`` None without
        ``with_E``.
    """
    fused = getattr(wall, "force_and_tangent", None)
    if fused is not None:
        return fused(d, with_E)
    w: Any = wall
    return w.force(d), w.dforce_dd(d), (w.dforce_dE(d) if with_E else None)


class StatefulWall(Protocol):
    """A last contact with internal state (the soil's motion, a sample's history).

    The integrator (:func:`ssw.chain.integrate.simulate`) keeps Verlet's structure
    (Hairer, Lubich & Wanner 2006, sec. I.1.4): each step drifts the positions, then
    evaluates the forces at the new positions, here

        F_wall(n+1), state(n+1) = wall.advance(state(n), u_last(n+1), dt),

    the wall integrating its own state over the step (implicitly if it likes: stiff
    internal dynamics cost nothing in step size) from the bead's new position only, so that
    the scheme stays explicit for the chain. Besides :class:`Wall`'s ``n``,
    ``indentation`` (the statics of the initial state), ``hertz_equivalent`` (the step)
    and ``take``, such a wall has (vectorized over ``n`` scenes, SI):

    * ``force(d)``: the force of the state at rest at ``d`` (the first step's);
    * ``start(d0) -> state``: the state at rest with the last beads at ``d0`` (m);
    * ``advance(state, d, dt) -> (F, state)``;
    * ``energy(state) -> (stored, dissipated)`` (J, (n,)): what the wall holds and what it
      radiated or dissipated so far (the run's energy record uses it instead of
      ``potential``);
    * ``take_state(state, idx)``: select scenes;
    * optionally ``dt`` (s): the step the wall was built for (a FEM's factorization).

    Exact forward sensitivities (:mod:`ssw.chain.sensitivity`) need two more methods:
    ``start_tangent(state, D0, dE) -> tstate`` and ``advance_tangent(state, tstate, d, D,
    dt, dE) -> (F, dF, state, tstate)``, ``D`` (n, k) the derivatives of the indentation
    with respect to the ``k`` parameters, ``dE`` (n, k) those of the soil's modulus, ``dF``
    (n, k) the force's; a wall without them is differentiated by central differences of
    its TOF (:mod:`ssw.tof.api`).

    Parameters
    ----------
    *args : Any
        Unused: a protocol is not instantiated.
    **kwargs : Any
        Unused: a protocol is not instantiated.
    """

    @property
    def n(self) -> int:
        """Number of scenes."""
        ...

    def force(self, d: np.ndarray) -> np.ndarray:
        """Force (N) of the state at rest at indentation ``d`` (the first step's).

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Force (N), (n,).
        """
        ...

    def indentation(self, F: np.ndarray) -> np.ndarray:
        """Indentation (m) at rest under force ``F`` (the initial state's statics).

        Parameters
        ----------
        F : numpy.ndarray
            Forces (N), (n,), >= 0.

        Returns
        -------
        numpy.ndarray
            Indentation (m), (n,).
        """
        ...

    def hertz_equivalent(self, d_ref: float) -> np.ndarray:
        """``F(d_ref) / d_ref^1.5`` (N/m^1.5), for the time-step choice.

        Parameters
        ----------
        d_ref : float
            Reference indentation (m), > 0.

        Returns
        -------
        numpy.ndarray
            Equivalent Hertz coefficient (N/m^1.5), (n,).
        """
        ...

    def start(self, d0: np.ndarray) -> Any:
        """The state at rest with the last beads at ``d0``.

        Parameters
        ----------
        d0 : numpy.ndarray
            Initial indentations (m), (n,).

        Returns
        -------
        Any
            The wall's state.
        """
        ...

    def advance(self, state: Any, d: np.ndarray, dt: float) -> tuple[np.ndarray, Any]:
        """Integrate the wall's state over one step to the bead's new position.

        Parameters
        ----------
        state : Any
            The state at the step's start.
        d : numpy.ndarray
            Indentations (m) at the step's end, (n,).
        dt : float
            Time step (s).

        Returns
        -------
        tuple
            ``(F, state)``: the force (N), (n,), and the state at the step's end.
        """
        ...

    def energy(self, state: Any) -> tuple[np.ndarray, np.ndarray]:
        """Energy the wall holds and the energy it radiated or dissipated so far.

        Parameters
        ----------
        state : Any
            The wall's state.

        Returns
        -------
        tuple
            ``(stored, dissipated)``: J, (n,) each.
        """
        ...

    def take(self, idx: np.ndarray) -> StatefulWall:
        """The scenes ``idx`` (may repeat).

        Parameters
        ----------
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        StatefulWall
            The wall of the selected scenes.
        """
        ...

    def take_state(self, state: Any, idx: np.ndarray) -> Any:
        """The state of the scenes ``idx``.

        Parameters
        ----------
        state : Any
            The wall's state.
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        Any
            The state of the selected scenes.
        """
        ...


def is_stateful(wall: Any) -> bool:
    """Whether ``wall`` has internal state (:class:`StatefulWall`).

    Parameters
    ----------
    wall : Any
        A last-contact law.

    Returns
    -------
    bool
        True if it has an ``advance`` method.
    """
    return hasattr(wall, "advance")
