"""Surface compliance of a layered elastic half-space under axisymmetric normal load.

The transfer-matrix kernel of the layered oracle (:mod:`ssw.contact.layered`): elastic
layers (an elastic plate, optionally a soil of finite depth) over an elastic half-space or
a rigid base, each interface bonded or frictionless (Burmister 1945; the Hankel-transform
method of Sneddon 1951, ch. 10; Johnson 1985, sec. 3.9).

In each body the field comes from Love's strain function, ``phi = f(z) J0(xi r)`` with
``f = (c1 + c2 xi z) e^(-xi z) + (c3 + c4 xi z) e^(xi z)`` (``nabla^4 phi = 0``; z
downward; Timoshenko & Goodier 1970, sec. 130):

* ``2 G u_z = (1 - 2 nu) f'' - 2 (1 - nu) xi^2 f``  (times ``J0(xi r)``),
* ``2 G u_r = xi f'``  (times ``J1(xi r)``),
* ``sigma_zz = (1 - nu) f''' - (2 - nu) xi^2 f'``  (times ``J0``),
* ``sigma_rz = xi [nu f'' + (1 - nu) xi^2 f]``  (times ``J1``).

Everything scales with ``xi``: the problem is solved at ``xi = 1`` with the layers'
thicknesses ``t_k = xi h_k``. The growing exponentials are written about the bottom of
their layer, ``e^(xi (z - z_bottom))`` (the exponentially scaled form), so no term exceeds
1 and nothing overflows for any ``xi h``. A half-space keeps only its decaying modes. The
surface (traction ``-p``, no shear), the interfaces (bonded: ``u_z, u_r, sigma_zz,
sigma_rz`` continuous; frictionless: ``u_z, sigma_zz`` continuous and no shear on either
side) and the base (rigid bonded: ``u = 0``; rigid frictionless: ``u_z = 0``, no shear)
give a square system of ``4 n_layers + 2`` (elastic base) or ``4 n_layers`` (rigid base)
unknowns per ``xi``, solved batched with partial pivoting.

The result is the ratio ``A(xi)`` of the surface deflection to the top material's own
half-space deflection: with the Hankel transforms ``p_bar(xi) = int_0^inf p(r) J0(xi r) r dr``,

    ``u_z(r, 0) = int_0^inf 2 (1 - nu_1^2) / E_1  A(xi)  p_bar(xi) J0(xi r) dxi``,

and ``A -> 1`` as ``xi h_1 -> inf`` (the load no longer feels the layers below), with
``A - 1 = O((xi h_1)^2 e^(-2 xi h_1))``. ``A = 1`` identically for a homogeneous body.

References
----------
Burmister, D. M. (1945). J. Appl. Phys. 16, 89-94. Sneddon, I. N. (1951). *Fourier
Transforms*, McGraw-Hill. Timoshenko, S. P. & Goodier, J. N. (1970). *Theory of
Elasticity*, 3rd ed. Johnson, K. L. (1985). *Contact Mechanics*, CUP.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ssw.errors import ConfigError, SolverError

#: Interface models between two bodies (and between the last layer and a rigid base).
INTERFACES = ("bonded", "frictionless")


@dataclass(frozen=True)
class Layer:
    """An elastic layer: Young's modulus ``E`` (Pa), Poisson's ratio ``nu``, ``thickness`` (m).

    Parameters
    ----------
    E : float
        Young's modulus (Pa).
    nu : float
        Poisson's ratio.
    thickness : float
        Thickness (m).
    """

    E: float
    nu: float
    thickness: float


@dataclass(frozen=True)
class Stack:
    """Layers (top first) over a base, each interface named by the layer above it.

    ``interfaces[k]`` is the interface under ``layers[k]``; ``base_E = inf`` is a rigid
    base. No layers is the homogeneous half-space of the base.

    Parameters
    ----------
    layers : tuple
        The layers, top first.
    interfaces : tuple
        The interface under each layer.
    base_E : float
        Young's modulus of the base (Pa); inf: rigid.
    base_nu : float
        Poisson's ratio of the base.
    """

    layers: tuple[Layer, ...]
    interfaces: tuple[str, ...]
    base_E: float
    base_nu: float

    def __post_init__(self) -> None:
        if len(self.interfaces) != len(self.layers):
            raise ConfigError("interfaces", self.interfaces, "one interface per layer")
        for k, name in enumerate(self.interfaces):
            if name not in INTERFACES:
                raise ConfigError(f"interfaces[{k}]", name, " | ".join(INTERFACES))
        for k, lay in enumerate(self.layers):
            _check_material(f"layers[{k}]", lay.E, lay.nu)
            if not (np.isfinite(lay.E) and lay.thickness > 0 and np.isfinite(lay.thickness)):
                raise ConfigError(f"layers[{k}]", lay, "a finite E and a thickness > 0 m")
        _check_material("base", self.base_E, self.base_nu)
        if not self.layers and not np.isfinite(self.base_E):
            raise ConfigError("base_E", self.base_E, "a finite modulus when there is no layer")

    @property
    def top(self) -> tuple[float, float]:
        """(E Pa, nu) of the surface material."""
        if self.layers:
            return self.layers[0].E, self.layers[0].nu
        return self.base_E, self.base_nu

    @property
    def top_compliance(self) -> float:
        """``2 (1 - nu^2) / E`` (1/Pa) of the surface material: the asymptote's factor."""
        E, nu = self.top
        return 2.0 * (1.0 - nu * nu) / E

    @property
    def depth(self) -> float:
        """Total thickness of the layers (m)."""
        return float(sum(lay.thickness for lay in self.layers))


