"""The contact forces a step applies: each law averaged over the step's relative motion.

Velocity Verlet's positions obey ``u_(n+1) - 2 u_n + u_(n-1) = dt^2 a(u_n)`` (Störmer's
form; Hairer, Lubich & Wanner 2006, sec. I.1.4), while the exact motion obeys::

    u(t + dt) - 2 u(t) + u(t - dt) = dt^2 <a>,  <a> = int_{-dt}^{dt} (dt - |s|) a(t + s) ds / dt^2,

the acceleration averaged with the hat weight of the two half-steps around ``t``. Taking
``a(u_n)`` for ``<a>`` errs by ``O(dt^2)`` where the force is smooth in time, an error that
is a smooth function of the run's parameters. The Hertz law ``A [d]_+^(3/2)`` and the
dashpot's switch at ``d = 0`` are not smooth where a contact opens or closes: there the
error depends on where the event falls between two steps (``O(dt^(5/2))``, oscillating
with that phase). The phase moves as a parameter moves the waves, so TOFs were noisy in
their parameters (~1e-6 relative between moduli 0.1 % apart, ``ssw bench smooth``) and
exact derivatives of the discrete TOF wiggled with it.

Here every bead-bead contact exerts the hat average of its law along the linear relative
motion ``d + s d'``, ``|s| <= dt`` (``delta = d' dt``, ``d'`` the
overlap's rate at the half step)::

    F = A |delta|^(3/2) psi(d / |delta|),
    psi(x) = [(x + 1)_+^(7/2) - 2 x_+^(7/2) + (x - 1)_+^(7/2)] / (35/4),

the second difference of the law's double antiderivative: exact for a linear motion, C3
in ``(d, delta)`` through the event, so that the impulse no longer depends on the event's
phase. Far from an event (``d >= FAR |delta|``) the same average is summed from its Taylor
series in ``r = (delta / d)^2``, ``F = A d^(3/2) [1 + r / 16 + r^2 / 640 + ...]`` (relative
truncation ``r^3 / 4096 < 4e-12`` there; no cancellation), which differs from the law by
``(delta / d)^2 / 16``, a part of the step's own ``O(dt^2)`` error: TOFs move by ~1e-6
relative, and nearer the independent DOP853 solution (10 MPa: -7.4e-5 instead of -7.7e-5).
The dashpot ``c d'`` acts with the hat-weighted share ``Phi(d / |delta|)`` of the two
half-steps the contact is closed (``Phi`` the hat's distribution function: 0 below -1,
``(1 + x)^2 / 2`` to 0, ``1 - (1 - x)^2 / 2`` to 1, 1 beyond), the exact average of its
switch along the linear motion, C1 (unchanged away from events).

Every dissipation law (:mod:`ssw.chain.dissipation`, damping ``c g(d) d'``) acts the same
way: the rate ``d'`` is the predicted new one, and its factor ``g`` the hat average of
``g(d + s d')`` along the step's linear motion, the second difference of ``g``'s double
antiderivative over ``delta^2``, everywhere (so that no switch between a point value and the
average breaks the smoothness): the dashpot's ``Phi`` (``g = [d > 0]``); the Kuwabara-Kono
factor (``g = sqrt(d_+)``)::

    <sqrt> = |delta|^(1/2) [(x + 1)_+^(5/2) - 2 x_+^(5/2) + (x - 1)_+^(5/2)] / (15/4),

C1 through the event, and far from it (``d >= FAR |delta|``) its series ``sqrt(d) [1 - r /
48 - r^2 / 384 - 3 r^3 / 4096 - ...]`` (the hat's moments ``<s^2> = 1/6``, ``<s^4> =
1/15``, ``<s^6> = 1/28`` times ``g``'s derivatives; truncation ``r^4 / 3500 < 1e-14``
there); the Hunt-Crossley factor (``g = F_el``) is the averaged Hertz force itself. Point
evaluation instead would bring back the event's phase the averaging removes: the factor
``sqrt(d)`` has an infinite slope at ``d = 0``, so its point value's error near an event is
``O(dt^(1/2))`` relative, not ``O(dt^2)``. The wall's law applies at
its point value (any law, and the same for a stateful wall's static limit: walls that
coincide give one TOF); the thesis device's wall stays closed under the chain's weight
through the first hit, so it has no event to smooth.

The step's code computes these laws (``ssw/chain/_step.c``, through
:mod:`ssw.chain.kernel`; :func:`ssw.chain.kernel.averaged_hertz` evaluates the force alone);
this module holds the constants the library is checked against when it loads.

References
----------
Hairer, E., Lubich, C. and Wanner, G. (2006). *Geometric Numerical Integration*, 2nd ed.,
Springer, sec. I.1.4 (Störmer-Verlet).
"""

from __future__ import annotations

#: ``d / |delta|`` from which the average is summed from its series.
FAR = 20.0
#: Coefficients of ``r`` and ``r^2`` of the series ``psi / d^(3/2) = 1 + r / 16 + r^2 / 640
#: + r^3 / 4096 + ...``: the terms ``delta^2 G''''/12 + delta^4 G^(6)/360 + ...`` of the
#: second difference of ``G = d^(7/2) / (35/4)``.
SERIES = (1.0 / 16.0, 1.0 / 640.0)
#: Coefficients of ``r``, ``r^2`` and ``r^3`` of the averaged square root's series
#: ``<sqrt> / d^(1/2) = 1 - r / 48 - r^2 / 384 - 3 r^3 / 4096 - ...`` (their negatives): the
#: terms ``delta^2 g^(2) / 12 + delta^4 g^(4) / 360 + delta^6 g^(6) / 20160`` of ``g =
#: d^(1/2)``.
ROOT_SERIES = (1.0 / 48.0, 1.0 / 384.0, 3.0 / 4096.0)
