"""What every constitutive model of a sample provides: the result of a strain-driven update,
the state layout, and the text of a model's key.

A model is a frozen, hashable parameter object (its strengths, Pa and degrees) with

* ``name`` (class attribute): the registry name (``von-mises``, ...);
* ``key``: a short file-name-safe text that tells two models apart (it enters the scene id);
* ``strength``: the reference stress (Pa) a contact pressure is compared with (the yield
  index of a measurement);
* ``update(E, nu, strain, state) -> Update``: the backward-Euler return mapping of a
  strain increment at many points at once (arrays of shape (n, ...), no loop per point);
* ``yield_ratio(stress, state)``: (n,) how far a stress is from yield: 1 on the yield
  surface, below 1 inside;
* ``params()``: the parameters as a plain dict (SI units);
* ``isochoric`` (class attribute, optional, default False): plastic flow keeps the volume,
  so the contact solver may use its mixed u-p form (exact and free of locking then).

The elastic constants (``E`` Pa, ``nu``) are the scene's, passed to ``update``: a model
holds only what elasticity does not say.

State. Every model stores per point the plastic strain (a Mandel 4-vector,
:mod:`ssw.constitutive.tensors`) and one hardening variable (von Mises: the accumulated
equivalent plastic strain; Drucker-Prager: ``sum sqrt(2/3) |d eps_p|``; crushable foam:
the work-conjugate equivalent plastic strain): ``state[:, :4]`` and ``state[:, 4]``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ssw.errors import ConfigError

#: Columns of a point's state: the plastic strain (4, Mandel) and the hardening variable.
STATE_SIZE = 5
#: A trial stress yields when its yield function exceeds this share of the strength: keeps
#: round-off (1e-16 relative) from flagging an elastic point plastic.
YIELD_RTOL = 1e-12


@dataclass(frozen=True)
class Update:
    """The result of a strain-driven update at ``n`` points. SI units.

    ``stress`` (n, 4) Pa (Mandel); ``tangent`` (n, 4, 4) Pa, the consistent tangent
    ``d stress / d strain``; ``state`` (n, 5) the new state; ``plastic`` (n,) bool, the
    step yielded; ``region`` (n,) int8, which return served (0 elastic, 1 smooth surface,
    2 a second surface, 3 a corner or apex), for the tests and the statistics.

    Parameters
    ----------
    stress : numpy.ndarray
        Stresses (Mandel, Pa), (n, 4).
    tangent : numpy.ndarray
        Consistent tangents (Pa), (n, 4, 4).
    state : numpy.ndarray
        New states, (n, 5).
    plastic : numpy.ndarray
        Whether the step yielded, (n,) bool.
    region : numpy.ndarray
        Which return served, (n,) int8.
    """

    stress: np.ndarray
    tangent: np.ndarray
    state: np.ndarray
    plastic: np.ndarray
    region: np.ndarray


def check_stress(model: Any, field: str, allowed: str, *, zero: bool = False) -> None:
    """Refuse a non-finite or negative stress (or modulus) ``field`` of a ``model`` (zero
    too unless ``zero``), naming the field, its value and ``allowed``.

    Parameters
    ----------
    model : Any
        The constitutive model.
    field : str
        Name of its stress or modulus field (Pa).
    allowed : str
        What the field accepts (the error's text).
    zero : bool
        Whether 0 is accepted.

    Raises
    ------
    ConfigError
        If the value is not finite, negative, or zero without ``zero``.
    """
    value = getattr(model, field)
    if not (np.isfinite(value) and (value >= 0 if zero else value > 0)):
        raise ConfigError(f"soil_model.{field}", value, allowed)


def initial_state(n: int) -> np.ndarray:
    """The virgin state of ``n`` points: no plastic strain, no hardening.

    Parameters
    ----------
    n : int
        Number of points.

    Returns
    -------
    numpy.ndarray
        Zeros, (n, STATE_SIZE).
    """
    return np.zeros((int(n), STATE_SIZE))


def number_text(x: float, unit: float = 1.0) -> str:
    """Short text of ``x / unit`` that reads back to ``x`` exactly (``g`` format when it
    does, else the shortest round-trip text); file-name safe (``e+`` written ``e``).

    Parameters
    ----------
    x : float
        The value (SI).
    unit : float
        The unit it is shown in (e.g. 1e6 for MPa).

    Returns
    -------
    str
        The text.
    """
    x = float(x)
    shown = x / unit
    for text in (format(shown, "g"), repr(shown)):
        if float(text) * unit == x:
            return text.replace("e+", "e")
    return repr(x).replace("e+", "e") + "SI"