def plate_on_soil(plate: tuple[float, float] | None, thickness: float,
                  soil: tuple[float, float], interface: str,
                  soil_depth: float | None = None, base: str = "bonded",
                  base_E: float | None = None, base_nu: float | None = None) -> Stack:
    """The stack of a plate (E, nu; None or ``thickness == 0``: no plate) on a soil.

    ``soil_depth`` None: the soil is a half-space; a depth (m): a soil layer of that depth
    on a rigid base, ``bonded`` (the FEM's fixed bottom) or ``sliding`` (frictionless), or
    bonded to an ``elastic`` half-space of ``base_E`` (Pa), ``base_nu`` (a lift on a
    subgrade).

    Parameters
    ----------
    plate : tuple of float or None
        The plate's ``(E, nu)`` (Pa, -), or None.
    thickness : float
        Plate thickness (m).
    soil : tuple of float
        The soil's ``(E, nu)`` (Pa, -).
    interface : str
        The plate-soil interface.
    soil_depth : float or None
        Depth of the soil layer (m); None: a half-space.
    base : str
        Below the layer: ``bonded``, ``sliding`` or ``elastic``.
    base_E : float or None
        Young's modulus of an elastic base (Pa).
    base_nu : float or None
        Poisson's ratio of an elastic base.

    Returns
    -------
    Stack
        The stack.

    Raises
    ------
    ConfigError
        If the interface is unknown.
    """
    layers: list[Layer] = []
    ifaces: list[str] = []
    if plate is not None and thickness > 0:
        layers.append(Layer(float(plate[0]), float(plate[1]), float(thickness)))
        ifaces.append(interface)
    if interface not in INTERFACES:
        raise ConfigError("interface", interface, " | ".join(INTERFACES))
    if soil_depth is None:
        return Stack(tuple(layers), tuple(ifaces), float(soil[0]), float(soil[1]))
    layers.append(Layer(float(soil[0]), float(soil[1]), float(soil_depth)))
    if base == "elastic":
        ifaces.append("bonded")
        return Stack(tuple(layers), tuple(ifaces), float(base_E), float(base_nu))
    ifaces.append({"bonded": "bonded", "sliding": "frictionless"}.get(base, base))
    return Stack(tuple(layers), tuple(ifaces), np.inf, 0.0)


def _check_material(name: str, E: float, nu: float) -> None:
    if not E > 0:
        raise ConfigError(f"{name}.E", E, "a Young's modulus > 0 Pa")
    if not -1.0 < nu <= 0.5:
        raise ConfigError(f"{name}.nu", nu, "a Poisson's ratio in (-1, 0.5]")


def _mode_derivatives(s: NDArray, growing: bool) -> NDArray:
    """``[f, f', f'', f''']`` (shape (..., 4 derivatives, 2 modes)) at ``xi = 1`` of the
    modes ``e^(-s), s e^(-s)`` (decaying; ``s >= 0`` below the top of the body) or
    ``e^s, s e^s`` (growing; ``s <= 0`` above the bottom of the layer)."""
    if growing:
        e = np.exp(s)
        plain = np.stack([e, e, e, e], axis=-1)
        lin = np.stack([s * e, (1 + s) * e, (2 + s) * e, (3 + s) * e], axis=-1)
    else:
        e = np.exp(-s)
        plain = np.stack([e, -e, e, -e], axis=-1)
        lin = np.stack([s * e, (1 - s) * e, (s - 2) * e, (3 - s) * e], axis=-1)
    return np.stack([plain, lin], axis=-1)


def _state(d: NDArray, nu: float, g_rel: float) -> NDArray:
    """Rows ``[2 G_ref u_z, 2 G_ref u_r, sigma_zz, sigma_rz]`` (..., 4, modes) from the
    derivatives ``d`` (..., 4, modes) of Love's function in a body of shear modulus
    ``g_rel G_ref`` (Timoshenko & Goodier 1970, sec. 130, at ``xi = 1``)."""
    f, f1, f2, f3 = d[..., 0, :], d[..., 1, :], d[..., 2, :], d[..., 3, :]
    uz = ((1 - 2 * nu) * f2 - 2 * (1 - nu) * f) / g_rel
    ur = f1 / g_rel
    szz = (1 - nu) * f3 - (2 - nu) * f1
    srz = nu * f2 + (1 - nu) * f
    return np.stack([uz, ur, szz, srz], axis=-2)


