"""Dissipation laws of the chain's contacts: which damping force a closed contact adds to its
elastic one, by name (:data:`LAWS`), like the wall laws of :mod:`ssw.walls`.

Every law adds, in a closed contact of overlap ``d > 0`` (m) and overlap rate ``d'`` (m/s),
a force ``c g(d) d'``: the coefficient ``c`` (``ChainParams.damping``, in the law's
``unit``) times the law's factor ``g`` times the rate. The same law and
coefficient act in every bead-bead contact and at the wall (the last contact, ``d`` the
last bead's indentation):

* ``dashpot``: ``g = 1``, a linear viscous dashpot (``c`` N s/m);
* ``kuwabara_kono``: ``g = sqrt(d)``, the viscoelastic sphere (``c`` N s/m^1.5): Kuwabara &
  Kono (1987) and Brilliantov et al. (1996), ``F = A (d^(3/2) + 3/2 tau sqrt(d) d')``,
  so ``c = 3/2 A tau`` with ``tau`` the material's dissipative time;
* ``hunt_crossley``: ``g = F_el(d)``, the contact's own elastic force (``c`` s/m): Hunt &
  Crossley (1975), the damping in proportion to the elastic force (``c = 3 (1 - e) / (2
  v)`` for a restitution coefficient ``e`` at impact speed ``v``); at the wall ``F_el`` is
  the wall's force at its point value (a stateful wall's as it reports it: the reduced
  dynamic wall's with its radiation dashpot and participating mass).

No clamp: a contact opening fast may pull (``d' < 0``), as the dashpot does. The rate ``d'``
the step uses is the predicted new one, and the factor ``g`` the hat average of ``g(d + s
d')`` over the step's relative motion ``|s| <= dt`` (:mod:`ssw.chain.impulse`: the share
``Phi`` the dashpot is closed, the averaged ``sqrt``, the averaged Hertz force): the
discrete solution stays smooth in its parameters through contact events. The step's code
evaluates the laws (``ssw/chain/_step.c``, the law's ``code``); the
factors here, :meth:`DissipationLaw.factor`, are their point values (the independent
references', ``ssw.chain.baseline``).

Each law states a typical scale and a plausible range of its coefficient for a calibration
(:func:`parameter`): the dashpot's are the waveform calibration's (scale 5 N s/m, range
0-100 N s/m); the others' are the same damping forces at the thesis chain's impact (the
striker at 0.5247 m/s on bead 1: peak overlap ``d_max = 1.19e-5`` m, ``sqrt(d_max) =
3.45e-3`` m^0.5, peak force ``F_max = 409`` N, :func:`ssw.chain.integrate.impact_scales`):
``c_KK = c_dashpot / sqrt(d_max)``, ``c_HC = c_dashpot / F_max``. A Hunt-Crossley ``c`` of
0.25 s/m is a restitution coefficient of 0.92 at 0.5 m/s; a Kuwabara-Kono ``c`` of 1.5e3 N
s/m^1.5 a dissipative time of 0.1 us for the chain's beads (``A = 1.0e10`` N/m^1.5).

References
----------
Brilliantov, N. V., Spahn, F., Hertzsch, J.-M. and Poschel, T. (1996). Model for collisions
in granular gases. Phys. Rev. E 53, 5382-5392.
Hunt, K. H. and Crossley, F. R. E. (1975). Coefficient of restitution interpreted as damping
in vibroimpact. J. Appl. Mech. 42, 440-445.
Kuwabara, G. and Kono, K. (1987). Restitution coefficient in a collision between two
spheres. Jpn. J. Appl. Phys. 26, 1230-1233.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ssw.errors import ConfigError


@dataclass(frozen=True)
class DissipationLaw:
    """One dissipation law of the contacts (module docstring).

    Parameters
    ----------
    name : str
        The law's name (a device file's ``dissipation.law``).
    code : int
        Its index in the compiled step (``ssw_chain.law``).
    unit : str
        The coefficient's SI unit.
    scale : float
        A typical coefficient (its unit): the calibration's scaled coordinate.
    upper : float
        The largest plausible coefficient (its unit; the smallest is 0, conservative).
    formula : str
        The damping force of a closed contact.
    source : str
        Where the law comes from.
    """

    name: str
    code: int
    unit: str
    scale: float
    upper: float
    formula: str
    source: str

    def factor(self, d: Any, f_el: Any) -> np.ndarray:
        """The law's factor ``g`` of a closed contact at its point value: the damping force
        is ``c g d'``.

        Parameters
        ----------
        d : array_like
            m, the overlap (``> 0``: closed; 0 is returned where ``d <= 0``).
        f_el : array_like
            N, the contact's elastic force (broadcast with ``d``; read by
            ``hunt_crossley`` only).

        Returns
        -------
        numpy.ndarray
            The factor (1, m^0.5 or N), 0 where the contact is open.
        """
        d = np.asarray(d, float)
        closed = d > 0
        if self.name == "dashpot":
            g = np.ones_like(d)
        elif self.name == "kuwabara_kono":
            g = np.sqrt(np.where(closed, d, 0.0))
        else:
            g = np.broadcast_to(np.asarray(f_el, float), d.shape)
        return np.where(closed, g, 0.0)


#: The dissipation laws by name (module docstring).
LAWS: dict[str, DissipationLaw] = {law.name: law for law in (
    DissipationLaw("dashpot", 0, "N s/m", 5.0, 100.0, "c d'",
                   "a linear viscous dashpot"),
    DissipationLaw("kuwabara_kono", 1, "N s/m^1.5", 1.5e3, 3.0e4, "c sqrt(d) d'",
                   "Kuwabara & Kono 1987; Brilliantov et al. 1996, Phys. Rev. E 53:5382"),
    DissipationLaw("hunt_crossley", 2, "s/m", 1.25e-2, 0.25, "c F_el(d) d'",
                   "Hunt & Crossley 1975, J. Appl. Mech. 42:440"),
)}
#: The law of a device that states none (conservative with a coefficient of 0).
DEFAULT_LAW = "dashpot"


def law_of(name: str, field: str = "dissipation.law") -> DissipationLaw:
    """The law ``name`` of :data:`LAWS`.

    Parameters
    ----------
    name : str
        A law's name.
    field : str
        The field named in the error (a device file's ``dissipation.law``, a flag).

    Returns
    -------
    DissipationLaw
        The law.

    Raises
    ------
    ConfigError
        An unknown name, listing the laws.
    """
    if name not in LAWS:
        raise ConfigError(field, name, " | ".join(LAWS) + " (the device file's "
                          "dissipation.law, or --damping-law)")
    return LAWS[name]


def parameter(law: str, name: str = "damping") -> Any:
    """The coefficient of ``law`` as a calibratable parameter: its unit, range (0 to the
    law's ``upper``) and linear scaled coordinate (``c / scale``), for a calibration that
    fits it under any law (the waveform level's global ``damping``).

    Parameters
    ----------
    law : str
        A name of :data:`LAWS`.
    name : str
        The parameter's name.

    Returns
    -------
    ssw.device.Parameter
        ``continuous``, linear (``log`` False: 0 is allowed), the law's unit and scale.
    """
    from ssw.device import Parameter

    d = law_of(law)
    return Parameter(name, d.unit, "continuous", 0.0, d.upper, False, d.scale,
                     f"the contact dissipation, {d.formula} ({d.name}) in every closed "
                     "contact")