def _layer_states(t: NDArray, nu: float, g_rel: float) -> tuple[NDArray, NDArray]:
    """State matrices (n, 4, 4 modes) at the top and bottom of a layer of thickness ``t``."""
    zero = np.zeros_like(t)
    top = np.concatenate([_state(_mode_derivatives(zero, False), nu, g_rel),
                          _state(_mode_derivatives(-t, True), nu, g_rel)], axis=-1)
    bottom = np.concatenate([_state(_mode_derivatives(t, False), nu, g_rel),
                             _state(_mode_derivatives(zero, True), nu, g_rel)], axis=-1)
    return top, bottom


def compliance_ratio(stack: Stack, xi: ArrayLike) -> NDArray[np.float64]:
    """``A(xi)``: surface deflection of the stack over the top material's half-space one.

    Parameters
    ----------
    stack : Stack
        The layered body.
    xi : array_like
        The Hankel variable, 1/m, any shape, ``>= 0``.

    Returns
    -------
    numpy.ndarray
        ``A`` of the shape of ``xi`` (see the module docstring):
        ``u_z_bar(xi) = 2 (1 - nu_1^2) / (E_1 xi) A(xi) p_bar(xi)``.
    """
    xi = np.asarray(xi, dtype=float)
    if not stack.layers:
        return np.ones_like(xi)
    if np.any(xi < 0) or not np.all(np.isfinite(xi)):
        raise ConfigError("xi", "negative or non-finite", "finite values >= 0 (1/m)")
    flat = xi.ravel()
    n_xi = flat.size
    E1, nu1 = stack.top
    g1 = E1 / (2 * (1 + nu1))
    rigid = not np.isfinite(stack.base_E)
    n_lay = len(stack.layers)
    n = 4 * n_lay + (0 if rigid else 2)
    M = np.zeros((n_xi, n, n))
    rhs = np.zeros(n)
    states = []
    for lay in stack.layers:
        g = lay.E / (2 * (1 + lay.nu)) / g1
        states.append(_layer_states(flat * lay.thickness, lay.nu, g))
    # surface: sigma_zz = -p (p_bar = 1), sigma_rz = 0
    M[:, 0, 0:4] = states[0][0][:, 2, :]
    M[:, 1, 0:4] = states[0][0][:, 3, :]
    rhs[0] = -1.0
    row = 2
    for k, iface in enumerate(stack.interfaces):
        upper = states[k][1]
        cu = slice(4 * k, 4 * k + 4)
        if k + 1 < n_lay:
            lower, cl = states[k + 1][0], slice(4 * k + 4, 4 * k + 8)
        elif not rigid:
            gb = stack.base_E / (2 * (1 + stack.base_nu)) / g1
            lower = _state(_mode_derivatives(np.zeros(n_xi), False), stack.base_nu, gb)
            cl = slice(4 * k + 4, 4 * k + 6)
        else:
            lower, cl = None, None
        if lower is None:  # rigid base: u_z = 0 and u_r = 0 (bonded) or sigma_rz = 0
            M[:, row, cu] = upper[:, 0, :]
            M[:, row + 1, cu] = upper[:, 1 if iface == "bonded" else 3, :]
            row += 2
        elif iface == "bonded":
            for q in range(4):
                M[:, row + q, cu] = upper[:, q, :]
                M[:, row + q, cl] = -lower[:, q, :]
            row += 4
        else:  # frictionless: u_z, sigma_zz continuous, no shear on either face
            for q in (0, 2):
                M[:, row, cu] = upper[:, q, :]
                M[:, row, cl] = -lower[:, q, :]
                row += 1
            M[:, row, cu] = upper[:, 3, :]
            M[:, row + 1, cl] = lower[:, 3, :]
            row += 2
    if row != n:  # pragma: no cover - the counts above are fixed by construction
        raise SolverError(f"layered kernel: {row} equations for {n} unknowns")
    try:
        c = np.linalg.solve(M, np.broadcast_to(rhs, (n_xi, n))[..., None])[..., 0]
    except np.linalg.LinAlgError as exc:
        raise SolverError(f"layered kernel: singular transfer system ({exc})") from exc
    uz_surface = np.einsum("nm,nm->n", states[0][0][:, 0, :], c[:, 0:4])  # 2 G1 u_z
    A = uz_surface / (2 * (1 - nu1))
    if not np.all(np.isfinite(A)):
        raise SolverError("layered kernel: non-finite compliance (check the moduli)")
    return A.reshape(xi.shape)
